"""The step's outcome, one roller at a time: what a step means for the task, compiled.

:func:`outcome_of` turns a roller's step (the integrator's rows and the step's context,
:mod:`roller_gym.episode.record`) into the outputs the kernel computes (``COMPUTED``): the
position error, a :class:`~roller_gym.episode.record.Step` of named quantities handed to the
task's own ``reward(s, k)`` and ``success(s, k)``, and the termination rule (lift-off, slip,
or a step that could not stay finite; a failed step earns nothing). :func:`outcome_range`
runs it over rollers lo..hi−1 block by block in a scratch vector, so that the loop runs in
SIMD lanes, and writes the outcome's tables and the observation. The task's functions and
numbers come in as arguments: :mod:`roller_gym.episode.kernel` compiles these per task.
"""

from __future__ import annotations

import platform

import numba
import numpy as np
from llvmlite import ir as llvm_ir
from numba.core import cgutils
from numba.extending import intrinsic, overload, register_jitable
from roller_gym.episode.record import (
    COMPUTED,
    CONTEXT_FIELDS,
    QUANTITIES,
    STEP_FIELDS,
    C,
    F,
    O,
    S,
    Step,
    rows,
)
from roller_gym.physics import trig
from roller_gym.physics.compiling import INLINED_OPTIONS, inlined
from roller_gym.task import (
    OBSERVATION_FIELDS,
    observation_values,
    position_error,
    state_observation,
    target_observation,
)

__all__ = ["SCRATCH_SIZE", "observe", "outcome_of", "outcome_one", "outcome_range"]

# The kernel works on blocks of rollers in a scratch vector of rows a compile-time number of
# elements apart (_B): the loop that computes the outcome then reads and writes one array at
# fixed offsets, which LLVM can prove free of overlap and runs in SIMD lanes (on the rows of
# the tables, whose distance is known only at run time, it would need an overlap check per pair
# of rows, and gives up). Rows are copied in and out of the scratch by one-row loops.
_B = 136  # a block's rollers and pad: 128 + 8 (rows not a power of two apart)
_BLOCK = 128
#: The step's rows the outcome reads: those of the quantities, whether it finished, its
#: error estimate (the others pass on or are not read).
_STEP_IN = tuple(f for f in STEP_FIELDS if f in QUANTITIES or f in ("finite", "error_estimate"))
#: The scratch's rows: the inputs (those step rows, every context row), the computed outputs,
#: then the observation's fields; named as their rows (``_BR.phi``).
_SCRATCH = (*_STEP_IN, *CONTEXT_FIELDS, *(f"out_{name}" for name in COMPUTED),
            *(f"obs_{name}" for name in OBSERVATION_FIELDS))
_BR = rows("ScratchRows", _SCRATCH)
#: The step's rows copied into the scratch, by their row in the stepper's result.
_STEP_ROWS = tuple(getattr(S, name) for name in _STEP_IN)
_N_STEP_IN, _N_CONTEXT = len(_STEP_IN), len(CONTEXT_FIELDS)
_IN = _N_STEP_IN + _N_CONTEXT  # the first computed row
_OBS = _IN + len(COMPUTED)  # the first observation row
_TARGET_OBS = _OBS + list(OBSERVATION_FIELDS).index("cos_psi_target")  # 5 fields on
#: A scratch's size (elements) for one block.
SCRATCH_SIZE = len(_SCRATCH) * _B
#: The computed outputs' rows: (k, row) with k the output's place in COMPUTED and row its
#: row in the outcome's table, or in its flags.
_TO_TABLE = tuple((k, getattr(O, n)) for k, n in enumerate(COMPUTED) if n in O._fields)
_TO_FLAGS = tuple((k, getattr(F, n)) for k, n in enumerate(COMPUTED) if n in F._fields)
#: The outputs that pass an input row of their name on: (output row, input row).
_PASS_STEP = tuple((getattr(O, n), getattr(S, n)) for n in O._fields
                   if n not in COMPUTED and n in S._fields)
