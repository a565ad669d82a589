"""The work-precision study's results file, and the page and plots rendered from it.

    save_results(results, results_path(out))   # OUT/benchmarks/workprecision.json
    write(load_results(results_path(out)), out)  # OUT/BENCHMARKS.md, OUT/benchmarks/*.png

Rendering measures nothing: every number on the page comes from the results (see
:func:`roller_gym.bench.workprecision.measure`), the verdicts from
:mod:`roller_gym.bench.verdicts`. The results file is JSON; a non-finite number (a diverged
run's error, a horizon never left) is written as the string ``"inf"``, ``"-inf"`` or ``"nan"``.
"""

from __future__ import annotations

import datetime
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from roller_gym.bench.verdicts import (
    TARGETS,
    VERDICTS,
    chaotic,
    compare_mujoco,
    cost_at_error,
    cost_rows,
    default_run,
    error_of,
    family,
    fmt_err,
    fmt_time,
    horizon,
    scene,
    verdict_cost,
)
from roller_gym.physics import integrators as integ

__all__ = ["load_results", "plot", "render", "results_path", "save_results", "write"]

Results = dict[str, Any]

#: The results file and the page, relative to the docs folder.
RESULTS_FILE = Path("benchmarks") / "workprecision.json"
PAGE = "BENCHMARKS.md"

OUR_FAMILIES = ("euler", "rk4", "rk4 auto", "rk8", "rk8 auto", "taylor", "taylor auto",
                "midpoint", "dop853")
MJ_FAMILIES = ("MuJoCo default", "MuJoCo tuned")
COLORS = {"euler": "tab:red", "rk4": "tab:blue", "rk4 auto": "tab:green", "rk8": "tab:cyan",
          "rk8 auto": "tab:olive", "taylor": "tab:pink", "taylor auto": "black",
          "midpoint": "tab:purple", "dop853": "tab:gray",
          "MuJoCo default": "tab:orange", "MuJoCo tuned": "tab:brown"}
MARKERS = {"euler": "v", "rk4": "o", "rk4 auto": "s", "rk8": "h", "rk8 auto": "p",
           "taylor": "<", "taylor auto": "*",
           "midpoint": "D", "dop853": "^", "MuJoCo default": "X", "MuJoCo tuned": "P"}
#: MuJoCo's integrators in words.
_INTEGRATORS = {"Euler": "semi-implicit Euler"}
#: Right-hand-side evaluations of an rk4 substep: under error control, and fixed.
_RK4_EVALUATIONS = tuple(integ.scheme("rk4").evaluations(fixed=f) for f in (False, True))


def substep_work(method: str) -> str:
    """The work of one substep of a compiled error-controlled scheme under error control, in
    words."""
    scheme = integ.SCHEMES.get(method)
    if method == "taylor":
        return (f"one expansion to degree {scheme.order} (the sines once, then products of "
                "series)")
    if scheme is None or scheme.tableau is None:
        return "several stages"
    return f"{scheme.evaluations(fixed=False)} right-hand sides"


# ================================================================================================
# The results file
# ================================================================================================
def results_path(out: Path) -> Path:
    """Where the results file of the docs folder ``out`` is."""
    return Path(out) / RESULTS_FILE


def _encode(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): _encode(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_encode(v) for v in x]
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return "nan" if math.isnan(x) else ("inf" if x > 0 else "-inf")
    return x


