"""Scenes: the roller and the fixed surface it rolls on, as one immutable value.

A :class:`Scene` holds the parameters of the model in ``docs/PHYSICS.md`` (SI units):

========  ==========================================================  ============
field     meaning                                                     unit
========  ==========================================================  ============
m         mass of the roller                                          kg
r         radius of the roller (its rim is the body centrode)         m
R         radius of the fixed surface, signed (see below)             m
e         distance from the geometric center O1 to the mass center C  m
k         central radius of gyration (J_C = m k²)                     m
g         gravitational acceleration (pointing down, −y)              m/s²
mu        friction coefficient at the contact                         1
damping   viscous damping at the roller's axle: torque −damping·φ'    N·m·s/rad
========  ==========================================================  ============

Shapes, through the signed curvature κ = 1/R of the fixed surface:

* inside a cylinder (the paper's case): ``r < R < inf`` (κ > 0);
* a flat floor: ``R = math.inf`` (κ = 0);
* the outside of a drum of radius −R, the roller on top of it: ``R < 0`` (κ < 0).

Every field may also be a NumPy array (a batch of differently built rollers, for domain
randomization); all functions of :mod:`roller_gym.physics` broadcast over them. A scene keeps
a read-only float64 copy of each array it was given: it cannot be changed after its checks.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from types import MappingProxyType
from typing import Any

import numpy as np

Number = float | np.ndarray

__all__ = ["PRESETS", "Scene", "finite_real", "preset", "shown", "whole_number"]


def _real(x: Any) -> bool:
    """Whether ``x`` is one real number of any size: a Python or NumPy int or float, not a
    bool or a timedelta (NumPy counts both among its integers)."""
    return (isinstance(x, int | float | np.integer | np.floating)
            and not isinstance(x, bool | np.bool_ | np.timedelta64))


def finite_real(x: Any) -> bool:
    """Whether ``x`` is one real number (a Python or NumPy int or float, not a bool or a
    timedelta) that is finite as a float64 and not rounded to 0 there: a Python int or a
    longdouble past float64's range is not."""
    if not _real(x):
        return False
    try:  # as a float64 (a longdouble past its range is inf there, or 0 below it)
        return math.isfinite(float(x)) and (float(x) != 0.0 or x == 0)
    except OverflowError:
        return False


def whole_number(x: Any) -> bool:
    """Whether ``x`` is one integer: a Python or NumPy int, not a bool or a timedelta (NumPy
    counts both among its integers)."""
    return isinstance(x, int | np.integer) and not isinstance(x, bool | np.bool_ | np.timedelta64)


