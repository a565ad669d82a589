"""Integration over one control step of constant torque, with automatic substepping.

==============  =====  ====================================================================
method          order  what it is for
==============  =====  ====================================================================
``"rk4"``       4      the default: classical Runge–Kutta on (φ, φ')
``"euler"``     1      semi-implicit (symplectic) Euler, the scheme of Gymnasium's Pendulum:
                       kept to show its error (J_I depends on φ, so it is not symplectic
                       here and drifts in energy)
``"midpoint"``  2      implicit midpoint on the canonical pair (φ, p = J_I φ'), solved by
                       Newton's method: symplectic, so its energy error stays bounded over
                       long horizons at zero torque
``"rk8"``       8      the Dormand–Prince 8 tableau at fixed substeps: the fastest at tight
                       tolerances (few substeps), the environments' default
``"dop853"``    8      scipy's adaptive Dormand–Prince 8(5,3): the reference
==============  =====  ====================================================================

**Substeps.** Unless a fixed count is given, the number of substeps per control step is
predicted from the scene's fastest time scale, so that the state error per control step stays
near ``tol``: with λ the sum of

* ω_max = sqrt(max V'' / min J_I), the linearized frequency at the smallest J_I
  (J_min = m(k² + (r − e)²), V''_max = m g (r²|κ|/s + e)),
* the rate at which θ sweeps the roller's geometry at the speed v reached in the step,
  (v/s)(1 + sqrt(re/(k² + (r − e)²))) (the second term: J_I changes over a width
  sqrt((k² + (r − e)²)/(re)) of θ about θ = 0),
* the damping rate c/J_min,

a method of order p takes n = ceil((C (λ dt)^(p+1) / tol)^(1/p)) substeps, and at least
λ dt / h_max, so that each substep stays inside the method's stability region. A step that
would need more than ``MAX_SUBSTEPS`` takes that many and may miss ``tol`` (its
``substeps`` says so): semi-implicit Euler reaches the cap below tol ≈ 1e-6 on the default
scene, and the implicit midpoint on the stiff presets. The count
is first set from the speed at the start of the step; a step whose substeps reach a speed
that asks for more is taken again with that many. An easy scene
takes few, a stiff one as many as it needs (up to ``max_substeps``). With e = 0 the
integrators use :func:`~roller_gym.physics.equations.accel_concentric`, which skips the terms
that vanish.

The kernels are the equations of :mod:`roller_gym.physics.equations`, compiled by numba; one
kernel advances one roller, and the batch loop calls it per element, so a vector of
rollers gives the same numbers as the rollers one at a time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from roller_gym.physics import equations as eq
from roller_gym.physics.scene import Scene
from scipy.integrate import solve_ivp
from scipy.integrate._ivp import dop853_coefficients

__all__ = ["METHODS", "StepResult", "predicted_substeps", "step"]

#: The integration methods and their codes in the compiled kernels.
METHODS = {"rk4": 0, "euler": 1, "midpoint": 2, "dop853": 3, "rk8": 4}
#: The order of each method, by code.
_ORDER = (4, 1, 2, 8, 8)
#: The constant C of the substep rule per method, calibrated against DOP853 on the presets
#: so that the error per control step stays below the tolerance (tests/test_integrators.py).
SUBSTEP_CONSTANT = (0.02, 2.0, 0.3, 0.0, 1e-6)
#: The largest λh each explicit method is allowed per substep (inside its stability region
#: with room to spare); the implicit midpoint is A-stable and needs none.
STABLE_STEP = (1.0, 0.5, math.inf, 0.0, 1.0)
#: How sharply each method feels the dip of J_I at θ = 0: the exponent of
#: re/(k² + (r − e)²) in the sweep rate (the 8th-order tableau needs the dip resolved finer).
SWEEP_EXPONENT = (0.5, 0.5, 0.5, 0.0, 0.75)
# The Dormand–Prince 8(5,3) tableau (scipy's), used at fixed substeps by "rk8".
_A8 = np.ascontiguousarray(dop853_coefficients.A[:12, :12])
_B8 = np.ascontiguousarray(dop853_coefficients.B)
#: The most substeps one control step may take.
MAX_SUBSTEPS = 200_000

_jit = numba.njit(cache=True, fastmath=False, nogil=True)
_accel = eq.accel
_accel_concentric = eq.accel_concentric
_inertia = eq.inertia
_dinertia = eq.dinertia
_d2inertia = eq.d2inertia
_dpotential = eq.dpotential
_d2potential = eq.d2potential


@_jit
def _rhs(phi, w, tau, m, r, kappa, e, k, g, c):
    if e == 0.0:
        return _accel_concentric(phi, w, tau, m, r, kappa, k, g, c)
    return _accel(phi, w, tau, m, r, kappa, e, k, g, c)


@_jit
def _substeps(speed, m, r, kappa, e, k, g, c, dt, tol, method):
    s = 1.0 - r * kappa
    j_min = m * (k * k + (r - e) * (r - e))
    omega = math.sqrt(m * g * (r * r * abs(kappa) / s + e) / j_min)
    sweep = speed / s * (1.0 + (r * e / (k * k + (r - e) * (r - e))) ** SWEEP_EXPONENT[method])
    lam = (omega + sweep + c / j_min) * dt
    order = _ORDER[method]
    n = (SUBSTEP_CONSTANT[method] * lam ** (order + 1) / tol) ** (1.0 / order)
    n = max(n, lam / STABLE_STEP[method])
    if not n < MAX_SUBSTEPS:  # also inf or nan at an absurd speed: the most, not int overflow
        return MAX_SUBSTEPS
    return max(1, math.ceil(n))


@_jit
def _midpoint(phi, w, tau, m, r, kappa, e, k, g, c, h):
    """One implicit-midpoint step on (φ, p = J_I φ'); Newton's method on the midpoint."""
    p0 = _inertia(phi, m, r, kappa, e, k) * w
    pm_phi, pm_p = phi + 0.5 * h * w, p0  # initial guess
    converged = False
    for _ in range(50):
        j = _inertia(pm_phi, m, r, kappa, e, k)
        jp = _dinertia(pm_phi, m, r, kappa, e)
        jpp = _d2inertia(pm_phi, m, r, kappa, e)
        f1 = pm_p / j
        f2 = pm_p * pm_p * jp / (2.0 * j * j) - _dpotential(pm_phi, m, r, kappa, e, g)
        f2 += tau - c * pm_p / j
        g1 = pm_phi - phi - 0.5 * h * f1
        g2 = pm_p - p0 - 0.5 * h * f2
        d11 = 1.0 + 0.5 * h * pm_p * jp / (j * j)
        d12 = -0.5 * h / j
        df2 = pm_p * pm_p * (jpp / (2.0 * j * j) - jp * jp / (j * j * j))
        df2 += -_d2potential(pm_phi, m, r, kappa, e, g) + c * pm_p * jp / (j * j)
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
    return phi1, (2.0 * pm_p - p0) / _inertia(phi1, m, r, kappa, e, k)


@_jit
def _measure(phi, w, a, m, r, kappa, e, g, mu):
    """(N/(m g), (μN − |F|)/(m g)): the lift-off and slip margins at a state."""
    normal, friction = eq.contact_forces(phi, w, a, m, r, kappa, e, g)
    return normal / (m * g), (mu * normal - abs(friction)) / (m * g)


@_jit
def _advance(phi0, w0, tau, m, r, kappa, e, k, g, c, mu, dt, method, tol, fixed, kp, kw):
    """Advance one roller over dt at constant τ.

    Returns ``(φ, φ', φ'', substeps, finite, N, F, E, liftoff, slip)`` at the end of the
    step, where ``liftoff`` and ``slip`` are the smallest margins met at the start of any
    substep and at the end (see :func:`_measure`). With ``fixed`` = 0 the substeps follow
    from the speed at the start; if the step reaches a speed that asks for more, it is
    taken again with as many as that speed asks for, and if it does not stay finite, again
    with twice as many (up to MAX_SUBSTEPS). ``kp``, ``kw``: scratch arrays of 12 for "rk8".
    """
    n = fixed if fixed > 0 else _substeps(abs(w0), m, r, kappa, e, k, g, c, dt, tol, method)
    lift, slip = np.inf, np.inf
    for _attempt in range(12):
        h = dt / n
        phi, w, top = phi0, w0, abs(w0)
        lift, slip = np.inf, np.inf
        for _ in range(n):
            a1 = _rhs(phi, w, tau, m, r, kappa, e, k, g, c)
            lift_i, slip_i = _measure(phi, w, a1, m, r, kappa, e, g, mu)
            lift, slip = min(lift, lift_i), min(slip, slip_i)
            if method == 0:
                w1 = w + 0.5 * h * a1
                a2 = _rhs(phi + 0.5 * h * w, w1, tau, m, r, kappa, e, k, g, c)
                w2 = w + 0.5 * h * a2
                a3 = _rhs(phi + 0.5 * h * w1, w2, tau, m, r, kappa, e, k, g, c)
                w3 = w + h * a3
                a4 = _rhs(phi + h * w2, w3, tau, m, r, kappa, e, k, g, c)
                phi = phi + h * (w + h * (a1 + a2 + a3) / 6.0)
                w = w + h * (a1 + 2.0 * a2 + 2.0 * a3 + a4) / 6.0
            elif method == 4:
                kp[0], kw[0] = w, a1
                for i in range(1, 12):
                    dp, dw = 0.0, 0.0
                    for j in range(i):
                        dp += _A8[i, j] * kp[j]
                        dw += _A8[i, j] * kw[j]
                    kp[i] = w + h * dw
                    kw[i] = _rhs(phi + h * dp, kp[i], tau, m, r, kappa, e, k, g, c)
                dp, dw = 0.0, 0.0
                for i in range(12):
                    dp += _B8[i] * kp[i]
                    dw += _B8[i] * kw[i]
                phi, w = phi + h * dp, w + h * dw
            elif method == 1:
                w = w + h * a1
                phi = phi + h * w
            else:
                phi, w = _midpoint(phi, w, tau, m, r, kappa, e, k, g, c, h)
            if not (math.isfinite(phi) and math.isfinite(w)):
                break
            top = max(top, abs(w))
        finite = math.isfinite(phi) and math.isfinite(w)
        if fixed > 0 or (not finite and n >= MAX_SUBSTEPS):
            break
        needed = _substeps(top, m, r, kappa, e, k, g, c, dt, tol, method) if finite else 2 * n
        if needed <= n:
            break
        n = min(needed, MAX_SUBSTEPS)
    if not (math.isfinite(phi) and math.isfinite(w)):
        return phi0, w0, 0.0, n, False, 0.0, 0.0, 0.0, 0.0, 0.0
    a = _rhs(phi, w, tau, m, r, kappa, e, k, g, c)
    normal, friction = eq.contact_forces(phi, w, a, m, r, kappa, e, g)
    energy = eq.energy(phi, w, m, r, kappa, e, k, g)
    ok = math.isfinite(a) and math.isfinite(energy)
    lift = min(lift, normal / (m * g))
    slip = min(slip, (mu * normal - abs(friction)) / (m * g))
    if not ok:
        return phi0, w0, 0.0, n, False, 0.0, 0.0, 0.0, 0.0, 0.0
    return phi, w, a, n, True, normal, friction, energy, lift, slip


#: The fields of a step's outcome, in the order the kernels return them.
_FIELDS = ("phi", "phi_dot", "phi_ddot", "substeps", "finite", "normal_force",
           "friction_force", "energy", "liftoff_margin", "slip_margin")
_DTYPES = (float, float, float, int, bool, float, float, float, float, float)


@_jit
def _advance_range(lo, hi, phi, w, tau, P, dt, method, tol, fixed, out):
    """Advance rollers lo to hi − 1 of a batch, writing their results into ``out``."""
    kp, kw = np.empty(12), np.empty(12)
    for i in range(lo, hi):
        res = _advance(phi[i], w[i], tau[i], P[i, 0], P[i, 1], P[i, 2], P[i, 3], P[i, 4],
                       P[i, 5], P[i, 6], P[i, 7], dt, method, tol, fixed, kp, kw)
        (out[0, i], out[1, i], out[2, i], out[3, i], out[4, i], out[5, i], out[6, i], out[7, i],
         out[8, i], out[9, i]) = res


#: Rollers per task handed to a core in a parallel batch.
_CHUNK = 256


@numba.njit(cache=True, parallel=True, nogil=True)
def _advance_batch_parallel(phi, w, tau, P, dt, method, tol, fixed, out):
    n = phi.shape[0]
    for chunk in numba.prange((n + _CHUNK - 1) // _CHUNK):
        lo = chunk * _CHUNK
        _advance_range(lo, min(lo + _CHUNK, n), phi, w, tau, P, dt, method, tol, fixed, out)


#: Batches at least this large are advanced on all cores.
PARALLEL_THRESHOLD = 2048


@dataclass(frozen=True)
class StepResult:
    """The outcome of one control step, at its end unless said otherwise.

    Attributes:
        phi: φ [rad].
        phi_dot: φ' [rad/s].
        phi_ddot: φ'' [rad/s²] under the step's torque.
        substeps: substeps taken (for ``"dop853"``, accepted steps).
        finite: False where the step could not stay finite; there φ and φ' are the state
            before the step, unchanged, and the other fields 0.
        normal_force: N [N] (positive: pressing; see ``equations.contact_forces``).
        friction_force: F [N].
        energy: E [J].
        liftoff_margin: the smallest N/(m g) met during the step (<= 0: lift-off).
        slip_margin: the smallest (μN − |F|)/(m g) met during the step (< 0: slip).
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

    @property
    def lifting(self) -> np.ndarray | bool:
        """True where the roller left the surface (N <= 0) during the step."""
        return self.liftoff_margin <= 0

    @property
    def slipping(self) -> np.ndarray | bool:
        """True where the friction needed exceeded μN during the step."""
        return self.slip_margin < 0


def _method_code(method: str) -> int:
    try:
        return METHODS[method]
    except KeyError:
        raise ValueError(
            f"unknown integrator {method!r}; allowed: {', '.join(METHODS)}"
        ) from None


def _check_step_args(dt: float, tol: float, substeps: int | None) -> None:
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt={dt!r} [s] must be finite and > 0")
    if not (math.isfinite(tol) and tol > 0):
        raise ValueError(f"tol={tol!r} must be finite and > 0")
    if substeps is not None and not (isinstance(substeps, int | np.integer) and substeps >= 1):
        raise ValueError(f"substeps={substeps!r} must be None (automatic) or an integer >= 1")


def step(
    scene: Scene,
    phi: float | np.ndarray,
    phi_dot: float | np.ndarray,
    tau: float | np.ndarray,
    dt: float,
    *,
    method: str = "rk4",
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
        method: one of :data:`METHODS`.
        tol: the target state error per control step (φ in rad, φ' in rad/s); sets the
            substeps (or, for ``"dop853"``, its rtol and atol).
        substeps: a fixed number of substeps instead of the automatic rule.

    Returns:
        A :class:`StepResult`; arrays of the broadcast shape, or scalars for scalar input.
    """
    _check_step_args(dt, tol, substeps)
    code = _method_code(method)
    params = (*scene.params, scene.mu)
    scalar = all(np.ndim(x) == 0 for x in (phi, phi_dot, tau, *params))
    arrays = np.broadcast_arrays(
        *(np.asarray(x, dtype=float) for x in (phi, phi_dot, tau, *params))
    )
    shape = arrays[0].shape
    flat = [np.ascontiguousarray(a.reshape(-1)) for a in arrays]
    if code == METHODS["dop853"]:
        out = _dop853(flat[0], flat[1], flat[2], np.stack(flat[3:], axis=1), dt, tol)
    else:
        P = np.ascontiguousarray(np.stack(flat[3:], axis=1))
        n = flat[0].shape[0]
        raw = np.empty((10, n))
        advance_batch(P, flat[0], flat[1], flat[2], dt, code, tol, substeps or 0, raw)
        out = [raw[j].astype(t) for j, t in enumerate(_DTYPES)]
    if scalar:
        return StepResult(*(t(o[0]) for o, t in zip(out, _DTYPES, strict=True)))
    return StepResult(*(o.reshape(shape) for o in out))


def advance_batch(
    rows: np.ndarray, phi: np.ndarray, phi_dot: np.ndarray, tau: np.ndarray, dt: float,
    method: int, tol: float, substeps: int, out: np.ndarray,
) -> None:
    """The fast path of :func:`step` for a batch, arguments already checked.

    ``rows`` is (n, 8): ``(*Scene.params, mu)`` per roller; ``phi``, ``phi_dot``, ``tau``
    are float arrays of n; ``method`` a code of :data:`METHODS` other than DOP853;
    ``substeps`` 0 for automatic. Writes the fields of :class:`StepResult`, in its order,
    into the rows of ``out`` (10, n).
    """
    n = phi.shape[0]
    if n >= PARALLEL_THRESHOLD:
        _advance_batch_parallel(phi, phi_dot, tau, rows, dt, method, tol, substeps, out)
    else:
        _advance_range(0, n, phi, phi_dot, tau, rows, dt, method, tol, substeps, out)


#: Layout of the buffer of :func:`advance_into`: inputs, then the outputs from OUT on.
BUFFER_INPUTS = ("phi", "phi_dot", "tau", "m", "r", "kappa", "e", "k", "g", "c", "mu", "dt",
                 "tol", "method", "substeps")
OUT = len(BUFFER_INPUTS)
BUFFER_SIZE = OUT + 34


@_jit
def advance_into(buf: np.ndarray) -> None:
    """One roller's step with every argument and result in one float array (the fastest call).

    ``buf[:OUT]`` holds :data:`BUFFER_INPUTS` (``method`` a code of :data:`METHODS` other than
    DOP853, ``substeps`` 0 for automatic); the fields of :class:`StepResult`, in its order,
    are written to ``buf[OUT:OUT + 10]``; ``buf[OUT + 10:BUFFER_SIZE]`` is scratch.
    """
    res = _advance(buf[0], buf[1], buf[2], buf[3], buf[4], buf[5], buf[6], buf[7], buf[8],
                   buf[9], buf[10], buf[11], int(buf[13]), buf[12], int(buf[14]),
                   buf[OUT + 10:OUT + 22], buf[OUT + 22:OUT + 34])
    (buf[OUT], buf[OUT + 1], buf[OUT + 2], buf[OUT + 3], buf[OUT + 4], buf[OUT + 5],
     buf[OUT + 6], buf[OUT + 7], buf[OUT + 8], buf[OUT + 9]) = res


def step_one(
    params: tuple[float, ...],
    phi: float,
    phi_dot: float,
    tau: float,
    dt: float,
    method: int,
    tol: float,
    substeps: int = 0,
) -> tuple:
    """The fast path of :func:`step` for one roller, arguments already checked.

    ``params`` is ``(*Scene.params, Scene.mu)`` as floats, ``method`` a code of
    :data:`METHODS` other than DOP853, ``substeps`` 0 for automatic. Returns the fields of
    :class:`StepResult` as a tuple, in its order.
    """
    return _advance(phi, phi_dot, tau, *params, dt, method, tol, substeps, np.empty(12),
                    np.empty(12))


def _dop853(phi, w, tau, P, dt, tol):
    """The reference: scipy's DOP853 on the whole batch as one system (margins at the end)."""
    params = tuple(P[:, i] for i in range(8))
    n = phi.shape[0]

    def rhs(_t, y):
        return np.concatenate((y[n:], eq.accel(y[:n], y[n:], tau, *params[:7])))

    sol = solve_ivp(rhs, (0.0, dt), np.concatenate((phi, w)), method="DOP853", rtol=tol,
                    atol=tol)
    y = sol.y[:, -1]
    ok = np.isfinite(y[:n]) & np.isfinite(y[n:]) & sol.success
    steps = np.full(n, sol.t.size - 1, dtype=np.int64)
    phi1, w1 = np.where(ok, y[:n], phi), np.where(ok, y[n:], w)
    m, r, kappa, e, k, g, c, mu = params
    with np.errstate(all="ignore"):  # where not ok the fields are 0, as in the kernels
        a = eq.accel(phi1, w1, tau, m, r, kappa, e, k, g, c)
        normal, friction = eq.contact_forces(phi1, w1, a, m, r, kappa, e, g)
        energy = eq.energy(phi1, w1, m, r, kappa, e, k, g)
        lift, slip = normal / (m * g), (mu * normal - np.abs(friction)) / (m * g)
    ok = ok & np.isfinite(a) & np.isfinite(energy)
    phi1, w1 = np.where(ok, phi1, phi), np.where(ok, w1, w)
    a, normal, friction, energy, lift, slip = (
        np.where(ok, x, 0.0) for x in (a, normal, friction, energy, lift, slip)
    )
    return phi1, w1, a, steps, ok, normal, friction, energy, lift, slip


def predicted_substeps(
    scene: Scene, phi_dot: float | np.ndarray, dt: float, tol: float, method: str = "rk4"
) -> np.ndarray | int:
    """The substeps the automatic rule asks for at speed |φ'| (see the module docs)."""
    code = _method_code(method)
    if code == METHODS["dop853"]:
        raise ValueError("method='dop853' chooses its own steps; no prediction is made")
    _check_step_args(dt, tol, None)
    arrays = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (phi_dot, *scene.params)))
    flat = [a.reshape(-1) for a in arrays]
    out = np.array(
        [_substeps(abs(v[0]), *v[1:], dt, tol, code) for v in zip(*flat, strict=True)]
    )
    return int(out[0]) if arrays[0].ndim == 0 else out.reshape(arrays[0].shape)