def _decode(x: Any) -> Any:
    if isinstance(x, dict):
        return {k: _decode(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_decode(v) for v in x]
    if x in ("inf", "-inf", "nan"):
        return float(x)
    return x


def _dumps(x: Any, level: int = 0, width: int = 100) -> str:
    """JSON, indented by one space a level; what fits in ``width`` and every list of numbers
    on one line."""
    one = json.dumps(x, ensure_ascii=False, allow_nan=False)
    numbers = isinstance(x, list) and all(isinstance(v, int | float) for v in x)
    if not isinstance(x, dict | list) or numbers or level + len(one) <= width:
        return one
    pad, inner = " " * level, " " * (level + 1)
    if isinstance(x, dict):
        body = ",\n".join(f"{inner}{json.dumps(k, ensure_ascii=False)}: {_dumps(v, level + 1)}"
                          for k, v in x.items())
        return "{\n" + body + "\n" + pad + "}"
    body = ",\n".join(inner + _dumps(v, level + 1) for v in x)
    return "[\n" + body + "\n" + pad + "]"


def save_results(results: Results, path: Path) -> None:
    """Write ``results`` to ``path`` as JSON (strict: non-finite numbers as strings)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(_dumps(_encode(results)) + "\n")


def load_results(path: Path) -> Results:
    """The results saved at ``path`` (non-finite numbers as floats again)."""
    return _decode(json.loads(Path(path).read_text()))


# ================================================================================================
# The plots
# ================================================================================================
def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _scene_panels(count: int, panel_height: float, legend_in: float) -> tuple[Any, Any]:
    """A figure of ``count`` panels, three to a row, ``panel_height`` inches each, with
    ``legend_in`` inches below them for the legend."""
    plt = _pyplot()
    cols = min(3, count)
    rows = math.ceil(count / cols)
    height = panel_height * rows + legend_in
    return plt.subplots(rows, cols, figsize=(5.2 * cols, height), squeeze=False)


def _save_panels(fig: Any, axes: Any, count: int, legend_in: float, legend_columns: int,
                 title: str, path: Path) -> None:
    """Blank the unused panels, put the first panel's legend in the ``legend_in`` inches under
    them, title, save, close."""
    for ax in axes.flat[count:]:
        ax.axis("off")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=legend_columns, fontsize=8)
    fig.suptitle(title)
    height = fig.get_figheight()
    fig.tight_layout(rect=(0, legend_in / height, 1, 1 - 0.4 / height))
    fig.savefig(path, dpi=110)
    _pyplot().close(fig)


def plot_work_precision(results: Results, path: Path, metric: str) -> None:
    """Cost against error, one panel per scene: the global or the local error."""
    st = results["settings"]
    scenes = results["scenes"]
    legend_in = 1.3  # inches under the plots for the legend
    fig, axes = _scene_panels(len(scenes), panel_height=4.2, legend_in=legend_in)
    for ax, sc in zip(axes.flat, scenes, strict=False):
        hz = horizon(results, sc)
        for fam in (*OUR_FAMILIES, *MJ_FAMILIES):
            # in the order of the setting (substeps up, tolerance down, timestep down)
            # (runs that blew up past 100 rad are left out: they are in the tables)
            pts = [(error_of(r, metric), r["seconds"] / hz) for r in family(sc, fam)
                   if error_of(r, metric) <= 100.0]
            if pts:
                e, c = zip(*pts, strict=True)
                ax.loglog(np.maximum(e, 1e-16), c, marker=MARKERS[fam], color=COLORS[fam],
                          label=fam, lw=1.2, ms=5, ls="--" if fam.startswith("MuJoCo") else "-")
        d = default_run(sc)
        ax.loglog([max(error_of(d, metric), 1e-16)], [d["seconds"] / hz], "*", color="k",
                  ms=15, label=f"default ({st['method']}, tol {st['tolerance']:.0e})", zorder=5)
        if metric == "global":
            ax.axvline(max(sc["reference"]["own_error"][0], 1e-16), color="k", lw=0.8, ls=":",
                       label="reference's own error")
            ax.axvline(st["target_error"], color="tab:red", lw=0.8, ls="-.",
                       label=f"target {st['target_error']:g} rad")
        else:
            ax.axvline(st["tolerance"], color="tab:red", lw=0.8, ls="-.",
                       label=f"tolerance {st['tolerance']:.0e}")
        title = f"{sc['name']}: {sc['note']}"
        if metric == "global" and chaotic(results, sc):
            title += (f"\n(chaotic: the reference itself is off by {st['target_error']:g} at "
                      f"{sc['reference']['predictable_s']:g} s)")
        ax.set_title(title, fontsize=9)
        ax.set_xlabel(f"largest |φ error| over {hz:g} s [rad]" if metric == "global"
                      else "largest |φ error| of one control step [rad]")
        ax.set_ylabel("wall time per simulated second [s]")
        ax.grid(True, which="major", alpha=0.3)
    _save_panels(fig, axes, len(scenes), legend_in, 6,
                 f"Work-precision, {metric} error: cost against error (lower left is better), "
                 "all measured in the same run", path)


def plot_energy(results: Results, path: Path) -> None:
    """The energy error at zero torque against time, one panel per scene."""
    scenes = results["scenes"]
    legend_in = 1.0
    fig, axes = _scene_panels(len(scenes), panel_height=3.8, legend_in=legend_in)
    for ax, sc in zip(axes.flat, scenes, strict=False):
        for item in sc["energy"]:
            t, value = item["curve"]["t"], item["curve"]["value"]
            ax.loglog(t, np.clip(np.asarray(value, dtype=float), 1e-17, 1e2), lw=1,
                      label=item["label"])
        ax.set_ylim(1e-17, 1e2)  # a blow-up leaves the plot at the top
        ax.set_title(sc["name"], fontsize=9)
        ax.set_xlabel("time [s]")
        ax.set_ylabel("|E − E0| / E0 (largest in each interval)")
        ax.grid(True, alpha=0.3)
    _save_panels(fig, axes, len(scenes), legend_in, 4,
                 f"Energy error at zero torque over {results['config']['energy_horizon_s']:g} s "
                 "(from rest at φ0)", path)


def plot_throughput(results: Results, path: Path) -> None:
    """Steps per second of the vector environment, its kernel and CartPoleVectorEnv."""
    plt = _pyplot()
    vector = results["throughput"]["vector"]
    sizes = sorted(int(n) for n in vector)
    fig, ax = plt.subplots(figsize=(6, 4.2))
    for name, color, label in (
        ("ours", "tab:green", "roller_gym/RollerStabilize-v1 (make_vec)"),
        ("kernel", "tab:olive", "our physics kernel alone (BatchStepper)"),
        ("CartPoleVectorEnv", "tab:orange", "CartPoleVectorEnv"),
    ):
        ax.loglog(sizes, [vector[str(n)][name] for n in sizes], marker="o", color=color,
                  label=label, ls=":" if name == "kernel" else "-")
    ax.set_xlabel("sub-environments")
    ax.set_ylabel("environment steps per second")
    ax.set_title("Vector environment throughput (same run, best of repeats)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot(results: Results, folder: Path) -> list[Path]:
    """Every plot of the page into ``folder``; their paths."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = [folder / "work_precision.png", folder / "work_precision_local.png",
             folder / "energy.png", folder / "throughput.png"]
    plot_work_precision(results, paths[0], "global")
    plot_work_precision(results, paths[1], "local")
    plot_energy(results, paths[2])
    plot_throughput(results, paths[3])
    return paths


# ================================================================================================
# The page
# ================================================================================================
def md_table(header: list[str], rows: list[list[str]]) -> list[str]:
    """A Markdown table's lines."""
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    return out


def _date(iso: str) -> str:
    try:
        return datetime.datetime.fromisoformat(iso).strftime("%Y-%m-%d %H:%M %Z").strip()
    except ValueError:
        return iso


def _subs(run: dict[str, Any]) -> str:
    s = run["substeps"]
    if run["family"].endswith("auto") or run["family"] == "dop853":
        return f"{s['mean']:.0f} (max {s['max']})"
    return f"{int(run['setting'])}"


