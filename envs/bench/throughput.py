"""The environments' speed against their peers, as ratios measured in one run.

    python -m roller_gym.bench.throughput measure --out docs   # measure, write the JSON, render
    python -m roller_gym.bench.throughput render --out docs    # render the JSON again, no measuring
    make throughput     # measure in .venv-peers, with EnvPool and Gymnasium's JAX Pendulum

Measuring writes ``<out>/benchmarks/throughput.json`` (the results with the machine, the
package versions and the command); rendering turns it into ``<out>/THROUGHPUT.md``. Each
verdict against a target is one small function of the results (:data:`VERDICTS`). Every
speed is a best-of-repeats time of a peer and of ours in the same run; the machine may be
shared, so the ratios are the figures to read, not the absolute speeds.
"""

from __future__ import annotations

import argparse
import datetime
import importlib.metadata
import json
import os
import platform
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from roller_gym.episode import INFO_KEYS
from roller_gym.physics.integrators import INPUT_FIELDS, ROWS

_INPUTS = [ROWS.index(f) for f in INPUT_FIELDS]  # a stepper table's rows of φ, φ' and τ

TASK = "roller_gym/RollerStabilize-v1"
#: The physics' share of a vector step is timed by replaying every REPLAY_EVERY-th step,
#: the fastest of SHARE_REPEATS repeats on each side (a whole episode against a few of its
#: steps: with fewer, the two fastest scatter by several points on a shared machine).
REPLAY_EVERY, SHARE_REPEATS = 10, 7
#: Targets: the vector env against CartPoleVectorEnv, the single env against Pendulum-v1,
#: starting 65,536 sub-environments, the share of a vector step outside the physics kernel,
#: the 10-s episode's state error.
TARGETS = {"vector_vs_cartpole": 0.25, "vector_vs_envpool": 1.0, "single_vs_pendulum": 1.5,
           "reset_65536_s": 0.25, "outside_kernel_share": 0.25, "episode_error_rad": 1e-6}


def best_time(run: Callable[[], None], repeats: int) -> float:
    """The shortest of ``repeats`` wall times [s] of ``run()``."""
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - start)
    return best


def interleaved(runs: dict[str, tuple[Any, np.ndarray, int]],
                repeats: int) -> dict[str, tuple[float, float | None]]:
    """Steps per second of vector envs, ``{name: (env, actions, steps)}`` (``actions[k]``
    the batch of step k, drawn anew every step as an exploring agent's): every repeat runs
    each env's ``steps`` steps in turn, so that a shared machine's drift hits them alike, and
    each env keeps its fastest run. For our envs, also the share of that run spent in
    compiled calls, timed inside the environment's own steps (its stepper's ``run``, which
    runs the physics and, on all cores, the step's outcome too, wrapped with a clock).
    Returns ``{name: (steps/s, compiled share or None)}``."""
    spent = {name: [0.0] for name in runs}
    ours = {name: env.unwrapped._stepper for name, (env, _, _) in runs.items()
            if hasattr(env.unwrapped, "_stepper")}
    for name, stepper in ours.items():

        def timed(*args: Any, run=stepper.run, clock=spent[name]) -> Any:
            start = time.perf_counter()
            out = run(*args)
            clock[0] += time.perf_counter() - start
            return out

        stepper.run = timed  # an instance attribute: shadows the method for these runs
    best = {name: (float("inf"), 0.0) for name in runs}
    try:
        for env, actions, _ in runs.values():
            env.step(actions[0])  # warm up
        for _ in range(repeats):
            for name, (env, actions, steps) in runs.items():
                spent[name][0] = 0.0
                start = time.perf_counter()
                for k in range(steps):
                    env.step(actions[k])
                wall = time.perf_counter() - start
                if wall < best[name][0]:
                    best[name] = (wall, spent[name][0] / wall)
    finally:
        for stepper in ours.values():
            del stepper.run
    return {name: (runs[name][0].num_envs * runs[name][2] / wall,
                   share if name in ours else None)
            for name, (wall, share) in best.items()}


