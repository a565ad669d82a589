"""Speed of the integrator kernels, as ratios to peers timed in the same run (not a test).

Prints:

* the batch stepper (``BatchStepper.advance``: "paper", dt 0.05 s, tol 1e-8, rk8, the
  error-controlled Runge–Kutta pair; the environments' default, taylor, is timed in
  ``docs/THROUGHPUT.md``) in ns per roller-step at 4,096 and 65,536 rollers, random start states
  around the bottom and random torques; against the same count of right-hand-side
  evaluations alone (``equations.accel`` in a compiled parallel loop, no control logic) and
  against Gymnasium's CartPoleVectorEnv at the same number of sub-environments;
* the scalar stepper (``Stepper.advance``) in µs per step, against Gymnasium's Pendulum-v1
  ``step`` (unwrapped);
* substeps per control step along the "paper" and "rim_mass" presets' own trajectories.

Run: ``python -m roller_gym.scripts.bench_kernel`` (about a minute).
"""

from __future__ import annotations

import numba
import numpy as np
from roller_gym.bench.timing import best_time
from roller_gym.physics import equations as eq
from roller_gym.physics import integrators as integ
from roller_gym.physics import preset

DT, TOL, METHOD = 0.05, 1e-8, "rk8"
#: right-hand-side evaluations per accepted substep of rk8 (12 stages after the first, which
#: reuses the last of the previous substep), and per control step besides (start and end).
RHS_PER_SUBSTEP, RHS_PER_STEP = 12, 2


@numba.njit(parallel=True, cache=True)
def _rhs_only(count, phi, w, tau, table):
    """``count[i]`` evaluations of φ'' for roller i (the arithmetic of the kernel's stages)."""
    n = phi.shape[0]
    out = np.empty(n)
    for i in numba.prange(n):
        m, r, kappa, e = table[0, i], table[1, i], table[2, i], table[3, i]
        k, g, c = table[4, i], table[5, i], table[6, i]
        p, v, acc = phi[i], w[i], 0.0
        for _ in range(count[i]):
            a = eq.accel(p, v, tau[i], m, r, kappa, e, k, g, c)
            acc += a
            p += 1e-9 * a  # a data dependence, so no evaluation is hoisted
        out[i] = acc
    return out


def batch(num: int, rng: np.random.Generator) -> dict[str, float]:
    scene = preset("paper")
    stepper = integ.BatchStepper(num, integrator=METHOD, dt=DT, tolerance=TOL)
    stepper.set_scenes(scene)
    phi, w = rng.uniform(-0.3, 0.3, num), rng.uniform(-1.0, 1.0, num)
    tau = rng.uniform(-0.5, 0.5, num)
    res = stepper.advance(phi, w, tau)  # compile, warm
    count = (np.asarray(res.substeps) * RHS_PER_SUBSTEP + RHS_PER_STEP).astype(np.int64)
    kernel = best_time(lambda: stepper.advance(phi, w, tau), 5)
    table = np.ascontiguousarray(stepper.scene_table())
    _rhs_only(count, phi, w, tau, table)
    rhs = best_time(lambda: _rhs_only(count, phi, w, tau, table), 5)
    out = {"kernel_ns": kernel / num * 1e9, "rhs_ns": rhs / num * 1e9,
           "substeps": float(np.mean(count - RHS_PER_STEP) / RHS_PER_SUBSTEP)}
    try:
        from gymnasium.envs.classic_control.cartpole import CartPoleVectorEnv

        env = CartPoleVectorEnv(num_envs=num)
        env.reset(seed=0)
        actions = rng.integers(0, 2, num)
        env.step(actions)
        out["cartpole_ns"] = best_time(lambda: env.step(actions), 20) / num * 1e9
    except ImportError:
        pass
    return out


def scalar(rng: np.random.Generator) -> dict[str, float]:
    import gymnasium as gym

    stepper = integ.Stepper(preset("paper"), integrator=METHOD, dt=DT, tolerance=TOL)
    torques = rng.uniform(-0.5, 0.5, 2000).tolist()
    substeps = []

    def run() -> None:  # episodes of 200 steps from rest near the bottom, random torques
        substeps.clear()
        phi, w = 0.1, 0.0
        for i, tau in enumerate(torques):
            if i % 200 == 0:
                phi, w = 0.1, 0.0
            out = stepper.advance(phi, w, tau)
            phi, w = out[0], out[1]
            substeps.append(out[3])

    run()
    ours = best_time(run, 5) / len(torques)
    env = gym.make("Pendulum-v1").unwrapped
    env.reset(seed=0)
    action = np.array([0.5], dtype=np.float32)

    def pend() -> None:
        for _ in range(len(torques)):
            env.step(action)

    pend()
    peer = best_time(pend, 5) / len(torques)
    return {"stepper_us": ours * 1e6, "pendulum_us": peer * 1e6,
            "substeps": float(np.mean(substeps))}


def trajectory_substeps(name: str, phi0: float, steps: int = 200) -> float:
    stepper = integ.Stepper(preset(name), integrator=METHOD, dt=DT, tolerance=TOL)
    phi, w, total = phi0, 0.0, 0
    for _ in range(steps):
        out = stepper.advance(phi, w, 0.0)
        phi, w, total = out[0], out[1], total + out[3]
    return total / steps


def main() -> None:
    rng = np.random.default_rng(0)
    print(f"default settings: paper, dt={DT} s, tolerance={TOL}, {METHOD}")
    for num in (4096, 65536):
        r = batch(num, rng)
        line = (f"batch {num:>6}: kernel {r['kernel_ns']:7.1f} ns/roller-step, its RHS calls "
                f"alone {r['rhs_ns']:7.1f} (kernel/RHS = {r['kernel_ns'] / r['rhs_ns']:.2f}), "
                f"{r['substeps']:.2f} substeps/step")
        if "cartpole_ns" in r:
            line += (f"; CartPoleVectorEnv {r['cartpole_ns']:.1f} ns/env-step "
                     f"(kernel/CartPole = {r['kernel_ns'] / r['cartpole_ns']:.1f})")
        print(line)
    s = scalar(rng)
    ratio = s["pendulum_us"] / s["stepper_us"]
    print(f"scalar Stepper: {s['stepper_us']:.2f} µs/step ({s['substeps']:.2f} substeps/step); "
          "Pendulum-v1 step "
          f"{s['pendulum_us']:.2f} µs (Pendulum/Stepper = {ratio:.2f})")
    for name, phi0 in (("paper", 1.0), ("rim_mass", 0.02)):
        print(f"{name}: {trajectory_substeps(name, phi0):.1f} substeps/step along its trajectory "
              f"(release at {phi0} rad, zero torque, 200 steps)")


if __name__ == "__main__":
    main()
