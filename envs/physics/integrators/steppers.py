"""The steppers: :class:`Stepper` (one roller, the lowest latency) and :class:`BatchStepper`
(N rollers, all cores) advance by one control step per call and carry the controller's
substep size from step to step; :func:`step` (stateless, any broadcast shape),
:func:`contact_state` (forces, energy and margins at states) and :func:`predicted_substeps`.
A step whose tolerance was not verified reports ``tol_met=False`` and the stepper warns once.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from typing import Any

import numba
import numpy as np
from roller_gym.physics import equations as eq
from roller_gym.physics.integrators.layout import (
    _FINITE,
    _G,
    _H_NEXT,
    _KIND,
    _M,
    _MU,
    _NSUB,
    _OUT,
    _PHI_IN,
    _TAU,
    _TOL_MET,
    _W_IN,
    CFG_FIELDS,
    ROWS,
    SCENE_FIELDS,
    STEP_FIELDS,
    StepResult,
    as_row_table,
    check_memory,
    row_table,
    scene_arrays,
)
from roller_gym.physics.integrators.rules import (
    MAX_SUBSTEPS,
    PARALLEL_THRESHOLD,
    _end_lanes,
    _jit,
    _substeps,
)
from roller_gym.physics.integrators.schemes import DEFAULT_INTEGRATOR, _check_step_args, scheme
from roller_gym.physics.packed import pack
from roller_gym.physics.scene import Scene, require_scene, shown, whole_number


class _Base:
    def __init__(self, num: int, integrator: str, dt: float, tolerance: float,
                 substeps: int | None, degree: int | None = None) -> None:
        _check_step_args(dt, tolerance, substeps)
        self.scheme = scheme(integrator)
        if substeps is not None and self.scheme.substep is None:
            raise ValueError(f"substeps={shown(substeps)}: integrator={shown(integrator)} "
                             "chooses its "
                             "own steps")
        if degree is not None and degree not in self.scheme.degrees:
            raise ValueError(f"degree={shown(degree)}: integrator={shown(integrator)} offers "
                             f"{self.scheme.degrees or 'one order only'}")
        self.integrator, self.dt, self.substeps = integrator, float(dt), substeps
        self.tolerance = float(tolerance)
        #: the order the steps run at (for ``"taylor"``, the degree chosen from the tolerance)
        self.degree = self.scheme.degree(self.tolerance) if degree is None else int(degree)
        self._serial, self._parallel = self.scheme.kernels(self.degree)
        tab = self.scheme.pair(substeps is not None)
        self._tab = tab if tab is not None else np.zeros((1, 1))
        sch = self.scheme
        settings = {"dt": dt, "tolerance": tolerance, "substeps": substeps or 0,
                    "halvings": sch.halvings,
                    "order": self.degree, "constant": sch.constant, "stable_step": sch.stable_step,
                    "sweep_exponent": sch.sweep_exponent, "tol_share": sch.tol_share,
                    "propagated_limit": sch.propagated_limit}
        self._cfg = np.array([settings[name] for name in CFG_FIELDS], dtype=float)
        self._io = self._new_io(num)
        self._warned = False

    @staticmethod
    def _new_io(num: int) -> np.ndarray:
        """The zeroed ``io`` table of ``num`` rollers, its rows padded (:func:`row_table`):
        one layout for every stepper, so that a kernel is compiled for one."""
        return row_table(len(ROWS), num)

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        # views and kernels, made again on unpickling
        for name in ("_serial", "_parallel", "_kernel", "_flat", "_results"):
            state.pop(name, None)
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self.__dict__.setdefault("degree", self.scheme.order)  # (pickled before degrees)
        self._serial, self._parallel = self.scheme.kernels(self.degree)
        self._link()

    def _link(self) -> None:
        """Views and kernel choices that refer to the buffers (again after unpickling)."""
        self._io = as_row_table(self._io)  # padded again after unpickling
        self._results = self._io[_OUT:]  # the STEP_FIELDS rows
        self._kernel = self._serial

    @property
    def kernel(self) -> Callable:
        """The compiled kernel ``kernel(io, tableau, cfg)`` a step runs: the scheme's serial
        kernel, or its parallel one for a batch of at least PARALLEL_THRESHOLD rollers (a
        caller fusing more work into the step looks its fused kernel up by it: :meth:`run`)."""
        return self._kernel

    def scene_table(self) -> np.ndarray:
        """The rollers' scene numbers, shape ``(len(SCENE_FIELDS), num)`` (a view)."""
        return self._io[: len(SCENE_FIELDS)]

    def _warn(self, stacklevel: int) -> None:
        if self.substeps is not None:  # fixed substeps: tol_met informs, no warning
            return
        if not self._warned:
            self._warned = True
            warnings.warn(
                f"tolerance={shown(self.tolerance)} is not verified for some step (integrator "
                f"{shown(self.integrator)}, dt={shown(self.dt)}: out of reach of float64's "
                "rounding or "
                f"of the {MAX_SUBSTEPS} substeps a step may take, or its error estimate grew "
                "past it along the step): those steps report tol_met=False; a looser "
                "tolerance or a more accurate integrator avoids this", RuntimeWarning,
                stacklevel=stacklevel)


