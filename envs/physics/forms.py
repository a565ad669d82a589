"""Every form of Vâlcovici's theorem in the paper, each returning φ'' [rad/s²].

The paper (Buracu & Lecu, Proc. Romanian Academy A 6(1), 2005) writes the relative angular
momentum theorem about the instant center I in four ways. Each function below evaluates
one of them with the vectors of the scene (positions, velocities, accelerations in the
plane) and solves it for φ''; they are independent of one another and of the closed form
:func:`roller_gym.physics.equations.accel`, which is what the simulation integrates (it is the
fastest). The tests check that all five agree.

=====================  =============================================================
function               equation of the paper
=====================  =============================================================
``accel_eq15``         Eq. 15: J_I ω' + ½ (dJ_I/dt) ω = M_I, I on the space centrode
``accel_eq18``         Eq. 18 + 19: J_I ω' + m IC × a_I = M_I, I on the body centrode,
                       a_I = ω² ρρ₁/(ρ₁ − ρ) along the common normal (ρ = r, ρ₁ = R)
``accel_eq24``         Eq. 24 + 23: the same with a_I from u, the velocity of I along the
                       space centrode (a_I = u × ω; the OCR of Eq. 23 lost the order)
``accel_eq30``         Eq. 30: J_C ω' + m IC × a_C = M_I (needs no choice of centrode)
``accel_closed_form``  the equation of motion of the paper's example
=====================  =============================================================

Signs: moments and ω are taken clockwise positive, the sense of φ (ω = φ'); M_I is the
moment about I of gravity, the drive τ and the axle's damping −cφ'.
"""

from __future__ import annotations

import numpy as np
from roller_gym.physics import equations as eq
from roller_gym.physics.scene import Scene

__all__ = [
    "FORMS",
    "accel_closed_form",
    "accel_eq15",
    "accel_eq18",
    "accel_eq24",
    "accel_eq30",
]


def _cross_cw(ax, ay, bx, by):
    """The clockwise (−z) component of a × b for plane vectors."""
    return -(ax * by - ay * bx)


def _frame(scene: Scene, phi, phi_dot, tau):
    """IC, |IC|², J_I and M_I (clockwise) at the given state."""
    m, r, kappa, e, k, g, c = scene.params
    _, _, cx, cy, ix, iy = eq.positions(phi, r, kappa, e)
    icx, icy = cx - ix, cy - iy
    ic2 = icx * icx + icy * icy
    j_i = m * (k * k + ic2)
    # Moment about I of gravity (0, −m g) acting at C, plus the drive and the damping.
    m_i = _cross_cw(icx, icy, 0.0, -m * g) + tau - c * phi_dot
    return icx, icy, j_i, m_i


def accel_eq15(scene: Scene, phi, phi_dot, tau):
    """Eq. 15: J_I φ'' + ½ (dJ_I/dt) φ' = M_I.

    dJ_I/dt = 2 m IC · d(IC)/dt, with d(IC)/dt = v_C − u: C moves as a point of the body
    (v_C = ω × IC), I as the geometric point on the space centrode (velocity u).
    """
    m, r, kappa = scene.m, scene.r, scene.kappa
    icx, icy, j_i, m_i = _frame(scene, phi, phi_dot, tau)
    vcx, vcy = phi_dot * icy, -phi_dot * icx  # ω × IC with ω = −φ' ẑ
    ux, uy = eq.instant_center_velocity(phi, phi_dot, r, kappa)
    dj_dt = 2.0 * m * (icx * (vcx - ux) + icy * (vcy - uy))
    return (m_i - 0.5 * dj_dt * phi_dot) / j_i


def accel_eq18(scene: Scene, phi, phi_dot, tau):
    """Eq. 18 with Eq. 19: J_I φ'' + m IC × a_I = M_I, a_I = φ'² ρρ₁/(ρ₁ − ρ) n.

    n is the unit normal from I toward O1 (the common normal of the centrodes);
    ρρ₁/(ρ₁ − ρ) = rR/(R − r) = r/(1 − rκ).
    """
    m, r, kappa, e = scene.m, scene.r, scene.kappa, scene.e
    o1x, o1y, _, _, ix, iy = eq.positions(phi, r, kappa, e)
    icx, icy, j_i, m_i = _frame(scene, phi, phi_dot, tau)
    magnitude = phi_dot * phi_dot * r / (1.0 - r * kappa)
    ax, ay = magnitude * (o1x - ix) / r, magnitude * (o1y - iy) / r
    return (m_i - m * _cross_cw(icx, icy, ax, ay)) / j_i


def accel_eq24(scene: Scene, phi, phi_dot, tau):
    """Eq. 24 with Eq. 23: J_I φ'' + m IC × (u × ω) = M_I."""
    m, r, kappa = scene.m, scene.r, scene.kappa
    icx, icy, j_i, m_i = _frame(scene, phi, phi_dot, tau)
    ux, uy = eq.instant_center_velocity(phi, phi_dot, r, kappa)
    wz = -phi_dot  # counter-clockwise component of ω
    ax, ay = uy * wz, -ux * wz  # u × (wz ẑ)
    return (m_i - m * _cross_cw(icx, icy, ax, ay)) / j_i


def accel_eq30(scene: Scene, phi, phi_dot, tau):
    """Eq. 30: J_C φ'' + m IC × a_C = M_I, with a_C = C_φ φ'' + C_φφ φ'², solved for φ''.

    C_φ and C_φφ are the derivatives of C = O1 + e(−sin φ, −cos φ) along the motion:
    dO1/dφ = r (cos ψ, sin ψ), d²O1/dφ² = (r²κ/s)(−sin ψ, cos ψ).
    """
    m, r, kappa, e, k = scene.m, scene.r, scene.kappa, scene.e, scene.k
    s, psi, _ = eq.shape_factors(phi, r, kappa)
    icx, icy, _, m_i = _frame(scene, phi, phi_dot, tau)
    c1x = r * np.cos(psi) - e * np.cos(phi)
    c1y = r * np.sin(psi) + e * np.sin(phi)
    c2x = -r * r * kappa / s * np.sin(psi) + e * np.sin(phi)
    c2y = r * r * kappa / s * np.cos(psi) + e * np.cos(phi)
    coefficient = m * k * k + m * _cross_cw(icx, icy, c1x, c1y)
    return (m_i - m * _cross_cw(icx, icy, c2x, c2y) * phi_dot * phi_dot) / coefficient


def accel_closed_form(scene: Scene, phi, phi_dot, tau):
    """The equation of motion of the paper's example
    (:func:`roller_gym.physics.equations.accel`)."""
    return eq.accel(phi, phi_dot, tau, *scene.params)


#: The forms by name, for tests and benchmarks.
FORMS = {
    "eq15": accel_eq15,
    "eq18": accel_eq18,
    "eq24": accel_eq24,
    "eq30": accel_eq30,
    "closed_form": accel_closed_form,
}
