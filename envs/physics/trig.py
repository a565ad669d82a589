"""Sine, cosine, exp and tanh without branches, so that compiled loops over a batch run in
SIMD lanes.

libm's ``sin`` is a call with branches inside; a loop that calls it stays scalar. These are
the same algorithm as musl's (and FreeBSD's) ``sin``, with every branch replaced by arithmetic:

1. **Range reduction** to y ∈ [−π/4, π/4]: n = round(2x/π) by the float64 rounding trick
   (adding and subtracting 1.5·2⁵², no conversion to an integer), then
   y = x − n·π/2 in double-double arithmetic, with π/2 split into four parts of which the
   first three have 33 significant bits, so that n times each is exact while |n| < 2²⁰.
2. **Kernels**: musl's minimax polynomials for sin and cos on [−π/4, π/4] (degrees 13 and 14),
   with the low part of y as a correction.
3. **Quadrant**: n mod 4 picks ±sin(y) or ±cos(y) by multiplying with 0, 1 or −1, computed
   by the same rounding trick.

Accuracy: within 1 ulp of the exact value for |x| ≤ :data:`EXACT_RANGE` (about 1.6·10⁶
rad; tested against mpmath and ``math.sin``). Beyond it the reduction loses bits gradually:
the absolute error stays below about |x|·2⁻⁵², the size of the rounding of x itself. For
|x| > :data:`DOMAIN` (about 10¹⁵ rad) and for inf the result is NaN.

:func:`sincos` gives both from one reduction and one pair of polynomials, for what one of
them costs: the equation of motion takes two such pairs per evaluation instead of four sines.

:func:`exp` is fdlibm's (FreeBSD's ``e_exp.c``) the same way: x = k·ln 2 + r by the rounding
trick, a rational form in r², and the scaling by 2^k built from its bits (a bitcast, which
SIMD lanes have), in two factors so that subnormal results are rounded once; within 1 ulp,
inf above 709.78 and 0 below −745.13. :func:`tanh` is Cephes' rational form for |x| < 0.625
and 1 − 2/(e^{2|x|} + 1) beyond; within 2 ulp. They are what the rewards and observations
compile to, so that the environments' outcome loop runs in SIMD lanes too (libm's exp and
tanh are calls: 3 and 10 ns an element in a loop, against under 1 and 1.5 ns).

:func:`sin`, :func:`cos`, :func:`sincos`, :func:`exp` and :func:`tanh` have two faces.
Compiled by numba (the simulation's kernels), they are this branch-free form, inlined where
they are called. Called
from Python with float64 numbers or arrays, they run this form compiled (arrays in a compiled
loop: 1.4 ns per element with AVX-512 and 4.7 with AVX2, measured, where NumPy's ``sin``,
which calls libm for float64, takes 14 to 16), so that a number gives the same bits alone,
in an array of any size and in the kernels: a single environment and a batch compute their
episode starts alike. Called from Python with anything else (complex numbers for
complex-step derivatives, intervals, float32) they are NumPy's ``sin``, ``cos``, ``exp`` and
``tanh``, within an ulp or two of the branch-free form.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit, types
from numba.extending import intrinsic, overload, register_jitable
from roller_gym.physics.compiling import INLINED_OPTIONS as _INLINED

__all__ = ["DOMAIN", "EXACT_RANGE", "cos", "exp", "select", "sin", "sincos", "tanh"]

_TOINT = 6755399441055744.0  # 1.5·2⁵²: (v + _TOINT) − _TOINT rounds v to an integer, |v| < 2⁵¹
_INVPIO2 = 6.36619772367581382433e-01  # 2/π
# π/2 = _PIO2_1 + _PIO2_2 + _PIO2_3 + _PIO2_3T (the first three: 33 significant bits)
_PIO2_1 = 1.57079632673412561417e00
_PIO2_2 = 6.07710050630396597660e-11
_PIO2_3 = 2.02226624871116645580e-21
_PIO2_3T = 8.47842766036889956997e-32

_S1 = -1.66666666666666324348e-01
_S2 = 8.33333333332248946124e-03
_S3 = -1.98412698298579493134e-04
_S4 = 2.75573137070700676789e-06
_S5 = -2.50507602534068634195e-08
_S6 = 1.58969099521155010221e-10

_C1 = 4.16666666666666019037e-02
_C2 = -1.38888888888741095749e-03
_C3 = 2.48015872894767294178e-05
_C4 = -2.75573143513906633035e-07
_C5 = 2.08757232129817482790e-09
_C6 = -1.13596475577881948265e-11

#: |x| [rad] up to which the results are within 1 ulp (n·π/2 exact in the reduction).
EXACT_RANGE = 2.0**20 * 1.5707963267948966
#: |x| [rad] beyond which the result is NaN (the rounding trick needs |2x/π| < 2⁵¹).
DOMAIN = 2.0**50


@register_jitable
def _round(v):
    """v rounded to the nearest integer (ties to even), as a float; |v| < 2⁵¹."""
    return (v + _TOINT) - _TOINT


@register_jitable
def _two_diff(a, b):
    """(s, t) with s = fl(a − b) and s + t = a − b exactly."""
    s = a - b
    bb = s - a
    t = (a - (s - bb)) - (b + bb)
    return s, t


def select(cond, a, b):
    """``a`` where ``cond`` else ``b``: elementwise for arrays (NumPy scalars for scalars)."""
    return np.where(cond, a, b)[()]


@overload(select, jit_options={"nogil": True})
def _select_compiled(cond, a, b):
    """The same for numba: a select instruction, which vectorizes (np.where makes an array)."""

    def impl(cond, a, b):
        return a if cond else b

    return impl


@register_jitable
def _reduce(x):
    """(n, y, y_lo): x = n·π/2 + y + y_lo, |y| ≲ π/4, n an integer-valued float (NaN where
    |x| > DOMAIN)."""
    n = _round(x * _INVPIO2)
    r = x - n * _PIO2_1  # exact: n·_PIO2_1 is exact and within a factor 2 of x (or 0)
    hi, lo = _two_diff(r, n * _PIO2_2)
    hi2, lo2 = _two_diff(hi, n * _PIO2_3)
    tail = (lo + lo2) - n * _PIO2_3T
    y = hi2 + tail
    return n, select(np.abs(x) <= DOMAIN, y, np.nan), (hi2 - y) + tail


@register_jitable
def _sin_kernel(y, y_lo):
    """sin(y + y_lo), |y| ≤ π/4 (musl's __sin with its correction for y_lo)."""
    z = y * y
    w = z * z
    r = _S2 + z * (_S3 + z * _S4) + z * w * (_S5 + z * _S6)
    v = z * y
    return y - ((z * (0.5 * y_lo - v * r) - y_lo) - v * _S1)


@register_jitable
def _cos_kernel(y, y_lo):
    """cos(y + y_lo), |y| ≤ π/4 (musl's __cos)."""
    z = y * y
    w = z * z
    r = z * (_C1 + z * (_C2 + z * _C3)) + w * w * (_C4 + z * (_C5 + z * _C6))
    hz = 0.5 * z
    w = 1.0 - hz
    return w + (((1.0 - w) - hz) + (z * r - y * y_lo))


@register_jitable
def _quadrant(n, s, c):
    """sin of n·π/2 + y from s = sin y and c = cos y: s, c, −s, −c for n mod 4 = 0, 1, 2, 3.

    Branch-free: q = n mod 4 and its bits by the rounding trick (no ties arise), then a sum in
    which one product is ±s or ±c and the other ±0.
    """
    q = n - 4.0 * _round((n - 1.5) * 0.25)  # 0, 1, 2, 3
    high = _round((q - 0.5) * 0.5)  # 0, 0, 1, 1
    odd = q - 2.0 * high  # 0, 1, 0, 1
    return (1.0 - 2.0 * high) * (odd * c + (1.0 - odd) * s)


# _sin, _cos and _sincos each spell out the reduction and the kernels: written as _sincos(x)[0],
# sin is one call deeper, and LLVM then leaves it a call in the larger loops (_end_lanes), which
# stop running in SIMD lanes.
def _sin(x):
    """The branch-free sin (plain arithmetic: also evaluates NumPy arrays, for the tests)."""
    n, y, y_lo = _reduce(x)
    return _quadrant(n, _sin_kernel(y, y_lo), _cos_kernel(y, y_lo))


def _cos(x):
    """The branch-free cos."""
    n, y, y_lo = _reduce(x)
    return _quadrant(n + 1.0, _sin_kernel(y, y_lo), _cos_kernel(y, y_lo))


def _sincos(x):
    """(sin x, cos x) from one reduction and one pair of kernels: the cost of one of them."""
    n, y, y_lo = _reduce(x)
    s, c = _sin_kernel(y, y_lo), _cos_kernel(y, y_lo)
    return _quadrant(n, s, c), _quadrant(n + 1.0, s, c)


def sin(x):
    """sin x [x in rad]. From Python: for float64 numbers and arrays the branch-free form,
    compiled (arrays in a loop), as NumPy scalars and arrays; for other types (complex:
    complex-step derivatives) ``np.sin``. Compiled by numba: the branch-free form, inlined.
    Within 1 ulp for |x| ≤ EXACT_RANGE, NaN beyond DOMAIN (the branch-free form)."""
    return _each(_sin_loop, x, 1)[0] if _looped(x) else np.sin(x)


def cos(x):
    """cos x [x in rad], with the faces of :func:`sin`."""
    return _each(_cos_loop, x, 1)[0] if _looped(x) else np.cos(x)


def sincos(x):
    """(sin x, cos x) [x in rad], bit for bit :func:`sin` and :func:`cos`, from one reduction
    and one pair of polynomials: the pair costs what one of them does (the branch-free sin
    evaluates both polynomials anyway). The faces of :func:`sin`: from Python, float64 numbers
    and arrays get the compiled form; anything else gets NumPy's sin and cos."""
    return _each(_sincos_loop, x, 2) if _looped(x) else (np.sin(x), np.cos(x))


def _looped(x) -> bool:
    """Whether a Python caller's x gets the branch-free form, compiled: a float64 number or
    array."""
    t = type(x)
    return (t is np.ndarray and x.dtype == np.float64) or t is float or t is np.float64


def _each(loop, x, outputs: int) -> Any:
    """``loop(flat x, *outs)`` over the elements of x (any shape and strides), into
    ``outputs`` new arrays of x's shape; for a number (or a 0-d array), NumPy scalars."""
    flat = np.ascontiguousarray(x, dtype=np.float64).reshape(-1)
    outs = tuple(np.empty_like(flat) for _ in range(outputs))
    loop(flat, *outs)
    if type(x) is not np.ndarray or x.ndim == 0:
        return tuple(out[0] for out in outs)
    return tuple(out.reshape(x.shape) for out in outs)


@njit(cache=True, nogil=True, error_model="numpy")
def _sin_loop(x, out):
    """out[i] = sin(x[i]), the branch-free form (a loop LLVM runs in SIMD lanes)."""
    for i in range(x.size):
        out[i] = sin(x[i])


@njit(cache=True, nogil=True, error_model="numpy")
def _sincos_loop(x, s, c):
    """s[i], c[i] = sin(x[i]), cos(x[i]), the branch-free form."""
    for i in range(x.size):
        s[i], c[i] = sincos(x[i])


@njit(cache=True, nogil=True, error_model="numpy")
def _cos_loop(x, out):
    """out[i] = cos(x[i]), the branch-free form."""
    for i in range(x.size):
        out[i] = cos(x[i])


# -- exp and tanh ------------------------------------------------------------------------------
# fdlibm's exp (FreeBSD's e_exp.c), its branches replaced by arithmetic: x = k ln2 + r with
# |r| ≤ ln2/2 (k by the rounding trick), exp(r) from a rational form in r², then the product
# with 2^k as two factors 2^k1 · 2^k2 (each a normal number, built from its bits), so that
# results in the subnormal range are rounded once. Within 1 ulp (fdlibm's bound; tested).
_LN2_HI = 6.93147180369123816490e-01  # ln 2 = _LN2_HI + _LN2_LO, _LN2_HI with 32 bits
_LN2_LO = 1.90821492927058770002e-10
_INV_LN2 = 1.44269504088896338700e00
_P1 = 1.66666666666666019037e-01
_P2 = -2.77777777770155933842e-03
_P3 = 6.61375632143793436117e-05
_P4 = -1.65339022054652515390e-06
_P5 = 4.13813679705723846039e-08
#: x is clamped to [_EXP_LOW, _EXP_HIGH] [-]: below, exp underflows to 0; above, to inf.
_EXP_LOW, _EXP_HIGH = -746.0, 710.0
_TOINT_BITS = int(np.array(_TOINT).view(np.int64))


def _bits(x):
    """The bits of float64 x as an int64 (elementwise for arrays)."""
    return np.asarray(x, dtype=np.float64).view(np.int64)[()]


def _from_bits(b):
    """The float64 whose bits are int64 b (elementwise for arrays)."""
    return np.asarray(b, dtype=np.int64).view(np.float64)[()]


@intrinsic
def _bitcast_to_int(typingctx, x):
    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], context.get_value_type(types.int64))

    return types.int64(types.float64), codegen


