"""The integrators' error control, measured: is a step within tol, and does it say so?

On the benchmark's adversarial sample, through spikes of φ'' and the dip of J_I, against
the smallest fixed count of substeps that meets tol (the cost), at tolerances below
float64's reach (tol_met False) and against the substep budget; the rk4 pair's tableau
against Butcher's order conditions; the scalar and batch steppers agree bit for bit. The
reference, the error and the random states are those of ``integrator_cases``.
"""

from __future__ import annotations

import functools
import itertools
import math
import warnings

import numpy as np
import pytest
from integrator_cases import DT, _adversarial_sample, error, reference
from roller_gym.bench.cost import smallest_fixed_counts
from roller_gym.physics import PRESETS, Scene, integrators, predicted_substeps, preset, step
from roller_gym.physics import equations as eq
from roller_gym.physics.taylor import DEGREES
from scipy.integrate import solve_ivp

# -- error control, measured --------------------------------------------------------------------


def _independent_rhs(m, r, R, e, k, g, c, tau):
    """φ'' of PHYSICS.md's closed form, typed here with cos θ and 1/R (not equations.py)."""
    kappa = np.where(np.isinf(R), 0.0, 1.0 / np.where(np.isinf(R), 1.0, R))
    s = 1 - r * kappa

    def f(_t, y):
        n = y.size // 2
        p, v = y[:n], y[n:]
        theta = p / s
        j = k * k + r * r + e * e - 2 * r * e * np.cos(theta)
        rhs = ((tau - c * v) / m - e * r / s * v * v * np.sin(theta)
               - g * (r * np.sin(r * kappa * theta) + e * np.sin(p)))
        return np.concatenate((v, rhs / j))

    return f


@functools.cache  # (about half a minute each: every test of a worker shares it)
def _with_references(seed: int):
    """500 control steps of the adversarial sample drawn from ``seed`` and their references,
    DOP853 at rtol = atol = 1e-13 and 1e-12 on the independent right-hand side, in groups of
    similar stiffness (sorted by predicted count)."""
    n = 500
    params, phi, w, tau = _adversarial_sample(n, seed)
    scene = Scene(m=params[0], r=params[1], R=params[2], e=params[3], k=params[4],
                  damping=params[6])
    order = np.argsort(predicted_substeps(scene, w, DT, 1e-8, "rk8"))
    refs = {}
    for rtol in (1e-13, 1e-12):
        out = np.empty((2, n))
        for group in np.array_split(order, 20):
            sub = [np.broadcast_to(x, (n,))[group] for x in params]
            f = _independent_rhs(*sub, tau[group])
            with np.errstate(all="ignore"):
                sol = solve_ivp(f, (0, DT), np.concatenate((phi[group], w[group])),
                                method="DOP853", rtol=rtol, atol=rtol)
            out[:, group] = sol.y[:, -1].reshape(2, -1)
        refs[rtol] = out
    uncertainty = np.abs(refs[1e-13] - refs[1e-12]).max(axis=0)
    return scene, phi, w, tau, refs[1e-13], uncertainty


@pytest.fixture(scope="module")
def adversarial():
    """The sample the error control was developed on (seed 2024), with references."""
    return _with_references(2024)


#: A sample no setting was tuned against: drawn from this seed once the settings were fixed.
FRESH_SEED = 20261127
#: (scheme, degree) of the error-controlled schemes, taylor at every degree, and their tols
CONTROLLED = [("rk8", None), ("rk4", None)] + [("taylor", d) for d in DEGREES]
CHECKED_TOLS = {"rk8": (1e-6, 1e-8), "rk4": (1e-6, 1e-8), "taylor": (0.3, 1e-4, 1e-6, 1e-8)}


@pytest.mark.parametrize(("method", "degree"), CONTROLLED)
def test_adversarial_steps_stay_within_tol(method, degree, adversarial):
    """On 500 random hard steps (references whose 1e-12 and 1e-13 runs differ by more than
    tol/10 skipped, and no other), at CHECKED_TOLS (taylor at each degree): every step is
    finite, its error <= tol in >= 99.9 % of them and <= 2 tol in all (taylor: <= tol in all),
    tol_met or not; at most 2 % report tol_met False (the carried estimate not verifying)."""
    scene, phi, w, tau, ref, uncertainty = adversarial
    for tol in CHECKED_TOLS[method]:
        out = step(scene, phi, w, tau, DT, integrator=method, tolerance=tol, degree=degree)
        err = np.maximum(np.abs(out.phi - ref[0]), np.abs(out.phi_dot - ref[1]))
        checked = uncertainty <= tol / 10
        assert checked.sum() >= 450, checked.sum()
        assert out.finite[checked].all()
        ratio = err[checked] / tol
        assert np.mean(ratio <= 1) >= 0.999, np.sort(ratio)[-5:]
        assert ratio.max() <= (1 if method == "taylor" else 2), (tol, ratio.max())
        assert np.mean(~out.tol_met[checked]) <= 0.02, np.flatnonzero(checked & ~out.tol_met)


