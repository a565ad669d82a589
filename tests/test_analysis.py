"""analysis.py: energy and power, contact margins, equilibria, linearization, small oscillations.

References: docs/PHYSICS.md's formulas typed in here, analytic results, finite differences and
complex-step derivatives, and scipy's DOP853 at rtol = 1e-13.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from roller_gym.physics import PRESETS, Scene, analysis, preset
from roller_gym.physics import equations as eq
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

STABLE_AT_REST = ["paper", "solid_disc", "tight_fit", "rim_mass", "floor", "drum", "balance"]


# -- PHYSICS.md, typed independently ----------------------------------------------------------


def spec_angles(scene: Scene, phi):
    """ψ = rφ/(R − r) and θ = Rφ/(R − r) (the floor: 0 and φ)."""
    if math.isinf(scene.R):
        return 0.0 * phi, phi
    return scene.r * phi / (scene.R - scene.r), scene.R * phi / (scene.R - scene.r)


def spec_moment_of_gravity(scene: Scene, phi):
    """m g (r sin ψ + e sin φ): the torque that holds the roller at rest at φ."""
    psi, _ = spec_angles(scene, phi)
    return scene.m * scene.g * (scene.r * np.sin(psi) + scene.e * np.sin(phi))


def spec_height(scene: Scene, phi):
    """y_C measured from the axis O (the floor: from the floor), PHYSICS.md's positions."""
    psi, _ = spec_angles(scene, phi)
    base = scene.r if math.isinf(scene.R) else -(scene.R - scene.r) * np.cos(psi)
    return base - scene.e * np.cos(phi)


def spec_j_i(scene: Scene, phi):
    _, theta = spec_angles(scene, phi)
    r, e = scene.r, scene.e
    return scene.m * (scene.k**2 + r**2 + e**2 - 2 * r * e * np.cos(theta))


def spec_omega0(scene: Scene) -> float:
    """ω0 = sqrt(g (r²/(R − r) + e)/(k² + (r − e)²)) (the floor: r²/(R − r) → 0)."""
    r, e, k = scene.r, scene.e, scene.k
    lift = 0.0 if math.isinf(scene.R) else r**2 / (scene.R - r)
    return math.sqrt(scene.g * (lift + e) / (k**2 + (r - e) ** 2))


def phi_range(scene: Scene) -> float:
    """half-width of the φ-interval that is one turn of ψ (one turn of φ on the floor)."""
    if math.isinf(scene.R):
        return math.pi
    return math.pi * abs(scene.R - scene.r) / scene.r


# -- energy and power -------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["paper", "solid_disc", "floor", "drum", "balance"])
def test_power_balance_along_a_damped_driven_trajectory(name):
    """E(T) − E(0) = ∫ (τφ' − cφ'²) dt along a DOP853 trajectory (rtol 1e-13) with damping.

    The work integral is a third state of the same integration; both sides are compared to
    1e-10 of the energy that flows (|E| plus the work of the drive and the damping).
    """
    scene = preset(name).replace(damping=0.02)
    params = scene.params
    torque = 0.3 * scene.m * scene.g * (scene.r + scene.e)

    def rhs(_t, y):
        phi, w, _, _ = y
        return [w, eq.accel(phi, w, torque, *params), torque * w, scene.damping * w * w]

    sol = solve_ivp(rhs, (0, 3.0), [0.4, -2.0, 0.0, 0.0], method="DOP853", rtol=1e-13,
                    atol=1e-13, dense_output=True)
    assert sol.success
    times = np.linspace(0, 3.0, 31)
    phi, w, work_in, loss = sol.sol(times)
    energy = analysis.energy(scene, phi, w)
    size = np.abs(energy).max() + np.abs(work_in).max() + loss.max()
    assert loss[-1] > 1e-3 * size  # the damping did take energy out
    assert np.max(np.abs(energy - energy[0] - (work_in - loss))) <= 1e-10 * size
    # analysis.power is the integrand: τφ' − cφ'²
    np.testing.assert_allclose(analysis.power(scene, w, torque), torque * w - 0.02 * w * w,
                               rtol=1e-14, atol=1e-15 * size)


