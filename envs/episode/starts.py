"""Episode starts: the scene (domain randomization), the target and the start state of a batch
of episodes, drawn from the random streams (:mod:`roller_gym.episode.streams`), with the
checks of ``reset``'s seed and options.

Every draw keeps its index whatever the options, so a seed gives the same episode in the
single and the vector environment; the start state is a rejection draw, vectorized: a fixed
number of Python operations whatever the batch's size.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

import numba
import numpy as np
from roller_gym import descent, validation
from roller_gym.episode.streams import uniform
from roller_gym.physics import Scene, trig
from roller_gym.physics import equations as eq
from roller_gym.physics.compiling import inlined
from roller_gym.physics.integrators import contact_state
from roller_gym.physics.scene import finite_real, shown, whole_number

__all__ = ["CANDIDATES", "OPTION_NAMES", "ROUNDS", "SEED_MAX", "RestState", "Starts", "at_start",
           "check_option_names", "check_seed", "per_scene_target", "put", "reset_mask",
           "reset_options", "scene_rows", "start_episodes", "state_option", "take",
           "target_terms", "vector_seeds"]

#: Draw indices: the randomized scene fields, the target, then the start-state candidates.
_SCENE_DRAW, _TARGET_DRAW, _STATE_DRAW = 0, 16, 32
#: Start-state candidates drawn per round, and the most rounds before giving up.
CANDIDATES, ROUNDS = 4, 256
_FIELDS = tuple(f.name for f in fields(Scene))


def take(scene: Scene, index: np.ndarray, size: int) -> Scene:
    """Rollers ``index`` of a scene of ``size`` rollers: a batch Scene, or the scalar scene
    itself when every roller shares it (every function of the physics broadcasts)."""
    if scene.batch_size is None:
        return scene
    return Scene(**{f: np.broadcast_to(np.asarray(getattr(scene, f), float), (size,))[index]
                    for f in _FIELDS})


def scene_rows(scene: Scene, size: int) -> dict[str, np.ndarray]:
    """The scene's fields as arrays of ``size`` (a scalar scene is broadcast)."""
    return {f: np.broadcast_to(np.asarray(getattr(scene, f), float), (size,)) for f in _FIELDS}


def target_terms(scene: Scene, target: Any) -> dict[str, Any]:
    """The step context's rows that follow from the target φ* [rad] (the names of
    :data:`~roller_gym.episode.record.CONTEXT_FIELDS`): ``target_torque`` τ* = dV/dφ(φ*)
    [N·m], the torque that holds the roller at rest there, and ``target_energy`` E* = V(φ*)
    [J], the energy of resting there (V = 0 at φ = 0)."""
    m, r, kappa, e, _, g, _ = scene.params
    if isinstance(target, float) and scene.batch_size is None:  # one roller: compiled, a call
        torque, energy = _target_terms_one(target, m, r, kappa, e, g)
    else:
        torque, energy = _target_terms(target, m, r, kappa, e, g)
    return {"target_torque": torque, "target_energy": energy}


@inlined
def _target_terms(target, m, r, kappa, e, g):
    """(τ* [N·m], E* [J]) of :func:`target_terms` (trig's sines: the same bits alone, in
    arrays and compiled)."""
    return eq.dpotential(target, m, r, kappa, e, g), eq.potential(target, m, r, kappa, e, g)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _target_terms_one(target, m, r, kappa, e, g):
    return _target_terms(target, m, r, kappa, e, g)


def put(scene: Scene, index: np.ndarray, rows: Scene, size: int) -> Scene:
    """A copy of ``scene`` (of ``size`` rollers) whose rollers ``index`` are ``rows``."""
    out = {}
    for f in _FIELDS:
        column = np.array(np.broadcast_to(np.asarray(getattr(scene, f), float), (size,)))
        column[index] = getattr(rows, f)
        out[f] = column
    return Scene(**out)


def per_scene_target(task: Any, scene: Scene, size: int) -> np.ndarray:
    """The task's default target φ* [rad] of each roller (before the first reset)."""
    from roller_gym.task import per_scene

    return np.broadcast_to(per_scene(task.default_target, scene), (size,)).copy()


#: The largest seed: the random streams are keyed by 64-bit seeds.
SEED_MAX = 2**64 - 1


def _valid_seed(s: Any) -> bool:
    return s is None or (whole_number(s) and 0 <= s <= SEED_MAX)