@pytest.mark.parametrize(("method", "degree"), CONTROLLED)
def test_tol_met_never_claims_a_step_twice_over_on_a_fresh_sample(method, degree):
    """On a fresh adversarial sample (FRESH_SEED, references as above), at CHECKED_TOLS: no
    step that reports tol_met is more than 2 tol off (taylor, at each degree: no step is more
    than tol off), and at most 2 % report False. (On earlier samples, before the carried
    estimate and the E3 limit, rk8 reported tol_met on steps 3.0, 5.8 and 7.0 tol off: a
    single substep whose blended estimate missed 60-fold, and two steps of thousands of
    substeps whose local errors grew 150-fold.)"""
    scene, phi, w, tau, ref, uncertainty = _with_references(FRESH_SEED)
    for tol in CHECKED_TOLS[method]:
        out = step(scene, phi, w, tau, DT, integrator=method, tolerance=tol, degree=degree)
        err = np.maximum(np.abs(out.phi - ref[0]), np.abs(out.phi_dot - ref[1]))
        checked = uncertainty <= tol / 10
        assert checked.sum() >= 450, checked.sum()
        claimed = checked & out.tol_met
        assert (err[claimed] <= 2 * tol).all(), (tol, np.flatnonzero(claimed & (err > 2 * tol)))
        assert method != "taylor" or (err[checked] <= tol).all(), (tol, degree, err.max() / tol)
        assert np.mean(~out.tol_met[checked]) <= 0.02, (tol, np.flatnonzero(checked & ~out.tol_met))


@pytest.mark.parametrize(("method", "tols"), [("midpoint", (1e-4,)), ("euler", (1e-3,))])
def test_fixed_schemes_claim_tol_met_only_where_their_check_confirms_it(method, tols):
    """euler and midpoint took tol_met from their prediction of the substeps alone, which
    undercounts on stiff scenes: midpoint claimed it on a step 37 tol off (g = 1e6). Their
    Richardson check (the same step in half as many substeps) now confirms it: on the fresh
    sample, no step that reports tol_met is more than 2 tol off, and on that step the
    estimate is within 10 % of the error against a taylor step at tol 1e-12."""
    scene, phi, w, tau, ref, uncertainty = _with_references(FRESH_SEED)
    for tol in tols:
        out = step(scene, phi, w, tau, DT, integrator=method, tolerance=tol)
        err = np.maximum(np.abs(out.phi - ref[0]), np.abs(out.phi_dot - ref[1]))
        claimed = (uncertainty <= tol / 10) & out.tol_met
        assert claimed.sum() >= 100, claimed.sum()
        assert (err[claimed] <= 2 * tol).all(), (tol, np.flatnonzero(claimed & (err > 2 * tol)))
    stiff = (Scene(g=1e6), 0.38126140102427764, 4.791366408038581, 0.887782526004016, DT)
    if method == "midpoint":
        out = step(*stiff, integrator=method, tolerance=1e-4)
        exact = step(*stiff, integrator="taylor", tolerance=1e-12)
        err = max(abs(out.phi - exact.phi), abs(out.phi_dot - exact.phi_dot))
        assert err > 10 * 1e-4 and not out.tol_met
        assert out.error_estimate == pytest.approx(err, rel=0.1)


#: Steps through a spike of φ'' (J_I near zero, passed at speed: φ' reached about 5,000 rad/s
#: in the first) whose substeps' shares of tol fall below float64's rounding of the state: one
#: of the test sample's (seed 2024, step 428) and one of the benchmark's (seed 1, step 135),
#: each at a tol its reference resolves.
SPIKES = {
    "seed 2024 step 428": (Scene(m=1.119179323603518, r=0.1477803870661366,
                                 R=0.15483102592879014, e=0.1452382818113869,
                                 k=0.0016083192682414954),
                           (-1.8779936109773632, 54.570750776068074, 0.3944251373021404), 1e-6),
    "seed 1 step 135": (Scene(m=1.124057612604869, r=0.163890275080937, R=0.16508904560258728,
                              e=0.15793657650361992, k=0.010130466646130803),
                        (1.2045298044117576, -6.15479035659489, -4.764265254482032), 1e-8),
}