_PASS_CONTEXT = tuple((getattr(O, n), getattr(C, n)) for n in O._fields
                      if n not in COMPUTED and n in C._fields)
_PASS_FLAGS = tuple((getattr(F, n), getattr(S, n)) for n in F._fields
                    if n not in COMPUTED and n in S._fields)
assert len(_TO_TABLE) + len(_TO_FLAGS) == len(COMPUTED)
assert (len(_PASS_STEP) + len(_PASS_CONTEXT) + len(_PASS_FLAGS) + len(COMPUTED)
        == len(O) + len(F))


def _at(table, row, i):
    """Roller i's value in ``row`` of a table: a scratch (1-d, rows _B apart) or a 2-d table
    (interpreted, as ``NUMBA_DISABLE_JIT`` runs it; compiled, the overload below)."""
    return table[row * _B + i] if table.ndim == 1 else table[row, i]


@overload(_at, jit_options=INLINED_OPTIONS)
def _at_overload(table, row, i):
    if table.ndim == 1:
        return lambda table, row, i: table[row * _B + i]
    return lambda table, row, i: table[row, i]


@inlined
def outcome_of(reward, success, k, steps, sr, context, cr, i):
    """Roller i's computed outputs, the values of COMPUTED in order (a flag as 1.0 or 0.0),
    from its step's rows (``steps``, rows ``sr`` by name) and its context (``context``, rows
    ``cr``): a scratch and its rows, or the stepper's result and the context table and
    :data:`~roller_gym.episode.record.S`, :data:`~roller_gym.episode.record.C`. ``reward``
    and ``success`` are the task's functions of (:class:`Step`, ``k``), ``k`` its numbers."""
    phi, phi_dot = _at(steps, sr.phi, i), _at(steps, sr.phi_dot, i)
    failed = _at(steps, sr.finite, i) == 0.0
    lift, slip = _at(steps, sr.liftoff_margin, i), _at(steps, sr.slip_margin, i)
    estimate = _at(steps, sr.error_estimate, i)
    target, rate = _at(context, cr.target_phi, i), _at(context, cr.psi_rate, i)
    error = position_error(phi, target, _at(context, cr.wrap_rate, i), k.symmetric_target)
    s = Step(phi=phi, phi_dot=phi_dot, psi=rate * phi, torque=_at(context, cr.torque, i),
             target_phi=target, target_phi_dot=_at(context, cr.target_phi_dot, i),
             target_torque=_at(context, cr.target_torque, i),
             target_energy=_at(context, cr.target_energy, i), position_error=error,
             energy=_at(steps, sr.energy, i), normal_force=_at(steps, sr.normal_force, i),
             friction_force=_at(steps, sr.friction_force, i), liftoff_margin=lift,
             slip_margin=slip)
    lifting, slipping = lift <= 0.0, slip < 0.0
    return (trig.select(failed, 0.0, reward(s, k)),  # reward: a failed step earns nothing
            trig.select(lifting | slipping | failed, 1.0, 0.0),  # terminated
            s.psi,
            trig.select(lifting, 1.0, 0.0),
            trig.select(slipping, 1.0, 0.0),
            trig.select(failed, 1.0, 0.0),  # nonfinite
            # inf where a finished step has no estimate (NaN from the integrator): info
            # values then compare equal across identical runs (Gymnasium's checker)
            trig.select((estimate != estimate) & (not failed), np.inf, estimate),
            rate * target,  # ψ*
            error,
            # is_success: never on a step that ends the episode by failing
            trig.select(lifting | slipping | failed, 0.0, trig.select(success(s, k), 1.0, 0.0)))


def _put_rows(b, start, values):
    """b[start + j·_B] = values[j] for each j: a tuple into consecutive rows of a scratch
    (interpreted; compiled, the overload below writes it unrolled: a tuple indexed by a loop's
    variable inside the loop over rollers keeps that loop out of SIMD lanes, at 2.5× the
    outcome's cost)."""
    for j, value in enumerate(values):
        b[start + j * _B] = value


