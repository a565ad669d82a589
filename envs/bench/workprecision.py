"""The work-precision study: what every integrator costs for the error it makes, MuJoCo on
the same scene, and the error of the environments themselves, measured in one run.

:func:`measure` returns the results as plain data (numbers, strings, lists and dicts: what
:mod:`roller_gym.bench.report` saves as JSON and renders). Its parts:

1. **Work-precision.** On the default scene and the hard cases, every integrator
   (semi-implicit Euler, RK4 and RK8 with fixed substeps, RK4 and RK8 with error control at
   several tolerances, implicit midpoint, scipy's DOP853) runs one episode of random torques.
   Cost: wall time per simulated second. Error: the largest state error along the episode
   against a DOP853 reference at rtol = atol = 1e-13 (global), and the largest error of one
   control step started from the reference state (local). Then the energy error at zero
   torque over a long horizon.
2. **MuJoCo** on the same scene (:mod:`roller_gym.bench.mujoco_roller`): at its default
   settings and at settings tuned for accuracy, the same episodes and errors, timed
   interleaved with ours.
3. **The environments' error**: the reference episode stepped through ``gymnasium.make``
   and ``gymnasium.make_vec`` at default settings (their speed is the throughput study's,
   :mod:`roller_gym.bench.throughput`).
4. **Hard cases**: from the same runs, substeps, errors, energy error, non-finite steps and
   contact loss.
5. **Cost of the error control** (:mod:`roller_gym.bench.cost`): on random hard control
   steps, rk8's and rk4's automatic substep counts against the smallest fixed counts that
   meet the same tolerance, and their errors.

Timing: every comparison is measured in this process, interleaved, best of repeats
(:mod:`roller_gym.bench.timing`). The figures to compare are ratios of such timings.
"""

from __future__ import annotations

import dataclasses
import inspect
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from itertools import pairwise
from typing import Any

import mujoco
import numpy as np
from roller_gym.bench import mujoco_roller as mjr
from roller_gym.bench import records, timing
from roller_gym.bench.cost import CostConfig
from roller_gym.bench.cost import measure as measure_cost
from roller_gym.bench.env_error import global_error, measure_environments
from roller_gym.bench.verdicts import TARGETS
from roller_gym.config import DEFAULT_DT, DEFAULT_TOLERANCE
from roller_gym.physics import Scene, energy, preset, taylor
from roller_gym.physics import integrators as integ
from roller_gym.physics.integrators import STEP_FIELDS, Stepper
from roller_gym.roller_env import RollerEnv
from roller_gym.task import Task

__all__ = ["SCENES", "SCENE_NOTES", "Config", "episode_torques", "global_error", "measure",
           "run_dop853", "run_kernel"]

# ================================================================================================
# Settings: the environments' defaults, the reference, the scenes
# ================================================================================================
#: The control step [s], the tolerance per control step, the largest torque [N·m] and the
#: integrator of the environments at their defaults.
DT = float(DEFAULT_DT)
DEFAULT_TOL = float(DEFAULT_TOLERANCE)
MAX_TORQUE = float(Task.default_max_torque)
DEFAULT_INTEGRATOR: str = inspect.signature(RollerEnv).parameters["integrator"].default
#: The reference: DOP853 at rtol = atol = REFERENCE_TOL.
REFERENCE_TOL = 1e-13
#: The bound [rad] on the 10-s episode's state error.
TARGET_ERROR = float(TARGETS["episode_error_rad"])
SEED = 0
#: A run slower than this [s] is timed once more at most.
SLOW_S = 1.0

#: The default scene and the hard cases (PHYSICS.md, "Where the numerics get hard").
SCENES: dict[str, Scene] = {
    "paper": preset("paper"),
    "tight_fit": preset("tight_fit"),
    "rim_mass": preset("rim_mass"),
    "floor": preset("floor"),
    "drum": preset("drum"),
    "huge_R": Scene(R=1e12),
}
SCENE_NOTES = {
    "paper": "the default scene: R = 5 r, e = 0.4 r",
    "tight_fit": "R = 1.01 r: ψ turns 100 times faster than φ",
    "rim_mass": "e = 0.99 r, k = 0.05 r: J_I nearly vanishes at θ = 0",
    "floor": "a flat floor (R = ∞)",
    "drum": "on top of a drum of radius 0.5 m",
    "huge_R": "R = 1e12 m: a floor written as a cylinder",
}

#: Points of each energy curve kept in the results: the largest error in each of this many
#: log-spaced intervals of time.
ENERGY_POINTS = 120