@pytest.mark.parametrize("name", list(PRESETS))
def test_energy_is_zero_at_rest_at_the_bottom_and_grows_with_speed(name):
    scene = preset(name)
    assert analysis.energy(scene, 0.0, 0.0) == 0.0
    # ½ J_I(0) φ'² with J_I(0) = m (k² + (r − e)²)
    j0 = scene.m * (scene.k**2 + (scene.r - scene.e) ** 2)
    assert math.isclose(analysis.energy(scene, 0.0, 3.0), 0.5 * j0 * 9.0, rel_tol=1e-14)
    phi = np.linspace(-1, 1, 11) * phi_range(scene)
    expected = 0.5 * spec_j_i(scene, phi) * 4.0 + scene.m * scene.g * (
        spec_height(scene, phi) - spec_height(scene, 0.0)
    )
    size = scene.m * (scene.g * (abs(scene.R) if scene.shape != "floor" else 1.0) + 4.0)
    assert np.max(np.abs(analysis.energy(scene, phi, 2.0) - expected)) <= 1e-13 * size


# -- contact ----------------------------------------------------------------------------------


@pytest.mark.parametrize("name", list(PRESETS))
def test_contact_at_rest_at_the_bottom(name):
    """At φ = 0, φ' = 0: N = m g; under a torque τ, φ'' = τ/J_I(0) and F = m (r − e) φ''."""
    scene = preset(name)
    weight = scene.m * scene.g
    j0 = scene.m * (scene.k**2 + (scene.r - scene.e) ** 2)
    for torque in (0.0, 0.2, -0.5):
        got = analysis.contact(scene, 0.0, 0.0, torque)
        friction = scene.m * (scene.r - scene.e) * torque / j0
        assert math.isclose(got.normal, weight, rel_tol=1e-15)
        assert abs(got.friction - friction) <= 1e-15 * weight + 1e-14 * abs(friction)
        assert math.isclose(got.liftoff_margin, 1.0, rel_tol=1e-15)
        slip = (scene.mu * weight - abs(friction)) / weight
        assert math.isclose(got.slip_margin, slip, rel_tol=1e-14, abs_tol=1e-15)
        assert not got.lifting
        assert bool(got.slipping) == (slip < 0)


def test_slipping_starts_where_the_friction_needed_exceeds_mu_n():
    """At rest at the bottom: |F| = m (r − e)|τ|/J_I(0) = μ m g at τ* = μ g J_I(0)/(r − e)."""
    scene = preset("paper").replace(mu=0.3)
    j0 = scene.m * (scene.k**2 + (scene.r - scene.e) ** 2)
    threshold = scene.mu * scene.g * j0 / (scene.r - scene.e)
    assert not analysis.contact(scene, 0.0, 0.0, 0.99 * threshold).slipping
    assert analysis.contact(scene, 0.0, 0.0, 1.01 * threshold).slipping
    assert analysis.contact(scene, 0.0, 0.0, -1.01 * threshold).slipping
    assert abs(analysis.contact(scene, 0.0, 0.0, threshold).slip_margin) <= 1e-14


def test_lift_off_on_top_of_a_drum_at_the_analytic_speed():
    """A concentric roller on top of a drum: N/m = g − r² φ'²/(|R| + r), zero at
    φ'² = g (|R| + r)/r² (where φ'' = 0 at φ = 0, τ = 0)."""
    scene = Scene(R=-0.5, e=0.0, k=0.1 / math.sqrt(2))
    speed = math.sqrt(scene.g * (abs(scene.R) + scene.r)) / scene.r
    below = analysis.contact(scene, 0.0, 0.99 * speed, 0.0)
    above = analysis.contact(scene, 0.0, 1.01 * speed, 0.0)
    assert below.liftoff_margin > 0 and not below.lifting
    assert above.liftoff_margin < 0 and above.lifting
    assert abs(analysis.contact(scene, 0.0, speed, 0.0).liftoff_margin) <= 1e-14
    np.testing.assert_allclose(above.liftoff_margin, 1 - 1.01**2, rtol=1e-13)


# -- equilibria -------------------------------------------------------------------------------


