"""Speed against error: the work-precision benchmark of roller-gym, peers measured in the same run.

    python scripts/benchmark.py             # the full run (~13 min on 2 cores): docs/BENCHMARKS.md
    python scripts/benchmark.py --quick     # seconds: a smoke run of every part
    python scripts/benchmark.py --out DIR   # write DIR/BENCHMARKS.md and DIR/benchmarks/*.png

Read top to bottom; each part is a section:

1. **Work-precision.** On the default scene and the hard cases, every integrator (semi-implicit
   Euler, RK4 with fixed substeps, RK4 with automatic substeps at several tolerances, the
   8th-order Dormand–Prince tableau (rk8, the environments' default) likewise, implicit
   midpoint, scipy's DOP853) runs one episode of random torques. Cost: wall time per
   simulated second. Error: the largest state error along the episode against a DOP853
   reference at rtol = atol = 1e-13 (global), and the largest error of one control step
   started from the reference state (local). Then the energy error at zero torque over a
   long horizon.
2. **MuJoCo** on the same scene (``roller_gym.bench.mujoco_roller``): at its default settings and
   at settings tuned for accuracy, the same episodes and metric, timed interleaved with ours.
3. **Throughput**: one environment through ``gymnasium.make`` against Pendulum-v1, the vector
   environment against Gymnasium's ``CartPoleVectorEnv``, stable-baselines3's PPO.
4. **Hard cases**: substeps, errors, energy error, non-finite steps and contact loss.

Timing: every comparison is measured in this process, interleaved (one repeat of every
candidate, then the next repeat), and the best of the repeats is kept: other processes on the
machine slow a run down, never speed it up. Figures to compare are ratios of such timings.
"""

from __future__ import annotations

import argparse
import datetime
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path

import mujoco
import numpy as np
from roller_gym.bench.throughput import machine
from roller_gym.physics import Scene, energy, preset
from roller_gym.physics import integrators as integ
from roller_gym.bench import mujoco_roller as mjr

ROOT = Path(__file__).resolve().parents[1]

# ================================================================================================
# Settings
# ================================================================================================
DT, DEFAULT_TOL, MAX_TORQUE, DEFAULT_METHOD = 0.05, 1e-8, 0.5, "rk4"
try:  # the environments' defaults: control step, tolerance, torque, integrator
    import inspect

    from roller_gym.config import DEFAULT_DT, DEFAULT_TOLERANCE
    from roller_gym.roller_env import RollerEnv
    from roller_gym.task import Task

    DT, DEFAULT_TOL = float(DEFAULT_DT), float(DEFAULT_TOLERANCE)
    MAX_TORQUE = float(Task.default_max_torque)
    DEFAULT_METHOD = inspect.signature(RollerEnv).parameters["integrator"].default
except ImportError:  # pragma: no cover - before the environments exist
    pass
REFERENCE_TOL = 1e-13  # the reference: DOP853 at rtol = atol = 1e-13
TARGET_ERROR = 1e-6  # [rad] the target's bound on the 10-s state error
SEED = 0

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


@dataclass(frozen=True)
class Config:
    """What a run measures; ``--quick`` shrinks every list."""

    quick: bool
    out: Path
    horizon_s: float = 10.0  # the episode [s] (the environments' 200 steps of 0.05 s)
    repeats: int = 5  # timing repeats (best kept); runs slower than SLOW_S get fewer
    scenes: tuple[str, ...] = tuple(SCENES)
    euler_substeps: tuple[int, ...] = (1, 10, 100, 1000, 10000)
    rk4_substeps: tuple[int, ...] = (1, 2, 4, 8, 16, 32, 64, 128, 256, 1024, 4096)
    rk8_substeps: tuple[int, ...] = (1, 2, 4, 8, 16, 32, 64, 256, 1024)
    auto_tols: tuple[float, ...] = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12)
    midpoint_substeps: tuple[int, ...] = (1, 4, 16, 64, 256, 1024, 4096)
    dop853_tols: tuple[float, ...] = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
    mujoco_default_n: tuple[int, ...] = (25, 100, 400)  # MuJoCo steps per control step
    mujoco_tuned_n: tuple[int, ...] = (25, 50, 100, 200, 400, 800, 1600)
    energy_horizon_s: float = 1000.0
    vector_sizes: tuple[int, ...] = (1, 16, 256, 4096, 65536)
    env_steps: int = 4000  # steps per repeat for the single environments
    ppo_steps: int = 2048

    @classmethod
    def make(cls, quick: bool, out: Path) -> Config:
        if not quick:
            return cls(quick, out)
        return cls(
            quick, out, horizon_s=2.0, repeats=2, scenes=("paper", "floor"),
            euler_substeps=(1, 10, 100), rk4_substeps=(1, 4, 16, 64), rk8_substeps=(1, 4),
            auto_tols=(1e-4, 1e-6, 1e-8, 1e-10), midpoint_substeps=(1, 16),
            dop853_tols=(1e-6, 1e-12), mujoco_default_n=(25,), mujoco_tuned_n=(25, 100),
            energy_horizon_s=20.0, vector_sizes=(1, 16, 256), env_steps=1000, ppo_steps=128,
        )


SLOW_S = 1.0  # a run slower than this [s] is timed once more at most


def parse_args(argv: Sequence[str] | None = None) -> Config:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a smoke run in seconds")
    parser.add_argument("--out", type=Path, default=ROOT / "docs",
                        help="where BENCHMARKS.md and benchmarks/*.png go (default: docs)")
    args = parser.parse_args(argv)
    return Config.make(args.quick, args.out)


# ================================================================================================
# Helpers: the episode, the runs, timing, errors
# ================================================================================================
_FIELD = {f.name: i for i, f in enumerate(fields(integ.StepResult))}


def kernel_row(scene: Scene) -> tuple[float, ...]:
    """The numbers the compiled kernels take: ``(*Scene.params, mu)`` as floats."""
    return (*(float(p) for p in scene.params), float(scene.mu))


def episode_torques(steps: int, seed: int = SEED) -> np.ndarray:
    """The drive [N·m] per control step: what random actions of an environment ask for.

    Actions uniform in [−1, 1] (float32, as an action space samples them) times the
    environments' default ``max_torque`` (0.5 N·m, about a third of the paper scene's largest
    holding torque m g (r + e)).
    """
    rng = np.random.default_rng(seed)
    actions = rng.uniform(-1.0, 1.0, steps).astype(np.float32)
    return actions.astype(np.float64) * MAX_TORQUE


def start_state(scene: Scene) -> tuple[float, float]:
    """The energy runs' start (φ0 [rad], 0): at rest, with max(|φ0|, |ψ0|) = 0.5 rad."""
    psi_per_phi = abs(float(scene.r * scene.kappa / (1.0 - scene.r * scene.kappa)))
    return 0.5 / max(1.0, psi_per_phi), 0.0


@dataclass
class Trajectory:
    """A run's states after each control step, and what its steps reported."""

    states: np.ndarray  # (n + 1, 2): φ [rad], φ' [rad/s]
    substeps: np.ndarray  # (n,)
    finite: bool
    lifting: np.ndarray | None = None  # (n,) bool, where the kernel reports it
    slipping: np.ndarray | None = None


def run_kernel(row: tuple[float, ...], torques: Sequence[float], dt: float, method: str,
               tol: float, substeps: int, phi0: float = 0.0, phi_dot0: float = 0.0) -> Trajectory:
    """An episode through ``integrators.step_one``, the path the environment takes."""
    code, n = integ.METHODS[method], len(torques)
    states, subs = np.empty((n + 1, 2)), np.zeros(n, dtype=np.int64)
    lift, slip = np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)
    i_n, i_ok = _FIELD["substeps"], _FIELD["finite"]
    i_lift, i_slip = _FIELD["liftoff_margin"], _FIELD["slip_margin"]
    phi, w = phi0, phi_dot0
    states[0] = phi, w
    step_one = integ.step_one
    for i, tau in enumerate(torques):
        res = step_one(row, phi, w, tau, dt, code, tol, substeps)
        if not res[i_ok]:
            states[i + 1:] = np.nan
            return Trajectory(states, subs, False, lift, slip)
        phi, w = res[0], res[1]
        states[i + 1] = phi, w
        subs[i], lift[i], slip[i] = res[i_n], res[i_lift] <= 0.0, res[i_slip] < 0.0
    return Trajectory(states, subs, True, lift, slip)


