"""The integrators over long horizons and on hard cases, and where a step must fail.

Long horizons: energy (zero torque) and E − τφ (constant torque) kept over 1e5 control steps,
against bounds set once; hard scenes (nearly tight fits, a rim mass, the floor, a drum's
unstable top); states and torques that overflow, steps past the sines' domain. The
reference, the error and the random states are those of ``integrator_cases``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from integrator_cases import DT, error, meaningful_states, reference
from roller_gym.physics import Scene, analysis, integrators, preset, step, trig
from roller_gym.physics import equations as eq
from scipy.integrate import solve_ivp

# -- long horizons --------------------------------------------------------------------------------


def _run(scene: Scene, phi, w, torque, steps, method, tol=1e-9, substeps=0):
    """Many control steps through a Stepper; the trajectory's φ and φ' (steps + 1 each)."""
    stepper = integrators.Stepper(scene, integrator=method, dt=DT, tolerance=tol,
                                  substeps=substeps or None)
    phis, ws = np.empty(steps + 1), np.empty(steps + 1)
    phis[0], ws[0] = phi, w
    for i in range(steps):
        out = stepper.advance(phi, w, torque)
        assert out[4], i
        phi, w = out[0], out[1]
        phis[i + 1], ws[i + 1] = phi, w
    return phis, ws


def test_midpoint_energy_error_stays_bounded_while_euler_drifts():
    """Zero torque, no damping, released from φ = 1 rad (E0 ≈ 0.302 J) on "paper", 20,000
    control steps (1000 s). The implicit midpoint (4 substeps) keeps its energy error
    bounded: measured 4.4e-5 J, the same in the last 1000 steps as in the first; asserted
    <= 1e-4 J and no growth (last <= 1.1 × first). Semi-implicit Euler, with ten times the
    substeps (40), drifts: measured 0.06 J in the first 1000 steps, 0.26 J in the last;
    asserted to grow at least 2× and to end 100× above the midpoint's."""
    scene = preset("paper")
    e0 = analysis.energy(scene, 1.0, 0.0)

    def drift(method, substeps):
        phi, w = _run(scene, 1.0, 0.0, 0.0, 20_000, method, substeps=substeps)
        err = np.abs(analysis.energy(scene, phi, w) - e0)
        return err[:1000].max(), err[-1000:].max()

    mid_first, mid_last = drift("midpoint", 4)
    assert max(mid_first, mid_last) <= 1e-4
    assert mid_last <= 1.1 * mid_first
    euler_first, euler_last = drift("euler", 40)
    assert euler_last >= 2 * euler_first
    assert euler_last >= 100 * mid_last


#: bounds on the drift of E (zero torque) and of E − τφ (maximum torque) [J] over 1e5 steps of
#: 0.05 s at tol 1e-9 on "paper", set on the integrators' first version (the largest then
#: measured, 3.2e-9 J for rk4 and 1.5e-8 J for rk8, with 1.5× and 4× margin) and kept since;
#: taylor's set when it was added (measured 5.7e-11 J, with 3.5× margin). rk4's also bounds
#: its tol_share (0.12: 2.1e-9 J at zero torque; 0.16: 3.2e-9 J; 0.25: 5.4e-9 J, over it).
LONG_RUN_BOUND = {"rk4": 5e-9, "rk8": 6e-8, "taylor": 2e-10}


@pytest.mark.parametrize("method", ["rk4", "rk8", "taylor"])
def test_zero_torque_for_1e5_steps_keeps_the_energy(method):
    """1e5 control steps (5000 s) of "paper" at zero torque, no damping, tol = 1e-9, from
    rest at φ = 1 rad (E0 ≈ 0.302 J). Measured energy error under error control: rk4
    2.1e-9 J, rk8 1.4e-9 J, taylor 5.7e-11 J (rk8's a slow linear drift, ~1.4e-14 J per
    step: 4.6e-9 of E0); asserted within LONG_RUN_BOUND: 5e-9 J
    (rk4), 6e-8 J (rk8), 2e-10 J (taylor). The motion stays
    the same swing: |φ| exceeds 1 rad by no more than that energy error allows."""
    scene = preset("paper")
    phi, w = _run(scene, 1.0, 0.0, 0.0, 100_000, method)
    energy = analysis.energy(scene, phi, w)
    assert np.max(np.abs(energy - energy[0])) <= LONG_RUN_BOUND[method]
    # the same swing: the turning points move by at most what the energy bound allows,
    # ΔE / V'(1) (V'(φ) = the torque that holds φ)
    slope = float(analysis.holding_torque(scene, 1.0))
    assert np.max(np.abs(phi)) <= 1.0 + LONG_RUN_BOUND[method] / slope