def kept_steps(env: Any, actions: np.ndarray, every: int) -> list[np.ndarray]:
    """Run ``env`` (ours) along ``actions`` and keep its stepper's table as each
    ``every``-th step (0, every, 2 every, ...) starts it: the scene, that step's state and
    torque, and the sizes carried into it (a copy each)."""
    stepper = env.unwrapped._stepper
    kept: list[np.ndarray] = []

    def keep(*args: Any, run=stepper.run) -> Any:
        if step[0] % every == 0:
            stepper._io[_INPUTS] = np.stack(args[:3])  # as run() will write them
            kept.append(stepper._io.copy())
        step[0] += 1
        return run(*args)

    step = [0]
    stepper.run = keep  # an instance attribute: shadows the method for these steps
    try:
        for a in actions:
            env.step(a)
    finally:
        del stepper.run
    return kept


def replay(stepper: Any, io: np.ndarray) -> float:
    """The physics kernel alone on a table :func:`kept_steps` kept (into the stepper's):
    the time [s] the kernel took."""
    stepper._io[...] = io  # the kernel overwrites the outputs and the carried sizes
    start = time.perf_counter()
    stepper._kernel(stepper._io, stepper._tab, stepper._cfg)
    return time.perf_counter() - start


def outside_physics_share(env: Any, actions: np.ndarray, every: int, repeats: int) -> float:
    """The share of ``env``'s (ours) steps along ``actions`` spent outside the physics
    kernel: its steps are timed, and every ``every``-th step of an episode replayed through
    the stepper's own kernel alone, so that the kernel works on the states and step sizes
    the environment really meets. Each repeat times both, one right after the other, so that
    a shared machine's drift hits them alike; each keeps its fastest repeat: the fastest of
    the environment's runs along ``actions`` and the fastest of the replays' sums (the same
    statistic on both sides; the fastest of each replayed step on its own would be faster
    than any one replay of them all)."""
    stepper = env.unwrapped._stepper
    kept = kept_steps(env, actions, every)

    def replays(tables: list[np.ndarray]) -> float:
        saved = stepper._io.copy()
        spent = sum(replay(stepper, io) for io in tables)
        stepper._io[...] = saved  # the environment's own table, to go on from
        return spent

    replays(kept[:1])  # the kernel loaded and warm, as the environment's steps are
    wall, physics = float("inf"), float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        for a in actions:
            env.step(a)
        wall = min(wall, time.perf_counter() - start)
        physics = min(physics, replays(kept))
    return 1.0 - physics / len(kept) * len(actions) / wall


def measure_vector(sizes: Sequence[int], steps: int, repeats: int,
                   whole_episodes: bool = True, share_repeats: int | None = None
                   ) -> dict[str, Any]:
    """Ours against CartPoleVectorEnv (interleaved) and the optional peers at each size.
    Ours runs whole episodes (``whole_episodes``: each timed run is one episode of every
    sub-environment, its autoreset included), since a step's cost depends on where the
    rollers are in an episode; CartPole runs as many steps; the optional peers, whose
    steps cost the same anywhere, run ``steps`` steps. ``share_repeats``: the repeats of
    the share outside the physics kernel (default ``repeats``)."""
    import gymnasium as gym

    share_repeats = share_repeats or repeats
    out: dict[str, Any] = {}
    rng = np.random.default_rng(0)
    for n in sizes:
        ours = gym.make_vec(TASK, num_envs=n)
        bare = gym.make_vec(TASK, num_envs=n, info_keys=[])  # the same steps, without info
        cart = gym.make_vec("CartPole-v1", num_envs=n, vectorization_mode="vector_entry_point")
        for env in (ours, bare, cart):
            env.reset(seed=0)
        episode = ours.unwrapped.max_episode_steps if whole_episodes else steps
        a = rng.uniform(-1, 1, (episode, n, 1)).astype(np.float32)
        runs = {"ours": (ours, a, episode), "ours_no_info": (bare, a, episode),
                "CartPoleVectorEnv": (cart, rng.integers(0, 2, (episode, n)), episode)}
        rates = interleaved(runs, repeats)
        bare.close()
        cart.close()
        # The optional peers run their own threads, which keep the cores busy for a while
        # after a step: each is timed on its own, after ours.
        for name, make in PEERS.items():
            try:
                peer = make(n)
            except ImportError:
                continue  # reported by peers_missing
            actions = rng.uniform(-2, 2, (steps, n, 1)).astype(np.float32)
            rates.update(interleaved({name: (peer, actions, steps)}, repeats))
            peer.close()
        base = ours.unwrapped
        tau = a[0, :, 0].astype(np.float64) * base.task.max_torque
        stepper = base._stepper

        def kernel(stepper=stepper, base=base, tau=tau) -> None:
            for _ in range(steps):
                stepper.run(base.phi, base.phi_dot, tau)

        kernel_rate = n * steps / best_time(kernel, repeats)
        out[str(n)] = {name: rate for name, (rate, _) in rates.items()}
        out[str(n)].update({"ours_steps": episode, "kernel": kernel_rate,
                            "outside_kernel_share": outside_physics_share(
                                ours, a, REPLAY_EVERY, share_repeats),
                            "outside_kernel_repeats": share_repeats,
                            "outside_compiled_share": 1.0 - rates["ours"][1],
                            **measure_arithmetic(stepper, base, tau, repeats)})
        ours.close()
    return out