def section_summary(results: Results) -> list[str]:
    st, paper = results["settings"], scene(results, "paper")
    d, c = default_run(paper), compare_mujoco(results, paper)
    hz = horizon(results, paper)
    rows = [[v.target, v.measured, v.sentence] for verdict in VERDICTS for v in verdict(results)]
    L = ["## Summary", "", *md_table(["target", "measured", "verdict"], rows), ""]
    L += [
        f"- Default settings ({st['method']}, automatic substeps at tol {st['tolerance']:.0e} "
        f"per control step, dt = {st['dt']} s) on the default scene: largest φ error over the "
        f"{hz:g}-s episode **{fmt_err(d['error'][0])} rad** (φ' {fmt_err(d['error'][1])} "
        f"rad/s), at **{fmt_time(d['seconds'] / hz)} per simulated second** "
        f"({paper['steps'] / d['seconds']:,.0f} control steps/s in the physics kernel).",
        f"- MuJoCo at its defaults ({_mj_default(st)}): φ error {fmt_err(c.default_err)} rad at "
        f"{fmt_time(c.default_cost)} per simulated second. Tuned for accuracy it reaches our "
        f"error at {c.mj_setting}.",
    ]
    hard = []
    for sc in results["scenes"]:
        bad = [f"{e['label']} at t = {e['blowup_s']:g} s" for e in sc["energy"]
               if "(default)" in e["label"] and math.isfinite(e["blowup_s"])]
        if not default_run(sc)["finite"]:
            bad.append("the episode")
        if bad:
            hard.append(f"{sc['name']} ({'; '.join(bad)})")
    chaos = [f"{sc['name']} (after {sc['reference']['predictable_s']:g} s)"
             for sc in results["scenes"] if chaotic(results, sc)]
    L += [
        "- Hard cases at default settings: "
        + ("no run went non-finite or blew up" if not hard else
           "**blew up** in " + ", ".join(hard) + " (zero-torque runs; see part 4)")
        + "; chaotic under random torques, so judged by the local error: "
        + (", ".join(chaos) if chaos else "none") + ".",
        "", "See *The targets* at the end for what would close each miss.", "",
    ]
    return L


def _mj_default(st: dict[str, Any]) -> str:
    mj = st["mujoco"]["default"]
    return f"{1e3 * mj['timestep']:g} ms {mj['integrator']} steps, soft constraint"


def section_machine(results: Results) -> list[str]:
    m = results["machine"]
    versions = ", ".join(f"{k} {v or '(not installed)'}" for k, v in m["versions"].items())
    return [
        "## Machine and command", "",
        f"- CPU: {m['cpu']}, {m['cores']} cores ({m['os']}), Python {m['python']}",
        f"- {versions}",
        f"- Date: {_date(results['date'])} (timings are best-of-repeats, and only ratios "
        "measured in this run are compared)",
        f"- Command: `{results['command']}` (from the repository root, in its venv: "
        "`make bench` runs the full one); the numbers are in "
        f"[`{RESULTS_FILE.as_posix()}`]({RESULTS_FILE.as_posix()}), and "
        "`roller-gym benchmark --render` draws this page and its plots again from them", "",
    ]


def section_method(results: Results) -> list[str]:
    st, paper = results["settings"], scene(results, "paper")
    return [
        "## How it is measured", "",
        f"- **Episode**: {horizon(results, paper):g} s = {paper['steps']} control steps of "
        f"dt = {st['dt']} s from rest at φ = 0. The drive is constant over a control step and "
        f"drawn once per step: actions uniform in [−1, 1] (float32, seed {st['seed']}) times "
        f"the environments' default max_torque = {st['max_torque']} N·m, i.e. what random "
        "actions in the environments do. The same torques for every scene, integrator and "
        "engine.",
        f"- **Reference**: scipy's DOP853 at rtol = atol = {st['reference_tol']:g}, restarted "
        "at each control step (the torque jumps there). Its own error is estimated by running "
        "it again at 1e-12 (`reference's own error` below): errors under it cannot be "
        "measured.",
        "- **Global error**: the largest |φ − φ_ref| [rad] (and |φ' − φ'_ref| [rad/s]) over "
        "the episode, each integrator run on its own from the same start with the same "
        "torques. It grows with the dynamics as well as with the integrator (a trajectory's "
        "sensitivity to a perturbation grows with time), so it is also given as the **local "
        "error**: the largest error of one control step started from the reference state, "
        "which is what `tol` bounds.",
        "- **Cost**: best-of-repeats wall time of the episode, per simulated second (a Python "
        "loop of one call per control step: `integrators.Stepper.advance`, the stepper the "
        "environment steps with, `integrators.step(method='dop853')`, "
        "`mujoco.mj_step(model, data, n)`). `steps/s` = control steps per second of the "
        "physics alone, the ceiling of an environment's steps/s.",
        "- **Families**: `euler` = semi-implicit Euler with n fixed substeps (n = 1 is "
        "Gymnasium's Pendulum scheme); `rk4` = classical RK4 with n fixed substeps; `rk4 "
        "auto` = error control at a tolerance per control step (the environments' default: "
        f"{st['tolerance']:.0e}) with the Bogacki–Shampine 5(4) pair (its 5th-order "
        "solution carried on); "
        "`rk8`, `rk8 auto` = the same with the 8th-order Dormand–Prince tableau and its "
        "embedded estimate; `taylor`, `taylor auto` = the Taylor series of the motion to "
        "degree 18, n fixed substeps or each substep's size chosen from the expansion's "
        "last two terms (the environments' default integrator: "
        f"`{st['method']}`); `midpoint` = implicit midpoint, n fixed substeps; "
        "`dop853` = scipy's, at rtol = atol = tol.",
        "",
    ]


