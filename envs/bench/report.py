"""The work-precision page, ``docs/BENCHMARKS.md``, rendered from the study's results file.

    write(records.load_results(results_path(out)), out)  # OUT/BENCHMARKS.md and its plots

Rendering measures nothing: every number on the page comes from the results (see
:func:`roller_gym.bench.workprecision.measure`; the file: :mod:`roller_gym.bench.records`).
The page says what was measured, against which peers, on which machine and how to measure
again; the targets and their verdicts are the maintainers' page's
(:mod:`roller_gym.bench.maintainers`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from roller_gym.bench import plots
from roller_gym.bench.markdown import machine_section, md_table
from roller_gym.bench.verdicts import (
    chaotic,
    compare_mujoco,
    cost_at_error,
    cost_rows,
    default_run,
    family,
    fmt_err,
    fmt_time,
    horizon,
    scene,
)
from roller_gym.physics import integrators as integ

__all__ = ["render", "results_path", "write"]

Results = dict[str, Any]

#: The results file and the page, relative to the docs folder.
RESULTS_FILE = Path("benchmarks") / "workprecision.json"
PAGE = "BENCHMARKS.md"

#: MuJoCo's integrators in words.
_INTEGRATORS = {"Euler": "semi-implicit Euler"}
#: Right-hand-side evaluations of an rk4 substep: under error control, and fixed.
_RK4_EVALUATIONS = tuple(integ.scheme("rk4").evaluations(fixed=f) for f in (False, True))


def results_path(out: Path) -> Path:
    """Where the results file of the docs folder ``out`` is."""
    return Path(out) / RESULTS_FILE


def _subs(run: dict[str, Any]) -> str:
    s = run["substeps"]
    if run["family"].endswith("auto") or run["family"] == "dop853":
        return f"{s['mean']:.0f} (max {s['max']})"
    return f"{int(run['setting'])}"


def section_summary(results: Results) -> list[str]:
    st, paper = results["settings"], scene(results, "paper")
    d, c = default_run(paper), compare_mujoco(results, paper)
    hz = horizon(results, paper)
    L = ["## Summary", ""]
    L += [
        f"- Default settings ({st['method']}, automatic substeps at tol {st['tolerance']:.0e} "
        f"per control step, dt = {st['dt']} s) on the default scene: largest φ error over the "
        f"{hz:g}-s episode **{fmt_err(d['error'][0])} rad** (φ' {fmt_err(d['error'][1])} "
        f"rad/s), at **{fmt_time(d['seconds'] / hz)} per simulated second** "
        f"({paper['steps'] / d['seconds']:,.0f} control steps/s in the physics kernel).",
        f"- MuJoCo at its defaults ({_mj_default(st)}): φ error {fmt_err(c.default_err)} rad at "
        f"{fmt_time(c.default_cost)} per simulated second. Tuned for accuracy it reaches our "
        f"error at {c.mj_setting}, taking {fmt_time(c.mj_cost)} per simulated second: "
        + (f"ours is **{c.ratio:,.0f} ×** as fast at equal error ({c.mj_how})."
           if math.isfinite(c.ratio) else f"{c.mj_how}."),
    ]
    costs = [f"{r['method']} {r['ratio']['median']:.2f} × / {r['ratio']['p99']:.2f} × (tol "
             f"{r['tol']:.0e})" for r in cost_rows(results, "stateless") if r["measured"]]
    if costs:
        L.append("- Cost of the error control (part 5): automatic substeps against the fewest "
                 "fixed substeps that meet the same tolerance, median / 99th percentile over "
                 "random hard control steps: " + ", ".join(costs) + ".")
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
        "",
    ]
    return L


def _mj_default(st: dict[str, Any]) -> str:
    mj = st["mujoco"]["default"]
    return f"{1e3 * mj['timestep']:g} ms {mj['integrator']} steps, soft constraint"


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
        "environment steps with, `integrators.step(integrator='dop853')`, "
        "`mujoco.mj_step(model, data, n)`). `steps/s` = control steps per second of the "
        "physics alone, the ceiling of an environment's steps/s.",
        "- **Families**: `euler` = semi-implicit Euler with n fixed substeps (n = 1 is "
        "Gymnasium's Pendulum scheme); `rk4` = classical RK4 with n fixed substeps; `rk4 "
        "auto` = error control at a tolerance per control step (the environments' default: "
        f"{st['tolerance']:.0e}) with the Bogacki–Shampine 5(4) pair (its 5th-order "
        "solution carried on); "
        "`rk8`, `rk8 auto` = the same with the 8th-order Dormand–Prince tableau and its "
        "embedded estimate; `taylor`, `taylor auto` = the Taylor series of the motion to "
        f"{_degrees_in_words(st)}, n fixed substeps or each substep's size chosen from the "
        "expansion's last two terms (the environments' default integrator: "
        f"`{st['method']}`); `midpoint` = implicit midpoint, n fixed substeps; "
        "`dop853` = scipy's, at rtol = atol = tol.",
        "",
    ]


def _degrees_in_words(st: dict[str, Any]) -> str:
    """The Taylor degrees the results' settings name, and the rule between them."""
    if "taylor_degrees" not in st:  # (results measured before the degree followed tol)
        return "degree 18"
    low, high = min(st["taylor_degrees"]), max(st["taylor_degrees"])
    return (f"the degree chosen from the tolerance (column `degree`: {low} above tol "
            f"{st['taylor_lower_above']:.0e}, else {high})")


