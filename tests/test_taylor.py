"""The Taylor series of the motion (``roller_gym.physics.taylor``), against series arithmetic
written here independently: plain convolutions on NumPy arrays, the sine and cosine of a
series from their derivatives, and the quotient L/D by long division."""

from __future__ import annotations

import importlib
import itertools
import math
import subprocess
import sys

import numpy as np
import pytest
from roller_gym.physics import integrators, preset, step, taylor
from roller_gym.physics.scene import Scene

#: The generated module of each degree offered.
SERIES = {d: importlib.import_module(taylor.module_name(d)) for d in taylor.DEGREES}
series = SERIES[taylor.ORDER]


def test_the_generated_modules_are_current():
    """Every ``_taylor_series_<degree>.py`` is what the generator writes today, one for each
    degree offered and no other (regenerate them with ``python -m roller_gym.physics.taylor``)."""
    for degree, module in SERIES.items():
        assert taylor.generated(degree).read_text() == taylor.source(degree)
        assert degree == module.ORDER
    on_disk = {p.name for p in taylor.generated(taylor.ORDER).parent.glob("_taylor_series*.py")}
    assert on_disk == {taylor.generated(d).name for d in taylor.DEGREES}


@pytest.mark.parametrize("degree", taylor.DEGREES)
def test_the_compiled_recurrences_run_the_interpreted_operations_bit_for_bit(degree):
    """Compiled, the recurrences are machine code emitted from the generator's program
    (``roller_gym.physics.taylor_ir``); numba compiling the generated Python, and CPython
    interpreting it, give the same bits on 500 random states, scenes and torques of every
    kind of curvature (every sum's order is the program's, and no operation is fused)."""
    numba = pytest.importorskip("numba")
    from roller_gym.physics import equations as eq

    module = SERIES[degree]
    lowered = numba.njit(error_model="numpy")(module.recurrences)  # numba's own lowering
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
        compiled = np.concatenate([np.array(part) for part in module.coefficients(*args)])
        for other in (lowered(*inputs), module.recurrences(*inputs)):
            other = np.concatenate([np.array(part) for part in other])
            np.testing.assert_array_equal(compiled.view(np.int64), other.view(np.int64))


def test_a_lower_degree_is_the_leading_terms_of_the_higher_bit_for_bit():
    """The recurrences of a coefficient do not depend on the degree: each lower degree's
    X and V are the first terms of the highest degree's, bit for bit, and its step-size
    root and power are x^(1/(p − 2)) and h^(p − 2)."""
    rng = np.random.default_rng(5)
    top = SERIES[max(taylor.DEGREES)]
    for degree, module in SERIES.items():
        for _ in range(50):
            args = (rng.uniform(-5, 5), rng.uniform(-30, 30), rng.uniform(-2, 2),
                    *preset("paper").params)
            X, V, angles = module.coefficients(*args)
            Xt, Vt, angles_t = top.coefficients(*args)
            low = np.array(X + V + angles)
            assert low.view(np.int64).tolist() == np.array(
                Xt[: degree + 1] + Vt[: degree + 1] + angles_t).view(np.int64).tolist()
        assert module.root(2.0 ** (degree - 2)) == pytest.approx(2.0, rel=1e-15)
        assert module.power(1.5) == pytest.approx(1.5 ** (degree - 2), rel=1e-14)


def test_the_degree_follows_the_tolerance():
    """The rule (``taylor.degree``) takes every degree offered somewhere, never a higher one
    for a looser tolerance, the default degree at the default tolerance; the steppers run
    the degree it chooses (the same bits as asking for it), or the one asked for."""
    tols = np.geomspace(1e-14, 10.0, 151)
    chosen = [taylor.degree(t) for t in tols]
    assert set(chosen) == set(taylor.DEGREES)
    assert all(a >= b for a, b in itertools.pairwise(chosen))
    assert taylor.degree(1e-8) == taylor.ORDER
    scene, state = preset("paper"), (np.array([0.3, -2.0]), np.array([4.0, 25.0]), 0.2)
    for tol in (0.3, 1e-4, 1e-8):
        stepper = integrators.Stepper(scene, dt=0.05, tolerance=tol)
        assert stepper.degree == taylor.degree(tol)
        ruled = step(scene, *state, 0.05, tolerance=tol)
        for degree in taylor.DEGREES:
            asked = step(scene, *state, 0.05, tolerance=tol, degree=degree)
            same = np.array_equal(asked.phi, ruled.phi) and np.array_equal(asked.phi_dot,
                                                                           ruled.phi_dot)
            assert same == (degree == taylor.degree(tol)), (tol, degree)
    with pytest.raises(ValueError, match="degree"):
        integrators.Stepper(scene, dt=0.05, tolerance=1e-8, degree=12)
    with pytest.raises(ValueError, match="degree"):
        integrators.Stepper(scene, integrator="rk8", dt=0.05, tolerance=1e-8, degree=10)


def test_a_default_step_imports_no_other_degree():
    """A process that steps at the default tolerance neither imports nor compiles another
    degree's series (each is compiled only where first used)."""
    code = ("import sys; from roller_gym.physics import preset, step; "
            "step(preset('paper'), 0.1, 0.0, 0.0, 0.05, tolerance=1e-8); "
            "print(sorted(m for m in sys.modules if '_taylor_series' in m))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == repr([taylor.module_name(taylor.ORDER)])


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
    """Every coefficient of φ and φ' to degree ORDER (the highest offered), at random
    states and torques, agrees with the independent series to 1e-12 of the largest term it
    feeds at h = 1/ρ (ρ the growth rate of the coefficients), and φ'' (V[1]) is the compiled
    equations.accel's bit for bit."""
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