def section_work_precision(results: Results) -> list[str]:
    L = ["## 1. Work-precision", "", "Global error (along the episode):", "",
         "![work-precision](benchmarks/work_precision.png)", "",
         "Local error (one control step from the reference state; MuJoCo's too):", "",
         "![work-precision, local](benchmarks/work_precision_local.png)", ""]
    for sc in results["scenes"]:
        ref, hz = sc["reference"], horizon(results, sc)
        L += [f"### {sc['name']}: {sc['note']}", ""]
        text = (f"Reference: {fmt_time(ref['seconds'])} for the episode, {ref['steps']:,} "
                f"DOP853 steps; its own error ≈ {fmt_err(ref['own_error'][0])} rad "
                f"({fmt_err(ref['own_error'][1])} rad/s). Largest |φ| "
                f"{ref['max_abs_phi']:.3g} rad, largest |φ'| {ref['max_abs_phi_dot']:.3g} rad/s.")
        if chaotic(results, sc):
            text += (f" **The motion is chaotic under these torques**: the reference's own "
                     f"error passes {results['settings']['target_error']:g} rad at t = "
                     f"{ref['predictable_s']:g} s and grows to {fmt_err(ref['own_error'][0])} "
                     "rad, so every global error here measures the dynamics' sensitivity, not "
                     "the integrator: read the local errors (and `work_precision_local.png`).")
        L += [text, ""]
        rows = []
        d = default_run(sc)
        for run in sc["runs"]:
            local = run["local_error"][0]
            rows.append([
                run["family"] + (" ★" if run is d else ""), run["label"],
                fmt_err(run["error"][0]), fmt_err(run["error"][1]),
                fmt_err(local) if not math.isnan(local) else "",
                _subs(run), fmt_time(run["seconds"] / hz),
                f"{sc['steps'] / run['seconds']:,.0f}",
            ])
        L += md_table(["family", "setting", "φ error [rad]", "φ' error [rad/s]",
                       "local φ error [rad]", "substeps per control step", "per sim. s",
                       "steps/s"], rows)
        L += [""]
    energy_s = results["config"]["energy_horizon_s"]
    L += ["### Energy at zero torque", "",
          f"From rest at φ0 with max(|φ0|, |ψ0|) = 0.5 rad, {energy_s:g} s "
          f"({round(energy_s / results['settings']['dt']):,} control steps): the largest "
          "relative energy error |E − E0|/E0 over the horizon. The system is not separable "
          "(J_I depends on φ), so semi-implicit Euler is not symplectic here and drifts; the "
          "implicit midpoint rule is symplectic and its error stays bounded; RK4 and RK8 drift "
          "slowly, by their error per step.", "", "![energy](benchmarks/energy.png)", ""]
    header = ["scene", *[item["label"] for item in results["scenes"][0]["energy"]]]
    rows = [[sc["name"], *[f"{fmt_err(item['max'])} ({fmt_time(item['seconds'])})"
                           for item in sc["energy"]]] for sc in results["scenes"]]
    L += [*md_table(header, rows), "", "(wall time of the whole horizon in brackets)", ""]
    return L


def section_mujoco(results: Results) -> list[str]:
    st = results["settings"]
    mj, tuned = st["mujoco"]["default"], st["mujoco"]["tuned"]
    method, mj_integrator = st["method"], _INTEGRATORS.get(mj["integrator"], mj["integrator"])
    L = ["## 2. MuJoCo on the same scene", "",
         "The model (`roller_gym.bench.mujoco_roller`): MuJoCo has no rolling constraint "
         "between a cylinder and a concave cylinder, so the roller is a body `arm` hinged at "
         "the axis O (angle ψ) carrying at R − r a body `roller` hinged to it (relative angle "
         "q), with the roller's mass m at e from its center and inertia m k² about C, and a "
         "joint equality constraint q = (R/r) ψ (rolling: (R − r) ψ = r φ with φ = q − ψ). The "
         "drive is a motor on a site of the roller, a pure couple (power τφ'). The floor (and "
         "a huge R, which cannot be an arm that long) is a slide joint x with the roller "
         "hinged at height r and the coupling x = r φ. The drum is the same arm pointing up "
         f"(R − r < 0). The arm carries {st['mujoco']['arm_mass']:g} kg (MuJoCo rejects "
         "massless moving bodies), a change of ~1e-8 in the dynamics at most.", "",
         f"- **MuJoCo default**: MuJoCo's own settings ({mj_integrator}, solref "
         f"({mj['solref'][0]:g}, {mj['solref'][1]:g}), solimp "
         f"({', '.join(f'{x:g}' for x in mj['solimp'][:3])})) at its default "
         f"{1e3 * mj['timestep']:g} ms timestep and smaller ones: the soft constraint, not the "
         "step, sets the error, which stops falling.",
         f"- **MuJoCo tuned**: {tuned['integrator']}; the stiffest constraint "
         f"{tuned['integrator']} keeps stable (timeconst = {tuned['timeconst_per_timestep']:g} "
         "timestep, with MuJoCo's safety clamp `refsafe` off, critical damping, impedance "
         f"{tuned['solimp'][0]:g}, MuJoCo's maximum); solver tolerance {tuned['tolerance']:g}, "
         f"{tuned['iterations']} iterations. Its error falls as timestep²: that is the "
         "**validation** that the model is the same system as ours — its trajectory converges "
         "to our DOP853 reference on every scene as the timestep shrinks (see the tables: the "
         "error keeps falling at the finest steps).", ""]
    rows = []
    for sc in results["scenes"]:
        cmp, loc = compare_mujoco(results, sc), compare_mujoco(results, sc, "local")
        hz, ref = horizon(results, sc), sc["reference"]
        tuned_runs = [r for r in family(sc, "MuJoCo tuned")
                      if math.isfinite(r["local_error"][0])]
        glob = (f"{fmt_time(cmp.mj_cost)}: {cmp.mj_setting}, {cmp.mj_how}; "
                f"**{cmp.ratio:,.0f} ×**" if math.isfinite(cmp.ratio) else cmp.mj_how)
        if chaotic(results, sc):
            best_glob = min((r["error"][0] for r in family(sc, "MuJoCo tuned")),
                            default=math.inf)
            glob = (f"not comparable: chaotic after {ref['predictable_s']:g} s (the "
                    f"reference's own error reaches {fmt_err(ref['own_error'][0])} rad); MuJoCo "
                    f"tuned's best: {fmt_err(best_glob)} rad")
        # the other way round: our cost at the finest local error MuJoCo reaches
        reverse = "–"
        if tuned_runs:
            finest = min(tuned_runs, key=lambda r: r["local_error"][0])
            ours_pts = [(r["local_error"][0], r["seconds"] / hz)
                        for r in family(sc, f"{method} auto")]
            our_cost, how = cost_at_error(ours_pts, finest["local_error"][0])
            mj_cost = finest["seconds"] / hz
            reverse = (f"MuJoCo {fmt_err(finest['local_error'][0])} ({finest['label']}) in "
                       f"{fmt_time(mj_cost)}; ours {fmt_time(our_cost)} ({how}): "
                       f"**{mj_cost / our_cost:,.0f} ×**" if math.isfinite(our_cost)
                       else f"MuJoCo {fmt_err(finest['local_error'][0])} in {fmt_time(mj_cost)}")
        rows.append([
            sc["name"], f"{fmt_err(cmp.our_err)} / {fmt_err(loc.our_err)}",
            fmt_time(cmp.our_cost),
            f"{fmt_err(cmp.default_err)} / {fmt_err(loc.default_err)} in "
            f"{fmt_time(cmp.default_cost)}",
            glob,
            (f"{fmt_time(loc.mj_cost)}: {loc.mj_setting}, {loc.mj_how}; "
             f"**{loc.ratio:,.0f} ×**") if math.isfinite(loc.ratio) else loc.mj_how,
            reverse,
        ])
    L += md_table(["scene", "ours (default settings): φ error global / local [rad]",
                   "our cost per sim. s",
                   "MuJoCo default: φ error global / local, cost per sim. s",
                   "MuJoCo tuned at our global error: cost per sim. s; speed ratio",
                   "MuJoCo tuned at our local error: cost; speed ratio",
                   f"at MuJoCo tuned's finest local error: its cost, ours (`{method} auto`); "
                   "speed ratio"], rows)
    L += ["", "MuJoCo's figures per setting are in the tables of part 1 (families `MuJoCo "
          "default`, `MuJoCo tuned`; setting = MuJoCo's timestep).", "",
          f"Our whole `{method} auto` curve against MuJoCo tuned, on the default scene "
          "(MuJoCo's cost interpolated at each of our errors):", ""]
    paper = scene(results, "paper")
    hz, floor = horizon(results, paper), paper["reference"]["own_error"][0]
    mj_pts = [(r["error"][0], r["seconds"] / hz) for r in family(paper, "MuJoCo tuned")]
    rows = []
    for run in family(paper, f"{method} auto"):
        cost, how = cost_at_error(mj_pts, max(run["error"][0], floor))
        ours_cost = run["seconds"] / hz
        rows.append([run["label"], fmt_err(run["error"][0]), fmt_time(ours_cost),
                     fmt_time(cost),
                     f"{cost / ours_cost:,.0f} × ({how})" if math.isfinite(cost) else how])
    L += [*md_table([f"{method} auto", "φ error [rad]", "ours per sim. s",
                     "MuJoCo tuned per sim. s", "ratio"], rows), ""]
    return L


