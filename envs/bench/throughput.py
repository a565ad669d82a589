"""The environments' speed against their peers, measured in one run: the throughput study.

    python -m roller_gym.bench.throughput measure --out docs   # measure, write the JSON, render
    python -m roller_gym.bench.throughput render --out docs    # render the JSON again, no measuring
    make throughput     # measure in .venv-peers, with EnvPool and Gymnasium's JAX Pendulum

:func:`measure` returns the results as plain data; ``measure`` saves them to
``<out>/benchmarks/throughput.json`` (:mod:`roller_gym.bench.records`: with the machine, the
package versions and the command) and renders ``<out>/THROUGHPUT.md``
(:mod:`roller_gym.bench.throughput_report`); the verdicts against the targets are
:mod:`roller_gym.bench.verdicts`'. Every speed is a best-of-repeats time of a peer and of ours
in the same run (:mod:`roller_gym.bench.timing`): the ratios are the figures to read.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from roller_gym.bench import records, timing
from roller_gym.physics.integrators import INPUT_FIELDS, ROWS

_INPUTS = [ROWS.index(f) for f in INPUT_FIELDS]  # a stepper table's rows of φ, φ' and τ

TASK = "roller_gym/RollerStabilize-v2"
#: The physics' share of a vector step is timed by replaying every REPLAY_EVERY-th step,
#: the fastest of SHARE_REPEATS repeats on each side (a whole episode against a few of its
#: steps: with fewer, the two fastest scatter by several points on a shared machine).
REPLAY_EVERY, SHARE_REPEATS = 10, 7
#: The results file, relative to the docs folder.
RESULTS_FILE = Path("benchmarks") / "throughput.json"


def vector_rates(runs: dict[str, tuple[Any, np.ndarray, int]],
                 repeats: int) -> dict[str, tuple[float, float | None]]:
    """Steps per second of vector envs, ``{name: (env, actions, steps)}`` (``actions[k]``
    the batch of step k, drawn anew every step as an exploring agent's), best of ``repeats``
    interleaved runs of ``steps`` steps (:func:`roller_gym.bench.timing.best`). For our envs,
    also the share of the fastest run spent in compiled calls, timed inside the
    environment's own steps (its stepper's ``run``, which runs the physics and, on all
    cores, the step's outcome too, wrapped with a clock).
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
    share: dict[str, tuple[float, float]] = {}  # the fastest run's (wall, compiled share)

    def episode(name: str, env: Any, actions: np.ndarray, steps: int) -> Callable[[], float]:
        def once() -> float:
            spent[name][0] = 0.0
            start = time.perf_counter()
            for k in range(steps):
                env.step(actions[k])
            wall = time.perf_counter() - start
            share[name] = min(share.get(name, (np.inf, 0.0)), (wall, spent[name][0] / wall))
            return wall

        return once

    try:
        for env, actions, _ in runs.values():
            env.step(actions[0])  # warm up
        walls = timing.best({name: episode(name, *run) for name, run in runs.items()}, repeats)
    finally:
        for stepper in ours.values():
            del stepper.run
    return {name: (runs[name][0].num_envs * runs[name][2] / wall,
                   share[name][1] if name in ours else None)
            for name, wall in walls.items()}


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
                   whole_episodes: bool = True, share_repeats: int | None = None,
                   progress: Callable[[str], None] = timing.progress) -> dict[str, Any]:
    """Ours against CartPoleVectorEnv (interleaved) and the optional peers at each size.
    Ours runs whole episodes (``whole_episodes``: each timed run is one episode of every
    sub-environment, its autoreset included), since a step's cost depends on where the
    rollers are in an episode; CartPole runs as many steps; the optional peers, whose
    steps cost the same anywhere, run ``steps`` steps. ``share_repeats``: the repeats of
    the share outside the physics kernel (default ``repeats``). ``progress`` is told of each
    measurement as it starts."""
    import gymnasium as gym

    share_repeats = share_repeats or repeats
    out: dict[str, Any] = {}
    rng = np.random.default_rng(0)
    for n in sizes:
        progress(f"vector {n:,}: making ours (compiling or loading its kernels) and "
                 "CartPoleVectorEnv")
        ours = gym.make_vec(TASK, num_envs=n)
        bare = gym.make_vec(TASK, num_envs=n, info_keys=[])  # the same steps, without info
        cart = gym.make_vec("CartPole-v1", num_envs=n, vectorization_mode="vector_entry_point")
        for env in (ours, bare, cart):
            env.reset(seed=0)
        episode = ours.unwrapped.max_episode_steps if whole_episodes else steps
        a = rng.uniform(-1, 1, (episode, n, 1)).astype(np.float32)
        runs = {"ours": (ours, a, episode), "ours_no_info": (bare, a, episode),
                "CartPoleVectorEnv": (cart, rng.integers(0, 2, (episode, n)), episode)}
        progress(f"vector {n:,}: ours and CartPoleVectorEnv, {repeats} interleaved repeats of "
                 f"{episode} steps")
        rates = vector_rates(runs, repeats)
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
            progress(f"vector {n:,}: {name}")
            rates.update(vector_rates({name: (peer, actions, steps)}, repeats))
            peer.close()
        base = ours.unwrapped
        tau = a[0, :, 0].astype(np.float64) * base.task.max_torque
        stepper = base._stepper

        def kernel(stepper=stepper, base=base, tau=tau) -> None:
            for _ in range(steps):
                stepper.run(base.phi, base.phi_dot, tau)

        progress(f"vector {n:,}: the physics kernel alone")
        kernel_rate = n * steps / timing.best_time(kernel, repeats)
        progress(f"vector {n:,}: the share of a step outside the physics kernel")
        outside = outside_physics_share(ours, a, REPLAY_EVERY, share_repeats)
        progress(f"vector {n:,}: the kernel against its arithmetic")
        out[str(n)] = {name: rate for name, (rate, _) in rates.items()}
        out[str(n)].update({"ours_steps": episode, "kernel": kernel_rate,
                            "outside_kernel_share": outside,
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

    rhs_ns = timing.best_time(rhs, repeats) / (20 * n) * 1e9
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
    rate = stepper.tolerance * scheme.tol_share / stepper.dt

    def expand() -> None:
        for _ in range(20):
            integ._taylor_lanes(x, n, 0.0, rate, lanes)

    return {"rhs_ns": rhs_ns, "unit": "expansion", "unit_ns": timing.best_time(expand, repeats)
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

    return timing.best_time(run, repeats)


def measure_single(steps: int, repeats: int) -> dict[str, float]:
    """Steps per second of one environment through ``gymnasium.make`` (with and without
    the info) and of Pendulum-v1, ``steps`` steps a run (resets included), best of
    ``repeats``."""
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

        out[key] = steps / timing.best_time(run, repeats)
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


def measure(quick: bool, command: str = "",
            progress: Callable[[str], None] = timing.progress) -> dict[str, Any]:
    """Measure everything (``quick``: a smoke run in seconds); the results as plain data.
    ``progress`` is told of each measurement as it starts (default: a line on stderr)."""
    sizes = (256, 1024) if quick else (4096, 65536)
    steps, repeats = (5, 2) if quick else (20, 3)
    start_n = 1024 if quick else 65536
    date = records.now()
    vector = measure_vector(sizes, steps, repeats, whole_episodes=not quick,
                            share_repeats=repeats if quick else SHARE_REPEATS,
                            progress=progress)
    progress(f"start: make_vec + reset of {start_n:,}")
    start = {str(start_n): measure_start(start_n, repeats)}
    progress("one environment against Pendulum-v1")
    single = measure_single(2000 if quick else 20000, repeats)
    progress("SB3 PPO, 16 environments: RollerVecEnv against DummyVecEnv")
    ppo = measure_ppo(16, 2048 if quick else 16384)
    return {
        "machine": records.machine(),
        "date": date,
        "command": command or " ".join([os.path.basename(sys.executable), "-m", __spec__.name
                                        if __spec__ else __name__, *sys.argv[1:]]),
        "quick": quick,
        "vector": vector,
        "start_seconds": start,
        "single": single,
        "ppo": ppo,
        "peers_missing": peers_missing(),
    }


def main(argv: Sequence[str] | None = None) -> None:
    from roller_gym.bench import throughput_report, verdicts

    parser = argparse.ArgumentParser(description="The environments' throughput against "
                                                 "their peers (ratios measured in one run).")
    parser.add_argument("action", choices=("measure", "render"),
                        help="measure (and render), or render the results file again")
    parser.add_argument("--out", type=Path, default=Path("docs"),
                        help="the docs folder: results go to OUT/benchmarks/throughput.json, "
                             "the page to OUT/THROUGHPUT.md (default ./docs)")
    parser.add_argument("--quick", action="store_true", help="a smoke run in seconds")
    args = parser.parse_args(argv)
    path = args.out / RESULTS_FILE
    if args.action == "measure":
        records.save_results(measure(args.quick), path)
        print(f"wrote {path}")
    results = records.load_results(path)
    for page in throughput_report.write(results, args.out):
        print(f"wrote {page}")
    for v in verdicts.throughput_verdicts(results):
        print(f"{v.sentence.replace('**', '')}: {v.target}: {v.measured}")


if __name__ == "__main__":
    main()