@pytest.mark.parametrize("method", ["rk8", "rk4"])
@pytest.mark.parametrize("name", list(SPIKES))
def test_spikes_of_phi_ddot_stay_within_tol_and_budget(name, method):
    """Through a spike the controller aims at float64's rounding where that is above a
    substep's share, instead of shrinking its substeps on to the smallest size (which spent
    rk8's whole budget of substeps: the first step ended non-finite, the second 16 tol off):
    the step is finite, is within tol of DOP853 and leaves most of the budget (measured: rk8
    17727 and 12054 substeps, rk4 52757 and 41080). tol_met is what the estimates verify:
    through the first spike the carried estimate grows to 9–240 tol, where the error is
    0.002–0.013 tol, so it reports False (not verified); through the second, True."""
    scene, state, tol = SPIKES[name]
    ref = reference(scene, *state)
    out = step(scene, *state, DT, integrator=method, tolerance=tol)
    assert out.finite
    assert error(out, ref) <= tol
    assert out.substeps <= integrators.MAX_SUBSTEPS // 2, out.substeps


def _smallest_fixed_count(scene, state, tol, method="rk8", dt=DT):
    """The smallest count n of equal substeps whose error is within tol, by the benchmark's
    search (``roller_gym.bench.cost.smallest_fixed_counts``: doubling, then bisection)."""
    ref = reference(scene, *state, dt=dt)

    def meets(_index, counts):
        return np.array([error(step(scene, *state, dt, integrator=method, substeps=int(n)), ref)
                         <= tol for n in counts])

    (n,) = smallest_fixed_counts(meets, 1, most=2**17)
    assert n > 0  # some count up to 2**17 meets tol
    return int(n)


def test_smallest_fixed_count_is_the_least_count_meeting_tol():
    """On one step whose error falls with n (paper, rk4, tol 1e-10), the search gives the
    first count of a linear scan that meets tol."""
    scene, state, tol = preset("paper"), (0.7, 2.0, 0.3), 1e-10
    ref = reference(scene, *state)
    scan = next(n for n in range(1, 1000)
                if error(step(scene, *state, DT, integrator="rk4", substeps=n), ref) <= tol)
    assert scan > 8 and scan & (scan - 1)  # not a power of two: the bisection is exercised
    assert _smallest_fixed_count(scene, state, tol, method="rk4") == scan


@pytest.mark.parametrize("method", ["taylor", "rk8"])
def test_tiny_k_rim_scene_takes_about_as_few_substeps_as_needed(method):
    """The mass at the rim with k = 0.0023 m (the rule of the scene's worst point asked 8094
    substeps): at most 4× the smallest fixed count that meets tol, and within tol (measured:
    taylor 10 against 13, rk8 24 against 7)."""
    scene = Scene(m=1, r=0.15173229446914027, R=0.15273942844741803, e=0.15074605257455018,
                  k=0.0023095850796728754)
    state, tol = (-2.6465, 1.8617, 3.9163), 1e-9
    smallest = _smallest_fixed_count(scene, state, tol, method=method, dt=0.01)
    sub = step(scene, *state, 0.01, integrator=method, tolerance=tol)
    assert sub.substeps <= 4 * smallest, (sub.substeps, smallest)
    assert error(sub, reference(scene, *state, dt=0.01)) <= tol


#: The bound of each scheme's cost along rim_mass's trajectory: 2× for taylor and rk4; for
#: rk8 the 99th-percentile ceiling of the benchmark's cost target (4×), as for the tiny-k step
#: above. Measured: taylor 1.66×, rk4 0.90×, rk8 3.1× (per step 2.8-3.9×). rk8's error is
#: 1e-3 tol there: DOP853's blended estimate overstates its 8th-order solution's error
#: 200-4500× on this scene, and the alternatives measured (``docs/INTEGRATORS.md``, "What
#: rk8's error control costs") either kept 2.6× or more
#: here or let steps of the adversarial sample exceed tol.
RIM_MASS_COST_BOUND = {"taylor": 2.0, "rk4": 2.0, "rk8": 4.0}