def section_throughput(results: Results) -> list[str]:
    tp, cfg = results["throughput"], results["config"]
    single, vector, resets = tp["single"], tp["vector"], tp["resets"]
    L = ["## 3. Throughput", "",
         "Random actions, the same for every repeat; best of repeats, interleaved. One "
         f"environment: `gymnasium.make` (with its wrappers) for both, {cfg['env_steps']:,} "
         f"steps a repeat, best of {3 * cfg['repeats']}, steps only (resets excluded). "
         "Vector: `gymnasium.make_vec(\"roller_gym/RollerStabilize-v1\", num_envs=N)` "
         "(the native vector environment, default settings) against "
         "`CartPoleVectorEnv(num_envs=N)`, `step()` with batched actions, "
         "environment steps per second = N × batched steps per second (autoresets "
         "inside step() count, the first reset does not).", ""]
    L += md_table(
        ["environment", "steps/s", "ratio"],
        [["roller_gym/RollerStabilize-v1", f"{single['ours']:,.0f}",
          f"**{single['ours'] / single['Pendulum-v1']:.2f} ×**"],
         ["Pendulum-v1", f"{single['Pendulum-v1']:,.0f}", "1"]])
    L += ["", "State error of `gymnasium.make(\"roller_gym/RollerStabilize-v1\")` itself over "
          f"the {cfg['horizon_s']:g}-s reference episode (default settings, stepped through "
          f"the environment): φ {fmt_err(tp['env_error'][0])} rad, φ' "
          f"{fmt_err(tp['env_error'][1])} rad/s. The vector environment "
          f"({tp['vector_error_envs']} sub-environments on the same episode, up to the first "
          f"termination): φ {fmt_err(tp['vector_error'][0])} rad — the same kernel, so the "
          "same error bound.", ""]
    rows = []
    for n in sorted(int(k) for k in vector):
        v, rs = vector[str(n)], resets[str(n)]
        rows.append([
            f"{n:,}", f"{v['ours']:,.0f}", f"{v['CartPoleVectorEnv']:,.0f}",
            f"**{v['ours'] / v['CartPoleVectorEnv']:.2f} ×**",
            f"{v['kernel']:,.0f} ({1e9 / v['kernel']:,.0f} ns per roller)",
            f"{v['kernel'] / v['CartPoleVectorEnv']:.2f} ×",
            f"{fmt_time(rs['ours'])} / {fmt_time(rs['CartPoleVectorEnv'])}",
        ])
    L += md_table(["sub-environments", "ours steps/s", "CartPoleVectorEnv steps/s",
                   "ratio", "our physics kernel alone, steps/s",
                   "kernel / CartPoleVectorEnv", "reset() of all: ours / CartPole"], rows)
    L += ["", "The kernel column is `integrators.BatchStepper.advance` (the stepper of the "
          "vector environment) on the same number of rollers at the default settings, "
          "nothing else: the ceiling of the vector environment; the gap between it and the "
          "environment is the environment's own work (autoreset of ended episodes, "
          "observation, reward, info). The timed window is 1,000,000 / N batched steps (20 at "
          "least, 1,000 at most), going on from one reset: where it passes the episode's "
          "truncation, the episodes begun together are truncated together and all restart in "
          "one step's autoreset (the last column: what that costs). `docs/THROUGHPUT.md` "
          "(`make throughput`) times whole episodes from a reset instead, against the "
          "optional peers too: the README quotes that page.",
          "", "![throughput](benchmarks/throughput.png)", ""]
    if tp["ppo"]:
        ppo, ps = tp["ppo"], tp["ppo_settings"]
        L += [f"stable-baselines3 PPO (MlpPolicy, n_steps {ps['n_steps']}, batch "
              f"{ps['batch_size']}, {ps['n_epochs']} epochs, torch on {ps['torch_threads']} "
              f"thread), {cfg['ppo_steps']:,} training steps: **{ppo['ours']:,.0f}** steps/s "
              f"on roller_gym/RollerStabilize-v1 against {ppo['Pendulum-v1']:,.0f} on "
              f"Pendulum-v1: **{ppo['ours'] / ppo['Pendulum-v1']:.2f} ×** (the network's "
              "updates dominate both).", ""]
    L += [f"- {note}" for note in tp["notes"]] + ([""] if tp["notes"] else [])
    return L