def check_seed(seed: Any) -> int | None:
    """A single environment's ``reset(seed=...)``: None or an int in [0, 2⁶⁴ − 1].

    Raises:
        ValueError: anything else, naming the value and the range.
    """
    if not _valid_seed(seed):
        raise ValueError(f"seed={shown(seed)} must be None or an integer in [0, 2**64 - 1]")
    return None if seed is None else int(seed)


def vector_seeds(seed: Any, n: int) -> list[int | None] | None:
    """The seeds of n sub-environments from ``reset(seed=...)``: an int s gives s + i, a
    sequence gives one each (None: that one not reseeded); None gives None (none reseeded).

    Raises:
        ValueError: a seed is not an integer in [0, 2⁶⁴ − 1] (or None; for an int s, s + n −
            1 too), or the sequence's length is not n.
    """
    if seed is None:
        return None
    if isinstance(seed, int | np.integer) and _valid_seed(seed):
        if int(seed) + n - 1 > SEED_MAX:
            raise ValueError(
                f"seed={shown(seed)} gives sub-environment i the seed seed + i, up to seed + "
                f"{n - 1} for num_envs={n}, which must be at most 2**64 - 1: seed must be at "
                f"most {SEED_MAX - n + 1}")
        return [int(seed) + i for i in range(n)]
    sequence = isinstance(seed, list | tuple | range) or (
        isinstance(seed, np.ndarray) and seed.ndim == 1)
    if sequence and all(_valid_seed(s) for s in seed):
        if len(seed) != n:
            raise ValueError(f"seed has {len(seed)} entries for num_envs={n}; it needs {n}")
        return [None if s is None else int(s) for s in seed]
    raise ValueError(
        f"seed={shown(seed)} must be None, an integer in [0, 2**64 - 1], or a list, tuple, "
        f"range or 1-D array of {n} of them"
    )


def reset_options(options: Any) -> dict[str, Any]:
    """``reset(options=...)`` as a new dict ({} for None).

    Raises:
        ValueError: options that are not a mapping, naming them.
    """
    if options is None:
        return {}
    if not isinstance(options, Mapping):
        raise ValueError(f"options={shown(options)} must be a dict of reset options (or None), "
                         "e.g. {'state': (0.3, 0.0)}")
    return dict(options)


def reset_mask(value: Any, n: int) -> np.ndarray:
    """``options["reset_mask"]`` as a boolean array of n (None: every sub-environment).

    Raises:
        ValueError: not a boolean array (or sequence of bools) of length n, or no True.
    """
    if value is None:
        return np.ones(n, dtype=bool)
    mask = np.asarray(value)
    if (np.ma.isMaskedArray(value) or mask.dtype != np.bool_ or mask.shape != (n,)
            or not mask.any()):
        raise ValueError(
            f"options['reset_mask']={shown(value)} must be a boolean array of shape ({n},) with at "
            "least one True (not a masked array)"
        )
    return mask


@dataclass
class Starts:
    """Episode starts of some rollers: their scene (a batch), target and state (arrays)."""

    scene: Scene
    target_params: np.ndarray
    target: np.ndarray
    target_rate: np.ndarray
    phi: np.ndarray
    phi_dot: np.ndarray


#: The options an episode's start takes (``reset(options=...)``).
OPTION_NAMES = ("state", "target", "scene")


def check_option_names(options: Mapping[str, Any]) -> None:
    """Raise ValueError naming the options of ``options`` that are not :data:`OPTION_NAMES`."""
    unknown = set(options) - set(OPTION_NAMES)
    if unknown:
        raise ValueError(
            f"reset options [{', '.join(sorted(map(shown, unknown)))}] are not known; allowed: "
            f"{', '.join(map(repr, OPTION_NAMES))}"
        )


