"""The benchmarks' targets, and what their results say about them.

Each verdict is one small function of one study's results (the plain data of
:func:`roller_gym.bench.throughput.measure` or :func:`roller_gym.bench.workprecision.measure`,
or of the JSON file it is saved to) returning :class:`Verdict` rows; :data:`THROUGHPUT` and
:data:`WORK_PRECISION` list them. They measure nothing: the results hold every number they
read. The helpers above them read the work-precision results (a scene's runs, its default
run, MuJoCo's cost at a given error). The targets are the maintainers' (``docs/MAINTAINERS.md``
renders the verdicts); the user-facing pages show what was measured.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, NamedTuple

__all__ = ["TARGETS", "THROUGHPUT", "WORK_PRECISION", "Comparison", "Verdict", "compare_mujoco",
           "cost_at_error", "cost_rows", "throughput_verdicts", "verdict_cost", "verdict_envpool",
           "verdict_error", "verdict_mujoco", "verdict_outside_kernel", "verdict_single",
           "verdict_start", "verdict_vector", "work_precision_verdicts"]

Results = dict[str, Any]

#: Targets. The throughput study: the vector environment's steps/s against
#: CartPoleVectorEnv's and EnvPool's Pendulum-v1's, one environment's against Pendulum-v1's,
#: the seconds to make and reset 65,536 sub-environments, the share of a vector step outside
#: the physics kernel. The work-precision study: the episode's state error [rad], our speed
#: against MuJoCo's at equal error on the default scene, and the automatic substep count
#: against the smallest fixed count that meets the same tolerance on hard control steps (its
#: median and 99th percentile over the steps).
TARGETS = {
    "vector_vs_cartpole": 0.25,
    "vector_vs_envpool": 1.0,
    "single_vs_pendulum": 1.5,
    "reset_65536_s": 0.25,
    "outside_kernel_share": 0.25,
    "episode_error_rad": 1e-6,
    "mujoco_speedup": 100.0,
    "substeps_median": 2.0,
    "substeps_p99": 4.0,
}


# -- the numbers in words -------------------------------------------------------------------------
def fmt_err(x: float) -> str:
    """An error, or "diverged" where it is not finite."""
    return "diverged" if not math.isfinite(x) else f"{x:.1e}"


def fmt_time(seconds: float) -> str:
    """A duration [s], in the unit that reads best ("–" where not finite)."""
    if not math.isfinite(seconds):
        return "–"
    if seconds >= 1.0:
        return f"{seconds:.2f} s"
    if seconds >= 1e-3:
        return f"{1e3 * seconds:.3g} ms"
    return f"{1e6 * seconds:.3g} µs"


def shown(value: float, target: float) -> str:
    """``value`` to 3 significant digits, or to as many more as it takes not to read as the
    target itself (0.24996 against 0.25)."""
    for digits in range(3, 8):
        text = f"{value:.{digits}g}"
        if float(text) != target or value == target:
            return text
    return text


# -- reading the results ------------------------------------------------------------------------
def scene(results: Results, name: str) -> dict[str, Any]:
    """The results of the scene called ``name``."""
    return next(s for s in results["scenes"] if s["name"] == name)


def horizon(results: Results, sc: dict[str, Any]) -> float:
    """The episode's length [s] on a scene."""
    return sc["steps"] * results["settings"]["dt"]


def family(sc: dict[str, Any], name: str) -> list[dict[str, Any]]:
    """A scene's runs of one family (e.g. ``"rk8 auto"``, ``"MuJoCo tuned"``), in order."""
    return [r for r in sc["runs"] if r["family"] == name]


def default_run(sc: dict[str, Any]) -> dict[str, Any]:
    """A scene's run at the environments' default settings."""
    return sc["runs"][sc["default"]]


def chaotic(results: Results, sc: dict[str, Any]) -> bool:
    """True where the reference's own error passes the target bound within the episode."""
    return sc["reference"]["predictable_s"] < horizon(results, sc)


def error_of(run: dict[str, Any], metric: str) -> float:
    """The φ error [rad] of a run: ``"global"`` (along the episode) or ``"local"`` (one
    control step from the reference state)."""
    return run["error"][0] if metric == "global" else run["local_error"][0]


