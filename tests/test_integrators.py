"""The integrators: the scheme table, accuracy per control step, order, substeps, batches.

Also the textbook form of one substep, the substep rule, the concentric path, and what a step
reports besides the state (its end state's forces and energy, the worst margins during it).
The reference, the error and the random states are those of ``integrator_cases``;
hard cases and long runs are in test_integrator_stability.py, the error control measured in
test_error_control.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from integrator_cases import DT, _adversarial_sample, error, meaningful_states, reference
from roller_gym.physics import (
    INTEGRATORS,
    PRESETS,
    Scene,
    analysis,
    integrators,
    predicted_substeps,
    preset,
    step,
)
from roller_gym.physics import equations as eq

SUBSTEPPED = tuple(name for name, row in integrators.SCHEMES.items() if row.substep is not None)
#: tolerances checked per method: from loose to the tightest the reference can verify on the
#: stiff presets (its own error there is ~2e-11).
TOLS = {
    "rk4": (1e-5, 1e-7, 1e-9),
    "rk8": (1e-5, 1e-7, 1e-9),
    "taylor": (1e-5, 1e-7, 1e-9),
    "midpoint": (1e-4, 1e-6),
    "euler": (1e-2, 1e-3, 1e-4),
}
ORDERS = {name: row.order for name, row in integrators.SCHEMES.items()}


def test_scheme_table_rows_are_consistent():
    """Every row of SCHEMES: its name is its key; the default is a row; every scheme with a
    substep function has tolerances checked here; each Runge–Kutta pair satisfies the order
    conditions Σb = 1, Σbc = 1/2, Σbc² = 1/3, Σbc³ = 1/4, Σb a c = 1/6 (c = row sums of A), and
    its error weights sum to 0 (they compare two solutions of the same step)."""
    assert integrators.DEFAULT_INTEGRATOR == "taylor"
    assert set(INTEGRATORS) == set(integrators.SCHEMES)
    for name, row in integrators.SCHEMES.items():
        assert row.name == name
        assert (row.substep is None) == (name == "dop853")
        if row.substep is not None:
            assert name in TOLS
        if row.tableau is None:
            continue
        assert row.adaptive
        tab = row.tableau
        s = tab.shape[0] - 3
        a, b, e3, e5 = tab[:s, :s], tab[s, :s], tab[s + 1], tab[s + 2]
        c = a.sum(axis=1)
        for q, want in ((0, 1), (1, 1 / 2), (2, 1 / 3), (3, 1 / 4)):
            assert b @ c**q == pytest.approx(want, abs=1e-13), (name, q)
        assert b @ (a @ c) == pytest.approx(1 / 6, abs=1e-13)
        assert e3.sum() == pytest.approx(0, abs=1e-13)
        assert e5.sum() == pytest.approx(0, abs=1e-13)


SCENES = {**PRESETS, "paper+damping": PRESETS["paper"].replace(damping=0.05)}


@pytest.fixture(scope="module")
def cases():
    """Per scene: 6 random states and their references (shared by all methods and tols)."""
    out = {}
    for i, (name, scene) in enumerate(SCENES.items()):
        states = meaningful_states(scene, np.random.default_rng(1000 + i), 6)
        out[name] = [(state, reference(scene, *state)) for state in states]
    return out


# -- accuracy per control step ----------------------------------------------------------------


@pytest.mark.parametrize("name", list(SCENES))
@pytest.mark.parametrize("method", SUBSTEPPED)
def test_error_per_control_step_is_within_tol(method, name, cases):
    """Automatic substeps: the state error after one control step is at most tol, for every
    scene and several tols — except where the rule hits MAX_SUBSTEPS (documented: a stiff
    scene at a tight tol for a low-order method), which must then be reported as such."""
    scene = SCENES[name]
    checked = 0
    for tol in TOLS[method]:
        for state, ref in cases[name]:
            result = step(scene, *state, DT, integrator=method, tolerance=tol)
            assert result.finite
            if result.substeps >= integrators.MAX_SUBSTEPS:
                assert result.substeps == integrators.MAX_SUBSTEPS
                continue
            checked += 1
            assert error(result, ref) <= tol, (tol, state, error(result, ref) / tol)
    if method in ("rk4", "rk8") or name not in ("tight_fit", "rim_mass"):
        assert checked == len(TOLS[method]) * len(cases[name])  # nothing was capped


@pytest.mark.parametrize("name", list(PRESETS))
def test_dop853_reference_is_converged(name, cases):
    """step(integrator="dop853", tolerance=1e-13), the test's own reference (max step
    dt/50) and RK4 at a fixed 20,000 substeps (error ~ (λh)^4 ≈ 1e-13 or less) agree to
    1e-10 on every preset."""
    scene = PRESETS[name]
    for state, ref in cases[name][:3]:
        own = step(scene, *state, DT, integrator="dop853", tolerance=1e-13)
        fine = step(scene, *state, DT, integrator="rk4", substeps=20_000)
        assert error(own, ref) <= 1e-10
        assert error(fine, ref) <= 1e-10


@pytest.mark.parametrize("method", SUBSTEPPED)
@pytest.mark.parametrize("name", ["paper", "drum"])
def test_observed_order_of_convergence(method, name):
    """Fixed substeps n, 2n, 4n: the error falls as n^−p, p the method's order, measured as
    log2(e_n/e_4n)/2 to ±0.2 (rk8 ±0.5: it is measured over a longer step, dt = 0.2 s,
    to stay above rounding, where its error constant still varies; taylor, of order 18, from
    n = 1 and 2 over 0.25 s, ±1 for the same reason)."""
    scene = preset(name).replace(damping=0.01)
    state = (0.7, 2.0, 0.3)
    dt, counts = {
        "rk4": (DT, (4, 8, 16)), "rk8": (0.2, (1, 2, 4)), "taylor": (0.25, (1, 2)),
        "midpoint": (DT, (10, 20, 40)), "euler": (DT, (100, 200, 400)),
    }[method]
    ref = reference(scene, *state, dt=dt)
    errors = [error(step(scene, *state, dt, integrator=method, substeps=n), ref) for n in counts]
    assert errors[-1] > 1e-13  # above rounding
    order = math.log(errors[0] / errors[-1]) / math.log(counts[-1] / counts[0])
    slack = {"rk8": 0.5, "taylor": 1.0}.get(method, 0.2)
    assert abs(order - ORDERS[method]) <= slack, (order, errors)


def _scheme_one_substep(scene: Scene, phi, w, torque, h, method):
    """One substep of each scheme as its textbook definition, on equations.accel."""

    def f(x, v):
        return eq.accel(x, v, torque, *scene.params)

    if method == "euler":  # semi-implicit (symplectic) Euler, as Gymnasium's Pendulum
        w1 = w + h * f(phi, w)
        return phi + h * w1, w1
    if method == "rk4":  # classical Runge–Kutta on y = (φ, φ')
        k1 = (w, f(phi, w))
        k2 = (w + h / 2 * k1[1], f(phi + h / 2 * k1[0], w + h / 2 * k1[1]))
        k3 = (w + h / 2 * k2[1], f(phi + h / 2 * k2[0], w + h / 2 * k2[1]))
        k4 = (w + h * k3[1], f(phi + h * k3[0], w + h * k3[1]))
        return tuple(
            y + h / 6 * (a + 2 * b + 2 * c + d)
            for y, a, b, c, d in zip((phi, w), k1, k2, k3, k4, strict=True)
        )
    raise AssertionError(method)


@pytest.mark.parametrize("method", ["euler", "rk4"])
@pytest.mark.parametrize("name", ["paper", "solid_disc", "drum"])
def test_one_substep_is_the_textbook_scheme(method, name):
    """With substeps=1 the step is one step of the scheme as defined (with damping)."""
    scene = preset(name).replace(damping=0.03)
    for phi, w, torque in meaningful_states(scene, np.random.default_rng(11), 5):
        out = step(scene, phi, w, torque, DT, integrator=method, substeps=1)
        ref = _scheme_one_substep(scene, phi, w, torque, DT, method)
        assert out.phi == pytest.approx(ref[0], rel=1e-14, abs=1e-14)
        assert out.phi_dot == pytest.approx(ref[1], rel=1e-14, abs=1e-14)


@pytest.mark.parametrize("name", ["paper", "rim_mass", "drum"])
def test_one_midpoint_substep_solves_the_midpoint_equations(name):
    """Implicit midpoint on (φ, p = J_I φ') with H = p²/(2 J_I) + V: the step satisfies
    φ1 − φ0 = h ∂H/∂p and p1 − p0 = h (−∂H/∂φ + τ − c φ') at the midpoint, to rounding
    (J_I, V and their derivatives from PHYSICS.md's formulas, typed here) — or, where
    Newton's method finds no solution (one substep of h = 5 ms through the rim mass's dip),
    reports finite=False with the state unchanged, never an unconverged iterate."""
    scene = preset(name).replace(damping=0.03)
    m, r, kappa, e, k, g, c = scene.params
    s = 1 - r * kappa

    def j(x):
        return m * (k**2 + r**2 + e**2 - 2 * r * e * math.cos(x / s))

    def dj(x):
        return 2 * m * r * e * math.sin(x / s) / s

    def dv(x):
        return m * g * (r * math.sin(r * kappa * x / s) + e * math.sin(x))

    h = DT / 10
    solved = 0
    for phi, w, torque in meaningful_states(scene, np.random.default_rng(12), 5):
        out = step(scene, phi, w, torque, h, integrator="midpoint", substeps=1)
        if not out.finite:
            assert (out.phi, out.phi_dot) == (phi, w)
            continue
        solved += 1
        p0, p1 = j(phi) * w, j(out.phi) * out.phi_dot
        xm, pm = (phi + out.phi) / 2, (p0 + p1) / 2
        vm = pm / j(xm)
        res_phi = out.phi - phi - h * vm
        res_p = p1 - p0 - h * (0.5 * dj(xm) * vm**2 - dv(xm) + torque - c * vm)
        assert abs(res_phi) <= 1e-13 * (abs(phi) + h * abs(vm) + 1)
        assert abs(res_p) <= 1e-13 * (abs(p0) + abs(p1) + h * m * g * (r + e) + h * abs(torque))
    assert solved >= 4


# -- the substep rule -----------------------------------------------------------------------------


@pytest.mark.parametrize("method", SUBSTEPPED)
def test_an_easy_scene_takes_fewer_substeps_than_a_stiff_one(method):
    for speed in (0.0, 2.0, 10.0):
        for tol in TOLS[method]:
            easy = predicted_substeps(preset("solid_disc"), speed, DT, tol, method)
            for stiff in ("tight_fit", "rim_mass"):
                hard = predicted_substeps(preset(stiff), speed, DT, tol, method)
                assert easy < hard or hard == integrators.MAX_SUBSTEPS == easy, (stiff, tol)
    # and the steps actually taken from rest:
    loose = TOLS[method][-1]
    easy = step(preset("solid_disc"), 0.3, 0.0, 0.0, DT, integrator=method, tolerance=loose)
    hard = step(preset("tight_fit"), 0.003, 0.0, 0.0, DT, integrator=method, tolerance=loose)
    assert easy.substeps < hard.substeps


@pytest.mark.parametrize("method", SUBSTEPPED)
def test_substeps_grow_with_speed_and_with_tighter_tol(method):
    """The rule is monotone: never fewer substeps for a faster roller or a tighter tol, up to
    MAX_SUBSTEPS — including absurd speeds, where it must ask for the most, not the fewest."""
    scene = preset("paper")
    speeds = np.array([0.0, 1.0, 10.0, 1e2, 1e4, 1e6, 1e10, 1e20, 1e100, 1e300])
    counts = predicted_substeps(scene, speeds, DT, 1e-6, method)
    assert np.all(np.diff(counts) >= 0), counts
    assert counts[-1] == integrators.MAX_SUBSTEPS
    by_tol = [predicted_substeps(scene, 5.0, DT, tol, method) for tol in (1e-3, 1e-6, 1e-9)]
    assert by_tol == sorted(by_tol)


def test_step_rejects_bad_arguments():
    scene = preset("paper")
    with pytest.raises(ValueError, match=r"dt=0\.0"):
        step(scene, 0.0, 0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="tolerance=-1"):
        step(scene, 0.0, 0.0, 0.0, DT, tolerance=-1e-9)
    with pytest.raises(ValueError, match="substeps=0"):
        step(scene, 0.0, 0.0, 0.0, DT, substeps=0)
    with pytest.raises(ValueError, match="'leapfrog'"):
        step(scene, 0.0, 0.0, 0.0, DT, integrator="leapfrog")
    with pytest.raises(ValueError, match="dop853"):
        predicted_substeps(scene, 0.0, DT, 1e-9, "dop853")


# -- the concentric path ------------------------------------------------------------------------


@pytest.mark.parametrize("method", SUBSTEPPED)
def test_concentric_roller_agrees_with_the_general_equation(method):
    """e = 0 takes accel_concentric; e = 1e-300 (the same roller to every digit) takes the
    general accel. Same substeps, same state to 1e-14; and e = 0 is within tol of DOP853.

    (Both states are in motion. Semi-implicit Euler started from rest under a torque on a
    concentric roller on the floor misses tol ~10×: its substep rule sees no frequency and no
    speed there, while its error ½ φ'' h dt grows with the drive's φ'' = τ/J_I.)"""
    tol = TOLS[method][-1]
    for base in ("solid_disc", "floor", "drum"):
        concentric = preset(base).replace(e=0.0, damping=0.02)
        general = concentric.replace(e=1e-300)
        for state in ((0.4, 1.5, 0.2), (-2.0, -4.0, -0.3)):
            a = step(concentric, *state, DT, integrator=method, tolerance=tol)
            b = step(general, *state, DT, integrator=method, tolerance=tol)
            assert a.substeps == b.substeps
            assert abs(a.phi - b.phi) <= 1e-14 * (1 + abs(a.phi))
            assert abs(a.phi_dot - b.phi_dot) <= 1e-14 * (1 + abs(a.phi_dot))
            assert error(a, reference(concentric, *state)) <= tol


# -- batches --------------------------------------------------------------------------------


@pytest.mark.parametrize("method", SUBSTEPPED)
def test_batch_step_equals_single_steps_exactly(method):
    """A batch of rollers of every preset gives bit for bit what each roller gives alone."""
    scenes = list(PRESETS.values()) * 3
    batch = Scene.stack(scenes)
    rng = np.random.default_rng(5)
    states = [meaningful_states(s, rng, 1)[0] for s in scenes]
    phi, w, tau = (np.array(x) for x in zip(*states, strict=True))
    tol = TOLS[method][0]
    out = step(batch, phi, w, tau, DT, integrator=method, tolerance=tol)
    for i, scene in enumerate(scenes):
        one = step(scene, phi[i], w[i], tau[i], DT, integrator=method, tolerance=tol)
        for field in ("phi", "phi_dot", "phi_ddot", "substeps", "finite", "energy",
                      "normal_force", "friction_force", "liftoff_margin", "slip_margin",
                      "error_estimate", "tol_met"):
            a, b = getattr(out, field)[i], getattr(one, field)
            assert a == b or (math.isnan(a) and math.isnan(b)), (field, i)


def test_large_parallel_batch_equals_single_steps_exactly():
    """A batch above PARALLEL_THRESHOLD (run on all cores) equals the rollers one at a time."""
    n = integrators.PARALLEL_THRESHOLD + 37
    rng = np.random.default_rng(6)
    scene = Scene(m=rng.uniform(0.5, 2, n), e=rng.uniform(0, 0.08, n),
                  k=rng.uniform(0.03, 0.08, n), R=rng.choice([0.3, 1.0, math.inf, -0.5], n))
    phi, w, tau = rng.uniform(-1, 1, n), rng.uniform(-3, 3, n), rng.uniform(-0.3, 0.3, n)
    out = step(scene, phi, w, tau, DT, tolerance=1e-7)
    for i in rng.choice(n, 200, replace=False):
        one = step(scene.item(i), phi[i], w[i], tau[i], DT, tolerance=1e-7)
        assert out.phi[i] == one.phi and out.phi_dot[i] == one.phi_dot
        assert out.substeps[i] == one.substeps


def test_batch_broadcasts_and_scalars_stay_scalars():
    scene = preset("paper")
    one = step(scene, 0.2, 0.0, 0.1, DT)
    assert isinstance(one.phi, float) and isinstance(one.substeps, int)
    assert isinstance(one.finite, bool)
    grid = step(scene, np.full((2, 3), 0.2), 0.0, np.array([0.1, 0.1, 0.1]), DT)
    assert grid.phi.shape == (2, 3)
    np.testing.assert_array_equal(grid.phi, one.phi)


def test_dop853_batch_matches_single_references():
    """DOP853 integrates a batch as one system (shared steps): within 1e-10 of each alone."""
    scenes = list(PRESETS.values())
    batch = Scene.stack(scenes)
    phi = np.linspace(-0.5, 0.5, len(scenes))
    out = step(batch, phi, 1.0, 0.1, DT, integrator="dop853", tolerance=1e-13)
    for i, scene in enumerate(scenes):
        ref = reference(scene, phi[i], 1.0, 0.1)
        assert abs(out.phi[i] - ref[0]) <= 1e-10 and abs(out.phi_dot[i] - ref[1]) <= 1e-10


def test_pickled_batch_stepper_keeps_its_padded_rows_and_its_steps():
    """A BatchStepper of a power-of-two batch, pickled and loaded: its table's rows are
    padded again (``row_table``), and it takes the same step as the original."""
    import pickle

    stepper = integrators.BatchStepper(4096, dt=DT, tolerance=1e-8)
    stepper.set_scenes(preset("paper"))
    phi, w = np.linspace(-1, 1, 4096), np.linspace(2, -2, 4096)
    stepper.run(phi, w, 0.1 * w)  # a carried substep size to continue from
    copy = pickle.loads(pickle.dumps(stepper))
    assert copy._io.strides == stepper._io.strides == (8 * (4096 + integrators._PAD), 8)
    np.testing.assert_array_equal(copy.run(phi, w, 0.2 * phi), stepper.run(phi, w, 0.2 * phi))


# -- what a step reports besides the state ---------------------------------------------------------


@pytest.mark.parametrize("name", ["paper", "drum", "rim_mass"])
def test_step_reports_the_end_state_and_the_worst_margins(name):
    """φ'', N, F, E are those of analysis at the returned state; the lift-off and slip margins
    are the smallest met during the step: no larger than at the start or the end, no smaller
    than the minimum along the DOP853 trajectory (sampled densely) by more than 1e-6."""
    scene = preset(name)
    for state in meaningful_states(scene, np.random.default_rng(7), 4):
        out = step(scene, *state, DT, tolerance=1e-10)
        acc = analysis.acceleration(scene, out.phi, out.phi_dot, state[2])
        end = analysis.contact(scene, out.phi, out.phi_dot, state[2])
        start = analysis.contact(scene, state[0], state[1], state[2])
        assert out.phi_ddot == pytest.approx(acc, rel=1e-13, abs=1e-12)
        assert out.normal_force == pytest.approx(end.normal, rel=1e-13, abs=1e-12)
        assert out.friction_force == pytest.approx(end.friction, rel=1e-13, abs=1e-12)
        assert out.energy == pytest.approx(analysis.energy(scene, out.phi, out.phi_dot),
                                           rel=1e-13, abs=1e-15)
        sol = reference(scene, *state, dense=True)
        phi, w = sol.sol(np.linspace(0, DT, 4001))
        along = analysis.contact(scene, phi, w, state[2])
        for field in ("liftoff_margin", "slip_margin"):
            got = getattr(out, field)
            assert got <= min(getattr(start, field), getattr(end, field)) + 1e-9
            assert got >= getattr(along, field).min() - 1e-6
        assert out.lifting == (out.liftoff_margin <= 0)
        assert out.slipping == (out.slip_margin < 0)


def test_contact_state_is_the_equations_at_the_states():
    """contact_state (compiled, one call) gives φ'', N, F, E and the margins of the equations
    evaluated by NumPy at the same states, on random scenes (a batch) and states; where the
    forces are undefined (a speed beyond float64's range) the margins are NaN, as the
    equations' own."""
    n = 300
    params, phi, w, tau = _adversarial_sample(n, 91)
    scene = Scene(m=params[0], r=params[1], R=params[2], e=params[3], k=params[4],
                  damping=params[6])
    w[:3] = (1e300, -1e300, np.inf)
    got = integrators.contact_state(scene, phi, w, tau)
    with np.errstate(all="ignore"):
        a = eq.accel(phi, w, tau, *scene.params)
        normal, friction = eq.contact_forces(phi, w, a, *scene.params[:4], scene.g)
        want = (a, normal, friction, eq.energy(phi, w, *scene.params[:6]),
                *eq.margins(normal, friction, scene.m, scene.g, scene.mu))
    for name, x, y in zip(integrators.CONTACT_FIELDS, got, want, strict=True):
        np.testing.assert_allclose(x, y, rtol=1e-9, atol=1e-12, err_msg=name)
    assert np.isnan(got[4:, :3]).all()


def test_contact_state_margins_where_both_forces_overflow_are_the_equations_nan():
    """On "paper" at φ' = 1.5e154 rad/s, N and F both overflow to +inf: μN − |F| is inf − inf,
    NaN in the equations, and so is the slip margin (not the inf the compiled loop starts
    from): a state with it never passes a "slip margin >= 0" check as rolling."""
    scene, phi, w = preset("paper"), 0.3, 1.5e154
    got = integrators.contact_state(scene, np.array([phi]), np.array([w]), 0.0)[:, 0]
    with np.errstate(all="ignore"):
        a = eq.accel(phi, w, 0.0, *scene.params)
        normal, friction = eq.contact_forces(phi, w, a, *scene.params[:4], scene.g)
        lift, slip = eq.margins(normal, friction, scene.m, scene.g, scene.mu)
    assert np.isposinf([normal, friction, got[1], got[2]]).all() and np.isnan(slip)
    np.testing.assert_array_equal(got[4:], [lift, slip])


def test_contact_state_refuses_mismatched_lengths():
    """A speed, torque or scene table of another length than φ is an error naming it, not a
    read past the end of an array."""
    scene, phi = preset("paper"), np.linspace(-0.3, 0.3, 6)
    with pytest.raises(ValueError, match="phi_dot"):
        integrators.contact_state(scene, phi, np.zeros(2), 0.0)
    with pytest.raises(ValueError, match="tau"):
        integrators.contact_state(scene, phi, np.zeros(6), np.zeros(5))
    with pytest.raises(ValueError, match="scene"):
        integrators.contact_state(integrators.scene_arrays(scene), phi, np.zeros(6), 0.0)