#: Right-hand-side evaluations of a Runge–Kutta control step besides its substeps' stages:
#: the one at the start and the one at the end (the outputs).
RHS_PER_STEP = 2


def measure_arithmetic(stepper: Any, base: Any, tau: np.ndarray, repeats: int) -> dict[str, Any]:
    """How close the kernel is to its arithmetic: the unit of its substeps per roller (the
    kernel's own compiled lane loop, timed alone: for a Runge–Kutta scheme one evaluation of
    φ'', for ``"taylor"`` one expansion with its size and values), and the kernel's cost in
    such units (its substeps counted, rejected attempts not)."""
    from roller_gym.physics import integrators as integ

    n = base.num_envs
    par = np.ascontiguousarray(stepper.scene_table())  # contiguous rows, as in the kernel
    out = np.empty(n)

    def rhs() -> None:
        for _ in range(20):
            integ._accel_lanes(base.phi, base.phi_dot, tau, par, n, out)

    rhs_ns = best_time(rhs, repeats) / (20 * n) * 1e9
    substeps = float(np.mean(stepper.advance(base.phi, base.phi_dot, tau).substeps))
    import numba

    threads = numba.get_num_threads() if n >= integ.PARALLEL_THRESHOLD else 1
    scheme = stepper.scheme
    if scheme.tableau is not None:
        return {"rhs_ns": rhs_ns, "unit": "φ'' evaluation", "unit_ns": rhs_ns,
                "substeps": substeps, "kernel_threads": threads,
                "units_per_step": scheme.evaluations(False) * substeps + RHS_PER_STEP}
    # taylor: the substep loop's table (the scene's rows, then its own) and its lane-by-lane
    # output
    x = np.empty((len(integ.SCENE_FIELDS) + len(integ._T_IN), n))  # C order, as the kernel's
    x[: len(integ.SCENE_FIELDS)] = par
    x[integ._TI_PHI], x[integ._TI_W], x[integ._TI_TAU] = base.phi, base.phi_dot, tau
    x[integ._TI_REST], x[integ._TI_FLOOR] = stepper.dt, 1e-12 * stepper.dt
    lanes = np.empty(integ._T_WIDTH * n)
    rate = stepper.tol * scheme.tol_share / stepper.dt

    def expand() -> None:
        for _ in range(20):
            integ._taylor_lanes(x, n, 0.0, rate, lanes)

    return {"rhs_ns": rhs_ns, "unit": "expansion", "unit_ns": best_time(expand, repeats)
            / (20 * n) * 1e9, "substeps": substeps, "kernel_threads": threads,
            "units_per_step": substeps}


def _envpool(n: int) -> Any:
    import envpool

    env = envpool.make_gymnasium("Pendulum-v1", num_envs=n, seed=0)
    env.reset()
    return env


def _jax_pendulum(n: int) -> Any:
    import gymnasium as gym
    import jax  # noqa: F401  (the vector env's backend)

    env = gym.make_vec("phys2d/Pendulum-v0", num_envs=n, vectorization_mode="vector_entry_point")
    env.reset(seed=0)
    return env


#: Optional peers of the vector environment (installed by the extra ``peers``).
PEERS: dict[str, Callable[[int], Any]] = {"EnvPool Pendulum-v1": _envpool,
                                          "Gymnasium phys2d/Pendulum-v0 (JAX)": _jax_pendulum}


