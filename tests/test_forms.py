"""Every form of Vâlcovici's theorem (Eqs. 15, 18, 24, 30 and the closed form) agrees.

The forms are evaluated from the scene's vectors (forms.py) and solved for φ''; they are
compared with one another on random scenes of all three shapes and against analytic
properties of the equation of motion in docs/PHYSICS.md. (Lagrange's equations and Newton–Euler
are in test_reference_derivations.py.)

Random states keep |ψ| <= π and |φ| <= 4π: in a physically meaningful range. (In a tight
fit at large |φ| the positions have large coordinates and the vector forms lose digits;
that is a property of those forms, not of the model.)
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from roller_gym.physics import FORMS, PRESETS, Scene
from roller_gym.physics import equations as eq
from sampling import SHAPES, accel_scale, sample, states

TOL = 1e-12  # relative to the magnitude of the terms (see sampling.accel_scale)


def spec_inertia(scene: Scene, phi):
    """J_I = m (k² + r² + e² − 2 r e cos θ), θ = φ R/(R − r) = φ/(1 − rκ) (PHYSICS.md)."""
    m, r, kappa, e, k, _, _ = scene.params
    return m * (k**2 + r**2 + e**2 - 2 * r * e * np.cos(phi / (1 - r * kappa)))


def spec_holding_torque(scene: Scene, phi):
    """m g (r sin ψ + e sin φ), ψ = rκφ/(1 − rκ): the moment of gravity about I."""
    m, r, kappa, e, _, g, _ = scene.params
    return m * g * (r * np.sin(r * kappa * phi / (1 - r * kappa)) + e * np.sin(phi))


def worst(a, b, scale) -> float:
    return float(np.max(np.abs(a - b) / scale))


@pytest.mark.parametrize("shape", SHAPES)
def test_all_forms_agree_on_random_scenes_and_states(shape):
    """10,000 random scenes, states and torques per shape: every pair of forms within 1e-12."""
    rng = np.random.default_rng(100 + SHAPES.index(shape))
    scene, phi, phi_dot, torque = sample(rng, 10_000, shape)
    scale = accel_scale(scene, phi, phi_dot, torque)
    results = {name: form(scene, phi, phi_dot, torque) for name, form in FORMS.items()}
    names = list(results)
    for i, x in enumerate(names):
        assert np.all(np.isfinite(results[x]))
        for y in names[i + 1 :]:
            assert worst(results[x], results[y], scale) <= TOL, (x, y)


HARD = {
    **{name: PRESETS[name] for name in ("tight_fit", "rim_mass", "balance", "floor", "drum")},
    "R=1.001r": PRESETS["paper"].replace(R=1.001 * 0.1),
    "e=0.999r,k=0.01r": PRESETS["paper"].replace(e=0.0999, k=0.001),
    "R=1e12": PRESETS["paper"].replace(R=1e12),
}


@pytest.mark.parametrize("name", list(HARD))
def test_all_forms_agree_on_the_hard_scenes(name):
    """The stiff and extreme scenes, 2,000 random states each (|ψ| <= π, |φ| <= 4π)."""
    scene = HARD[name]
    rng = np.random.default_rng(200 + list(HARD).index(name))
    phi, phi_dot, torque = states(rng, scene, 2000)
    scale = accel_scale(scene, phi, phi_dot, torque)
    reference = FORMS["closed_form"](scene, phi, phi_dot, torque)
    for form_name, form in FORMS.items():
        assert worst(form(scene, phi, phi_dot, torque), reference, scale) <= TOL, form_name


@pytest.mark.parametrize("shape", SHAPES)
def test_every_form_is_at_rest_under_the_holding_torque(shape):
    """φ' = 0 and τ = m g (r sin ψ + e sin φ) (PHYSICS.md's moment of gravity): φ'' = 0."""
    rng = np.random.default_rng(110 + SHAPES.index(shape))
    scene, phi, _, _ = sample(rng, 5000, shape)
    zero = np.zeros_like(phi)
    torque = spec_holding_torque(scene, phi)
    scale = accel_scale(scene, phi, zero, torque)
    for name, form in FORMS.items():
        assert worst(form(scene, phi, zero, torque), 0.0, scale) <= TOL, name


@pytest.mark.parametrize("shape", SHAPES)
def test_every_form_responds_to_torque_as_one_over_j_i(shape):
    """∂φ''/∂τ = 1/J_I with J_I = m (k² + r² + e² − 2 r e cos θ): φ''(τ + δ) − φ''(τ) = δ/J_I."""
    rng = np.random.default_rng(120 + SHAPES.index(shape))
    scene, phi, phi_dot, torque = sample(rng, 5000, shape)
    delta = rng.uniform(0.5, 1.0, phi.shape) * scene.m * scene.g * scene.r
    scale = accel_scale(scene, phi, phi_dot, np.abs(torque) + delta)
    expected = delta / spec_inertia(scene, phi)
    for name, form in FORMS.items():
        change = form(scene, phi, phi_dot, torque + delta) - form(scene, phi, phi_dot, torque)
        assert worst(change, expected, scale) <= 4 * TOL, name


@pytest.mark.parametrize("shape", SHAPES)
def test_every_form_treats_damping_as_a_torque_minus_c_phi_dot(shape):
    """The axle's damping is the torque −cφ': φ''(c) at τ equals φ''(c = 0) at τ − cφ'."""
    rng = np.random.default_rng(130 + SHAPES.index(shape))
    scene, phi, phi_dot, torque = sample(rng, 5000, shape)
    undamped = scene.replace(damping=np.zeros_like(phi))
    scale = accel_scale(scene, phi, phi_dot, torque)
    for name, form in FORMS.items():
        damped = form(scene, phi, phi_dot, torque)
        shifted = form(undamped, phi, phi_dot, torque - scene.damping * phi_dot)
        assert worst(damped, shifted, scale) <= TOL, name