def _independent_equilibria(scene: Scene, torque: float) -> list[float]:
    """Roots of m g (r sin ψ + e sin φ) = τ for φ in [−half, half), on a grid 10 times finer
    than equilibria()'s (and not aligned with it), each refined by Brent's method."""
    half = phi_range(scene)
    fast = max(1.0, abs(scene.R / (scene.R - scene.r)) if scene.shape != "floor" else 1.0)
    count = int(40_000 * fast * half / math.pi) + 7
    grid = np.linspace(-half - 1e-3, half + 1e-3, count)

    def f(phi):
        return spec_moment_of_gravity(scene, phi) - torque

    values = f(grid)
    roots = []
    for a, b, fa, fb in zip(grid[:-1], grid[1:], values[:-1], values[1:], strict=True):
        if fa == 0.0:
            roots.append(a)
        elif fa * fb < 0:
            roots.append(brentq(f, a, b, xtol=1e-15, rtol=1e-15))
    edge = 1e-9 * half
    return [x for x in roots if -half - edge <= x < half - edge]


def _torques(scene: Scene) -> list[float]:
    half = phi_range(scene)
    top = np.max(np.abs(spec_moment_of_gravity(scene, np.linspace(-half, half, 100_001))))
    return [0.0, 0.31 * top, -0.62 * top, 0.93 * top]


@pytest.mark.parametrize("name", list(PRESETS))
def test_equilibria_hold_are_complete_and_classified(name):
    """Each rest position holds (m g (r sin ψ + e sin φ) = τ); none is missing; stable iff
    d²V/dφ² > 0 by finite differences of m g y_C(φ); and the eigenvalues of linearize()
    there are a purely imaginary pair (stable) or include a positive real one (unstable)."""
    scene = preset(name)
    weight_arm = scene.m * scene.g * (scene.r + scene.e)
    half = phi_range(scene)
    psi_per_phi = 1.0 if scene.shape == "floor" else abs(scene.R / (scene.R - scene.r))
    for torque in _torques(scene):
        found = analysis.equilibria(scene, torque)
        expected = _independent_equilibria(scene, torque)
        assert len(found) == len(expected), (torque, found, expected)
        for eq_, ref in zip(found, expected, strict=True):
            assert abs(eq_.phi - ref) <= 1e-10 * half
            assert -half <= eq_.phi < half
            assert abs(spec_moment_of_gravity(scene, eq_.phi) - torque) <= 1e-12 * weight_arm
            assert eq_.psi == pytest.approx(spec_angles(scene, eq_.phi)[0], rel=1e-14, abs=1e-300)
            # d²(V − τφ)/dφ² by central differences of the potential m g y_C
            h = 1e-4 / psi_per_phi
            heights = spec_height(scene, eq_.phi + np.array([-h, 0.0, h]))
            stiffness = scene.m * scene.g * (heights[0] - 2 * heights[1] + heights[2]) / h**2
            if abs(stiffness) > 1e-5 * weight_arm * psi_per_phi**2:  # not degenerate
                assert eq_.stable == (stiffness > 0)
            A, _ = analysis.linearize(scene, eq_.phi, 0.0, torque)
            eig = np.linalg.eigvals(A)
            if eq_.stable:
                assert np.all(np.abs(eig.real) <= 1e-9 * np.abs(eig.imag))
                assert np.all(np.abs(eig.imag) > 0)
            else:
                assert np.max(eig.real) > 0 and np.all(np.abs(eig.imag) <= 1e-12 * abs(eig[0]))


@pytest.mark.parametrize("fraction", [0.0, 0.3, 0.99, -0.7])
def test_floor_has_two_rest_positions_below_m_g_e(fraction):
    """On the floor m g e sin φ = τ: φ = asin(τ/(m g e)) (stable) and π − asin (unstable)."""
    scene = preset("floor")
    limit = scene.m * scene.g * scene.e
    found = analysis.equilibria(scene, fraction * limit)
    assert len(found) == 2
    stable = [x for x in found if x.stable]
    unstable = [x for x in found if not x.stable]
    assert len(stable) == 1 and len(unstable) == 1
    base = math.asin(fraction)
    assert abs(stable[0].phi - base) <= 1e-12
    other = math.pi - base
    other = other - 2 * math.pi if other >= math.pi else other
    assert abs(unstable[0].phi - other) <= 1e-12
    assert all(x.psi == 0.0 for x in found)


