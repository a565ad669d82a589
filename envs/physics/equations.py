"""The equations of the model, each written once.

Every function here is plain arithmetic, so the same source serves a Python float, a NumPy
array (a batch of states, torques and per-element scene parameters, broadcast together) and,
compiled by numba (:data:`~roller_gym.physics.compiling.inlined`), the integrators' inner
loops. Sines and cosines are :mod:`roller_gym.physics.trig`'s: a branch-free form (so a
loop over rollers runs in SIMD lanes), within 1 ulp of the exact value, compiled for float64
whether called from numba or from Python, so a state gives the same bits alone and in a
batch.

Conventions (``docs/PHYSICS.md``): φ is the roller's rotation, positive clockwise,
0 when C is straight below O1 and O1 straight below O. With the signed curvature
κ = 1/R of the fixed surface and s = 1 − rκ,

* ψ = rκφ/s, the angle of O→O1 from the downward vertical (counter-clockwise positive);
* θ = φ/s, the angle at O1 between O1→I and O1→C.

Nothing divides by R − r, so the inside of a cylinder (κ > 0), the floor (κ = 0) and
the top of a drum (κ < 0) are one formula, continuous in κ.

The scene enters as ``m, r, kappa, e, k, g, c`` (``Scene.params``: kg, m, 1/m, m, m,
m/s², N·m·s/rad); φ in rad, φ' in rad/s, τ in N·m.
"""

from __future__ import annotations

from roller_gym.physics import trig
from roller_gym.physics.compiling import inlined

__all__ = [
    "accel",
    "accel_concentric",
    "accel_jacobian",
    "accel_terms",
    "angles",
    "contact_forces",
    "d2inertia",
    "d2potential",
    "denergy_dt",
    "dinertia",
    "dpotential",
    "energy",
    "energy_at",
    "fastest_turn",
    "forces",
    "half_theta_sin",
    "ic_squared",
    "inertia",
    "inertia_per_mass",
    "instant_center_velocity",
    "margins",
    "positions",
    "potential",
    "shape_factors",
    "sinc",
    "sinc_of",
]


@inlined
def sinc(x):
    """sin(x)/x, with its limit 1 at x = 0."""
    return sinc_of(x, trig.sin(x))


@inlined
def sinc_of(x, sin_x):
    """:func:`sinc` of x given its sine ``sin_x``."""
    nonzero = x != 0.0
    return trig.select(nonzero, sin_x / trig.select(nonzero, x, 1.0), 1.0)


@inlined
def shape_factors(phi, r, kappa):
    """(s, ψ, θ): s = 1 − rκ, ψ = rκφ/s [rad], θ = φ/s [rad]."""
    s = 1.0 - r * kappa
    return s, r * kappa * phi / s, phi / s


@inlined
def fastest_turn(r, kappa):
    """The fastest angle's turn per radian of φ [-]: max(1, 1/|1 − rκ|), θ = φ/s in a tight fit
    (s = 1 − rκ < 1), φ itself on a floor or a drum (ψ = rκφ/s never turns faster than θ)."""
    per = 1.0 / abs(1.0 - r * kappa)
    return trig.select(per > 1.0, per, 1.0)


@inlined
def ic_squared(phi, r, kappa, e):
    """|IC|² = r² + e² − 2re cos θ [m²], written (r − e)² + 4re sin²(θ/2) (no cancellation):
    :func:`inertia_per_mass` of a point mass (k = 0)."""
    return inertia_per_mass(half_theta_sin(phi, r, kappa), r, e, 0.0)


@inlined
def half_theta_sin(phi, r, kappa):
    """sin(θ/2), θ = φ/s: what |IC| and J_I depend on."""
    return trig.sin(0.5 * phi / (1.0 - r * kappa))


@inlined
def inertia_per_mass(half_sin, r, e, k):
    """J_I/m = k² + |IC|² = k² + (r − e)² + 4re sin²(θ/2) [m²], from ``half_sin`` = sin(θ/2):
    the denominator D of :func:`accel_terms`."""
    return k * k + (r - e) * (r - e) + 4.0 * r * e * half_sin * half_sin


@inlined
def inertia(phi, m, r, kappa, e, k):
    """J_I = m (k² + |IC|²), the moment of inertia about the instant center I [kg·m²]."""
    return m * inertia_per_mass(half_theta_sin(phi, r, kappa), r, e, k)


@inlined
def dinertia(phi, m, r, kappa, e):
    """dJ_I/dφ = 2 m r e sin θ / s [kg·m²/rad]."""
    s = 1.0 - r * kappa
    return 2.0 * m * r * e * trig.sin(phi / s) / s


@inlined
def d2inertia(phi, m, r, kappa, e):
    """d²J_I/dφ² = 2 m r e cos θ / s² [kg·m²/rad²]."""
    s = 1.0 - r * kappa
    return 2.0 * m * r * e * trig.cos(phi / s) / (s * s)