def shown(value: Any, limit: int = 200) -> str:
    """``value``'s repr for an error message: its middle cut where it is longer than ``limit``
    characters, and described where Python refuses to write it (an integer past
    ``sys.get_int_max_str_digits()`` digits, or a container holding one) or its ``__repr__``
    raises."""
    try:
        text = repr(value)
    except Exception:  # (any: a user's class may raise anything from its __repr__)
        if isinstance(value, int):
            digits = int(abs(value).bit_length() * math.log10(2)) + 1
            return f"<an integer of about {digits} digits>"
        if isinstance(value, list | tuple | dict | set | frozenset):
            return f"<a {type(value).__name__} holding a value Python cannot write>"
        return f"<a {type(value).__name__} object>"
    half = max(limit // 2 - 2, 1)
    return text if len(text) <= limit else f"{text[:half]}...{text[-half:]}"


def _stored(value: np.ndarray) -> float | np.ndarray:
    """A checked field as a Scene keeps it: a float, or a read-only float64 copy of an array
    (so that neither the caller's array nor the scene's can be changed past the checks)."""
    if value.ndim == 0:
        return float(value)
    out = np.array(value, dtype=float)
    out.setflags(write=False)
    return out


def _describe(value: np.ndarray) -> str:
    return repr(value.item()) if value.ndim == 0 else f"array {shown(value)}"


@dataclass(frozen=True, eq=False)
class Scene:
    """A roller of mass ``m``, radius ``r``, rolling without slipping on a surface of radius ``R``.

    Args:
        m: mass of the roller [kg], > 0.
        r: radius of the roller [m], > 0.
        R: signed radius of the fixed surface [m]: ``R > r`` inside a cylinder, ``math.inf``
            for a flat floor, ``R < 0`` on top of a drum of radius ``-R``.
        e: eccentricity, distance from the geometric center to the mass center [m], >= 0
            (e > r, a mass center beyond the rim, as on an arm, is allowed: the equations
            hold for any rigid body rolling on its circular rim).
        k: central radius of gyration [m], > 0.
        g: gravitational acceleration [m/s²], > 0.
        mu: friction coefficient [-], >= 0 (used to report slip, not to model it).
        damping: viscous damping coefficient at the roller's axle [N·m·s/rad], >= 0.

    Raises:
        ValueError: a field is NaN or outside its allowed range; the message names the field,
            the value and the range.
    """

    m: Number = 1.0
    r: Number = 0.1
    R: Number = 0.5
    e: Number = 0.04
    k: Number = 0.1
    g: Number = 9.81
    mu: Number = 1.0
    damping: Number = 0.0

    def __post_init__(self) -> None:
        rules = {
            "m": (lambda v: v > 0, "> 0"),
            "r": (lambda v: v > 0, "> 0"),
            "e": (lambda v: v >= 0, ">= 0"),
            "k": (lambda v: v > 0, "> 0"),
            "g": (lambda v: v > 0, "> 0"),
            "mu": (lambda v: v >= 0, ">= 0"),
            "damping": (lambda v: v >= 0, ">= 0"),
        }
        for f in fields(self):
            raw = getattr(self, f.name)
            if np.ma.isMaskedArray(raw):
                raise ValueError(f"Scene.{f.name} is a masked array: give its numbers as a "
                                 "plain array (the data under a mask would be used)")
            try:
                np.shape(raw)
            except ValueError:  # a ragged list
                raise ValueError(f"Scene.{f.name}={shown(raw)} is not a number or a 1-D array of "
                                 "numbers") from None
        shapes = {f.name: np.shape(getattr(self, f.name)) for f in fields(self)}
        try:
            shape = np.broadcast_shapes(*shapes.values())
        except ValueError:
            shape = None
        if shape is None or len(shape) > 1 or shape == (0,):
            given = {n: s for n, s in shapes.items() if s}
            raise ValueError(f"Scene fields of shapes {given} are not a batch: each field must "
                             "be a number or a 1-D array, the arrays of one length >= 1")
        for f in fields(self):
            raw = getattr(self, f.name)
            try:
                value = np.asarray(raw)
            except (TypeError, ValueError):
                value = np.asarray(None)
            if value.dtype.kind == "O" and value.size and all(map(_real, value.flat)):
                raise ValueError(f"Scene.{f.name}={shown(raw)} is out of range: an integer "
                                 "past float64's range (about ±1.8e308); it must be finite")
            if value.dtype.kind not in "iuf":  # not text, bool, complex or objects
                raise ValueError(f"Scene.{f.name}={shown(raw)} is not a real number (SI units); "
                                 f"it must be an int or a float, or an array of them")
            with np.errstate(over="ignore", under="ignore"):
                wide, value = value, value.astype(float)
            if wide.dtype.itemsize > 8 and wide.dtype.kind == "f" and np.any(
                    (np.isfinite(wide) & ~np.isfinite(value)) | ((wide != 0) & (value == 0))):
                raise ValueError(f"Scene.{f.name}={shown(raw)} is out of range: past float64's "
                                 "range (about 4.9e-324 to 1.8e308 in size), where it would "
                                 "become inf or 0; it must be a float64 number")
            if np.isnan(value).any():
                raise ValueError(f"Scene.{f.name}={_describe(value)} is NaN; it must be a number")
            if f.name == "R":
                r = np.asarray(self.r, dtype=float)
                ok = (value > r) | (value < 0)
                if not ok.all() or np.isneginf(value).any():
                    raise ValueError(
                        f"Scene.R={_describe(value)} is not allowed with r={_describe(r)}: R must "
                        "be > r (inside a cylinder), math.inf (a flat floor) or a finite negative "
                        "number (on top of a drum of radius -R)"
                    )
                with np.errstate(divide="ignore", over="ignore"):
                    curvature = 1.0 / value
                if not np.isfinite(curvature).all():
                    raise ValueError(
                        f"Scene.R={_describe(value)} is out of range: its curvature 1/R is past "
                        "float64's range; |R| must be at least about 5.6e-309 m"
                    )
                object.__setattr__(self, f.name, _stored(value))
                continue
            check, allowed = rules[f.name]
            if not np.all(check(value)) or np.isinf(value).any():
                raise ValueError(
                    f"Scene.{f.name}={_describe(value)} is out of range: it must be finite and "
                    f"{allowed}"
                )
            # stored as float64 (NumPy int scalars overflowed in the formulas: k*k in int16)
            object.__setattr__(self, f.name, _stored(value))

    # -- derived quantities -------------------------------------------------------------
    @property
    def kappa(self) -> Number:
        """Signed curvature κ = 1/R of the fixed surface [1/m] (0 for the floor)."""
        return 1.0 / self.R if np.ndim(self.R) == 0 else 1.0 / np.asarray(self.R)

    @property
    def shape(self) -> str | np.ndarray:
        """``"cylinder"``, ``"floor"`` or ``"drum"`` (an array of them for a batch)."""
        kappa = np.asarray(self.kappa)
        names = np.where(kappa > 0, "cylinder", np.where(kappa < 0, "drum", "floor"))
        batch = np.broadcast_shapes(*(np.shape(getattr(self, f.name)) for f in fields(self)))
        names = np.broadcast_to(names, batch) if batch else names  # a batch with a scalar R
        return str(names) if names.ndim == 0 else names

    @property
    def params(self) -> tuple[Number, ...]:
        """The tuple ``(m, r, kappa, e, k, g, damping)`` every equation of the physics takes."""
        return (self.m, self.r, self.kappa, self.e, self.k, self.g, self.damping)

    @functools.cached_property
    def batch_size(self) -> int | None:
        """Number of rollers when fields are arrays, else ``None`` (the scene is frozen: found
        once)."""
        shapes = [np.shape(getattr(self, f.name)) for f in fields(self)]
        shape = np.broadcast_shapes(*shapes)
        return int(np.prod(shape)) if shape else None

    def replace(self, **changes: Any) -> Scene:
        """A copy with some fields changed (validated again).

        Raises:
            ValueError: a name that is not a field of Scene, or a value a field refuses.
        """
        names = [f.name for f in fields(self)]
        unknown = [name for name in changes if name not in names]
        if unknown:
            raise ValueError(f"{unknown[0]!r} is not a field of Scene; its fields: "
                             f"{', '.join(names)}")
        return replace(self, **changes)

    def item(self, i: int) -> Scene:
        """The ``i``-th roller of a batch scene, as a scalar scene."""
        n = self.batch_size or 1
        if not (whole_number(i) and -n <= i < n):
            raise ValueError(f"i={shown(i)} is not a roller of this scene's {n}: it must be an "
                             f"integer in [{-n}, {n})")
        return Scene(
            **{
                f.name: float(np.broadcast_to(getattr(self, f.name), (n,))[i])
                for f in fields(self)
            }
        )

    @staticmethod
    def stack(scenes: list[Scene]) -> Scene:
        """One batch scene whose ``i``-th roller is ``scenes[i]``."""
        if not isinstance(scenes, list | tuple) or not scenes:
            raise ValueError(f"scenes={shown(scenes)} must be a non-empty list of scalar Scenes")
        scenes = [require_scene(s, f"scenes[{i}]") for i, s in enumerate(scenes)]
        batch = next((i for i, s in enumerate(scenes) if s.batch_size is not None), None)
        if batch is not None:
            raise ValueError(f"scenes[{batch}] is a batch of {scenes[batch].batch_size} "
                             "rollers: stack takes scalar Scenes (a batch's i-th is .item(i))")
        return Scene(
            **{
                f.name: np.array([float(getattr(s, f.name)) for s in scenes])
                for f in fields(Scene)
            }
        )

    def as_dict(self) -> dict[str, float | list[float]]:
        """The fields as plain Python numbers, e.g. for logging as JSON: floats for a scalar
        scene, for a batch each field as a list of one float per roller."""
        shape = () if self.batch_size is None else (self.batch_size,)
        return {f.name: np.broadcast_to(np.asarray(getattr(self, f.name), dtype=float),
                                        shape).tolist() for f in fields(self)}

    def __repr__(self) -> str:
        inner = ", ".join(f"{f.name}={shown(getattr(self, f.name))}" for f in fields(self))
        return f"Scene({inner})"

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Scene):
            return NotImplemented
        return all(
            np.array_equal(getattr(self, f.name), getattr(other, f.name)) for f in fields(self)
        )

    __hash__ = None  # type: ignore[assignment]


