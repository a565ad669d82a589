"""The physics checked against derivations written here, independently of roller_gym.physics.

* Lagrange's equations with ``sympy.physics.mechanics``, built from docs/PHYSICS.md alone: the
  generalized coordinate φ, the mass center C = O1 + e(−sin φ, −cos φ) with
  O1 = O + (R − r)(sin ψ, −cos ψ), ψ = rφ/(R − r) (on the floor O1 = (rφ, r)), the kinetic
  energy ½ m v_C² + ½ m k² φ'² of a rigid body turning clockwise at φ', the potential
  m g y_C and the generalized force τ − cφ' of the drive and the axle's damping.
* Newton–Euler for the mass center: m a_C = N n + F t + m g and J_C φ'' = τ − cφ' + the
  moment about C of the contact force, with a_C from sympy's derivatives of C(φ(t)).
* sympy's symbolic simplification, where it closes: the closed form of PHYSICS.md, the
  contact-force formulas, the energy, the rolling constraint.

Random states keep |ψ| <= π and |φ| <= 4π (the physically meaningful range; beyond it the
vector forms only lose digits to large coordinates).
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from roller_gym.physics import FORMS, Scene, analysis
from roller_gym.physics import equations as eq
from sampling import SHAPES, accel_scale, sample
from sympy.physics import mechanics as me

# -- the independent derivation ---------------------------------------------------------------

_t = me.dynamicsymbols._t
_phi = me.dynamicsymbols("phi")
m, r, R, e, k, g, c, tau = sp.symbols("m r R e k g c tau", real=True)
q, w, a, P = sp.symbols("q w a P", real=True)  # φ, φ', φ'' as plain symbols; P stands for ψ
ARGS = (q, w, tau, m, r, R, e, k, g, c)


def _plain(expr):
    """Replace φ(t) and its derivatives by the symbols q, w, a."""
    return expr.subs({_phi.diff(_t, 2): a}).subs({_phi.diff(_t): w}).subs({_phi: q})


class Derivation:
    """Everything derived from PHYSICS.md's geometry for one shape ("curved" or "floor")."""

    def __init__(self, floor: bool):
        self.floor = floor
        N = me.ReferenceFrame("N")
        body_frame = N.orientnew("B", "Axis", [-_phi, N.z])  # φ is clockwise
        O = me.Point("O")
        O.set_vel(N, 0)
        if floor:
            psi = sp.S(0)
            # The floor is y = 0; O1 rolls along it.
            o1 = O.locatenew("O1", r * _phi * N.x + r * N.y)
            contact = O.locatenew("I", r * _phi * N.x)
        else:
            psi = r * _phi / (R - r)
            radial = sp.sin(psi) * N.x - sp.cos(psi) * N.y
            o1 = O.locatenew("O1", (R - r) * radial)
            contact = O.locatenew("I", R * radial)
        cm = o1.locatenew("C", e * (-sp.sin(_phi) * N.x - sp.cos(_phi) * N.y))
        cm.set_vel(N, cm.pos_from(O).dt(N))
        o1.set_vel(N, o1.pos_from(O).dt(N))
        central_inertia = (me.inertia(body_frame, 0, 0, m * k**2), cm)  # J_C = m k²
        body = me.RigidBody("roller", cm, body_frame, m, central_inertia)
        body.potential_energy = m * g * cm.pos_from(O).dot(N.y)
        lagrangian = me.Lagrangian(N, body)
        torque = (tau - c * _phi.diff(_t)) * (-N.z)  # clockwise positive
        lm = me.LagrangesMethod(lagrangian, [_phi], forcelist=[(body_frame, torque)], frame=N)
        lm.form_lagranges_equations()
        self.accel_expr = _plain((lm.mass_matrix.inv() * lm.forcing)[0])
        self.psi = _plain(psi)
        self.theta = q + self.psi  # the angle between O1→I (ψ from down) and O1→C (−φ)

        # Positions relative to O, their φ-derivatives, the velocity of the material point
        # of the body at I, and the Koenig energy.
        def xy(point):
            vec = point.pos_from(O)
            return sp.Matrix([vec.dot(N.x), vec.dot(N.y)])

        self.c_expr = _plain(xy(cm))
        self.o1_expr = _plain(xy(o1))
        self.i_expr = _plain(xy(contact))
        v_material_i = cm.vel(N) + body_frame.ang_vel_in(N).cross(contact.pos_from(cm))
        self.v_material_i = [_plain(v_material_i.dot(N.x)), _plain(v_material_i.dot(N.y))]
        self.v_contact = _plain(xy(contact).diff(_t))  # u: I as a geometric point
        kinetic = body.kinetic_energy(N)
        y_rest = self.c_expr[1].subs(q, 0)
        self.energy_expr = _plain(kinetic) + m * g * (self.c_expr[1] - y_rest)

        lam = self._lambdify
        self.accel = lam(ARGS, self.accel_expr)
        self.positions = lam((q, r, R, e), [*self.o1_expr, *self.c_expr, *self.i_expr])
        self.dc = lam((q, r, R, e), list(self.c_expr.diff(q)))
        self.d2c = lam((q, r, R, e), list(self.c_expr.diff(q, 2)))
        self.energy = lam((q, w, m, r, R, e, k, g), self.energy_expr)
        self.denergy = lam(
            (q, w, m, r, R, e, k, g), [self.energy_expr.diff(q), self.energy_expr.diff(w)]
        )
        self.u = lam((q, w, r, R), list(self.v_contact))

    @staticmethod
    def _lambdify(args, expr):
        """A NumPy function of args; a list of expressions gives one stacked array."""
        f = sp.lambdify(args, expr, "numpy")

        def evaluate(*x):
            out = f(*x)
            if isinstance(out, list):
                return np.array(np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in out)))
            return np.asarray(out, dtype=float)

        return evaluate