def section_hard_cases(results: Results) -> list[str]:
    st = results["settings"]
    L = ["## 4. Hard cases", "",
         f"Default settings ({st['method']}, automatic substeps, tol {st['tolerance']:.0e}) on "
         "the episode of part 1, and the zero-torque horizon of the energy table. "
         "`non-finite or blown up`: every run of ours on the scene (all families and the "
         "energy runs) that could not stay finite (such a step reports it and keeps the "
         "state), or whose energy at zero torque went off by more than E0 (a step that blew "
         "up yet stayed finite), with when. `contact`: control steps of the episode at which "
         "the roller would leave the surface or slip (the model keeps rolling; an "
         "environment ends the episode there).", ""]
    rows = []
    for sc in results["scenes"]:
        d, ref = default_run(sc), sc["reference"]
        s = d["substeps"]
        bad = [f"{r['family']} {r['label']}" for r in sc["runs"] if r["ours"] and not r["finite"]]
        bad += [f"energy run {e['label']} at t = {e['blowup_s']:g} s" for e in sc["energy"]
                if math.isfinite(e["blowup_s"])]
        e_def = sc["energy"][-1] if sc["energy"] else None
        rows.append([
            sc["name"], f"{s['min']} / {s['median']:.0f} / {s['max']}",
            f"{fmt_err(d['local_error'][0])} / {fmt_err(d['local_error'][1])}",
            f"{fmt_err(d['error'][0])} / {fmt_err(d['error'][1])}",
            fmt_err(ref["own_error"][0]),
            f"{ref['predictable_s']:g} s" if chaotic(results, sc) else "whole episode",
            fmt_err(e_def["max"]) if e_def else "–",
            "none" if not bad else "; ".join(bad),
            f"{d['lifting'] or 0} lift-off, {d['slipping'] or 0} slip (μ = {sc['mu']:g})",
            f"{ref['max_abs_phi_dot']:.3g}",
        ])
    L += md_table(["scene", "substeps min / median / max", "local error φ / φ'",
                   "global error φ / φ'", "reference's own φ error",
                   f"reference good to {st['target_error']:g} rad for",
                   "energy error (default)", "non-finite or blown up", "contact",
                   "max |φ'| [rad/s]"], rows)
    return [*L, ""]


def _skipped(row: dict[str, Any]) -> str:
    why = [f"{k} {v}" for k, v in row["skipped"].items() if v]
    return "; ".join(why) if why else "none"


def section_cost(results: Results) -> list[str]:
    """The automatic substep counts against the smallest fixed counts that meet tol."""
    L = ["## 5. Cost of the error control", ""]
    if "cost" not in results:
        return [*L, "Not measured in this results file (it predates the measurement): "
                "`roller-gym benchmark` measures it.", ""]
    st = results["cost"]["settings"]
    L += [
        "Is the automatic substep count of each error-controlled scheme near the fewest "
        "substeps that "
        f"would do? On {st['steps']} random hard control steps of dt = {st['dt']} s (seed "
        f"{st['seed']}): scenes inside a cylinder, nearly tight (R/r − 1 down to 0.005), on a "
        "floor and on a drum; e/r up to 0.999, k/r down to 0.01; |τ| up to 5 m g r; |φ'| up "
        "to 15 sqrt(g/r). Per step and tolerance: the **automatic** count (the accepted "
        "substeps of `integrators.step`), and the **smallest fixed** count: the least n "
        "whose n equal substeps of the same scheme end within tol of the reference (DOP853 "
        f"at rtol = atol = {st['reference_tol']:g}), found by doubling n and then bisecting "
        "between n/2 and n. `ratio` = automatic / smallest fixed, per step, counted in "
        "right-hand-side evaluations: the same as substeps for `rk8` and `taylor` (one "
        "expansion a substep, automatic or fixed); `rk4` takes "
        f"Bogacki–Shampine 5(4) substeps of {_RK4_EVALUATIONS[0]} evaluations under error "
        f"control and classical steps of {_RK4_EVALUATIONS[1]} with fixed substeps. Skipped: "
        "steps "
        f"whose reference's own error (against a run at 10 × rtol) exceeds "
        f"{st['uncertainty_share']:g} tol, and steps no fixed count up to "
        f"{st['max_fixed']:,} meets (the tolerance is out of float64's reach there).",
        "",
        "- **stateless** (judged): the sample's independent steps, each started afresh (its "
        "first substep predicted), as the target's sample is of independent control steps.",
        f"- **carried**: {st['trajectories']} trajectories of {st['trajectory_steps']} "
        "control steps from the sample's first states, under random torques of the same "
        "range, each step taken from the reference state by a `BatchStepper` that carries "
        "the controller's proposed substep size from one step to the next, as the "
        "environments step; the first step of each is left out"
        + (f" ({st['trajectories_dropped']} trajectories dropped: their reference went "
           "non-finite)" if st.get("trajectories_dropped") else "") + ".",
        "",
        "The accuracy bought is shown beside the cost: `error ≤ tol` is the share of the "
        "steps measured whose automatic step ends within tol of the reference (in brackets, "
        "of those reporting `tol_met`); `tol_met False` counts the steps whose error "
        "estimates passed the scheme's share of tol (out of reach; reported, not looped on).",
        "",
    ]
    rows = []
    for row in cost_rows(results):
        ratio, auto, fixed = row["ratio"], row["auto_substeps"], row["fixed_substeps"]
        rows.append([
            row["method"], f"{row['tol']:.0e}", row["variant"] + (
                " ★" if row["variant"] == st["verdict_variant"] else ""),
            f"{row['measured']} of {row['steps']}", _skipped(row),
            f"{ratio['median']:.2f}", f"{ratio['p99']:.2f}", f"{ratio['max']:.2f}",
            f"{auto['mean']:,.0f} / {fixed['mean']:,.0f}",
            f"{100 * row['within_tol']:.1f} % ({100 * row['within_tol_where_met']:.1f} %)",
            fmt_err(row["worst_error_over_tol"]), str(row["tol_not_met"]),
        ])
    L += md_table(["method", "tol", "variant", "steps measured", "skipped",
                   "ratio median", "ratio 99th pct", "ratio max",
                   "mean substeps automatic / smallest fixed (rk4: Bogacki–Shampine / classical)",
                   "error ≤ tol",
                   "worst error / tol", "tol_met False"], rows)
    L += ["", "The means compare totals: a fixed count must resolve a step's fastest part along "
          "all of it, so where a step's pace varies the error control can take fewer substeps "
          "than any fixed count that meets tol (a ratio below 1). Counts are integers: a step "
          "that one fixed substep resolves and the controller takes in two has a ratio of "
          "exactly 2."]
    L += ["", f"Measured in {results['cost']['elapsed_s']:.0f} s"
          + (f" by `{results['cost']['command']}`" if "command" in results["cost"] else "")
          + ". ★: the variant the verdicts judge.", ""]
    return L