@pytest.mark.parametrize("fraction", [1.01, -1.5, 3.0])
def test_floor_has_no_rest_position_above_m_g_e(fraction):
    scene = preset("floor")
    assert analysis.equilibria(scene, fraction * scene.m * scene.g * scene.e) == []


def test_balance_preset_has_an_unstable_rest_position_near_23_degrees():
    """At τ = 0 the balance scene (R = 10 r, e = 0.8 r) rests unstably at |ψ| ≈ 23°: the
    root of 0.1 sin ψ + 0.08 sin 9ψ = 0 near 23°, solved here by Brent's method."""
    scene = preset("balance")
    ratio = (scene.R - scene.r) / scene.r  # φ = 9 ψ

    def f(psi):
        return scene.r * math.sin(psi) + scene.e * math.sin(ratio * psi)

    psi_ref = brentq(f, math.radians(20), math.radians(26), xtol=1e-15)
    assert 22.5 <= math.degrees(psi_ref) <= 23.5
    found = analysis.equilibria(scene, 0.0)
    for sign in (1, -1):
        match = [x for x in found if abs(x.psi - sign * psi_ref) <= 1e-10]
        assert len(match) == 1
        assert not match[0].stable
        assert abs(match[0].phi - sign * ratio * psi_ref) <= 1e-9


def test_equilibria_rejects_batches_and_non_finite_torque():
    with pytest.raises(ValueError, match="scalar scene"):
        analysis.equilibria(Scene.stack([preset("paper"), preset("floor")]))
    with pytest.raises(ValueError, match="tau"):
        analysis.equilibria(preset("paper"), math.nan)


# -- linearization ------------------------------------------------------------------------------


def _complex_step(scene: Scene, phi, phi_dot, torque):
    """∂φ''/∂φ, ∂φ''/∂φ', ∂φ''/∂τ of eq.accel by complex steps (exact to rounding)."""
    h = 1e-30
    p = scene.params
    d_phi = eq.accel(phi + 1j * h, phi_dot, torque, *p).imag / h
    d_w = eq.accel(phi, phi_dot + 1j * h, torque, *p).imag / h
    d_tau = eq.accel(phi, phi_dot, torque + 1j * h, *p).imag / h
    return d_phi, d_w, d_tau