_R = 0.1  # radius of the presets' roller [m]

#: The named scenes, read-only. "paper" is the default; the others are the hard cases and
#: other shapes.
PRESETS: Mapping[str, Scene] = MappingProxyType({
    # The paper's example: an eccentric roller inside a cylinder (numbers of our choice).
    "paper": Scene(),
    # A uniform solid disc: e = 0, k² = r²/2.
    "solid_disc": Scene(e=0.0, k=_R / math.sqrt(2.0)),
    # A nearly tight fit: R = 1.01 r; ψ and θ turn ~100 times faster than φ.
    "tight_fit": Scene(R=1.01 * _R),
    # Mass at the rim: e = 0.99 r, k = 0.05 r; J_I nearly vanishes at θ = 0.
    "rim_mass": Scene(e=0.99 * _R, k=0.05 * _R),
    # A flat floor.
    "floor": Scene(R=math.inf),
    # On top of a drum of radius 0.5 m; bottom-heavy enough (e > r²/(|R| + r)) to rest on top.
    "drum": Scene(R=-0.5, e=0.05),
    # RollerBalance's scene: R = 10 r, e = 0.8 r: an unstable equilibrium at ψ ≈ 23°;
    # k = r keeps φ'' = τ/J_I moderate, so the torque does not lift the roller off.
    "balance": Scene(R=10 * _R, e=0.8 * _R, k=_R),
})


def require_scene(scene: Any, name: str = "scene") -> Scene:
    """``scene`` if it is a :class:`Scene`, else a TypeError naming the argument ``name``
    (a preset's name gets the call that turns it into one)."""
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, str):
        raise TypeError(f"{name}={shown(scene)} must be a Scene; for the preset of that name use "
                        f"preset({shown(scene)})")
    raise TypeError(f"{name}={shown(scene)} must be a Scene, not {type(scene).__name__}")


def preset(name: str) -> Scene:
    """The preset scene called ``name`` (one of :data:`PRESETS`)."""
    try:
        return PRESETS[name]
    except (KeyError, TypeError):  # (TypeError: not hashable)
        raise ValueError(
            f"unknown scene preset {shown(name)}; allowed: {', '.join(sorted(PRESETS))}"
        ) from None
