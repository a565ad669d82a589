"""Integration over one control step of constant torque.

**Schemes.** One table, :data:`SCHEMES`, one row per scheme:

==============  =====  ========  ==================================================================
name            order  control   what it is for
==============  =====  ========  ==================================================================
``"taylor"``    18     adaptive  the default everywhere: the Taylor series of the motion to degree
                                 18 (:mod:`roller_gym.physics.taylor`), compiled; each substep's
                                 size is chosen from its own last terms after expanding, so no
                                 substep is rejected, and the sines are evaluated once a substep
``"rk8"``       8      adaptive  Dormand–Prince 8(5,3) (scipy's DOP853 tableau), compiled, with its
                                 embedded 5th- and 3rd-order error estimators and a step-size
                                 controller per roller (rejected substeps are taken again)
``"rk4"``       4      adaptive  Runge–Kutta of order 4: under error control the
                                 Bogacki–Shampine 5(4) pair (7 evaluations a substep: the
                                 estimate is of its embedded 4th-order solution's error, the
                                 5th-order solution is carried on, as in scipy's RK45 and
                                 MATLAB's ode45 with the Dormand–Prince pair);
                                 ``substeps=n``: n classical RK4 steps of 4 evaluations
``"euler"``     1      fixed     semi-implicit (symplectic) Euler, the scheme of Gymnasium's
                                 Pendulum: kept to show its error (J_I depends on φ, so it is
                                 not symplectic here and drifts in energy)
``"midpoint"``  2      fixed     implicit midpoint on the canonical pair (φ, p = J_I φ'), solved
                                 by Newton's method: symplectic, its energy error stays bounded
                                 over long horizons at zero torque
``"dop853"``    8      adaptive  scipy's ``solve_ivp(method="DOP853")``: the reference (slow)
==============  =====  ========  ==================================================================

**Error control (taylor).** A substep expands the motion at its start to degree p = 18 and
takes the largest size h whose last two terms, t₁ h^(p−1) and t₂ hᵖ (t the larger of |φ|'s
and |φ'|'s coefficient), are each within ``tol_share · tol · h / dt`` (two terms, because one
coefficient can vanish by accident): the estimates of a control step's substeps add up to at
most its share of ``tol``, as for the Runge–Kutta pairs below, and no substep is taken twice.
The size goes as the 16th root of the allowance, so even a tolerance far below float64's reach
costs only a few more substeps; the rounding the substeps add (``TAYLOR_ROUNDING · ε ·
max(|φ|, |φ'|)`` each) is summed, and where it passes ``ROUNDING_SHARE · tol`` the step reports
the tolerance as out of reach (below).

**Error control (rk8, rk4).** Each roller's control step is a sequence of substeps whose sizes
follow its own trajectory: a substep of size h is accepted when its estimated local error
(max over |Δφ| [rad] and |Δφ'| [rad/s], estimated as scipy's DOP853 does) is at most
``tol · h / dt``, so that the errors of the accepted substeps add up to at most ``tol`` over
the control step. The next size is ``h · clip(0.9 (tol h/dt / err)^(1/8), 0.2, 10)``
(exponent 1/4 for rk4; no growth right after a rejection). A roller's control step starts with the
substep size the controller proposed at the end of its previous step (carried by the stepper,
:data:`CARRY_FIELDS`); after a reset (:meth:`Stepper.forget`) or a new scene, with the
prediction of :func:`predicted_substeps` (from the scene's fastest time scale). Either only
starts the controller: the error estimates decide.

**Cost of rk8's error control.** DOP853's blended estimate is of lower order than its
8th-order solution, so it overstates that solution's error, and by how much depends on the
scene: 200–4500× along ``rim_mass``'s trajectory at tol 1e-8, where rk8 takes 3.1× the
right-hand-side evaluations of the smallest fixed counts that meet tol (taylor 1.7×, rk4
0.9×), while on some steps of the tests' and the benchmark's hard samples the estimates add up
to less than the error (over the benchmark's sample rk8's cost is 1.8–2.0× in the median). Its
``tol_share`` (0.1) leaves room for those: a share of 0.3 (2.7× on ``rim_mass``) keeps the
samples within tol, at up to 0.99 tol; 1 (2.3×) lets 1–3 % of their steps end over tol, at up
to 2.5 tol, and 3 (2.0×) 1–4 %, at up to 58 tol. Sharper estimates were measured and not
adopted: step doubling (Richardson) costs 1.46× the evaluations and left 7 % of the hard steps
over tol at 1e-6; weighting each substep's estimate by its propagation to the step's end
overstates ``rim_mass``'s error more; a 9(8) pair carrying its 8th-order solution (1.5–2.0×
here) misses by 150× at a share of 0.03 where J_I dips, since its sharp local estimates do not
see the error grow along the step; and checking the whole step (n equal substeps against n/2)
took 2.6–3.1×, because the error of a fixed count there falls 1000× from 16 to 32 substeps and
not monotonically. Closing the gap would take a global error estimate (the variational
equation carried along the step). Where cost matters most, use taylor, the default.

**Unreachable tolerances** are reported per step, never looped on: a substep whose error
estimate is at the level of float64 rounding (``ROUNDOFF_FACTOR · ε · max(|φ|, |φ'|)``) is
accepted even if that exceeds its share of ``tol`` (no smaller substep would do better); a
substep's next size aims at the larger of its share and ε · max(|φ|, |φ'|), so that through
a spike of φ'' (J_I near zero), where the share of a substep small enough falls below
float64's rounding of the state, the substeps do not keep shrinking. After half of
``MAX_SUBSTEPS`` accepted substeps the rest of the control step is taken in fewer than as
many more, each accepted: no step takes more than ``MAX_SUBSTEPS``. A step whose accepted
substeps' estimates add up to more than ``tol_share · tol`` reports ``tol_met=False`` (its
tolerance was not verified); :class:`Stepper` and :class:`BatchStepper` then warn once (not
with fixed ``substeps``).
``error_estimate`` is the sum of the accepted substeps' error estimates. Measured on random
scenes, the estimates can miss part of the error (local errors also grow along the step), so
each scheme's estimates may add up to only ``tol_share · tol``.

**Fixed-substep schemes (euler, midpoint)** and taylor, rk8 and rk4 with ``substeps=n`` take n
equal substeps; for euler and midpoint n is, unless given, predicted from the scene's fastest time
scale and the speed at the start (taken again with more if the speed reached asks for more); a
step whose prediction asks for more than ``MAX_SUBSTEPS`` takes that many and reports
``tol_met=False`` (its tolerance is out of their reach).

**Adding a scheme.** A fixed-substep scheme is three pieces of this module: its substep,
``f(phi, w, tau, m, r, kappa, e, k, g, c, h) -> (phi, w)`` compiled with ``_jit`` (as
``_euler_substep``); its kernel, two lines around ``_fixed_steps`` (as ``_euler_kernel``, a
function of its own so that numba caches it); and its row of :data:`SCHEMES`
(``Scheme(name, order, stable_step, False, substep, kernel=kernel, constant=C)``).
``constant`` and ``stable_step`` set only the predicted count of substeps: too large costs
time, too small fails the tests' tolerances. An explicit Runge–Kutta pair is its
coefficients (:func:`_tableau`) and a row with ``tableau=``, ``halvings`` and ``tol_share``:
it runs in the shared pair kernels, and the single environment fuses its step with the
step's outcome in one compiled call, as for taylor (the other schemes take two calls).
``tests/test_integrators.py`` runs every row; give a new one its tolerances in ``TOLS`` and
its substep counts in ``test_observed_order_of_convergence``.

**Failure.** Where a step cannot stay finite, or ends with |φ| past ``trig.DOMAIN`` (2⁵⁰
rad, beyond which the sines are NaN: only a step that blew up gets there), ``finite`` is
False, φ and φ' are the state before the step, and ``phi_ddot``, ``normal_force``,
``friction_force``, ``energy``, both margins and ``error_estimate`` are NaN (so
``liftoff_margin <= 0`` is False: a failed step is
never reported as a lift-off).

**Margins.** The lift-off and slip margins are the smallest met at the start of every
accepted substep and at the end of the step. At the end, the contact forces take the sines
φ'' took (:func:`~roller_gym.physics.equations.angles`) and the energy its J_I/m; within a
Taylor substep, the margins take the expansion's.

**Batch kernel.** A batch is cut into chunks of ``CHUNK`` rollers, handed to the cores
(``numba.prange``) from ``PARALLEL_THRESHOLD`` rollers on. Within a chunk, the running rollers
advance together, each with its own (t, h): every stage is one loop over contiguous lanes, and
a roller that has finished swaps places with the last running one, so the loops shrink with
the work left. The loops that evaluate the equations (``_accel_lanes``, ``_margin_lanes``,
``_end_lanes``) and the three that accept or reject substeps have no branch and no call in
their bodies (the sines are :mod:`roller_gym.physics.trig`'s, inlined; choices are selects),
so LLVM runs them in SIMD lanes. Accepting is three loops rather than one because LLVM
vectorizes a loop only if the rows it touches need few pairwise overlap checks. The
per-roller rules of a substep (its size, accepting it, the next size, the clock) are
functions of their own, which the lane loops and the one-roller kernel both call. The kernels
are compiled with ``error_model="numpy"``: a division by zero gives inf or NaN, reported as a
failed step, instead of raising.

**One roller.** A batch of one (what :class:`Stepper` advances) runs ``_rk_one``: the same
arithmetic in the same order, without lanes, in about half the time the lanes take.

**The Taylor kernel** (``_taylor_chunk``, ``_taylor_one``) has the same structure: running
rollers in lanes that shrink, one loop over lanes per part of a substep. Its substep
(``_taylor_substep``: the expansion, the size, the polynomials' values, the margins at its
start from the sines the expansion took) is one function of
straight-line code that both kernels call, compiled once and inlined by LLVM
(``forceinline``); its lane loop reads one table and writes another, lane by lane, so that
LLVM needs a single overlap check to run a body that long in SIMD lanes.

**Layout.** The kernels work on one float64 table per batch, ``io`` of shape
``(len(ROWS), n)``: one row per name of :data:`ROWS` (the scene's :data:`SCENE_FIELDS`, the
inputs :data:`INPUT_FIELDS`, what is carried :data:`CARRY_FIELDS`, the outputs
:data:`STEP_FIELDS`), one column per roller, so a roller's numbers never depend on the other
columns: a roller's step is bit for bit the same alone and in any batch. A batch's table and
a chunk's scratch have rows a little longer than their rollers (:func:`row_table`), so that
rows are not a power of two apart in memory. A stepper's settings reach the kernels as one
float64 array, ``cfg``, in the order of :data:`CFG_FIELDS`.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import Any

import numba
import numpy as np
from roller_gym.physics import _taylor_series as series
from roller_gym.physics import equations as eq
from roller_gym.physics import trig
from roller_gym.physics.packed import pack
from roller_gym.physics.scene import Scene
from scipy.integrate import solve_ivp
from scipy.integrate._ivp import dop853_coefficients

__all__ = [
    "CARRY_FIELDS",
    "CONTACT_FIELDS",
    "INPUT_FIELDS",
    "METHODS",
    "ROWS",
    "SCENE_FIELDS",
    "SCHEMES",
    "STEP_FIELDS",
    "BatchStepper",
    "Scheme",
    "StepResult",
    "Stepper",
    "contact_state",
    "missed",
    "predicted_substeps",
    "put_inputs",
    "row_table",
    "scene_arrays",
    "step",
]

# error_model="numpy": a division by zero gives inf or NaN (reported as a failed step) instead
# of raising, so that the loops have no hidden branch and vectorize.
_jit = numba.njit(cache=True, fastmath=False, nogil=True, error_model="numpy")

# -- the layout, declared once ----------------------------------------------------------------

#: The per-roller scene numbers the kernels take, in the order of their rows.
SCENE_FIELDS = ("m", "r", "kappa", "e", "k", "g", "damping", "mu")
#: The per-roller inputs of a step: φ [rad], φ' [rad/s] at its start, τ [N·m].
INPUT_FIELDS = ("phi_in", "phi_dot_in", "tau")
#: What a stepper carries per roller from one step to the next: the substep size [s] the
#: controller proposed at the end of the last step, where the next one starts (0: none, the
#: first substep is predicted).
CARRY_FIELDS = ("h_next",)


@dataclass(frozen=True)
class StepResult:
    """The outcome of one control step, at its end unless said otherwise.

    Attributes:
        phi: φ [rad].
        phi_dot: φ' [rad/s].
        phi_ddot: φ'' [rad/s²] under the step's torque (NaN where not finite).
        substeps: accepted substeps (for ``"dop853"``, its accepted steps).
        finite: False where the step could not stay finite (or ended with |φ| past
            ``trig.DOMAIN``, 2⁵⁰ rad, where sines are NaN); there φ and φ' are the state
            before the step, unchanged, and every other float field is NaN.
        normal_force: N [N] (positive: pressing; see ``equations.contact_forces``).
        friction_force: F [N].
        energy: E [J].
        liftoff_margin: the smallest N/(m g) met during the step (<= 0: lift-off).
        slip_margin: the smallest (μN − |F|)/(m g) met during the step (< 0: slip).
        error_estimate: the sum of the accepted substeps' estimated errors
            (max of |Δφ| [rad], |Δφ'| [rad/s]); NaN for fixed schemes and DOP853.
        tol_met: False where the accepted substeps' error estimates add up to more than the
            scheme's share of ``tol`` (substeps accepted at float64 rounding or past the
            budget: the tolerance was out of reach and is not verified); for euler and
            midpoint, where the predicted substeps were more than ``MAX_SUBSTEPS``; for
            DOP853, where scipy failed or raised rtol = ``tol`` to its floor, 100 ε.
    """

    phi: np.ndarray | float
    phi_dot: np.ndarray | float
    phi_ddot: np.ndarray | float
    substeps: np.ndarray | int
    finite: np.ndarray | bool
    normal_force: np.ndarray | float
    friction_force: np.ndarray | float
    energy: np.ndarray | float
    liftoff_margin: np.ndarray | float
    slip_margin: np.ndarray | float
    error_estimate: np.ndarray | float
    tol_met: np.ndarray | bool

    @property
    def lifting(self) -> np.ndarray | bool:
        """True where the roller left the surface (N <= 0) during the step."""
        return self.liftoff_margin <= 0

    @property
    def slipping(self) -> np.ndarray | bool:
        """True where the friction needed exceeded μN during the step."""
        return self.slip_margin < 0


#: The fields of a step's outcome, in the order of :class:`StepResult`.
STEP_FIELDS = tuple(f.name for f in fields(StepResult))
#: The type of each field of one roller's result (the kernels store all as float64).
_KIND = {name: {"substeps": int, "finite": bool, "tol_met": bool}.get(name, float)
         for name in STEP_FIELDS}
#: The rows of a kernel's ``io`` table.
ROWS = SCENE_FIELDS + INPUT_FIELDS + CARRY_FIELDS + STEP_FIELDS
_ROW = {name: i for i, name in enumerate(ROWS)}
# Row numbers as compile-time constants of the kernels.
(_M, _RR, _KAPPA, _E, _K, _G, _C, _MU) = (_ROW[f] for f in SCENE_FIELDS)
(_PHI_IN, _W_IN, _TAU) = (_ROW[f] for f in INPUT_FIELDS)
_H_NEXT = _ROW["h_next"]
(_PHI, _W, _ACC, _NSUB, _FINITE, _NORMAL, _FRICTION, _ENERGY, _LIFT, _SLIP, _ERR,
 _TOL_MET) = (_ROW[f] for f in STEP_FIELDS)
_OUT = _PHI  # the outputs are the last rows, in STEP_FIELDS order
assert ROWS[_OUT:] == STEP_FIELDS
#: A stepper's settings, as the kernels read them from its float64 array ``cfg``: the control
#: step [s], ``tol``, the fixed substeps (0: automatic), and its scheme's controller halvings,
#: order, constant, stable step, sweep exponent and tol_share (:class:`Scheme`).
CFG_FIELDS = ("dt", "tol", "substeps", "halvings", "order", "constant", "stable_step",
              "sweep_exponent", "tol_share")
(_CF_DT, _CF_TOL, _CF_SUBSTEPS, _CF_HALVINGS, _CF_ORDER, _CF_CONSTANT, _CF_STABLE, _CF_SWEEP,
 _CF_SHARE) = range(len(CFG_FIELDS))


def scene_arrays(scene: Scene, n: int | None = None) -> np.ndarray:
    """The kernels' per-roller scene numbers: shape ``(len(SCENE_FIELDS), n)``, float64.

    A scalar scene is broadcast to ``n`` rollers (1 if ``n`` is None); a batch scene gives its
    rollers (``n`` must then be None or its size).
    """
    values = (*scene.params, scene.mu)  # the order of SCENE_FIELDS
    size = scene.batch_size
    if n is None:
        n = size or 1
    elif size is not None and size != n:
        raise ValueError(f"n={n} does not match the scene's batch size {size}")
    out = np.empty((len(SCENE_FIELDS), n))
    if size is None:
        out[...] = np.array(values, dtype=float)[:, None]
    else:
        for i, value in enumerate(values):
            out[i] = np.asarray(value, dtype=float).reshape(-1)  # broadcast if a scalar
    return out


# -- the substep rule (the first step-size guess of the adaptive schemes) ------------------------

#: The most substeps one control step may take: the fixed-substep schemes' (the smallest
#: substep is dt / MAX_SUBSTEPS), and the error-controlled schemes' budget (after half as
#: many accepted substeps, the rest of the control step is taken in fewer than as many more,
#: of at least its length over _FORCE_REST each, accepted whatever their estimates).
MAX_SUBSTEPS = 200_000
_FORCE_AFTER = MAX_SUBSTEPS // 2
_FORCE_REST = float(MAX_SUBSTEPS - _FORCE_AFTER - 2)  # one spare for a rounded-off end
#: A substep whose error estimate is below ROUNDOFF_FACTOR · ε · max(|φ|, |φ'|) (float64
#: rounding) is accepted even above its share of tol: no smaller substep would do better.
ROUNDOFF_FACTOR = 8.0
_EPS = float(np.finfo(float).eps)
#: ``"taylor"``: the share of ``tol`` float64 rounding may take: where its substeps'
#: rounding (TAYLOR_ROUNDING ε max(|φ|, |φ'|) each) adds up to more, the tolerance is
#: reported out of reach (``tol_met=False``).
ROUNDING_SHARE = 0.5
#: The rounding one ``"taylor"`` substep adds, in ε max(|φ|, |φ'|) of its end state: about
#: what was measured against 40-digit references (8, rk8's bound for one estimate, counted
#: at both ends, overstated it about 10×, and flagged reachable tolerances of 1e-10).
TAYLOR_ROUNDING = 2.0


@_jit
def _substeps(speed, m, r, kappa, e, k, g, c, dt, tol, order, constant, stable, sweep_exponent):
    """The predicted substeps (see :func:`predicted_substeps`)."""
    s = 1.0 - r * kappa
    j_min = m * (k * k + (r - e) * (r - e))
    omega = math.sqrt(m * g * (r * r * abs(kappa) / s + e) / j_min)
    sweep = speed / s * (1.0 + (r * e / (k * k + (r - e) * (r - e))) ** sweep_exponent)
    lam = (omega + sweep + c / j_min) * dt
    n = (constant * lam ** (order + 1) / tol) ** (1.0 / order)
    n = max(n, lam / stable)
    if not n < MAX_SUBSTEPS:  # also inf or nan at an absurd speed: the most, not int overflow
        return MAX_SUBSTEPS
    return max(1, math.ceil(n))


# -- substep functions --------------------------------------------------------------------------


@_jit
def _euler_substep(phi, w, tau, m, r, kappa, e, k, g, c, h):
    """Semi-implicit Euler: φ' first, then φ with the new φ'."""
    w = w + h * eq.accel(phi, w, tau, m, r, kappa, e, k, g, c)
    return phi + h * w, w


@_jit
def _midpoint_substep(phi, w, tau, m, r, kappa, e, k, g, c, h):
    """One implicit-midpoint step on (φ, p = J_I φ'); Newton's method on the midpoint."""
    p0 = eq.inertia(phi, m, r, kappa, e, k) * w
    pm_phi, pm_p = phi + 0.5 * h * w, p0  # initial guess
    converged = False
    for _ in range(50):
        j = eq.inertia(pm_phi, m, r, kappa, e, k)
        jp = eq.dinertia(pm_phi, m, r, kappa, e)
        jpp = eq.d2inertia(pm_phi, m, r, kappa, e)
        f1 = pm_p / j
        f2 = pm_p * pm_p * jp / (2.0 * j * j) - eq.dpotential(pm_phi, m, r, kappa, e, g)
        f2 += tau - c * pm_p / j
        g1 = pm_phi - phi - 0.5 * h * f1
        g2 = pm_p - p0 - 0.5 * h * f2
        d11 = 1.0 + 0.5 * h * pm_p * jp / (j * j)
        d12 = -0.5 * h / j
        df2 = pm_p * pm_p * (jpp / (2.0 * j * j) - jp * jp / (j * j * j))
        df2 += -eq.d2potential(pm_phi, m, r, kappa, e, g) + c * pm_p * jp / (j * j)
        d21 = -0.5 * h * df2
        d22 = 1.0 - 0.5 * h * (pm_p * jp / (j * j) - c / j)
        det = d11 * d22 - d12 * d21
        dphi = (g1 * d22 - g2 * d12) / det
        dp = (g2 * d11 - g1 * d21) / det
        pm_phi -= dphi
        pm_p -= dp
        if abs(dphi) <= 1e-15 * (1.0 + abs(pm_phi)) and abs(dp) <= 1e-15 * (1.0 + abs(pm_p)):
            converged = True
            break
    if not converged:  # no midpoint solution found from here: non-finite, so the step splits
        return math.nan, math.nan
    phi1 = 2.0 * pm_phi - phi
    return phi1, (2.0 * pm_p - p0) / eq.inertia(phi1, m, r, kappa, e, k)


def _tableau(a: np.ndarray, b: np.ndarray, e3: np.ndarray, e5: np.ndarray) -> np.ndarray:
    """An explicit Runge–Kutta pair as one array of shape (s + 3, s + 1): rows 0..s−1 the
    matrix A, row s the weights b, rows s + 1 and s + 2 the error weights E3 and E5 over the s
    stages and the stage f(y_new) (E3 = 0: a single estimator E5)."""
    s = b.shape[0]
    out = np.zeros((s + 3, s + 1))
    out[:s, :s] = a[:s, :s]
    out[s, :s] = b
    out[s + 1] = e3
    out[s + 2] = e5
    return out


_N8 = dop853_coefficients.N_STAGES
_DOP853 = _tableau(dop853_coefficients.A, dop853_coefficients.B, dop853_coefficients.E3,
                   dop853_coefficients.E5)
_RK4 = _tableau(  # classical RK4: rk4 with fixed substeps (their reported error_estimate)
    np.array([[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1.0, 0]]),
    np.array([1 / 6, 1 / 3, 1 / 3, 1 / 6]),
    np.zeros(5),
    np.array([0, 0, 0, 1 / 6, -1 / 6]),  # RK4 − the embedded 3rd-order (1/6, 1/3, 1/3, 0, 1/6)
)


#: Bogacki–Shampine 5(4) (P. Bogacki and L. F. Shampine, "An efficient Runge–Kutta (4,5)
#: pair", Comput. Math. Appl. 32(6) (1996) 15–28; the paper's rational coefficients, each
#: rounded once to float64 by Python's division): rk4 under error control. Eight stages, the
#: last the first of the next substep (7 evaluations a substep); the 5th-order solution
#: (weights b) is carried on and E = b̂ − b estimates the error of the embedded 4th-order one
#: (weights b̂, over all eight stages). The paper also gives an original 4th-order formula
#: over the first six stages, whose estimate RKSuite checks first (to reject a step two
#: evaluations early) and requires to pass as well; it is not used here: E alone keeps the
#: tests' adversarial steps within tol.
#: Why this pair: its 5th-order solution's error constant is about a ninth of Tsitouras
#: 5(4)'s (the largest order-6 defect 2.5e-5 against 2.2e-4). Against Tsitouras 5(4) at
#: share 0.16, the pair before it (which had replaced Dormand–Prince 5(4), scipy's RK45, at
#: 0.05), at share 0.12 it takes fewer evaluations on the benchmark's hard steps (cost ratio
#: at the 99th percentile 3.31 × / 3.22 × at tol 1e-6 / 1e-8, against 4.04 × / 4.05 ×; 4.88 ×
#: / 4.64 × for Dormand–Prince, each measured by the benchmark) and the larger of its energy
#: drifts over the tests' 1e5 steps is under half as large (2.1e-9 J at zero torque, against
#: 4.8e-9 J at the maximum torque). Its drift at zero torque is the larger of the two, where
#: Tsitouras 5(4)'s was 4e-11 J: the pairs' errors lean differently on the energy.
_BS5 = _tableau(
    np.array([
        [0, 0, 0, 0, 0, 0, 0],
        [1 / 6, 0, 0, 0, 0, 0, 0],
        [2 / 27, 4 / 27, 0, 0, 0, 0, 0],
        [183 / 1372, -162 / 343, 1053 / 1372, 0, 0, 0, 0],
        [68 / 297, -4 / 11, 42 / 143, 1960 / 3861, 0, 0, 0],
        [597 / 22528, 81 / 352, 63099 / 585728, 58653 / 366080, 4617 / 20480, 0, 0],
        [174197 / 959244, -30942 / 79937, 8152137 / 19744439, 666106 / 1039181,
         -29421 / 29068, 482048 / 414219, 0],
    ]),
    np.array([587 / 8064, 0, 4440339 / 15491840, 24353 / 124800, 387 / 44800, 2152 / 5985,
              7267 / 94080]),
    np.zeros(8),
    np.array([-3817 / 1959552, 0, 140181 / 15491840, -4224731 / 272937600, 8557 / 403200,
              -57928 / 4363065, -23930231 / 4366535040, 3293 / 556956]),
)


@numba.extending.register_jitable
def _finite(x):
    """True where x is finite (a comparison, no call)."""
    return x - x == 0.0


@numba.extending.register_jitable(inline="always")
def _margins(phi, w, a, m, r, kappa, e, g, mu):
    """(N/(m g), (μN − |F|)/(m g)): the lift-off and slip margins at a state."""
    normal, friction = eq.contact_forces(phi, w, a, m, r, kappa, e, g)
    return eq.margins(normal, friction, m, g, mu)


# The loops over lanes that evaluate the equations: no branch and no call in their bodies (the
# sines are trig's, inlined), so that LLVM runs them in SIMD lanes. They are functions of their
# own so that the inlining stays within a few lines.


@_jit
def _accel_lanes(phi, w, tau, par, na, out):
    """out[i] = φ'' of lane i at (phi[i], w[i]) under tau[i], for lanes 0..na−1."""
    for i in range(na):
        out[i] = eq.accel(phi[i], w[i], tau[i], par[0, i], par[1, i], par[2, i], par[3, i],
                          par[4, i], par[5, i], par[6, i])


@_jit
def _margin_lanes(phi, w, a, par, na, lift, slip):
    """Lower lift[i] and slip[i] to lane i's margins at (phi[i], w[i], a[i]) if smaller."""
    for i in range(na):
        li, si = _margins(phi[i], w[i], a[i], par[0, i], par[1, i], par[2, i], par[3, i],
                          par[5, i], par[7, i])
        lift[i], slip[i] = min(lift[i], li), min(slip[i], si)


@numba.extending.register_jitable(inline="always")
def _end_fields(phi, w, tau, m, r, kappa, e, k, g, c, mu):
    """(φ'', N, F, E, N/(m g), (μN − |F|)/(m g)) at the end state (no branch)."""
    lhs, d, sin_t, cos_t, sin_psi, cos_psi, _ = eq.accel_terms(phi, w, tau, m, r, kappa, e, k,
                                                               g, c)
    a = lhs / d  # eq.accel; the forces and the energy from its sines and J_I/m
    normal, friction = eq.forces(sin_t, cos_t, sin_psi, cos_psi, w, a, m, r, kappa, e, g)
    energy = eq.energy_at(d, phi, w, m, r, kappa, e, g)
    lift, slip = eq.margins(normal, friction, m, g, mu)
    return a, normal, friction, energy, lift, slip


@numba.extending.register_jitable
def _write(io, col, ok, phi, w, nsub, a, normal, friction, energy, lift, slip, err, tol_met):
    """Write one roller's outputs: the end state's fields, or the failure's (see module docs)."""
    ok = ok and math.isfinite(a) and math.isfinite(energy) and math.isfinite(w)
    ok = ok and abs(phi) <= trig.DOMAIN  # (False for NaN) past it, sin φ would be NaN
    io[_NSUB, col] = nsub
    if ok:
        io[_PHI, col], io[_W, col], io[_ACC, col] = phi, w, a
        io[_FINITE, col] = 1.0
        io[_NORMAL, col], io[_FRICTION, col], io[_ENERGY, col] = normal, friction, energy
        io[_LIFT, col], io[_SLIP, col] = lift, slip
        io[_ERR, col], io[_TOL_MET, col] = err, 1.0 if tol_met else 0.0
    else:
        io[_PHI, col], io[_W, col] = io[_PHI_IN, col], io[_W_IN, col]
        io[_FINITE, col], io[_TOL_MET, col] = 0.0, 0.0
        for row in (_ACC, _NORMAL, _FRICTION, _ENERGY, _LIFT, _SLIP, _ERR):
            io[row, col] = math.nan


@numba.extending.register_jitable
def _finish(io, col, ok, phi, w, tau, nsub, lift, slip, err, tol_met):
    """One roller's end fields and outputs (lift, slip: the smallest margins met before)."""
    m, r, kappa, e = io[_M, col], io[_RR, col], io[_KAPPA, col], io[_E, col]
    k, g, c, mu = io[_K, col], io[_G, col], io[_C, col], io[_MU, col]
    a, normal, friction, energy, lift_end, slip_end = _end_fields(phi, w, tau, m, r, kappa, e,
                                                                  k, g, c, mu)
    _write(io, col, ok, phi, w, nsub, a, normal, friction, energy, min(lift, lift_end),
           min(slip, slip_end), err, tol_met)


@_jit
def _end_lanes(phi, w, tau, par, n, out):
    """_end_fields of lanes 0..n−1 into the rows of ``out`` (lift and slip: the smaller of
    out[4], out[5] and the end's)."""
    for i in range(n):
        a, normal, friction, energy, li, si = _end_fields(
            phi[i], w[i], tau[i], par[0, i], par[1, i], par[2, i], par[3, i], par[4, i],
            par[5, i], par[6, i], par[7, i])
        out[0, i], out[1, i], out[2, i], out[3, i] = a, normal, friction, energy
        out[4, i], out[5, i] = min(out[4, i], li), min(out[5, i], si)


# -- the adaptive kernel: explicit Runge–Kutta pairs, a chunk of rollers together ----------------

#: Rollers advanced together (each with its own step size) by one task.
CHUNK = 512
#: Unused elements at the end of each row of a chunk's scratch block and of a batch's tables
#: (:func:`row_table`), so that rows are not a power of two apart: the same element of many
#: rows would otherwise fall into one set of the cache, and a loop that reads many rows at
#: once (the stages read up to 30) would miss it at every element.
_PAD = 8


def row_table(rows: int, n: int, zeroed: bool = True) -> np.ndarray:
    """A float64 table of ``rows`` rows of ``n`` rollers whose rows lie ``n + _PAD`` elements
    apart in memory (a view): what the batch kernels read and write a roller's column of (see
    ``_PAD``). Zeroed, unless ``zeroed`` is False (for a table that is written whole)."""
    return (np.zeros if zeroed else np.empty)((rows, n + _PAD))[:, :n]


_SAFETY, _MIN_FACTOR, _MAX_FACTOR = 0.9, 0.2, 10.0
#: Attempts (accepted or rejected substeps) after which a roller still running is failed.
_MAX_ATTEMPTS = 4 * MAX_SUBSTEPS


@numba.extending.register_jitable
def _first_size(io, col, phi_dot, dt, tol, nfixed, cfg):
    """The size [s] a roller's first substep wants: the fixed one; else where the last step's
    controller left off, split even over what is left; else the prediction."""
    if nfixed > 0:
        return dt / nfixed
    if io[_H_NEXT, col] > 0.0:
        return dt / math.ceil(dt / io[_H_NEXT, col] * (1.0 - 1e-9))
    guess = _substeps(abs(phi_dot), io[_M, col], io[_RR, col], io[_KAPPA, col], io[_E, col],
                      io[_K, col], io[_G, col], io[_C, col], dt, tol, cfg[_CF_ORDER],
                      cfg[_CF_CONSTANT], cfg[_CF_STABLE], cfg[_CF_SWEEP])
    return dt / guess


@numba.extending.register_jitable
def _attempt_size(fixed, nfixed, hdes, count, t, dt):
    """(h [s], last): the size of a roller's next attempt, and 1.0 if it would end the step."""
    if fixed:
        return hdes, 1.0 if count + 1 >= nfixed else 0.0
    rest = dt - t
    return min(hdes, rest), 1.0 if hdes >= rest else 0.0


@numba.extending.register_jitable
def _judge(h, e5p, e5w, e3p, e3w, phi, w, phin, wn, a_new, count, hforce, t, hdes, rejected,
           last, status, dt, share, fixed, halvings):
    """Accept or reject one roller's attempt of size h, from its error sums (scipy's DOP853
    form; E3 = 0 gives |h E5·K|), and the size of its next: selects only, no branch.

    Returns (accepted, its error estimate, the next size [s], the roller's status, hforce).
    """
    dp = e5p * e5p + 0.01 * e3p * e3p
    dw = e5w * e5w + 0.01 * e3w * e3w
    errp = h * e5p * e5p / math.sqrt(trig.select(dp > 0.0, dp, 1.0))
    errw = h * e5w * e5w / math.sqrt(trig.select(dw > 0.0, dw, 1.0))
    err = max(errp, errw)
    fin = _finite(phin) & _finite(wn) & _finite(a_new) & _finite(err)
    # past _FORCE_AFTER accepted substeps, the rest in fewer than as many more
    start = (count == _FORCE_AFTER) & (hforce == 0.0)
    hforce = trig.select(start, (dt - t) / _FORCE_REST, hforce)
    floor = max(1e-12 * dt, hforce)
    # the error a substep aims at: its share of tol, or float64's rounding of the state if
    # that is larger (a smaller substep would only add rounding)
    big = max(max(abs(phi), abs(w)), max(abs(phin), abs(wn)))
    aim = max(share * h / dt, _EPS * big)
    ratio = trig.select(aim > 0.0, err / trig.select(aim > 0.0, aim, 1.0), 0.0)
    # an estimate at the level of float64 rounding is accepted: no smaller substep does better
    # (a non-finite trial never is: it is rejected and shrunk, failing only at the floor)
    forced = (h <= floor) | (fin & (err <= ROUNDOFF_FACTOR * _EPS * big))
    accept = trig.select(fixed, fin, fin & ((ratio <= 1.0) | forced))
    fail = (not fin) & (fixed | forced)
    ends = accept & (last != 0.0)
    status = trig.select(ends, 1.0, trig.select(fail, 2.0, status))
    # the next size: h · clip(0.9 ratio^(−1/order), 0.2, 10), the root as square roots
    q = math.sqrt(math.sqrt(ratio))
    q = trig.select(halvings >= 3, math.sqrt(q), q)
    factor = min(_MAX_FACTOR, max(_MIN_FACTOR, _SAFETY / q))  # ratio 0: the largest
    factor = trig.select(fin, factor, _MIN_FACTOR)
    factor = trig.select(rejected != 0.0, min(factor, 1.0), factor)
    h_new = trig.select(fixed, hdes, max(h * factor, floor))
    return accept, err, h_new, status, hforce


@numba.extending.register_jitable
def _tick(accept, last, t, h, count, err_sum, err, hwant, h_new, carry, dt):
    """A roller's clock [s], accepted count, error sum, rejected flag and carried size [s]
    after an attempt of size h (the size carried on is the size wanted, not the last one cut
    short at dt)."""
    ends = accept & (last != 0.0)
    t = trig.select(ends, dt, trig.select(accept, t + h, t))
    taken = trig.select(accept, 1.0, 0.0)
    return (t, count + taken, err_sum + trig.select(accept, err, 0.0), 1.0 - taken,
            trig.select(ends, max(hwant, h_new), carry))


@_jit
def _rk_chunk(io, lo, hi, tab, cfg):
    """Advance rollers (columns) lo..hi−1 of ``io`` over one control step.

    ``tab``: the pair (see :func:`_tableau`); ``cfg``: the stepper's settings
    (:data:`CFG_FIELDS`).
    """
    n = hi - lo
    s = tab.shape[0] - 3
    dt, tol = cfg[_CF_DT], cfg[_CF_TOL]
    nfixed, halvings = int(cfg[_CF_SUBSTEPS]), int(cfg[_CF_HALVINGS])
    share = tol * cfg[_CF_SHARE]  # the error the accepted substeps' estimates may add up to
    fixed = nfixed > 0
    # one scratch block: the stages, then one row per per-roller quantity
    nf = len(SCENE_FIELDS)
    scratch = np.empty((2 * (s + 1) + nf + 31, n + _PAD))
    kp = scratch[: s + 1]  # stage velocities φ'
    kw = scratch[s + 1: 2 * (s + 1)]  # stage accelerations φ''
    par = scratch[2 * (s + 1): 2 * (s + 1) + nf]
    rows = scratch[2 * (s + 1) + nf:]
    acc_p, acc_w, e5p, e5w, e3p, e3w = rows[0], rows[1], rows[2], rows[3], rows[4], rows[5]
    tau, phi, w, hh, hdes, t = rows[6], rows[7], rows[8], rows[9], rows[10], rows[11]
    phin, wn, lift, slip, err_sum = rows[12], rows[13], rows[14], rows[15], rows[16]
    hforce, count, last = rows[17], rows[18], rows[19]
    status = rows[20]  # 0 running, 1 done, 2 failed
    rejected = rows[21]  # 0 or 1
    slot = rows[22]  # the roller (column lo + slot) whose numbers are in this lane
    hwant, carry = rows[29], rows[30]  # the size wanted this attempt; the size carried on
    for i in range(n):
        hforce[i], count[i], status[i], rejected[i], slot[i] = 0.0, 0.0, 0.0, 0.0, i
        carry[i] = 0.0
    # The running rollers are kept in lanes 0..na−1 (a finished one swaps places with the last
    # running one), so every per-lane loop runs over contiguous lanes.
    na = n
    for i in range(n):
        col = lo + i
        for f in range(len(SCENE_FIELDS)):
            par[f, i] = io[f, col]
        tau[i] = io[_TAU, col]
        phi[i], w[i] = io[_PHI_IN, col], io[_W_IN, col]
        kp[0, i] = w[i]
        t[i], lift[i], slip[i], err_sum[i] = 0.0, np.inf, np.inf, 0.0
        hdes[i] = _first_size(io, col, w[i], dt, tol, nfixed, cfg)
    _accel_lanes(phi, w, tau, par, n, kw[0])
    for _attempt in range(_MAX_ATTEMPTS):
        if na == 0:
            break
        # this attempt's sizes, and the margins at the start of the substep
        for i in range(na):
            hh[i], last[i] = _attempt_size(fixed, nfixed, hdes[i], count[i], t[i], dt)
            hwant[i] = hdes[i]
        _margin_lanes(phi, w, kw[0], par, na, lift, slip)
        # the stages
        for st in range(1, s + 1):
            for i in range(na):
                acc_p[i], acc_w[i] = 0.0, 0.0
            for j in range(st):
                a = tab[st, j]
                if a != 0.0:
                    for i in range(na):
                        acc_p[i] += a * kp[j, i]
                        acc_w[i] += a * kw[j, i]
            for i in range(na):
                phin[i] = phi[i] + hh[i] * acc_p[i]
                kp[st, i] = w[i] + hh[i] * acc_w[i]
            _accel_lanes(phin, kp[st], tau, par, na, kw[st])
        # the last stage's weights are b: its state is the new state
        for i in range(na):
            wn[i] = kp[s, i]
        # the error sums
        for i in range(na):
            e5p[i], e5w[i], e3p[i], e3w[i] = 0.0, 0.0, 0.0, 0.0
        for j in range(s + 1):
            a3, a5 = tab[s + 1, j], tab[s + 2, j]
            for i in range(na):
                e3p[i] += a3 * kp[j, i]
                e3w[i] += a3 * kw[j, i]
                e5p[i] += a5 * kp[j, i]
                e5w[i] += a5 * kw[j, i]
        # Accept or reject, and the next size, per roller: selects only, in three loops that
        # each touch few rows, so that LLVM can vectorize them (it gives up on a loop whose
        # rows it would have to check pairwise for overlap too many times).
        accepted, err_now, h_new = acc_p, e3p, e3w  # rows free until the next attempt
        for i in range(na):
            accept, err_now[i], h_new[i], status[i], hforce[i] = _judge(
                hh[i], e5p[i], e5w[i], e3p[i], e3w[i], phi[i], w[i], phin[i], wn[i], kw[s, i],
                count[i], hforce[i], t[i], hdes[i], rejected[i], last[i], status[i], dt,
                share, fixed, halvings)
            accepted[i] = trig.select(accept, 1.0, 0.0)
        for i in range(na):  # the state of the accepted
            accept = accepted[i] != 0.0
            phi[i] = trig.select(accept, phin[i], phi[i])
            w[i] = trig.select(accept, wn[i], w[i])
            kp[0, i] = trig.select(accept, kp[s, i], kp[0, i])
            kw[0, i] = trig.select(accept, kw[s, i], kw[0, i])
        for i in range(na):  # the clocks and counts
            t[i], count[i], err_sum[i], rejected[i], carry[i] = _tick(
                accepted[i] != 0.0, last[i], t[i], hh[i], count[i], err_sum[i], err_now[i],
                hwant[i], h_new[i], carry[i], dt)
            hdes[i] = h_new[i]
        i = 0
        while i < na:
            if status[i] != 0.0:
                na -= 1
                for f in range(nf):
                    par[f, i], par[f, na] = par[f, na], par[f, i]
                for x in (kp[0], kw[0], tau, phi, w, hdes, t, lift, slip, err_sum, hforce, count,
                          status, rejected, slot, carry):  # what outlives an attempt
                    x[i], x[na] = x[na], x[i]
            else:
                i += 1
    # the end states' fields, all lanes at once, then each roller's outputs to its column
    end = rows[23:29]
    end[4, :n], end[5, :n] = lift[:n], slip[:n]
    _end_lanes(phi, w, tau, par, n, end)
    for i in range(n):
        io[_H_NEXT, lo + int(slot[i])] = 0.0 if fixed or status[i] != 1.0 else carry[i]
        _write(io, lo + int(slot[i]), status[i] == 1.0, phi[i], w[i], count[i], end[0, i],
               end[1, i], end[2, i], end[3, i], end[4, i], end[5, i], err_sum[i],
               err_sum[i] <= share)


@_jit
def _rk_one(io, tab, cfg):
    """One roller (column 0 of ``io``) over one control step: :func:`_rk_chunk`'s arithmetic
    in the same order, without its lanes (bit for bit the same result, at a fraction of the
    latency). What :class:`Stepper` runs."""
    s = tab.shape[0] - 3
    dt, tol = cfg[_CF_DT], cfg[_CF_TOL]
    nfixed, halvings = int(cfg[_CF_SUBSTEPS]), int(cfg[_CF_HALVINGS])
    share = tol * cfg[_CF_SHARE]
    fixed = nfixed > 0
    m, r, kappa, e = io[_M, 0], io[_RR, 0], io[_KAPPA, 0], io[_E, 0]
    k, g, c, mu = io[_K, 0], io[_G, 0], io[_C, 0], io[_MU, 0]
    tau, phi, w = io[_TAU, 0], io[_PHI_IN, 0], io[_W_IN, 0]
    kp, kw = np.empty(s + 1), np.empty(s + 1)  # the stages' φ' and φ''
    kp[0], kw[0] = w, eq.accel(phi, w, tau, m, r, kappa, e, k, g, c)
    t, lift, slip, err_sum, hforce, count = 0.0, np.inf, np.inf, 0.0, 0.0, 0.0
    status, rejected, carry = 0.0, 0.0, 0.0
    hdes = _first_size(io, 0, w, dt, tol, nfixed, cfg)
    for _attempt in range(_MAX_ATTEMPTS):
        if status != 0.0:
            break
        h, last = _attempt_size(fixed, nfixed, hdes, count, t, dt)
        li, si = _margins(phi, w, kw[0], m, r, kappa, e, g, mu)
        lift, slip = min(lift, li), min(slip, si)
        phin = phi
        for st in range(1, s + 1):
            acc_p, acc_w = 0.0, 0.0
            for j in range(st):
                a = tab[st, j]
                if a != 0.0:
                    acc_p += a * kp[j]
                    acc_w += a * kw[j]
            phin = phi + h * acc_p
            kp[st] = w + h * acc_w
            kw[st] = eq.accel(phin, kp[st], tau, m, r, kappa, e, k, g, c)
        wn = kp[s]
        e5p, e5w, e3p, e3w = 0.0, 0.0, 0.0, 0.0
        for j in range(s + 1):
            a3, a5 = tab[s + 1, j], tab[s + 2, j]
            e3p += a3 * kp[j]
            e3w += a3 * kw[j]
            e5p += a5 * kp[j]
            e5w += a5 * kw[j]
        accept, err, h_new, status, hforce = _judge(
            h, e5p, e5w, e3p, e3w, phi, w, phin, wn, kw[s], count, hforce, t, hdes, rejected,
            last, status, dt, share, fixed, halvings)
        if accept:
            phi, w, kp[0], kw[0] = phin, wn, kp[s], kw[s]
        t, count, err_sum, rejected, carry = _tick(accept, last, t, h, count, err_sum, err,
                                                   hdes, h_new, carry, dt)
        hdes = h_new
    io[_H_NEXT, 0] = 0.0 if fixed or status != 1.0 else carry
    _finish(io, 0, status == 1.0, phi, w, tau, count, lift, slip, err_sum, err_sum <= share)


@numba.extending.register_jitable(inline="always")
def _serial(io, tab, cfg, one, chunk):
    """A batch kernel on one core: ``one`` for a batch of one roller (a Stepper: the same
    arithmetic without lanes), else ``chunk`` over chunks of CHUNK rollers."""
    n = io.shape[1]
    if n == 1:
        one(io, tab, cfg)
        return
    for lo in range(0, n, CHUNK):
        chunk(io, lo, min(lo + CHUNK, n), tab, cfg)


@numba.extending.register_jitable(inline="always")
def _parallel(io, tab, cfg, chunk):
    """A batch kernel on all cores: ``chunk`` over chunks of CHUNK rollers."""
    n = io.shape[1]
    for c in numba.prange((n + CHUNK - 1) // CHUNK):
        lo = c * CHUNK
        chunk(io, lo, min(lo + CHUNK, n), tab, cfg)


# Each chunked scheme's kernels: the shared loops around its functions, a function of its own
# per scheme so that numba caches it (as the fixed-substep kernels below).
@_jit
def _rk_serial(io, tab, cfg):
    _serial(io, tab, cfg, _rk_one, _rk_chunk)


@numba.njit(cache=True, parallel=True, nogil=True, error_model="numpy")
def _rk_parallel(io, tab, cfg):
    _parallel(io, tab, cfg, _rk_chunk)


#: Batches at least this large are advanced on all cores.
PARALLEL_THRESHOLD = 2048


# -- the Taylor kernel: one expansion a substep, its size chosen after expanding ----------------

_T_IN = ("phi", "phi_dot", "tau", "rest", "floor")  # the rows a substep reads, after the scene's
_T_OUT = ("phi", "phi_dot", "h", "err", "lift", "slip", "last", "rounding")  # what it gives
(_TI_PHI, _TI_W, _TI_TAU, _TI_REST, _TI_FLOOR) = (len(SCENE_FIELDS) + i for i in range(len(_T_IN)))
_T_WIDTH = 8  # elements per lane in the substep loop's output (its fields, padded)
assert len(_T_OUT) <= _T_WIDTH


@numba.njit(cache=True, nogil=True, error_model="numpy", forceinline=True)
def _root(x):
    """x^(1/16), as four square roots (which vectorize; a power does not)."""
    return math.sqrt(math.sqrt(math.sqrt(math.sqrt(x))))


@numba.njit(cache=True, nogil=True, error_model="numpy", forceinline=True)
def _taylor_substep(phi, w, tau, m, r, kappa, e, k, g, c, mu, rest, floor, hfixed, rate):
    """One substep of ``"taylor"`` from (φ, φ'): (φ, φ', h [s], its error estimate, the
    lift-off and slip margins at its start, 1.0 if it reaches ``rest`` [s], the float64
    rounding of its state). The margins take the sines the expansion evaluated.

    The estimate is the size of the last two terms, t₁ h^(p−1) + t₂ hᵖ (p the degree, t the
    largest of |X| and |V| at that power): two terms, as one coefficient can vanish by
    accident where the next does not. With ``hfixed`` > 0 the substep is that long.
    Otherwise h is the largest size whose terms are each within ``rate`` · h (the error
    allowed per second): h₁ = (rate/t₁)^(1/(p−2)), and h₂ from t₂ h^(p−1) <= rate h with
    h^(p−1) taken as min(h₁, rest) h^(p−2); then 0.9 of the smaller, at least ``floor``, at
    most ``rest``.

    The size goes as the 16th root of ``rate``, so a tolerance far below float64's reach
    costs only a few more substeps, never a runaway count; the rounding the substep adds,
    TAYLOR_ROUNDING ε max(|φ|, |φ'|) at its end, is returned so that the step can report
    such a tolerance (``tol_met``). No branch: the batch runs it in SIMD lanes.
    """
    X, V, (sin_t, cos_t, sin_psi, cos_psi) = series.coefficients(phi, w, tau, m, r, kappa, e,
                                                                  k, g, c)
    p = series.ORDER
    t1 = max(abs(X[p - 1]), abs(V[p - 1]))
    t2 = max(abs(X[p]), abs(V[p]))
    h1 = trig.select(t1 > 0.0, _root(rate / t1), math.inf)
    near = min(h1, rest)
    h2 = trig.select(t2 * near > 0.0, _root(rate / (t2 * near)), math.inf)
    free = max(_SAFETY * min(h1, h2), floor)
    fixed = hfixed > 0.0
    h = trig.select(fixed, hfixed, min(free, rest))
    sq = h * h
    h8 = sq * sq * (sq * sq)
    # t1 h^17 + t2 h^18; 0 where the series ends before them (h^17 may overflow there)
    err = trig.select(t1 + t2 > 0.0, (t1 + t2 * h) * (h8 * h8) * h, 0.0)
    last = trig.select(free >= rest, 1.0, 0.0)
    phin, wn = series.value(X, h), series.value(V, h)
    rounding = TAYLOR_ROUNDING * _EPS * max(abs(phin), abs(wn))
    normal, friction = eq.forces(sin_t, cos_t, sin_psi, cos_psi, w, V[1], m, r, kappa, e, g)
    lift, slip = eq.margins(normal, friction, m, g, mu)
    return phin, wn, h, err, lift, slip, last, rounding


@_jit
def _taylor_lanes(x, na, hfixed, rate, out):
    """:func:`_taylor_substep` of lanes 0..na−1: the scene and state from the rows of ``x``,
    the results lane by lane into ``out`` (_T_WIDTH elements a lane). Reading one table and
    writing another, laid out so, is what lets LLVM vectorize a body this long: it needs
    just one overlap check."""
    for i in range(na):
        o = np.uint64(i) * np.uint64(_T_WIDTH)  # unsigned: no wraparound check on the index
        (out[o], out[o + np.uint64(1)], out[o + np.uint64(2)], out[o + np.uint64(3)],
         out[o + np.uint64(4)], out[o + np.uint64(5)], out[o + np.uint64(6)],
         out[o + np.uint64(7)]) = _taylor_substep(
            x[_TI_PHI, i], x[_TI_W, i], x[_TI_TAU, i], x[0, i], x[1, i], x[2, i], x[3, i],
            x[4, i], x[5, i], x[6, i], x[7, i], x[_TI_REST, i], x[_TI_FLOOR, i], hfixed, rate)


@numba.extending.register_jitable
def _taylor_tick(fin, last, rounding, count, nfixed, t, h, err_sum, err, hforce, status,
                 round_sum, dt):
    """A roller's (status, clock [s], accepted count, error sum, hforce [s], rounding sum)
    after a substep (``fin``: it stayed finite): selects only. A substep that brings the
    clock to dt ends the step."""
    last = trig.select(nfixed > 0, count + 1.0 >= nfixed, (last != 0.0) | (t + h >= dt))
    ends = fin & last
    status = trig.select(ends, 1.0, trig.select(fin, status, 2.0))
    t = trig.select(ends, dt, t + h)
    count = count + trig.select(fin, 1.0, 0.0)
    # past _FORCE_AFTER substeps, the rest in fewer than as many more
    start = (count == _FORCE_AFTER) & (hforce == 0.0)
    hforce = trig.select(start, (dt - t) / _FORCE_REST, hforce)
    return status, t, count, err_sum + err, hforce, round_sum + rounding


@_jit
def _taylor_chunk(io, lo, hi, tab, cfg):
    """Advance rollers (columns) lo..hi−1 of ``io`` over one control step with ``"taylor"``
    (``cfg`` as for :func:`_rk_chunk`; ``tab`` unused): the running rollers in lanes
    0..na−1, as there."""
    n = hi - lo
    dt, tol, nfixed = cfg[_CF_DT], cfg[_CF_TOL], cfg[_CF_SUBSTEPS]
    share = tol * cfg[_CF_SHARE]
    hfixed = dt / nfixed if nfixed > 0 else 0.0
    nf = len(SCENE_FIELDS)
    x = np.empty((nf + len(_T_IN), n + _PAD))  # what the substep loop reads
    par = x[:nf]
    phi, w, tau, rest, floor = x[_TI_PHI], x[_TI_W], x[_TI_TAU], x[_TI_REST], x[_TI_FLOOR]
    out = np.empty(_T_WIDTH * n)
    rows = np.empty((17, n + _PAD))
    phin, wn, hh, err, lift_at, slip_at = rows[0], rows[1], rows[2], rows[3], rows[4], rows[5]
    t, count, err_sum, hforce, status, slot = rows[6], rows[7], rows[8], rows[9], rows[10], rows[11]
    lift, slip, rounding, round_sum, last = rows[12], rows[13], rows[14], rows[15], rows[16]
    for i in range(n):
        col = lo + i
        for f in range(nf):
            par[f, i] = io[f, col]
        tau[i], phi[i], w[i] = io[_TAU, col], io[_PHI_IN, col], io[_W_IN, col]
        t[i], count[i], err_sum[i], hforce[i], status[i], slot[i] = 0.0, 0.0, 0.0, 0.0, 0.0, i
        lift[i], slip[i], round_sum[i] = np.inf, np.inf, 0.0
    na = n
    for _attempt in range(_MAX_ATTEMPTS):
        if na == 0:
            break
        for i in range(na):
            rest[i], floor[i] = dt - t[i], max(1e-12 * dt, hforce[i])
        _taylor_lanes(x, na, hfixed, share / dt, out)
        for i in range(na):
            o = _T_WIDTH * i
            phin[i], wn[i], hh[i], err[i], lift_at[i], slip_at[i], last[i], rounding[i] = (
                out[o], out[o + 1], out[o + 2], out[o + 3], out[o + 4], out[o + 5], out[o + 6],
                out[o + 7])
        for i in range(na):
            lift[i], slip[i] = min(lift[i], lift_at[i]), min(slip[i], slip_at[i])
            fin = _finite(phin[i]) & _finite(wn[i]) & _finite(err[i])
            status[i], t[i], count[i], err_sum[i], hforce[i], round_sum[i] = _taylor_tick(
                fin, last[i], rounding[i], count[i], nfixed, t[i], hh[i], err_sum[i], err[i],
                hforce[i], status[i], round_sum[i], dt)
            phi[i] = trig.select(fin, phin[i], phi[i])
            w[i] = trig.select(fin, wn[i], w[i])
        i = 0
        while i < na:
            if status[i] != 0.0:
                na -= 1
                for f in range(nf):
                    par[f, i], par[f, na] = par[f, na], par[f, i]
                for v in (tau, phi, w, t, count, err_sum, hforce, status, slot, lift, slip,
                          round_sum):
                    v[i], v[na] = v[na], v[i]
            else:
                i += 1
    end = np.empty((6, n + _PAD))
    end[4, :n], end[5, :n] = lift[:n], slip[:n]
    _end_lanes(phi, w, tau, par, n, end)
    for i in range(n):
        col = lo + int(slot[i])
        io[_H_NEXT, col] = 0.0
        _write(io, col, status[i] == 1.0, phi[i], w[i], count[i], end[0, i], end[1, i],
               end[2, i], end[3, i], end[4, i], end[5, i], err_sum[i],
               (err_sum[i] <= share) & (round_sum[i] <= ROUNDING_SHARE * tol))


@_jit
def _taylor_one(io, tab, cfg):
    """One roller (column 0 of ``io``) with ``"taylor"``: :func:`_taylor_chunk`'s arithmetic
    without lanes (bit for bit the same result)."""
    dt, tol, nfixed = cfg[_CF_DT], cfg[_CF_TOL], cfg[_CF_SUBSTEPS]
    share = tol * cfg[_CF_SHARE]
    hfixed = dt / nfixed if nfixed > 0 else 0.0
    m, r, kappa, e = io[_M, 0], io[_RR, 0], io[_KAPPA, 0], io[_E, 0]
    k, g, c, mu = io[_K, 0], io[_G, 0], io[_C, 0], io[_MU, 0]
    tau, phi, w = io[_TAU, 0], io[_PHI_IN, 0], io[_W_IN, 0]
    t, count, err_sum, hforce, status, round_sum = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    lift, slip = np.inf, np.inf
    for _attempt in range(_MAX_ATTEMPTS):
        if status != 0.0:
            break
        phin, wn, h, err, li, si, last, rounding = _taylor_substep(
            phi, w, tau, m, r, kappa, e, k, g, c, mu, dt - t, max(1e-12 * dt, hforce), hfixed,
            share / dt)
        lift, slip = min(lift, li), min(slip, si)
        fin = _finite(phin) & _finite(wn) & _finite(err)
        status, t, count, err_sum, hforce, round_sum = _taylor_tick(
            fin, last, rounding, count, nfixed, t, h, err_sum, err, hforce, status, round_sum,
            dt)
        phi, w = trig.select(fin, phin, phi), trig.select(fin, wn, w)
    io[_H_NEXT, 0] = 0.0
    _finish(io, 0, status == 1.0, phi, w, tau, count, lift, slip, err_sum,
            (err_sum <= share) & (round_sum <= ROUNDING_SHARE * tol))


@_jit
def _taylor_serial(io, tab, cfg):
    _serial(io, tab, cfg, _taylor_one, _taylor_chunk)


@numba.njit(cache=True, parallel=True, nogil=True, error_model="numpy")
def _taylor_parallel(io, tab, cfg):
    _parallel(io, tab, cfg, _taylor_chunk)


# -- the fixed-substep kernel ------------------------------------------------------------------


@numba.extending.register_jitable(inline="always")
def _fixed_steps(io, cfg, substep):
    """The loop of a fixed-substep scheme around its ``substep`` function: each roller on its
    own, n equal substeps."""
    dt, tol, nfixed = cfg[_CF_DT], cfg[_CF_TOL], int(cfg[_CF_SUBSTEPS])
    for col in range(io.shape[1]):
        m, r, kappa, e = io[_M, col], io[_RR, col], io[_KAPPA, col], io[_E, col]
        k, g, c, mu = io[_K, col], io[_G, col], io[_C, col], io[_MU, col]
        phi0, w0, tau = io[_PHI_IN, col], io[_W_IN, col], io[_TAU, col]
        n = nfixed if nfixed > 0 else _substeps(abs(w0), m, r, kappa, e, k, g, c, dt, tol,
                                               cfg[_CF_ORDER], cfg[_CF_CONSTANT],
                                               cfg[_CF_STABLE], cfg[_CF_SWEEP])
        phi, w, needed = phi0, w0, n
        lift, slip = np.inf, np.inf
        for _attempt in range(20):
            h = dt / n
            phi, w, top = phi0, w0, abs(w0)
            lift, slip = np.inf, np.inf
            for _ in range(n):
                a = eq.accel(phi, w, tau, m, r, kappa, e, k, g, c)
                li, si = _margins(phi, w, a, m, r, kappa, e, g, mu)
                lift, slip = min(lift, li), min(slip, si)
                phi, w = substep(phi, w, tau, m, r, kappa, e, k, g, c, h)
                if not (math.isfinite(phi) and math.isfinite(w)):
                    break
                top = max(top, abs(w))
            finite = math.isfinite(phi) and math.isfinite(w)
            if nfixed > 0 or (not finite and n >= MAX_SUBSTEPS):
                break
            needed = (_substeps(top, m, r, kappa, e, k, g, c, dt, tol, cfg[_CF_ORDER],
                                cfg[_CF_CONSTANT], cfg[_CF_STABLE], cfg[_CF_SWEEP])
                      if finite else 2 * n)
            if needed <= n:
                break
            n = min(needed, MAX_SUBSTEPS)
        # the tolerance is met as far as the prediction tells, unless it asked for more
        # substeps than MAX_SUBSTEPS
        _finish(io, col, True, phi, w, tau, n, lift, slip, math.nan,
                nfixed > 0 or needed < MAX_SUBSTEPS)


# Each fixed-substep scheme's kernel: the shared loop around its substep function. A function
# of its own per scheme, so that numba caches it on disk (a kernel made by a factory closes
# over its substep, and numba cannot cache such closures).
@_jit
def _euler_kernel(io, tab, cfg):
    _fixed_steps(io, cfg, _euler_substep)


@_jit
def _midpoint_kernel(io, tab, cfg):
    _fixed_steps(io, cfg, _midpoint_substep)


# -- the reference --------------------------------------------------------------------------------


def _dop853_kernel(io: np.ndarray, tab: None, cfg: np.ndarray) -> None:
    """scipy's DOP853 on the whole batch as one system (margins at the start and the end)."""
    dt, tol = float(cfg[_CF_DT]), float(cfg[_CF_TOL])
    n = io.shape[1]
    m, r, kappa, e, k, g, c, mu = (io[_ROW[f]] for f in SCENE_FIELDS)
    phi, w, tau = io[_PHI_IN], io[_W_IN], io[_TAU]

    def rhs(_t, y):
        return np.concatenate((y[n:], eq.accel(y[:n], y[n:], tau, m, r, kappa, e, k, g, c)))

    with np.errstate(all="ignore"):
        sol = solve_ivp(rhs, (0.0, dt), np.concatenate((phi, w)), method="DOP853", rtol=tol,
                        atol=tol)
        y = sol.y[:, -1] if sol.success else np.full(2 * n, np.nan)
        # scipy raises an rtol below 100 ε to 100 ε (and warns): tol is then not what it met
        met = bool(sol.success) and tol >= 100.0 * _EPS
        a0 = eq.accel(phi, w, tau, m, r, kappa, e, k, g, c)
        normal, friction = eq.contact_forces(phi, w, a0, m, r, kappa, e, g)
        lift, slip = eq.margins(normal, friction, m, g, mu)
    for col in range(n):
        _finish_py(io, col, bool(sol.success), float(y[col]), float(y[n + col]),
                   float(tau[col]), sol.t.size - 1, float(lift[col]), float(slip[col]),
                   math.nan, met)


_finish_py = _finish  # register_jitable leaves it a Python function too


# -- the table of schemes ---------------------------------------------------------------------


@dataclass(frozen=True)
class Scheme:
    """One integration scheme: a row of :data:`SCHEMES`.

    Attributes:
        name: its name, the ``method`` argument.
        order: its order of accuracy.
        stable_step: the largest λh per substep (λ the fastest rate), inside its stability
            region with room to spare (``math.inf``: A-stable).
        adaptive: True if its substeps follow an error estimate (see the module docs).
        substep: its substep function (for the Runge–Kutta pairs, the shared pair kernel).
        kernel: for a fixed-substep scheme, its compiled kernel: ``_fixed_steps`` around
            ``substep``, written as a function of its own (two lines) so that numba caches it;
            for ``"taylor"``, its serial kernel.
        parallel: the kernel for large batches, where it is not ``kernel``.
        chunk: for a scheme whose batch kernels advance chunks of rollers in lanes, that
            function, ``chunk(io, lo, hi, tableau, cfg)`` (rollers lo..hi−1): what a caller
            fusing more work into the same pass over chunks calls (:meth:`BatchStepper.run`).
        tableau: for an explicit Runge–Kutta pair, its coefficients (see ``_tableau``).
        fixed_tableau: the coefficients its fixed substeps (``substeps=n``) take, where they
            differ from ``tableau`` (rk4: classical RK4; under error control,
            Bogacki–Shampine 5(4)).
        constant: C of the substep prediction n = (C (λ dt)^(p+1) / tol)^(1/p), calibrated
            on the presets (for the adaptive schemes only the first step-size guess).
        sweep_exponent: the exponent of re/(k² + (r − e)²) in the prediction's sweep rate.
        halvings: the adaptive controller takes the 2^halvings-th root of the error ratio
            (2 or 3: the kernel takes it as square roots, which vectorize).
        tol_share: the share of ``tol`` the accepted substeps' error estimates may add up to
            (below 1: room for what the estimates miss, measured in the tests). rk4's 0.12
            keeps its energy drift over 1e5 steps under half the tests' bound of 5e-9 J
            (measured on "paper" at tol 1e-9, zero torque: 1.7e-9 J at 0.10, 2.1e-9 J at
            0.12, 3.2e-9 J at 0.16, 5.4e-9 J at 0.25, over it) and meets the cost targets
            with room (99th percentile 3.3 ×); 0.16 would take about 7 % fewer evaluations
            on the benchmark's hard steps, at two thirds of the drift bound.
            taylor's 0.01: where a step runs through the dip of J_I (the mass near the
            contact), the end state is up to 1e5 times as sensitive to an error early in the
            step, and the substeps' estimates cannot see it; on random "rim_mass" steps the
            error stays within tol at 0.01 (at 0.3 it reached 13 tol), for 16 % more
            substeps (the size goes as the 16th root of the share).
    """

    name: str
    order: int
    stable_step: float
    adaptive: bool
    substep: Callable | None
    tableau: np.ndarray | None = None
    fixed_tableau: np.ndarray | None = None
    kernel: Callable | None = None
    parallel: Callable | None = None
    chunk: Callable | None = None
    constant: float = 0.0
    sweep_exponent: float = 0.5
    halvings: int = 0
    tol_share: float = 1.0

    def kernels(self) -> tuple[Callable, Callable]:
        """(serial, parallel) kernels ``f(io, tableau, cfg)`` of this scheme."""
        return _kernels(self)

    def __reduce__(self) -> tuple[Callable, tuple[str]]:
        """Pickled by name: unpickled, it is the row of :data:`SCHEMES` (its compiled
        functions those of this process)."""
        return scheme, (self.name,)

    def pair(self, fixed: bool) -> np.ndarray | None:
        """The coefficients its kernel takes: under error control, or with ``fixed`` substeps."""
        return self.fixed_tableau if fixed and self.fixed_tableau is not None else self.tableau

    def evaluations(self, fixed: bool) -> int:
        """Right-hand-side evaluations per substep of a Runge–Kutta pair (the first stage is
        the last substep's end, evaluated once): under error control, or with ``fixed``
        substeps. A substep of ``"taylor"`` is one expansion, counted as one."""
        pair = self.pair(fixed)
        return 1 if pair is None else pair.shape[0] - 3


_SCHEME_LIST = (
    Scheme("rk8", 8, 1.0, True, _rk_chunk, _DOP853, chunk=_rk_chunk, constant=1e-6,
           sweep_exponent=0.75, halvings=3, tol_share=0.1),
    Scheme("rk4", 4, 1.0, True, _rk_chunk, _BS5, fixed_tableau=_RK4, chunk=_rk_chunk,
           constant=0.02, halvings=2, tol_share=0.12),
    Scheme("euler", 1, 0.5, False, _euler_substep, kernel=_euler_kernel, constant=2.0),
    Scheme("midpoint", 2, math.inf, False, _midpoint_substep, kernel=_midpoint_kernel,
           constant=0.3),
    Scheme("taylor", series.ORDER, 1.0, True, _taylor_substep, kernel=_taylor_serial,
           parallel=_taylor_parallel, chunk=_taylor_chunk, constant=1e-6, tol_share=0.01),
    Scheme("dop853", 8, math.inf, True, None),
)
#: The schemes by name.
SCHEMES: dict[str, Scheme] = {s.name: s for s in _SCHEME_LIST}
#: The schemes by name (the ``method`` arguments are its keys).
METHODS = SCHEMES
DEFAULT_METHOD = "taylor"

_KERNELS: dict[str, tuple[Callable, Callable]] = {}


def _kernels(scheme: Scheme) -> tuple[Callable, Callable]:
    """The factory: one compiled kernel per scheme (serial, parallel), made once."""
    if scheme.name not in _KERNELS:
        if scheme.substep is None:
            pair = (_dop853_kernel, _dop853_kernel)
        elif scheme.tableau is not None:
            pair = (_rk_serial, _rk_parallel)
        else:
            pair = (scheme.kernel, scheme.parallel or scheme.kernel)
        _KERNELS[scheme.name] = pair
    return _KERNELS[scheme.name]


def scheme(method: str) -> Scheme:
    """The row of :data:`SCHEMES` called ``method``."""
    try:
        return SCHEMES[method]
    except (KeyError, TypeError):
        raise ValueError(f"unknown integrator {method!r}; allowed: {', '.join(METHODS)}") from None


def _check_step_args(dt: float, tol: float, substeps: int | None) -> None:
    if not (isinstance(dt, int | float | np.floating) and math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt={dt!r} [s] must be finite and > 0")
    if not (isinstance(tol, int | float | np.floating) and math.isfinite(tol) and tol > 0):
        raise ValueError(f"tol={tol!r} must be finite and > 0")
    if substeps is not None and not (
        isinstance(substeps, int | np.integer) and 1 <= substeps <= MAX_SUBSTEPS
    ):
        raise ValueError(
            f"substeps={substeps!r} must be None (automatic) or an integer in [1, {MAX_SUBSTEPS}]"
        )


# -- the steppers -----------------------------------------------------------------------------


class _Base:
    def __init__(self, num: int, method: str, dt: float, tol: float,
                 substeps: int | None) -> None:
        _check_step_args(dt, tol, substeps)
        self.scheme = scheme(method)
        if substeps is not None and self.scheme.substep is None:
            raise ValueError(f"substeps={substeps!r}: method={method!r} chooses its own steps")
        self.method, self.dt, self.tol, self.substeps = method, float(dt), float(tol), substeps
        self._serial, self._parallel = self.scheme.kernels()
        tab = self.scheme.pair(substeps is not None)
        self._tab = tab if tab is not None else np.zeros((1, 1))
        sch = self.scheme
        settings = {"dt": dt, "tol": tol, "substeps": substeps or 0, "halvings": sch.halvings,
                    "order": sch.order, "constant": sch.constant, "stable_step": sch.stable_step,
                    "sweep_exponent": sch.sweep_exponent, "tol_share": sch.tol_share}
        self._cfg = np.array([settings[name] for name in CFG_FIELDS], dtype=float)
        self._io = self._new_io(num)
        self._warned = False

    @staticmethod
    def _new_io(num: int) -> np.ndarray:
        """The zeroed ``io`` table of ``num`` rollers."""
        return np.zeros((len(ROWS), num))

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        # views and kernels, made again on unpickling
        for name in ("_serial", "_parallel", "_kernel", "_flat", "_results"):
            state.pop(name, None)
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._serial, self._parallel = self.scheme.kernels()
        self._link()

    def _link(self) -> None:
        """Views and kernel choices that refer to the buffers (again after unpickling)."""
        self._results = self._io[_OUT:]  # the STEP_FIELDS rows
        self._kernel = self._serial

    @property
    def kernel(self) -> Callable:
        """The compiled kernel ``kernel(io, tableau, cfg)`` a step runs: the scheme's serial
        kernel, or its parallel one for a batch of at least PARALLEL_THRESHOLD rollers (a
        caller fusing more work into the step looks its fused kernel up by it: :meth:`run`)."""
        return self._kernel

    def _warn(self, stacklevel: int) -> None:
        if self.substeps is not None:  # fixed substeps: tol_met informs, no warning
            return
        if not self._warned:
            self._warned = True
            warnings.warn(
                f"tol={self.tol!r} is out of reach for some step (method {self.method!r}, "
                f"dt={self.dt!r}: of float64's rounding, or of the {MAX_SUBSTEPS} substeps a "
                "step may take): those steps report tol_met=False; a looser tol or a more "
                "accurate method avoids this", RuntimeWarning, stacklevel=stacklevel)


@numba.extending.register_jitable
def missed(flat: np.ndarray) -> bool:
    """Whether a Stepper's finished step missed the tolerance, from its ``io`` as one row (a
    view of its one column): a finite step whose tolerance was out of reach. In Python and in
    compiled code (a step that does more than the physics: :meth:`Stepper.bind`)."""
    return flat[_TOL_MET] == 0.0 and flat[_FINITE] != 0.0


@_jit
def _any_missed(io: np.ndarray) -> bool:
    """Whether some roller of a batch's ``io`` missed its tolerance (:func:`missed`)."""
    col, n = 0, io.shape[1]
    while col < n and not missed(io[:, col]):
        col += 1
    return col < n


@numba.extending.register_jitable
def put_inputs(flat: np.ndarray, phi: float, phi_dot: float, tau: float) -> None:
    """Write a Stepper's inputs (φ [rad], φ' [rad/s], τ [N·m]) into its ``io`` as one row, in
    Python and in compiled code."""
    flat[_PHI_IN], flat[_W_IN], flat[_TAU] = phi, phi_dot, tau


class Stepper(_Base):
    """Advances one roller by one control step per call, at the lowest latency.

    Args:
        scene: a scalar :class:`Scene`.
        method: a name of :data:`SCHEMES` (default ``"taylor"``).
        dt: the control step [s].
        tol: the state error allowed per control step (φ in rad, φ' in rad/s).
        substeps: a fixed count of equal substeps instead of the error control.
    """

    def __init__(self, scene: Scene, *, method: str = DEFAULT_METHOD, dt: float, tol: float,
                 substeps: int | None = None) -> None:
        super().__init__(1, method, dt, tol, substeps)
        self._link()
        self.set_scene(scene)

    def _link(self) -> None:
        super()._link()
        self._flat = self._io.reshape(-1)  # a view: row i is element i

    def set_scene(self, scene: Scene) -> None:
        """Use ``scene`` (scalar) from the next step on."""
        if scene.batch_size is not None:
            raise ValueError(f"scene has a batch of {scene.batch_size} rollers; Stepper takes "
                             "a scalar Scene (use BatchStepper for a batch)")
        self._io[: len(SCENE_FIELDS)] = scene_arrays(scene)
        self.forget()

    def forget(self) -> None:
        """Start afresh: the next step predicts its first substep instead of continuing where
        the last one left off. Call it where the state is set rather than stepped (a reset), so
        that an episode's steps do not depend on the episodes before it."""
        self._flat[_H_NEXT] = 0.0

    def run(self, phi: float, phi_dot: float, tau: float, fused: Callable | None = None,
            *extra: Any) -> np.ndarray:
        """One control step from (φ [rad], φ' [rad/s]) at torque τ [N·m]; returns the
        result as a table (:data:`STEP_FIELDS` rows × 1 roller, float64), a view of the
        stepper's buffer, valid until the next call (what the environment reads).

        ``fused``: a compiled kernel run in place of :attr:`kernel`, as for
        :meth:`BatchStepper.run`.
        """
        return self._run(phi, phi_dot, tau, 4, fused, extra)

    def bind(self, one: Callable | None = None,
             *extra: Any) -> Callable[[float, float, float], Any]:
        """A function ``step(φ [rad], φ' [rad/s], τ [N·m])`` with the kernel and buffers
        looked up once, for a caller that steps its roller many times: without ``one``, it
        returns what :meth:`run` does.

        ``one``: a compiled step of this roller that does more than the physics (the single
        environment's: the step, its outcome and what the environment reads back, in one
        call), run as ``one(φ, φ', τ, packed)``, where ``packed`` is the
        :func:`~roller_gym.physics.packed.pack` table of (io, tableau, cfg, *extra): this
        stepper's buffers, then the caller's (unlike :meth:`run`'s ``fused``, which takes
        the arrays themselves). It writes the inputs (:func:`put_inputs`), runs
        :attr:`kernel` and returns a tuple whose first element is :func:`missed`; ``step``
        then returns the rest of the tuple. Its attribute ``arrays`` holds the packed arrays,
        which live as long as it does.
        """
        args = (self._io, self._tab, self._cfg)
        if one is None:
            flat, results, kernel = self._flat, self._results, self._kernel

            def step(phi: float, phi_dot: float, tau: float) -> np.ndarray:
                put_inputs(flat, phi, phi_dot, tau)
                kernel(*args)
                if missed(flat):
                    self._warn(3)  # pointing at the caller of step()
                return results

            return step
        packed = pack(*args, *extra)

        def step_one(phi: float, phi_dot: float, tau: float) -> tuple:
            out = one(phi, phi_dot, tau, packed)
            if out[0]:
                self._warn(3)
            return out[1:]

        step_one.arrays = (*args, *extra)  # the packed table's memory: alive as long as step_one
        return step_one

    def _run(self, phi: float, phi_dot: float, tau: float, stacklevel: int,
             fused: Callable | None = None, extra: tuple = ()) -> np.ndarray:
        flat = self._flat
        put_inputs(flat, phi, phi_dot, tau)
        if fused is None:
            self._kernel(self._io, self._tab, self._cfg)
        else:
            fused(self._io, self._tab, self._cfg, self._results, *extra)
        if missed(flat):
            self._warn(stacklevel)  # pointing at the caller of run() or advance()
        return self._results

    def advance(self, phi: float, phi_dot: float, tau: float) -> tuple:
        """One control step from (φ [rad], φ' [rad/s]) at torque τ [N·m]: the fields of
        :class:`StepResult` in :data:`STEP_FIELDS` order, as Python float, int and bool."""
        (p, w, a, nsub, finite, normal, friction, energy, lift, slip, err,
         met) = self._run(phi, phi_dot, tau, 4)[:, 0].tolist()
        return (p, w, a, int(nsub), finite != 0.0, normal, friction, energy, lift, slip, err,
                met != 0.0)


class BatchStepper(_Base):
    """Advances N rollers by one control step per call (structure of arrays, all cores).

    Args:
        num: the number of rollers.
        method, dt, tol, substeps: as for :class:`Stepper`.

    Set the rollers' scenes with :meth:`set_scenes` before the first :meth:`advance`.
    """

    def __init__(self, num: int, *, method: str = DEFAULT_METHOD, dt: float, tol: float,
                 substeps: int | None = None) -> None:
        if not (isinstance(num, int | np.integer) and num >= 1):
            raise ValueError(f"num={num!r} must be an integer >= 1")
        super().__init__(int(num), method, dt, tol, substeps)
        self.num = int(num)
        self._io[: len(SCENE_FIELDS)] = np.nan  # no scene yet
        self._unset = True  # some roller has no scene (checked where scenes are set)
        self._substeps = np.zeros(self.num, dtype=np.int64)
        self._finite = np.zeros(self.num, dtype=bool)
        self._tol_met = np.zeros(self.num, dtype=bool)
        self._typed = {"substeps": self._substeps, "finite": self._finite,
                       "tol_met": self._tol_met}
        self._link()

    @staticmethod
    def _new_io(num: int) -> np.ndarray:
        """The zeroed ``io`` table, its rows padded (:func:`row_table`)."""
        return row_table(len(ROWS), num)

    def _link(self) -> None:
        if self._io.strides[0] != (self.num + _PAD) * self._io.itemsize:  # unpickled: padded again
            io = self._new_io(self.num)
            io[...] = self._io
            self._io = io
        super()._link()
        self._kernel = self._parallel if self.num >= PARALLEL_THRESHOLD else self._serial

    def set_scenes(self, scene: Scene, index=None) -> None:
        """Put ``scene`` (scalar: broadcast; batch: one roller each) into rows ``index``
        (an index, slice, mask or index array of the rollers; all if None)."""
        rows = np.arange(self.num)[slice(None) if index is None else index]
        size = scene.batch_size
        if size is not None and size != np.size(rows):
            raise ValueError(f"scene has {size} rollers for {np.size(rows)} rows of index")
        self._put_scenes(scene_arrays(scene, np.size(rows)).reshape(
            len(SCENE_FIELDS), *np.shape(rows)), rows)

    def _put_scenes(self, numbers: Any, rows: Any) -> None:
        """Put the scene ``numbers`` (SCENE_FIELDS rows) into the rollers ``rows``."""
        self._io[: len(SCENE_FIELDS), rows] = numbers
        self._unset = self._unset and bool(np.isnan(self._io[_M]).any())
        self.forget(rows)

    def forget(self, index=None) -> None:
        """Start rollers ``index`` (all if None) afresh, as :meth:`Stepper.forget` does."""
        self._io[_H_NEXT, slice(None) if index is None else index] = 0.0

    def scene_table(self) -> np.ndarray:
        """The rollers' scene numbers, shape ``(len(SCENE_FIELDS), num)`` (a view)."""
        return self._io[: len(SCENE_FIELDS)]

    @property
    def parallel(self) -> bool:
        """True if the rollers are advanced in chunks on all cores (``num`` at least
        PARALLEL_THRESHOLD)."""
        return self._kernel is self._parallel

    def run(self, phi: np.ndarray, phi_dot: np.ndarray, tau: np.ndarray,
            fused: Callable | None = None, *extra: Any) -> np.ndarray:
        """One control step of every roller (arrays of ``num``); returns the result as a
        table (:data:`STEP_FIELDS` rows × ``num``, float64), a view of the stepper's buffer,
        valid until the next call.

        ``fused``: a compiled kernel ``fused(io, tableau, cfg, result, *extra)`` to run in
        place of :attr:`kernel`, for a caller that does more work on the rollers right after
        advancing them (while their numbers are in cache): it must advance them as
        :attr:`kernel` does (the same chunks, on the same cores); ``result`` is the returned
        table.
        """
        return self._run(phi, phi_dot, tau, 4, fused, extra)

    def _run(self, phi: np.ndarray, phi_dot: np.ndarray, tau: np.ndarray,
             stacklevel: int, fused: Callable | None = None, extra: tuple = ()) -> np.ndarray:
        io = self._io
        io[_PHI_IN], io[_W_IN], io[_TAU] = phi, phi_dot, tau
        if self._unset:
            raise ValueError("some rollers have no scene: call set_scenes first")
        if fused is None:
            self._kernel(io, self._tab, self._cfg)
        else:
            fused(io, self._tab, self._cfg, self._results, *extra)
        if _any_missed(io):
            self._warn(stacklevel)  # pointing at the caller of run() or advance()
        return self._results

    def advance(self, phi: np.ndarray, phi_dot: np.ndarray, tau: np.ndarray) -> StepResult:
        """One control step of every roller; arrays of ``num``. The result's arrays are views
        of the stepper's own buffers, valid until the next call."""
        io = self._run(phi, phi_dot, tau, 4)
        np.copyto(self._substeps, io[_NSUB - _OUT], casting="unsafe")
        np.not_equal(io[_FINITE - _OUT], 0.0, out=self._finite)
        np.not_equal(io[_TOL_MET - _OUT], 0.0, out=self._tol_met)
        return StepResult(*(self._typed.get(f, row) for f, row in zip(STEP_FIELDS, io,
                                                                       strict=True)))


#: The rows of :func:`contact_state`'s table.
CONTACT_FIELDS = ("phi_ddot", "normal_force", "friction_force", "energy", "liftoff_margin",
                  "slip_margin")


def contact_state(scene: Scene | np.ndarray, phi: np.ndarray, phi_dot: np.ndarray,
                  tau: np.ndarray | float) -> np.ndarray:
    """What holds at states, compiled (the kernels' own loop, which costs one call where the
    same equations on small NumPy arrays cost dozens): a table of :data:`CONTACT_FIELDS` rows
    (φ'' [rad/s²], N [N], F [N], E [J], N/(m g), (μN − |F|)/(m g)) and one column per state.

    Args:
        scene: a scalar scene, or a batch of as many rollers as states, or their numbers
            as :func:`scene_arrays` gives them (one column per state).
        phi, phi_dot: the states (φ [rad], φ' [rad/s]), 1-D arrays of the same length.
        tau: the torque [N·m] (a float, or an array of that length).

    Where a force is not finite (a speed beyond float64's range), the margins are the
    equations' own (NaN where they are undefined), so such a state never passes as rolling.

    Raises:
        ValueError: ``phi_dot``, ``tau`` or the scene's numbers do not have one value per state.
    """
    n = len(phi)
    par = (np.ascontiguousarray(scene, dtype=float) if isinstance(scene, np.ndarray)
           else scene_arrays(scene, n))
    for name, value, shape in (("phi_dot", phi_dot, (n,)), ("tau", tau, (n,)),
                               ("scene", par, (len(SCENE_FIELDS), n))):
        if np.ndim(value) and np.shape(value) != shape:
            raise ValueError(f"{name} has shape {np.shape(value)}; {n} states need {shape}")
    lanes = np.empty((3, n))  # contiguous rows of φ, φ' and τ (broadcast as they are written)
    lanes[0], lanes[1], lanes[2] = phi, phi_dot, tau
    out = np.empty((len(CONTACT_FIELDS), n))
    out[4:] = np.inf  # the loop keeps the smaller of these and each state's margins
    _end_lanes(lanes[0], lanes[1], lanes[2], par, n, out)
    # where a force is not finite, the margins are the equations' own (NaN, not that inf)
    odd = ~(np.isfinite(out[1]) & np.isfinite(out[2]))
    if odd.any():
        with np.errstate(all="ignore"):
            out[4:, odd] = eq.margins(out[1, odd], out[2, odd], par[_M, odd], par[_G, odd],
                                      par[_MU, odd])
    return out


def step(
    scene: Scene,
    phi: float | np.ndarray,
    phi_dot: float | np.ndarray,
    tau: float | np.ndarray,
    dt: float,
    *,
    method: str = DEFAULT_METHOD,
    tol: float = 1e-9,
    substeps: int | None = None,
) -> StepResult:
    """Advance the roller(s) over ``dt`` seconds at constant torque ``tau``.

    Args:
        scene: the scene (scalar, or a batch broadcasting with the state).
        phi: φ [rad], scalar or array.
        phi_dot: φ' [rad/s].
        tau: the drive torque [N·m], constant over the step.
        dt: the control step [s].
        method: a name of :data:`SCHEMES`.
        tol: the state error allowed per control step (φ in rad, φ' in rad/s); for
            ``"dop853"`` its rtol and atol.
        substeps: a fixed number of equal substeps instead of the error control.

    Returns:
        A :class:`StepResult`; arrays of the broadcast shape, or scalars for scalar input.
    """
    _check_step_args(dt, tol, substeps)
    params = (*scene.params, scene.mu)
    scalar = all(np.ndim(x) == 0 for x in (phi, phi_dot, tau, *params))
    arrays = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (phi, phi_dot, tau,
                                                                         *params)))
    shape = arrays[0].shape
    n = max(1, int(np.prod(shape)))
    stepper = BatchStepper(n, method=method, dt=dt, tol=tol, substeps=substeps)
    stepper._put_scenes([a.reshape(-1) for a in arrays[3:]], slice(None))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        out = stepper.advance(*(a.reshape(-1) for a in arrays[:3]))
    if scalar:
        return StepResult(*(_KIND[f](getattr(out, f)[0]) for f in STEP_FIELDS))
    return StepResult(*(np.array(getattr(out, f)).reshape(shape) for f in STEP_FIELDS))


def predicted_substeps(
    scene: Scene, phi_dot: float | np.ndarray, dt: float, tol: float, method: str = DEFAULT_METHOD
) -> np.ndarray | int:
    """The substeps the prediction asks for at speed |φ'|: with λ the sum of

    * ω_max = sqrt(max V'' / min J_I), the linearized frequency at the smallest J_I
      (J_min = m(k² + (r − e)²), V''_max = m g (r²|κ|/s + e)),
    * the rate at which θ sweeps the roller's geometry at speed |φ'|,
      (|φ'|/s)(1 + (re/(k² + (r − e)²))^x) (x the scheme's ``sweep_exponent``),
    * the damping rate c/J_min,

    a scheme of order p takes n = ceil((C (λ dt)^(p+1) / tol)^(1/p)) substeps, and at least
    λ dt / stable_step. The fixed-substep schemes take n; the adaptive ones start from dt/n.
    """
    sch = scheme(method)
    if sch.substep is None:
        raise ValueError(f"method={method!r} chooses its own steps; no prediction is made")
    _check_step_args(dt, tol, None)
    arrays = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (phi_dot, *scene.params)))
    flat = [a.reshape(-1) for a in arrays]
    out = np.array([
        _substeps(abs(v[0]), *v[1:], dt, tol, sch.order, sch.constant, sch.stable_step,
                  sch.sweep_exponent) for v in zip(*flat, strict=True)
    ])
    return int(out[0]) if arrays[0].ndim == 0 else out.reshape(arrays[0].shape)