@overload(_put_rows, jit_options=INLINED_OPTIONS)
def _put_rows_overload(b, start, values):
    lines = "".join(f"    b[start + {j * _B}] = values[{j}]\n" for j in range(len(values)))
    namespace: dict = {"__name__": __name__}  # the generated function's module: this one
    exec(f"def put_rows(b, start, values):\n{lines}    return None\n", namespace)
    return namespace["put_rows"]


@register_jitable
def _outcome_block(reward, success, k, b, m):
    """The outcome of the block's m rollers in the scratch ``b`` (rows _B apart): from the
    input rows into the computed rows and the observation's rows."""
    for i in range(m):
        _put_rows(b, _IN * _B + i, outcome_of(reward, success, k, b, _BR, b, _BR, i))
        v = _OBS * _B + i
        (b[v], b[v + _B], b[v + 2 * _B], b[v + 3 * _B],
         b[v + 4 * _B]) = state_observation(b[_BR.phi * _B + i], b[_BR.phi_dot * _B + i],
                                            b[_BR.psi_rate * _B + i])
    # the target's fields, for a task that observes them: in a loop of their own, as a branch
    # in the loop above would be made a select, computing them always
    if k.observes_target != 0.0:
        for i in range(m):
            v = _TARGET_OBS * _B + i
            (b[v], b[v + _B], b[v + 2 * _B], b[v + 3 * _B],
             b[v + 4 * _B]) = target_observation(b[_BR.target_phi * _B + i],
                                                 b[_BR.psi_rate * _B + i],
                                                 b[_BR.target_phi_dot * _B + i])


@register_jitable
def outcome_one(reward, success, k, result, context, observed, out, flags, obs):
    """The outcome of a batch of one roller: :func:`outcome_range`'s arithmetic without the
    blocks (the same bits, for a fraction of the cost of copying rows of one)."""
    computed = outcome_of(reward, success, k, result, S, context, C, 0)
    for pair in _TO_TABLE:
        out[pair[1], 0] = computed[pair[0]]
    for pair in _TO_FLAGS:
        flags[pair[1], 0] = computed[pair[0]] != 0.0
    for pair in _PASS_STEP:
        out[pair[0], 0] = result[pair[1], 0]
    for pair in _PASS_FLAGS:
        flags[pair[0], 0] = result[pair[1], 0] != 0.0
    for pair in _PASS_CONTEXT:
        out[pair[0], 0] = context[pair[1], 0]
    _observe_row(obs, 0, result[S.phi, 0], result[S.phi_dot, 0], context, observed)


@inlined
def _observe_row(obs, i, phi, phi_dot, context, observed):
    """Row i of ``obs``: the ``observed`` fields of a roller at φ [rad], φ' [rad/s] under
    column i of ``context``."""
    seen = observation_values(phi, phi_dot, context[C.target_phi, i], context[C.psi_rate, i],
                              context[C.target_phi_dot, i])
    for j in range(observed.size):
        obs[i, j] = seen[observed[j]]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def observe(rows, phi, phi_dot, context, observed, obs):
    """The observation of rollers ``rows`` at φ [rad], φ' [rad/s] under their ``context``:
    what a step ending there writes (the batch of one's :func:`_observe_row`)."""
    for i in rows:
        _observe_row(obs, i, phi[i], phi_dot[i], context, observed)


@inlined
def _copy(dst, dst_start, src, src_start, m):
    """dst[dst_start + i] = src[src_start + i] for i < m, on rows (1-d arrays); the indices
    unsigned, so that no wraparound check keeps the loop out of SIMD lanes."""
    d, s = np.uint64(dst_start), np.uint64(src_start)
    for i in range(np.uint64(m)):
        dst[d + i] = src[s + i]


