"""The maintainers' page, ``docs/MAINTAINERS.md``: the benchmarks' targets, the verdicts of
both studies' committed results against them, and what would close each miss, rendered from
the results files (no measuring; :mod:`roller_gym.bench.verdicts` judges). What is not data
(the history of runs, how to work on the project) is written by hand below
:data:`HAND_WRITTEN` on the page, and kept as it is when the page is rendered again.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from roller_gym.bench import records, report, throughput
from roller_gym.bench.markdown import date, md_table
from roller_gym.bench.report import _RK4_EVALUATIONS
from roller_gym.bench.verdicts import (
    TARGETS,
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
    throughput_verdicts,
    verdict_cost,
    work_precision_verdicts,
)
from roller_gym.physics import integrators as integ

Results = dict[str, Any]

PAGE = "MAINTAINERS.md"
#: The line under which the page is written by hand (kept when the page is rendered again).
HAND_WRITTEN = "<!-- Written by hand below this line: `render` keeps it. -->"


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


def _verdict_table(verdicts: list) -> list[str]:
    return md_table(["target", "measured", "verdict"],
                    [[v.target, v.measured, v.sentence] for v in verdicts])


def render(wp: Results | None, tp: Results | None, hand_written: str = "") -> str:
    """The page from the two studies' results (either may be None: not measured yet), with
    ``hand_written`` (the text under :data:`HAND_WRITTEN`) at its end."""
    L = ["# For maintainers: the benchmarks' targets", "",
         "The targets the project holds its speed and accuracy to, and how the committed "
         "results stand against them. The user-facing pages, `BENCHMARKS.md` and "
         "`THROUGHPUT.md`, show what was measured; this page is rendered from the same "
         "results files (`roller-gym benchmark --render`, `python -m "
         "roller_gym.bench.throughput render`), the targets are "
         "`roller_gym.bench.verdicts.TARGETS`.", ""]
    if tp is not None:
        L += ["## Throughput", "", f"`{tp['command']}`, {date(tp['date'])}:", "",
              *_verdict_table(throughput_verdicts(tp)), ""]
    if wp is not None:
        L += ["## Work-precision", "", f"`{wp['command']}`, {date(wp['date'])}:", "",
              *_verdict_table(work_precision_verdicts(wp)), "",
              "## What is met, and what would close the misses", "", *target_notes(wp, tp), ""]
    return "\n".join([*L, HAND_WRITTEN, hand_written.strip("\n"), ""])


def write(out: Path) -> Path:
    """Render the page into the docs folder ``out`` from its results files, keeping what is
    written by hand on it; the page's path."""
    out = Path(out)
    files = (report.results_path(out), out / throughput.RESULTS_FILE)
    wp, tp = (records.load_results(f) if f.is_file() else None for f in files)
    page = out / PAGE
    old = page.read_text() if page.is_file() else ""
    hand = old.split(HAND_WRITTEN, 1)[1] if HAND_WRITTEN in old else ""
    page.write_text(render(wp, tp, hand))
    return page


def throughput_notes(results: Results, tp: Results) -> list[str]:
    """The throughput targets, and what would close them if missed, with the work-precision
    study's kernel figures beside the throughput study's."""
    st, env = results["settings"], results["environments"]
    method = st["method"]
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
        f"{fmt_err(env['env_error'][0])} rad (bound {TARGETS['episode_error_rad']:g}). The "
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
            f"{100 * v['ours'] / v['kernel']:.0f} % of this kernel's rate (the share of a "
            "step spent outside the physics kernel along an episode is in `THROUGHPUT.md`). "
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
            "gets cheaper, the environment's work around it (`THROUGHPUT.md`: the "
            "share of a step outside the physics kernel, and the kernel against its "
            "arithmetic)."
        )
        notes.append(text)
    return notes


def target_notes(results: Results, tp: Results | None) -> list[str]:
    """Each target, and what would close it if missed (``results``: the work-precision
    study's; ``tp``: the throughput study's, or None where there is none)."""
    st = results["settings"]
    tol = st["tolerance"]
    paper = scene(results, "paper")
    notes = (["- No throughput results: `make throughput` measures them."] if tp is None
             else throughput_notes(results, tp))
    c, mj_target = compare_mujoco(results, paper), TARGETS["mujoco_speedup"]
    notes.append(
        f"- **MuJoCo at equal error (default scene)**: {c.ratio:,.0f} × (target "
        f"{mj_target:g} ×). "
        + ("Met. " if c.ratio >= mj_target else
           "Missed. MuJoCo tuned is limited by its soft constraint (error ∝ timestep²) and "
           "pays a constraint solve per RK4 stage; ours integrates a closed-form ODE. To "
           "close it: fewer substeps for the same error, or a cheaper kernel. ")
        + "The hard scenes are in the table of part 2 of `BENCHMARKS.md`: where MuJoCo's "
        "tuned family does not reach our error within its finest timestep its cost is "
        "extrapolated along its trend (and says so), or reported as not reached."
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
    return notes