@intrinsic
def _bitcast_to_float(typingctx, b):
    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], context.get_value_type(types.float64))

    return types.float64(types.int64), codegen


@overload(_bits, jit_options=_INLINED)
def _bits_compiled(x):
    """Compiled: a bitcast (one instruction, in SIMD lanes too)."""
    return lambda x: _bitcast_to_int(x)


@overload(_from_bits, jit_options=_INLINED)
def _from_bits_compiled(b):
    return lambda b: _bitcast_to_float(b)


@register_jitable
def _pow2(shifted):
    """2^j from ``shifted`` = j + 1.5·2⁵² (j an integer in [−1022, 1023]): the integer j is
    in the low bits of shifted, the exponent field of 2^j is j + 1023."""
    return _from_bits((_bits(shifted) - _TOINT_BITS + 1023) << 52)


@register_jitable
def _exp(x):
    """The branch-free exp (plain arithmetic: also evaluates NumPy arrays, for the tests)."""
    xc = select(x != x, x, np.minimum(np.maximum(x, _EXP_LOW), _EXP_HIGH))
    shifted = xc * _INV_LN2 + _TOINT
    k = shifted - _TOINT  # round(x / ln2), in [−1076, 1024]
    hi = xc - k * _LN2_HI  # exact
    lo = k * _LN2_LO
    r = hi - lo
    t = r * r
    c = r - t * (_P1 + t * (_P2 + t * (_P3 + t * (_P4 + t * _P5))))
    y = 1.0 - ((lo - (r * c) / (2.0 - c)) - hi)
    half = _round(k * 0.5 - 0.25)  # floor(k/2): k = k1 + k2, both within the normal range
    return y * _pow2(half + _TOINT) * _pow2((k - half) + _TOINT)