def measure_start(n: int, repeats: int) -> float:
    """Seconds to construct and reset ``n`` sub-environments."""
    import gymnasium as gym

    def run() -> None:
        gym.make_vec(TASK, num_envs=n).reset(seed=0)

    return best_time(run, repeats)


def measure_single(steps: int, repeats: int) -> dict[str, float]:
    import gymnasium as gym

    out = {}
    runs = (("ours", TASK, {}), ("ours_no_info", TASK, {"info_keys": []}),
            ("Pendulum-v1", "Pendulum-v1", {}))
    for key, env_id, kwargs in runs:
        env = gym.make(env_id, **kwargs)
        env.reset(seed=0)
        a = np.array([0.1], np.float32)

        def run(env=env, a=a) -> None:
            for _ in range(steps):
                _, _, terminated, truncated, _ = env.step(a)
                if terminated or truncated:
                    env.reset()

        out[key] = steps / best_time(run, repeats)
    return out


def measure_ppo(n_envs: int, steps: int) -> dict[str, float]:
    """SB3 PPO training steps per second, the native batch against DummyVecEnv."""
    import torch
    from roller_gym.sb3 import RollerVecEnv
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env

    torch.set_num_threads(1)
    out = {}
    for key, env in (("RollerVecEnv", RollerVecEnv(TASK, n_envs=n_envs, seed=0)),
                     ("DummyVecEnv", make_vec_env(TASK, n_envs=n_envs, seed=0))):
        model = PPO("MlpPolicy", env, n_steps=128, batch_size=256, n_epochs=1, seed=0,
                    device="cpu")
        model.learn(128 * n_envs)  # one rollout and update first: kernels compiled (or loaded)
        start = time.perf_counter()
        model.learn(steps, reset_num_timesteps=False)
        out[key] = steps / (time.perf_counter() - start)
    return out


def measure_episode_error(seconds: float = 10.0) -> float:
    """The largest |φ − φ_ref| [rad] over an episode of random torques through
    ``gymnasium.make`` at default settings, the reference DOP853 at rtol 1e-13."""
    import gymnasium as gym
    from roller_gym.physics import step

    env = gym.make(TASK, max_episode_steps=10**6)
    env.reset(seed=0, options={"state": (0.0, 0.0)})
    base = env.unwrapped
    rng = np.random.default_rng(1)
    phi, phi_dot, worst = 0.0, 0.0, 0.0
    for _ in range(round(seconds / base.config.dt)):
        a = float(np.float32(rng.uniform(-1, 1)))  # the action the environment is given
        _, _, terminated, _, info = env.step(np.array([a], np.float32))
        ref = step(base.scene, phi, phi_dot, a * base.task.max_torque, base.config.dt,
                   method="dop853", tol=1e-13)
        phi, phi_dot = ref.phi, ref.phi_dot
        worst = max(worst, abs(info["phi"] - phi))
        if terminated:
            break
    return worst


def peers_missing() -> dict[str, str]:
    """The optional peers that are not installed here, with why they are not measured."""
    missing = {}
    for name, module in (("EnvPool Pendulum-v1", "envpool"),
                         ("Gymnasium phys2d/Pendulum-v0 (JAX)", "jax")):
        try:
            __import__(module)
        except ImportError:
            missing[name] = (f"not measured: {module} is not installed in this environment "
                             "(the extra `peers`; `make throughput` measures with it)")
    return missing


def machine() -> dict[str, Any]:
    """The machine measured on: the CPU as Linux names it (with its family, model, clock and
    widest SIMD, which set the kernels' speed: a virtual machine's name alone can hide them),
    its cores, the OS, Python and the packages' versions."""
    cpu = platform.processor() or platform.machine()
    try:
        info: dict[str, str] = {}
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            key, _, value = line.partition(":")
            if not key.strip():
                break  # the first processor's block is enough
            info.setdefault(key.strip(), value.strip())
        flags = info.get("flags", "").split()
        simd = next((name for flag, name in (("avx512f", "AVX-512"), ("avx2", "AVX2"))
                     if flag in flags), "no AVX2")
        cpu = (f"{info.get('model name', cpu)} (family {info.get('cpu family', '?')} model "
               f"{info.get('model', '?')}, {float(info.get('cpu MHz', 'nan')):.0f} MHz, {simd})")
    except (OSError, ValueError):
        pass
    versions = package_versions(("roller-gym", "gymnasium", "numpy", "numba",
                                 "stable-baselines3", "torch"))
    return {"cpu": cpu, "cores": os.cpu_count(), "os": platform.platform(),
            "python": platform.python_version(), "versions": versions}