@pytest.fixture(scope="module")
def curved() -> Derivation:
    return Derivation(floor=False)


@pytest.fixture(scope="module")
def flat() -> Derivation:
    return Derivation(floor=True)


@pytest.fixture(scope="module")
def derivations(curved, flat):
    return {"cylinder": curved, "drum": curved, "floor": flat}


# -- random scenes and states ------------------------------------------------------------------

def _R(scene: Scene):
    return np.asarray(scene.R, dtype=float)


# -- symbolic checks -----------------------------------------------------------------------------


def _vanishes(expr, floor: bool) -> bool:
    """True if sympy proves expr == 0 (with R = r + rφ/P, so that ψ = P and θ = φ + P)."""
    if not floor:
        expr = expr.subs(R, r + r * q / P)
    return sp.simplify(sp.expand_trig(sp.simplify(expr))) == 0


@pytest.mark.parametrize("shape", ["curved", "flat"])
def test_rolling_constraint_holds(shape, request):
    """The material point of the roller at I has zero velocity: ψ = rφ/(R − r) is rolling."""
    d = request.getfixturevalue(shape)
    assert all(_vanishes(v, d.floor) for v in d.v_material_i)


@pytest.mark.parametrize("shape", ["curved", "flat"])
def test_lagrange_gives_the_closed_form_of_physics_md(shape, request):
    """Lagrange's equations reduce symbolically to PHYSICS.md's equation of motion."""
    d = request.getfixturevalue(shape)
    psi, theta = d.psi, d.theta
    coupling = e * r if d.floor else e * r * R / (R - r)  # e r R/(R − r) → e r as R → ∞
    closed = (
        (tau - c * w) / m
        - coupling * w**2 * sp.sin(theta)
        - g * (r * sp.sin(psi) + e * sp.sin(q))
    ) / (k**2 + e**2 + r**2 - 2 * e * r * sp.cos(theta))
    assert _vanishes(d.accel_expr - closed, d.floor)


