"""Rendering: rgb_array frames, render_mode=None, headless "human" mode, and
pygame imported only when rendering.

The pictures are checked against the geometry of ``docs/PHYSICS.md``: the contact
point I = R (sin ψ, −cos ψ) from the axis O, so the red contact marker sits below the
picture's center at ψ = 0 and moves right for ψ > 0, left for ψ < 0.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import roller_gym  # noqa: F401  (registers the IDs)

ROOT = Path(__file__).resolve().parents[1]
IDS = ["roller_gym/RollerStabilize-v2", "roller_gym/RollerHold-v2", "roller_gym/RollerBalance-v2"]
CONTACT_RGB = (220, 30, 30)  # the instant center's marker (envs/rendering.py)
TARGET_RGB = (30, 160, 60)  # the target contact point, tasks with a target


def pixels_of(frame: np.ndarray, rgb: tuple[int, int, int]) -> np.ndarray:
    """(row, column) of the pixels of exactly that colour."""
    return np.argwhere(np.all(frame == np.array(rgb, dtype=np.uint8), axis=-1))


def frame_at(env, phi: float, phi_dot: float = 0.0) -> np.ndarray:
    env.reset(seed=0, options={"state": (phi, phi_dot)})
    return env.render()


def test_import_and_stepping_do_not_import_pygame():
    code = (
        "import sys, numpy as np, gymnasium as gym, roller_gym\n"
        "assert 'pygame' not in sys.modules\n"
        "env = gym.make('roller_gym/RollerHold-v2'); env.reset(seed=0)\n"
        "env.step(np.zeros(1, np.float32))\n"
        "vec = gym.make_vec('roller_gym/RollerStabilize-v2', num_envs=2); vec.reset(seed=0)\n"
        "assert 'pygame' not in sys.modules\n"
        "env = gym.make('roller_gym/RollerHold-v2', render_mode='rgb_array'); env.reset(seed=0)\n"
        "env.render()\n"
        "assert 'pygame' in sys.modules\n"
    )
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0, out.stderr


def test_without_pygame_an_env_asked_for_frames_is_made_and_render_says_what_to_install():
    """SB3's make_vec_env asks every environment for render_mode="rgb_array", whether or
    not anything renders: without pygame the environment is made and steps; only render()
    fails, saying what to install."""
    code = ("import sys; sys.modules['pygame'] = None\n"
            "import gymnasium as gym, numpy as np, roller_gym\n"
            "env = gym.make('roller_gym/RollerStabilize-v2', render_mode='rgb_array')\n"
            "env.reset(seed=0); env.step(np.zeros(1, np.float32))\n"
            "try:\n"
            "    env.render()\n"
            "except ImportError as exc:\n"
            "    print(exc)\n")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == ("rendering needs pygame, which is not installed: "
                                  'pip install ".[render]" (in a clone of the repository)')


@pytest.mark.parametrize("env_id", IDS)
def test_rgb_array_frames(env_id):
    env = gym.make(env_id, render_mode="rgb_array")
    assert env.render_mode == "rgb_array"
    first = frame_at(env, 0.0)
    assert first.dtype == np.uint8 and first.ndim == 3 and first.shape[2] == 3
    assert first.shape[0] > 100 and first.shape[1] > 100
    assert len(np.unique(first.reshape(-1, 3), axis=0)) > 3  # a picture, not a blank
    np.testing.assert_array_equal(first, frame_at(env, 0.0))  # the same state, the same frame
    moved = frame_at(env, 0.5)
    assert first.shape == moved.shape
    assert np.count_nonzero(np.any(first != moved, axis=-1)) > 100
    # Stepping moves the roller and draws the torque: the frame changes.
    env.reset(seed=0, options={"state": (0.0, 0.0)})
    before = env.render()
    env.step(np.array([1.0], np.float32))
    assert np.any(env.render() != before)
    # Only the task with a target draws it.
    assert (len(pixels_of(first, TARGET_RGB)) > 0) == (env_id == "roller_gym/RollerHold-v2")
    env.close()


@pytest.mark.parametrize("phi", [-1.5, 0.0, 1.5])
def test_contact_marker_follows_psi(phi):
    """ψ = rφ/(R − r) = φ/4 in "paper": the marker moves right of the centre line for
    ψ > 0, left for ψ < 0, and lies below the centre at ψ = 0."""
    env = gym.make("roller_gym/RollerStabilize-v2", render_mode="rgb_array")
    frame = frame_at(env, phi)
    red = pixels_of(frame, CONTACT_RGB)
    assert len(red) > 5
    row, col = red.mean(axis=0)
    height, width = frame.shape[:2]
    psi = phi * 0.1 / (0.5 - 0.1)
    # The picture shows the wall's circle about O; x offset ∝ R sin ψ, y ∝ R cos ψ.
    dx, dy = col - width / 2, row - height / 2
    if psi == 0:
        assert abs(dx) <= 2 and dy > 0
    else:
        assert math.copysign(1, dx) == math.copysign(1, psi)
        assert math.atan2(dx, dy) == pytest.approx(psi, abs=0.05)


def test_render_mode_none_warns_and_returns_none():
    env = gym.make("roller_gym/RollerStabilize-v2")
    env.reset(seed=0)
    with pytest.warns(UserWarning, match="render_mode"):
        assert env.render() is None


def test_human_mode_headless(monkeypatch, tmp_path):
    """With SDL's dummy video driver the window is drawn off screen: its content is the
    rgb_array frame of the same state."""
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    import pygame

    env = gym.make("roller_gym/RollerHold-v2", render_mode="human")
    env.reset(seed=0, options={"state": (0.3, 0.0), "target": 0.1})
    assert env.render() is None
    surface = pygame.display.get_surface()
    assert surface is not None
    shown = np.transpose(pygame.surfarray.array3d(surface), (1, 0, 2))
    reference = gym.make("roller_gym/RollerHold-v2", render_mode="rgb_array")
    reference.reset(seed=0, options={"state": (0.3, 0.0), "target": 0.1})
    np.testing.assert_array_equal(shown, reference.render())
    env.step(np.array([0.5], np.float32))  # renders on step as well
    after = np.transpose(pygame.surfarray.array3d(pygame.display.get_surface()), (1, 0, 2))
    assert np.any(after != shown)
    env.close()
    assert not pygame.display.get_init()


def test_vector_env_renders_one_frame_per_sub_env():
    vec = gym.make_vec("roller_gym/RollerStabilize-v2", num_envs=2, render_mode="rgb_array",
                       scene=["paper", "floor"])
    vec.reset(seed=0)
    frames = vec.render()
    assert len(frames) == 2
    for f in frames:
        assert f.dtype == np.uint8 and f.ndim == 3 and f.shape[2] == 3
    assert np.any(frames[0] != frames[1])
    single = gym.make("roller_gym/RollerStabilize-v2", render_mode="rgb_array")
    single.reset(seed=0)
    np.testing.assert_array_equal(frames[0], single.render())  # seed 0 + 0, same state
    vec.close()


def test_a_target_far_along_the_floor_is_off_the_picture_not_a_crash():
    """On the floor the picture follows the roller: a target hundreds of radians away lies
    beyond pygame's 16-bit coordinates, and drawing it raised OverflowError. It is drawn off
    the picture (no target pixels), the roller and its contact still on it."""
    env = gym.make("roller_gym/RollerHold-v2", scene="floor", render_mode="rgb_array")
    env.reset(seed=0, options={"target": 0.0, "state": (1000.0, 0.0)})
    frame = env.render()
    assert len(pixels_of(frame, TARGET_RGB)) == 0 and len(pixels_of(frame, CONTACT_RGB)) > 5
    env.reset(seed=0, options={"target": 0.0, "state": (0.3, 0.0)})  # near: on the picture
    assert len(pixels_of(env.render(), TARGET_RGB)) > 5