#: ``num`` of :func:`_check_states` for states of any shape (broadcast together later).
ANY_SHAPE = -1


def _check_states(num: int | None = None, **values: Any) -> None:
    """Raise a ValueError naming the first of ``values`` (φ [rad], φ' [rad/s], τ [N·m]) that
    is not a finite real number (a bool is not one), or not of the shape ``num`` asks for:
    None one number, ANY_SHAPE numbers of any shape, else one or a 1-D array of ``num``."""
    shapes = {None: "a real number", ANY_SHAPE: "real numbers (a number or an array)"}
    for name, value in values.items():
        if np.ma.isMaskedArray(value):
            raise ValueError(f"{name} is a masked array: give plain numbers (the data under a "
                             "mask would be used)")
        array = np.asarray(value) if not isinstance(value, float) else None
        if array is not None and (array.dtype.kind not in "iuf" or (num != ANY_SHAPE and (
                array.ndim > 1 or (num is None and array.ndim)))):
            shape = shapes.get(num, f"a real number or a 1-D array of {num} of them")
            raise ValueError(f"{name}={shown(value)} must be {shape}, not "
                             f"{type(value).__name__}")
        if array is not None and array.ndim and num not in shapes and array.shape != (num,):
            raise ValueError(f"{name} has {array.shape[0]} values for {num} rollers")
        with np.errstate(over="ignore"):  # (a longdouble past float64's range: inf there)
            finite = np.isfinite(value if array is None else array.astype(float)).all()
        if not finite:
            raise ValueError(f"{name}={shown(value)} is not finite (as a float64)")


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
        integrator: a name of :data:`SCHEMES` (default ``"taylor"``).
        dt: the control step [s].
        tolerance: the state error allowed per control step (φ in rad, φ' in rad/s).
        substeps: a fixed count of equal substeps instead of the error control.
        degree: for ``"taylor"``, the degree of its expansion (one of its ``degrees``) in place
            of the one ``tolerance`` chooses (``taylor.degree``).
    """

    def __init__(self, scene: Scene, *, integrator: str = DEFAULT_INTEGRATOR, dt: float,
                 tolerance: float, substeps: int | None = None,
                 degree: int | None = None) -> None:
        super().__init__(1, integrator, dt, tolerance, substeps, degree)
        self._link()
        self.set_scene(scene)

    def _link(self) -> None:
        super()._link()
        self._flat = self._io.reshape(-1)  # a view: row i is element i

    def set_scene(self, scene: Scene) -> None:
        """Use ``scene`` (scalar) from the next step on."""
        scene = require_scene(scene)
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

        Raises:
            ValueError: a state or torque that is not a finite real number.
        """
        if not (isinstance(phi, float) and isinstance(phi_dot, float)
                and isinstance(tau, float) and math.isfinite(phi + phi_dot + tau)):
            _check_states(phi=phi, phi_dot=phi_dot, tau=tau)
        return self._run(phi, phi_dot, tau, 4, fused, extra)

    def bind(self, one: Callable | None = None,
             *extra: Any) -> Callable[[float, float, float], Any]:
        """A function ``step(φ [rad], φ' [rad/s], τ [N·m])`` with the kernel and buffers
        looked up once, for a caller that steps its roller many times: without ``one``, it
        returns what :meth:`run` does.

        ``one``: a compiled step of this roller that does more than the physics (the single
        environment's: the step, its outcome and what the environment reads back, in one
        call), run as ``one(φ, φ', τ, packed, advance)``, where ``packed`` is the
        :func:`~roller_gym.physics.packed.pack` table of (io, tableau, cfg, *extra): this
        stepper's buffers, then the caller's (unlike :meth:`run`'s ``fused``, which takes
        the arrays themselves). It writes the inputs (:func:`put_inputs`), runs
        :attr:`kernel` (with ``advance`` False, :func:`at_rest` instead: the state's own
        fields, no step taken) and returns a tuple whose first element is :func:`missed`;
        ``step`` then returns the rest of the tuple, and its attribute ``start(φ, φ')`` the
        same for no step at zero torque (an episode's start). Its attribute ``arrays`` holds
        the packed arrays, which live as long as it does.
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
            out = one(phi, phi_dot, tau, packed, True)
            if out[0]:
                self._warn(3)
            return out[1:]

        def start(phi: float, phi_dot: float) -> tuple:
            return one(phi, phi_dot, 0.0, packed, False)[1:]

        step_one.start = start
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
        :class:`StepResult` in :data:`STEP_FIELDS` order, as Python float, int and bool.

        Raises:
            ValueError: a state or torque that is not a finite real number.
        """
        # the common case (floats, finite) in a fraction of a microsecond; else the reason
        if not (isinstance(phi, float) and isinstance(phi_dot, float)
                and isinstance(tau, float) and math.isfinite(phi + phi_dot + tau)):
            _check_states(phi=phi, phi_dot=phi_dot, tau=tau)
        (p, w, a, nsub, finite, normal, friction, energy, lift, slip, err,
         met) = self._run(phi, phi_dot, tau, 4)[:, 0].tolist()
        return (p, w, a, int(nsub), finite != 0.0, normal, friction, energy, lift, slip, err,
                met != 0.0)


#: Bytes a BatchStepper holds per roller: its ``io`` rows and the typed result arrays.
BYTES_PER_ROLLER = 8 * len(ROWS) + 10


class BatchStepper(_Base):
    """Advances N rollers by one control step per call (structure of arrays, all cores).

    Args:
        num: the number of rollers.
        integrator, dt, tolerance, substeps, degree: as for :class:`Stepper`.

    Set the rollers' scenes with :meth:`set_scenes` before the first :meth:`advance`.
    """

    def __init__(self, num: int, *, integrator: str = DEFAULT_INTEGRATOR, dt: float,
                 tolerance: float, substeps: int | None = None,
                 degree: int | None = None) -> None:
        if not (whole_number(num) and num >= 1):
            raise ValueError(f"num={shown(num)} must be an integer >= 1")
        check_memory("num", int(num), BYTES_PER_ROLLER)
        super().__init__(int(num), integrator, dt, tolerance, substeps, degree)
        self.num = int(num)
        self._io[: len(SCENE_FIELDS)] = np.nan  # no scene yet
        self._unset = True  # some roller has no scene (checked where scenes are set)
        self._substeps = np.zeros(self.num, dtype=np.int64)
        self._finite = np.zeros(self.num, dtype=bool)
        self._tol_met = np.zeros(self.num, dtype=bool)
        self._typed = {"substeps": self._substeps, "finite": self._finite,
                       "tol_met": self._tol_met}
        self._link()

    def _link(self) -> None:
        super()._link()
        self._kernel = self._parallel if self.num >= PARALLEL_THRESHOLD else self._serial

    def set_scenes(self, scene: Scene, index=None) -> None:
        """Put ``scene`` (scalar: broadcast; batch: one roller each) into rows ``index``
        (an index, slice, mask or index array of the rollers; all if None)."""
        scene = require_scene(scene)
        rows = self._rows(index)
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
        """Start rollers ``index`` (all if None; as for :meth:`set_scenes`) afresh, as
        :meth:`Stepper.forget` does."""
        if isinstance(index, bool | np.bool_):
            self._rows(index)  # names it
        try:  # (an autoreset's: indexed directly, not through _rows)
            self._io[_H_NEXT, slice(None) if index is None else index] = 0.0
        except IndexError:
            self._rows(index)  # names it
            raise

    def _rows(self, index: Any) -> np.ndarray:
        """The rollers ``index`` selects (an index, slice, mask or index array; all if None),
        or a ValueError naming it."""
        if isinstance(index, bool | np.bool_):  # (NumPy reads True as every roller)
            raise ValueError(f"index={shown(index)} does not select rollers: give an integer, a "
                             "slice, a boolean mask of the rollers or an index array")
        try:
            return np.arange(self.num)[slice(None) if index is None else index]
        except IndexError as error:
            raise ValueError(f"index={shown(index)} does not select rollers of the {self.num}: "
                             f"{error}") from None

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

        The arrays are not checked here (a batch's check would cost a pass over them every
        step): a caller's own, such as the vector env's, or :meth:`advance`, which checks.
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
        """One control step of every roller; arrays of ``num`` (or numbers, for all). The
        result's arrays are views of the stepper's own buffers, valid until the next call.

        Raises:
            ValueError: states or torques that are not finite real numbers, or not of ``num``.
        """
        _check_states(self.num, phi=phi, phi_dot=phi_dot, tau=tau)
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
        ValueError: ``phi`` is not a 1-D array, or ``phi_dot``, ``tau`` or the scene's numbers
            do not have one value per state.
    """
    if np.ndim(phi) != 1:
        raise ValueError(f"phi={shown(phi)} must be a 1-D array of states (one φ [rad] each)")
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
    integrator: str = DEFAULT_INTEGRATOR,
    tolerance: float = 1e-9,
    substeps: int | None = None,
    degree: int | None = None,
) -> StepResult:
    """Advance the roller(s) over ``dt`` seconds at constant torque ``tau``.

    Args:
        scene: the scene (scalar, or a batch broadcasting with the state).
        phi: φ [rad], scalar or array.
        phi_dot: φ' [rad/s].
        tau: the drive torque [N·m], constant over the step.
        dt: the control step [s].
        integrator: a name of :data:`SCHEMES`.
        tolerance: the state error allowed per control step (φ in rad, φ' in rad/s); for
            ``"dop853"`` its rtol and atol.
        substeps: a fixed number of equal substeps instead of the error control.
        degree: for ``"taylor"``, as for :class:`Stepper`.

    Returns:
        A :class:`StepResult`; arrays of the broadcast shape, or scalars for scalar input.
    """
    _check_step_args(dt, tolerance, substeps)
    params = (*require_scene(scene).params, scene.mu)
    _check_states(ANY_SHAPE, phi=phi, phi_dot=phi_dot, tau=tau)
    scalar = all(np.ndim(x) == 0 for x in (phi, phi_dot, tau, *params))
    try:
        arrays = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (phi, phi_dot, tau,
                                                                             *params)))
    except ValueError:
        shapes = {n: np.shape(x) for n, x in (("phi", phi), ("phi_dot", phi_dot), ("tau", tau))}
        raise ValueError(f"the shapes {shapes} and the scene's batch of {scene.batch_size} do "
                         "not broadcast together") from None
    shape = arrays[0].shape
    if arrays[0].size == 0:  # no states: a result of their (empty) shape
        return StepResult(*(np.empty(shape, dtype=_KIND[f]) for f in STEP_FIELDS))
    n = int(np.prod(shape))
    stepper = BatchStepper(n, integrator=integrator, dt=dt, tolerance=tolerance, substeps=substeps,
                           degree=degree)
    stepper._put_scenes([a.reshape(-1) for a in arrays[3:]], slice(None))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        out = stepper.advance(*(a.reshape(-1) for a in arrays[:3]))
    if scalar:
        return StepResult(*(_KIND[f](getattr(out, f)[0]) for f in STEP_FIELDS))
    return StepResult(*(np.array(getattr(out, f)).reshape(shape) for f in STEP_FIELDS))


def predicted_substeps(
    scene: Scene, phi_dot: float | np.ndarray, dt: float, tolerance: float,
    integrator: str = DEFAULT_INTEGRATOR,
) -> np.ndarray | int:
    """The substeps the prediction asks for at speed |φ'|: with λ the sum of

    * ω_max = sqrt(max V'' / min J_I), the linearized frequency at the smallest J_I
      (J_min = m(k² + (r − e)²), V''_max = m g (r²|κ|/s + e)),
    * the rate at which θ sweeps the roller's geometry at speed |φ'|,
      (|φ'|/s)(1 + (re/(k² + (r − e)²))^x) (x the scheme's ``sweep_exponent``),
    * the damping rate c/J_min,

    a scheme of order p takes n = ceil((C (λ dt)^(p+1) / tolerance)^(1/p)) substeps, and at least
    λ dt / stable_step. The fixed-substep schemes take n; the adaptive ones start from dt/n.
    """
    sch = scheme(integrator)
    if sch.substep is None:
        raise ValueError(f"integrator={shown(integrator)} chooses its own steps; no prediction "
                         "is made")
    _check_step_args(dt, tolerance, None)
    _check_states(ANY_SHAPE, phi_dot=phi_dot)
    dt, tolerance = float(dt), float(tolerance)
    try:
        arrays = np.broadcast_arrays(*(np.asarray(x, dtype=float)
                                       for x in (phi_dot, *require_scene(scene).params)))
    except ValueError:
        raise ValueError(f"phi_dot of shape {np.shape(phi_dot)} and the scene's batch of "
                         f"{scene.batch_size} do not broadcast together") from None
    flat = [a.reshape(-1) for a in arrays]
    out = np.array([
        _substeps(abs(v[0]), *v[1:], dt, tolerance, sch.order, sch.constant, sch.stable_step,
                  sch.sweep_exponent) for v in zip(*flat, strict=True)
    ])
    return int(out[0]) if arrays[0].ndim == 0 else out.reshape(arrays[0].shape)
