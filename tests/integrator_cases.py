"""What the integrators' tests share: the control step, the reference, the error, random states.

The reference is scipy's DOP853 at rtol = atol = 1e-13 (and at most dt/50 per step) on
``equations.accel`` — the equation checked against Lagrange and Newton–Euler in
test_reference_derivations.py. "Error" is the state error after one control step,
max(|Δφ| [rad], |Δφ'| [rad/s]), which is what ``tol`` bounds.

Random states are physically meaningful: |ψ| <= π (|φ| <= 2π on the drum), kinetic energy up
to m g r, |τ| <= m g (r + e)/2. The benchmark's adversarial sample is the hard one.
"""

from __future__ import annotations

import math

import numpy as np
from roller_gym.bench.cost import adversarial_sample
from roller_gym.physics import Scene, analysis
from roller_gym.physics import equations as eq
from scipy.integrate import solve_ivp

DT = 0.05


def reference(scene: Scene, phi, phi_dot, torque, dt=DT, dense=False):
    """DOP853 at rtol = atol = 1e-13 over dt, at most dt/50 per step: the end state."""
    params = scene.params

    def rhs(_t, y):
        return [y[1], eq.accel(y[0], y[1], torque, *params)]

    sol = solve_ivp(rhs, (0.0, dt), [phi, phi_dot], method="DOP853", rtol=1e-13, atol=1e-13,
                    max_step=dt / 50, dense_output=dense)
    assert sol.success
    return sol if dense else sol.y[:, -1]


def error(result, ref) -> float:
    return max(abs(result.phi - ref[0]), abs(result.phi_dot - ref[1]))


def meaningful_states(scene: Scene, rng: np.random.Generator, n: int):
    """|ψ| <= π (|φ| <= 2π where ψ turns slower), ½ J_I φ'² <= m g r, |τ| <= m g (r + e)/2."""
    m, r, kappa, e, _, g, _ = scene.params
    s = 1 - r * kappa
    half = 2 * math.pi if kappa <= 0 else min(2 * math.pi, math.pi * s / (r * kappa))
    out = []
    for _ in range(n):
        phi = rng.uniform(-half, half)
        kinetic = rng.uniform(0, 1) * m * g * r
        w = rng.choice([-1, 1]) * math.sqrt(2 * kinetic / analysis.moment_of_inertia(scene, phi))
        torque = rng.uniform(-0.5, 0.5) * m * g * (r + e)
        out.append((phi, w, torque))
    return out


def _adversarial_sample(n: int, seed: int):
    """Random scenes inside a cylinder, nearly tight (R/r − 1 down to 0.005), on the floor and
    on a drum; e/r up to 0.999, k/r down to 0.01, |τ| up to 5 m g r, |φ'| up to 15 sqrt(g/r):
    the benchmark's sample (``roller_gym.bench.cost.adversarial_sample``), as
    ((m, r, R, e, k, g, c), φ, φ', τ)."""
    scene, phi, w, tau = adversarial_sample(n, seed)
    return (scene.m, scene.r, scene.R, scene.e, scene.k, scene.g, scene.damping), phi, w, tau