def section_targets(results: Results) -> list[str]:
    """Each target, and what would close it if missed."""
    st, tp = results["settings"], results["throughput"]
    method, tol = st["method"], st["tolerance"]
    paper = scene(results, "paper")
    hz, d = horizon(results, paper), default_run(paper)
    notes: list[str] = []
    # how much cheaper could the default be at the same error? (fixed substeps, same method)
    fixed = [(r["error"][0], r["seconds"] / hz) for r in family(paper, method)]
    fixed_cost, _ = cost_at_error(fixed, max(d["error"][0], paper["reference"]["own_error"][0]))
    d_cost = d["seconds"] / hz
    single, speed = tp["single"], TARGETS["single_vs_pendulum"]
    r1 = single["ours"] / single["Pendulum-v1"]
    kernel_steps = paper["steps"] / d["seconds"]
    notes.append(
        f"- **One environment**: {r1:.2f} × Pendulum-v1 (target {speed:g} ×), error "
        f"{fmt_err(tp['env_error'][0])} rad (bound {TARGETS['episode_error_rad']:g}). The "
        f"physics alone runs {kernel_steps:,.0f} control steps/s (mean "
        f"{d['substeps']['mean']:.1f} {method} substeps per step); the environment reaches "
        f"{single['ours']:,.0f}, {100 * single['ours'] / kernel_steps:.0f} % of that: the rest "
        "is the environment's own (the action check, calling the compiled step from Python, "
        "and the info's 21 NumPy scalars, about a third of a step) and Gymnasium's wrappers, "
        "which Pendulum pays too. "
        + ("Met." if r1 >= speed else
           "To close it: an info of fewer keys (`info_keys`), fewer Python operations per "
           "step and less work of the error control for a single roller"
           + (f"; fewer substeps at the same error would help a little (fixed {method} "
              f"substeps reach the default's error at {fmt_time(fixed_cost)} per simulated "
              f"second against {fmt_time(d_cost)})" if fixed_cost < 0.9 * d_cost else "")
           + ".")
    )
    vector = {int(n): v for n, v in tp["vector"].items()}
    per_roller = {n: 1e9 / v["kernel"] for n, v in vector.items()}
    if 1 in vector:
        notes.append(
            f"- **Vector environment, fixed cost**: at 1 sub-environment one step() takes "
            f"{fmt_time(1 / vector[1]['ours'])} against {fmt_time(1 / single['ours'])} for the "
            f"single environment (and {fmt_time(1 / vector[1]['CartPoleVectorEnv'])} for "
            "CartPoleVectorEnv): the per-step arrays (the info dict and its masks, the "
            "observation) cost more than the physics up to a few hundred sub-environments."
        )
    target = TARGETS["vector_vs_cartpole"]
    small = [m for m in vector if m < st["parallel_threshold"]]
    for n, v in sorted(vector.items()):
        if n not in (4096, 65536):
            continue
        r, rk = v["ours"] / v["CartPoleVectorEnv"], v["kernel"] / v["CartPoleVectorEnv"]
        text = (f"- **Vector environment at {n:,}**: {r:.2f} × CartPoleVectorEnv (target "
                f"{target:g} ×). ")
        if r >= target:
            notes.append(text + "Met.")
            continue
        text += (
            f"Missed: {r / target:.2f} of the target. The physics kernel alone runs at "
            f"{rk:.2f} × CartPoleVectorEnv ({per_roller[n]:,.0f} ns per roller per control "
            f"step: {method}, ≥ 1 substep of {substep_work(method)}, "
            "and the contact margins at every substep), against "
            f"{1e9 / v['CartPoleVectorEnv']:,.0f} ns per sub-environment for CartPole's whole "
            "step (one Euler step in a few NumPy operations). The environment runs at "
            f"{100 * v['ours'] / v['kernel']:.0f} % of this kernel's rate, but the kernel "
            "here steps states near rest (|φ| ≤ 0.5 rad, |φ'| ≤ 1 rad/s), which take fewer "
            "substeps than an episode under random torques; the share of a step spent "
            "outside the physics kernel along an episode is in `docs/THROUGHPUT.md`. "
        )
        if small and per_roller[n] > 0.8 * min(per_roller[m] for m in small):
            text += (
                "In this run the parallel kernel was no faster per roller than the serial one "
                f"at {max(small):,} rollers ({per_roller[max(small)]:,.0f} ns): with other "
                "processes on the cores, numba's threads wait for each other. "
            )
        text += (
            "The kernel already evaluates the equations in SIMD lanes and the autoreset is "
            "vectorized; what is left is the kernel's own arithmetic and, as the kernel "
            "gets cheaper, the environment's work around it (`docs/THROUGHPUT.md`: the "
            "share of a step outside the physics kernel, and the kernel against its "
            "arithmetic)."
        )
        notes.append(text)
    c, mj_target = compare_mujoco(results, paper), TARGETS["mujoco_speedup"]
    notes.append(
        f"- **MuJoCo at equal error (default scene)**: {c.ratio:,.0f} × (target "
        f"{mj_target:g} ×). "
        + ("Met. " if c.ratio >= mj_target else
           "Missed. MuJoCo tuned is limited by its soft constraint (error ∝ timestep²) and "
           "pays a constraint solve per RK4 stage; ours integrates a closed-form ODE. To "
           "close it: fewer substeps for the same error, or a cheaper kernel. ")
        + "The hard scenes are in the table of part 2: where MuJoCo's tuned family does not "
        "reach our error within its finest timestep its cost is extrapolated along its "
        "trend (and says so), or reported as not reached."
    )
    energy_s = results["config"]["energy_horizon_s"]
    for sc in results["scenes"]:
        d, ref = default_run(sc), sc["reference"]
        own = ref["own_error"][0]
        if chaotic(results, sc):
            meaning = (
                "so no engine's global error over the episode means anything there: after "
                "that time every trajectory is as good as any other" if own > 0.1 else
                f"so global errors under ~{fmt_err(own)} rad cannot be told apart there"
            )
            notes.append(
                f"- **{sc['name']}**: the motion under these torques is chaotic: two DOP853 "
                f"runs at 1e-12 and {st['reference_tol']:g} part by {st['target_error']:g} rad "
                f"at t = {ref['predictable_s']:g} s and by {fmt_err(own)} rad at the end, "
                f"{meaning}. The local error, one control step from the reference state, is "
                f"what the integrators answer for: {fmt_err(d['local_error'][0])} rad at "
                f"default settings against the tolerance {tol:.0e}. (The roller would also "
                f"leave the surface at {d['lifting'] or 0} and slip at {d['slipping'] or 0} of "
                f"the {sc['steps']} control steps: an environment ends the episode at the "
                "first.)"
            )
        if d["local_error"][0] > 10 * tol or not d["finite"]:
            notes.append(
                f"- **{sc['name']}**: at default settings the largest error of one control "
                f"step is {fmt_err(d['local_error'][0])} rad against the tolerance {tol:.0e}: "
                "the error control undershoots on this scene under these torques (largest "
                f"|φ'| {ref['max_abs_phi_dot']:.3g} rad/s; substeps up to "
                f"{d['substeps']['max']:,}): an issue for the integrators."
            )
        for e in sc["energy"]:
            if "(default)" in e["label"] and math.isfinite(e["blowup_s"]):
                notes.append(
                    f"- **{sc['name']}, default integrator at zero torque**: blew up at t = "
                    f"{e['blowup_s']:g} s of the {energy_s:g}-s run (energy off by more than "
                    "E0; a non-finite step follows). One step from a slow state accelerates "
                    "through the dip of J_I with too few substeps; a step that blows up to a "
                    "huge but finite speed must be retried, not accepted: an issue for the "
                    "integrators."
                )
    for v, row in zip(verdict_cost(results), cost_rows(results, "stateless"), strict=False):
        ratio, bounds = row["ratio"], (TARGETS["substeps_median"], TARGETS["substeps_p99"])
        if v.met and (ratio["median"] >= 0.95 * bounds[0] or ratio["p99"] >= 0.95 * bounds[1]):
            notes.append(
                f"- **Cost of the error control, {row['method']} at tol {row['tol']:.0e}**: met "
                f"at the bound (median {ratio['median']:.2f} ×, 99th percentile "
                f"{ratio['p99']:.2f} ×; largest {ratio['max']:.2f} ×): no margin, so a small "
                "change of the controller, of the kernels or of the sample can tip it.")
        if v.met is not False:
            continue
        notes.append(
            f"- **Cost of the error control, {row['method']} at tol {row['tol']:.0e}**: "
            f"{v.miss}. The automatic count follows the scheme's error estimate, which "
            + ("for rk4 is Bogacki–Shampine 5(4)'s: the estimate is of the embedded "
               "4th-order solution's error, while the 5th-order solution is carried on, so "
               "it overstates the error of what is carried, most on the stiff scenes; a "
               f"substep costs {_RK4_EVALUATIONS[0]} evaluations, against "
               f"{_RK4_EVALUATIONS[1]} for a classical one"
               if row["method"] == "rk4" else
               "for taylor is the size of the expansion's last two terms, which overstates "
               "what the terms left out add"
               if row["method"] == "taylor" else
               "for rk8 is DOP853's blended 5th/3rd-order one: it overstates the 8th-order "
               "step's error, most on the stiff scenes")
            + ", and the accepted substeps' estimates may add up to only the scheme's "
            "tol_share of tol (room for what the estimates miss). "
            + ("The tail is set by steps (fast spins, nearly tight fits) along which the "
               "equal classical substeps' local errors cancel, their sum many times the error "
               "left at the step's end, which no controller that judges each substep by its "
               "own estimate can see. The share of tol is bounded by the tests' bound on the "
               "energy drift over 1e5 steps (5e-9 J)."
               if row["method"] == "rk4" else
               "To close it: a sharper error estimate (a larger tol_share or a bolder "
               "step-size controller alone lets some steps exceed tol).")
        )
    notes.append(
        "- Timings are best-of-repeats; if other processes share the machine, absolute "
        "figures are noisy, ratios measured in the same run much less so."
    )
    return ["## The targets: what is met, and what would close the misses", "", *notes]


def render(results: Results) -> str:
    """The page of a results file (Markdown; no measuring)."""
    cfg = results["config"]
    L = ["# Benchmarks: speed against error", ""]
    if results["quick"]:
        L += ["> **A `--quick` run**: a short episode, two scenes, few settings. The numbers "
              "show that the benchmark works, not what it finds; run without `--quick` for "
              "the report.", ""]
    L += [f"Generated by `{results['command']}` in {results['elapsed_s']:.0f} s (rerun it to "
          "reproduce; the machine is below). The same run measures every peer, interleaved: "
          f"best of {cfg['repeats']} repeats, and only ratios are compared.", ""]
    for section in (section_summary, section_machine, section_method, section_work_precision,
                    section_mujoco, section_throughput, section_hard_cases, section_cost,
                    section_targets):
        L += section(results)
    return "\n".join(L) + "\n"


def write(results: Results, out: Path) -> Path:
    """Render ``results`` into the docs folder ``out``: ``out/BENCHMARKS.md`` and
    ``out/benchmarks/*.png``; the page's path."""
    out = Path(out)
    plot(results, out / "benchmarks")
    page = out / PAGE
    page.write_text(render(results))
    return page