@dataclass(frozen=True)
class Config:
    """What a run measures; :meth:`make` with ``quick`` shrinks every list."""

    quick: bool
    horizon_s: float = 10.0  # the episode [s] (the environments' 200 steps of 0.05 s)
    repeats: int = 5  # timing repeats (best kept); runs slower than SLOW_S get fewer
    scenes: tuple[str, ...] = tuple(SCENES)
    euler_substeps: tuple[int, ...] = (1, 10, 100, 1000, 10000)
    rk4_substeps: tuple[int, ...] = (1, 2, 4, 8, 16, 32, 64, 128, 256, 1024, 4096)
    rk8_substeps: tuple[int, ...] = (1, 2, 4, 8, 16, 32, 64, 256, 1024)
    taylor_substeps: tuple[int, ...] = (1, 2, 4, 8, 16, 64, 256)
    auto_tols: tuple[float, ...] = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12)
    midpoint_substeps: tuple[int, ...] = (1, 4, 16, 64, 256, 1024, 4096)
    dop853_tols: tuple[float, ...] = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
    mujoco_default_n: tuple[int, ...] = (25, 100, 400)  # MuJoCo steps per control step
    mujoco_tuned_n: tuple[int, ...] = (25, 50, 100, 200, 400, 800, 1600)
    energy_horizon_s: float = 1000.0
    vector_error_envs: int = 16  # sub-environments of make_vec on the reference episode
    cost: CostConfig = field(default_factory=CostConfig)  # part 5

    @classmethod
    def make(cls, quick: bool) -> Config:
        """The full run, or with ``quick`` a smoke run of every part."""
        if not quick:
            return cls(quick)
        return cls(
            quick, horizon_s=2.0, repeats=2, scenes=("paper", "floor"),
            euler_substeps=(1, 10, 100), rk4_substeps=(1, 4, 16, 64), rk8_substeps=(1, 4),
            taylor_substeps=(1, 4),
            auto_tols=(1e-4, 1e-6, 1e-8, 1e-10), midpoint_substeps=(1, 16),
            dop853_tols=(1e-6, 1e-12), mujoco_default_n=(25,), mujoco_tuned_n=(25, 100),
            energy_horizon_s=20.0, cost=CostConfig.make(quick),
        )


# ================================================================================================
# The episode, the runs, timing, errors
# ================================================================================================
_FIELD = {name: i for i, name in enumerate(STEP_FIELDS)}


def episode_torques(steps: int, seed: int = SEED) -> np.ndarray:
    """The drive [N·m] per control step: what random actions of an environment ask for.

    Actions uniform in [−1, 1] (float32, as an action space samples them) times the
    environments' default ``max_torque`` [N·m].
    """
    rng = np.random.default_rng(seed)
    actions = rng.uniform(-1.0, 1.0, steps).astype(np.float32)
    return actions.astype(np.float64) * MAX_TORQUE


def start_state(scene: Scene) -> tuple[float, float]:
    """The energy runs' start (φ0 [rad], 0 [rad/s]): at rest, with max(|φ0|, |ψ0|) = 0.5 rad."""
    psi_per_phi = abs(float(scene.r * scene.kappa / (1.0 - scene.r * scene.kappa)))
    return 0.5 / max(1.0, psi_per_phi), 0.0


@dataclass
class Trajectory:
    """A run's states after each control step, and what its steps reported."""

    states: np.ndarray  # (n + 1, 2): φ [rad], φ' [rad/s]
    substeps: np.ndarray  # (n,)
    finite: bool
    lifting: np.ndarray | None = None  # (n,) bool, where the integrator reports it
    slipping: np.ndarray | None = None


def run_kernel(stepper: Stepper, torques: Sequence[float], phi0: float = 0.0,
               phi_dot0: float = 0.0) -> Trajectory:
    """An episode through ``stepper`` (a :class:`Stepper`, as the environment steps), one
    call per control step at the torques [N·m] given, from (φ0 [rad], φ'0 [rad/s])."""
    n = len(torques)
    states, subs = np.empty((n + 1, 2)), np.zeros(n, dtype=np.int64)
    lift, slip = np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)
    i_n, i_ok = _FIELD["substeps"], _FIELD["finite"]
    i_lift, i_slip = _FIELD["liftoff_margin"], _FIELD["slip_margin"]
    phi, w = phi0, phi_dot0
    states[0] = phi, w
    advance = stepper.advance
    for i, tau in enumerate(torques):
        res = advance(phi, w, tau)
        if not res[i_ok]:
            states[i + 1:] = np.nan
            return Trajectory(states, subs, False, lift, slip)
        phi, w = res[0], res[1]
        states[i + 1] = phi, w
        subs[i], lift[i], slip[i] = res[i_n], res[i_lift] <= 0.0, res[i_slip] < 0.0
    return Trajectory(states, subs, True, lift, slip)