@inlined
def potential(phi, m, r, kappa, e, g):
    """V = m g [(R − r)(1 − cos ψ) + e (1 − cos φ)] [J], zero at φ = 0.

    (R − r)(1 − cos ψ) is written r φ sin(ψ/2) sinc(ψ/2), exact and finite at κ = 0.
    """
    _, psi, _ = shape_factors(phi, r, kappa)
    h = trig.sin(0.5 * phi)
    half_sin = trig.sin(0.5 * psi)
    return m * g * (r * phi * half_sin * sinc_of(0.5 * psi, half_sin) + 2.0 * e * h * h)


@inlined
def dpotential(phi, m, r, kappa, e, g):
    """dV/dφ = m g (r sin ψ + e sin φ) [N·m]: minus the moment of gravity about I."""
    psi = r * kappa * phi / (1.0 - r * kappa)
    return m * g * (r * trig.sin(psi) + e * trig.sin(phi))


@inlined
def d2potential(phi, m, r, kappa, e, g):
    """d²V/dφ² = m g (r²κ/s cos ψ + e cos φ) [N·m/rad]."""
    s, psi, _ = shape_factors(phi, r, kappa)
    return m * g * (r * r * kappa / s * trig.cos(psi) + e * trig.cos(phi))


@inlined
def accel(phi, phi_dot, tau, m, r, kappa, e, k, g, c):
    """φ'' [rad/s²] from the closed-form equation of motion (PHYSICS.md, the paper's example):

    (k² + e² + r² − 2er cos θ) φ'' + (e r / s) φ'² sin θ + g (r sin ψ + e sin φ) = (τ − c φ')/m

    (e r R/(R − r) of the paper is e r / s.) This is the form that drives the simulation:
    φ'' = L/D with (L, D) the first two of :func:`accel_terms`.
    """
    lhs, inertia, _, _, _, _, _ = accel_terms(phi, phi_dot, tau, m, r, kappa, e, k, g, c)
    return lhs / inertia


@inlined
def accel_terms(phi, phi_dot, tau, m, r, kappa, e, k, g, c):
    """The parts of :func:`accel`: (L [N·m/kg], D [m²], sin θ, cos θ, sin ψ, cos ψ, sin φ),
    φ'' = L/D with

    L = (τ − c φ')/m − (e r / s) φ'² sin θ − g (r sin ψ + e sin φ),
    D = k² + e² + r² − 2er cos θ (J_I/m).

    It takes two sine–cosine pairs (:func:`~roller_gym.physics.trig.sincos`), of θ/2 and of
    ψ, instead of four sines: sin θ = 2 sin(θ/2) cos(θ/2), D = k² + (r − e)² + 4re
    sin²(θ/2) (no cancellation), and, since φ = θ − ψ, sin φ = sin θ cos ψ − cos θ sin ψ.
    The Taylor series of the motion (:mod:`roller_gym.physics.taylor`) starts from them.
    """
    s = 1.0 - r * kappa
    h, sin_t, cos_t, sin_psi, cos_psi, sin_phi = angles(phi, r, kappa)
    lhs = (
        (tau - c * phi_dot) / m
        - e * r / s * phi_dot * phi_dot * sin_t
        - g * (r * sin_psi + e * sin_phi)
    )
    return lhs, inertia_per_mass(h, r, e, k), sin_t, cos_t, sin_psi, cos_psi, sin_phi


@inlined
def accel_jacobian(phi, phi_dot, tau, m, r, kappa, e, k, g, c):
    """(φ'' [rad/s²], ∂φ''/∂φ [1/s²], ∂φ''/∂φ' [1/s]): :func:`accel` and its derivatives,
    the linearized motion's matrix [[0, 1], [∂φ''/∂φ, ∂φ''/∂φ']]. With φ'' = L/D
    (:func:`accel_terms`),

    ∂L/∂φ = −(e r / s²) φ'² cos θ − g (r²κ/s cos ψ + e cos φ),  ∂D/∂φ = 2 e r sin θ / s,
    ∂φ''/∂φ = (∂L/∂φ − φ'' ∂D/∂φ)/D,  ∂φ''/∂φ' = (−c/m − 2 (e r / s) φ' sin θ)/D.

    φ'' is bit for bit :func:`accel`'s.
    """
    s = 1.0 - r * kappa
    lhs, d, sin_t, cos_t, sin_psi, cos_psi, _ = accel_terms(phi, phi_dot, tau, m, r, kappa, e,
                                                            k, g, c)
    a = lhs / d
    cos_phi = cos_t * cos_psi + sin_t * sin_psi  # φ = θ − ψ
    dl = -e * r / (s * s) * phi_dot * phi_dot * cos_t - g * (r * r * kappa / s * cos_psi
                                                             + e * cos_phi)
    dd = 2.0 * e * r * sin_t / s
    return a, (dl - a * dd) / d, (-c / m - 2.0 * e * r / s * phi_dot * sin_t) / d