def package_versions(dists: Sequence[str]) -> dict[str, str | None]:
    """The installed version of each distribution, None where it is not installed."""
    versions: dict[str, str | None] = {}
    for dist in dists:
        try:
            versions[dist] = importlib.metadata.version(dist)
        except importlib.metadata.PackageNotFoundError:
            versions[dist] = None
    return versions


def _share_repeats(results: dict[str, Any]) -> str:
    """The repeats the share outside the physics kernel took (as one number, or a list)."""
    counts = sorted({v["outside_kernel_repeats"] for v in results["vector"].values()})
    return " or ".join(str(c) for c in counts)


def measure(quick: bool) -> dict[str, Any]:
    sizes = (256, 1024) if quick else (4096, 65536)
    steps, repeats = (5, 2) if quick else (20, 3)
    start_n = 1024 if quick else 65536
    return {
        "machine": machine(),
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "command": " ".join([os.path.basename(sys.executable), "-m", __spec__.name
                             if __spec__ else __name__, *sys.argv[1:]]),
        "quick": quick,
        "vector": measure_vector(sizes, steps, repeats, whole_episodes=not quick,
                                 share_repeats=repeats if quick else SHARE_REPEATS),
        "start_seconds": {str(start_n): measure_start(start_n, repeats)},
        "single": measure_single(2000 if quick else 20000, repeats),
        "ppo": measure_ppo(16, 2048 if quick else 16384),
        "episode_error_rad": measure_episode_error(1.0 if quick else 10.0),
        "peers_missing": peers_missing(),
    }


# -- verdicts: one small function each --------------------------------------------------------
def verdict_vector(results: dict[str, Any]) -> list[tuple[str, float, float, bool]]:
    """(what, value, target, met) of the vector env against CartPoleVectorEnv, per size."""
    target = TARGETS["vector_vs_cartpole"]
    return [(f"vector env ≥ {target} × CartPoleVectorEnv at {int(n):,}",
             v["ours"] / v["CartPoleVectorEnv"], target,
             v["ours"] / v["CartPoleVectorEnv"] >= target)
            for n, v in results["vector"].items()]


def verdict_envpool(results: dict[str, Any]) -> list[tuple[str, float, float, bool]]:
    """The vector env against EnvPool's Pendulum-v1, per size (where measured)."""
    target = TARGETS["vector_vs_envpool"]
    peer = "EnvPool Pendulum-v1"
    return [(f"vector env ≥ {target} × EnvPool Pendulum-v1 at {int(n):,}", v["ours"] / v[peer],
             target, v["ours"] / v[peer] >= target)
            for n, v in results["vector"].items() if peer in v]


def verdict_outside_kernel(results: dict[str, Any]) -> list[tuple[str, float, float, bool]]:
    n, v = max(results["vector"].items(), key=lambda item: int(item[0]))
    target = TARGETS["outside_kernel_share"]
    share = v["outside_kernel_share"]
    return [(f"share of a vector step outside the physics kernel at {int(n):,} ≤ "
             f"{target:.0%}", share, target, share <= target)]


def verdict_start(results: dict[str, Any]) -> list[tuple[str, float, float, bool]]:
    target = TARGETS["reset_65536_s"]
    return [(f"make_vec + reset of {int(n):,} ≤ {target} s", s, target, s <= target)
            for n, s in results["start_seconds"].items()]


def verdict_single(results: dict[str, Any]) -> list[tuple[str, float, float, bool]]:
    target = TARGETS["single_vs_pendulum"]
    ratio = results["single"]["ours"] / results["single"]["Pendulum-v1"]
    return [(f"single env ≥ {target} × Pendulum-v1", ratio, target, ratio >= target)]


def verdict_error(results: dict[str, Any]) -> list[tuple[str, float, float, bool]]:
    target = TARGETS["episode_error_rad"]
    err = results["episode_error_rad"]
    return [(f"episode state error ≤ {target:g} rad", err, target, err <= target)]


VERDICTS = (verdict_vector, verdict_envpool, verdict_outside_kernel, verdict_start, verdict_single,
            verdict_error)


