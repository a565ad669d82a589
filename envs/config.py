"""The construction arguments every roller environment takes, checked in one place.

Both the single environment (:mod:`roller_gym.roller_env`) and the native vector environment
(:mod:`roller_gym.vector_env`) build their settings here, so they accept the same keywords with
the same errors, draw scenes the same way and turn actions into torques the same way.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from roller_gym import feasibility, validation
from roller_gym.episode import INFO_KEYS
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
    info_keys: tuple[str, ...]

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
        info_keys: Sequence[str] | None = None,
        scenes: Sequence[Scene] | None = None,
    ) -> EnvConfig:
        """The checked arguments; ``scenes`` (the vector env's, one per sub-environment)
        replaces ``scene`` in the checks: each distinct one is checked, ``randomize``'s range
        proof included, and an error names its first sub-environment."""
        if max_torque is not None:
            max_torque = validation.real("max_torque", max_torque, positive=True, unit="N·m")
        task = task_class(max_torque)
        scene = resolve_scene(scene, task.default_scene)
        dt = validation.real("dt", dt, positive=True, unit="s")
        tolerance = validation.real("tolerance", tolerance, positive=True)
        integrator = validation.choice("integrator", integrator, tuple(METHODS))
        if substeps is not None:
            substeps = validation.count("substeps", substeps, high=MAX_SUBSTEPS)
        render_mode = validation.choice("render_mode", render_mode, (*render_modes, None))
        # (pygame is not required here: SB3's make_vec_env asks every environment for
        # render_mode="rgb_array" whether or not it will render; render() says what to install)
        info_keys = validation.subset("info_keys", info_keys, tuple(INFO_KEYS))
        distinct: dict[tuple, tuple[int, Scene]] = {}
        for i, one in enumerate([scene] if scenes is None else scenes):
            distinct.setdefault(tuple(one.as_dict().items()), (i, one))
        ranges: dict[str, tuple[float, float]] = {}
        for i, one in distinct.values():
            try:
                validation.check_integrable(one, dt, task.max_torque)
                reason = task.infeasible(one)
                if reason is not None:
                    raise ValueError(reason)
                ranges = check_randomize(task, one, dt, randomize)
            except ValueError as exc:
                if scenes is None:
                    raise
                shared = sum(1 for s in scenes if s == one)
                raise ValueError(f"scene[{i}] (sub-environment {i}"
                                 f"{f' and {shared - 1} more of that scene' if shared > 1 else ''}"
                                 f", {one!r}): {exc}") from None
        return cls(task, scene, dt, tolerance, integrator, substeps or 0, ranges, render_mode,
                   info_keys)

    def resolve_option_scene(self, value: Any) -> Scene:
        return resolve_scene(value, self.task.default_scene)


def check_randomize(task: Task, scene: Scene, dt: float,
                    randomize: Mapping[str, Any] | None) -> dict[str, tuple[float, float]]:
    """The ``randomize`` ranges, checked: each names a Scene field and is a (low, high) pair
    of finite reals with low <= high; every value in it gives a valid scene (each field's
    rule holds on the whole interval: these rules are intervals, so the ends and, for R,
    the forbidden band [0, r] decide); and the task can be posed in every scene of the box
    of ranges (:meth:`Task.infeasible`, and :func:`validation.check_integrable`). The last
    is proven over the whole box, not sampled (:mod:`roller_gym.feasibility`: branch and
    bound, the equations evaluated on intervals), so a range that constructs cannot fail
    at a later reset. Where a scene of the box fails the check, the error names the field,
    the scene and a feasible part of the field's range (found by bisection to 1e-6 of its
    width, through the failing scene); where the proof does not close (as at an isolated
    infeasible value), the range is refused all the same, naming the part that was proven.
    The result is cached per (task, scene, dt, ranges).
    """
    if randomize is None:
        return {}
    if not isinstance(randomize, Mapping):
        raise ValueError(f"randomize={randomize!r} is not allowed: it must be a mapping "
                         "{field: (low, high)} of Scene fields, e.g. {'m': (0.8, 1.2)}")
    ranges: dict[str, tuple[float, float]] = {}
    for name, bounds in randomize.items():
        if name not in _SCENE_FIELDS:
            raise ValueError(f"randomize names {name!r}, not a Scene field; allowed: "
                             f"{', '.join(_SCENE_FIELDS)}")
        if not (isinstance(bounds, tuple | list | np.ndarray) and len(bounds) == 2):
            raise ValueError(f"randomize[{name!r}]={bounds!r} must be a (low, high) pair of "
                             "finite real numbers")
        low = validation.real(f"randomize[{name!r}][0]", bounds[0])
        high = validation.real(f"randomize[{name!r}][1]", bounds[1])
        if low > high:
            raise ValueError(f"randomize[{name!r}]={bounds!r} needs finite low <= high")
        ranges[name] = (low, high)
    for name, (low, high) in ranges.items():  # each field's own rule, on the whole interval
        for end in (low, high):
            try:
                scene.replace(**{name: end})
            except ValueError as exc:
                raise ValueError(f"randomize[{name!r}]={randomize[name]!r} reaches a scene "
                                 f"that is not allowed: {exc}") from None
    if "R" in ranges:
        low, high = ranges["R"]
        r_high = ranges.get("r", (0.0, float(scene.r)))[1]
        if not (high < 0 or low > r_high):
            raise ValueError(
                f"randomize['R']={ranges['R']!r} passes through R in [0, r] (r up to "
                f"{r_high} m), which is no scene: R must stay > r (inside a cylinder) or < 0 "
                "(on a drum) over the whole range"
            )

    if ranges:
        feasibility.check_ranges(task, scene, dt, ranges)
    return ranges