@pytest.mark.parametrize("shape", SHAPES)
def test_every_form_is_mirror_symmetric(shape):
    """The scene is symmetric about the vertical: φ''(−φ, −φ', −τ) = −φ''(φ, φ', τ)."""
    rng = np.random.default_rng(140 + SHAPES.index(shape))
    scene, phi, phi_dot, torque = sample(rng, 5000, shape)
    scale = accel_scale(scene, phi, phi_dot, torque)
    for name, form in FORMS.items():
        mirrored = form(scene, -phi, -phi_dot, -torque)
        assert worst(mirrored, -form(scene, phi, phi_dot, torque), scale) <= TOL, name


@pytest.mark.parametrize("name", ["paper", "solid_disc", "tight_fit", "rim_mass", "drum", "floor"])
def test_every_form_linearizes_to_the_papers_small_amplitude_equation(name):
    """φ'' ≈ −ω0² φ near φ = 0 with ω0² = g (r²/(R − r) + e)/(k² + (r − e)²) (the paper).

    At φ = 1e-7 rad at rest, the neglected terms are relatively O(θ²) from sin and O(θ² re/
    (k² + (r − e)²)) from J_I (θ = φ/(1 − rκ)); the bound is their sum plus 1e-13 of rounding.
    """
    scene = PRESETS[name]
    _, r, kappa, e, k, g, _ = scene.params
    lift = 0.0 if math.isinf(scene.R) else r**2 / (scene.R - r)
    j0 = k**2 + (r - e) ** 2
    omega0_sq = g * (lift + e) / j0
    phi = 1e-7
    theta = phi / (1 - r * kappa)
    bound = theta**2 * (1 + r * e / j0) + 1e-13
    for form_name, form in FORMS.items():
        slope = form(scene, phi, 0.0, 0.0) / phi
        assert abs(slope + omega0_sq) <= bound * omega0_sq, form_name


@pytest.mark.parametrize("shape", SHAPES)
def test_concentric_equation_is_the_general_one_at_e_zero(shape):
    """accel_concentric (the e = 0 path of the integrators) equals accel with e = 0."""
    rng = np.random.default_rng(150 + SHAPES.index(shape))
    scene, phi, phi_dot, torque = sample(rng, 5000, shape)
    scene = scene.replace(e=np.zeros_like(phi))
    m, r, kappa, e, k, g, c = scene.params
    general = eq.accel(phi, phi_dot, torque, m, r, kappa, e, k, g, c)
    concentric = eq.accel_concentric(phi, phi_dot, torque, m, r, kappa, k, g, c)
    assert worst(general, concentric, accel_scale(scene, phi, phi_dot, torque)) <= 1e-14
    # ... and with e = 0 the analytic (k² + r²) φ'' + g r sin ψ = (τ − cφ')/m holds.
    psi = r * kappa * phi / (1 - r * kappa)
    expected = ((torque - c * phi_dot) / m - g * r * np.sin(psi)) / (k**2 + r**2)
    assert worst(concentric, expected, accel_scale(scene, phi, phi_dot, torque)) <= TOL


def test_forms_of_a_batch_equal_the_forms_element_by_element():
    """A batch scene with array states gives, per element, what the scalar scene gives."""
    rng = np.random.default_rng(160)
    parts = [sample(rng, 20, shape) for shape in SHAPES]
    scene = Scene.stack([p[0].item(i) for p in parts for i in range(20)])
    phi, phi_dot, torque = (np.concatenate([p[j] for p in parts]) for j in (1, 2, 3))
    scale = accel_scale(scene, phi, phi_dot, torque)
    for name, form in FORMS.items():
        batch = form(scene, phi, phi_dot, torque)
        single = np.array(
            [form(scene.item(i), phi[i], phi_dot[i], torque[i]) for i in range(phi.size)]
        )
        assert worst(batch, single, scale) <= 1e-15, name