def _degree(run: dict[str, Any]) -> str:
    return "" if run.get("degree") is None else str(run["degree"])


def section_degrees(results: Results) -> list[str]:
    """taylor's degree, cost and local error at each tolerance, beside rk8's and rk4's."""
    sc = scene(results, "paper")
    hz = horizon(results, sc)
    auto = {name: {r["setting"]: r for r in sc["runs"] if r["family"] == f"{name} auto"}
            for name in ("taylor", "rk8", "rk4")}
    rows = []
    for tol in sorted(auto["taylor"], reverse=True):
        row = [f"{tol:.0e}", _degree(auto["taylor"][tol])]
        for name in ("taylor", "rk8", "rk4"):
            run = auto[name].get(tol)
            row += (["", ""] if run is None else
                    [fmt_err(run["local_error"][0]), fmt_time(run["seconds"] / hz)])
        rows.append(row)
    return ["### The Taylor degree against the tolerance", "",
            f"On `{sc['name']}` (the runs above): the degree `taylor auto` chose at each "
            "tolerance, and its largest local φ error [rad] and cost per simulated second "
            "beside those of `rk8 auto` and `rk4 auto` at the same tolerance.", "",
            *md_table(["tol", "taylor degree", "taylor local φ error", "taylor per sim. s",
                       "rk8 local φ error", "rk8 per sim. s", "rk4 local φ error",
                       "rk4 per sim. s"], rows), ""]


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
                f"{sc['steps'] / run['seconds']:,.0f}", _degree(run),
            ])
        L += md_table(["family", "setting", "φ error [rad]", "φ' error [rad/s]",
                       "local φ error [rad]", "substeps per control step", "per sim. s",
                       "steps/s", "degree"], rows)
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


def section_environments(results: Results) -> list[str]:
    env, cfg = results["environments"], results["config"]
    return [
        "## 3. The environments' error", "",
        "State error of `gymnasium.make(\"roller_gym/RollerStabilize-v2\")` itself over "
        f"the {cfg['horizon_s']:g}-s reference episode of the default scene (default settings, "
        f"stepped through the environment): φ {fmt_err(env['env_error'][0])} rad, φ' "
        f"{fmt_err(env['env_error'][1])} rad/s. The vector environment "
        f"({env['vector_error_envs']} sub-environments on the same episode, up to the first "
        f"termination): φ {fmt_err(env['vector_error'][0])} rad — the same kernel, so the "
        "same error bound. How fast the environments step, against Gymnasium's and EnvPool's, "
        "is on [`THROUGHPUT.md`](THROUGHPUT.md).", "",
    ]


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
        "- **stateless** (★): the sample's independent steps, each started afresh (its "
        "first substep predicted): the headline figures.",
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
          + ". ★: the variant of the headline figures (independent steps).", ""]
    return L


def render(results: Results) -> str:
    """The page of a results file (Markdown; no measuring)."""
    cfg = results["config"]
    L = ["# Benchmarks: speed against error", ""]
    if results["quick"]:
        L += ["> **A `--quick` run**: a short episode, two scenes, few settings. The numbers "
              "show that the benchmark works, not what it finds; run without `--quick` for "
              "the report.", ""]
    L += ["What each integrator of `roller_gym.physics` costs for the error it makes, against "
          "scipy's DOP853 (the reference) and MuJoCo on the same scene, on the default scene "
          "and five hard ones; the error of the environments themselves; and the cost of the "
          "error control on random hard control steps.", "",
          f"Generated by `{results['command']}` in {results['elapsed_s']:.0f} s (rerun it to "
          "reproduce; the machine is below). The same run measures every peer, interleaved: "
          f"best of {cfg['repeats']} repeats, and only ratios are compared.", ""]
    for section in (section_summary, section_machine, section_method, section_work_precision,
                    section_degrees, section_mujoco, section_environments, section_hard_cases,
                    section_cost):
        L += section(results)
    return "\n".join(L) + "\n"


def section_machine(results: Results) -> list[str]:
    return machine_section(
        results, "From the repository root, in its venv, `make bench` measures again (about "
        "7 minutes on an idle 2-core machine) and `roller-gym benchmark --render` draws this "
        "page and its plots again from the numbers.", RESULTS_FILE.as_posix())


def write(results: Results, out: Path) -> Path:
    """Render ``results`` into the docs folder ``out``: ``out/BENCHMARKS.md`` and
    ``out/benchmarks/*.png``; the page's path."""
    out = Path(out)
    plots.work_precision_plots(results, out / "benchmarks")
    page = out / PAGE
    page.write_text(render(results))
    return page