@pytest.mark.parametrize("method", ["taylor", "rk4", "rk8"])
def test_rim_mass_cost_follows_its_trajectory(method):
    """rim_mass along its own trajectory (20 steps from a release at 0.02 rad, tol 1e-8),
    stepped as an environment steps (a Stepper, carrying its substep size from one step to
    the next where the scheme does): each step within tol of the reference, and on average
    at most RIM_MASS_COST_BOUND times the smallest fixed count that meets tol at each step's
    start, in right-hand-side evaluations as the benchmark counts them (the rule of the
    scene's worst point took 7× with rk8)."""
    scene, tol = preset("rim_mass"), 1e-8
    scheme = integrators.scheme(method)
    stepper = integrators.Stepper(scene, integrator=method, dt=DT, tolerance=tol)
    state = (0.02, 0.0, 0.0)
    adaptive, smallest = [], []
    for _ in range(20):
        out = dict(zip(integrators.STEP_FIELDS, stepper.advance(*state), strict=True))
        assert out["finite"] and out["tol_met"]
        assert error(StepResultView(out), reference(scene, *state)) <= tol
        adaptive.append(out["substeps"] * scheme.evaluations(fixed=False))
        smallest.append(_smallest_fixed_count(scene, state, tol, method=method)
                        * scheme.evaluations(fixed=True))
        state = (out["phi"], out["phi_dot"], 0.0)
    bound = RIM_MASS_COST_BOUND[method]
    assert np.mean(adaptive) <= bound * np.mean(smallest), (adaptive, smallest)


def test_euler_past_its_substep_cap_reports_the_tolerance_unmet():
    """Semi-implicit Euler at tol 1e-8 on "paper" would need more than MAX_SUBSTEPS
    substeps: it takes that many, and its error against DOP853, over tol, is reported as
    tol_met=False with a warning (the same step at tol 1e-4 is within its prediction)."""
    scene, state = preset("paper"), (0.5, 2.0, 0.3)
    stepper = integrators.Stepper(scene, integrator="euler", dt=DT, tolerance=1e-8)
    with pytest.warns(RuntimeWarning, match="of the 200000 substeps a step may take"):
        out = dict(zip(integrators.STEP_FIELDS, stepper.advance(*state), strict=True))
    assert out["substeps"] == integrators.MAX_SUBSTEPS == 200_000
    assert out["finite"] and not out["tol_met"]
    assert error(StepResultView(out), reference(scene, *state)) > 1e-8
    loose = step(scene, *state, DT, integrator="euler", tolerance=1e-4)
    assert loose.tol_met and loose.substeps < integrators.MAX_SUBSTEPS


def test_unreachable_tolerance_is_flagged_and_warned_not_looped():
    """tol = 1e-16 cannot be met in float64 at |φ| ~ 1: the step ends (at most
    2·MAX_SUBSTEPS substeps), reports tol_met=False, and the Stepper warns once."""
    scene = preset("tight_fit")
    stepper = integrators.Stepper(scene, dt=DT, tolerance=1e-16)
    with pytest.warns(RuntimeWarning, match="tolerance=1e-16"):
        out = stepper.advance(1.0, 3.0, 0.0)
    fields = dict(zip(integrators.STEP_FIELDS, out, strict=True))
    assert fields["finite"] and not fields["tol_met"]
    assert fields["substeps"] <= 2 * integrators.MAX_SUBSTEPS
    assert error(StepResultView(fields), reference(scene, 1.0, 3.0, 0.0)) <= 1e-9


class StepResultView:
    def __init__(self, fields):
        self.phi, self.phi_dot = fields["phi"], fields["phi_dot"]


@pytest.mark.parametrize(("method", "substeps"), [("rk8", None), ("rk4", None), ("rk8", 2),
                                                 ("rk4", 3), ("taylor", None), ("taylor", 2),
                                                 ("euler", None), ("midpoint", None)])
