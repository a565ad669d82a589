"""Many arrays handed to a compiled function as one argument.

Calling a numba function from Python costs about 45 ns for each array argument, which it
checks and wraps; a step of the single environment passes ten, more than its physics costs.
:func:`pack` writes the arrays' addresses and shapes into one int64 table, and
:func:`unpack` makes each array again inside the compiled function, at no cost.

The table is valid only while its arrays live: whoever packs them keeps a reference to them
next to the table (as :meth:`~roller_gym.physics.integrators.Stepper.bind` does).
"""

from __future__ import annotations

import numba
import numpy as np
from numba import types
from numba.extending import intrinsic
from roller_gym.physics.compiling import inlined

__all__ = ["pack", "unpack"]

_ADDRESS, _ROWS, _COLUMNS, _STRIDE = range(4)  # the columns of a table: one row per array


def pack(*arrays: np.ndarray) -> np.ndarray:
    """The table of ``arrays`` (each 1-D or 2-D, its last axis contiguous, its rows one after
    another): per array its address, rows (1 for a 1-D array), columns and the distance of
    its rows in elements; ValueError for an array it cannot describe so."""
    table = np.zeros((len(arrays), 4), dtype=np.int64)
    for row, a in zip(table, arrays, strict=True):
        packs = a.ndim in (1, 2) and a.strides[-1] == a.itemsize
        rows, columns = (1, a.shape[0]) if a.ndim == 1 else a.shape if packs else (0, 0)
        stride = columns  # of a single row: never used
        if packs and rows > 1:
            stride, rest = divmod(a.strides[0], a.itemsize)
            packs = rest == 0 and stride >= columns  # not reversed, repeated or overlapping
        if not packs:
            raise ValueError(f"arrays of shape {a.shape} and strides {a.strides} do not pack: "
                             "1-D or 2-D arrays whose last axis is contiguous and whose rows "
                             "follow one another only")
        row[:] = a.ctypes.data, rows, columns, stride
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