def start_episodes(
    config: Any,
    base: Scene,
    seed: np.ndarray,
    episode: np.ndarray,
    options: Mapping[str, Any] | None,
) -> Starts:
    """The starts of ``len(seed)`` episodes (scene, target, state), drawn from the streams.

    Args:
        config: the environment's :class:`~roller_gym.config.EnvConfig` (task, randomize).
        base: the base scene of those rollers (scalar, or a batch of ``len(seed)``).
        seed: the rollers' stream seeds (uint64).
        episode: the number of each roller's episode since its seed was set.
        options: reset options: ``"state"`` (φ [rad], φ' [rad/s]), ``"target"`` (the
            task's target, see the task), ``"scene"`` (a Scene or preset for these
            episodes). Draws keep their indices whatever the options, so a seed gives the
            same episode in the single and the vector environment.
    """
    n = len(seed)
    options = reset_options(options)
    check_option_names(options)
    task = config.task
    if options.get("scene") is not None:
        scene = config.resolve_option_scene(options["scene"])
        verdict = descent.fixed_scene_problem(task, scene, config.dt)
        if verdict.refused is not None:
            raise ValueError(f"options['scene']: {verdict.refused}")
        if verdict.caution is not None:
            warnings.warn(f"options['scene']: {verdict.caution}", UserWarning, stacklevel=4)
        validation.check_integrable(scene, config.dt, task.max_torque, task.start_speed)
    elif config.randomize:
        fields_ = scene_rows(base, n)
        drawn = {
            name: low + (high - low) * uniform(seed, episode, _SCENE_DRAW + j)
            for j, (name, (low, high)) in enumerate(sorted(config.randomize.items()))
        }
        scene = Scene(**{**fields_, **drawn})
    else:
        scene = base
    draws = _TARGET_DRAW + np.arange(task.target_size)
    params = task.sample_target_params(uniform(seed[:, None], episode[:, None], draws), scene)
    params = np.broadcast_to(np.asarray(params, float), (n, task.target_size)).copy()
    if options.get("target") is not None:
        if task.moving_target:
            raise ValueError(f"{task.name}'s target moves; options['target'] is not allowed")
        params[:, 0] = [_target_option(task, options["target"], scene, i) for i in range(n)]
    target, target_rate = task.target_at(params, np.zeros(n))
    if options.get("state") is not None:
        phi, phi_dot = state_option(options["state"], scene, n, config.dt)
    else:
        phi, phi_dot = _draw_states(task, scene, target, seed, episode)
    return Starts(scene, params, np.asarray(target, float), np.asarray(target_rate, float), phi,
                  phi_dot)