@pytest.mark.parametrize("name", list(PRESETS))
def test_linearize_matches_derivatives_of_the_acceleration(name):
    """A = [[0, 1], [∂φ''/∂φ, ∂φ''/∂φ']], B = [[0], [∂φ''/∂τ]] at arbitrary states, against
    complex-step derivatives and (independently of the complex arithmetic) central
    differences with Richardson extrapolation."""
    scene = preset(name).replace(damping=0.01)
    rng = np.random.default_rng(list(PRESETS).index(name))
    half = min(phi_range(scene), 4 * math.pi)
    phi = rng.uniform(-half, half, 200)
    phi_dot = rng.uniform(-3, 3, 200) * spec_omega0(scene) / 3
    torque = rng.uniform(-1, 1, 200) * scene.m * scene.g * (scene.r + scene.e)
    A, B = analysis.linearize(scene, phi, phi_dot, torque)
    assert A.shape == (200, 2, 2) and B.shape == (200, 2, 1)
    np.testing.assert_array_equal(A[:, 0, 0], 0.0)
    np.testing.assert_array_equal(A[:, 0, 1], 1.0)
    np.testing.assert_array_equal(B[:, 0, 0], 0.0)
    d_phi, d_w, d_tau = _complex_step(scene, phi, phi_dot, torque)
    m, r, kappa, e, _, g, c = scene.params
    s = abs(1 - r * kappa)
    # The size of each derivative is the sum of the magnitudes of its terms:
    # ∂φ''/∂φ = (−½ J_I'' φ'² − V'' − φ'' J_I')/J_I, ∂φ''/∂φ' = −(c + J_I' φ')/J_I.
    j = spec_j_i(scene, phi)
    acc = eq.accel(phi, phi_dot, torque, *scene.params)
    size_phi = (
        m * r * e / s**2 * phi_dot**2
        + m * g * (r**2 * abs(kappa) / s + e)
        + 2 * m * r * e / s * np.abs(acc)
    ) / j
    assert np.max(np.abs(A[:, 1, 0] - d_phi) / size_phi) <= 1e-12
    size_w = (c + 2 * m * r * e / s * np.abs(phi_dot)) / j
    assert np.max(np.abs(A[:, 1, 1] - d_w) / size_w) <= 1e-12
    np.testing.assert_allclose(B[:, 1, 0], d_tau, rtol=1e-14)
    np.testing.assert_allclose(B[:, 1, 0], 1 / j, rtol=1e-12)

    def central(f, x, h):
        d1 = (f(x + h) - f(x - h)) / (2 * h)
        d2 = (f(x + h / 2) - f(x - h / 2)) / h
        return (4 * d2 - d1) / 3

    p = scene.params
    # h small against the fastest angle (θ = φ/s, ψ = rκφ/s) and against the width
    # sqrt((k² + (r − e)²)/(re)) of θ over which J_I changes near θ = 0.
    width = math.sqrt((scene.k**2 + (r - e) ** 2) / (r * e)) if e > 0 else 1.0
    h = 1e-3 * s * min(1.0, width)
    fd_phi = central(lambda x: eq.accel(x, phi_dot, torque, *p), phi, h)
    assert np.max(np.abs(A[:, 1, 0] - fd_phi) / size_phi) <= 1e-6


def test_linearize_broadcasts_over_a_batch():
    scenes = list(PRESETS.values())
    batch = Scene.stack(scenes)
    phi = np.linspace(-0.5, 0.5, len(scenes))
    A, B = analysis.linearize(batch, phi, 1.0, 0.1)
    for i, scene in enumerate(scenes):
        a, b = analysis.linearize(scene, phi[i], 1.0, 0.1)
        np.testing.assert_allclose(A[i], a, rtol=1e-15, atol=1e-300)
        np.testing.assert_allclose(B[i], b, rtol=1e-15)


# -- small oscillations -------------------------------------------------------------------------


@pytest.mark.parametrize("name", STABLE_AT_REST)
def test_small_oscillation_frequency_is_the_papers(name):
    scene = preset(name)
    assert analysis.small_oscillation_frequency(scene) == pytest.approx(
        spec_omega0(scene), rel=1e-14
    )


@pytest.mark.parametrize("ratio", [1.01, 1.5, 5.0, 100.0])
def test_small_oscillation_frequency_of_a_solid_disc(ratio):
    """A uniform solid disc (e = 0, k² = r²/2): ω0² = 2g/(3(R − r))."""
    scene = preset("solid_disc").replace(R=ratio * 0.1)
    expected = math.sqrt(2 * scene.g / (3 * (scene.R - scene.r)))
    assert analysis.small_oscillation_frequency(scene) == pytest.approx(expected, rel=1e-14)


def test_small_oscillation_frequency_at_a_tilted_rest_position():
    """Under the holding torque at φ, ω² = d²V/dφ²/J_I(φ) (V'' by finite differences)."""
    scene = preset("paper")
    phi = 0.6
    h = 1e-4
    heights = spec_height(scene, phi + np.array([-h, 0.0, h]))
    stiffness = scene.m * scene.g * (heights[0] - 2 * heights[1] + heights[2]) / h**2
    expected = math.sqrt(stiffness / spec_j_i(scene, phi))
    assert analysis.small_oscillation_frequency(scene, phi) == pytest.approx(expected, rel=1e-6)


def test_small_oscillation_frequency_refuses_an_unstable_rest_position():
    scene = preset("floor")
    with pytest.raises(ValueError, match="not a stable rest position"):
        analysis.small_oscillation_frequency(scene, math.pi)
    with pytest.raises(ValueError, match="not a stable rest position"):
        analysis.small_oscillation_frequency(preset("balance"), 0.4 * 9)