#: the largest torque of these tests: m g (r + e)/2, about half of the largest the weight can
#: hold (1.31 N·m on "paper") and below the 0.605 × 1.31 N·m above which the roller, released
#: at rest at the bottom, would climb out of its well and spin up without bound.
def _max_torque(scene: Scene) -> float:
    return 0.5 * scene.m * scene.g * (scene.r + scene.e)


def _turning_point(scene: Scene, torque: float) -> float:
    """The φ > 0 where V(φ) = τφ (from rest at 0 with E − τφ = 0, the far turning point)."""
    from scipy.optimize import brentq

    m, r, e, g, R = scene.m, scene.r, scene.e, scene.g, scene.R

    def f(phi):
        psi = r * phi / (R - r)
        return m * g * ((R - r) * (1 - math.cos(psi)) + e * (1 - math.cos(phi))) - torque * phi

    grid = np.linspace(0.1, 20, 2000)
    values = np.array([f(x) for x in grid])
    i = int(np.nonzero(values >= 0)[0][0])
    return brentq(f, grid[i - 1], grid[i], xtol=1e-14)


@pytest.mark.parametrize("method", ["rk4", "rk8", "taylor"])
def test_maximum_torque_for_1e5_steps_keeps_e_minus_tau_phi(method):
    """Constant maximum torque, no damping: E − τφ is an exact invariant. 1e5 steps of 0.05 s
    at tol 1e-9 from rest at φ = 0 on "paper": measured drift 2.5e-10 J (rk4), 5.1e-9
    J (rk8), 8e-12 J (taylor); asserted <= LONG_RUN_BOUND. The swing reaches the turning
    point where V(φ) = τφ (solved here independently), and not beyond it by more than the
    drift allows."""
    scene = preset("paper")
    torque = _max_torque(scene)
    phi, w = _run(scene, 0.0, 0.0, torque, 100_000, method)
    invariant = analysis.energy(scene, phi, w) - torque * phi
    assert np.max(np.abs(invariant)) <= LONG_RUN_BOUND[method]
    turn = _turning_point(scene, torque)
    # A drift δ of E − τφ moves the turning points by δ/|d(V − τφ)/dφ| there.
    slope = abs(float(analysis.holding_torque(scene, turn)) - torque)
    shift = LONG_RUN_BOUND[method] / slope
    assert turn - 0.05 <= phi.max() <= turn + shift
    assert phi.min() >= -LONG_RUN_BOUND[method] / torque


@pytest.mark.parametrize("method", ["rk4", "rk8", "taylor"])
def test_maximum_torque_segment_against_dop853(method):
    """The first 200 control steps (10 s) under the maximum torque: each step within tol of
    DOP853 restarted from the integrator's state, and the whole segment within 200 · tol of
    one DOP853 run from the start."""
    scene = preset("paper")
    torque = _max_torque(scene)
    tol = 1e-9
    phi, w = _run(scene, 0.0, 0.0, torque, 200, method, tol=tol)
    for i in range(0, 200, 10):
        ref = reference(scene, phi[i], w[i], torque)
        assert max(abs(phi[i + 1] - ref[0]), abs(w[i + 1] - ref[1])) <= tol
    params = scene.params
    sol = solve_ivp(lambda _t, y: [y[1], eq.accel(y[0], y[1], torque, *params)], (0, 200 * DT),
                    [0.0, 0.0], method="DOP853", rtol=1e-13, atol=1e-13, max_step=DT / 10,
                    t_eval=np.arange(201) * DT)
    assert np.max(np.abs(phi - sol.y[0])) <= 200 * tol
    assert np.max(np.abs(w - sol.y[1])) <= 200 * tol


