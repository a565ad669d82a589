"""Interval arithmetic with outward rounding, for proofs over boxes of scene parameters.

An :class:`Interval` holds NumPy arrays ``lo`` and ``hi`` (any shape, broadcast like arrays)
and encloses, elementwise, every real value the same expression takes when its inputs range
over their intervals. It supports what :mod:`roller_gym.physics.equations` needs, so those
functions evaluate on intervals unchanged: ``+ − × ÷``, unary minus, ``abs``, ``** 2``, and
the ufuncs ``np.sin``, ``np.cos`` and ``np.sqrt`` (which :mod:`roller_gym.physics.trig` calls
from Python) through ``__array_ufunc__``. Python floats and NumPy numbers or arrays mix in as
exact (degenerate) intervals. ``x * x`` of one Interval object is its square (never
negative), as the equations write squares (``h * h``, ``phi_dot * phi_dot``).

Rounding: each result of ``+ − × ÷ sqrt`` is correctly rounded in float64, so moving each
end one ulp outward (``np.nextafter``) encloses the exact result. ``sin`` and ``cos`` are
NumPy's, which are accurate to a few ulps; their ends move :data:`TRIG_ULPS` ulps outward,
and an extremum (±1) is included wherever a critical point x = π/2 + jπ (sin) or jπ (cos)
may lie inside the argument, with a margin, so a doubtful one widens the result (beyond
10⁶ rad, or over a whole turn, the result is [−1, 1]).
A division by an interval that contains 0 gives NaN ends, as does anything undefined
(0·inf, inf − inf): every comparison with NaN is false, so nothing is proven from them
(sin and cos of them give [−1, 1]). Callers run with NumPy's floating-point warnings
silenced (``np.errstate``), as infinities and NaN are expected here.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np
from roller_gym.physics.scene import shown

__all__ = ["TRIG_ULPS", "Interval"]

#: How many ulps outward the ends of NumPy's sin and cos are moved.
TRIG_ULPS = 4
_INF = math.inf


def _down(x: np.ndarray) -> np.ndarray:
    return np.nextafter(x, -_INF)


def _up(x: np.ndarray) -> np.ndarray:
    return np.nextafter(x, _INF)


class Interval:
    """[lo, hi] elementwise (arrays broadcast together); see the module docs."""

    __slots__ = ("hi", "lo")

    def __init__(self, lo: Any, hi: Any = None) -> None:
        self.lo = np.asarray(lo, dtype=float)
        self.hi = self.lo if hi is None else np.asarray(hi, dtype=float)

    @classmethod
    def hull(cls, values: Any, axis: int = 0) -> Interval:
        """The smallest interval holding every float of ``values`` along ``axis``."""
        values = np.asarray(values, dtype=float)
        return cls(values.min(axis=axis), values.max(axis=axis))

    def __repr__(self) -> str:
        return f"Interval({shown(self.lo)}, {shown(self.hi)})"

    def contains(self, x: Any) -> np.ndarray:
        """Whether lo <= x <= hi, elementwise."""
        return (self.lo <= x) & (x <= self.hi)

    # -- arithmetic ---------------------------------------------------------------------
    def __add__(self, other: Any) -> Interval:
        if isinstance(other, Interval):
            return Interval(_down(self.lo + other.lo), _up(self.hi + other.hi))
        return Interval(_down(self.lo + other), _up(self.hi + other))

    __radd__ = __add__

    def __sub__(self, other: Any) -> Interval:
        if isinstance(other, Interval):
            return Interval(_down(self.lo - other.hi), _up(self.hi - other.lo))
        return Interval(_down(self.lo - other), _up(self.hi - other))

    def __rsub__(self, other: Any) -> Interval:
        return Interval(_down(other - self.hi), _up(other - self.lo))

    def __neg__(self) -> Interval:
        return Interval(-self.hi, -self.lo)

    def __mul__(self, other: Any) -> Interval:
        if other is self:  # x · x, one variable: its square, never negative
            return self ** 2
        if not isinstance(other, Interval):
            if isinstance(other, float | int):
                a, b = self.lo * other, self.hi * other
                return Interval(_down(a), _up(b)) if other >= 0 else Interval(_down(b), _up(a))
            other = Interval(other)
        a, b = self.lo * other.lo, self.lo * other.hi
        c, d = self.hi * other.lo, self.hi * other.hi
        return Interval(_down(np.minimum(np.minimum(a, b), np.minimum(c, d))),
                        _up(np.maximum(np.maximum(a, b), np.maximum(c, d))))

    __rmul__ = __mul__

    def __truediv__(self, other: Any) -> Interval:
        o = _as_interval(other)
        zero = (o.lo <= 0) & (o.hi >= 0)  # no bound: NaN, which proves nothing
        a, b = self.lo / np.where(zero, np.nan, o.lo), self.lo / o.hi
        c, d = self.hi / o.lo, self.hi / o.hi
        return Interval(_down(np.minimum(np.minimum(a, b), np.minimum(c, d))),
                        _up(np.maximum(np.maximum(a, b), np.maximum(c, d))))

    def __rtruediv__(self, other: Any) -> Interval:
        return _as_interval(other) / self

    def __abs__(self) -> Interval:
        low = np.where(self.lo > 0, self.lo, np.where(self.hi < 0, -self.hi, 0.0))
        return Interval(low, np.maximum(-self.lo, self.hi))

    def __pow__(self, n: int) -> Interval:
        if n != 2:
            return NotImplemented
        a = abs(self)
        return Interval(_down(a.lo * a.lo), _up(a.hi * a.hi))

    def sqrt(self) -> Interval:
        lo = np.where(self.lo < 0, np.nan, np.maximum(_down(np.sqrt(self.lo)), 0.0))
        return Interval(lo, _up(np.sqrt(self.hi)))

    def sin(self) -> Interval:
        return _trig(np.sin, self, 0.5)

    def cos(self) -> Interval:
        return _trig(np.cos, self, 0.0)

    # NumPy's ufuncs on intervals (np.sin(x) in trig.sin, ndarray ⊕ Interval, …)
    _UFUNCS: ClassVar[dict[np.ufunc, str]] = {
        np.add: "__add__", np.subtract: "__sub__", np.multiply: "__mul__",
        np.true_divide: "__truediv__", np.negative: "__neg__", np.absolute: "__abs__",
        np.sin: "sin", np.cos: "cos", np.sqrt: "sqrt"}

    def __array_ufunc__(self, ufunc: np.ufunc, method: str, *inputs: Any, **kwargs: Any):
        name = self._UFUNCS.get(ufunc)
        if method != "__call__" or name is None or kwargs:
            return NotImplemented
        first, *rest = (_as_interval(x) for x in inputs)
        return getattr(first, name)(*rest)


def _as_interval(x: Any) -> Interval:
    return x if isinstance(x, Interval) else Interval(x)


def _trig(function, x: Interval, offset: float) -> Interval:
    """sin (offset ½) or cos (offset 0) of an interval: the ends' values widened, and ±1
    where a critical point (offset + j)·π, value (−1)^j, may lie in [lo, hi]."""
    lo, hi = x.lo, x.hi
    a, b = function(lo), function(hi)
    low, high = np.minimum(a, b), np.maximum(a, b)
    low = low - TRIG_ULPS * np.spacing(np.abs(low))
    high = high + TRIG_ULPS * np.spacing(np.abs(high))
    tolerance = 1e-9
    first = np.ceil(lo / np.pi - offset - tolerance)  # the first j with (j + offset)π >= lo
    last = np.floor(hi / np.pi - offset + tolerance)
    some = last >= first
    has_even = some & ((last > first) | (np.mod(first, 2.0) == 0))
    has_odd = some & ((last > first) | (np.mod(first, 2.0) == 1))
    wide = ~(np.abs(lo) <= 1e6) | ~(np.abs(hi) <= 1e6) | (hi - lo >= 2.0 * np.pi)
    high = np.where(has_even | wide, 1.0, np.minimum(high, 1.0))
    low = np.where(has_odd | wide, -1.0, np.maximum(low, -1.0))
    return Interval(low, high)