@pytest.mark.parametrize("name", STABLE_AT_REST)
def test_small_oscillation_period_from_a_dop853_integration(name):
    """Released at rest from a small φ, the period (mean spacing of the upward zero crossings
    over 8 periods; DOP853, rtol 1e-13) is 2π/ω0 to 1e-7.

    The amplitude makes θ's swing 1e-5 rad or less, and 1e-5 of the width over which J_I
    changes, so its own correction to the period is O(1e-10); the crossings are located to
    ~1e-12 of a period.
    """
    scene = preset(name)
    omega0 = spec_omega0(scene)
    period = 2 * math.pi / omega0
    _, r, kappa, e, k, _, _ = scene.params
    width = math.sqrt((k**2 + (r - e) ** 2) / (r * e)) if e > 0 else 1.0
    amplitude = 1e-5 * abs(1 - r * kappa) * min(1.0, width)
    params = scene.params

    def rhs(_t, y):
        return [y[1], eq.accel(y[0], y[1], 0.0, *params)]

    def upward(_t, y):
        return y[0]

    upward.direction = 1
    sol = solve_ivp(rhs, (0, 8.3 * period), [amplitude, 0.0], method="DOP853", rtol=1e-13,
                    atol=[1e-13 * amplitude, 1e-13 * amplitude * omega0], events=upward)
    crossings = sol.t_events[0]
    assert len(crossings) == 8
    measured = np.diff(crossings).mean()
    assert measured == pytest.approx(period, rel=1e-7)


# -- batches ----------------------------------------------------------------------------------


def test_every_analysis_function_broadcasts_per_element():
    """A batch of all presets with (4, 7) states equals the scalar calls, element by element."""
    scenes = list(PRESETS.values())
    batch = Scene.stack(scenes)
    rng = np.random.default_rng(7)
    shape = (4, len(scenes))
    phi = rng.uniform(-2, 2, shape)
    w = rng.uniform(-3, 3, shape)
    tau = rng.uniform(-1, 1, shape)

    def evaluate(scene, phi, w, tau):
        kin = analysis.kinematics(scene, phi)
        con = analysis.contact(scene, phi, w, tau)
        return {
            "acceleration": analysis.acceleration(scene, phi, w, tau),
            "moment_of_inertia": analysis.moment_of_inertia(scene, phi),
            "energy": analysis.energy(scene, phi, w),
            "power": analysis.power(scene, w, tau),
            "holding_torque": analysis.holding_torque(scene, phi),
            "psi": kin.psi, "theta": kin.theta,
            "o1": np.array(kin.o1), "c": np.array(kin.c), "i": np.array(kin.i),
            "normal": con.normal, "friction": con.friction,
            "liftoff": con.liftoff_margin, "slip": con.slip_margin,
            "lifting": con.lifting, "slipping": con.slipping,
        }

    got = evaluate(batch, phi, w, tau)
    for i in range(shape[0]):
        for j, scene in enumerate(scenes):
            ref = evaluate(scene, phi[i, j], w[i, j], tau[i, j])
            for name, value in got.items():
                element = value[..., i, j]
                if value.dtype == bool:
                    assert element == ref[name], name
                else:
                    np.testing.assert_allclose(element, ref[name], rtol=1e-14, atol=1e-15,
                                               err_msg=name)
    omega = analysis.small_oscillation_frequency(batch)
    for j, scene in enumerate(scenes):
        assert omega[j] == pytest.approx(analysis.small_oscillation_frequency(scene), rel=1e-15)


def test_holding_torque_is_the_moment_of_gravity():
    for scene in PRESETS.values():
        phi = np.linspace(-1, 1, 101) * phi_range(scene)
        np.testing.assert_allclose(
            analysis.holding_torque(scene, phi), spec_moment_of_gravity(scene, phi),
            rtol=0, atol=1e-13 * scene.m * scene.g * (scene.r + scene.e),
        )
        np.testing.assert_allclose(analysis.moment_of_inertia(scene, phi), spec_j_i(scene, phi),
                                   rtol=1e-12)
