"""The Taylor series of the motion (``roller_gym.physics.taylor``), against series arithmetic
written here independently: plain convolutions on NumPy arrays, the sine and cosine of a
series from their derivatives, and the quotient L/D by long division."""

from __future__ import annotations

import math

import numpy as np
import pytest
from roller_gym.physics import _taylor_series as series
from roller_gym.physics import integrators, preset, taylor
from roller_gym.physics.scene import Scene


def test_the_generated_module_is_current():
    """``_taylor_series.py`` is what the generator writes today (regenerate it with
    ``python -m roller_gym.physics.taylor``)."""
    assert taylor.GENERATED.read_text() == taylor.source()
    assert series.ORDER == taylor.ORDER


def test_the_compiled_recurrences_run_the_interpreted_operations_bit_for_bit():
    """Compiled, the recurrences are machine code emitted from the generator's program
    (``roller_gym.physics.taylor_ir``); numba compiling the generated Python, and CPython
    interpreting it, give the same bits on 500 random states, scenes and torques of every
    kind of curvature (every sum's order is the program's, and no operation is fused)."""
    numba = pytest.importorskip("numba")
    from roller_gym.physics import equations as eq

    lowered = numba.njit(error_model="numpy")(series.recurrences)  # numba's own lowering
    rng = np.random.default_rng(20261127)
    for _ in range(500):
        r = rng.uniform(0.05, 0.2)
        kappa = rng.choice([0.0, 1 / rng.uniform(r + 0.01, 2.0), -1 / rng.uniform(0.2, 2.0)])
        m, e, k = rng.uniform(0.5, 2), rng.uniform(0, r), rng.uniform(1e-3, 0.1)
        c = rng.uniform(0, 0.1)
        phi, phi_dot, tau = rng.uniform(-5, 5), rng.uniform(-30, 30), rng.uniform(-2, 2)
        args = (phi, phi_dot, tau, m, r, kappa, e, k, 9.81, c)
        terms = eq.accel_terms(*args)
        inputs = (phi, phi_dot, m, r, kappa, e, 9.81, c, *terms)
        compiled = np.concatenate([np.array(part) for part in series.coefficients(*args)])
        for other in (lowered(*inputs), series.recurrences(*inputs)):
            other = np.concatenate([np.array(part) for part in other])
            np.testing.assert_array_equal(compiled.view(np.int64), other.view(np.int64))


def _product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.convolve(a, b)[: a.size]


def _quotient(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    q = np.zeros(a.size)
    for n in range(a.size):
        q[n] = (a[n] - np.dot(b[1 : n + 1], q[n - 1 :: -1][:n])) / b[0]
    return q


def _sin_cos(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """sin u and cos u of a series u, from (sin u)' = u' cos u, (cos u)' = −u' sin u."""
    du = np.arange(u.size) * u  # coefficient n of t·u'
    s, c = np.zeros(u.size), np.zeros(u.size)
    s[0], c[0] = math.sin(u[0]), math.cos(u[0])
    for n in range(1, u.size):
        s[n] = np.dot(du[1 : n + 1], c[n - 1 :: -1][:n]) / n
        c[n] = -np.dot(du[1 : n + 1], s[n - 1 :: -1][:n]) / n
    return s, c


def _independent(phi, w, tau, m, r, kappa, e, k, g, c, order):
    """X, V of φ(t0 + h) and φ'(t0 + h), coefficient by coefficient from the equation of
    motion as PHYSICS.md writes it: (k² + r² + e² − 2 r e cos θ) φ'' = (τ − c φ')/m
    − (e r/s) φ'² sin θ − g (r sin ψ + e sin φ)."""
    X, V = np.zeros(order + 1), np.zeros(order + 1)
    X[0], V[0] = phi, w
    s = 1 - r * kappa
    for n in range(order):
        x, v = X[: n + 1], V[: n + 1]
        one = np.eye(1, n + 1)[0]
        sin_t, cos_t = _sin_cos(x / s)
        sin_q, _ = _sin_cos(r * kappa * x / s)
        sin_p, _ = _sin_cos(x)
        lhs = ((tau * one - c * v) / m - e * r / s * _product(_product(v, v), sin_t)
               - g * (r * sin_q + e * sin_p))
        inertia = (k * k + r * r + e * e) * one - 2 * r * e * cos_t
        V[n + 1] = _quotient(lhs, inertia)[n] / (n + 1)
        X[n + 1] = V[n] / (n + 1)
    return X, V


def _compiled_accel(scene: Scene, phi: float, w: float, tau: float) -> float:
    """equations.accel as the kernels compile it (from Python it takes NumPy's sines,
    which may differ in the last bit)."""
    out = np.empty(1)
    integrators._accel_lanes(np.array([phi]), np.array([w]), np.array([tau]),
                             integrators.scene_arrays(scene), 1, out)
    return float(out[0])


SCENES = {
    "paper": preset("paper").replace(damping=0.02),
    "tight_fit": preset("tight_fit"),
    "rim_mass": preset("rim_mass"),
    "floor": preset("floor"),
    "drum": preset("drum"),
    "concentric": Scene(e=0.0),
}


@pytest.mark.parametrize("name", list(SCENES))
def test_coefficients_match_independent_series_arithmetic(name):
    """Every coefficient of φ and φ' to degree ORDER, at random states and torques, agrees
    with the independent series to 1e-12 of the largest term it feeds at h = 1/ρ (ρ the
    growth rate of the coefficients), and φ'' (V[1]) is the compiled equations.accel's bit
    for bit."""
    scene = SCENES[name]
    params = scene.params
    rng = np.random.default_rng(list(SCENES).index(name))
    for _ in range(5):
        phi, w = rng.uniform(-3, 3), rng.uniform(-8, 8)
        tau = rng.uniform(-0.5, 0.5) * scene.m * scene.g * scene.r
        X, V, angles = series.coefficients(phi, w, tau, *params)
        X, V = np.array(X), np.array(V)
        # the expansion point's sin θ, cos θ, sin ψ, cos ψ, for the margins: libm's
        theta = phi / (1 - scene.r * scene.kappa)
        psi = scene.r * scene.kappa * theta
        exact = (math.sin(theta), math.cos(theta), math.sin(psi), math.cos(psi))
        assert np.max(np.abs(np.subtract(angles, exact))) <= 4 * np.finfo(float).eps, name
        Xi, Vi = _independent(phi, w, tau, *params, series.ORDER)
        for got, want in ((X, Xi), (V, Vi)):
            n = np.arange(want.size)
            # scale each coefficient by the growth of the series, so that all count alike
            rate = max(np.max(np.abs(want[1:]) ** (1 / n[1:])), 1.0)
            scaled = np.abs(got - want) / rate**n
            assert scaled.max() <= 1e-12 * np.max(np.abs(want) / rate**n), (name, scaled)
        assert V[1] == _compiled_accel(scene, phi, w, tau)