def _shown(value: float, target: float) -> str:
    """``value`` to 3 significant digits, or to as many more as it takes not to read as the
    target itself (0.24996 against 0.25)."""
    for digits in range(3, 8):
        text = f"{value:.{digits}g}"
        if float(text) != target or value == target:
            return text
    return text


def _faster(ratio: float) -> str:
    """A speed ratio in words: "4% faster", "2% slower" or "as fast" (within 0.5%)."""
    if abs(ratio - 1) < 0.005:
        return "as fast"
    return f"{abs(ratio - 1):.0%} {'faster' if ratio > 1 else 'slower'}"


def render(results: dict[str, Any]) -> str:
    """The Markdown page of a results file (no measuring)."""
    m = results["machine"]
    lines = [
        "# Throughput", "",
        "The environments' speed against their peers, as ratios of best-of-repeats times "
        "measured in the same run. Regenerate with `make throughput` (in an environment with "
        "the optional peers, the extra `peers`) or `python -m roller_gym.bench.throughput "
        "measure --out docs`; render the committed results again with `render`.", "",
        f"Measured {results['date']} on {m['cpu']}, {m['cores']} cores, {m['os']}, Python "
        f"{m['python']}; " + ", ".join(f"{k} {v}" for k, v in m["versions"].items() if v)
        + (" — a quick (smoke) run" if results["quick"] else "") + ".", "",
        "## Targets", "", "| target | measured | met |", "|---|---:|:---:|",
    ]
    for verdict in VERDICTS:
        for what, value, target, met in verdict(results):
            lines.append(f"| {what} | {_shown(value, target)} | {'yes' if met else '**no**'} |")
    lines += ["", "## The vector environment", "",
              "| sub-environments | ours, steps/s | CartPoleVectorEnv, steps/s | ratio | "
              "physics kernel alone, steps/s | share of a step outside the physics kernel | "
              "outside any compiled call |",
              "|---:|---:|---:|---:|---:|---:|---:|"]
    for n, v in results["vector"].items():
        compiled = v.get("outside_compiled_share")
        lines.append(f"| {int(n):,} | {v['ours']:,.0f} | {v['CartPoleVectorEnv']:,.0f} | "
                     f"{v['ours'] / v['CartPoleVectorEnv']:.3f} | {v['kernel']:,.0f} | "
                     f"{v['outside_kernel_share']:.0%} | "
                     + ("–" if compiled is None else f"{compiled:.0%}") + " |")
    steps = {v.get("ours_steps") for v in results["vector"].values()}
    lines += ["", (f"Ours and CartPole run {steps.pop()} steps per timed run (for ours a whole "
                   "episode of every sub-environment, its autoreset included), as a step's cost "
                   "depends on where the rollers are in an episode. "
                   if len(steps) == 1 and None not in steps else "")
              + "Every env's actions are drawn uniformly anew for every step and "
              "sub-environment, as an exploring agent's (a torque that changes every step "
              "costs the error control more substeps than a steady one). "
              "The kernel alone: `BatchStepper.run` repeated from one state. "
              "The share outside the physics kernel: every "
              f"{REPLAY_EVERY}th step of an episode through the environment replayed through "
              "the physics kernel alone, its time against the environment's step "
              "(observation, reward, info, autoreset and the copies are the rest), the "
              f"fastest of {_share_repeats(results)} repeats of each: of the episode through "
              "the environment, of the replays' sum. On all "
              "cores the step's outcome (reward, termination, info and observation) runs in "
              "the same compiled pass as the physics, chunk by chunk; the last column is the "
              "share outside that pass and any other compiled call (the environment's Python "
              "and NumPy), timed inside its own steps."]
    if all("ours_no_info" in v for v in results["vector"].values()):
        lines += ["", "The info's cost: the same steps with `info_keys=[]` run " + " and ".join(
            f"{_faster(v['ours_no_info'] / v['ours'])} at {int(n):,}"
            for n, v in results["vector"].items())
            + f". Its {len(INFO_KEYS)} arrays are the rows of the step's own outcome tables, "
            "one of floats and one of booleans (new tables every step, so that they can be "
            "handed out as they are); the integer one is converted."]
    peers = [p for p in PEERS if any(p in v for v in results["vector"].values())]
    if peers:
        lines += ["", "Optional peers, in the same run:", "",
                  "| sub-environments | " + " | ".join(f"{p}, steps/s | ours / it" for p in peers)
                  + " |", "|---:|" + "---:|---:|" * len(peers)]
        for n, v in results["vector"].items():
            lines.append(f"| {int(n):,} | " + " | ".join(
                f"{v[p]:,.0f} | {v['ours'] / v[p]:.2f}" if p in v else "– | –" for p in peers)
                + " |")
    if all("unit_ns" in v for v in results["vector"].values()):
        unit = next(iter(results["vector"].values()))["unit"]
        lines += ["", "How close the kernel is to its arithmetic: one evaluation of φ'' per "
                  f"roller and one {unit} (the unit of the default integrator's substeps), "
                  "each the kernel's own compiled loop over rollers, timed alone on one core; "
                  f"and the kernel's cost per core against the {unit}s its substeps need (the "
                  "rest is rejected attempts where there are any, the contact margins at every "
                  "substep, the end state's fields and the outputs):", "",
                  f"| sub-environments | one φ'' evaluation, ns/roller | one {unit}, "
                  "ns/roller | substeps per step | kernel, core-ns/roller-step | "
                  f"kernel / its {unit}s |", "|---:|---:|---:|---:|---:|---:|"]
        for n, v in results["vector"].items():
            kernel_ns = 1e9 / v["kernel"] * v["kernel_threads"]
            lines.append(f"| {int(n):,} | {v['rhs_ns']:.2f} | {v['unit_ns']:.2f} | "
                         f"{v['substeps']:.2f} | {kernel_ns:.0f} | "
                         f"{kernel_ns / (v['unit_ns'] * v['units_per_step']):.1f} |")
    single, ppo = results["single"], results["ppo"]
    lines += ["", "## One environment and SB3", "",
              f"- `gymnasium.make(\"{TASK}\")`: {single['ours']:,.0f} steps/s; Pendulum-v1 "
              f"{single['Pendulum-v1']:,.0f} steps/s: "
              f"{single['ours'] / single['Pendulum-v1']:.2f} ×."
              + (f" With `info_keys=[]` (no info): {single['ours_no_info']:,.0f} steps/s, "
                 f"{single['ours_no_info'] / single['Pendulum-v1']:.2f} ×; the info's "
                 f"{len(INFO_KEYS)} typed "
                 f"values are {1 - single['ours'] / single['ours_no_info']:.0%} of a step."
                 if "ours_no_info" in single else ""),
              f"- SB3 PPO, 16 environments: {ppo['RollerVecEnv']:,.0f} training steps/s through "
              f"`roller_gym.sb3.RollerVecEnv`, {ppo['DummyVecEnv']:,.0f} through `DummyVecEnv` "
              f"of single environments: {ppo['RollerVecEnv'] / ppo['DummyVecEnv']:.2f} ×.",
              f"- The state error of a 10-s episode of random torques through the environment "
              f"at default settings, against DOP853 at rtol 1e-13: "
              f"{results['episode_error_rad']:.2g} rad.", ""]
    if results["peers_missing"]:
        lines += ["## Peers not measured", ""]
        lines += [f"- {name}: {why}." for name, why in results["peers_missing"].items()]
        lines.append("")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description="The environments' throughput against "
                                                 "their peers (ratios measured in one run).")
    parser.add_argument("action", choices=("measure", "render"),
                        help="measure (and render), or render the results file again")
    parser.add_argument("--out", type=Path, default=Path("docs"),
                        help="the docs folder: results go to OUT/benchmarks/throughput.json, "
                             "the page to OUT/THROUGHPUT.md (default ./docs)")
    parser.add_argument("--quick", action="store_true", help="a smoke run in seconds")
    args = parser.parse_args(argv)
    path = args.out / "benchmarks" / "throughput.json"
    if args.action == "measure":
        results = measure(args.quick)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(results, indent=2) + "\n")
        print(f"wrote {path}")
    results = json.loads(path.read_text())
    page = args.out / "THROUGHPUT.md"
    page.write_text(render(results))
    print(f"wrote {page}")
    for verdict in VERDICTS:
        for what, value, target, met in verdict(results):
            print(f"{'met ' if met else 'MISS'} {what}: {_shown(value, target)}")


if __name__ == "__main__":
    main()
