"""The compiled outcome of a task, alone and fused with the physics: one room that knows both.

:func:`task_kernels` compiles, per task class, the kernels that run
:mod:`roller_gym.episode.outcome` with the task's own ``reward`` and ``success`` and its
numbers (``Task.constants``): over every roller on one core or on all, and fused with a
scheme's physics kernel into one compiled call per step (a chunk's physics, then its
outcome while the results are in cache). numba caches each per task on disk
(:mod:`roller_gym.kernel_cache` keys it on every source it inlines).
:class:`OutcomeKernel` holds the buffers both environments step with; :func:`outcome` is the
same kernel for floats and arrays.
"""

from __future__ import annotations

import functools
import math
import re
import sys
import types as pytypes
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
from numba.core import types
from numba.extending import overload
from numba.np.unsafe.ndarray import to_fixed_tuple
from roller_gym.episode.outcome import (
    SCRATCH_SIZE,
    observe,
    outcome_one,
    outcome_range,
)
from roller_gym.episode.record import (
    CONTEXT_FIELDS,
    FLAG_ROWS,
    INFO_KEYS,
    INFO_ROW,
    OUTCOME_ROWS,
    STEP_FIELDS,
    C,
    F,
    O,
)
from roller_gym.episode.starts import at_start
from roller_gym.physics.compiling import c_function, inlined, named
from roller_gym.physics.integrators import (
    CHUNK,
    PARALLEL_THRESHOLD,
    ROWS,
    SCHEMES,
    BatchStepper,
    Stepper,
    as_row_table,
    at_rest,
    missed,
    put_inputs,
    row_table,
)
from roller_gym.physics.integrators.taylor_kernel import taylor_kernels
from roller_gym.physics.packed import PACKED_CALL, call_packed, pack_row, table_at, unpack
from roller_gym.task import OBSERVATION_FIELDS

__all__ = ["Outcome", "OutcomeKernel", "TaskKernels", "flag_table", "info_rows", "outcome",
           "result_table", "task_kernels"]

_FIELD_NUMBER = {name: i for i, name in enumerate(OBSERVATION_FIELDS)}


def _numbers(constants, n):
    """The first n numbers of the array ``constants`` as a tuple (compiled: a tuple of a
    size known when compiling, ``n`` a constant)."""
    return tuple(constants[:n])


@overload(_numbers)
def _numbers_overload(constants, n):
    if isinstance(n, types.IntegerLiteral):
        size = n.literal_value
        return lambda constants, n: to_fixed_tuple(constants, size)
    return None


_STEP_ROWS = ROWS.index(STEP_FIELDS[0])  # a stepper's io: its result is the last rows
#: What a single environment's step unpacks, in order (the stepper's io, tableau and cfg,
#: then OutcomeKernel._buffers()): the dtype and dimensions of each, checked when bound.
_ONE_ARRAYS = ((np.float64, 2), (np.float64, 2), (np.float64, 1), (np.float64, 2),
               (np.float64, 1), (np.int64, 1), (np.float64, 2), (np.bool_, 2), (np.float32, 2),
               (np.float64, 1))
_ONE_DTYPES = tuple(dtype for dtype, _ in _ONE_ARRAYS)


@inlined
def _unpack_one(packed):
    """The single environment's buffers from ``packed`` (see :data:`_ONE_ARRAYS`): the
    stepper's io, tableau and cfg, then the context, the task's numbers, the observed fields,
    the outcome's table, flags and observation."""
    d = _ONE_DTYPES  # a 1-D array is its table's row 0
    return (unpack(packed, 0, d[0]), unpack(packed, 1, d[1]), unpack(packed, 2, d[2])[0],
            unpack(packed, 3, d[3]), unpack(packed, 4, d[4])[0], unpack(packed, 5, d[5])[0],
            unpack(packed, 6, d[6]), unpack(packed, 7, d[7]), unpack(packed, 8, d[8]))


@inlined
def _inputs_one(phi, phi_dot, tau, io, context):
    """The single environment's step, before its physics: its roller's inputs and torque
    written (the physics is then the scheme's kernel for one roller, ``Scheme.one``, called
    by its global name: passed in as an argument it doubled the first compile)."""
    put_inputs(io[:, 0], phi, phi_dot, tau)
    context[C.torque, 0] = tau