def run_dop853(scene: Scene, torques: Sequence[float], dt: float, tol: float,
               phi0: float = 0.0, phi_dot0: float = 0.0) -> Trajectory:
    """An episode through scipy's DOP853 (``integrators.step(method="dop853")``)."""
    n = len(torques)
    states, subs = np.empty((n + 1, 2)), np.zeros(n, dtype=np.int64)
    phi, w = phi0, phi_dot0
    states[0] = phi, w
    for i, tau in enumerate(torques):
        res = integ.step(scene, phi, w, tau, dt, method="dop853", tol=tol)
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
    finite = bool(np.isfinite(states).all())
    return Trajectory(states, np.full(len(torques), n), finite)


def local_error(row: tuple[float, ...], ref: np.ndarray, torques: Sequence[float], dt: float,
                method: str, tol: float, substeps: int) -> tuple[float, float]:
    """The largest error (|Δφ| [rad], |Δφ'| [rad/s]) of one control step from the reference."""
    code, worst = integ.METHODS[method], np.zeros(2)
    for i, tau in enumerate(torques):
        res = integ.step_one(row, ref[i, 0], ref[i, 1], tau, dt, code, tol, substeps)
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
    """The time [s] at which the reference's own φ error (|ref(1e-12) − ref(1e-13)| along the
    episode) first exceeds ``bound``: beyond it, global errors under ~1 rad are not
    measurable, and the trajectory is sensitive (chaotic) rather than the integrators poor."""
    above = np.flatnonzero(floor > bound)
    return math.inf if above.size == 0 else float(above[0] * DT)


def global_error(states: np.ndarray, ref: np.ndarray) -> tuple[float, float]:
    """The largest error along the episode (|Δφ| [rad], |Δφ'| [rad/s]); inf if it diverged."""
    if not np.isfinite(states).all():
        return math.inf, math.inf
    worst = np.abs(states - ref).max(axis=0)
    return float(worst[0]), float(worst[1])


@dataclass
class Run:
    """One candidate on one scene: how it is run, and what it measured."""

    scene: str
    family: str
    label: str
    fn: Callable[[], Trajectory]
    ours: bool = True
    sim: mjr.MujocoRoller | None = None
    setting: float = 0.0  # substeps, tolerance or MuJoCo steps per control step
    method: str = ""  # our kernels' method, tolerance and fixed substeps (0: automatic)
    tol: float = 0.0
    substeps: int = 0
    seconds: float = math.inf  # the best wall time of the episode [s]
    traj: Trajectory | None = None
    err: tuple[float, float] = (math.inf, math.inf)
    local: tuple[float, float] = (math.nan, math.nan)

    @property
    def finite(self) -> bool:
        return self.traj is not None and self.traj.finite


def time_interleaved(runs: list[Run], repeats: int) -> None:
    """Run every candidate ``repeats`` times, interleaved; keep the result and the best time.

    A run slower than ``SLOW_S`` is repeated at most once more (its noise is relatively small
    and the budget is not).
    """
    for rep in range(repeats):
        for run in runs:
            if (rep >= 2 and run.seconds > SLOW_S) or (rep >= 1 and run.seconds > 10 * SLOW_S):
                continue
            t0 = time.perf_counter()
            traj = run.fn()
            elapsed = time.perf_counter() - t0
            run.seconds = min(run.seconds, elapsed)
            if run.traj is None:
                run.traj = traj


def best(times: dict[str, Callable[[], float]], repeats: int) -> dict[str, float]:
    """The best of ``repeats`` interleaved measurements; each callable returns its own time."""
    out = dict.fromkeys(times, math.inf)
    for _ in range(repeats):
        for key, fn in times.items():
            out[key] = min(out[key], fn())
    return out


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


# ================================================================================================
# Part 1 and 2: work-precision, ours and MuJoCo, per scene
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
    energy: list[dict] = field(default_factory=list)
    default: Run | None = None
    predictable_s: float = math.inf  # when the reference's own error passes 1e-6 rad

    @property
    def chaotic(self) -> bool:
        """The reference's own error passes the target bound within the episode."""
        return self.predictable_s < len(self.torques) * DT

    def family(self, name: str) -> list[Run]:
        return [r for r in self.runs if r.family == name]


def kernel_families(cfg: Config) -> list[tuple[str, str, tuple[float, ...]]]:
    """(family, method, settings) of our compiled integrators: fixed substeps or, for the
    "auto" families, tolerances per control step (the default's tolerance always in)."""
    tols = tuple(sorted({*cfg.auto_tols, DEFAULT_TOL}, reverse=True))
    fams = [("euler", "euler", cfg.euler_substeps), ("rk4", "rk4", cfg.rk4_substeps),
            ("rk4 auto", "rk4", tols)]
    if "rk8" in integ.METHODS:
        fams += [("rk8", "rk8", cfg.rk8_substeps), ("rk8 auto", "rk8", tols)]
    fams += [("midpoint", "midpoint", cfg.midpoint_substeps)]
    return fams


OUR_FAMILIES = ("euler", "rk4", "rk4 auto", "rk8", "rk8 auto", "midpoint", "dop853")
MJ_FAMILIES = ("MuJoCo default", "MuJoCo tuned")


def build_runs(cfg: Config, name: str, scene: Scene, torques: list[float]) -> list[Run]:
    """Every candidate on one scene, ours and MuJoCo's."""
    row, dt = kernel_row(scene), DT
    runs: list[Run] = []
    for family, method, settings in kernel_families(cfg):
        auto = family.endswith("auto")
        for x in settings:
            tol, n = (x, 0) if auto else (DEFAULT_TOL, int(x))
            runs.append(Run(
                name, family, f"tol {tol:.0e}" if auto else f"×{n}",
                lambda method=method, tol=tol, n=n: run_kernel(row, torques, dt, method, tol, n),
                setting=x, method=method, tol=tol, substeps=n,
            ))
    for tol in cfg.dop853_tols:
        runs.append(Run(name, "dop853", f"tol {tol:.0e}",
                        lambda tol=tol: run_dop853(scene, torques, dt, tol), setting=tol))
    for family, ns, settings in (
        ("MuJoCo default", cfg.mujoco_default_n, lambda n: mjr.DEFAULT.with_timestep(dt / n)),
        ("MuJoCo tuned", cfg.mujoco_tuned_n, lambda n: mjr.tuned(dt / n)),
    ):
        for n in ns:
            sim = mjr.MujocoRoller(scene, settings(n))
            label = f"{1e3 * dt / n:.3g} ms"
            runs.append(Run(name, family, label, lambda sim=sim: run_mujoco(sim, torques, dt),
                            ours=False, sim=sim, setting=n))
    return runs


def measure_scene(cfg: Config, name: str) -> SceneResult:
    """Part 1 and 2 on one scene: the reference, then every candidate timed interleaved."""
    scene = SCENES[name]
    steps = round(cfg.horizon_s / DT)
    torques = episode_torques(steps)
    tq = [float(t) for t in torques]
    t0 = time.perf_counter()
    ref = run_dop853(scene, tq, DT, REFERENCE_TOL)
    ref_seconds = time.perf_counter() - t0
    runs = build_runs(cfg, name, scene, tq)
    time_interleaved(runs, cfg.repeats)
    check = next((r for r in runs if r.family == "dop853" and r.setting == 1e-12), None)
    if check is None or not check.finite:
        check_traj = run_dop853(scene, tq, DT, 1e-12)
    else:
        check_traj = check.traj
    floor = global_error(check_traj.states, ref.states)
    horizon_ok = predictability(np.abs(check_traj.states[:, 0] - ref.states[:, 0]))
    row = kernel_row(scene)
    for run in runs:
        run.err = global_error(run.traj.states, ref.states)
        if run.method:
            run.local = local_error(row, ref.states, tq, DT, run.method, run.tol, run.substeps)
        elif run.sim is not None:
            run.local = mujoco_local_error(run.sim, ref.states, tq, DT)
    result = SceneResult(name, scene, torques, ref, ref_seconds, floor, runs,
                         predictable_s=horizon_ok)
    result.default = next(r for r in runs if r.family == f"{DEFAULT_METHOD} auto"
                          and r.tol == DEFAULT_TOL)
    return result


