"""The construction arguments every roller environment takes, checked in one place.

Both the single environment (:mod:`roller_gym.roller_env`) and the native vector environment
(:mod:`roller_gym.vector_env`) build their settings here, so they accept the same keywords with
the same errors, draw scenes the same way and turn actions into torques the same way.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from roller_gym.physics import METHODS, Scene, preset
from roller_gym.physics.integrators import MAX_SUBSTEPS
from roller_gym.task import Task

__all__ = ["DEFAULT_DT", "DEFAULT_TOLERANCE", "EnvConfig", "resolve_scene"]

#: The control step [s] (as Gymnasium's Pendulum).
DEFAULT_DT = 0.05
#: The integrator's target state error per control step (φ in rad, φ' in rad/s).
DEFAULT_TOLERANCE = 1e-8
_SCENE_FIELDS = tuple(f.name for f in fields(Scene))


def resolve_scene(scene: Scene | str | None, default: str) -> Scene:
    """A Scene from a Scene, a preset's name, or None (the task's default preset)."""
    if scene is None:
        return preset(default)
    if isinstance(scene, str):
        return preset(scene)
    if isinstance(scene, Scene):
        if scene.batch_size is not None:
            raise ValueError("scene must be a scalar Scene here; a batch goes to the vector env")
        return scene
    raise ValueError(
        f"scene={scene!r} is not allowed: pass an roller_gym.Scene or a preset name "
        "(see roller_gym.PRESETS)"
    )


@dataclass(frozen=True)
class EnvConfig:
    """Checked construction arguments (see :class:`roller_gym.roller_env.RollerEnv` for each)."""

    task: Task
    scene: Scene
    dt: float
    tolerance: float
    integrator: str
    substeps: int
    randomize: Mapping[str, tuple[float, float]]
    render_mode: str | None

    @classmethod
    def build(
        cls,
        task_class: type[Task],
        *,
        scene: Scene | str | None,
        dt: float,
        max_torque: float | None,
        tolerance: float,
        integrator: str,
        substeps: int | None,
        randomize: Mapping[str, tuple[float, float]] | None,
        render_mode: str | None,
        render_modes: list[str],
    ) -> EnvConfig:
        task = task_class(max_torque)
        scene = resolve_scene(scene, task.default_scene)
        task.check_scene(scene)
        if not (isinstance(dt, int | float) and math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt={dt!r} [s] must be a finite number > 0")
        if not (isinstance(tolerance, int | float) and math.isfinite(tolerance) and tolerance > 0):
            raise ValueError(f"tolerance={tolerance!r} must be a finite number > 0")
        if integrator not in METHODS:
            raise ValueError(f"integrator={integrator!r} is not one of {', '.join(METHODS)}")
        if substeps is not None and not (
            isinstance(substeps, int) and 1 <= substeps <= MAX_SUBSTEPS
        ):
            raise ValueError(
                f"substeps={substeps!r} must be None (automatic) or an integer in "
                f"[1, {MAX_SUBSTEPS}]"
            )
        ranges = {}
        for name, bounds in (randomize or {}).items():
            if name not in _SCENE_FIELDS:
                raise ValueError(
                    f"randomize names {name!r}, not a Scene field; allowed: "
                    f"{', '.join(_SCENE_FIELDS)}"
                )
            try:
                low, high = (float(b) for b in bounds)
            except (TypeError, ValueError):
                raise ValueError(
                    f"randomize[{name!r}]={bounds!r} must be a (low, high) pair of numbers"
                ) from None
            if not (math.isfinite(low) and math.isfinite(high) and low <= high):
                raise ValueError(f"randomize[{name!r}]={bounds!r} needs finite low <= high")
            scene.replace(**{name: low})  # each end must make a valid scene
            scene.replace(**{name: high})
            ranges[name] = (low, high)
        if render_mode is not None and render_mode not in render_modes:
            raise ValueError(
                f"render_mode={render_mode!r} is not one of {render_modes} (or None)"
            )
        return cls(task, scene, float(dt), float(tolerance), integrator, substeps or 0,
                   ranges, render_mode)

    def draw_scene(self, rng: np.random.Generator) -> Scene:
        """The scene of a new episode: the base scene, with the randomized fields drawn."""
        if not self.randomize:
            return self.scene
        return self.scene.replace(
            **{name: rng.uniform(low, high) for name, (low, high) in self.randomize.items()}
        )

    def scene_row(self, scene: Scene) -> tuple[float, ...]:
        """The numbers the integrator kernels take: ``(*Scene.params, mu)`` as floats."""
        return (*(float(p) for p in scene.params), float(scene.mu))

    @staticmethod
    def action_values(action: Any, shape: tuple[int, ...]) -> np.ndarray:
        """Actions as float64 in [−1, 1] of ``shape``: out-of-range values are clipped;
        NaN, inf or a wrong shape raise ValueError."""
        try:
            a = np.asarray(action, dtype=np.float64).reshape(shape)
        except (TypeError, ValueError):
            raise ValueError(
                f"action={action!r} must be numbers of shape {shape} in [-1, 1]"
            ) from None
        if not np.isfinite(a).all():
            raise ValueError(
                f"action={action!r} is not finite; actions must be finite numbers in [-1, 1] "
                "(out-of-range values are clipped)"
            )
        return np.clip(a, -1.0, 1.0)

    def resolve_option_scene(self, value: Any) -> Scene:
        return resolve_scene(value, self.task.default_scene)