def run_dop853(scene: Scene, torques: Sequence[float], dt: float, tol: float,
               phi0: float = 0.0, phi_dot0: float = 0.0) -> Trajectory:
    """An episode through scipy's DOP853 (``integrators.step(integrator="dop853")``) at
    rtol = atol = ``tol``, restarted at each control step of ``dt`` [s]."""
    n = len(torques)
    states, subs = np.empty((n + 1, 2)), np.zeros(n, dtype=np.int64)
    phi, w = phi0, phi_dot0
    states[0] = phi, w
    for i, tau in enumerate(torques):
        res = integ.step(scene, phi, w, tau, dt, integrator="dop853", tolerance=tol)
        if not res.finite:
            states[i + 1:] = np.nan
            return Trajectory(states, subs, False)
        phi, w = res.phi, res.phi_dot
        states[i + 1] = phi, w
        subs[i] = res.substeps
    return Trajectory(states, subs, True)


def run_mujoco(sim: mjr.MujocoRoller, torques: Sequence[float], dt: float) -> Trajectory:
    """An episode through MuJoCo (the model is built before, outside the timing)."""
    states = sim.run(0.0, 0.0, torques, dt)
    n = sim.steps_per(dt)
    return Trajectory(states, np.full(len(torques), n), bool(np.isfinite(states).all()))


def local_error(stepper: Stepper, ref: np.ndarray, torques: Sequence[float]) -> tuple[float, float]:
    """The largest error (|Δφ| [rad], |Δφ'| [rad/s]) of one control step from the reference."""
    worst = np.zeros(2)
    for i, tau in enumerate(torques):
        res = stepper.advance(ref[i, 0], ref[i, 1], tau)
        if not res[_FIELD["finite"]]:
            return math.inf, math.inf
        worst = np.maximum(worst, np.abs(np.array(res[:2]) - ref[i + 1]))
    return float(worst[0]), float(worst[1])


def mujoco_local_error(sim: mjr.MujocoRoller, ref: np.ndarray, torques: Sequence[float],
                       dt: float) -> tuple[float, float]:
    """The same for MuJoCo: one control step from each reference state (put on the
    constraint), against the reference's next state."""
    n, worst = sim.steps_per(dt), np.zeros(2)
    for i, tau in enumerate(torques):
        sim.reset(ref[i, 0], ref[i, 1])
        sim.step(tau, n)
        if sim.diverged:
            return math.inf, math.inf
        worst = np.maximum(worst, np.abs(np.array(sim.state()) - ref[i + 1]))
    return float(worst[0]), float(worst[1])


def predictability(floor: np.ndarray, bound: float = TARGET_ERROR) -> float:
    """The time [s] at which the reference's own φ error (|ref(1e-12) − ref(1e-13)| [rad]
    along the episode) first exceeds ``bound`` [rad]: beyond it, global errors under ~1 rad
    are not measurable, and the trajectory is sensitive (chaotic) rather than the integrators
    poor."""
    above = np.flatnonzero(floor > bound)
    return math.inf if above.size == 0 else float(above[0] * DT)


@dataclass
class Run:
    """One candidate on one scene: how it is run, and what it measured."""

    scene: str
    family: str
    label: str
    fn: Callable[[], Trajectory]
    ours: bool = True
    stepper: Stepper | None = None  # our compiled schemes
    sim: mjr.MujocoRoller | None = None  # MuJoCo
    setting: float = 0.0  # substeps, tolerance or MuJoCo steps per control step
    tol: float = 0.0
    seconds: float = math.inf  # the best wall time of the episode [s]
    traj: Trajectory | None = None
    err: tuple[float, float] = (math.inf, math.inf)
    local: tuple[float, float] = (math.nan, math.nan)

    @property
    def finite(self) -> bool:
        return self.traj is not None and self.traj.finite