def cost_at_error(points: list[tuple[float, float]], target: float) -> tuple[float, str]:
    """The cost at which a family of (error, cost) points reaches ``target`` error.

    Log-log interpolation between the last point above the target and the first at or below
    it (points taken in order of cost); log-log extrapolation from the two finest points if
    none reaches it; ``(nan, why)`` if that is not possible either.
    """
    pts = sorted((c, e) for e, c in points if math.isfinite(e) and e > 0)
    for i, (c, e) in enumerate(pts):
        if e <= target:
            if i == 0:
                return c, "reached at its cheapest setting"
            c0, e0 = pts[i - 1]
            if e0 <= e:
                return c, "reached"
            x = math.log(target / e0) / math.log(e / e0)
            return math.exp(math.log(c0) + x * math.log(c / c0)), "interpolated"
    if len(pts) >= 2:
        (c0, e0), (c1, e1) = pts[-2], pts[-1]
        if e1 < e0 / 2:  # a clear trend: extrapolate, but not beyond 100 times the finest cost
            x = math.log(target / e0) / math.log(e1 / e0)
            cost = math.exp(math.log(c0) + x * math.log(c1 / c0))
            if cost <= 100 * c1:
                return cost, "extrapolated"
            return math.nan, f"not reached: would cost over 100 × its finest ({fmt_time(c1)})"
    return math.nan, "not reached: its error stops falling"


class Comparison(NamedTuple):
    """Ours at default settings against MuJoCo (tuned) at equal error, on one scene."""

    scene: str
    metric: str  # "global" or "local"
    our_err: float  # [rad]
    our_cost: float  # [s per simulated s]
    mj_cost: float  # [s per simulated s]
    mj_how: str
    mj_setting: str
    ratio: float
    default_err: float  # MuJoCo at its defaults [rad]
    default_cost: float  # [s per simulated s]


def compare_mujoco(results: Results, sc: dict[str, Any], metric: str = "global") -> Comparison:
    """What MuJoCo (tuned) needs to reach the error of our default settings, and its cost."""
    dt = results["settings"]["dt"]
    hz = horizon(results, sc)
    ours = default_run(sc)
    floor = sc["reference"]["own_error"][0] if metric == "global" else 1e-14
    target = max(error_of(ours, metric), floor)
    tuned = family(sc, "MuJoCo tuned")
    cost, how = cost_at_error([(error_of(r, metric), r["seconds"] / hz) for r in tuned], target)
    # the MuJoCo timestep that reaches it: the error falls as timestep² along the tuned family
    setting = "–"
    finite = [r for r in tuned if math.isfinite(error_of(r, metric)) and error_of(r, metric) > 0]
    if math.isfinite(cost) and finite:
        reached = [r for r in finite if error_of(r, metric) <= target]
        if reached:
            r0 = min(reached, key=lambda r: r["seconds"])
            setting = (f"timestep {1e3 * dt / r0['setting']:.3g} ms "
                       f"({int(r0['setting'])} per step)")
        else:
            finest = min(finite, key=lambda r: error_of(r, metric))
            ts = dt / finest["setting"] * math.sqrt(target / error_of(finest, metric))
            setting = f"timestep ≈ {1e3 * ts:.2g} ms (≈ {dt / ts:.0f} per step)"
    own_steps = round(dt / results["settings"]["mujoco"]["default"]["timestep"])
    default = next((r for r in family(sc, "MuJoCo default") if r["setting"] == own_steps), None)
    our_cost = ours["seconds"] / hz
    return Comparison(
        sc["name"], metric, error_of(ours, metric), our_cost, cost, how, setting,
        cost / our_cost,
        error_of(default, metric) if default else math.nan,
        default["seconds"] / hz if default else math.nan,
    )