@inlined
def _copy_flag(dst, dst_start, src, src_start, m):
    """dst[dst_start + i] = src[src_start + i] != 0 for i < m: a row of 1.0/0.0 into a
    boolean row (as :func:`_copy`)."""
    d, s = np.uint64(dst_start), np.uint64(src_start)
    for i in range(np.uint64(m)):
        dst[d + i] = src[s + i] != 0.0


@intrinsic
def _store_streaming(typingctx, row, index, value):
    """row[index] = value (a 1-d array, an unsigned index) as a non-temporal store: a hint to
    the CPU that the line need not be read first nor kept in cache (the outcome's new tables,
    written whole and read, if at all, after the step)."""
    def codegen(context, builder, signature, args):
        rowty, _, valty = signature.args
        array = context.make_array(rowty)(context, builder, args[0])
        ptr = cgutils.get_item_pointer(context, builder, rowty, array, [args[1]],
                                       wraparound=False)
        store = builder.store(context.cast(builder, args[2], valty, rowty.dtype), ptr)
        store.set_metadata("nontemporal", builder.module.add_metadata(
            [llvm_ir.Constant(llvm_ir.IntType(32), 1)]))
        return context.get_dummy_value()

    return numba.types.void(row, index, value), codegen


@intrinsic
def _fence(typingctx):
    """A store fence: the streaming stores before it are seen by every core after it (they
    are weakly ordered otherwise), whatever the threading layer's own ordering. On x86 an
    ``sfence`` (a seq_cst fence compiles to a locked instruction there, which need not wait
    for them); elsewhere a full fence."""
    def codegen(context, builder, signature, args):
        if platform.machine().lower() in ("x86_64", "amd64"):  # numba compiles for its host
            builder.call(cgutils.get_or_insert_function(
                builder.module, llvm_ir.FunctionType(llvm_ir.VoidType(), []),
                "llvm.x86.sse.sfence"), [])
        else:
            builder.fence("seq_cst")
        return context.get_dummy_value()

    return numba.types.void(), codegen


@inlined
def _stream(dst, dst_start, src, src_start, m):
    """:func:`_copy` into a new table's row, by non-temporal stores (followed, once the
    rows are written, by :func:`_fence`)."""
    d, s = np.uint64(dst_start), np.uint64(src_start)
    for i in range(np.uint64(m)):
        _store_streaming(dst, d + i, src[s + i])




@register_jitable
def outcome_range(reward, success, k, lo, hi, result, context, observed, out, flags, obs, b):
    """The outcome of rollers lo..hi−1, block by block in the scratch ``b``
    (:data:`SCRATCH_SIZE` elements). The float rows go out by streaming stores: the tables
    are new (or written whole) every step, and a store that need not first read its cache
    line from memory costs less where the pass is bound by memory (large batches)."""
    for start in range(lo, hi, _BLOCK):
        m = min(_BLOCK, hi - start)
        for j in range(_N_STEP_IN):
            _copy(b, j * _B, result[_STEP_ROWS[j]], start, m)
        for j in range(_N_CONTEXT):
            _copy(b, (_N_STEP_IN + j) * _B, context[j], start, m)
        _outcome_block(reward, success, k, b, m)
        for pair in _TO_TABLE:
            _stream(out[pair[1]], start, b, (_IN + pair[0]) * _B, m)
        for pair in _TO_FLAGS:
            _copy_flag(flags[pair[1]], start, b, (_IN + pair[0]) * _B, m)
        for pair in _PASS_STEP:
            _stream(out[pair[0]], start, result[pair[1]], start, m)
        for pair in _PASS_FLAGS:
            _copy_flag(flags[pair[0]], start, result[pair[1]], start, m)
        for pair in _PASS_CONTEXT:
            _stream(out[pair[0]], start, context[pair[1]], start, m)
        for j in range(observed.size):  # field by field: the inner loop reads one row
            row = np.uint64((_OBS + observed[j]) * _B)
            for i in range(np.uint64(m)):
                obs[np.uint64(start) + i, j] = b[row + i]
    _fence()