@inlined
def angles(phi, r, kappa):
    """A state's trigonometry from two sine–cosine pairs (θ/2 and ψ): (sin(θ/2), sin θ,
    cos θ, sin ψ, cos ψ, sin φ), with sin θ = 2 sin(θ/2) cos(θ/2), cos θ = 1 − 2 sin²(θ/2)
    and, since φ = θ − ψ, sin φ = sin θ cos ψ − cos θ sin ψ. :func:`accel_terms` and
    :func:`contact_forces` take theirs from here, so a kernel that has one may pass it on
    (:func:`forces`)."""
    theta = phi / (1.0 - r * kappa)
    h, hc = trig.sincos(0.5 * theta)
    sin_psi, cos_psi = trig.sincos(r * kappa * theta)
    sin_t = 2.0 * h * hc
    cos_t = 1.0 - 2.0 * h * h
    return h, sin_t, cos_t, sin_psi, cos_psi, sin_t * cos_psi - cos_t * sin_psi


@inlined
def accel_concentric(phi, phi_dot, tau, m, r, kappa, k, g, c):
    """φ'' [rad/s²] of :func:`accel` with e = 0, the terms that vanish left out:

    (k² + r²) φ'' + g r sin ψ = (τ − c φ')/m.
    """
    return ((tau - c * phi_dot) / m - g * r * trig.sin(r * kappa * phi / (1.0 - r * kappa))) / (
        k * k + r * r
    )


@inlined
def energy(phi, phi_dot, m, r, kappa, e, k, g):
    """E = ½ J_I φ'² + V [J]."""
    return energy_at(inertia_per_mass(half_theta_sin(phi, r, kappa), r, e, k), phi, phi_dot,
                     m, r, kappa, e, g)


@inlined
def energy_at(d, phi, phi_dot, m, r, kappa, e, g):
    """:func:`energy` given d = J_I/m [m²] at φ (:func:`accel_terms`' D)."""
    return 0.5 * (m * d) * phi_dot * phi_dot + potential(phi, m, r, kappa, e, g)


@inlined
def denergy_dt(phi_dot, tau, c):
    """dE/dt = τφ' − c φ'² [W]: the power balance (the drive in, the axle's damping out)."""
    return (tau - c * phi_dot) * phi_dot


@inlined
def positions(phi, r, kappa, e):
    """Positions [m] of O1, C and I: ``(o1x, o1y, cx, cy, ix, iy)``.

    The origin is the surface point the roller touches at φ = 0 (the bottom of the cylinder,
    the top of the drum), so that the floor is finite; the axis O is at (0, R). In that frame
    O1 = ((R − r) sin ψ, r + (R − r)(1 − cos ψ)), written with sinc so that κ = 0 is exact,
    C = O1 + e (−sin φ, −cos φ) and I = O1 + r (sin ψ, −cos ψ).
    """
    _, psi, _ = shape_factors(phi, r, kappa)
    o1x = r * phi * sinc(psi)
    o1y = r + r * phi * trig.sin(0.5 * psi) * sinc(0.5 * psi)
    cx = o1x - e * trig.sin(phi)
    cy = o1y - e * trig.cos(phi)
    ix = o1x + r * trig.sin(psi)
    iy = o1y - r * trig.cos(psi)
    return o1x, o1y, cx, cy, ix, iy


@inlined
def instant_center_velocity(phi, phi_dot, r, kappa):
    """u [m/s], the velocity with which I runs along the space centrode: (rφ'/s)(cos ψ, sin ψ)."""
    s, psi, _ = shape_factors(phi, r, kappa)
    speed = r * phi_dot / s
    return speed * trig.cos(psi), speed * trig.sin(psi)


@inlined
def contact_forces(phi, phi_dot, phi_ddot, m, r, kappa, e, g):
    """(N, F) [N], the contact force on the roller at I, from m a_C = N + F + m g.

    N is along the normal from I toward the roller's center O1 (positive: pushing);
    F along (cos ψ, sin ψ), the direction O1 moves for increasing φ:

    N/m = g cos ψ + (r²κ/s) φ'² + e (φ'' sin θ + φ'² cos θ)
    F/m = g sin ψ + (r − e cos θ) φ'' + e φ'² sin θ
    """
    _, sin_t, cos_t, sin_psi, cos_psi, _ = angles(phi, r, kappa)
    return forces(sin_t, cos_t, sin_psi, cos_psi, phi_dot, phi_ddot, m, r, kappa, e, g)


@inlined
def forces(sin_t, cos_t, sin_psi, cos_psi, phi_dot, phi_ddot, m, r, kappa, e, g):
    """:func:`contact_forces` (N, F) [N] given the state's sin θ, cos θ, sin ψ and cos ψ
    (:func:`angles`)."""
    w2 = phi_dot * phi_dot
    normal = m * (g * cos_psi + r * r * kappa / (1.0 - r * kappa) * w2
                  + e * (phi_ddot * sin_t + w2 * cos_t))
    friction = m * (g * sin_psi + (r - e * cos_t) * phi_ddot + e * w2 * sin_t)
    return normal, friction


@inlined
def margins(normal, friction, m, g, mu):
    """(N/(m g), (μN − |F|)/(m g)): the lift-off margin (<= 0: the roller leaves the surface)
    and the slip margin (< 0: the friction needed exceeds μN), from the contact forces [N]."""
    weight = m * g
    return normal / weight, (mu * normal - abs(friction)) / weight