# -- the verdicts: one small function each ----------------------------------------------------
class Verdict(NamedTuple):
    """A target and what was measured against it.

    Attributes:
        target: what is asked, in words.
        measured: what was measured, in words and numbers.
        met: True or False; None where the results cannot tell.
        miss: how far off, where not met (or why it cannot be told).
        value: the number judged, where there is one (a ratio, a share, seconds, radians).
    """

    target: str
    measured: str
    met: bool | None
    miss: str = ""
    value: float = math.nan

    @property
    def sentence(self) -> str:
        """The verdict as the report writes it."""
        if self.met is None:
            return f"**not judged**: {self.miss}"
        return "**met**" if self.met else f"**missed**: {self.miss}"


# -- the throughput study ------------------------------------------------------------------------
def _ratio_verdicts(results: Results, peer: str, key: str) -> list[Verdict]:
    """The vector environment's steps/s at least ``TARGETS[key]`` × ``peer``'s, per size
    measured (none where the peer was not measured)."""
    target = TARGETS[key]
    out = []
    for n, v in results["vector"].items():
        if peer not in v:
            continue
        r = v["ours"] / v[peer]
        out.append(Verdict(
            f"vector env ≥ {target:g} × {peer} at {int(n):,} sub-environments",
            f"{shown(r, target)} × ({v['ours']:,.0f} against {v[peer]:,.0f} steps/s)",
            r >= target, f"{r / target:.2f} of the target ({target / r:.1f}× too slow)", r))
    return out


def verdict_vector(results: Results) -> list[Verdict]:
    """The vector environment against ``CartPoleVectorEnv``, per size."""
    return _ratio_verdicts(results, "CartPoleVectorEnv", "vector_vs_cartpole")


def verdict_envpool(results: Results) -> list[Verdict]:
    """The vector environment against EnvPool's Pendulum-v1, per size (where measured)."""
    return _ratio_verdicts(results, "EnvPool Pendulum-v1", "vector_vs_envpool")


def verdict_outside_kernel(results: Results) -> list[Verdict]:
    """The share of a vector step outside the physics kernel, at the largest size, at most
    ``outside_kernel_share``."""
    n, v = max(results["vector"].items(), key=lambda item: int(item[0]))
    target, share = TARGETS["outside_kernel_share"], v["outside_kernel_share"]
    return [Verdict(f"share of a vector step outside the physics kernel at {int(n):,} ≤ "
                    f"{target:.0%}", f"{shown(share, target)}", share <= target,
                    f"{share / target:.2f} × the bound", share)]


def verdict_start(results: Results) -> list[Verdict]:
    """Making and resetting the vector environment within ``reset_65536_s`` seconds."""
    target = TARGETS["reset_65536_s"]
    return [Verdict(f"make_vec + reset of {int(n):,} ≤ {target:g} s", f"{shown(s, target)} s",
                    s <= target, f"{s / target:.2f} × the bound", s)
            for n, s in results["start_seconds"].items()]


def verdict_single(results: Results) -> list[Verdict]:
    """One environment through ``gymnasium.make``: its steps/s at least
    ``single_vs_pendulum`` × Pendulum-v1's."""
    target, single = TARGETS["single_vs_pendulum"], results["single"]
    ratio = single["ours"] / single["Pendulum-v1"]
    return [Verdict(f"one environment ≥ {target:g} × Pendulum-v1's steps/s",
                    f"{shown(ratio, target)} × Pendulum-v1 ({single['ours']:,.0f} against "
                    f"{single['Pendulum-v1']:,.0f} steps/s)",
                    ratio >= target, f"speed {ratio / target:.2f} of the target", ratio)]


# -- the work-precision study ---------------------------------------------------------------------
def verdict_error(results: Results) -> list[Verdict]:
    """The state error over the episode of the environment at default settings (and of the
    default integrator on the default scene) at most ``episode_error_rad`` [rad]."""
    bound, env_error = TARGETS["episode_error_rad"], results["environments"]["env_error"][0]
    paper = scene(results, "paper")
    error = max(env_error, default_run(paper)["error"][0])
    return [Verdict(f"{horizon(results, paper):g}-s episode's error ≤ {bound:g} rad",
                    f"{fmt_err(env_error)} rad through the environment, "
                    f"{fmt_err(default_run(paper)['error'][0])} rad in the stepper",
                    error <= bound, f"error {error / bound:.1f} × the bound", error)]