@pytest.mark.parametrize("shape", ["curved", "flat"])
def test_contact_force_formulas_of_physics_md(shape, request):
    """N and F of PHYSICS.md are the normal and tangential parts of m a_C − m g (symbolic)."""
    d = request.getfixturevalue(shape)
    psi, theta = d.psi, d.theta
    a_c = d.c_expr.diff(q) * a + d.c_expr.diff(q, 2) * w**2
    force = m * a_c - m * sp.Matrix([0, -g])
    normal = sp.Matrix([-sp.sin(psi), sp.cos(psi)])  # from I toward O1
    tangent = sp.Matrix([sp.cos(psi), sp.sin(psi)])
    centripetal = 0 if d.floor else r**2 / (R - r)
    n_spec = g * sp.cos(psi) + centripetal * w**2 + e * (a * sp.sin(theta) + w**2 * sp.cos(theta))
    f_spec = g * sp.sin(psi) + (r - e * sp.cos(theta)) * a + e * w**2 * sp.sin(theta)
    assert _vanishes(force.dot(normal) / m - n_spec, d.floor)
    assert _vanishes(force.dot(tangent) / m - f_spec, d.floor)


@pytest.mark.parametrize("shape", ["curved", "flat"])
def test_energy_of_physics_md_is_koenigs(shape, request):
    """E = ½ J_I φ'² + m g[(R − r)(1 − cos ψ) + e(1 − cos φ)] equals ½ m v_C² + ½ J_C φ'² + V."""
    d = request.getfixturevalue(shape)
    j_i = m * (k**2 + r**2 + e**2 - 2 * r * e * sp.cos(d.theta))
    lift = 0 if d.floor else (R - r) * (1 - sp.cos(d.psi))
    spec = j_i * w**2 / 2 + m * g * (lift + e * (1 - sp.cos(q)))
    assert _vanishes(d.energy_expr - spec, d.floor)


# -- the code against the derivation, on random states ------------------------------------------


@pytest.mark.parametrize("shape", SHAPES)
def test_closed_form_and_every_form_match_lagrange(shape, derivations):
    """eq.accel and all of FORMS equal Lagrange's φ'' on 10,000 random states, to 1e-12."""
    rng = np.random.default_rng(["cylinder", "floor", "drum"].index(shape))
    scene, phi, phi_dot, torque = sample(rng, 10_000, shape)
    m_, r_, _, e_, k_, g_, c_ = scene.params
    reference = derivations[shape].accel(phi, phi_dot, torque, m_, r_, _R(scene), e_, k_, g_, c_)
    scale = accel_scale(scene, phi, phi_dot, torque)
    assert np.all(np.isfinite(reference))
    for name, form in FORMS.items():
        err = np.abs(form(scene, phi, phi_dot, torque) - reference) / scale
        assert err.max() <= 1e-12, f"{name}: worst {err.max():.2e} of the scale"


@pytest.mark.parametrize("shape", SHAPES)
def test_positions_and_angles_match_physics_md(shape, derivations):
    """O1, C, I (code frame: origin at the rest contact point, O at (0, R)), ψ and θ."""
    rng = np.random.default_rng(10 + SHAPES.index(shape))
    scene, phi, _, _ = sample(rng, 2000, shape)
    _, r_, kappa, e_, _, _, _ = scene.params
    got = eq.positions(phi, r_, kappa, e_)
    ref = derivations[shape].positions(phi, r_, _R(scene), e_)
    if shape != "floor":
        ref[1::2] += _R(scene)  # the code's origin is the rest contact point, O is at (0, R)
    # The reference subtracts coordinates of size |R|: it is good to eps·|R|.
    size = np.maximum(np.abs(_R(scene)), r_) if shape != "floor" else r_ * (1 + np.abs(phi))
    assert np.max(np.abs(np.asarray(got) - ref) / size) <= 1e-12
    kin = analysis.kinematics(scene, phi)
    psi = 0.0 if shape == "floor" else r_ * phi / (_R(scene) - r_)
    theta = phi if shape == "floor" else _R(scene) * phi / (_R(scene) - r_)
    np.testing.assert_allclose(kin.psi, psi, rtol=1e-13, atol=1e-300)
    np.testing.assert_allclose(kin.theta, theta, rtol=1e-13)


