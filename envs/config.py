"""The construction arguments every roller environment takes: declared, documented and checked
once.

:class:`Settings` is the one signature: its fields, defaults and documentation are the
keywords of ``gymnasium.make`` and ``gymnasium.make_vec`` for every task ID, of
:class:`roller_gym.roller_env.RollerEnv` and of :class:`roller_gym.vector_env.RollerVectorEnv`
(:func:`takes_settings` gives both classes that signature and those docs), and each keyword
keeps its name down to the physics (``Stepper(integrator=..., tolerance=...)``).
:meth:`EnvConfig.build` checks them, so both environments accept the same keywords with the
same errors, draw scenes the same way and turn actions into torques the same way.
"""

from __future__ import annotations

import inspect
import re
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import MISSING, dataclass, field, fields
from typing import Any, TypeVar

from roller_gym import descent, feasibility, validation
from roller_gym.episode import INFO_KEYS
from roller_gym.physics import INTEGRATORS, Scene, preset
from roller_gym.physics.integrators import DEFAULT_INTEGRATOR, MAX_SUBSTEPS
from roller_gym.physics.scene import shown
from roller_gym.task import Task

__all__ = ["DEFAULT_DT", "DEFAULT_TOLERANCE", "EnvConfig", "Settings", "resolve_scene",
           "settings_table", "takes_settings"]

#: The control step [s] (as Gymnasium's Pendulum).
DEFAULT_DT = 0.05
#: The integrator's target state error per control step (φ in rad, φ' in rad/s).
DEFAULT_TOLERANCE = 1e-8
#: The tightest tolerance an environment takes (the physics' steppers take any, and flag what
#: they cannot verify).
TOLERANCE_MIN = 1e-12


def resolve_scene(scene: Scene | str | None, default: str, name: str = "scene") -> Scene:
    """A Scene from a Scene, a preset's name, or None (the task's default preset); errors
    name the argument ``name``."""
    if scene is None:
        return preset(default)
    if isinstance(scene, str):
        return preset(scene)
    if isinstance(scene, Scene):
        if scene.batch_size is not None:
            raise ValueError(f"{name} is a batch Scene of {scene.batch_size} rollers: it must "
                             "be one scalar Scene (a vector environment's scene= takes a list "
                             "of them, one per sub-environment)")
        return scene
    raise ValueError(
        f"{name}={shown(scene)} is not allowed: pass an roller_gym.Scene or a preset name "
        "(see roller_gym.PRESETS)"
    )


def _doc(text: str) -> dict[str, str]:
    return {"doc": text}