def verdict_mujoco(results: Results) -> list[Verdict]:
    """Our default settings at least ``mujoco_speedup`` × faster than MuJoCo tuned at equal
    global error on the default scene."""
    target = TARGETS["mujoco_speedup"]
    paper = scene(results, "paper")
    c, c_local = compare_mujoco(results, paper), compare_mujoco(results, paper, "local")
    what = f"≥ {target:g} × MuJoCo's speed at equal error (default scene)"
    if not math.isfinite(c.ratio):
        return [Verdict(what, "MuJoCo tuned does not reach our error", None, c.mj_how)]
    local = (f"{c_local.ratio:,.0f} ×" if math.isfinite(c_local.ratio) else c_local.mj_how)
    return [Verdict(
        what,
        f"{c.ratio:,.0f} × (MuJoCo tuned needs {fmt_time(c.mj_cost)} per simulated second to "
        f"reach our {fmt_err(c.our_err)} rad, we take {fmt_time(c.our_cost)}; {c.mj_how}); "
        f"at equal local error {local}",
        c.ratio >= target, f"{c.ratio / target:.2f} of the target", c.ratio)]


def cost_rows(results: Results, variant: str | None = None) -> list[dict[str, Any]]:
    """The rows of the cost measurement (one per method, tolerance and variant; none in a
    results file from before it), of one ``variant`` (``"stateless"``, ``"carried"``) if
    given."""
    rows = results.get("cost", {}).get("rows", [])
    return [r for r in rows if variant is None or r["variant"] == variant]


def verdict_cost(results: Results) -> list[Verdict]:
    """Per error-controlled method and tolerance: its automatic substep count at most
    ``substeps_median`` × the smallest fixed count that meets the tolerance (both counted in
    right-hand-side evaluations, see :func:`roller_gym.bench.cost.compare`) in the median of
    the hard steps measured, and at most ``substeps_p99`` × at their 99th percentile. Judged
    on the variant the results name (the independent steps: ``"stateless"``)."""
    med_t, p99_t = TARGETS["substeps_median"], TARGETS["substeps_p99"]
    variant = results.get("cost", {}).get("settings", {}).get("verdict_variant", "stateless")
    out = []
    for row in cost_rows(results, variant):
        ratio = row["ratio"]
        what = (f"{row['method']} tol {row['tol']:.0e}: automatic substeps ≤ {med_t:g} × the "
                f"smallest fixed count meeting tol (median), ≤ {p99_t:g} × (99th percentile), "
                "in right-hand-side evaluations")
        if not row["measured"]:
            out.append(Verdict(what, "no step measured", None, "every step was skipped"))
            continue
        misses = [f"{name} {x:.2f} × ({x / t:.2f} × the target)"
                  for name, x, t in (("median", ratio["median"], med_t),
                                     ("99th percentile", ratio["p99"], p99_t)) if x > t]
        out.append(Verdict(
            what,
            f"median {ratio['median']:.2f} ×, 99th percentile {ratio['p99']:.2f} × over "
            f"{row['measured']} hard steps ({row['steps'] - row['measured']} skipped); error "
            f"≤ tol in {100 * row['within_tol']:.1f} % of them",
            not misses, "; ".join(misses)))
    return out


#: The throughput study's verdicts, in the order the maintainers' page lists them.
THROUGHPUT: tuple[Callable[[Results], list[Verdict]], ...] = (
    verdict_vector, verdict_envpool, verdict_outside_kernel, verdict_start, verdict_single)
#: The work-precision study's verdicts, in that order.
WORK_PRECISION: tuple[Callable[[Results], list[Verdict]], ...] = (
    verdict_error, verdict_mujoco, verdict_cost)


def throughput_verdicts(results: Results) -> list[Verdict]:
    """Every verdict on the throughput study's results."""
    return [v for verdict in THROUGHPUT for v in verdict(results)]


def work_precision_verdicts(results: Results) -> list[Verdict]:
    """Every verdict on the work-precision study's results."""
    return [v for verdict in WORK_PRECISION for v in verdict(results)]
