"""Scenes: validation, shapes, presets, continuity as R grows, and batches."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from roller_gym.physics import PRESETS, Scene, analysis, preset
from roller_gym.physics import equations as eq

FIELDS = ("m", "r", "R", "e", "k", "g", "mu", "damping")

# -- validation -----------------------------------------------------------------------------------

OUT_OF_RANGE = [
    # (field, value, the allowed range as the message must state it)
    ("m", 0.0, "> 0"),
    ("m", -2.0, "> 0"),
    ("m", math.inf, "finite"),
    ("r", 0.0, "> 0"),
    ("r", -0.1, "> 0"),
    ("k", 0.0, "> 0"),
    ("k", -0.06, "> 0"),
    ("e", -0.01, ">= 0"),
    ("mu", -0.1, ">= 0"),
    ("g", 0.0, "> 0"),
    ("g", -9.81, "> 0"),
    ("damping", -1e-3, ">= 0"),
]


@pytest.mark.parametrize(("field", "value", "allowed"), OUT_OF_RANGE)
def test_out_of_range_field_is_named_with_its_value_and_range(field, value, allowed):
    with pytest.raises(ValueError) as info:
        Scene(**{field: value})
    message = str(info.value)
    assert f"Scene.{field}={value!r}" in message
    assert allowed in message


@pytest.mark.parametrize("R", [0.05, 0.1, 1e-9, 0.0, -0.0, -math.inf])
def test_radius_not_allowed_for_any_shape(R):
    """0 < R <= r (a cylinder narrower than the roller), R = 0 and R = −inf are rejected."""
    with pytest.raises(ValueError) as info:
        Scene(r=0.1, R=R)
    message = str(info.value)
    assert f"Scene.R={R!r}" in message
    assert "r=0.1" in message
    for allowed in ("> r", "math.inf", "negative"):
        assert allowed in message


@pytest.mark.parametrize("field", FIELDS)
def test_nan_is_rejected_for_every_field(field):
    with pytest.raises(ValueError) as info:
        Scene(**{field: math.nan})
    assert f"Scene.{field}=nan" in str(info.value)
    assert "NaN" in str(info.value)


def test_a_bad_element_of_a_batch_is_rejected():
    with pytest.raises(ValueError) as info:
        Scene(k=np.array([0.06, -1.0, 0.05]))
    assert "Scene.k=" in str(info.value) and "-1." in str(info.value)
    with pytest.raises(ValueError, match=r"Scene\.R=.*0\.05"):
        Scene(r=0.1, R=np.array([0.5, 0.05]))
    with pytest.raises(ValueError, match=r"Scene\.e=.*NaN"):
        Scene(e=np.array([0.0, math.nan]))


@pytest.mark.parametrize(("field", "value"), [("m", "2"), ("e", "0.04"), ("R", "inf"),
                                              ("m", True), ("k", 1j), ("g", [9.81, "x"])])
def test_text_bools_and_complex_numbers_are_not_real_numbers(field, value):
    """What NumPy would convert to a float ("2", True) is refused as well, naming the field."""
    with pytest.raises(ValueError, match=rf"Scene\.{field}=.* is not a real number"):
        Scene(**{field: value})


def test_not_a_number_is_rejected():
    with pytest.raises(ValueError, match=r"Scene\.m='heavy' is not a real number"):
        Scene(m="heavy")


def test_replace_validates_again():
    with pytest.raises(ValueError, match=r"Scene\.r=-0\.1"):
        PRESETS["paper"].replace(r=-0.1)
    assert PRESETS["paper"].replace(e=0.0).e == 0.0


def test_scene_is_immutable():
    with pytest.raises(dataclasses.FrozenInstanceError):
        PRESETS["paper"].m = 2.0  # type: ignore[misc]


# -- shapes and presets ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("R", "shape", "kappa"),
    [(0.5, "cylinder", 2.0), (0.1 + 1e-12, "cylinder", 1 / (0.1 + 1e-12)),
     (math.inf, "floor", 0.0), (-0.5, "drum", -2.0), (-0.01, "drum", -100.0)],
)
def test_shape_and_signed_curvature(R, shape, kappa):
    scene = Scene(r=0.1, R=R)
    assert scene.shape == shape
    assert scene.kappa == kappa
    assert scene.params == (scene.m, scene.r, kappa, scene.e, scene.k, scene.g, scene.damping)


def test_presets_are_the_scenes_they_say():
    r = 0.1
    solid = preset("solid_disc")
    assert solid.e == 0.0
    assert math.isclose(solid.k**2, solid.r**2 / 2, rel_tol=1e-15)
    assert math.isclose(preset("tight_fit").R, 1.01 * r, rel_tol=1e-15)
    rim = preset("rim_mass")
    assert math.isclose(rim.e, 0.99 * rim.r, rel_tol=1e-15)
    assert math.isclose(rim.k, 0.05 * rim.r, rel_tol=1e-15)
    assert preset("floor").shape == "floor"
    drum = preset("drum")
    assert drum.shape == "drum"
    # Bottom-heavy enough to rest on top of the drum: d²V/dφ² = m g (r²/(R − r) + e) > 0.
    assert drum.e > drum.r**2 / (abs(drum.R) + drum.r)
    balance = preset("balance")
    assert math.isclose(balance.R, 10 * r, rel_tol=1e-15)
    assert math.isclose(balance.e, 0.8 * r, rel_tol=1e-15)
    assert preset("paper").shape == "cylinder"
    for name, scene in PRESETS.items():
        assert scene.r == r, name
        assert scene.batch_size is None


def test_unknown_preset_lists_the_allowed_names():
    with pytest.raises(ValueError) as info:
        preset("moon")
    for name in PRESETS:
        assert name in str(info.value)


# -- continuity as R grows --------------------------------------------------------------------


def _quantities(scene: Scene, phi, phi_dot, torque):
    """Acceleration, energy, positions and contact forces, with the size of each."""
    m, r, _, e, k, g, _ = scene.params
    acc = analysis.acceleration(scene, phi, phi_dot, torque)
    acc_size = (np.abs(torque) / m + g * (r + e) + (r + e) ** 2 * phi_dot**2) / k**2
    kin = analysis.kinematics(scene, phi)
    force = analysis.contact(scene, phi, phi_dot, torque)
    pos_size = r * (1 + np.abs(phi))
    return {
        "accel": (acc, acc_size),
        "energy": (
            analysis.energy(scene, phi, phi_dot),
            m * ((k + r + e) ** 2 * phi_dot**2 + g * (r + e) * (1 + np.abs(phi))),
        ),
        **{
            f"{point}{axis}": (getattr(kin, point)[j], pos_size)
            for point in ("o1", "c", "i")
            for j, axis in enumerate("xy")
        },
        "normal": (force.normal, m * (g + (r + e) * acc_size)),
        "friction": (force.friction, m * (g + (r + e) * acc_size)),
    }


@pytest.fixture(scope="module")
def floor_states():
    rng = np.random.default_rng(1)
    n = 2000
    phi = rng.uniform(-4 * math.pi, 4 * math.pi, n)
    phi_dot = rng.uniform(-30, 30, n)
    torque = rng.uniform(-3, 3, n)
    return phi, phi_dot, torque


@pytest.mark.parametrize("R", [1e12, -1e12])
def test_huge_radius_is_the_floor(R, floor_states):
    """R = ±1e12 m agrees with the floor (R = inf) to 1e-12 of each quantity's size.

    The floor's formulas have no R in them; a formula that subtracted coordinates of size R
    (e.g. R − (R − r) cos ψ) would be off by ~1e-4 here.
    """
    floor = PRESETS["paper"].replace(R=math.inf)
    far = PRESETS["paper"].replace(R=R)
    ref = _quantities(floor, *floor_states)
    got = _quantities(far, *floor_states)
    for name, (value, size) in got.items():
        assert np.all(np.isfinite(value)), name
        assert np.max(np.abs(value - ref[name][0]) / size) <= 1e-12, name


@pytest.mark.parametrize("ratio", [1e3, 1e6, 1e9, -1e3, -1e6, -1e9])
def test_quantities_converge_to_the_floor_at_rate_r_over_R(ratio, floor_states):
    """|f(R) − f(floor)| <= 2 (1 + |φ|)(r/|R|) size: continuous in κ = 1/R, no cancellation.

    ψ ≈ rφ/R, so each quantity moves from the floor's by about (r/R)|φ| of its size (the
    heights by (r/R) φ²/2, and |φ| r <= (1 + |φ|) r is inside the positions' size).
    """
    base = PRESETS["paper"]
    floor = base.replace(R=math.inf)
    far = base.replace(R=ratio * base.r)
    phi = floor_states[0]
    ref = _quantities(floor, *floor_states)
    got = _quantities(far, *floor_states)
    bound = 2 * (1 + np.abs(phi)) / abs(ratio) + 1e-13
    for name, (value, size) in got.items():
        assert np.all(np.abs(value - ref[name][0]) / size <= bound), name


# -- batches ----------------------------------------------------------------------------------


def test_stack_and_item_round_trip():
    scenes = list(PRESETS.values())
    batch = Scene.stack(scenes)
    assert batch.batch_size == len(scenes)
    assert list(batch.shape) == [s.shape for s in scenes]
    for i, scene in enumerate(scenes):
        assert batch.item(i) == scene
    np.testing.assert_array_equal(batch.kappa, [s.kappa for s in scenes])


def test_mixed_scalar_and_array_fields_broadcast():
    scene = Scene(m=np.array([1.0, 2.0, 3.0]), R=math.inf)
    assert scene.batch_size == 3
    assert scene.item(2) == Scene(m=3.0, R=math.inf)
    assert list(scene.shape) == ["floor"] * 3


def test_batch_evaluation_equals_scalar_evaluation():
    """Per-element scene parameters broadcast against (3, 7) states: every element equals
    the scalar evaluation with that element's scene (to 1e-15 of its size: the same
    arithmetic, though NumPy may vectorize it differently)."""
    scenes = list(PRESETS.values())
    batch = Scene.stack(scenes)
    rng = np.random.default_rng(2)
    shape = (3, len(scenes))
    phi = rng.uniform(-3, 3, shape)
    phi_dot = rng.uniform(-5, 5, shape)
    torque = rng.uniform(-1, 1, shape)
    got = _quantities(batch, phi, phi_dot, torque)
    for i in range(shape[0]):
        for j, scene in enumerate(scenes):
            ref = _quantities(scene, phi[i, j], phi_dot[i, j], torque[i, j])
            for name, (value, size) in got.items():
                assert np.shape(value) == shape, name
                assert abs(value[i, j] - ref[name][0]) <= 1e-15 * size[i, j], (name, i, j)


def test_every_equation_broadcasts_per_element_scene_parameters():
    """Each function of `equations` with a batch of scene parameters and (3, 7) states gives,
    element by element, its value for that element's scalar parameters."""
    scenes = list(PRESETS.values())
    batch = Scene.stack(scenes)
    rng = np.random.default_rng(3)
    shape = (3, len(scenes))
    phi, w, tau, acc = (rng.uniform(-3, 3, shape) for _ in range(4))

    def calls(scene, phi, w, tau, acc):
        m, r, kappa, e, k, g, c = scene.params
        return {
            "accel": eq.accel(phi, w, tau, m, r, kappa, e, k, g, c),
            "accel_concentric": eq.accel_concentric(phi, w, tau, m, r, kappa, k, g, c),
            "inertia": eq.inertia(phi, m, r, kappa, e, k),
            "dinertia": eq.dinertia(phi, m, r, kappa, e),
            "d2inertia": eq.d2inertia(phi, m, r, kappa, e),
            "ic_squared": eq.ic_squared(phi, r, kappa, e),
            "potential": eq.potential(phi, m, r, kappa, e, g),
            "dpotential": eq.dpotential(phi, m, r, kappa, e, g),
            "d2potential": eq.d2potential(phi, m, r, kappa, e, g),
            "energy": eq.energy(phi, w, m, r, kappa, e, k, g),
            "denergy_dt": eq.denergy_dt(w, tau, c),
            "positions": np.array(eq.positions(phi, r, kappa, e)),
            "instant_center_velocity": np.array(eq.instant_center_velocity(phi, w, r, kappa)),
            "contact_forces": np.array(eq.contact_forces(phi, w, acc, m, r, kappa, e, g)),
            "shape_factors": np.array(np.broadcast_arrays(*eq.shape_factors(phi, r, kappa))),
        }

    got = calls(batch, phi, w, tau, acc)
    for i in range(shape[0]):
        for j, scene in enumerate(scenes):
            ref = calls(scene, phi[i, j], w[i, j], tau[i, j], acc[i, j])
            for name, value in got.items():
                np.testing.assert_allclose(value[..., i, j], ref[name], rtol=1e-14,
                                           atol=1e-14, err_msg=name)