@pytest.mark.parametrize("shape", SHAPES)
def test_newton_euler_for_the_mass_center(shape, derivations):
    """m a_C = N n + F t + m g, with a_C = C'(φ)φ'' + C''(φ)φ'² differentiated by sympy.

    φ'' and (N, F) are the code's; n = (−sin ψ, cos ψ) points from I toward O1 and
    t = (cos ψ, sin ψ). Both components must balance to 1e-12 of m (|a_C| + g + scale).
    """
    d = derivations[shape]
    rng = np.random.default_rng(20 + SHAPES.index(shape))
    scene, phi, phi_dot, torque = sample(rng, 5000, shape)
    m_, r_, _, e_, _, g_, _ = scene.params
    acc = analysis.acceleration(scene, phi, phi_dot, torque)
    dc, d2c = d.dc(phi, r_, _R(scene), e_), d.d2c(phi, r_, _R(scene), e_)
    a_c = dc * acc + d2c * phi_dot**2
    force = analysis.contact(scene, phi, phi_dot, torque)
    psi = analysis.kinematics(scene, phi).psi
    n = np.array([-np.sin(psi), np.cos(psi)])
    t = np.array([np.cos(psi), np.sin(psi)])
    gravity = np.array([np.zeros_like(g_), -g_])
    residual = m_ * a_c - (force.normal * n + force.friction * t + m_ * gravity)
    scale = accel_scale(scene, phi, phi_dot, torque)
    size = m_ * (np.abs(a_c).sum(axis=0) + g_ + (r_ + e_) * scale)
    assert np.max(np.abs(residual) / size) <= 1e-12


@pytest.mark.parametrize("shape", SHAPES)
def test_moment_balance_about_the_mass_center(shape, derivations):
    """m k² φ'' = τ − cφ' + (moment about C of the contact force), all clockwise."""
    d = derivations[shape]
    rng = np.random.default_rng(30 + SHAPES.index(shape))
    scene, phi, phi_dot, torque = sample(rng, 5000, shape)
    m_, r_, _, e_, k_, _, c_ = scene.params
    acc = analysis.acceleration(scene, phi, phi_dot, torque)
    force = analysis.contact(scene, phi, phi_dot, torque)
    pos = d.positions(phi, r_, _R(scene), e_)
    arm = pos[4:6] - pos[2:4]  # from C to I
    psi = analysis.kinematics(scene, phi).psi
    fx = -force.normal * np.sin(psi) + force.friction * np.cos(psi)
    fy = force.normal * np.cos(psi) + force.friction * np.sin(psi)
    moment_cw = -(arm[0] * fy - arm[1] * fx)
    lhs = m_ * k_**2 * acc
    rhs = torque - c_ * phi_dot + moment_cw
    size = m_ * (k_**2 + (r_ + e_) ** 2) * accel_scale(scene, phi, phi_dot, torque)
    assert np.max(np.abs(lhs - rhs) / size) <= 1e-12


@pytest.mark.parametrize("shape", SHAPES)
def test_energy_matches_koenig(shape, derivations):
    """analysis.energy = ½ m v_C² + ½ m k² φ'² + m g (y_C − y_C at rest)."""
    rng = np.random.default_rng(40 + SHAPES.index(shape))
    scene, phi, phi_dot, _ = sample(rng, 5000, shape)
    m_, r_, _, e_, k_, g_, _ = scene.params
    ref = derivations[shape].energy(phi, phi_dot, m_, r_, _R(scene), e_, k_, g_)
    got = analysis.energy(scene, phi, phi_dot)
    # Each term is at most m (k² + (r + e)²) φ'²/2 and m g (2|R − r| + 2e) (a bounded height);
    # the reference subtracts heights of size |R|.
    height = np.where(np.isinf(_R(scene)), 0.0, np.abs(_R(scene))) + r_ + e_
    size = m_ * ((k_**2 + (r_ + e_) ** 2) * phi_dot**2 + g_ * height)
    assert np.max(np.abs(got - ref) / size) <= 1e-12