def time_runs(runs: list[Run], repeats: int) -> None:
    """Time every candidate ``repeats`` times, interleaved (:func:`roller_gym.bench.timing.best`);
    keep each one's best time and its first trajectory.

    A run slower than ``SLOW_S`` [s] is repeated at most once more (its noise is relatively
    small and the budget is not).
    """

    def once(run: Run) -> Callable[[], float]:
        def timed() -> float:
            t0 = time.perf_counter()
            traj = run.fn()
            elapsed = time.perf_counter() - t0
            if run.traj is None:
                run.traj = traj
            return elapsed

        return timed

    def slow(_key: Any, rep: int, seconds: float) -> bool:
        return (rep >= 2 and seconds > SLOW_S) or (rep >= 1 and seconds > 10 * SLOW_S)

    seconds = timing.best({i: once(run) for i, run in enumerate(runs)}, repeats, skip=slow)
    for i, run in enumerate(runs):
        run.seconds = min(run.seconds, seconds[i])


# ================================================================================================
# Parts 1 and 2: work-precision, ours and MuJoCo, per scene
# ================================================================================================
@dataclass
class SceneResult:
    """Everything measured on one scene."""

    name: str
    scene: Scene
    torques: np.ndarray
    ref: Trajectory
    ref_seconds: float
    ref_floor: tuple[float, float]  # |ref(1e-13) − ref(1e-12)|: the reference's own error
    runs: list[Run]
    default: Run
    predictable_s: float = math.inf  # when the reference's own error passes TARGET_ERROR
    energy: list[dict[str, Any]] = field(default_factory=list)


def kernel_families(cfg: Config) -> list[tuple[str, str, tuple[float, ...]]]:
    """(family, method, settings) of our compiled integrators: fixed substeps or, for the
    "auto" families, tolerances per control step (the default's tolerance always in)."""
    tols = tuple(sorted({*cfg.auto_tols, DEFAULT_TOL}, reverse=True))
    return [("euler", "euler", cfg.euler_substeps), ("rk4", "rk4", cfg.rk4_substeps),
            ("rk4 auto", "rk4", tols), ("rk8", "rk8", cfg.rk8_substeps),
            ("rk8 auto", "rk8", tols), ("taylor", "taylor", cfg.taylor_substeps),
            ("taylor auto", "taylor", tols), ("midpoint", "midpoint", cfg.midpoint_substeps)]


def build_runs(cfg: Config, name: str, scene: Scene, torques: list[float]) -> list[Run]:
    """Every candidate on one scene, ours and MuJoCo's."""
    runs: list[Run] = []
    for family, method, settings in kernel_families(cfg):
        auto = family.endswith("auto")
        for x in settings:
            tol, n = (x, None) if auto else (DEFAULT_TOL, int(x))
            stepper = Stepper(scene, integrator=method, dt=DT, tolerance=tol, substeps=n)
            runs.append(Run(
                name, family, f"tol {tol:.0e}" if auto else f"×{n}",
                lambda s=stepper: run_kernel(s, torques), stepper=stepper, setting=x, tol=tol,
            ))
    for tol in cfg.dop853_tols:
        runs.append(Run(name, "dop853", f"tol {tol:.0e}",
                        lambda tol=tol: run_dop853(scene, torques, DT, tol), setting=tol,
                        tol=tol))
    for family, ns, settings in (
        ("MuJoCo default", cfg.mujoco_default_n, lambda n: mjr.DEFAULT.with_timestep(DT / n)),
        ("MuJoCo tuned", cfg.mujoco_tuned_n, lambda n: mjr.tuned(DT / n)),
    ):
        for n in ns:
            sim = mjr.MujocoRoller(scene, settings(n))
            runs.append(Run(name, family, f"{1e3 * DT / n:.3g} ms",
                            lambda sim=sim: run_mujoco(sim, torques, DT), ours=False, sim=sim,
                            setting=n))
    return runs


def measure_scene(cfg: Config, name: str) -> SceneResult:
    """Parts 1 and 2 on one scene: the reference, then every candidate timed interleaved."""
    scene = SCENES[name]
    torques = episode_torques(round(cfg.horizon_s / DT))
    tq = [float(t) for t in torques]
    t0 = time.perf_counter()
    ref = run_dop853(scene, tq, DT, REFERENCE_TOL)
    ref_seconds = time.perf_counter() - t0
    runs = build_runs(cfg, name, scene, tq)
    time_runs(runs, cfg.repeats)
    check = next((r for r in runs if r.family == "dop853" and r.setting == 1e-12), None)
    check_traj = check.traj if check is not None and check.finite else run_dop853(
        scene, tq, DT, 1e-12)
    floor = global_error(check_traj.states, ref.states)
    horizon_ok = predictability(np.abs(check_traj.states[:, 0] - ref.states[:, 0]))
    for run in runs:
        run.err = global_error(run.traj.states, ref.states)
        if run.stepper is not None:
            run.local = local_error(run.stepper, ref.states, tq)
        elif run.sim is not None:
            run.local = mujoco_local_error(run.sim, ref.states, tq, DT)
    default = next(r for r in runs if r.family == f"{DEFAULT_INTEGRATOR} auto"
                   and r.tol == DEFAULT_TOL)
    return SceneResult(name, scene, torques, ref, ref_seconds, floor, runs, default,
                       predictable_s=horizon_ok)