@inlined
def _outcome_one_roller(reward, success, k, io, context, observed, out, flags, obs):
    """The single environment's step, after its physics: the outcome, and what the
    environment reads back, as :meth:`~roller_gym.physics.integrators.Stepper.bind` takes
    it: (missed, φ [rad], φ' [rad/s], reward, terminated)."""
    outcome_one(reward, success, k, io[_STEP_ROWS:], context, observed, out, flags, obs)
    return (missed(io[:, 0]), out[O.phi, 0], out[O.phi_dot, 0], out[O.reward, 0],
            flags[F.terminated, 0])


# The schemes whose kernels have fused ones. A fused kernel reaches the scheme's through a
# module (in ``sys.modules``), as numba keys a cached kernel on its closure's contents, which
# pickle a module by its name (a compiled function differently in every process): "taylor"'s,
# of each degree, through ``TaylorKernels.namespace``, rk8's through ``_RK_KERNELS``. Each
# holds ``serial``, ``parallel``, ``chunk`` and ``one`` (a roller alone: no chunk's lanes).
_TAYLOR, _RK = SCHEMES["taylor"], SCHEMES["rk8"]
_RK_KERNELS = pytypes.ModuleType(f"{__name__}.rk8")
sys.modules[_RK_KERNELS.__name__] = _RK_KERNELS
(_RK_KERNELS.serial, _RK_KERNELS.parallel), _RK_KERNELS.chunk = _RK.kernels(), _RK.chunk
_RK_KERNELS.one = _RK.one


#: The arrays of a packed table (:data:`_ONE_ARRAYS`: the single environment's, and the
#: parallel fused kernel's).
_PACKED = len(_ONE_ARRAYS)


def _lazy_c_function(function: Callable) -> Callable[[], Any]:
    """A function giving ``function`` compiled as a C function of
    :data:`~roller_gym.physics.packed.PACKED_CALL` (compiled, or loaded from the cache, on
    the first call)."""

    @functools.cache
    def compiled() -> Any:
        return c_function(function, PACKED_CALL, nogil=True, error_model="numpy")

    return compiled


@functools.cache
def _chunk_c(kernels: pytypes.ModuleType) -> Callable[[], Any]:
    """A scheme's physics of rollers lo..hi−1 (``kernels.chunk``), from a packed table, as a
    C function (:func:`_lazy_c_function`)."""

    def chunk_packed(pointer, lo, hi):
        io, tab, cfg = _unpack_one(table_at(pointer, _PACKED))[:3]
        kernels.chunk(io, lo, hi, tab, cfg)

    return _lazy_c_function(chunk_packed)