@pytest.mark.parametrize("shape", SHAPES)
def test_power_balance_by_the_chain_rule(shape, derivations):
    """dE/dt = ∂E/∂φ φ' + ∂E/∂φ' φ'' (sympy's partials, the code's φ'') = τφ' − cφ'²."""
    d = derivations[shape]
    rng = np.random.default_rng(50 + SHAPES.index(shape))
    scene, phi, phi_dot, torque = sample(rng, 5000, shape)
    m_, r_, _, e_, k_, g_, c_ = scene.params
    e_phi, e_w = d.denergy(phi, phi_dot, m_, r_, _R(scene), e_, k_, g_)
    acc = analysis.acceleration(scene, phi, phi_dot, torque)
    rate = e_phi * phi_dot + e_w * acc
    expected = analysis.power(scene, phi_dot, torque)
    drive, loss = torque * phi_dot, c_ * phi_dot**2
    assert np.all(np.abs(expected - (drive - loss)) <= 1e-15 * (np.abs(drive) + loss))
    size = m_ * (k_**2 + (r_ + e_) ** 2) * np.abs(phi_dot) * accel_scale(
        scene, phi, phi_dot, torque
    )
    assert np.max(np.abs(rate - expected) / size) <= 1e-12


@pytest.mark.parametrize("shape", SHAPES)
def test_inertia_potential_and_their_derivatives(shape):
    """J_I, V and their φ-derivatives in `equations` against sympy's, from PHYSICS.md."""
    rng = np.random.default_rng(60 + SHAPES.index(shape))
    scene, phi, _, _ = sample(rng, 3000, shape)
    m_, r_, kappa, e_, k_, g_, _ = scene.params
    if shape == "floor":
        psi_expr, theta_expr, lift = sp.S(0), q, sp.S(0)
    else:
        psi_expr, theta_expr = r * q / (R - r), R * q / (R - r)
        lift = (R - r) * (1 - sp.cos(psi_expr))
    j_i = m * (k**2 + r**2 + e**2 - 2 * r * e * sp.cos(theta_expr))
    v = m * g * (lift + e * (1 - sp.cos(q)))
    args = (q, m, r, R, e, k, g)
    Rv = _R(scene)
    ref = {
        name: sp.lambdify(args, expr, "numpy")(phi, m_, r_, Rv, e_, k_, g_)
        for name, expr in {
            "J": j_i, "dJ": j_i.diff(q), "d2J": j_i.diff(q, 2),
            "V": v, "dV": v.diff(q), "d2V": v.diff(q, 2),
        }.items()
    }
    got = {
        "J": eq.inertia(phi, m_, r_, kappa, e_, k_),
        "dJ": eq.dinertia(phi, m_, r_, kappa, e_),
        "d2J": eq.d2inertia(phi, m_, r_, kappa, e_),
        "V": eq.potential(phi, m_, r_, kappa, e_, g_),
        "dV": eq.dpotential(phi, m_, r_, kappa, e_, g_),
        "d2V": eq.d2potential(phi, m_, r_, kappa, e_, g_),
    }
    s = np.abs(1 - r_ * kappa)
    height = np.where(np.isinf(Rv), 0.0, np.abs(Rv)) + r_ + e_
    sizes = {  # the magnitude of the terms of each quantity
        "J": m_ * (k_ + r_ + e_) ** 2,
        "dJ": m_ * r_ * e_ / s + 1e-300,
        "d2J": m_ * r_ * e_ / s**2 + 1e-300,
        "V": m_ * g_ * height,
        "dV": m_ * g_ * (r_ + e_),
        "d2V": m_ * g_ * (r_**2 * np.abs(kappa) / s + e_) + 1e-300,
    }
    for name in ref:
        err = np.abs(got[name] - ref[name]) / sizes[name]
        assert err.max() <= 1e-12, f"{name}: {err.max():.2e}"


@pytest.mark.parametrize("shape", SHAPES)
def test_instant_center_velocity_is_that_of_the_contact_point(shape, derivations):
    """u = dI/dt, I the geometric contact point R(sin ψ, −cos ψ) (the floor: (rφ, 0))."""
    rng = np.random.default_rng(70 + SHAPES.index(shape))
    scene, phi, phi_dot, _ = sample(rng, 3000, shape)
    _, r_, kappa, _, _, _, _ = scene.params
    got = np.asarray(eq.instant_center_velocity(phi, phi_dot, r_, kappa))
    ref = derivations[shape].u(phi, phi_dot, r_, _R(scene))
    size = r_ * np.abs(phi_dot) / np.abs(1 - r_ * kappa)
    assert np.max(np.abs(got - ref) / size) <= 1e-13