def test_as_dict_gives_plain_numbers_for_a_scalar_scene_and_a_batch():
    """A batch gives one list per field, a field shared by the batch repeated (it raised
    NumPy's "only 0-dimensional arrays can be converted")."""
    assert Scene(m=2.0).as_dict() == {f.name: getattr(Scene(m=2.0), f.name)
                                      for f in dataclasses.fields(Scene)}
    batch = Scene(m=np.array([1.0, 2.0]), e=np.array([0.01, 0.02]))
    got = batch.as_dict()
    for i in range(2):
        assert {name: values[i] for name, values in got.items()} == batch.item(i).as_dict()
    assert all(type(v) is list and all(type(x) is float for x in v) for v in got.values())


def test_the_presets_cannot_be_changed_by_accident():
    """``PRESETS`` is read-only: a user's assignment would otherwise change every later
    environment's default scene in the process."""
    with pytest.raises(TypeError):
        PRESETS["paper"] = Scene(m=2.0)
    with pytest.raises(AttributeError):
        PRESETS.pop("paper")
    assert preset("paper") == Scene()


def test_a_batch_scene_cannot_be_changed_past_its_checks():
    """A batch scene kept the caller's array: changing it afterwards (or the scene's own
    array) gave a scene its checks would refuse, R below r, which physics.step then stepped
    and reported within tol. The scene now keeps a read-only copy."""
    given = np.array([0.5, 0.6, 0.7])
    scene = Scene(R=given, m=np.array([1.0, 2.0, 3.0]))
    given[1] = 0.05  # the caller's array: the scene does not see it
    assert scene.R[1] == 0.6
    with pytest.raises(ValueError, match="read-only"):
        scene.R[1] = 0.05
    assert not scene.m.flags.writeable
    with pytest.raises(ValueError, match="R must be > r"):
        Scene(R=np.array([0.5, 0.05, 0.7]))  # what the change would have made
