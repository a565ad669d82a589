"""The construction arguments every roller environment takes, checked in one place.

Both the single environment (:mod:`roller_gym.roller_env`) and the native vector environment
(:mod:`roller_gym.vector_env`) build their settings here, so they accept the same keywords with
the same errors, draw scenes the same way and turn actions into torques the same way.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from roller_gym import validation
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
    ) -> EnvConfig:
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
        info_keys = validation.subset("info_keys", info_keys, tuple(INFO_KEYS))
        validation.check_integrable(scene, dt, task.max_torque)
        reason = task.infeasible(scene)
        if reason is not None:
            raise ValueError(reason)
        ranges = check_randomize(task, scene, dt, randomize)
        return cls(task, scene, dt, tolerance, integrator, substeps or 0, ranges, render_mode,
                   info_keys)

    def resolve_option_scene(self, value: Any) -> Scene:
        return resolve_scene(value, self.task.default_scene)


#: Points per randomized field at which a range's feasibility is checked (and refined).
RANGE_POINTS = 33


def check_randomize(task: Task, scene: Scene, dt: float,
                    randomize: Mapping[str, Any] | None) -> dict[str, tuple[float, float]]:
    """The ``randomize`` ranges, checked: each names a Scene field and is a (low, high) pair
    of finite reals with low <= high; every value in it gives a valid scene (each field's
    rule holds on the whole interval: these rules are intervals, so the ends and, for R,
    the forbidden band [0, r] decide); and the task can be posed in the scenes of the
    ranges (:meth:`Task.infeasible`, and :func:`validation.check_integrable`). The last is
    checked at every corner of the box of ranges and at RANGE_POINTS points along each
    field with the others at their ends, so a narrow infeasible pocket between checked
    points can escape it; where a check fails the error names the field and the feasible
    part of its range found by bisection to 1e-6 of its width.
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
            scene.replace(**{name: end})
    if "R" in ranges:
        low, high = ranges["R"]
        r_high = ranges.get("r", (0.0, float(scene.r)))[1]
        if not (high < 0 or low > r_high):
            raise ValueError(
                f"randomize['R']={ranges['R']!r} passes through R in [0, r] (r up to "
                f"{r_high} m), which is no scene: R must stay > r (inside a cylinder) or < 0 "
                "(on a drum) over the whole range"
            )

    def problem(values: dict[str, float]) -> str | None:
        candidate = scene.replace(**values)
        try:
            validation.check_integrable(candidate, dt, task.max_torque)
        except ValueError as error:
            return str(error)
        return task.infeasible(candidate)

    names = list(ranges)
    corners = [dict(zip(names, ends, strict=True))
               for ends in itertools.product(*(ranges[n] for n in names))]
    for name in names:
        low, high = ranges[name]
        for corner in corners:
            for value in np.linspace(low, high, RANGE_POINTS):
                reason = problem({**corner, name: float(value)})
                if reason is not None:
                    feasible = _feasible_part(lambda v, c=corner, n=name: problem(
                        {**c, n: v}) is None, low, high, RANGE_POINTS)
                    raise ValueError(
                        f"randomize[{name!r}]={ranges[name]!r} cannot be used: at {name} = "
                        f"{float(value):.6g} (other fields at {corner}) {reason}; feasible "
                        f"part of the range: {feasible}"
                    )
    return ranges


def _feasible_part(ok, low: float, high: float, points: int) -> str:
    """The longest feasible run of a scan of [low, high], its ends refined by bisection."""
    grid = np.linspace(low, high, points)
    flags = [ok(float(v)) for v in grid]
    best, start = None, None
    for i, flag in enumerate([*flags, False]):
        if flag and start is None:
            start = i
        if not flag and start is not None:
            if best is None or i - start > best[1] - best[0]:
                best = (start, i - 1)
            start = None
    if best is None:
        return "none"
    ends = []
    for inside, step in ((best[0], -1), (best[1], 1)):
        a = float(grid[inside])
        outside = inside + step
        if not 0 <= outside < points:
            ends.append(a)
            continue
        b = float(grid[outside])
        for _ in range(40):
            if abs(b - a) <= 1e-6 * (high - low):
                break
            mid = 0.5 * (a + b)
            a, b = (mid, b) if ok(mid) else (a, mid)
        ends.append(a)
    return f"[{min(ends):.6g}, {max(ends):.6g}]"