def measure_energy(cfg: Config, result: SceneResult) -> None:
    """Energy error at zero torque over ``cfg.energy_horizon_s`` from rest at φ0."""
    scene, row = result.scene, kernel_row(result.scene)
    phi0, w0 = start_state(scene)
    steps = round(cfg.energy_horizon_s / DT)
    zeros = [0.0] * steps
    e0 = float(energy(scene, phi0, w0))
    for label, method, tol, n in (
        ("euler ×1 (Pendulum's scheme)", "euler", DEFAULT_TOL, 1),
        ("euler ×10", "euler", DEFAULT_TOL, 10),
        ("midpoint ×10", "midpoint", DEFAULT_TOL, 10),
        ("rk4 ×10", "rk4", DEFAULT_TOL, 10),
        *([("rk8 ×4", "rk8", DEFAULT_TOL, 4)] if "rk8" in integ.METHODS else []),
        (f"{DEFAULT_METHOD} auto tol {DEFAULT_TOL:.0e} (default)", DEFAULT_METHOD,
         DEFAULT_TOL, 0),
    ):
        t0 = time.perf_counter()
        traj = run_kernel(row, zeros, DT, method, tol, n, phi0, w0)
        seconds = time.perf_counter() - t0
        e = np.asarray(energy(scene, traj.states[:, 0], traj.states[:, 1]), dtype=float)
        rel = np.abs(e - e0) / abs(e0)
        # a blow-up: the first state whose energy is off by more than E0 (or not finite)
        bad = np.flatnonzero(~(rel <= 1.0))
        result.energy.append({
            "label": label, "seconds": seconds, "finite": traj.finite,
            "blowup_s": float(bad[0] * DT) if bad.size else math.inf,
            "max": float(np.nanmax(rel)) if traj.finite else math.inf,
            "end": float(rel[-1]) if traj.finite else math.inf,
            "curve": rel, "substeps": traj.substeps,
        })


# ================================================================================================
# Part 3: throughput (the environments)
# ================================================================================================
def envs_available() -> str | None:
    """None if ``gymnasium.make("roller_gym/RollerStabilize-v1")`` works, else why not."""
    try:
        import gymnasium as gym
        import roller_gym  # noqa: F401

        gym.make("roller_gym/RollerStabilize-v1").close()
    except Exception as exc:  # the environments may not exist yet
        return f"{type(exc).__name__}: {exc}"
    return None


def time_single_env(env, actions: np.ndarray) -> float:
    """Wall time [s] of ``len(actions)`` calls of ``env.step`` (resets not counted)."""
    env.reset(seed=SEED)
    total = 0.0
    clock = time.perf_counter
    for a in actions:
        t0 = clock()
        _, _, terminated, truncated, _ = env.step(a)
        total += clock() - t0
        if terminated or truncated:
            env.reset()
    return total


def time_vector_env(env, actions: np.ndarray) -> float:
    """Wall time [s] of ``len(actions)`` batched steps, going on from the env's state (its
    autoresets count, the first reset does not)."""
    t0 = time.perf_counter()
    for a in actions:
        env.step(a)
    return time.perf_counter() - t0


def env_episode_error(ref: np.ndarray, torques: np.ndarray) -> tuple[float, float]:
    """The state error of ``gymnasium.make("roller_gym/RollerStabilize-v1")`` (default
    settings) over the reference episode: the same start (rest at φ = 0) and the same
    torques, through the env."""
    import gymnasium as gym

    env = gym.make("roller_gym/RollerStabilize-v1")
    base = env.unwrapped
    base.reset(seed=SEED, options={"state": (0.0, 0.0)})
    states = [(0.0, 0.0)]
    for tau in torques:  # the episode goes on past a termination: the physics is measured
        base.step(np.array([tau / base.task.max_torque], dtype=np.float32))
        states.append((base.phi, base.phi_dot))
    env.close()
    return global_error(np.array(states), ref)


def vector_episode_error(ref: np.ndarray, torques: np.ndarray, n: int) -> tuple[float, float]:
    """The same for ``gymnasium.make_vec`` with ``n`` sub-environments, all on the reference
    episode, up to the first step at which one terminates (autoreset would restart it)."""
    import gymnasium as gym

    env = gym.make_vec("roller_gym/RollerStabilize-v1", num_envs=n)
    env.reset(seed=SEED, options={"state": (0.0, 0.0)})
    base = env.unwrapped
    worst = np.zeros(2)
    for i, tau in enumerate(torques):
        a = np.full((n, 1), tau / base.task.max_torque, dtype=np.float32)
        _, _, terminated, truncated, info = env.step(a)
        if terminated.any() or truncated.any():
            break
        got = np.stack([info["phi"], info["phi_dot"]], axis=1)
        worst = np.maximum(worst, np.abs(got - ref[i + 1]).max(axis=0))
    env.close()
    return float(worst[0]), float(worst[1])


def batch_kernel(scene: Scene, n: int, rng: np.random.Generator) -> Callable[[], float]:
    """A callable timing one control step of ``n`` rollers through the physics kernel alone
    (``integrators.advance_batch``, what the vector environment calls; the parallel kernel
    from ``PARALLEL_THRESHOLD`` rollers on), at the default settings; returns seconds."""
    rows = np.ascontiguousarray(np.tile(np.array(kernel_row(scene)), (n, 1)))
    phi, w = rng.uniform(-0.5, 0.5, n), rng.uniform(-1.0, 1.0, n)
    tau = rng.uniform(-MAX_TORQUE, MAX_TORQUE, n)
    code = integ.METHODS[DEFAULT_METHOD]
    raw = np.empty((len(_FIELD), n))

    def once() -> float:
        t0 = time.perf_counter()
        if hasattr(integ, "advance_batch"):
            integ.advance_batch(rows, phi, w, tau, DT, code, DEFAULT_TOL, 0, raw)
        else:  # pragma: no cover - older physics
            integ.step(scene, phi, w, tau, DT, method=DEFAULT_METHOD, tol=DEFAULT_TOL)
        return time.perf_counter() - t0

    return once


@dataclass
class Throughput:
    single: dict[str, float] = field(default_factory=dict)  # steps/s
    vector: dict[int, dict[str, float]] = field(default_factory=dict)  # n -> name -> steps/s
    resets: dict[int, dict[str, float]] = field(default_factory=dict)  # n -> name -> [s]
    ppo: dict[str, float] = field(default_factory=dict)  # training steps/s
    env_error: tuple[float, float] = (math.nan, math.nan)
    vector_error: tuple[float, float] = (math.nan, math.nan)
    vector_error_steps: int = 0
    notes: list[str] = field(default_factory=list)