# -- hard cases -----------------------------------------------------------------------------------

HARD = {
    "R=1.001r": Scene(R=1.001 * 0.1),
    "e=0.999r,k=0.01r": Scene(e=0.999 * 0.1, k=0.01 * 0.1),
    "floor": Scene(R=math.inf),
    "R=1e12": Scene(R=1e12),
    "drum": preset("drum"),
}


@pytest.mark.parametrize("method", ["rk4", "rk8", "taylor"])
@pytest.mark.parametrize("name", list(HARD))
def test_hard_scenes_stay_within_tol(name, method):
    """R = 1.001 r (θ turns 1000× faster than φ), e = 0.999 r with k = 0.01 r (J_I dips
    10^4-fold at θ = 0), the floor, R = 1e12 and the drum: error per step <= tol = 1e-7,
    and every step reports tol_met (none is out of reach)."""
    scene = HARD[name]
    tol = 1e-7
    rng = np.random.default_rng(list(HARD).index(name))
    for state in meaningful_states(scene, rng, 3 if name == "R=1.001r" else 4):
        out = step(scene, *state, DT, integrator=method, tolerance=tol)
        assert out.finite
        assert out.tol_met, (state, out.substeps)
        assert error(out, reference(scene, *state)) <= tol, state


def test_rim_mass_through_the_dip_of_j_i():
    """e = 0.999 r, k = 0.01 r swinging through θ = 0 (J_I at its 10^4-fold dip) with the
    energy of a 1 rad release: within tol = 1e-7 of DOP853, and E − τφ kept to 1e-6 J."""
    scene = HARD["e=0.999r,k=0.01r"]
    w0 = math.sqrt(2 * analysis.energy(scene, 1.0, 0.0) / analysis.moment_of_inertia(scene, 0.0))
    for method in ("rk4", "rk8", "taylor"):
        out = step(scene, -0.01, w0, 0.0, DT, integrator=method, tolerance=1e-7)
        assert out.tol_met, method
        assert error(out, reference(scene, -0.01, w0, 0.0)) <= 1e-7
        assert abs(out.energy - analysis.energy(scene, -0.01, w0)) <= 1e-6


def test_floor_and_a_huge_cylinder_step_alike():
    """R = 1e12 takes the floor's substeps, and both are within tol of their references.
    They differ physically by ~rκ|φ| ≈ 1e-12 relative (θ = φ/(1 − r/R)), so agree to 1e-10."""
    floor, huge = HARD["floor"], HARD["R=1e12"]
    for state in meaningful_states(floor, np.random.default_rng(9), 6):
        a = step(floor, *state, DT)
        b = step(huge, *state, DT)
        assert a.substeps == b.substeps
        assert error(a, reference(floor, *state)) <= 1e-9
        assert error(b, reference(huge, *state)) <= 1e-9
        assert error(a, (b.phi, b.phi_dot)) <= 1e-10


def test_drum_falls_off_its_unstable_top_as_dop853_does():
    """On top of the drum, released 1e-3 rad beside the unstable rest position: 40 steps
    (2 s) of the fall stay within 40 · tol of one DOP853 run."""
    scene = preset("drum")
    unstable = next(x for x in analysis.equilibria(scene) if not x.stable and x.phi > 0)
    phi0, tol = unstable.phi + 1e-3, 1e-9
    phi, w = _run(scene, phi0, 0.0, 0.0, 40, "rk4", tol=tol)
    params = scene.params
    sol = solve_ivp(lambda _t, y: [y[1], eq.accel(y[0], y[1], 0.0, *params)], (0, 40 * DT),
                    [phi0, 0.0], method="DOP853", rtol=1e-13, atol=1e-13, max_step=DT / 10,
                    t_eval=np.arange(41) * DT)
    assert abs(phi[-1] - phi0) > 0.5  # it did fall
    assert np.max(np.abs(phi - sol.y[0])) <= 40 * tol
    assert np.max(np.abs(w - sol.y[1])) <= 40 * tol


