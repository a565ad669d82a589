"""Many arrays handed to a compiled function as one argument.

Calling a numba function from Python costs about 45 ns for each array argument, which it
checks and wraps; a step of the single environment passes ten, more than its physics costs.
:func:`pack` writes the arrays' addresses and shapes into one int64 table, and
:func:`unpack` makes each array again inside the compiled function, at no cost.

:func:`pack_row` writes a row of such a table in compiled code too, and :func:`call_packed`
calls a compiled C function with a table through the function's address, a call that LLVM
does not inline into the caller (whose compile stays small).

The table is valid only while its arrays live: whoever packs them keeps a reference to them
next to the table (as :meth:`~roller_gym.physics.integrators.Stepper.bind` does).
"""

from __future__ import annotations

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic, overload, register_jitable
from roller_gym.physics.compiling import inlined

__all__ = ["PACKED_CALL", "call_packed", "pack", "pack_row", "table_at", "unpack"]

_ADDRESS, _ROWS, _COLUMNS, _STRIDE = range(4)  # the columns of a table: one row per array


def _layout_1(a):
    """(rows, columns, row stride [elements], packs) of a 1-D array: its one row."""
    return 1, a.shape[0], a.shape[0], a.strides[0] == a.itemsize


def _layout_2(a):
    """(rows, columns, row stride [elements], packs) of a 2-D array: its last axis contiguous,
    its rows one after another (not reversed, repeated or overlapping)."""
    rows, columns = a.shape[0], a.shape[1]
    stride, rest = a.strides[0] // a.itemsize, a.strides[0] % a.itemsize
    packs = a.strides[1] == a.itemsize
    if rows > 1:
        packs = packs and rest == 0 and stride >= columns
    else:
        stride = columns  # of a single row: never used
    return rows, columns, stride, packs


def _layout(a):
    """(rows, columns, row stride [elements], packs) of array ``a``, as a table row holds it."""
    if a.ndim == 1:
        return _layout_1(a)
    if a.ndim == 2:
        return _layout_2(a)
    return 0, 0, 0, False


@overload(_layout, jit_options={"nogil": True})
def _layout_compiled(a):
    return {1: register_jitable(_layout_1), 2: register_jitable(_layout_2)}.get(a.ndim)


def _address(a):
    """The address of array ``a``'s first element."""
    return a.ctypes.data


@intrinsic
def _address_compiled(typingctx, array):
    def codegen(context, builder, sig, args):
        data = context.make_array(sig.args[0])(context, builder, args[0]).data
        return builder.ptrtoint(data, ir.IntType(64))

    return types.int64(array), codegen


@overload(_address, jit_options={"nogil": True})
def _address_overload(a):
    if isinstance(a, types.Array):
        return lambda a: _address_compiled(a)
    return None


@inlined
def pack_row(table, k, a):
    """Write array ``a`` into row ``k`` of a table (its address, rows, columns and row stride),
    in Python and in compiled code; False if it does not pack (see :func:`pack`)."""
    rows, columns, stride, packs = _layout(a)
    table[k, _ADDRESS], table[k, _ROWS] = _address(a), rows
    table[k, _COLUMNS], table[k, _STRIDE] = columns, stride
    return packs


def pack(*arrays: np.ndarray) -> np.ndarray:
    """The table of ``arrays`` (each 1-D or 2-D, its last axis contiguous, its rows one after
    another): per array its address, rows (1 for a 1-D array), columns and the distance of
    its rows in elements; ValueError for an array it cannot describe so."""
    table = np.zeros((len(arrays), 4), dtype=np.int64)
    for k, a in enumerate(arrays):
        if not pack_row(table, k, a):
            raise ValueError(f"arrays of shape {a.shape} and strides {a.strides} do not pack: "
                             "1-D or 2-D arrays whose last axis is contiguous and whose rows "
                             "follow one another only")
    return table


@intrinsic
def _pointer(typingctx, address, dtype):
    """An int64 address as a pointer to ``dtype`` (a numba type, e.g. ``numba.float64``)."""
    signature = types.CPointer(dtype.dtype)(address, dtype)

    def codegen(context, builder, sig, args):
        return builder.inttoptr(args[0], context.get_value_type(sig.return_type))

    return signature, codegen


@inlined
def unpack(table, k, dtype):
    """Array ``k`` of a :func:`pack` table, of ``dtype`` (a numba type), as a 2-D view of its
    memory (a 1-D array as its one row: ``unpack(table, k, dtype)[0]``). Nothing is checked
    here: ``dtype`` must be the array's own, and ``k`` a row of the table."""
    rows = numba.carray(_pointer(table[k, _ADDRESS], dtype), (table[k, _ROWS], table[k, _STRIDE]))
    return rows[:, :table[k, _COLUMNS]]


#: The C signature of a function :func:`call_packed` calls: (a :func:`pack` table's first
#: element, lo, hi), nothing returned.
PACKED_CALL = types.void(types.CPointer(types.int64), types.int64, types.int64)

_PACKED_CALL_IR = ir.FunctionType(ir.VoidType(), [ir.IntType(64).as_pointer(), ir.IntType(64),
                                                  ir.IntType(64)])


@intrinsic
def call_packed(typingctx, address, table, lo, hi):
    """Call the compiled C function at ``address`` (a ``numba.cfunc`` of :data:`PACKED_CALL`,
    its address given at run time) with ``table`` (a :func:`pack` table), ``lo`` and ``hi``.
    A call through a pointer: LLVM neither inlines nor optimises the callee again into the
    caller, whose compile stays small."""
    if not (isinstance(address, types.Integer) and isinstance(table, types.Array)):
        return None

    def codegen(context, builder, sig, args):
        function = builder.inttoptr(args[0], _PACKED_CALL_IR.as_pointer())
        data = context.make_array(sig.args[1])(context, builder, args[1]).data
        builder.call(function, [builder.bitcast(data, ir.IntType(64).as_pointer()),
                                args[2], args[3]])
        return context.get_dummy_value()

    return types.void(types.int64, table, types.int64, types.int64), codegen


@inlined
def table_at(pointer, count):
    """The :func:`pack` table of ``count`` arrays at ``pointer`` (what a function
    :func:`call_packed` calls receives), as an array."""
    return numba.carray(pointer, (count, 4))