def measure_throughput(cfg: Config, paper: SceneResult) -> Throughput:
    """Part 3: steps per second, ours against Gymnasium's own, interleaved."""
    import gymnasium as gym
    import roller_gym  # noqa: F401 - registers the environments
    from gymnasium.envs.classic_control.cartpole import CartPoleVectorEnv

    out = Throughput()
    rng = np.random.default_rng(SEED)
    # -- one environment through gymnasium.make, against Pendulum-v1 ------------------------
    ours, pendulum = gym.make("roller_gym/RollerStabilize-v1"), gym.make("Pendulum-v1")
    actions = rng.uniform(-1.0, 1.0, (cfg.env_steps, 1)).astype(np.float32)
    pend_actions = 2.0 * actions  # Pendulum's action space is [−2, 2]
    for env in (ours, pendulum):  # warm up (compilation, first reset)
        time_single_env(env, actions[:50])
    # cheap (~0.1 s a repeat) and sensitive to the load: three times the repeats
    t = best({"ours": lambda: time_single_env(ours, actions),
              "Pendulum-v1": lambda: time_single_env(pendulum, pend_actions)}, 3 * cfg.repeats)
    out.single = {k: cfg.env_steps / v for k, v in t.items()}
    ours.close()
    pendulum.close()
    out.env_error = env_episode_error(paper.ref.states, paper.torques)
    # -- the vector environment against CartPoleVectorEnv --------------------------------
    scene = preset("paper")
    for n in cfg.vector_sizes:
        # at 4096 and below the window passes step 200, where the episodes begun together
        # are truncated together and restarted by the autoreset
        steps = int(np.clip(1_000_000 // n, 20, 1000)) if not cfg.quick else 20
        ours_v = gym.make_vec("roller_gym/RollerStabilize-v1", num_envs=n)
        cart = CartPoleVectorEnv(num_envs=n)
        a_ours = rng.uniform(-1.0, 1.0, (steps, n, 1)).astype(np.float32)
        a_cart = rng.integers(0, 2, (steps, n))
        resets = {}
        for key, env in (("ours", ours_v), ("CartPoleVectorEnv", cart)):
            t0 = time.perf_counter()
            env.reset(seed=SEED)
            resets[key] = time.perf_counter() - t0
        out.resets[n] = resets
        time_vector_env(ours_v, a_ours[:2])  # warm up
        time_vector_env(cart, a_cart[:2])
        kernel = batch_kernel(scene, n, rng)
        kernel()
        t = best({"ours": lambda e=ours_v, a=a_ours: time_vector_env(e, a),
                  "CartPoleVectorEnv": lambda e=cart, a=a_cart: time_vector_env(e, a),
                  "kernel": lambda k=kernel, steps=steps: sum(k() for _ in range(steps))},
                 cfg.repeats if n < 65536 else min(cfg.repeats, 3))
        out.vector[n] = {k: n * steps / v for k, v in t.items()}
        ours_v.close()
        cart.close()
    out.vector_error = vector_episode_error(paper.ref.states, paper.torques, 16)
    # -- stable-baselines3: PPO training steps per second ---------------------------------
    try:
        import torch
        from stable_baselines3 import PPO

        torch.set_num_threads(1)

        def train(env_id: str) -> float:
            env = gym.make(env_id)
            model = PPO("MlpPolicy", env, n_steps=min(256, cfg.ppo_steps), batch_size=64,
                        n_epochs=4, seed=SEED, device="cpu", verbose=0)
            t0 = time.perf_counter()
            model.learn(total_timesteps=cfg.ppo_steps)
            elapsed = time.perf_counter() - t0
            env.close()
            return elapsed

        t = best({"ours": lambda: train("roller_gym/RollerStabilize-v1"),
                  "Pendulum-v1": lambda: train("Pendulum-v1")}, 1 if cfg.quick else 2)
        out.ppo = {k: cfg.ppo_steps / v for k, v in t.items()}
    except ImportError as exc:  # pragma: no cover - SB3 is an optional extra
        out.notes.append(f"stable-baselines3 not measured: {exc}")
    return out


# ================================================================================================
# The report
# ================================================================================================
def fmt_err(x: float) -> str:
    return "diverged" if not math.isfinite(x) else f"{x:.1e}"


def fmt_time(seconds: float) -> str:
    """A duration, in the unit that reads best."""
    if not math.isfinite(seconds):
        return "–"
    if seconds >= 1.0:
        return f"{seconds:.2f} s"
    if seconds >= 1e-3:
        return f"{1e3 * seconds:.3g} ms"
    return f"{1e6 * seconds:.3g} µs"


def machine_info() -> list[str]:
    """CPU model, cores, library versions, date."""
    m = machine()
    versions = ", ".join(f"{k} {v or '(not installed)'}" for k, v in m["versions"].items())
    return [
        f"- CPU: {m['cpu']}, {m['cores']} cores ({m['os']}), Python {m['python']}",
        f"- {versions}",
        f"- Date: {datetime.datetime.now().astimezone():%Y-%m-%d %H:%M %Z} (timings are "
        "best-of-repeats, and only ratios measured in this run are compared)",
    ]


def md_table(header: list[str], rows: list[list[str]]) -> list[str]:
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    return out


def verdict_single(ratio: float, error: float) -> str:
    """The verdict on the one-environment target: speed ≥ 1.5 × Pendulum, error ≤ 1e-6 rad."""
    misses = []
    if ratio < 1.5:
        misses.append(f"speed {ratio / 1.5:.2f} of the target")
    if not error <= TARGET_ERROR:
        misses.append(f"error {error / TARGET_ERROR:.1f} × the bound")
    return "**met**" if not misses else "**missed**: " + "; ".join(misses)


@dataclass
class Comparison:
    """Ours at default settings against MuJoCo (tuned) at equal error, on one scene."""

    scene: str
    metric: str  # "global" or "local"
    our_err: float  # [rad]
    our_cost: float  # [s per simulated s]
    mj_cost: float
    mj_how: str
    mj_setting: str
    ratio: float
    default_err: float  # MuJoCo at its defaults
    default_cost: float


def error_of(run: Run, metric: str) -> float:
    """The φ error [rad] of a run: global (along the episode) or local (one control step)."""
    return run.err[0] if metric == "global" else run.local[0]


def compare_mujoco(res: SceneResult, metric: str = "global") -> Comparison:
    """What MuJoCo (tuned) needs to reach the error of our default settings, and its cost."""
    horizon = len(res.torques) * DT
    ours = res.default
    floor = res.ref_floor[0] if metric == "global" else 1e-14
    target = max(error_of(ours, metric), floor)
    tuned = res.family("MuJoCo tuned")
    cost, how = cost_at_error([(error_of(r, metric), r.seconds / horizon) for r in tuned], target)
    # the MuJoCo timestep that reaches it: the error falls as timestep² along the tuned family
    setting = "–"
    finite = [r for r in tuned if math.isfinite(error_of(r, metric)) and error_of(r, metric) > 0]
    if math.isfinite(cost) and finite:
        reached = [r for r in finite if error_of(r, metric) <= target]
        if reached:
            r0 = min(reached, key=lambda r: r.seconds)
            setting = f"timestep {1e3 * DT / r0.setting:.3g} ms ({int(r0.setting)} per step)"
        else:
            finest = min(finite, key=lambda r: error_of(r, metric))
            ts = DT / finest.setting * math.sqrt(target / error_of(finest, metric))
            setting = f"timestep ≈ {1e3 * ts:.2g} ms (≈ {DT / ts:.0f} per step)"
    default = next((r for r in res.family("MuJoCo default") if r.setting == 25), None)
    return Comparison(
        res.name, metric, error_of(ours, metric), ours.seconds / horizon, cost, how, setting,
        cost / (ours.seconds / horizon),
        error_of(default, metric) if default else math.nan,
        default.seconds / horizon if default else math.nan,
    )


COLORS = {"euler": "tab:red", "rk4": "tab:blue", "rk4 auto": "tab:green", "rk8": "tab:cyan",
          "rk8 auto": "tab:olive",
          "midpoint": "tab:purple", "dop853": "tab:gray", "MuJoCo default": "tab:orange",
          "MuJoCo tuned": "tab:brown"}
MARKERS = {"euler": "v", "rk4": "o", "rk4 auto": "s", "rk8": "h", "rk8 auto": "p",
           "midpoint": "D", "dop853": "^",
           "MuJoCo default": "X", "MuJoCo tuned": "P"}


def plot_work_precision(results: list[SceneResult], path: Path, metric: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cols = min(3, len(results))
    rows = math.ceil(len(results) / cols)
    legend_in = 1.3  # inches under the plots for the legend
    height = 4.2 * rows + legend_in
    fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, height), squeeze=False)
    for ax, res in zip(axes.flat, results, strict=False):
        horizon = len(res.torques) * DT
        for fam in (*OUR_FAMILIES, *MJ_FAMILIES):
            # in the order of the setting (substeps up, tolerance down, timestep down)
            # (runs that blew up past 100 rad are left out: they are in the tables)
            pts = [(error_of(r, metric), r.seconds / horizon) for r in res.family(fam)
                   if error_of(r, metric) <= 100.0]
            if pts:
                e, c = zip(*pts, strict=True)
                ax.loglog(np.maximum(e, 1e-16), c, marker=MARKERS[fam], color=COLORS[fam],
                          label=fam, lw=1.2, ms=5, ls="--" if fam.startswith("MuJoCo") else "-")
        d = res.default
        ax.loglog([max(error_of(d, metric), 1e-16)], [d.seconds / horizon], "*", color="k",
                  ms=15, label=f"default ({DEFAULT_METHOD}, tol {DEFAULT_TOL:.0e})", zorder=5)
        if metric == "global":
            ax.axvline(max(res.ref_floor[0], 1e-16), color="k", lw=0.8, ls=":",
                       label="reference's own error")
            ax.axvline(TARGET_ERROR, color="tab:red", lw=0.8, ls="-.", label="target 1e-6 rad")
        else:
            ax.axvline(DEFAULT_TOL, color="tab:red", lw=0.8, ls="-.",
                       label=f"tolerance {DEFAULT_TOL:.0e}")
        title = f"{res.name}: {SCENE_NOTES[res.name]}"
        if metric == "global" and res.chaotic:
            title += f"\n(chaotic: the reference itself is off by 1e-6 at {res.predictable_s:g} s)"
        ax.set_title(title, fontsize=9)
        ax.set_xlabel(f"largest |φ error| over {horizon:g} s [rad]" if metric == "global"
                      else "largest |φ error| of one control step [rad]")
        ax.set_ylabel("wall time per simulated second [s]")
        ax.grid(True, which="major", alpha=0.3)
    for ax in axes.flat[len(results):]:
        ax.axis("off")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=6, fontsize=8)
    fig.suptitle(f"Work-precision, {metric} error: cost against error (lower left is better), "
                 "all measured in the same run")
    fig.tight_layout(rect=(0, legend_in / height, 1, 1 - 0.4 / height))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_energy(results: list[SceneResult], path: Path, horizon: float) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cols = min(3, len(results))
    rows = math.ceil(len(results) / cols)
    legend_in = 1.0
    height = 3.8 * rows + legend_in
    fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, height), squeeze=False)
    for ax, res in zip(axes.flat, results, strict=False):
        for item in res.energy:
            curve = item["curve"]
            t = np.arange(len(curve)) * DT
            ax.loglog(t[1:], np.clip(curve[1:], 1e-17, 1e2), lw=1, label=item["label"])
        ax.set_ylim(1e-17, 1e2)  # a blow-up leaves the plot at the top
        ax.set_title(res.name, fontsize=9)
        ax.set_xlabel("time [s]")
        ax.set_ylabel("|E − E0| / E0")
        ax.grid(True, alpha=0.3)
    for ax in axes.flat[len(results):]:
        ax.axis("off")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8)
    fig.suptitle(f"Energy error at zero torque over {horizon:g} s (from rest at φ0)")
    fig.tight_layout(rect=(0, legend_in / height, 1, 1 - 0.4 / height))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_throughput(tp: Throughput, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sizes = sorted(tp.vector)
    fig, ax = plt.subplots(figsize=(6, 4.2))
    for name, color, label in (
        ("ours", "tab:green", "roller_gym/RollerStabilize-v1 (make_vec)"),
        ("kernel", "tab:olive", "our physics kernel alone (advance_batch)"),
        ("CartPoleVectorEnv", "tab:orange", "CartPoleVectorEnv"),
    ):
        ax.loglog(sizes, [tp.vector[n][name] for n in sizes], marker="o", color=color,
                  label=label, ls=":" if name == "kernel" else "-")
    ax.set_xlabel("sub-environments")
    ax.set_ylabel("environment steps per second")
    ax.set_title("Vector environment throughput (same run, best of repeats)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_report(cfg: Config, results: list[SceneResult], tp: Throughput | None,
                 tp_why: str | None, elapsed: float) -> Path:
    """docs/BENCHMARKS.md and the plots."""
    img_dir = cfg.out / "benchmarks"
    img_dir.mkdir(parents=True, exist_ok=True)
    plot_work_precision(results, img_dir / "work_precision.png", "global")
    plot_work_precision(results, img_dir / "work_precision_local.png", "local")
    plot_energy(results, img_dir / "energy.png", cfg.energy_horizon_s)
    if tp is not None and tp.vector:
        plot_throughput(tp, img_dir / "throughput.png")
    by_name = {r.name: r for r in results}
    paper = by_name["paper"]
    horizon = cfg.horizon_s
    comps = [compare_mujoco(r) for r in results]
    command = "python scripts/benchmark.py" + (" --quick" if cfg.quick else "")
    if cfg.out.resolve() != (ROOT / "docs").resolve():
        command += f" --out {cfg.out}"

    L: list[str] = ["# Benchmarks: speed against error", ""]
    if cfg.quick:
        L += ["> **A `--quick` run**: a short episode, two scenes, few settings. The numbers "
              "show that the benchmark works, not what it finds; run without `--quick` for "
              "the report.", ""]
    L += [f"Generated by `{command}` in {elapsed:.0f} s (rerun it to reproduce; the machine is "
          "below). The same run measures every peer, interleaved: best of "
          f"{cfg.repeats} repeats, and only ratios are compared.", ""]

    # -- the summary: targets -------------------------------------------------------------
    L += ["## Summary", ""]
    targets: list[list[str]] = []
    d = paper.default
    d_cost = d.seconds / horizon
    if tp is not None:
        r1 = tp.single["ours"] / tp.single["Pendulum-v1"]
        targets.append([
            "one environment ≥ 1.5 × Pendulum-v1's steps/s, 10-s error ≤ 1e-6 rad",
            f"{r1:.2f} × Pendulum-v1 ({tp.single['ours']:,.0f} against "
            f"{tp.single['Pendulum-v1']:,.0f} steps/s); error {fmt_err(tp.env_error[0])} rad",
            verdict_single(r1, max(tp.env_error[0], d.err[0])),
        ])
        for n in (4096, 65536):
            if n in tp.vector:
                r = tp.vector[n]["ours"] / tp.vector[n]["CartPoleVectorEnv"]
                targets.append([
                    f"vector env ≥ CartPoleVectorEnv at {n:,} sub-environments",
                    f"{r:.2f} × ({tp.vector[n]['ours']:,.0f} against "
                    f"{tp.vector[n]['CartPoleVectorEnv']:,.0f} steps/s)",
                    "**met**" if r >= 1.0 else f"**missed**: {r:.2f} of the target "
                    f"({1 / r:.1f}× too slow)",
                ])
    c = next(c for c in comps if c.scene == "paper")
    c_local = compare_mujoco(paper, "local")
    targets.append([
        "≥ 100 × MuJoCo's speed at equal error (default scene)",
        f"{c.ratio:,.0f} × (MuJoCo tuned needs {fmt_time(c.mj_cost)} per simulated second "
        f"to reach our {fmt_err(c.our_err)} rad, we take {fmt_time(c.our_cost)}; "
        f"{c.mj_how}); at equal local error {c_local.ratio:,.0f} ×"
        if math.isfinite(c.ratio) else "MuJoCo does not reach our error",
        "**met**" if c.ratio >= 100 else f"**missed**: {c.ratio / 100:.2f} of the target",
    ])
    L += md_table(["target", "measured", "verdict"], targets)
    if tp is None:
        L += ["", f"The environments could not be measured: {tp_why}."]
    L += [""]
    L += [
        f"- Default settings ({DEFAULT_METHOD}, automatic substeps at tol {DEFAULT_TOL:.0e} "
        f"per control step, dt = {DT} s) on the default scene: largest φ error over the "
        f"{horizon:g}-s episode **{fmt_err(d.err[0])} rad** (φ' {fmt_err(d.err[1])} rad/s), at "
        f"**{fmt_time(d_cost)} per simulated second** "
        f"({len(paper.torques) / d.seconds:,.0f} control steps/s in the physics kernel).",
        f"- MuJoCo at its defaults (2 ms Euler steps, soft constraint): φ error "
        f"{fmt_err(c.default_err)} rad at {fmt_time(c.default_cost)} per simulated second. "
        f"Tuned for accuracy it reaches our error at {c.mj_setting}.",
    ]
    hard = []
    for res in results:
        bad = [f"{e['label']} at t = {e['blowup_s']:g} s" for e in res.energy
               if "(default)" in e["label"] and math.isfinite(e["blowup_s"])]
        if not res.default.finite:
            bad.append("the episode")
        if bad:
            hard.append(f"{res.name} ({'; '.join(bad)})")
    chaotic = [f"{r.name} (after {r.predictable_s:g} s)" for r in results if r.chaotic]
    L += [
        "- Hard cases at default settings: "
        + ("no run went non-finite or blew up" if not hard else
           "**blew up** in " + ", ".join(hard) + " (zero-torque runs; see part 4)")
        + "; chaotic under random torques, so judged by the local error: "
        + (", ".join(chaotic) if chaotic else "none") + ".",
    ]
    L += ["", "See *The targets* at the end for what would close each miss.", ""]

    L += ["## Machine and command", "", *machine_info(),
          f"- Command: `{command}` (from the repository root, in its venv: `make bench` runs "
          "the full one)", ""]

    # -- method -----------------------------------------------------------------------------
    L += ["## How it is measured", ""]
    L += [
        f"- **Episode**: {horizon:g} s = {len(paper.torques)} control steps of dt = {DT} s from "
        "rest at φ = 0. The drive is constant over a control step and drawn once per step: "
        f"actions uniform in [−1, 1] (float32, seed {SEED}) times the environments' default "
        f"max_torque = {MAX_TORQUE} N·m, i.e. what random actions in the environments do. "
        "The same torques for every scene, integrator and engine.",
        f"- **Reference**: scipy's DOP853 at rtol = atol = {REFERENCE_TOL:g}, restarted at "
        "each control step (the torque jumps there). Its own error is estimated by running it "
        "again at 1e-12 (`reference's own error` below): errors under it cannot be measured.",
        "- **Global error**: the largest |φ − φ_ref| [rad] (and |φ' − φ'_ref| [rad/s]) over the "
        "episode, each integrator run on its own from the same start with the same torques. "
        "It grows with the dynamics as well as with the integrator (a trajectory's sensitivity "
        "to a perturbation grows with time), so it is also given as the **local error**: the "
        "largest error of one control step started from the reference state, which is what "
        "`tol` bounds.",
        "- **Cost**: best-of-repeats wall time of the episode, per simulated second (a Python "
        "loop of one call per control step: `integrators.step_one` as the environment calls "
        "it, `integrators.step(method='dop853')`, `mujoco.mj_step(model, data, n)`). "
        "`steps/s` = control steps per second of the physics alone, the ceiling of an "
        "environment's steps/s.",
        "- **Families**: `euler` = semi-implicit Euler with n fixed substeps (n = 1 is "
        "Gymnasium's Pendulum scheme); `rk4` = RK4 with n fixed substeps; `rk4 auto` = RK4 "
        "with the automatic substep rule at a tolerance per control step (the environments' "
        f"default: {DEFAULT_TOL:.0e}); `rk8`, `rk8 auto` = the same with the 8th-order "
        "Dormand–Prince tableau (the environments' default integrator: "
        f"`{DEFAULT_METHOD}`); `midpoint` = implicit midpoint, n fixed substeps; "
        "`dop853` = scipy's, at rtol = atol = tol.",
        "",
    ]

    # -- part 1 -------------------------------------------------------------------------------
    L += ["## 1. Work-precision", "",
          "Global error (along the episode):", "",
          "![work-precision](benchmarks/work_precision.png)", "",
          "Local error (one control step from the reference state; MuJoCo's too):", "",
          "![work-precision, local](benchmarks/work_precision_local.png)", ""]
    for res in results:
        L += [f"### {res.name}: {SCENE_NOTES[res.name]}", ""]
        L += [f"Reference: {fmt_time(res.ref_seconds)} for the episode, "
              f"{int(res.ref.substeps.sum()):,} DOP853 steps; its own error ≈ "
              f"{fmt_err(res.ref_floor[0])} rad ({fmt_err(res.ref_floor[1])} rad/s). Largest "
              f"|φ| {np.nanmax(np.abs(res.ref.states[:, 0])):.3g} rad, largest |φ'| "
              f"{np.nanmax(np.abs(res.ref.states[:, 1])):.3g} rad/s."]
        if res.chaotic:
            L[-1] += (f" **The motion is chaotic under these torques**: the reference's own "
                      f"error passes 1e-6 rad at t = {res.predictable_s:g} s and grows to "
                      f"{fmt_err(res.ref_floor[0])} rad, so every global error here measures "
                      "the dynamics' sensitivity, not the integrator: read the local errors "
                      "(and `work_precision_local.png`).")
        L += [""]
        rows = []
        for run in res.runs:
            cost = run.seconds / horizon
            subs = run.traj.substeps
            sub = (f"{subs.mean():.0f} (max {subs.max()})"
                   if run.family.endswith("auto") or run.family == "dop853"
                   else f"{int(run.setting)}")
            rows.append([
                run.family + (" ★" if run is res.default else ""), run.label,
                fmt_err(run.err[0]), fmt_err(run.err[1]),
                fmt_err(run.local[0]) if not math.isnan(run.local[0]) else "",
                sub, fmt_time(cost), f"{len(res.torques) / run.seconds:,.0f}",
            ])
        L += md_table(["family", "setting", "φ error [rad]", "φ' error [rad/s]",
                       "local φ error [rad]", "substeps per control step", "per sim. s",
                       "steps/s"], rows)
        L += [""]

    L += ["### Energy at zero torque", "",
          f"From rest at φ0 with max(|φ0|, |ψ0|) = 0.5 rad, {cfg.energy_horizon_s:g} s "
          f"({round(cfg.energy_horizon_s / DT):,} control steps): the largest relative energy "
          "error |E − E0|/E0 over the horizon. The system is not separable (J_I depends on "
          "φ), so semi-implicit Euler is not symplectic here and drifts; the implicit midpoint "
          "rule is symplectic and its error stays bounded; RK4 and RK8 drift slowly, by their "
          "error per step.", "", "![energy](benchmarks/energy.png)", ""]
    header = ["scene", *[item["label"] for item in results[0].energy]]
    rows = [[res.name, *[f"{fmt_err(item['max'])} ({fmt_time(item['seconds'])})"
                         for item in res.energy]] for res in results]
    L += [*md_table(header, rows), "", "(wall time of the whole horizon in brackets)", ""]

    # -- part 2 -------------------------------------------------------------------------------
    L += ["## 2. MuJoCo on the same scene", ""]
    L += [
        "The model (`roller_gym.bench.mujoco_roller`): MuJoCo has no rolling constraint between a "
        "cylinder and a concave cylinder, so the roller is a body `arm` hinged at the axis O "
        "(angle ψ) carrying at R − r a body `roller` hinged to it (relative angle q), with the "
        "roller's mass m at e from its center and inertia m k² about C, and a joint equality "
        "constraint q = (R/r) ψ (rolling: (R − r) ψ = r φ with φ = q − ψ). The drive is a "
        "motor on a site of the roller, a pure couple (power τφ'). The floor (and R = 1e12 m, "
        "which cannot be an arm 1e12 m long) is a slide joint x with the roller hinged at "
        "height r and the coupling x = r φ. The drum is the same arm pointing up (R − r < 0). "
        "The arm carries 1e-14 kg (MuJoCo rejects massless moving bodies), a change of ~1e-8 "
        "in the dynamics at most.",
        "",
        "- **MuJoCo default**: MuJoCo's own settings (semi-implicit Euler, solref (0.02, 1), "
        "solimp (0.9, 0.95, 0.001)) at its default 2 ms timestep and smaller ones: the soft "
        "constraint, not the step, sets the error, which stops falling.",
        "- **MuJoCo tuned**: RK4; the stiffest constraint RK4 keeps stable (timeconst = 0.5 "
        "timestep, with MuJoCo's safety clamp `refsafe` off, critical damping, impedance "
        "0.9999, MuJoCo's maximum); solver tolerance 1e-15, 200 iterations. Its error falls as "
        "timestep²: that is the **validation** that the model is the same system as ours — "
        "its trajectory converges to our DOP853 reference on every scene as the timestep "
        "shrinks (see the tables: the error keeps falling at the finest steps).",
        "",
    ]
    rows = []
    local_comps = [compare_mujoco(r, "local") for r in results]
    for res, cmp, loc in zip(results, comps, local_comps, strict=True):
        hz = len(res.torques) * DT
        tuned = [r for r in res.family("MuJoCo tuned") if math.isfinite(r.local[0])]
        glob = (f"{fmt_time(cmp.mj_cost)}: {cmp.mj_setting}, {cmp.mj_how}; "
                f"**{cmp.ratio:,.0f} ×**" if math.isfinite(cmp.ratio) else cmp.mj_how)
        if res.chaotic:
            best_glob = min((r.err[0] for r in res.family("MuJoCo tuned")), default=math.inf)
            glob = (f"not comparable: chaotic after {res.predictable_s:g} s (the reference's "
                    f"own error reaches {fmt_err(res.ref_floor[0])} rad); MuJoCo tuned's "
                    f"best: {fmt_err(best_glob)} rad")
        # the other way round: our cost at the finest local error MuJoCo reaches
        finest = min(tuned, key=lambda r: r.local[0]) if tuned else None
        reverse = "–"
        if finest is not None:
            ours_pts = [(r.local[0], r.seconds / hz) for r in res.family(f"{DEFAULT_METHOD} auto")]
            our_cost, how = cost_at_error(ours_pts, finest.local[0])
            mj_cost = finest.seconds / hz
            reverse = (f"MuJoCo {fmt_err(finest.local[0])} ({finest.label}) in "
                       f"{fmt_time(mj_cost)}; ours {fmt_time(our_cost)} ({how}): "
                       f"**{mj_cost / our_cost:,.0f} ×**" if math.isfinite(our_cost)
                       else f"MuJoCo {fmt_err(finest.local[0])} in {fmt_time(mj_cost)}")
        rows.append([
            res.name, f"{fmt_err(cmp.our_err)} / {fmt_err(loc.our_err)}",
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
                   f"at MuJoCo tuned's finest local error: its cost, ours (`{DEFAULT_METHOD} "
                   "auto`); speed ratio"], rows)
    L += ["", "MuJoCo's figures per setting are in the tables of part 1 (families `MuJoCo "
          "default`, `MuJoCo tuned`; setting = MuJoCo's timestep).", ""]
    L += [f"Our whole `{DEFAULT_METHOD} auto` curve against MuJoCo tuned, on the default scene "
          "(MuJoCo's cost "
          "interpolated at each of our errors):", ""]
    rows = []
    hz = len(paper.torques) * DT
    mj_pts = [(r.err[0], r.seconds / hz) for r in paper.family("MuJoCo tuned")]
    for run in paper.family(f"{DEFAULT_METHOD} auto"):
        cost, how = cost_at_error(mj_pts, max(run.err[0], paper.ref_floor[0]))
        ours_cost = run.seconds / hz
        rows.append([run.label, fmt_err(run.err[0]), fmt_time(ours_cost), fmt_time(cost),
                     f"{cost / ours_cost:,.0f} × ({how})" if math.isfinite(cost) else how])
    L += [*md_table([f"{DEFAULT_METHOD} auto", "φ error [rad]", "ours per sim. s",
                     "MuJoCo tuned per sim. s", "ratio"], rows), ""]

    # -- part 3 -------------------------------------------------------------------------------
    L += ["## 3. Throughput", ""]
    if tp is None:
        L += [f"Not measured: the environments are not importable ({tp_why}).", ""]
    else:
        L += ["Random actions, the same for every repeat; best of repeats, interleaved. One "
              f"environment: `gymnasium.make` (with its wrappers) for both, {cfg.env_steps:,} "
              f"steps a repeat, best of {3 * cfg.repeats}, steps only (resets excluded). "
              "Vector: `gymnasium.make_vec(\"roller_gym/RollerStabilize-v1\", num_envs=N)` "
              "(the native vector environment, default settings) against "
              "`CartPoleVectorEnv(num_envs=N)`, `step()` with batched actions, "
              "environment steps per second = N × batched steps per second (autoresets "
              "inside step() count, the first reset does not).", ""]
        L += md_table(
            ["environment", "steps/s", "ratio"],
            [["roller_gym/RollerStabilize-v1", f"{tp.single['ours']:,.0f}",
              f"**{tp.single['ours'] / tp.single['Pendulum-v1']:.2f} ×**"],
             ["Pendulum-v1", f"{tp.single['Pendulum-v1']:,.0f}", "1"]])
        L += ["", "State error of `gymnasium.make(\"roller_gym/RollerStabilize-v1\")` itself "
              "over the "
              f"{horizon:g}-s reference episode (default settings, stepped through the "
              f"environment): φ {fmt_err(tp.env_error[0])} rad, φ' {fmt_err(tp.env_error[1])} "
              f"rad/s. The vector environment (16 sub-environments on the same episode, up to "
              f"the first termination): φ {fmt_err(tp.vector_error[0])} rad — the same kernel, "
              "so the same error bound.", ""]
        rows = []
        for n in sorted(tp.vector):
            v = tp.vector[n]
            rows.append([
                f"{n:,}", f"{v['ours']:,.0f}", f"{v['CartPoleVectorEnv']:,.0f}",
                f"**{v['ours'] / v['CartPoleVectorEnv']:.2f} ×**",
                f"{v['kernel']:,.0f} ({1e9 / v['kernel']:,.0f} ns per roller)",
                f"{v['kernel'] / v['CartPoleVectorEnv']:.2f} ×",
                f"{fmt_time(tp.resets[n]['ours'])} / "
                f"{fmt_time(tp.resets[n]['CartPoleVectorEnv'])}",
            ])
        L += md_table(["sub-environments", "ours steps/s", "CartPoleVectorEnv steps/s",
                       "ratio", "our physics kernel alone, steps/s",
                       "kernel / CartPoleVectorEnv", "reset() of all: ours / CartPole"], rows)
        L += ["", "The kernel column is `integrators.advance_batch` on the same number of "
              "rollers at the default settings, nothing else: the ceiling of the vector "
              "environment; the gap between it and the environment is the environment's own "
              "work (autoreset of ended episodes in a Python loop, observation, reward, "
              "info). The timed window is 1,000,000 / N batched steps (20 at least, 1,000 at "
              "most), going on from one reset: up to 4,096 it passes step 200, where the "
              "episodes begun together are truncated together and all restart in one "
              "step's autoreset (the last column: what that costs); at 65,536 it does not, "
              "so the table leaves that cost out there."]
        L += ["", "![throughput](benchmarks/throughput.png)", ""]
        if tp.ppo:
            L += [f"stable-baselines3 PPO (MlpPolicy, n_steps {min(256, cfg.ppo_steps)}, "
                  f"batch 64, 4 epochs, torch on 1 thread), {cfg.ppo_steps:,} training steps: "
                  f"**{tp.ppo['ours']:,.0f}** steps/s on roller_gym/RollerStabilize-v1 against "
                  f"{tp.ppo['Pendulum-v1']:,.0f} on Pendulum-v1: "
                  f"**{tp.ppo['ours'] / tp.ppo['Pendulum-v1']:.2f} ×** (the network's updates "
                  "dominate both).", ""]
        L += [f"- {note}" for note in tp.notes] + ([""] if tp.notes else [])

    # -- part 4 -------------------------------------------------------------------------------
    L += ["## 4. Hard cases", "",
          f"Default settings ({DEFAULT_METHOD}, automatic substeps, tol {DEFAULT_TOL:.0e}) on "
          "the episode of part 1, and the zero-torque horizon of the energy table. "
          "`non-finite or blown up`: every run of ours on the scene (all families and the "
          "energy runs) that could not stay finite (such a step reports it and keeps the "
          "state), or whose energy at zero torque went off by more than E0 (a step that blew "
          "up yet stayed finite), with when. `contact`: control steps of the episode at which "
          "the roller would leave the surface or slip (the model keeps rolling; an "
          "environment ends the episode there).", ""]
    rows = []
    for res in results:
        d = res.default
        subs = d.traj.substeps
        bad = [f"{r.family} {r.label}" for r in res.runs if r.ours and not r.finite]
        bad += [f"energy run {e['label']} at t = {e['blowup_s']:g} s" for e in res.energy
                if math.isfinite(e["blowup_s"])]
        lift = int(d.traj.lifting.sum()) if d.traj.lifting is not None else 0
        slip = int(d.traj.slipping.sum()) if d.traj.slipping is not None else 0
        e_def = res.energy[-1] if res.energy else None
        rows.append([
            res.name,
            f"{subs.min()} / {np.median(subs):.0f} / {subs.max()}",
            f"{fmt_err(d.local[0])} / {fmt_err(d.local[1])}",
            f"{fmt_err(d.err[0])} / {fmt_err(d.err[1])}",
            fmt_err(res.ref_floor[0]),
            f"{res.predictable_s:g} s" if res.chaotic else "whole episode",
            fmt_err(e_def["max"]) if e_def else "–",
            "none" if not bad else "; ".join(bad),
            f"{lift} lift-off, {slip} slip (μ = {float(res.scene.mu):g})",
            f"{np.nanmax(np.abs(res.ref.states[:, 1])):.3g}",
        ])
    L += md_table(["scene", "substeps min / median / max", "local error φ / φ'",
                   "global error φ / φ'", "reference's own φ error",
                   "reference good to 1e-6 rad for", "energy error (default)",
                   "non-finite or blown up", "contact", "max |φ'| [rad/s]"], rows)
    L += [""]

    # -- notes --------------------------------------------------------------------------------
    L += ["## The targets: what is met, and what would close the misses", ""]
    L += closing_notes(cfg, results, comps, tp)
    path = cfg.out / "BENCHMARKS.md"
    path.write_text("\n".join(L) + "\n")
    return path


def closing_notes(cfg: Config, results: list[SceneResult], comps: list[Comparison],
                  tp: Throughput | None) -> list[str]:
    """The notes at the end of the report: each target, and what would close it if missed."""
    notes: list[str] = []
    paper = next(r for r in results if r.name == "paper")
    horizon = len(paper.torques) * DT
    # how much cheaper could the default be at the same error? (fixed substeps, same method)
    fixed = [(r.err[0], r.seconds / horizon) for r in paper.family(DEFAULT_METHOD)]
    target = max(paper.default.err[0], paper.ref_floor[0])
    fixed_cost, _ = cost_at_error(fixed, target)
    d_cost = paper.default.seconds / horizon
    subs = paper.default.traj.substeps
    if tp is not None:
        r1 = tp.single["ours"] / tp.single["Pendulum-v1"]
        kernel_steps = len(paper.torques) / paper.default.seconds
        notes.append(
            f"- **One environment**: {r1:.2f} × Pendulum-v1 (target 1.5 ×), error "
            f"{fmt_err(tp.env_error[0])} rad (bound 1e-6). The physics alone runs "
            f"{kernel_steps:,.0f} control steps/s (mean {subs.mean():.1f} {DEFAULT_METHOD} "
            f"substeps per step); the environment reaches {tp.single['ours']:,.0f}, "
            f"{100 * tp.single['ours'] / kernel_steps:.0f} % of that: the rest is the "
            "environment's Python (action check, observation, reward, info) and Gymnasium's "
            "wrappers, which Pendulum pays too. "
            + ("Met." if r1 >= 1.5 else
               "To close it: a leaner step() (the observation, reward and info are built from "
               "Python floats every step): the physics is not the bottleneck"
               + (f"; fewer substeps at the same error would help a little (fixed "
                  f"{DEFAULT_METHOD} substeps reach the default's error at "
                  f"{fmt_time(fixed_cost)} per simulated second against {fmt_time(d_cost)})"
                  if fixed_cost < 0.9 * d_cost else "") + ".")
        )
        sizes = sorted(tp.vector)
        per_roller = {n: 1e9 / tp.vector[n]["kernel"] for n in sizes}
        if 1 in tp.vector:
            notes.append(
                f"- **Vector environment, fixed cost**: at 1 sub-environment one step() takes "
                f"{fmt_time(1 / tp.vector[1]['ours'])} against {fmt_time(1 / tp.single['ours'])}"
                " for the single environment (and "
                f"{fmt_time(1 / tp.vector[1]['CartPoleVectorEnv'])} for CartPoleVectorEnv): "
                "the per-step arrays (the info dict and its masks, the observation) cost more "
                "than the physics up to a few hundred sub-environments."
            )
        for n in (4096, 65536):
            if n not in tp.vector:
                continue
            v = tp.vector[n]
            r = v["ours"] / v["CartPoleVectorEnv"]
            rk = v["kernel"] / v["CartPoleVectorEnv"]
            text = (f"- **Vector environment at {n:,}**: {r:.2f} × CartPoleVectorEnv (target "
                    "1 ×). ")
            if r >= 1:
                notes.append(text + "Met.")
                continue
            text += (
                f"Missed by {1 / r:.1f} ×. The physics kernel alone runs at {rk:.2f} × "
                f"CartPoleVectorEnv ({per_roller[n]:,.0f} ns per roller per control step: "
                f"{DEFAULT_METHOD}, ≥ 1 substep of {12 if DEFAULT_METHOD == 'rk8' else 4} "
                "right-hand sides, and the contact margins at every substep), against "
                f"{1e9 / v['CartPoleVectorEnv']:,.0f} ns per sub-environment for CartPole's "
                "whole step (one Euler step in a few NumPy operations); the environment "
                f"reaches {100 * v['ours'] / v['kernel']:.0f} % of its kernel, the rest being "
                "the autoreset of ended episodes in a Python loop and the per-step arrays. "
            )
            small = [m for m in sizes if m < integ.PARALLEL_THRESHOLD] if hasattr(
                integ, "PARALLEL_THRESHOLD") else []
            if small and per_roller[n] > 0.8 * min(per_roller[m] for m in small):
                text += (
                    "In this run the parallel kernel was no faster per roller than the serial "
                    f"one at {max(small):,} rollers ({per_roller[max(small)]:,.0f} ns): with "
                    "other processes on both cores, numba's OpenMP threads wait for each "
                    "other. "
                )
            text += (
                "To close it: (1) a kernel that vectorizes across rollers (each stage computed "
                "for a block of rollers, so that LLVM uses SIMD: AVX-512 holds 8 doubles) and "
                "contact margins at the end of the step only; (2) a vectorized autoreset "
                "(draw the start states of all ended sub-environments at once); (3) at "
                "equal error, no more substeps than needed."
            )
            notes.append(text)
    c = next(c for c in comps if c.scene == "paper")
    notes.append(
        f"- **MuJoCo at equal error (default scene)**: {c.ratio:,.0f} × (target 100 ×). "
        + ("Met. " if c.ratio >= 100 else
           "Missed. MuJoCo tuned is limited by its soft constraint (error ∝ timestep²) and "
           "pays a constraint solve per RK4 stage; ours integrates a closed-form ODE. To "
           "close it: fewer substeps for the same error, or a cheaper kernel. ")
        + "The hard scenes are in the table of part 2: where MuJoCo's tuned family does not "
        "reach our error within its finest timestep its cost is extrapolated along its "
        "trend (and says so), or reported as not reached."
    )
    for res in results:
        d = res.default
        if res.chaotic:
            lift = int(d.traj.lifting.sum()) if d.traj.lifting is not None else 0
            slip = int(d.traj.slipping.sum()) if d.traj.slipping is not None else 0
            meaning = (
                "so no engine's global error over the episode means anything there: after "
                "that time every trajectory is as good as any other"
                if res.ref_floor[0] > 0.1 else
                f"so global errors under ~{fmt_err(res.ref_floor[0])} rad cannot be told "
                "apart there"
            )
            notes.append(
                f"- **{res.name}**: the motion under these torques is chaotic: two DOP853 "
                f"runs at 1e-12 and 1e-13 part by 1e-6 rad at t = {res.predictable_s:g} s and "
                f"by {fmt_err(res.ref_floor[0])} rad at the end, {meaning}. The local error, "
                "one control step from the reference state, is what the integrators answer "
                f"for: {fmt_err(d.local[0])} rad at default settings against the tolerance "
                f"{DEFAULT_TOL:.0e}. (The roller would also leave the surface at {lift} and "
                f"slip at {slip} of the {len(res.torques)} control steps: an environment "
                "ends the episode at the first.)"
            )
        if d.local[0] > 10 * DEFAULT_TOL or not d.finite:
            notes.append(
                f"- **{res.name}**: at default settings the largest error of one control step "
                f"is {fmt_err(d.local[0])} rad against the tolerance {DEFAULT_TOL:.0e}: the "
                "automatic substep rule undershoots on this scene under these torques "
                f"(largest |φ'| {np.nanmax(np.abs(res.ref.states[:, 1])):.3g} rad/s; substeps "
                f"up to {d.traj.substeps.max():,}): an issue for the integrators."
            )
        for e in res.energy:
            if "(default)" in e["label"] and math.isfinite(e["blowup_s"]):
                notes.append(
                    f"- **{res.name}, default integrator at zero torque**: blew up at t = "
                    f"{e['blowup_s']:g} s of the {cfg.energy_horizon_s:g}-s run (energy off by "
                    "more than E0; a non-finite step follows). One step from a slow state "
                    "accelerates through the dip of J_I with too few substeps; a step that "
                    "blows up to a huge but finite speed must be retried, not accepted: an "
                    "issue for the integrators."
                )
    notes.append(
        "- Timings are best-of-repeats; if other processes share the machine, absolute "
        "figures are noisy, ratios measured in the same run much less so."
    )
    return notes


# ================================================================================================
# Main
# ================================================================================================
def main(argv: Sequence[str] | None = None) -> None:
    cfg = parse_args(argv)
    t_start = time.perf_counter()
    mujoco.set_mju_user_warning(lambda _msg: None)  # divergence is detected from mjData
    print(f"roller-gym benchmark ({'quick' if cfg.quick else 'full'}), writing to {cfg.out}")
    # warm up the compiled kernels (compilation is not what is measured)
    warm = kernel_row(SCENES["paper"])
    for method in {"rk4", "euler", "midpoint", DEFAULT_METHOD}:
        integ.step_one(warm, 0.1, 0.0, 0.0, DT, integ.METHODS[method], DEFAULT_TOL, 0)

    results: list[SceneResult] = []
    for name in cfg.scenes:
        t0 = time.perf_counter()
        res = measure_scene(cfg, name)
        measure_energy(cfg, res)
        results.append(res)
        d = res.default
        print(f"\n== {name}: {SCENE_NOTES[name]} ({time.perf_counter() - t0:.0f} s; reference "
              f"{res.ref_seconds:.1f} s, its own error {fmt_err(res.ref_floor[0])} rad)")
        print(f"{'family':16s} {'setting':12s} {'φ err [rad]':>11s} {'local':>9s} "
              f"{'per sim s':>10s}")
        for run in res.runs:
            print(f"{run.family:16s} {run.label:12s} {fmt_err(run.err[0]):>11s} "
                  f"{fmt_err(run.local[0]) if not math.isnan(run.local[0]) else '':>9s} "
                  f"{fmt_time(run.seconds / cfg.horizon_s):>10s}")
        cmp = compare_mujoco(res)
        print(f"default: φ error {fmt_err(d.err[0])} rad at {fmt_time(cmp.our_cost)}/sim s; "
              f"MuJoCo tuned at that error: {fmt_time(cmp.mj_cost)}/sim s ({cmp.mj_how}): "
              f"{cmp.ratio:,.0f} ×")
        for item in res.energy:
            print(f"  energy {item['label']:34s} max rel. error {fmt_err(item['max'])}")

    tp, why = None, envs_available()
    if why is None:
        tp = measure_throughput(cfg, results[0])
        print("\n== throughput")
        print(f"one env: {tp.single['ours']:,.0f} steps/s, Pendulum-v1 "
              f"{tp.single['Pendulum-v1']:,.0f}: {tp.single['ours'] / tp.single['Pendulum-v1']:.2f}"
              f" ×; env error {fmt_err(tp.env_error[0])} rad")
        for n, v in tp.vector.items():
            print(f"vector {n:6d}: ours {v['ours']:,.0f}, CartPole {v['CartPoleVectorEnv']:,.0f}: "
                  f"{v['ours'] / v['CartPoleVectorEnv']:.2f} ×")
        if tp.ppo:
            print(f"PPO: ours {tp.ppo['ours']:,.0f} steps/s, Pendulum {tp.ppo['Pendulum-v1']:,.0f}")
    else:
        print(f"\n== throughput not measured: {why}")
    path = write_report(cfg, results, tp, why, time.perf_counter() - t_start)
    print(f"\nwrote {path} in {time.perf_counter() - t_start:.0f} s")


if __name__ == "__main__":
    main()
