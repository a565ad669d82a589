"""What else the physics answers: kinematics, contact, energy, equilibria, linearization.

Every function takes a :class:`~roller_gym.physics.scene.Scene` and states as floats or arrays
(broadcast together, per-element scene parameters included), except :func:`equilibria`,
which searches one scene at one torque. They are NumPy formulas and take what NumPy
computes with: complex states give complex results (complex-step derivatives), bools are 0
and 1; the steppers, unlike them, refuse anything but finite real numbers.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import numba
import numba.extending
import numpy as np
from roller_gym.physics import equations as eq
from roller_gym.physics import trig
from roller_gym.physics.scene import Scene, finite_real, require_scene, shown, whole_number
from scipy.optimize import brentq

__all__ = [
    "Contact",
    "Equilibrium",
    "Kinematics",
    "acceleration",
    "contact",
    "energy",
    "equilibria",
    "holding_torque",
    "kinematics",
    "linearize",
    "moment_of_inertia",
    "nearest_unstable_rests",
    "power",
    "small_oscillation_frequency",
]

Array = float | np.ndarray


#: The largest |φ'| [rad/s] the analysis takes: φ'² and the forces stay within float64.
LARGEST_SPEED = 1e150


def _numbers(**values: Any) -> tuple[Any, ...]:
    """``values`` (states, torques) as NumPy computes with them: numbers and arrays as they
    are, lists and tuples as arrays; a ValueError names the first that is not finite numbers
    (a number or an array of them; complex and bool included, for complex-step
    derivatives)."""
    out = []
    for name, value in values.items():
        if isinstance(value, list | tuple):
            try:
                value = np.asarray(value)
            except ValueError:  # a ragged list
                value = np.asarray(None)
        try:
            kind = np.asarray(value).dtype.kind
        except ValueError:
            kind = "O"
        if kind not in "biufc":
            raise ValueError(f"{name}={shown(values[name])} must be numbers: a number or an "
                             "array of them (within float64's range)")
        with np.errstate(over="ignore"):  # (a longdouble past float64's range: inf there)
            finite = np.isfinite(np.asarray(value).astype(complex if kind == "c" else float))
        if not finite.all():
            raise ValueError(f"{name}={shown(values[name])} must be finite numbers (it holds "
                             "NaN or inf, as a float64)")
        if name == "phi" and not np.all(np.abs(np.real(value)) < trig.DOMAIN):
            raise ValueError(f"phi={shown(values[name])} must be within ±{trig.DOMAIN:.4g} rad, "
                             "where the sines are defined")
        if name == "phi_dot" and not np.all(np.abs(np.real(value)) <= LARGEST_SPEED):
            raise ValueError(f"phi_dot={shown(values[name])} must be within ±{LARGEST_SPEED:g} "
                             "rad/s, where its square, the energy and the forces stay finite")
        out.append(value)
    return tuple(out)


def acceleration(scene: Scene, phi: Array, phi_dot: Array, tau: Array) -> Array:
    """φ'' [rad/s²] at the state (φ [rad], φ' [rad/s]) under the drive τ [N·m]."""
    scene = require_scene(scene)
    phi, phi_dot, tau = _numbers(phi=phi, phi_dot=phi_dot, tau=tau)
    return eq.accel(phi, phi_dot, tau, *scene.params)


def moment_of_inertia(scene: Scene, phi: Array) -> Array:
    """J_I [kg·m²], the moment of inertia about the instant center."""
    scene = require_scene(scene)
    phi, = _numbers(phi=phi)
    return eq.inertia(phi, scene.m, scene.r, scene.kappa, scene.e, scene.k)


@dataclass(frozen=True)
class Kinematics:
    """Angles [rad] and positions [m] (origin at the rest contact point, O at (0, R))."""

    psi: Array
    theta: Array
    o1: tuple[Array, Array]
    c: tuple[Array, Array]
    i: tuple[Array, Array]


def kinematics(scene: Scene, phi: Array) -> Kinematics:
    """ψ, θ and the positions of O1, C and I at φ [rad]."""
    scene = require_scene(scene)
    phi, = _numbers(phi=phi)
    _, psi, theta = eq.shape_factors(phi, scene.r, scene.kappa)
    o1x, o1y, cx, cy, ix, iy = eq.positions(phi, scene.r, scene.kappa, scene.e)
    return Kinematics(psi, theta, (o1x, o1y), (cx, cy), (ix, iy))


def energy(scene: Scene, phi: Array, phi_dot: Array) -> Array:
    """E = ½ J_I φ'² + V [J], zero at rest at φ = 0."""
    scene = require_scene(scene)
    phi, phi_dot = _numbers(phi=phi, phi_dot=phi_dot)
    m, r, kappa, e, k, g, _ = scene.params
    return eq.energy(phi, phi_dot, m, r, kappa, e, k, g)


def power(scene: Scene, phi_dot: Array, tau: Array) -> Array:
    """dE/dt = τφ' − c φ'² [W]."""
    scene = require_scene(scene)
    phi_dot, tau = _numbers(phi_dot=phi_dot, tau=tau)
    return eq.denergy_dt(phi_dot, tau, scene.damping)


@dataclass(frozen=True)
class Contact:
    """The contact force on the roller and its margins.

    Attributes:
        normal: N [N], along the normal from I toward O1; rolling needs N > 0.
        friction: F [N], along the direction O1 moves for increasing φ.
        liftoff_margin: N/(m g) [-]; <= 0 means the roller leaves the surface.
        slip_margin: (μN − |F|)/(m g) [-]; < 0 means the friction needed exceeds μN.
        lifting: not liftoff_margin > 0 (also where a force overflows float64 at a speed
            past its range: rolling is not shown there).
        slipping: not slip_margin >= 0 (likewise).
    """

    normal: Array
    friction: Array
    liftoff_margin: Array
    slip_margin: Array
    lifting: Array
    slipping: Array


def contact(scene: Scene, phi: Array, phi_dot: Array, tau: Array) -> Contact:
    """The contact forces at the state under the drive τ [N·m] (φ'' from the dynamics)."""
    scene = require_scene(scene)
    phi, phi_dot, tau = _numbers(phi=phi, phi_dot=phi_dot, tau=tau)
    m, r, kappa, e, _, g, _ = scene.params
    phi_ddot = acceleration(scene, phi, phi_dot, tau)
    normal, friction = eq.contact_forces(phi, phi_dot, phi_ddot, m, r, kappa, e, g)
    liftoff, slip = eq.margins(normal, friction, m, g, scene.mu)
    return Contact(normal, friction, liftoff, slip, ~(liftoff > 0), ~(slip >= 0))


def holding_torque(scene: Scene, phi: Array) -> Array:
    """The torque [N·m] that holds the roller at rest at φ: dV/dφ = m g (r sin ψ + e sin φ)."""
    scene = require_scene(scene)
    phi, = _numbers(phi=phi)
    m, r, kappa, e, _, g, _ = scene.params
    return eq.dpotential(phi, m, r, kappa, e, g)


def linearize(
    scene: Scene, phi: Array, phi_dot: Array = 0.0, tau: Array = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of d/dt (δφ, δφ') = A (δφ, δφ') + B δτ about the state (exact derivatives).

    The derivatives of φ'' are :func:`~roller_gym.physics.equations.accel_jacobian`'s;
    ∂φ''/∂τ = 1/J_I. Shapes (..., 2, 2) and (..., 2, 1).
    """
    scene = require_scene(scene)
    phi, phi_dot, tau = _numbers(phi=phi, phi_dot=phi_dot, tau=tau)
    m, r, kappa, e, k, g, c = scene.params
    _, d_phi, d_w = eq.accel_jacobian(phi, phi_dot, tau, m, r, kappa, e, k, g, c)
    j = eq.inertia(phi, m, r, kappa, e, k)
    shape = np.shape(d_phi + d_w)
    A = np.zeros((*shape, 2, 2))
    A[..., 0, 1] = 1.0
    A[..., 1, 0] = d_phi
    A[..., 1, 1] = d_w
    B = np.zeros((*shape, 2, 1))
    B[..., 1, 0] = 1.0 / j
    return A, B


def small_oscillation_frequency(scene: Scene, phi: Array = 0.0) -> Array:
    """ω0 [rad/s] of small oscillations about the rest position φ (at its holding torque).

    About φ = 0: ω0² = g (r²κ/s + e)/(k² + (r − e)²), which inside a cylinder is the
    paper's g (r²/(R − r) + e)/(k² + (r − e)²).

    Raises:
        ValueError: φ is not a stable rest position (no oscillation).
    """
    scene = require_scene(scene)
    phi, = _numbers(phi=phi)
    A, _ = linearize(scene, phi, 0.0, holding_torque(scene, phi))
    stiffness = -A[..., 1, 0]
    if np.any(stiffness <= 0):
        raise ValueError(
            f"phi={shown(phi)} is not a stable rest position of {shown(scene)}: d²V/dφ² <= 0 there"
        )
    out = np.sqrt(stiffness)
    return float(out) if out.ndim == 0 else out


@dataclass(frozen=True)
class Equilibrium:
    """A rest position under a constant torque: φ [rad], ψ [rad], and whether it is stable."""

    phi: float
    psi: float
    stable: bool


#: Where one turn of ψ spans more turns of φ than this (a nearly flat surface), equilibria
#: are searched within this many turns of φ either way: the cost stays bounded whatever R.
MAX_TURNS = 64


#: The grid points per turn of φ :func:`equilibria` accepts: fewer may step over a pair of
#: critical points, more costs seconds for nothing.
RESOLUTIONS = (100, 1_000_000)


def _check_resolution(resolution: Any) -> None:
    """ValueError unless ``resolution`` is an integer in :data:`RESOLUTIONS`."""
    if not (whole_number(resolution) and RESOLUTIONS[0] <= resolution <= RESOLUTIONS[1]):
        raise ValueError(f"resolution={shown(resolution)} must be an integer in "
                         f"[{RESOLUTIONS[0]}, {RESOLUTIONS[1]}] (grid points per turn of φ)")


def equilibria(scene: Scene, tau: float = 0.0, resolution: int = 4000) -> list[Equilibrium]:
    """The rest positions under the constant torque τ [N·m], sorted by φ.

    Solves f(φ) = m g (r sin ψ + e sin φ) − τ = 0 within one turn of ψ (ψ in [−π, π)), or,
    where that spans more than :data:`MAX_TURNS` turns of φ (a nearly flat surface), within
    that many turns of φ either way; on the floor, where ψ stays 0 and V is periodic in φ,
    within one turn of φ (φ in [−π, π)). The critical points of f
    (d²V/dφ² = 0) are bracketed on a grid of ``resolution`` points per turn of φ and
    refined by Brent's method; between two consecutive ones f is monotone, so it has at
    most one root there, found by Brent's method where f changes sign or vanishes. So
    nearly coincident pairs of rest positions near an extremum of f are found too, and the
    cost is bounded whatever R is. A rest position is stable where d²V/dφ² > 0 (a minimum
    of V − τφ).

    A scene without a restoring potential (a uniform disc on the floor: e = 0, κ = 0) has
    no isolated rest positions (every position is neutral at τ = 0, none holds at τ ≠ 0):
    the result is empty.
    """
    scene = require_scene(scene)
    if scene.batch_size is not None:
        raise ValueError("equilibria() takes a scalar scene; call it per element of a batch")
    if not finite_real(tau):
        raise ValueError(f"tau={shown(tau)} [N·m] must be a finite real number")
    _check_resolution(resolution)
    m, r, kappa, e, _, g, _ = scene.params
    if r * kappa == 0 and e == 0:  # the floor, or a surface so flat that rκ underflows
        return []
    s = 1.0 - r * kappa
    rate = abs(r * kappa / s)  # dψ/dφ
    # (rκ can underflow to 0 on a nearly flat surface: as far as on the floor's window, or
    # MAX_TURNS turns, whichever is further)
    half = math.pi if kappa == 0 else math.pi * (MAX_TURNS if rate == 0.0
                                                 else min(1.0 / rate, MAX_TURNS))
    count = int(resolution * half / math.pi) + 1
    pad = 2.0 * half / count  # a root at the window's ends is bracketed from outside too
    grid = np.linspace(-half - pad, half + pad, count + 2)

    def f(phi):
        return eq.dpotential(phi, m, r, kappa, e, g) - tau

    def stiffness(phi):
        return eq.d2potential(phi, m, r, kappa, e, g)

    values = stiffness(grid)
    knots = [float(grid[0])]
    for a, b, fa, fb in zip(grid[:-1], grid[1:], values[:-1], values[1:], strict=True):
        if fa == 0.0:
            knots.append(float(a))
        elif fa * fb < 0:
            knots.append(brentq(stiffness, a, b, xtol=1e-15, rtol=1e-15))
    knots.append(float(grid[-1]))
    roots: list[float] = []
    for a, b in itertools.pairwise(knots):
        fa, fb = f(a), f(b)
        if fa == 0.0:
            roots.append(a)
        elif fa * fb < 0:
            roots.append(brentq(f, a, b, xtol=1e-15, rtol=1e-15))
    out = []
    edge = 1e-9 * half  # the window is half-open: ψ = π is ψ = −π, counted once
    for phi in sorted(set(roots)):
        if not -half - edge <= phi < half - edge:
            continue
        psi = r * kappa * phi / s
        out.append(Equilibrium(float(phi), float(psi), bool(stiffness(phi) > 0)))
    return out


def nearest_unstable_rests(r: np.ndarray, kappa: np.ndarray, e: np.ndarray,
                           resolution: int = 4000) -> np.ndarray:
    """The smallest unstable rest position φ > 0 [rad] at zero torque of each scene of the
    arrays ``r`` [m], ``kappa`` [1/m], ``e`` [m] (no other field moves a rest position), in
    one compiled call: the roots of dV/dφ with d²V/dφ² < 0 in (0, the window's end) of
    :func:`equilibria` (the same window and grid spacing), NaN where there is none there.

    As :func:`equilibria` does, the zeros of d²V/dφ² are bracketed on the grid, walked
    outward from 0 and refined by bisection to the last bit; between two of them dV/dφ is
    monotone, and its root there is refined likewise. The walk stops at the first unstable
    root, so the cost is that of the distance to it.
    """
    _check_resolution(resolution)
    arrays = _numbers(r=r, kappa=kappa, e=e)
    for name, x in zip(("r", "kappa", "e"), arrays, strict=True):
        x = np.asarray(x)
        if x.dtype.kind not in "iuf" or not np.isfinite(x).all() or x.size != np.size(arrays[0]):
            raise ValueError(f"{name}={shown(x)} must be finite real numbers, as many as r's "
                             f"{np.size(arrays[0])}")
    r, kappa, e = (np.ascontiguousarray(x, dtype=float).reshape(-1) for x in arrays)
    rate = np.abs(r * kappa / (1.0 - r * kappa))
    with np.errstate(divide="ignore"):
        half = np.where(kappa == 0.0, math.pi, math.pi * np.minimum(1.0 / rate, MAX_TURNS))
    out = np.empty(r.size)
    _nearest_unstable_root(r, kappa, e, half, resolution, out)
    return out


@numba.extending.register_jitable
def _derivative(order, phi, r, kappa, e):
    """dV/dφ (order 1) or d²V/dφ² (order 2) at φ, per m g."""
    if order == 1:
        return eq.dpotential(phi, 1.0, r, kappa, e, 1.0)
    return eq.d2potential(phi, 1.0, r, kappa, e, 1.0)


@numba.njit(cache=True, nogil=True)
def _bisect(order, a, b, r, kappa, e):
    """The zero of :func:`_derivative` between a and b (a sign change), to the last bit:
    the end of the last bracket where it is smaller."""
    fa = _derivative(order, a, r, kappa, e)
    while True:
        mid = 0.5 * (a + b)
        if mid <= a or mid >= b:
            return b if abs(_derivative(order, b, r, kappa, e)) < abs(fa) else a
        fm = _derivative(order, mid, r, kappa, e)
        if fm == 0.0:
            return mid
        if (fm < 0.0) == (fa < 0.0):
            a, fa = mid, fm
        else:
            b = mid


@numba.njit(cache=True, nogil=True)
def _nearest_unstable_root(r, kappa, e, half, resolution, out):
    """out[j]: the smallest φ in (0, half[j]·(1 − 1e-9)) where dV/dφ = 0 and d²V/dφ² < 0
    (m g = 1: neither moves it), or NaN where there is none."""
    for j in range(r.size):
        rj, kj, ej = r[j], kappa[j], e[j]
        out[j] = np.nan
        count = int(resolution * half[j] / np.pi) + 1
        step = 2.0 * half[j] / count
        end = half[j] * (1.0 - 1e-9)
        knot = 0.0  # dV/dφ is monotone between consecutive knots (zeros of d²V/dφ²)
        s_prev = eq.d2potential(0.0, 1.0, rj, kj, ej, 1.0)
        i = 0
        while True:
            i += 1
            x = i * step
            last = x > half[j] + step
            s_x = eq.d2potential(x, 1.0, rj, kj, ej, 1.0)
            new = np.nan
            if s_prev == 0.0:
                new = (i - 1) * step
            elif (s_prev < 0.0 and s_x > 0.0) or (s_prev > 0.0 and s_x < 0.0):
                new = _bisect(2, (i - 1) * step, x, rj, kj, ej)
            elif last:
                new = x
            if new > knot:
                fa = eq.dpotential(knot, 1.0, rj, kj, ej, 1.0)
                fb = eq.dpotential(new, 1.0, rj, kj, ej, 1.0)
                root = np.nan
                if fa == 0.0:
                    root = knot
                elif (fa < 0.0 and fb > 0.0) or (fa > 0.0 and fb < 0.0):
                    root = _bisect(1, knot, new, rj, kj, ej)
                if (root > 0.0 and root < end
                        and eq.d2potential(root, 1.0, rj, kj, ej, 1.0) < 0.0):
                    out[j] = root
                    break
                knot = new
            if last or knot >= end:
                break
            s_prev = s_x