def test_scalar_and_batch_steppers_agree_bit_for_bit(method, substeps):
    """The Stepper (one roller, its own compiled path) and the BatchStepper (a batch above
    PARALLEL_THRESHOLD, run on all cores, for rk8 and taylor; a small one otherwise) give ==
    on every field, random scenes and states, over three steps in a row (the error control's
    substep size carried from one step to the next)."""
    big = method in ("rk8", "taylor") and not substeps
    n = integrators.PARALLEL_THRESHOLD + 5 if big else 40
    params, phi, w, tau = _adversarial_sample(n, 77)
    scene = Scene(m=params[0], r=params[1], R=params[2], e=params[3], k=params[4],
                  damping=params[6])
    phi, w, tau = phi, w / 10, tau / 10  # keep the low-order schemes' counts moderate
    batch = integrators.BatchStepper(n, integrator=method, dt=DT, tolerance=1e-5, substeps=substeps)
    batch.set_scenes(scene)
    picks = np.random.default_rng(1).choice(n, 25, replace=False)
    ones = {int(i): integrators.Stepper(scene.item(int(i)), integrator=method, dt=DT,
                                        tolerance=1e-5, substeps=substeps) for i in picks}
    states = {i: (float(phi[i]), float(w[i])) for i in ones}
    for _ in range(3):
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            out = batch.advance(phi, w, tau)
            for i, one in ones.items():
                got = one.advance(*states[i], float(tau[i]))
                for name, value in zip(integrators.STEP_FIELDS, got, strict=True):
                    b = getattr(out, name)[i]
                    assert value == b or (math.isnan(value) and math.isnan(b)), (name, i)
                states[i] = got[0], got[1]
        phi, w = out.phi, out.phi_dot


def _rooted_trees(order: int) -> list[tuple]:
    """The rooted trees with ``order`` nodes, each as the sorted tuple of its root's subtrees
    (Butcher's trees: one order condition each)."""
    if order == 1:
        return [()]

    def partitions(n: int, largest: int):
        if n == 0:
            yield []
        for part in range(min(n, largest), 0, -1):
            for rest in partitions(n - part, part):
                yield [part, *rest]

    found = set()
    for sizes in partitions(order - 1, order - 1):
        for children in itertools.product(*(_rooted_trees(k) for k in sizes)):
            found.add(tuple(sorted(children)))
    return sorted(found)


def _order_defect(a: np.ndarray, b: np.ndarray, order: int) -> float:
    """The largest |b·Φ(t) − 1/γ(t)| over the trees t of up to ``order`` nodes: 0 (to
    rounding) where the weights ``b`` over the stages of matrix ``a`` reach that order."""

    def stage_weights(tree: tuple) -> np.ndarray:  # Φ(t) at every stage
        out = np.ones(a.shape[0])
        for child in tree:
            out = out * (a @ stage_weights(child))
        return out

    def density(tree: tuple) -> int:  # γ(t)
        return _tree_size(tree) * math.prod(density(child) for child in tree)

    return max(abs(b @ stage_weights(t) - 1.0 / density(t))
               for q in range(1, order + 1) for t in _rooted_trees(q))


def _tree_size(tree: tuple) -> int:
    return 1 + sum(_tree_size(child) for child in tree)


def test_rooted_trees_are_counted_as_known():
    """1, 1, 2, 4, 9, 20 trees of 1..6 nodes (OEIS A000081): 17 order conditions to order 5."""
    assert [len(_rooted_trees(q)) for q in range(1, 7)] == [1, 1, 2, 4, 9, 20]
    # the classical RK4 meets the 8 conditions of order 4 and not all 9 of order 5
    tab = integrators.SCHEMES["rk4"].fixed_tableau
    a, b = tab[:4, :4], tab[4, :4]
    assert _order_defect(a, b, 4) < 1e-15 < 1e-3 < _order_defect(a, b, 5)