@numba.njit(cache=True, nogil=True, error_model="numpy", parallel=True)
def _chunks_on_all_cores(addresses, io, tab, cfg, context, constants, observed, out, flags, obs,
                         scratch):
    """One pass over chunks of CHUNK rollers on all cores: each chunk's physics, then its
    outcome, while the chunk's results are in cache; both C functions (``addresses``) of the
    packed table of the arrays. One kernel for every task and scheme: the physics and the
    outcome are compiled on their own, not inlined and optimised again into the parallel
    loop (which made the first vector step of 4,096 rollers cost several seconds more)."""
    table = np.empty((_PACKED, 4), dtype=np.int64)
    pack_row(table, 0, io)
    pack_row(table, 1, tab)
    pack_row(table, 2, cfg)
    pack_row(table, 3, context)
    pack_row(table, 4, constants)
    pack_row(table, 5, observed)
    pack_row(table, 6, out)
    pack_row(table, 7, flags)
    pack_row(table, 8, obs)
    pack_row(table, 9, scratch)
    rollers = io.shape[1]
    for c in numba.prange((rollers + CHUNK - 1) // CHUNK):
        lo, hi = c * CHUNK, min(rollers, (c + 1) * CHUNK)
        call_packed(addresses[0], table, lo, hi)
        call_packed(addresses[1], table, lo, hi)


def _parallel_fused(physics: Callable[[], Any], outcome: Callable[[], Any]) -> Callable:
    """The parallel fused kernel of one scheme's physics and one task's outcome (C functions
    made by :func:`_lazy_c_function`), called as a stepper's fused kernel; its attribute
    ``c_functions()`` gives the two once it has run (none before)."""
    addresses = []

    def fused(io, tab, cfg, result, context, constants, observed, out, flags, obs, scratch):
        if not addresses:
            addresses.append(np.array([physics().address, outcome().address], dtype=np.int64))
        _chunks_on_all_cores(addresses[0], io, tab, cfg, context, constants, observed, out,
                             flags, obs, scratch)

    fused.c_functions = lambda: (physics(), outcome()) if addresses else ()
    return fused


@dataclass(frozen=True)
class TaskKernels:
    """A task's compiled kernels (each compiled at its first call, then cached on disk).

    ``loop`` and ``parallel``: the outcome of every roller on one core or on all, as
    ``(result, context, constants, observed, out, flags, obs, scratch)``, ``result`` laid out
    as a stepper's (:func:`~roller_gym.physics.integrators.row_table`). The serial fused
    kernels call ``loop``, the parallel ones inline its code. ``fused``: the physics and the
    outcome in one call, by the stepper's kernel they run in place of; ``one``: the single
    environment's step, by the stepper's serial kernel, and with ``advance`` False its reset
    (the outcome of the state itself, no step taken: one kernel compiled for both).
    ``add_degree(degree)`` adds those of ``"taylor"`` at a degree other than the default's
    (made where a stepper first runs it: :meth:`for_stepper`)."""

    loop: Callable
    parallel: Callable
    fused: dict[Callable, Callable]
    one: dict[Callable, Callable]
    add_degree: Callable[[int], None]

    def for_stepper(self, stepper: Stepper | BatchStepper) -> TaskKernels:
        """These kernels, with the fused ones of ``stepper``'s degree made."""
        if stepper.integrator == _TAYLOR.name:
            self.add_degree(stepper.degree)
        return self


def kernel_owner(task: type) -> type:
    """The registered class whose kernels ``task`` runs: its furthest registered base with the
    same ``reward``, ``success`` and ``parameters`` (a variant that changes no objective, such
    as one whose scene is drawn per episode, shares its parent's compiled kernels), else
    ``task`` itself."""
    owner = task
    for base in task.__mro__[1:]:
        if ("Constants" in vars(base) and base.reward is task.reward
                and base.success is task.success and base.parameters == task.parameters):
            owner = base
    return owner


@functools.cache
def task_kernels(task: type) -> TaskKernels:
    """The kernels of a task class, specialised to its ``reward``, ``success`` and
    ``Constants`` (see :class:`TaskKernels`); those of :func:`kernel_owner` where it has
    them."""
    owner = kernel_owner(task)
    if owner is not task:
        return task_kernels(owner)
    reward, success, K = task.reward, task.success, task.Constants
    n = len(K._fields)
    jit = functools.partial(numba.njit, cache=True, nogil=True, error_model="numpy")

    # The outcome's code is compiled once per task for the serial kernels, in ``loop``, which
    # they call through ``call_loop`` (a function this module names: see
    # :func:`~roller_gym.physics.compiling.named`). The parallel kernels inline it. The task's
    # numbers cross into a parallel loop as the array (numba rebuilds a tuple that crosses
    # into one by its class's name, which Constants is not in scope under).
    @jit
    def loop(result, context, constants, observed, out, flags, obs, scratch):
        outcome_range(reward, success, K(*_numbers(constants, n)), np.int64(0),
                      result.shape[1], result, context, observed, out, flags, obs, scratch)

    def call_loop(result, context, constants, observed, out, flags, obs, scratch):
        loop(result, context, constants, observed, out, flags, obs, scratch)

    tag = re.sub(r"\W", "_", f"{task.__module__}.{task.__qualname__}")
    call_loop = named(__name__, f"_loop_{tag}", call_loop)

    # The loops over chunks on all cores: each chunk's physics (a scheme's ``chunk``) then its
    # outcome, while the chunk's results are in cache: one parallel pass per step.
    @jit(parallel=True)
    def parallel(result, context, constants, observed, out, flags, obs, scratch):
        rollers = result.shape[1]
        for c in numba.prange((rollers + CHUNK - 1) // CHUNK):
            outcome_range(reward, success, K(*_numbers(constants, n)), c * CHUNK,
                          min(rollers, (c + 1) * CHUNK), result, context, observed, out, flags,
                          obs, np.empty(SCRATCH_SIZE))

    # The outcome of rollers lo..hi−1 as a C function of a packed table, called through its
    # address by the parallel fused kernel (compiled when that kernel is first needed).
    def outcome_packed(pointer, lo, hi):
        io, _, _, context, constants, observed, out, flags, obs = _unpack_one(
            table_at(pointer, _PACKED))
        outcome_range(reward, success, K(*_numbers(constants, n)), lo, hi, io[_STEP_ROWS:],
                      context, observed, out, flags, obs, np.empty(SCRATCH_SIZE))

    outcome_c = _lazy_c_function(outcome_packed)

    # the parallel fused kernels leave ``scratch`` unused (a chunk's is its own), as
    # ``parallel`` does
    fused: dict[Callable, Callable] = {}
    ones: dict[Callable, Callable] = {}

    def add(kernels: pytypes.ModuleType) -> None:
        """The fused kernels of the scheme whose kernels ``kernels`` holds."""

        @jit
        def then_outcome(io, tab, cfg, result, context, constants, observed, out, flags, obs,
                         scratch):
            kernels.serial(io, tab, cfg)
            call_loop(result, context, constants, observed, out, flags, obs, scratch)

        @jit
        def one_roller(phi, phi_dot, tau, packed, advance):
            io, tab, cfg, context, constants, observed, out, flags, obs = _unpack_one(packed)
            _inputs_one(phi, phi_dot, tau, io, context)
            if advance:
                kernels.one(io, tab, cfg)
            else:
                at_rest(io, 0)
            return _outcome_one_roller(reward, success, K(*_numbers(constants, n)), io,
                                       context, observed, out, flags, obs)

        fused[kernels.parallel] = _parallel_fused(_chunk_c(kernels), outcome_c)
        fused[kernels.serial], ones[kernels.serial] = then_outcome, one_roller

    degrees: set[int] = set()

    def add_degree(degree: int) -> None:
        if degree not in degrees:
            degrees.add(degree)
            add(taylor_kernels(degree).namespace)

    add(_RK_KERNELS)
    add_degree(_TAYLOR.order)  # the default's, made with the task's kernels
    return TaskKernels(loop, parallel, fused, ones, add_degree)


def _outcome_interpreted(task: type, result: np.ndarray, context: np.ndarray,
                         constants: np.ndarray, observed: np.ndarray, out: np.ndarray,
                         flags: np.ndarray, obs: np.ndarray, scratch: np.ndarray) -> None:
    """``loop`` of a task for one roller, interpreted (``NUMBA_DISABLE_JIT``): the same bits."""
    outcome_one(task.reward, task.success, task.Constants(*constants), result, context,
                observed, out, flags, obs)


@dataclass
class Outcome:
    """Reward, flags, info and observation of a step (arrays of rollers, or scalars where
    every input was a scalar)."""

    reward: Any
    terminated: Any
    info: dict[str, Any]
    observation: np.ndarray
    #: all of it as the kernel's table (OUTCOME_ROWS × rollers, float64; rollers flattened)
    table: np.ndarray
    #: and its flags (FLAG_ROWS × rollers, bool; rollers flattened)
    flags: np.ndarray


class OutcomeKernel:
    """The step's outcome for a fixed set of rollers, into buffers of its own: what both
    environments call once per step (and per reset).

    ``table`` (``OUTCOME_ROWS`` × rollers, float64), ``flags`` (``FLAG_ROWS`` × rollers,
    bool), ``observation`` (rollers × the task's observation size, float32) and ``context``
    (``CONTEXT_FIELDS`` × rollers, for the caller to fill) are its buffers; :meth:`run`
    overwrites the first three. With ``fresh``, every run writes a new ``table``, ``flags``
    and ``observation`` instead, which the caller may then hand out (see :func:`info_rows`).
    Its kernel is ``loop``, or ``parallel`` for at least PARALLEL_THRESHOLD rollers unless
    ``serial`` (the outcome of episodes' starts: one kernel for any number, the one the serial
    fused kernels call).
    """

    def __init__(self, task: Any, num: int, fresh: bool = False, serial: bool = False) -> None:
        self._task_class = type(task)
        self.constants = np.array(task.constants, dtype=float)
        self.observed = np.array([_FIELD_NUMBER[f] for f in task.observation],
                                 dtype=np.int64)
        self.context = row_table(len(CONTEXT_FIELDS), num)
        self.table = row_table(len(OUTCOME_ROWS), num)
        self.flags = flag_table(num)
        self.observation = np.empty((num, self.observed.size), dtype=np.float32)
        self.fresh = fresh
        self._parallel = num >= PARALLEL_THRESHOLD and not serial
        self._link()
        self._scratch = np.empty(0 if self._parallel else SCRATCH_SIZE)

    def _link(self) -> None:
        """The kernels, looked up by the task's class (again after unpickling: they are this
        process's)."""
        self.kernels = task_kernels(self._task_class)
        self._kernel = self.kernels.parallel if self._parallel else self.kernels.loop
        if self.table.shape[1] == 1 and numba.config.DISABLE_JIT:  # (loop's streaming stores
            # run compiled only)
            self._kernel = functools.partial(_outcome_interpreted,
                                             kernel_owner(self._task_class))

    def run(self, result: np.ndarray) -> np.ndarray:
        """The outcome of the rollers' ``result`` (STEP_FIELDS rows × rollers, float64, laid
        out as a stepper's: :func:`result_table`; another layout compiles the kernels again)
        under the context in :attr:`context`; returns :attr:`table`."""
        self._renew()
        self._kernel(result, *self._buffers())
        return self.table

    def step(self, stepper: Stepper | BatchStepper, phi: Any, phi_dot: Any,
             tau: Any) -> np.ndarray:
        """A control step of the rollers (``stepper``'s, a Stepper or a BatchStepper, from φ
        [rad] and φ' [rad/s] under τ [N·m]) and its outcome, as :meth:`run` on
        ``stepper.run``'s result; in one compiled call where the stepper's kernel has a fused
        kernel (on all cores: one pass over chunks of rollers). Returns :attr:`table`."""
        fused = self.kernels.for_stepper(stepper).fused.get(stepper.kernel)
        if fused is None:
            return self.run(stepper.run(phi, phi_dot, tau))
        self._renew()
        stepper.run(phi, phi_dot, tau, fused, *self._buffers())
        return self.table

    def observe(self, phi: np.ndarray, phi_dot: np.ndarray, rows: np.ndarray,
                obs: np.ndarray) -> None:
        """Write into ``obs`` (rollers × fields, float32) the observation of rollers ``rows``
        at φ [rad], φ' [rad/s] under :attr:`context`, as a step ending there gives it."""
        observe(rows, phi, phi_dot, self.context, self.observed, obs)

    def bind(self, stepper: Stepper) -> Callable[[float, float, float], tuple]:
        """:meth:`step` for one Stepper, with the kernels and buffers looked up once: a
        function ``step(φ [rad], φ' [rad/s], τ [N·m])`` for the single environment, which
        also writes τ into :attr:`context` and returns what the environment reads back:
        (φ [rad], φ' [rad/s], reward, terminated) as Python float and bool. Its attribute
        ``start(φ, φ')`` writes the outcome of an episode's start at that state instead (zero
        torque, no step taken). One compiled call each where the stepper's kernel has one
        (:attr:`TaskKernels.one`; not with ``NUMBA_DISABLE_JIT``, where nothing is compiled to
        unpack its arrays). Not for ``fresh`` buffers, which every step renews."""
        if self.fresh:
            raise ValueError("a fresh OutcomeKernel renews its buffers every step: use step()")
        one = self.kernels.for_stepper(stepper).one.get(stepper.kernel)
        if one is not None and not numba.config.DISABLE_JIT:  # (interpreted: two calls)
            step = stepper.bind(one, *self._buffers())
            kinds = tuple((a.dtype.type, a.ndim) for a in step.arrays)
            assert kinds == _ONE_ARRAYS, f"the one-roller kernels would misread {kinds}"
            return step
        advance, torque = stepper.bind(), self.context[C.torque]
        table, flags = self.table[:, 0], self.flags[:, 0]

        def step(phi: float, phi_dot: float, tau: float) -> tuple:
            torque[0] = tau
            self.run(advance(phi, phi_dot, tau))
            row = table.tolist()
            return row[O.phi], row[O.phi_dot], row[O.reward], bool(flags[F.terminated])

        def start(phi: float, phi_dot: float) -> None:
            torque[0] = 0.0
            self.run(result_table(at_start(stepper.scene_table(), np.array([phi]),
                                           np.array([phi_dot])), (1,)))

        step.start = start
        return step

    def _buffers(self) -> tuple[np.ndarray, ...]:
        """What the kernels take after the step's result: the context, the task's numbers, the
        outcome's buffers and the scratch."""
        return (self.context, self.constants, self.observed, self.table, self.flags,
                self.observation, self._scratch)

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        for name in ("kernels", "_kernel"):  # this process's, found again by the task's class
            del state[name]
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        # Pickling copies a padded table into a compact one: pad it again, so that the kernels
        # run the layout they were compiled (and cached) for, not a second one.
        for name in ("context", "table"):
            state[name] = as_row_table(state[name])
        flags = state["flags"]
        state["flags"] = flag_table(flags.shape[1])
        state["flags"][...] = flags
        self.__dict__.update(state)
        self._link()

    def _renew(self) -> None:
        if self.fresh:
            self.table = row_table(*self.table.shape, zeroed=False)
            self.flags = flag_table(self.flags.shape[1])
            self.observation = np.empty_like(self.observation)


def outcome(task: Any, result: Any, context: Mapping[str, Any]) -> Outcome:
    """What a step means for the task: the termination rule, the reward, the info and the
    observation (the environments run the same kernel through :class:`OutcomeKernel`).

    ``result`` is the integrator's StepResult (floats or arrays); ``context`` the step's
    context by name (every name of :data:`~roller_gym.episode.record.CONTEXT_FIELDS`: the
    torque, the target and what follows from it, :func:`~roller_gym.episode.starts.target_terms`,
    the rates of :mod:`roller_gym.task`). The step terminates on lift-off, slip or a step that
    could not stay finite, each flagged in the info; a failed step earns no reward.
    """
    values = [getattr(result, f) for f in STEP_FIELDS]
    missing = set(CONTEXT_FIELDS) - set(context)
    if missing:
        raise ValueError(f"context lacks {sorted(missing)}; it takes {', '.join(CONTEXT_FIELDS)}")
    context = [context[name] for name in CONTEXT_FIELDS]
    shape = np.broadcast(*values, *context).shape
    n = math.prod(shape)
    kernel = OutcomeKernel(task, n, serial=True)
    context_rows = kernel.context.reshape(len(context), *shape)
    for row, value in enumerate(context):  # broadcast as they are written
        context_rows[row] = value
    kernel.run(result_table(result, shape))
    rows = info_rows(kernel.table, kernel.flags, tuple(INFO_KEYS), views=True)  # this call's
    scalar = shape == ()
    info = {k: v[0] if scalar else v if v.shape == shape else v.reshape(shape)
            for k, v in rows.items()}
    reward, terminated = kernel.table[O.reward], kernel.flags[F.terminated]
    if scalar:
        return Outcome(reward[0], terminated[0], info, kernel.observation[0], kernel.table,
                       kernel.flags)
    return Outcome(reward.reshape(shape), terminated.reshape(shape), info,
                   kernel.observation.reshape(*shape, -1), kernel.table, kernel.flags)


def result_table(result: Any, shape: tuple[int, ...] = ()) -> np.ndarray:
    """``result`` (a StepResult or a :class:`RestState`, of floats or arrays broadcast to
    ``shape``) as a stepper's result table: STEP_FIELDS rows × the rollers of ``shape``
    (flattened), float64, laid out as a stepper's
    (:func:`~roller_gym.physics.integrators.row_table`), so that the kernels that read a
    stepper's result are compiled for one layout."""
    table = row_table(len(STEP_FIELDS), math.prod(shape), zeroed=False)
    rows = table.reshape(len(STEP_FIELDS), *shape)  # a view: splits each row
    assert np.shares_memory(rows, table)
    for row, field in enumerate(STEP_FIELDS):
        rows[row] = getattr(result, field)  # broadcast as it is written
    return table


def flag_table(n: int) -> np.ndarray:
    """A boolean table of FLAG_ROWS rows of ``n`` rollers (zeroed), rows a cache line more
    than ``n`` apart (as :func:`~roller_gym.physics.integrators.row_table`)."""
    return np.zeros((len(FLAG_ROWS), n + 64), dtype=bool)[:, :n]


def info_rows(table: np.ndarray, flags: np.ndarray, keys: tuple[str, ...],
              views: bool = False, only: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """The info arrays of ``keys`` from an outcome's ``table`` and ``flags``, each of its
    INFO_KEYS type: new arrays, or with ``views`` the float and boolean rows themselves (for
    tables never written again); with ``only`` (column indices), new arrays of those columns'
    values and 0 (False) in the others, as Gymnasium's vector infos leave unmasked entries."""
    info = {}
    for key in keys:
        kind = INFO_KEYS[key][0]
        row = (flags if kind is bool else table)[INFO_ROW[key]]
        if only is not None:
            info[key] = np.zeros(row.shape, dtype=kind)
            info[key][only] = row[only]
        else:
            info[key] = row if views and kind is not int else row.astype(kind)
    return info