def energy_envelope(rel: np.ndarray, points: int = ENERGY_POINTS) -> dict[str, list[float]]:
    """The largest relative energy error in each of ``points`` log-spaced intervals of the
    control steps after the first: ``{"t": start of each interval [s], "value": ...}``
    (NaN where the run had stopped, being non-finite)."""
    edges = np.unique(np.round(np.geomspace(1, len(rel), points + 1)).astype(int))
    t, value = [], []
    for a, b in pairwise(edges):
        seg = rel[a:b]
        seg = seg[~np.isnan(seg)]
        t.append(round(a * DT, 10))
        value.append(float(f"{seg.max():.4g}") if seg.size else math.nan)
    return {"t": t, "value": value}


def measure_energy(cfg: Config, result: SceneResult) -> None:
    """Energy error at zero torque over ``cfg.energy_horizon_s`` [s] from rest at φ0."""
    scene = result.scene
    phi0, w0 = start_state(scene)
    zeros = [0.0] * round(cfg.energy_horizon_s / DT)
    e0 = float(energy(scene, phi0, w0))
    for label, method, tol, n in (
        ("euler ×1 (Pendulum's scheme)", "euler", DEFAULT_TOL, 1),
        ("euler ×10", "euler", DEFAULT_TOL, 10),
        ("midpoint ×10", "midpoint", DEFAULT_TOL, 10),
        ("rk4 ×10", "rk4", DEFAULT_TOL, 10),
        ("rk8 ×4", "rk8", DEFAULT_TOL, 4),
        (f"{DEFAULT_INTEGRATOR} auto tol {DEFAULT_TOL:.0e} (default)", DEFAULT_INTEGRATOR,
         DEFAULT_TOL, None),
    ):
        stepper = Stepper(scene, integrator=method, dt=DT, tolerance=tol, substeps=n)
        t0 = time.perf_counter()
        traj = run_kernel(stepper, zeros, phi0, w0)
        seconds = time.perf_counter() - t0
        finite = np.isfinite(traj.states).all(axis=1)  # (energy() refuses a diverged state)
        e = np.full(len(traj.states), np.nan)
        e[finite] = energy(scene, traj.states[finite, 0], traj.states[finite, 1])
        rel = np.abs(e - e0) / abs(e0)
        # a blow-up: the first state whose energy is off by more than E0 (or not finite)
        bad = np.flatnonzero(~(rel <= 1.0))
        result.energy.append({
            "label": label, "seconds": seconds, "finite": traj.finite,
            "blowup_s": float(bad[0] * DT) if bad.size else math.inf,
            "max": float(np.nanmax(rel)) if traj.finite else math.inf,
            "end": float(rel[-1]) if traj.finite else math.inf,
            "curve": energy_envelope(rel),
        })


# ================================================================================================
# The results: plain data
# ================================================================================================
def _pair(x: Sequence[float]) -> list[float]:
    return [float(x[0]), float(x[1])]


def run_record(run: Run) -> dict[str, Any]:
    """One run's numbers: cost [s], errors (φ [rad], φ' [rad/s]), substeps, contact."""
    traj = run.traj
    subs = traj.substeps
    return {
        "family": run.family, "label": run.label, "setting": float(run.setting),
        "ours": run.ours, "seconds": run.seconds, "finite": traj.finite,
        "error": _pair(run.err), "local_error": _pair(run.local),
        "substeps": {"min": int(subs.min()), "median": float(np.median(subs)),
                     "mean": float(subs.mean()), "max": int(subs.max())},
        "lifting": None if traj.lifting is None else int(traj.lifting.sum()),
        "degree": run.stepper.degree if run.family.startswith("taylor") else None,
        "slipping": None if traj.slipping is None else int(traj.slipping.sum()),
    }


