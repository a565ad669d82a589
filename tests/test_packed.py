"""Arrays handed to a compiled function as one table (roller_gym.physics.packed)."""

from __future__ import annotations

import numba
import numpy as np
import pytest
from roller_gym.physics.packed import PACKED_CALL, call_packed, pack, pack_row, table_at, unpack


@numba.njit
def _double_in_place(table):
    """Each packed array doubled through its unpacked view, returned as read there."""
    a = unpack(table, 0, numba.float64)  # 2-D, rows apart by more than their length
    b = unpack(table, 1, numba.float32)  # 2-D, contiguous
    c = unpack(table, 2, numba.int64)[0]  # 1-D
    d = unpack(table, 3, numba.boolean)  # 2-D, one column of a wider table
    for i in range(a.shape[0]):
        for j in range(a.shape[1]):
            a[i, j] *= 2.0
    for i in range(b.shape[0]):
        for j in range(b.shape[1]):
            b[i, j] *= 2.0
    for i in range(c.shape[0]):
        c[i] *= 2
    for i in range(d.shape[0]):
        d[i, 0] = not d[i, 0]
    return a.shape, b.shape, c.shape, d.shape, a[1, 2], c[-1]


def test_unpacked_arrays_are_the_packed_ones_in_place():
    """A compiled function sees each packed array with its shape, dtype and values, and
    writes through to it, and to nothing around it (padding and other columns stay)."""
    rng = np.random.default_rng(0)
    wide = rng.normal(size=(3, 9))
    a = wide[:, :4]  # rows 9 elements apart
    b = rng.normal(size=(2, 5)).astype(np.float32)
    c = np.arange(1, 8, dtype=np.int64)
    flags = rng.random((4, 6)) < 0.5
    d = flags[:, 2:3]
    before = [x.copy() for x in (wide, b, c, flags)]
    shapes_and_values = _double_in_place(pack(a, b, c, d))
    assert shapes_and_values == ((3, 4), (2, 5), (7,), (4, 1), 2 * before[0][1, 2],
                                 2 * before[2][-1])
    expected_wide = before[0].copy()
    expected_wide[:, :4] *= 2
    np.testing.assert_array_equal(wide, expected_wide)  # the pad columns untouched
    np.testing.assert_array_equal(b, 2 * before[1])
    np.testing.assert_array_equal(c, 2 * before[2])
    expected_flags = before[3].copy()
    expected_flags[:, 2] = ~expected_flags[:, 2]
    np.testing.assert_array_equal(flags, expected_flags)  # only column 2 flipped


@pytest.mark.parametrize("array", [
    np.zeros((4, 6))[:, ::2], np.zeros((2, 2, 2)), np.zeros(8)[::2], np.zeros(()),
    np.zeros((4, 6))[::-1], np.broadcast_to(np.zeros(3), (4, 3)),
    np.lib.stride_tricks.as_strided(np.zeros(12), (4, 6), (16, 8)),  # rows overlap
], ids=["columns apart", "3-D", "1-D apart", "0-D", "rows reversed", "rows repeated",
        "rows overlap"])
def test_arrays_that_do_not_pack_are_refused(array):
    """Only 1-D and 2-D arrays whose last axis is contiguous, and whose rows follow one
    another, have a table row."""
    with pytest.raises(ValueError, match="do not pack"):
        pack(np.zeros(3), array)


@numba.njit
def _packed_in_compiled_code(a, b, c, d, address):
    """The table of (a, b, c, d) written in compiled code, and the C function at ``address``
    called on it for rows 1..2."""
    table = np.empty((4, 4), dtype=np.int64)
    ok = (pack_row(table, 0, a), pack_row(table, 1, b), pack_row(table, 2, c),
          pack_row(table, 3, d))
    call_packed(address, table, 1, 3)
    return table, ok


def _scale_rows(pointer, lo, hi):
    """Rows lo..hi−1 of the packed table's first array, times the third array's first value."""
    table = table_at(pointer, 4)
    a, factor = unpack(table, 0, numba.float64), unpack(table, 2, numba.int64)[0, 0]
    for i in range(lo, hi):
        for j in range(a.shape[1]):
            a[i, j] *= factor


def test_a_table_written_in_compiled_code_is_pythons_and_its_c_function_runs_on_it():
    """pack_row in compiled code writes the table pack writes in Python (address, rows,
    columns, row stride); call_packed runs a C function on exactly the rows it is given."""
    rng = np.random.default_rng(1)
    wide = rng.normal(size=(4, 9))
    a, b = wide[:, :5], rng.normal(size=(2, 3)).astype(np.float32)
    c, d = np.array([3, 4], dtype=np.int64), np.zeros((3, 70), dtype=bool)[:, :64]
    before, padding = a.copy(), wide[:, 5:].copy()
    c_function = numba.cfunc(PACKED_CALL)(_scale_rows)
    table, ok = _packed_in_compiled_code(a, b, c, d, c_function.address)
    assert all(ok)
    np.testing.assert_array_equal(table, pack(a, b, c, d))
    np.testing.assert_array_equal(a[[0, 3]], before[[0, 3]])
    np.testing.assert_array_equal(a[1:3], 3 * before[1:3])
    np.testing.assert_array_equal(wide[:, 5:], padding)  # the columns past a: untouched
