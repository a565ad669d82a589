"""Random scenes, states and torques shared by the tests of the forms and the derivations."""

from __future__ import annotations

import math

import numpy as np
from roller_gym.physics import Scene

SHAPES = ("cylinder", "floor", "drum")


def sample(rng: np.random.Generator, n: int, shape: str):
    """n random scenes of one shape, with states and torques.

    m in [0.1, 10] kg, r in [0.03, 1] m, e in [0, 0.99 r) (10 % exactly 0), k in
    [0.05 r, r], g in [1, 20], damping in [0, m r² sqrt(g/r)] (20 % exactly 0); R/r in
    (1.01, 33) inside a cylinder, −R/r in (0.3, 33) for a drum. |ψ| <= π and |φ| <= 4π,
    |φ'| <= 3 sqrt(g/r), |τ| <= 2 m g (r + e).
    """
    m = 10 ** rng.uniform(-1, 1, n)
    r = 10 ** rng.uniform(-1.5, 0, n)
    e = r * rng.uniform(0, 0.99, n)
    e[rng.random(n) < 0.1] = 0.0
    k = r * 10 ** rng.uniform(-1.3, 0, n)
    g = rng.uniform(1, 20, n)
    c = m * r**2 * np.sqrt(g / r) * rng.uniform(0, 1, n)
    c[rng.random(n) < 0.2] = 0.0
    if shape == "cylinder":
        R = r * (1 + 10 ** rng.uniform(-2, 1.5, n))
    elif shape == "floor":
        R = np.full(n, math.inf)
    else:
        R = -r * 10 ** rng.uniform(-0.5, 1.5, n)
    scene = Scene(m=m, r=r, R=R, e=e, k=k, g=g, damping=c)
    return (scene, *states(rng, scene, n))


def states(rng: np.random.Generator, scene: Scene, n: int):
    """Random (φ, φ', τ) for a scene (scalar or batch) in the ranges of :func:`sample`."""
    m, r, kappa, e, _, g, _ = scene.params
    s = 1 - r * kappa
    with np.errstate(divide="ignore"):
        phi_max = np.minimum(4 * math.pi, math.pi * np.abs(s) / (r * np.abs(kappa)))
    phi = rng.uniform(-1, 1, n) * phi_max
    phi_dot = rng.uniform(-3, 3, n) * np.sqrt(g / r)
    torque = rng.uniform(-2, 2, n) * m * g * (r + e)
    return phi, phi_dot, torque


def accel_scale(scene: Scene, phi, phi_dot, torque):
    """The size of φ'' as the sum of the magnitudes of the terms that make it up.

    Each form sums moments about I — |τ| + c|φ'|, gravity's m g|IC| <= m g (r + e), and
    velocity terms each at most m |IC| (r + e + r/|s| + r²|κ|/|s|) φ'² — and divides by
    J_I = m (k² + |IC|²). Rounding errors of a sum are relative to the magnitudes of its
    terms, not to the result (which may cancel to ~0): forms agree to 1e-12 of this scale.
    It is of the order g/r for the states sampled here.
    """
    m, r, kappa, e, k, g, c = scene.params
    s = 1 - r * kappa
    ic2 = np.maximum(r**2 + e**2 - 2 * r * e * np.cos(phi / s), 0.0)
    speed_terms = (r + e) * (r + e + (r + r**2 * np.abs(kappa)) / np.abs(s)) * phi_dot**2
    moments = (np.abs(torque) + c * np.abs(phi_dot)) / m + g * (r + e) + speed_terms
    return moments / (k**2 + ic2)
