"""One rule for every argument, and the limits of what can be integrated.

* Floats are real numbers: Python or NumPy, not ``bool``, not strings, not complex.
* Counts are integers: Python or NumPy, not ``bool``.
* Anything else is refused with a ``ValueError`` naming the argument, the value, what was
  wrong and what is allowed.

:func:`check_integrable` states the limits of a scene and a control step that the
integrators can follow in float64; the environments call it at construction, so that a
setting that cannot work fails there and not at a random step later.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import fields
from typing import Any

import numba
import numpy as np
from roller_gym.physics import Scene
from roller_gym.physics.scene import finite_real, shown, whole_number

__all__ = ["actions", "check_integrable", "choice", "count", "integration_magnitudes",
           "integration_rates", "ranges", "real", "subset"]

_REAL = (int, float, np.integer, np.floating)
#: The largest magnitude [SI] of the scene's derived quantities (m g r, …): squares stay finite.
LARGEST = 1e100
#: The smallest magnitude [SI] of those quantities: squares stay normal numbers.
SMALLEST = 1e-100
#: The largest ω_max·dt: the scene's fastest linear oscillation, or the torque's spin-up,
#: over one control step (the adaptive integrators take a few substeps per radian of it).
LARGEST_PHASE_PER_STEP = 1e4


def real(name: str, value: Any, *, positive: bool = False, nonnegative: bool = False,
         unit: str = "") -> float:
    """``value`` (a number, or an array of one: 0-d) as a finite float, or ValueError naming
    ``name``."""
    allowed = "a finite real number" + (" > 0" if positive else " >= 0" if nonnegative else "")
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]  # its NumPy scalar
    if not isinstance(value, _REAL) or isinstance(value, bool | np.bool_ | np.timedelta64):
        raise ValueError(f"{name}={shown(value)} is not allowed: it must be {allowed}"
                         f"{f' [{unit}]' if unit else ''} (a Python or NumPy number, not "
                         f"{type(value).__name__})")
    if not finite_real(value) or (positive and float(value) <= 0) or (
            nonnegative and float(value) < 0):
        raise ValueError(f"{name}={shown(value)} is out of range: it must be {allowed}"
                         f"{f' [{unit}]' if unit else ''}")
    return float(value)


#: The fields a ``randomize`` range may name (the Scene's own names).
_SCENE_NAMES = tuple(f.name for f in fields(Scene))


def ranges(name: str, value: Any) -> dict[str, tuple[float, float]]:
    """``value``, a mapping ``{field: (low, high)}`` of Scene fields to pairs of finite reals
    with low <= high, as a dict of float pairs; or ValueError naming ``name``."""
    if not isinstance(value, Mapping):
        raise ValueError(f"{name}={shown(value)} is not allowed: it must be a mapping "
                         "{field: (low, high)} of Scene fields, e.g. {'m': (0.8, 1.2)}")
    checked: dict[str, tuple[float, float]] = {}
    for field, bounds in value.items():
        if field not in _SCENE_NAMES:
            raise ValueError(f"{name} names {shown(field)}, not a Scene field; allowed: "
                             f"{', '.join(_SCENE_NAMES)}")
        if not (isinstance(bounds, tuple | list | np.ndarray) and len(bounds) == 2):
            raise ValueError(f"{name}[{shown(field)}]={shown(bounds)} must be a (low, high) "
                             "pair of finite real numbers")
        low = real(f"{name}[{shown(field)}][0]", bounds[0])
        high = real(f"{name}[{shown(field)}][1]", bounds[1])
        if low > high:
            raise ValueError(f"{name}[{shown(field)}]={shown(bounds)} needs finite low <= high")
        checked[field] = (low, high)
    return checked


def count(name: str, value: Any, *, low: int = 1, high: int | None = None) -> int:
    """``value`` as an int in [low, high], or ValueError naming ``name``."""
    allowed = f"an integer >= {low}" + (f" and <= {high}" if high is not None else "")
    if (not whole_number(value) or value < low or (high is not None and value > high)):
        raise ValueError(f"{name}={shown(value)} is not allowed: it must be {allowed} (a Python or "
                         "NumPy integer)")
    return int(value)


def choice(name: str, value: Any, allowed: Any) -> Any:
    """``value`` if it is one of ``allowed`` (hashable or not), else ValueError."""
    if not isinstance(value, str | type(None)) or value not in allowed:
        raise ValueError(f"{name}={shown(value)} is not allowed: it must be one of "
                         f"{', '.join(repr(a) for a in allowed)}")
    return value


def subset(name: str, value: Any, allowed: tuple[str, ...]) -> tuple[str, ...]:
    """``value``, a sequence of distinct names among ``allowed`` (a list, tuple, set or 1-d
    NumPy array), as a tuple in the order of ``allowed`` (None: all of them), or ValueError
    naming ``name``."""
    if value is None:
        return allowed
    if isinstance(value, np.ndarray) and value.ndim == 1:
        value = value.tolist()  # a NumPy array of names: its names, as Python strings
    names = list(value) if isinstance(value, list | tuple | set | frozenset) else None
    if names is None or not all(isinstance(x, str) for x in names):
        raise ValueError(f"{name}={shown(value)} is not allowed: it must be None (all) or a "
                         "list of "
                         f"names among {', '.join(allowed)}")
    unknown = [x for x in names if x not in allowed]
    if unknown or len(set(names)) != len(names):
        what = f"unknown names {unknown}" if unknown else "repeated names"
        raise ValueError(f"{name}={shown(value)} has {what}; allowed: {', '.join(allowed)}")
    return tuple(x for x in allowed if x in names)


def actions(value: Any, shape: tuple[int, ...], scale: float = 1.0,
            out: np.ndarray | None = None) -> np.ndarray:
    """Actions as float64 in [−1, 1] of ``shape``, times ``scale``: real numbers only, of
    ``shape`` or, where its last axis is 1, of ``shape`` without it (an action a number, a
    batch's a row), of any real dtype (longdouble too); out-of-range values are clipped; NaN,
    inf, another shape (a transposed batch among them), complex, text or a masked array
    raise ValueError (and leave ``out`` as it was). Into
    ``out`` (C-contiguous float64 of as many elements) if given: compiled, one pass to check
    and one to write."""
    if isinstance(value, np.ma.MaskedArray):  # np.asarray would take the data under the mask
        raise ValueError(f"action={shown(value)} is a masked array, which is not allowed: every "
                         "action must be given (pass a plain NumPy array)")
    shapes = (shape, shape[:-1]) if shape and shape[-1] == 1 else (shape,)
    try:
        a = np.asarray(value)
    except ValueError:  # a ragged nest of lists
        allowed = " or ".join(str(s) for s in shapes)
        raise ValueError(f"action={shown(value)} is not allowed: it must be real numbers of shape "
                         f"{allowed}, not a ragged list") from None
    except (TypeError, RuntimeError) as exc:  # e.g. a torch tensor needing grad, or bfloat16
        raise ValueError(f"action={shown(value)} cannot be read as numbers ({exc}); pass a NumPy "
                         "array or real numbers (a torch tensor: tensor.detach().cpu().float()"
                         ".numpy())") from None
    if a.dtype.kind not in "iuf" or a.shape not in shapes:
        allowed = " or ".join(str(s) for s in shapes)
        raise ValueError(f"action={shown(value)} is not allowed: it must be real numbers of shape "
                         f"{allowed} in [-1, 1] (out-of-range values are clipped), not "
                         f"{a.dtype} of shape {a.shape}")
    if a.dtype.kind == "f" and a.dtype.itemsize > 8:  # longdouble: clipped in its own type
        a = np.where(np.isfinite(a), np.clip(a, -1, 1), a)  # (one past float64's range: ±1)
    if a.dtype not in _COMPILED_ACTIONS:  # e.g. float16, longdouble, int8
        a = a.astype(np.float64)
    out = np.empty(shape) if out is None else out
    assert out.flags.c_contiguous and out.dtype == np.float64 and out.size == a.size
    if not _clipped(a.reshape(-1), scale, out.reshape(-1)):
        raise ValueError(f"action={shown(value)} is not finite; actions must be finite numbers in "
                         "[-1, 1] (out-of-range values are clipped)")
    return out.reshape(shape)


_COMPILED_ACTIONS = (np.dtype(np.float64), np.dtype(np.float32), np.dtype(np.int64))


@numba.njit(cache=True, nogil=True)
def _clipped(a: np.ndarray, scale: float, out: np.ndarray) -> bool:
    """out = clip(a, −1, 1) · scale; False, ``out`` untouched, if some element of ``a`` is
    not finite."""
    finite = True
    for i in range(a.size):
        x = np.float64(a[i])
        finite &= math.isfinite(x)
    if finite:
        for i in range(a.size):
            out[i] = min(max(np.float64(a[i]), -1.0), 1.0) * scale
    return finite


def check_integrable(scene: Scene, dt: float, max_torque: float,
                     start_speed: float = 0.0) -> None:
    """Raise ValueError if the integrators cannot follow ``scene`` over steps of ``dt`` [s]
    under torques up to ``max_torque`` [N·m] in float64, from start states as fast as
    ``start_speed`` [rad/s] (a task's :attr:`~roller_gym.task.Task.start_speed`).

    With J_min = m (k² + (r − e)²) [kg·m²] the smallest moment of inertia about the contact,
    the limits are: m g r, J_min and max_torque representable with room for their squares
    (between 1e-100 and 1e100 in SI units), and the fastest phase per control step,
    (ω_max + sqrt(max_torque / J_min) + c / J_min + start_speed T) · dt
    + (max_torque / J_min) T dt² / 2 with T = 1 + 1/|1 − rκ| (the fastest angle's turns per
    radian of φ), ω_max² = m g (r²|κ|/(1 − rκ) + e)/J_min and c the damping, at most 1e4:
    beyond it a control step spans more oscillations, or more e-foldings of the damping's
    decay, or turns of the fastest angle from a start or from the speed a held torque builds
    over the step, than the integrators' substep budget can follow.
    """
    for i in range(scene.batch_size or 1):
        one = scene.item(i) if scene.batch_size else scene
        m, r, kappa, e, k, g, c = (float(x) for x in one.params)
        weight_arm, j_min = integration_magnitudes(m, r, e, k, g)
        for label, x in (("m g r", weight_arm), ("J_min = m (k² + (r − e)²)", j_min),
                         ("max_torque", max_torque)):
            if not (math.isfinite(x) and SMALLEST <= abs(x) <= LARGEST):
                raise ValueError(
                    f"{shown(one)} cannot be integrated in float64: {label} = {x:.3g} (SI) lies "
                    "outside [1e-100, 1e100]; rescale the scene's units"
                )
        rates = integration_rates(m, r, kappa, e, g, c, j_min, max_torque, start_speed)
        omega, spin, decay, start, _ = rates
        phase = step_phase(rates, dt)
        if not phase <= LARGEST_PHASE_PER_STEP:
            held = phase - (omega + spin + decay + start) * dt  # the held torque's turns
            raise ValueError(
                f"dt={shown(dt)} s is too long for {shown(one)}: its fastest time scale is "
                f"{1.0 / (omega + spin + decay + start):.3g} s (ω_max = {omega:.3g} rad/s, "
                f"torque spin-up {spin:.3g} rad/s, damping c/J_min = {decay:.3g} 1/s, starts "
                f"up to {start_speed:g} rad/s: {start:.3g} rad/s), and a held max_torque "
                f"turns its fastest angle {held:.3g} rad in a step: "
                f"{phase:.3g} rad per step where at most {LARGEST_PHASE_PER_STEP:g} can be "
                "followed; use a shorter dt, a smaller max_torque, a larger k, a smaller e or "
                "less damping"
            )


def step_phase(rates: tuple[Any, Any, Any, Any, Any], dt: float) -> Any:
    """The fastest phase per control step [rad] of :func:`check_integrable` from
    :func:`integration_rates` and ``dt`` [s]: the rates' sum times dt, and the turns of the
    fastest angle at the speed a held torque builds, spin² T dt²/2 (floats, arrays or
    intervals), at most :data:`LARGEST_PHASE_PER_STEP`."""
    omega, spin, decay, start, turn = rates
    return (omega + spin + decay + start) * dt + spin * spin * turn * (0.5 * dt * dt)


def integration_magnitudes(m: Any, r: Any, e: Any, k: Any, g: Any) -> tuple[Any, Any]:
    """(m g r [N·m], J_min = m (k² + (r − e)²) [kg·m²]), the magnitudes
    :func:`check_integrable` bounds (floats, or intervals of :mod:`roller_gym.intervals`)."""
    return m * g * r, m * (k * k + (r - e) ** 2)


def integration_rates(m: Any, r: Any, kappa: Any, e: Any, g: Any, c: Any, j_min: Any,
                      max_torque: Any, start_speed: float = 0.0
                      ) -> tuple[Any, Any, Any, Any, Any]:
    """(ω_max, spin, decay, start, T) [rad/s, rad/s, 1/s, rad/s, 1] of
    :func:`check_integrable`: ω_max² = m g (r²|κ|/(1 − rκ) + e) / J_min,
    spin² = max_torque / J_min, decay = c / J_min, the damping's fastest rate,
    T = 1 + 1/|1 − rκ|, at least the fastest angle's turns per radian of φ
    (:func:`~roller_gym.physics.equations.fastest_turn`), and start = start_speed T, its rate
    at a start (floats, or intervals)."""
    s = 1.0 - r * kappa
    omega = np.sqrt(m * g * (r * r * abs(kappa) / s + e) / j_min)
    turn = 1.0 + 1.0 / abs(s)
    return omega, np.sqrt(max_torque / j_min), c / j_min, start_speed * turn, turn