def _draw_states(task: Any, scene: Scene, target: np.ndarray, seed: np.ndarray,
                 episode: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The task's start states: the first of its candidates that it accepts, per roller.

    Candidates are tried one at a time (round by round, CANDIDATES a round), each only where
    no earlier one was accepted: the same starts as trying a round's all at once, for a
    fraction of the checks where most first candidates are accepted. One roller (a single
    environment's reset) tries a round's all at once (:func:`_draw_one`): its calls cost
    their fixed overheads, not their size."""
    n = len(seed)
    if n == 1:
        start = _draw_one(task, scene, seed, episode)
        if start is not None:
            return start
    phi, phi_dot = np.zeros(n), np.zeros(n)
    todo = np.arange(n)
    for candidate in range(ROUNDS * CANDIDATES):
        # candidate j of a round takes draws 2j (φ) and 2j + 1 (φ')
        sub = take(scene, todo, n)
        u = uniform(seed[todo, None], episode[todo, None],
                    _STATE_DRAW + 2 * candidate + np.arange(2))
        c_phi, c_dot = task.start_candidates(u[:, :1], u[:, 1:], sub)
        ok = task.start_accepted(c_phi, c_dot, sub)[:, 0]
        phi[todo[ok]], phi_dot[todo[ok]] = c_phi[ok, 0], c_dot[ok, 0]
        todo = todo[~ok]
        if todo.size == 0:
            return phi, phi_dot
    # The fallback the task's feasibility check guarantees (rare: every candidate failed).
    for i in todo:
        start = task.fallback_start(scene if scene.batch_size is None else scene.item(int(i)))
        if start is None:
            break
        phi[i], phi_dot[i] = start
    else:
        return phi, phi_dot
    raise ValueError(
        f"no start state found for {todo.size} episode(s) after {ROUNDS * CANDIDATES} "
        f"candidates in {shown(take(scene, todo[:1], n))}: {task.start_rule}"
    )


def _draw_one(task: Any, scene: Scene, seed: np.ndarray,
              episode: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """:func:`_draw_states` of one roller, a round of candidates per call of the task's
    candidates and checks (which are elementwise: candidate j of a round takes the same
    draws and gets the same answer as alone); None where no candidate is accepted (the
    general path then finds the fallback)."""
    draws = _STATE_DRAW + np.arange(2 * CANDIDATES)  # a round's: (φ, φ') of each candidate
    for first in range(0, ROUNDS * CANDIDATES, CANDIDATES):
        u = uniform(seed[:, None], episode[:, None], draws + 2 * first)
        c_phi, c_dot = task.start_candidates(u[:, 0::2], u[:, 1::2], scene)
        ok = task.start_accepted(c_phi, c_dot, scene)[0]
        if ok.any():
            j = int(ok.argmax())  # the round's first accepted
            return np.array([c_phi[0, j]], float), np.array([c_dot[0, j]], float)
    return None


@dataclass(frozen=True)
class RestState:
    """The StepResult-like state of rollers at the start of an episode (no step taken)."""

    phi: Any
    phi_dot: Any
    phi_ddot: Any
    substeps: Any
    finite: Any
    normal_force: Any
    friction_force: Any
    energy: Any
    liftoff_margin: Any
    slip_margin: Any
    error_estimate: Any = 0.0
    tol_met: Any = True


def at_start(scene: Scene | np.ndarray, phi: np.ndarray, phi_dot: np.ndarray) -> RestState:
    """The contact forces, energy and margins of start states under zero torque (``scene``:
    a Scene, or its numbers as :func:`~roller_gym.physics.integrators.contact_state` takes
    them)."""
    a, normal, friction, energy, lift, slip = contact_state(scene, phi, phi_dot, 0.0)
    n = len(phi)
    return RestState(phi, phi_dot, a, np.zeros(n, np.int64), np.ones(n, bool), normal,
                     friction, energy, lift, slip)


def _target_option(task: Any, value: Any, scene: Scene, i: int) -> float:
    """``options['target']`` in the scene of roller ``i`` (of a batch: its error names it)."""
    if scene.batch_size is None:
        return task.target_from_option(value, scene)
    try:
        return task.target_from_option(value, scene.item(i))
    except ValueError as error:
        which = f"sub-environment {i}" if scene.batch_size > 1 else "this episode's scene"
        raise ValueError(f"{which} ({shown(scene.item(i))}): {error}") from None


def state_option(value: Any, scene: Scene, n: int, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """(φ, φ') arrays of n from ``reset(options={"state": (φ [rad], φ' [rad/s])})``, for
    control steps of ``dt`` [s].

    Raises:
        ValueError: not a pair of finite real numbers, a speed that turns φ or θ = φ/(1 − rκ)
            (the faster in a tight fit) more than
            :data:`~roller_gym.validation.LARGEST_PHASE_PER_STEP` rad in a step (which no
            integrator follows within its substeps), or a state at which the roller does not
            roll under zero torque (N <= 0 or |F| > μN): such an episode could not start.
    """
    pair = tuple(value) if isinstance(value, tuple | list | np.ndarray) else None
    if (pair is None or len(pair) != 2
            or not all(finite_real(x) for x in pair)):
        raise ValueError(
            f"options['state']={shown(value)} must be a pair (phi [rad], phi_dot [rad/s]) of "
            "finite real numbers"
        )
    if not abs(float(pair[0])) < trig.DOMAIN:
        raise ValueError(f"options['state']={shown(value)}: phi must be within "
                         f"±{trig.DOMAIN:.4g} rad, where the sines are defined")
    # the fastest of the angles φ, θ and ψ turns at most so far in a step
    turn = float(np.max(eq.fastest_turn(np.asarray(scene.r), np.asarray(scene.kappa, float))))
    fastest = validation.LARGEST_PHASE_PER_STEP / turn / dt
    if not abs(float(pair[1])) <= fastest:
        raise ValueError(f"options['state']={shown(value)}: phi_dot must be within ±{fastest:.4g} "
                         f"rad/s: at most {validation.LARGEST_PHASE_PER_STEP:g} rad per step of "
                         f"dt={dt:g} s for the fastest of φ, θ = φ/(1 − rκ) and ψ (faster, no "
                         "integrator follows it)")
    phi, phi_dot = np.full(n, float(pair[0])), np.full(n, float(pair[1]))
    with np.errstate(all="ignore"):
        start = at_start(scene, phi, phi_dot)
        rolls = (start.liftoff_margin > 0) & (start.slip_margin >= 0)
    if not rolls.all():
        remedy = ("a state on the surface with less speed" if pair[1] != 0 else
                  "another phi, where the roller rests without slipping, or a scene with more "
                  "friction (mu)")
        bad = int(np.flatnonzero(~rolls)[0])
        where = (f" of sub-environment {bad} ({shown(scene.item(bad))})" if scene.batch_size
                 else "")
        raise ValueError(
            f"options['state']={shown(value)}: the roller{where} does not roll there under zero "
            "torque "
            f"(N/(m g) = {float(np.min(start.liftoff_margin)):.3g}, "
            f"(μN − |F|)/(m g) = {float(np.min(start.slip_margin)):.3g}; both must be "
            f"> 0 and >= 0): choose {remedy}"
        )
    return phi, phi_dot