def scene_record(res: SceneResult) -> dict[str, Any]:
    """One scene's numbers: the reference, every run, the energy runs."""
    states = res.ref.states
    return {
        "name": res.name, "note": SCENE_NOTES[res.name], "mu": float(res.scene.mu),
        "steps": len(res.torques),
        "reference": {
            "seconds": res.ref_seconds, "steps": int(res.ref.substeps.sum()),
            "own_error": _pair(res.ref_floor), "predictable_s": res.predictable_s,
            "max_abs_phi": float(np.nanmax(np.abs(states[:, 0]))),
            "max_abs_phi_dot": float(np.nanmax(np.abs(states[:, 1]))),
        },
        "default": res.runs.index(res.default),
        "runs": [run_record(r) for r in res.runs],
        "energy": res.energy,
    }


def versions() -> dict[str, str | None]:
    """The versions of the packages measured: roller-gym, its peers and its dependencies."""
    return {**records.machine()["versions"], **records.package_versions(("scipy", "mujoco"))}


def settings() -> dict[str, Any]:
    """The fixed settings of the study: the environments' defaults, the reference, MuJoCo's
    settings (SI units: s, N·m, rad)."""
    tuned = mjr.tuned(1.0)  # per unit timestep
    return {
        "dt": DT, "tolerance": DEFAULT_TOL, "method": DEFAULT_INTEGRATOR,
        "max_torque": MAX_TORQUE, "reference_tol": REFERENCE_TOL,
        "target_error": TARGET_ERROR, "seed": SEED, "slow_s": SLOW_S,
        "parallel_threshold": integ.PARALLEL_THRESHOLD,
        "taylor_degrees": list(taylor.DEGREES), "taylor_lower_above": taylor.LOWER_DEGREE_ABOVE,
        "mujoco": {
            "default": dataclasses.asdict(mjr.DEFAULT),
            "tuned": {"integrator": tuned.integrator, "solimp": list(tuned.solimp),
                      "tolerance": tuned.tolerance, "iterations": tuned.iterations,
                      "refsafe": tuned.refsafe, "timeconst_per_timestep": tuned.solref[0],
                      "dampratio": tuned.solref[1]},
            "arm_mass": mjr.ARM_MIN,
        },
    }


def measure(cfg: Config, command: str, progress: Callable[[str], None] = timing.progress
            ) -> dict[str, Any]:
    """Measure parts 1 to 5; the results as plain data (see :mod:`roller_gym.bench.records`).

    Args:
        cfg: what to measure.
        command: the command line that ran the measurement, recorded with the results.
        progress: called with a line as each measurement starts and as each scene ends
            (default: on stderr).
    """
    t_start = time.perf_counter()
    date = records.now()
    mujoco.set_mju_user_warning(lambda _msg: None)  # divergence is detected from mjData
    progress("compiling (or loading) the kernels")  # compilation is not what is measured
    for method in ("rk4", "rk8", "taylor", "euler", "midpoint"):
        Stepper(SCENES["paper"], integrator=method, dt=DT,
                tolerance=DEFAULT_TOL).advance(0.1, 0.0, 0.0)
    results = []
    for name in cfg.scenes:
        t0 = time.perf_counter()
        progress(f"{name}: the reference, then every integrator and MuJoCo, {cfg.repeats} "
                 "interleaved repeats")
        res = measure_scene(cfg, name)
        progress(f"{name}: energy at zero torque over {cfg.energy_horizon_s:g} s")
        measure_energy(cfg, res)
        results.append(res)
        d = res.default
        progress(f"{name}: default φ error {d.err[0]:.1e} rad (local {d.local[0]:.1e}), "
                 f"{d.seconds / cfg.horizon_s * 1e6:,.0f} µs per simulated s; reference's own "
                 f"error {res.ref_floor[0]:.1e} rad ({time.perf_counter() - t0:.0f} s)")
    paper = next(r for r in results if r.name == "paper")
    progress("the environments' error on the default scene's episode")
    environments = measure_environments(paper.ref.states, paper.torques,
                                        cfg.vector_error_envs, SEED)
    costs = measure_cost(cfg.cost, command, progress)
    return {
        "study": "work-precision",
        "machine": {**records.machine(), "versions": versions()},
        "date": date,
        "command": command,
        "elapsed_s": time.perf_counter() - t_start,
        "quick": cfg.quick,
        "settings": settings(),
        "config": dataclasses.asdict(cfg),
        "scenes": [scene_record(r) for r in results],
        "environments": environments,
        "cost": costs,
    }