@dataclass(frozen=True, kw_only=True)
class Settings:
    """The keywords every roller environment takes, as given (:meth:`EnvConfig.build` checks
    them). Each field's documentation is :func:`setting_docs`."""

    scene: Scene | str | Sequence[Scene | str | None] | None = field(default=None, metadata=_doc(
        "a :class:`roller_gym.Scene` or a preset's name (``roller_gym.PRESETS``); default: "
        "the task's preset. The vector environment also takes a sequence of them (one per "
        "sub-environment; None in it: the task's preset) or a batch Scene of ``num_envs`` "
        "rollers."))
    dt: float = field(default=DEFAULT_DT, metadata=_doc(
        "the control step [s]; the torque is constant over it."))
    max_torque: float | None = field(default=None, metadata=_doc(
        "the torque [N·m] an action of ±1 applies; default: the task's. A task that must pump "
        "energy (RollerBalance, RollerBalanceWeak, RollerSwing) refuses a torque whose most "
        "power, max_torque·|φ'| at the speed of the energy pumped so far, would need more "
        "than 0.3 of the episode to bring the energy success needs. The others (RollerStabilize, "
        "RollerHold, RollerTrack, RollerHoldRandomized) refuse a torque, scene or ``dt`` with "
        "which bringing the roller from a start the draw may take (at rest or moving, "
        ":func:`roller_gym.start_set.covering`) to rest at the bottom takes, at the "
        "least, more than half the episode, by the bounds of "
        ":func:`roller_gym.bounds.least_times` (its energy taken out, the way rolled at the "
        "speeds its energy, its lift-off and the damping allow), and a fixed scene with a "
        "start from which no torque can stop the roller before a point where it must slip or "
        "lift off (:func:`roller_gym.descent.doomed`), and warn where they would refuse it "
        f"at max_torque / {descent.NEAR:g}, and on every drum, scene or randomize box "
        "(:func:`roller_gym.descent.fixed_scene_problem`: the check holds in continuous time "
        "only, so a scene accepted without a warning is not proven solvable from every "
        "start); RollerStabilize also refuses "
        "damping that might bring the roller to rest there with no torque within the "
        "episode."))
    tolerance: float = field(default=DEFAULT_TOLERANCE, metadata=_doc(
        "the integrator's target state error per control step (φ [rad], φ' [rad/s]), >= 1e-12 "
        "(float64 cannot verify a tighter one); it sets the number of substeps."))
    integrator: str = field(default=DEFAULT_INTEGRATOR, metadata=_doc(
        "``\"taylor\"`` (the series of the motion to degree 18, 10 at a tolerance above "
        "0.1 (:func:`roller_gym.physics.taylor.degree`), its substeps chosen from "
        "its own error estimate; the default and the fastest), ``\"rk8\"`` and ``\"rk4\"`` "
        "(error-controlled Runge–Kutta), ``\"euler\"`` (semi-implicit, Pendulum's scheme), "
        "``\"midpoint\"`` (implicit, energy-stable) or ``\"dop853\"`` (scipy's adaptive, "
        "slow: a reference; the single environment only: under SB3 and ``roller-gym train`` a "
        "batch of them is a ``DummyVecEnv``)."))
    substeps: int | None = field(default=None, metadata=_doc(
        "a fixed number of substeps per control step instead of the automatic rule; "
        "``info[\"tol_met\"]`` then says whether they met the tolerance by the scheme's error "
        "estimate (euler, midpoint: by Richardson's estimate, the same step in half as many "
        "substeps)."))
    randomize: Mapping[str, tuple[float, float]] | None = field(default=None, metadata=_doc(
        "``{field: (low, high)}``: Scene fields drawn uniformly at each reset (domain "
        "randomization), e.g. ``{\"m\": (0.8, 1.2), \"e\": (0.03, 0.05)}``. At "
        "construction the task is proven posable in every scene of the box of ranges "
        "(:mod:`roller_gym.feasibility`), so no later reset can fail on a drawn scene; "
        "otherwise a ``ValueError`` names the field and a feasible part of its range, and "
        "whether that part, with the other ranges as given, is proven. The tasks that bring "
        "the roller down also refuse a box with a start doomed to slip in its middle, at "
        "any corner or in scenes drawn from it (:func:`roller_gym.descent.range_problem`; not "
        "proven between them). "
        "RollerSwing takes none: its scenes are checked one by one (its target swings must "
        "roll and stay below the potential's barrier). "
        "Default: the task's own ranges (``Task.scene_ranges``: none but for the tasks "
        "whose scene varies unobserved); ``{}`` fixes the scene."))
    render_mode: str | None = field(default=None, metadata=_doc(
        "``\"human\"`` or ``\"rgb_array\"`` (the vector environment: ``\"rgb_array\"``), "
        "or None."))
    info_keys: Sequence[str] | None = field(default=None, metadata=_doc(
        "the keys of the step's and reset's info, among :data:`roller_gym.episode.INFO_KEYS` "
        "(default None: all of them). Building the info is a notable share of a single "
        "environment's step; ask only for what you read (e.g. ``[\"is_success\"]``) to "
        "step faster. Reward and termination are the same whatever the keys."))

    @classmethod
    def of(cls, owner: type, keywords: Mapping[str, Any]) -> Settings:
        """The settings from the keywords the class ``owner`` was given beyond its own
        arguments, naming an unknown one and every argument ``owner`` takes."""
        names = [f.name for f in fields(cls)]
        unknown = [key for key in keywords if key not in names]
        if unknown:
            allowed = ", ".join(inspect.signature(owner).parameters)
            raise TypeError(f"{owner.__name__} got an unexpected keyword argument "
                            f"{shown(unknown[0])}; allowed: {allowed}")
        return cls(**keywords)


def setting_docs(indent: str = "        ") -> str:
    """The ``Args`` lines of :class:`Settings`' fields, wrapped as a docstring's."""
    import textwrap

    lines = []
    for f in fields(Settings):
        lines += textwrap.wrap(f"{f.name}: {f.metadata['doc']}", 91 - len(indent),
                               initial_indent="", subsequent_indent="    ")
    return "\n".join(indent + line for line in lines)


def settings_table() -> str:
    """:class:`Settings` as the README's Markdown table (argument, meaning, default): the
    README holds this text, and a test compares the two."""
    rows = ["| argument | meaning | default |", "|---|---|---|"]
    for f in fields(Settings):
        meaning = re.sub(r":\w+:(`[^`]+`)", r"\1", f.metadata["doc"])  # Sphinx roles dropped
        meaning = meaning.replace("``", "`").replace("|", "\\|")
        rows.append(f"| `{f.name}` | {meaning} | `{shown(f.default)}` |")
    return "\n".join(rows)


_Env = TypeVar("_Env", bound=type)