ABSURD = [
    (0.3, 1e200, 0.0),
    (0.3, -1e308, 0.0),
    (0.3, 0.0, 1e300),
]
NAN_FIELDS = ("phi_ddot", "normal_force", "friction_force", "energy", "liftoff_margin",
              "slip_margin", "error_estimate")


@pytest.mark.parametrize(
    ("state", "method"), [(s, m) for m in ("rk8", "rk4", "taylor", "euler", "midpoint", "dop853")
                          for s in ABSURD]
)
def test_a_step_that_cannot_stay_finite_reports_nan_and_keeps_the_state(state, method):
    """States or torques that overflow on the first evaluation: finite=False, φ and φ' the
    state before the step, every other float field NaN (so it never reads as a lift-off)."""
    scene = preset("paper")
    with np.errstate(all="ignore"):
        out = step(scene, *state, DT, integrator=method, tolerance=1e-6)
    assert out.finite is False
    assert (out.phi, out.phi_dot) == state[:2]
    for field in NAN_FIELDS:
        assert math.isnan(getattr(out, field)), field
    assert not out.lifting and not out.slipping


@pytest.mark.parametrize("method", ["rk8", "rk4", "taylor"])
def test_failure_semantics_for_huge_dt_and_gravity(method):
    """dt = 1e6 s and g = 1e300 m/s²: either finite within tol of nothing we can check, or
    failed with the NaN fields; never a finite-looking step with a non-finite field, and a
    batch with one failing roller keeps the other rollers' results."""
    cases = [(preset("paper"), 1e6), (preset("paper").replace(g=1e300), DT)]
    for scene, dt in cases:
        with np.errstate(all="ignore"):
            out = step(scene, 0.3, 1.0, 0.1, dt, integrator=method, tolerance=1e-6)
        if out.finite:
            assert all(math.isfinite(getattr(out, f)) for f in NAN_FIELDS)
        else:
            assert (out.phi, out.phi_dot) == (0.3, 1.0)
            assert all(math.isnan(getattr(out, f)) for f in NAN_FIELDS)
    batch = Scene.stack([preset("paper"), preset("paper").replace(g=1e300)])
    with np.errstate(all="ignore"):
        out = step(batch, 0.3, 1.0, 0.1, DT, integrator=method, tolerance=1e-6)
    alone = step(preset("paper"), 0.3, 1.0, 0.1, DT, integrator=method, tolerance=1e-6)
    assert out.finite[0] and out.phi[0] == alone.phi


@pytest.mark.parametrize("method", ["taylor", "rk8", "rk4"])
def test_a_step_ending_past_the_domain_of_the_sines_is_failed(method):
    """A concentric roller on the floor (it rolls at constant speed) at 1000 rad/s, 0.05 s
    from φ = 2⁵⁰ − 10 rad: the step ends past trig.DOMAIN = 2⁵⁰ rad, where sin φ is NaN, so
    it fails (the state before it, NaN fields); from 2⁵⁰ − 100 rad it ends inside and is an
    ordinary step, 50 rad on."""
    scene, domain = Scene(R=math.inf, e=0.0), trig.DOMAIN
    assert domain == 2.0**50 and math.isnan(trig.sin(domain * 1.01))
    out = step(scene, domain - 10.0, 1000.0, 0.0, DT, integrator=method)
    assert not out.finite and (out.phi, out.phi_dot) == (domain - 10.0, 1000.0)
    assert math.isnan(out.energy) and math.isnan(out.normal_force)
    inside = step(scene, domain - 100.0, 1000.0, 0.0, DT, integrator=method)
    assert inside.finite and abs(inside.phi - (domain - 50.0)) <= 1.0


def test_taylor_at_rest_over_a_huge_step_stays_finite():
    """At rest at the bottom with no torque every coefficient past the first is 0: the
    substep is the whole step, however long (2e19 s: h¹⁷ overflows), and nothing changes."""
    out = step(preset("paper"), 0.0, 0.0, 0.0, 2e19, integrator="taylor", tolerance=1e-9)
    assert out.finite and out.tol_met
    assert (out.phi, out.phi_dot, out.error_estimate) == (0.0, 0.0, 0.0)