def test_rk4_error_control_is_a_5_4_pair_step():
    """rk4 under error control takes substeps of its pair (Bogacki–Shampine 5(4)): its
    weights meet all 17 order conditions of order 5 (Butcher's rooted trees, written out
    here) and not those of order 6; the embedded weights b̂ = b + E are the paper's and meet
    those of order 4 and not of order 5.
    One substep of the kernel is the explicit Runge–Kutta step of that tableau computed here
    with NumPy, and its error estimate is max |h E·K| over φ and φ'."""
    tab = integrators.SCHEMES["rk4"].tableau
    s = tab.shape[0] - 3
    a = np.zeros((s + 1, s + 1))
    a[:, :s] = tab[: s + 1, :s]  # the last stage is at the new state: its row is b
    b = np.append(tab[s, :s], 0.0)
    embedded = b + tab[s + 2]  # E = b̂ − b
    # b̂ as the paper gives it (any b + λE meets order 4: this fixes E's sign and scale)
    paper = [2479 / 34992, 0, 123 / 416, 612941 / 3411720, 43 / 1440, 2272 / 6561,
             79937 / 1113912, 3293 / 556956]
    np.testing.assert_allclose(embedded, paper, rtol=1e-14, atol=1e-16)
    assert _order_defect(a, b, 5) < 1e-13 < 1e-5 < _order_defect(a, b, 6)
    assert _order_defect(a, embedded, 4) < 1e-13 < 1e-5 < _order_defect(a, embedded, 5)

    scene, (phi, w, tau) = preset("paper"), (0.7, 2.0, 0.3)
    params = scene.params

    def f(y: np.ndarray) -> np.ndarray:
        return np.array([y[1], eq.accel(y[0], y[1], tau, *params)])

    y0, k = np.array([phi, w]), np.zeros((s + 1, 2))
    for i in range(s + 1):
        k[i] = f(y0 + DT * a[i] @ k)
    y1 = y0 + DT * b @ k
    one = integrators.Stepper(scene, integrator="rk4", dt=DT, tolerance=1e-8, substeps=1)
    one._tab = tab  # one substep of the error-control pair
    out = integrators.StepResult(*one.advance(phi, w, tau))
    assert out.phi == pytest.approx(y1[0], rel=1e-14)
    assert out.phi_dot == pytest.approx(y1[1], rel=1e-14)
    assert out.error_estimate == pytest.approx(np.max(np.abs(DT * tab[s + 2] @ k)), rel=1e-9)
    classical = step(scene, phi, w, tau, DT, integrator="rk4", substeps=1)  # fixed substeps
    assert abs(classical.phi - out.phi) > 1e3 * abs(out.phi) * 1e-16


@pytest.fixture(scope="module")
def rim_mass_dip():
    """600 random steps of "rim_mass" (dt 0.02 s, |φ'| up to 60 rad/s, |τ| up to m g r), many
    through the dip of J_I, where the end state is up to 1e5 times as sensitive to an error
    early in the step, and their references (DOP853 at 1e-13, and how far its 1e-12 run
    ends from it)."""
    scene = preset("rim_mass")
    rng = np.random.default_rng(5)
    n, dt = 600, 0.02
    phi, w = rng.uniform(-4, 4, n), rng.uniform(-60, 60, n)
    tau = rng.uniform(-1, 1, n) * scene.m * scene.g * scene.r
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        ref = step(scene, phi, w, tau, dt, integrator="dop853", tolerance=1e-13)
        ref12 = step(scene, phi, w, tau, dt, integrator="dop853", tolerance=1e-12)
    uncertainty = np.maximum(np.abs(ref.phi - ref12.phi), np.abs(ref.phi_dot - ref12.phi_dot))
    return scene, (phi, w, tau, dt), ref, uncertainty


def _dip_errors(rim_mass_dip, method, tol):
    """(error [rad or rad/s] of each step, steps whose reference resolves tol, the steps)."""
    scene, (phi, w, tau, dt), ref, uncertainty = rim_mass_dip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        out = step(scene, phi, w, tau, dt, integrator=method, tolerance=tol)
    err = np.maximum(np.abs(out.phi - ref.phi), np.abs(out.phi_dot - ref.phi_dot))
    return err, uncertainty <= tol / 10, out


def test_taylor_stays_within_tol_through_the_dip_of_j_i(rim_mass_dip):
    """On the dip's 600 steps (references that do not resolve tol/10 skipped), taylor's
    estimates cannot see the error's growth; its tol_share (0.01) leaves room for it: every
    step is within tol at 1e-5, 1e-7 and 1e-9 (measured at most 0.53 tol; at tol_share 0.3
    it was 13 tol), and at most 0.5 % report tol_met False: the reruns of a rounding-bound
    step see the error (measured: one step at 1e-7, 0.28 tol off, over tol / SHADOW_MARGIN
    from its rerun)."""
    for tol in (1e-5, 1e-7, 1e-9):
        err, checked, out = _dip_errors(rim_mass_dip, "taylor", tol)
        assert checked.sum() >= 450, (tol, checked.sum())
        assert np.mean(~out.tol_met[checked]) <= 0.005, (tol, np.flatnonzero(~out.tol_met))
        assert err[checked].max() <= tol, (tol, err[checked].max() / tol)