# tanh: for |x| < 0.625 Cephes' rational form x + x³ P(x²)/Q(x²); beyond, 1 − 2/(e^{2|x|} + 1)
# with the sign of x (e^{2|x|} = inf gives ±1).
_TP0, _TP1, _TP2 = -9.64399179425052238628e-1, -9.92877231001918586564e1, -1.61468768441708447952e3
_TQ0, _TQ1, _TQ2 = 1.12811678491632931402e2, 2.23548839060100448583e3, 4.84406305325125486048e3


@register_jitable
def _tanh(x):
    """The branch-free tanh."""
    z = x * x
    small = x + x * z * ((_TP0 * z + _TP1) * z + _TP2) / (((z + _TQ0) * z + _TQ1) * z + _TQ2)
    large = 1.0 - 2.0 / (_exp(2.0 * np.abs(x)) + 1.0)
    small = select(x == 0.0, x, small)  # tanh(−0) = −0
    return select(np.abs(x) < 0.625, small, select(x < 0.0, -large, large))


def exp(x):
    """e^x, with the faces of :func:`sin` (from Python NumPy's exp but for float64)."""
    return _each(_exp_loop, x, 1)[0] if _looped(x) else np.exp(x)


def tanh(x):
    """tanh x, with the faces of :func:`sin` (from Python NumPy's tanh but for float64)."""
    return _each(_tanh_loop, x, 1)[0] if _looped(x) else np.tanh(x)


# Compiled, each function is its branch-free form, inlined (by LLVM: _INLINED) where it is
# called so that the loop that calls it keeps no call (and vectorizes).
def _compiled_as(form):
    """numba's overload of a function of x: its branch-free ``form``."""

    def implementation(x):
        return form

    return implementation


for _face, _form in ((sin, _sin), (cos, _cos), (sincos, _sincos), (exp, _exp), (tanh, _tanh)):
    overload(_face, jit_options=_INLINED)(_compiled_as(_form))


@njit(cache=True, nogil=True, error_model="numpy")
def _exp_loop(x, out):
    """out[i] = exp(x[i]), the branch-free form."""
    for i in range(x.size):
        out[i] = exp(x[i])


@njit(cache=True, nogil=True, error_model="numpy")
def _tanh_loop(x, out):
    """out[i] = tanh(x[i]), the branch-free form."""
    for i in range(x.size):
        out[i] = tanh(x[i])