def takes_settings(before: Sequence[str], after: Sequence[str] = ()) -> Callable[[_Env], _Env]:
    """Class decorator: the class's signature is its ``__init__``'s parameters ``before``,
    then every :class:`Settings` field (keyword, with its default), then ``after``; its
    docstring's ``{settings}`` becomes the fields' documentation (:func:`setting_docs`)."""
    def decorate(cls: _Env) -> _Env:
        own = inspect.signature(cls.__init__).parameters
        params = [p for name, p in own.items() if name in before]
        params += [inspect.Parameter(f.name, inspect.Parameter.KEYWORD_ONLY,
                                     default=None if f.default is MISSING else f.default,
                                     annotation=f.type) for f in fields(Settings)]
        params += [own[name].replace(kind=inspect.Parameter.KEYWORD_ONLY) for name in after]
        cls.__signature__ = inspect.Signature(params, return_annotation=None)
        cls.__doc__ = cls.__doc__.replace("{settings}", setting_docs().lstrip())
        return cls
    return decorate


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
        settings: Settings,
        *,
        render_modes: list[str],
        scenes: Sequence[Scene] | None = None,
    ) -> EnvConfig:
        """The checked ``settings``; ``scenes`` (the vector env's, one per sub-environment)
        replaces ``settings.scene`` in the checks: each distinct one is checked,
        ``randomize``'s range proof included, and an error names its first sub-environment."""
        scene, dt, max_torque, tolerance = (settings.scene, settings.dt, settings.max_torque,
                                            settings.tolerance)
        integrator, substeps, randomize = (settings.integrator, settings.substeps,
                                           settings.randomize)
        render_mode, info_keys = settings.render_mode, settings.info_keys
        if max_torque is not None:
            max_torque = validation.real("max_torque", max_torque, positive=True, unit="N·m")
        task = task_class(max_torque)
        scene = resolve_scene(scene, task.default_scene)
        dt = validation.real("dt", dt, positive=True, unit="s")
        tolerance = validation.real("tolerance", tolerance, positive=True)
        if tolerance < TOLERANCE_MIN:
            raise ValueError(
                f"tolerance={shown(tolerance)} is not allowed: it must be >= "
                f"{TOLERANCE_MIN:g} (float64's rounding of the state, about 2.2e-16 of |φ| per "
                "operation, keeps a step from verifying a tighter one: at 1e-14 half the "
                "steps, at 1e-15 nearly all report tol_met=False); for tighter steps use "
                "roller_gym.physics.Stepper, which flags them")
        integrator = validation.choice("integrator", integrator, tuple(INTEGRATORS))
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
                ranges = check_randomize(task, one, dt, task.scene_ranges if randomize is None
                                         else randomize)
                if not ranges:  # (a range's proof covers every scene drawn, and only those:
                    # the base values of the fields it draws are never stepped)
                    validation.check_integrable(one, dt, task.max_torque, task.start_speed)
                    verdict = descent.fixed_scene_problem(task, one, dt)
                    if verdict.refused is not None:
                        raise ValueError(verdict.refused)
                    caution = verdict.caution
                else:
                    caution = descent.range_caution(task, one, ranges)
                if caution is not None:
                    where = "" if scenes is None else f"scene[{i}]: "
                    warnings.warn(where + caution, UserWarning, stacklevel=5)
            except ValueError as exc:
                if scenes is None:
                    raise
                shared = sum(1 for s in scenes if s == one)
                raise ValueError(f"scene[{i}] (sub-environment {i}"
                                 f"{f' and {shared - 1} more of that scene' if shared > 1 else ''}"
                                 f", {shown(one)}): {exc}") from None
        return cls(task, scene, dt, tolerance, integrator, substeps or 0, ranges, render_mode,
                   info_keys)

    @property
    def nominal_scene(self) -> Scene:
        """The scene the classical controller designs for and the target before the first
        reset is shown in: :attr:`scene`, with each field ``randomize`` draws moved to the
        middle of its range where its value lies outside (never stepped, so never checked)."""
        moved = {name: 0.5 * (low + high) for name, (low, high) in self.randomize.items()
                 if not low <= getattr(self.scene, name) <= high}
        return self.scene.replace(**moved) if moved else self.scene

    def resolve_option_scene(self, value: Any) -> Scene:
        return resolve_scene(value, self.task.default_scene, "options['scene']")


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
    width, through the failing scene), and whether that part is proven with the other
    ranges as given (the scan's edge may lie past where the proof closes); where the proof
    does not close (as at an isolated
    infeasible value), the range is refused all the same, naming the part that was proven.
    The result is cached per (task, scene, dt, ranges).
    """
    if randomize is None:
        return {}
    ranges = validation.ranges("randomize", randomize)
    for name, (low, high) in ranges.items():  # each field's own rule, on the whole interval
        for end in (low, high):
            try:
                scene.replace(**{name: end})
            except ValueError as exc:
                raise ValueError(f"randomize[{shown(name)}]={shown(randomize[name])} reaches a "
                                 "scene "
                                 f"that is not allowed: {exc}") from None
    if "R" in ranges:
        low, high = ranges["R"]
        r_high = ranges.get("r", (0.0, float(scene.r)))[1]
        if not (high < 0 or low > r_high):
            raise ValueError(
                f"randomize['R']={shown(ranges['R'])} passes through R in [0, r] (r up to "
                f"{r_high} m), which is no scene: R must stay > r (inside a cylinder) or < 0 "
                "(on a drum) over the whole range"
            )

    if ranges:
        feasibility.check_ranges(task, scene, dt, ranges)
        reason = descent.range_problem(task, scene, ranges)
        if reason is not None:
            raise ValueError(reason)
    return ranges