@pytest.mark.parametrize("method", ["rk8", "rk4"])
def test_the_pairs_through_the_dip_of_j_i_miss_rarely(rim_mass_dip, method):
    """The Runge–Kutta pairs on the dip's steps, a known limit of their estimates (README):
    every step finite, at least 99.5 % within tol and none past 10 tol, at 1e-5, 1e-7 and
    1e-9 (measured: rk8 one step at 2.8 tol and one at 1.3; rk4 two at up to 6.3 tol and
    one at 1.4; all others within tol)."""
    for tol in (1e-5, 1e-7, 1e-9):
        err, checked, out = _dip_errors(rim_mass_dip, method, tol)
        assert out.finite.all()
        ratio = err[checked] / tol
        assert np.mean(ratio <= 1) >= 0.995, (tol, np.sort(ratio)[-4:])
        assert ratio.max() <= 10, (tol, ratio.max())


@pytest.mark.parametrize("method", ["taylor", "rk8"])
def test_a_tolerance_below_rounding_is_reported_out_of_reach(method):
    """tol = 1e-20 at φ' = 3 rad/s (the spacing of float64 there is 4.4e-16): tol_met False,
    and the state still within rounding of the reference."""
    scene, state = preset("paper"), (1.0, 3.0, 0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        out = step(scene, *state, 0.01, integrator=method, tolerance=1e-20)
    assert out.finite and not out.tol_met
    assert error(out, reference(scene, *state, dt=0.01)) <= 1e-10


def test_dop853_reports_tol_met_only_where_scipy_kept_the_tolerance():
    """scipy raises an rtol below 100 ε to 100 ε (and warns); the step then reports
    tol_met=False, as every other scheme does at a tolerance float64 cannot reach."""
    scene = PRESETS["paper"]
    for tol, kept in ((1e-8, True), (1e-15, False)):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            out = step(scene, 0.3, 0.5, 0.1, DT, integrator="dop853", tolerance=tol)
        loosened = any("rtol" in str(w.message) for w in caught)
        assert loosened == (not kept)  # scipy's own account of what it did
        assert out.finite and bool(out.tol_met) == kept
        others = step(scene, 0.3, 0.5, 0.1, DT, integrator="rk8", tolerance=tol)
        assert bool(others.tol_met) == kept


def test_a_carried_substep_size_never_fails_a_step_that_a_fresh_one_passes():
    """rk8 carries its proposed substep size to the next step; on a state it did not step
    to, a first trial that overflows is rejected and shrunk (it ended the step non-finite,
    with 0 substeps), and the step ends as the same step from a fresh stepper does. rk4
    carries one too; taylor carries none (its size comes from the expansion at the state)."""
    scene = PRESETS["rim_mass"]
    first = (2.939902186110369, 4.969354228348603, -0.04551300450597362)
    second = (0.03250393038817867, 2.83564580148128, 0.22713056202077542)
    fresh = integrators.Stepper(scene, integrator="rk8", dt=0.05, tolerance=1e-6)
    expected = fresh.advance(*second)
    ref = reference(scene, *second[:2], second[2])
    assert expected[4] and max(abs(expected[0] - ref[0]), abs(expected[1] - ref[1])) <= 1e-6
    for method in ("rk8", "rk4", "taylor"):
        rng = np.random.default_rng(5)
        stepper = integrators.Stepper(scene, integrator=method, dt=0.05, tolerance=1e-6)
        states = [first, second] + [(rng.uniform(-6, 6), rng.uniform(-8, 8),
                                     rng.uniform(-0.3, 0.3)) for _ in range(30)]
        for state in states:
            carried = stepper.advance(*state)  # after a step to somewhere else
            stepper.forget()
            anew = stepper.advance(*state)
            if anew[4]:
                assert carried[4], (method, state)  # finite
            if anew[4] and anew[11]:
                assert carried[11], (method, state)  # tol_met
            stepper.advance(*states[0])  # leaves a carried size for the next


@pytest.mark.parametrize("method", ["taylor", "rk8", "rk4"])
@pytest.mark.parametrize("case", ["tolerance 1e-300", "R = 0.1000001"])
def test_no_step_takes_more_substeps_than_the_documented_budget(method, case):
    """MAX_SUBSTEPS (200,000) is the most a step takes, even where the tolerance is out of
    reach (it took 400,001 at tol 1e-300 and 385,786 at R = 1.000001 r)."""
    scene, tol = ((PRESETS["paper"], 1e-300) if case == "tolerance 1e-300" else
                  (Scene(R=0.1000001), 1e-8))
    out = step(scene, 0.4, 1.0, 0.2, DT, integrator=method, tolerance=tol)
    assert out.substeps <= integrators.MAX_SUBSTEPS
    assert out.finite


@pytest.mark.parametrize("method", ["rk4", "rk8"])
def test_loose_tolerances_on_a_tight_fit_claim_no_step_they_miss(method):
    """tight_fit sweeps θ = φ/s about 100× faster than φ: at loose tolerances the controller
    grew its substeps past the scheme's stable step, where the embedded estimate missed the
    error up to 16-fold and tol_met still claimed the step (rk4, tol 1e-2: error 0.16 at the
    first state below). Every substep is now at most stable_step / λ: on 300 random rolling
    states at tol 1e-1 to 1e-3, no step that reports tol_met is off by more than tol, against
    DOP853 at rtol = atol = 1e-12 on the independent right-hand side."""
    scene = PRESETS["tight_fit"]
    rng = np.random.default_rng(20261127)
    n = 300
    phi = np.concatenate(([-2.0526113769241086], rng.uniform(-np.pi, np.pi, n - 1)))
    w = np.concatenate(([5.443725526868146], rng.uniform(-10, 10, n - 1)))
    tau = np.concatenate(([-0.10538505069704085], rng.uniform(-0.5, 0.5, n - 1)))
    f = _independent_rhs(*(np.full(n, v) for v in (scene.m, scene.r, scene.R, scene.e,
                                                   scene.k, scene.g, scene.damping)), tau)
    sol = solve_ivp(f, (0, DT), np.concatenate((phi, w)), method="DOP853", rtol=1e-12,
                    atol=1e-12)
    ref = sol.y[:, -1].reshape(2, n)
    for tol in (1e-1, 1e-2, 1e-3):
        out = step(scene, phi, w, tau, DT, integrator=method, tolerance=tol)
        err = np.maximum(np.abs(out.phi - ref[0]), np.abs(out.phi_dot - ref[1]))
        claimed = out.tol_met & out.finite
        assert claimed.sum() >= 50, claimed.sum()  # (the rest lift off or slip)
        assert (err[claimed] <= tol).all(), (tol, np.flatnonzero(claimed & (err > tol)))


@pytest.mark.parametrize("method", ["rk4", "rk8"])
def test_fixed_substeps_claim_tol_only_within_the_stable_step(method):
    """With fixed substeps the estimate (classical RK4 against its embedded 3rd order; DOP853's
    blend) was reported as verified even on substeps far past the scheme's stable step, where
    it missed the error up to 650-fold (paper, rk4, one substep: error 2.0e-3 at tol 1e-3,
    estimate 3.1e-6). Such a step now reports tol_met False: on 200 random states of each of
    three scenes at 1, 2 and 5 substeps, no step that claims tol is off by more than tol,
    against DOP853 at rtol = atol = 1e-12 on the independent right-hand side."""
    rng = np.random.default_rng(6)
    n, claimed_total = 200, 0
    for name in ("paper", "rim_mass", "tight_fit"):
        scene = PRESETS[name]
        phi, w = rng.uniform(-np.pi, np.pi, n), rng.uniform(-8, 8, n)
        tau = rng.uniform(-1, 1, n) * scene.m * scene.g * scene.r / 2
        if name == "paper":
            phi[0], w[0], tau[0] = 0.3663767818801187, 7.44045441077882, -0.9487961352590799
        f = _independent_rhs(*(np.full(n, v) for v in (scene.m, scene.r, scene.R, scene.e,
                                                       scene.k, scene.g, scene.damping)), tau)
        sol = solve_ivp(f, (0, DT), np.concatenate((phi, w)), method="DOP853", rtol=1e-12,
                        atol=1e-12)
        ref = sol.y[:, -1].reshape(2, n)
        for substeps, tol in itertools.product((1, 2, 5), (1e-3, 1e-5)):
            out = step(scene, phi, w, tau, DT, integrator=method, tolerance=tol,
                       substeps=substeps)
            err = np.maximum(np.abs(out.phi - ref[0]), np.abs(out.phi_dot - ref[1]))
            claimed = out.tol_met & out.finite
            claimed_total += int(claimed.sum())
            assert (err[claimed] <= tol).all(), (name, substeps, tol,
                                                 np.flatnonzero(claimed & (err > tol)))
    assert claimed_total >= 500  # (claims remain where the substeps are short enough)
