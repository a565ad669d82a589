"""The episode core, written once for the single and the vector environment.

It holds what happens between the integrator and Gymnasium, on arrays of rollers (the
single environment's are arrays of one):

* **Random streams.** Every random draw of an episode start is a counter-based uniform:
  ``uniform(seed, episode, draw)``, a pure function of the sub-environment's seed, the
  number of the episode since that seed was set, and the draw's fixed index. So sub-
  environment i of a vector env seeded ``s`` (seed ``s + i``) makes exactly the draws
  of a single env seeded ``s + i``, and a whole batch of episode starts is a handful of
  array operations: no generator object per sub-environment.
* **Episode starts** (:func:`start_episodes`): the scene (domain randomization), the
  target and the start state (a rejection draw, vectorized), with reset options.
* **The step's outcome** (:class:`OutcomeKernel`, :func:`outcome`): reward, termination,
  success, the info (:data:`INFO_KEYS`) and the observation from a
  :class:`~roller_gym.physics.integrators.StepResult`, for every roller in one compiled
  loop over the task's formulas (:mod:`roller_gym.task`): the single environment runs it
  on one roller, the vector environment on all of them, with the same bits.

The generator is SplitMix64's mixing function applied to a counter that combines the
three numbers (as in counter-based generators such as Philox or Squares): each
``(seed, episode, draw)`` gives an independent 53-bit uniform in [0, 1).
"""

from __future__ import annotations

import math
import platform
from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields
from typing import Any

import numba
import numpy as np
from llvmlite import ir as llvm_ir
from numba.core import cgutils
from numba.extending import intrinsic, register_jitable
from roller_gym import validation
from roller_gym.physics import Scene, trig
from roller_gym.physics import equations as eq
from roller_gym.physics.integrators import (
    CHUNK,
    PARALLEL_THRESHOLD,
    ROWS,
    SCHEMES,
    STEP_FIELDS,
    BatchStepper,
    Stepper,
    contact_state,
    missed,
    put_inputs,
    row_table,
)
from roller_gym.physics.packed import unpack
from roller_gym.task import (
    OBSERVATION_FIELDS,
    TASK_CONSTANTS,
    observation_values,
    position_error,
    state_observation,
    step_reward,
    step_success,
    target_observation,
)

__all__ = [
    "CONTEXT_FIELDS",
    "FLAG_ROWS",
    "INFO_KEYS",
    "INFO_ROW",
    "OUTCOME_ROWS",
    "Outcome",
    "OutcomeKernel",
    "flag_table",
    "info_rows",
    "random_seed",
    "result_table",
    "scene_rows",
    "start_episodes",
    "take",
    "uniform",
]

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
#: Draw indices: the randomized scene fields, the target, then the start-state candidates.
_SCENE_DRAW, _TARGET_DRAW, _STATE_DRAW = 0, 16, 32
#: Start-state candidates drawn per round, and the most rounds before giving up.
CANDIDATES, ROUNDS = 4, 256
_FIELDS = tuple(f.name for f in fields(Scene))
_FIELD_NUMBER = {name: i for i, name in enumerate(OBSERVATION_FIELDS)}


@register_jitable
def _mix(x):
    """SplitMix64's finalizer on uint64 (wrapping arithmetic)."""
    x = (x ^ (x >> np.uint64(30))) * _M1
    x = (x ^ (x >> np.uint64(27))) * _M2
    return x ^ (x >> np.uint64(31))


@numba.vectorize(["float64(uint64, uint64, uint64)"], cache=True, nopython=True)
def _uniform(seed, episode, draw):
    """The uniform of one (seed, episode, draw): a NumPy ufunc, so it broadcasts."""
    s = _mix(seed + _GOLDEN)
    x = _mix(s + episode * _GOLDEN)
    x = _mix(x + (draw + np.uint64(1)) * _M1)
    return np.float64(x >> np.uint64(11)) * 2.0**-53


def uniform(seed: np.ndarray, episode: np.ndarray, draw: np.ndarray | int) -> np.ndarray:
    """Uniforms in [0, 1): one per element of the broadcast (seed, episode, draw), a
    counter-based stream (SplitMix64's finalizer, compiled)."""
    return _uniform(np.asarray(seed, dtype=np.uint64), np.asarray(episode, dtype=np.uint64),
                    np.asarray(draw, dtype=np.uint64))


def random_seed() -> int:
    """A fresh seed from the operating system's entropy (for ``reset()`` with no seed)."""
    return int(np.random.SeedSequence().generate_state(1, np.uint64)[0] >> np.uint64(1))


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


def target_torque(scene: Scene, target: Any) -> Any:
    """τ* = dV/dφ(φ*) [N·m], the torque that holds the roller at rest at the target."""
    m, r, kappa, e, _, g, _ = scene.params
    return eq.dpotential(target, m, r, kappa, e, g)


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
    return s is None or (isinstance(s, int | np.integer) and not isinstance(s, bool)
                         and 0 <= s <= SEED_MAX)


def check_seed(seed: Any) -> int | None:
    """A single environment's ``reset(seed=...)``: None or an int in [0, 2⁶⁴ − 1].

    Raises:
        ValueError: anything else, naming the value and the range.
    """
    if not _valid_seed(seed):
        raise ValueError(f"seed={seed!r} must be None or an integer in [0, 2**64 - 1]")
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
                f"seed={seed!r} gives sub-environment i the seed seed + i, up to seed + "
                f"{n - 1} for num_envs={n}, which must be at most 2**64 - 1: seed must be at "
                f"most {SEED_MAX - n + 1}")
        return [int(seed) + i for i in range(n)]
    if isinstance(seed, list | tuple | np.ndarray) and all(_valid_seed(s) for s in seed):
        if len(seed) != n:
            raise ValueError(f"seed has {len(seed)} entries for num_envs={n}; it needs {n}")
        return [None if s is None else int(s) for s in seed]
    raise ValueError(
        f"seed={seed!r} must be None, an integer in [0, 2**64 - 1], or a sequence of {n} of "
        "them"
    )


def reset_options(options: Any) -> dict[str, Any]:
    """``reset(options=...)`` as a new dict ({} for None).

    Raises:
        ValueError: options that are not a mapping, naming them.
    """
    if options is None:
        return {}
    if not isinstance(options, Mapping):
        raise ValueError(f"options={options!r} must be a dict of reset options (or None), "
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
    if mask.dtype != np.bool_ or mask.shape != (n,) or not mask.any():
        raise ValueError(
            f"options['reset_mask']={value!r} must be a boolean array of shape ({n},) with at "
            "least one True"
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
    unknown = set(options) - {"state", "target", "scene"}
    if unknown:
        raise ValueError(
            f"reset options {sorted(unknown)} are not known; allowed: 'state', 'target', 'scene'"
        )
    task = config.task
    if options.get("scene") is not None:
        scene = config.resolve_option_scene(options["scene"])
        reason = task.infeasible(scene)
        if reason is not None:
            raise ValueError(f"options['scene']: {reason}")
        validation.check_integrable(scene, config.dt, task.max_torque)
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
        params[:, 0] = [task.target_from_option(
            options["target"], scene if scene.batch_size is None else scene.item(i))
            for i in range(n)]
    target, target_rate = task.target_at(params, np.zeros(n))
    if options.get("state") is not None:
        phi, phi_dot = state_option(options["state"], scene, n)
    else:
        phi, phi_dot = _draw_states(task, scene, target, seed, episode)
    return Starts(scene, params, np.asarray(target, float), np.asarray(target_rate, float), phi,
                  phi_dot)


def _draw_states(task: Any, scene: Scene, target: np.ndarray, seed: np.ndarray,
                 episode: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The task's start states: the first of its candidates that it accepts, per roller.

    Candidates are tried one at a time (round by round, CANDIDATES a round), each only where
    no earlier one was accepted: the same starts as trying a round's all at once, for a
    fraction of the checks where most first candidates are accepted."""
    n = len(seed)
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
        f"candidates in {take(scene, todo[:1], n)!r}: {task.start_rule}"
    )


# -- the step's outcome ----------------------------------------------------------------
#: The info keys of every step and reset, with their types and units; grouped by type (the
#: floats, the integer, the flags), so that each type's keys are consecutive rows of the
#: outcome's table or flags, which the single environment reads in one pass.
INFO_KEYS: dict[str, tuple[type, str]] = {
    "phi": (float, "φ [rad]"),
    "phi_dot": (float, "φ' [rad/s]"),
    "psi": (float, "ψ [rad], where the roller is on the surface"),
    "torque": (float, "τ [N·m] applied over the step (0 at reset)"),
    "normal_force": (float, "N [N] at the end of the step (NaN where the step failed)"),
    "friction_force": (float, "F [N] at the end of the step (NaN where the step failed)"),
    "energy": (float, "E [J] at the end of the step (NaN where the step failed)"),
    "liftoff_margin": (float, "smallest N/(m g) during the step [-] (NaN: failed step)"),
    "slip_margin": (float, "smallest (μN − |F|)/(m g) during the step [-] (NaN: failed)"),
    "error_estimate": (float, "the integrator's estimate of the step's state error (inf: not "
                              "estimated, fixed-substep schemes and DOP853; 0 at reset)"),
    "target_phi": (float, "the target φ* [rad]"),
    "target_psi": (float, "the target ψ* [rad]"),
    "target_phi_dot": (float, "how fast the target moves, φ*' [rad/s] (0: a rest position)"),
    "target_torque": (float, "τ* [N·m], the torque that holds the roller at rest at φ*"),
    "position_error": (float, "the task's position error [rad of φ]"),
    "substeps": (int, "integrator substeps taken (0 at reset)"),
    "lifting": (bool, "the roller left the surface (N <= 0) during the step"),
    "slipping": (bool, "the friction needed exceeded μN during the step"),
    "nonfinite": (bool, "the step could not stay finite (or |φ| passed 2⁵⁰ rad, where "
                       "sines are NaN): the state is the one before it"),
    "tol_met": (bool, "the step met the integrator's tolerance (False: out of reach of "
                     "float64, or of the substeps a step may take)"),
    "is_success": (bool, "inside the task's success band, at rest (moving with the target "
                         "in Track)"),
}


#: Per-roller numbers a step's outcome takes besides the integrator's StepResult, in the
#: order of their rows: the torque τ [N·m], the target φ* [rad], its rate φ*' [rad/s], its
#: holding torque τ* [N·m], the wrap rate q and dψ/dφ (``roller_gym.task``).
CONTEXT_FIELDS = ("torque", "target_phi", "target_phi_dot", "target_torque", "wrap_rate",
                  "psi_rate")
#: The rows of the outcome's table (float64): the reward, then the info's float and integer
#: keys in INFO_KEYS order (integers as whole floats).
OUTCOME_ROWS = ("reward", *(key for key, (kind, _) in INFO_KEYS.items() if kind is not bool))
#: The rows of the outcome's flags (bool): terminated, then the info's boolean keys in
#: INFO_KEYS order. Written as booleans by the kernel: no conversion after it.
FLAG_ROWS = ("terminated", *(key for key, (kind, _) in INFO_KEYS.items() if kind is bool))
_O = {name: i for i, name in enumerate(OUTCOME_ROWS)}
_F = {name: i for i, name in enumerate(FLAG_ROWS)}
#: Each info key's row: in the outcome's flags for a boolean key, else in its table.
INFO_ROW = {key: _F[key] if kind is bool else _O[key] for key, (kind, _) in INFO_KEYS.items()}
(_S_PHI, _S_PHI_DOT, _S_PHI_DDOT, _S_SUBSTEPS, _S_FINITE, _S_NORMAL, _S_FRICTION, _S_ENERGY,
 _S_LIFT, _S_SLIP, _S_ERR, _S_TOL_MET) = range(len(STEP_FIELDS))
(_C_TORQUE, _C_TARGET, _C_TARGET_RATE, _C_TARGET_TORQUE, _C_Q,
 _C_PSI_RATE) = range(len(CONTEXT_FIELDS))
assert STEP_FIELDS[_S_TOL_MET] == "tol_met" and CONTEXT_FIELDS[_C_PSI_RATE] == "psi_rate"
# A task's numbers (Task.constants), each read by its name's place in TASK_CONSTANTS.
(_K_BAND, _K_MARGIN, _K_PRECISION, _K_SPEED_MARGIN, _K_SPEED_WEIGHT, _K_CONTROL_WEIGHT,
 _K_SUCCESS_SPEED, _K_MAX_TORQUE, _K_SYMMETRIC, _K_OBSERVES_TARGET) = (
    TASK_CONSTANTS.index(name) for name in (
        "success_band", "position_margin", "precision_weight", "speed_margin", "speed_weight",
        "control_weight", "success_speed", "max_torque", "symmetric_target", "observes_target"))
# Row numbers as compile-time constants of the kernel.
(_O_REWARD, _O_PHI, _O_PHI_DOT, _O_PSI, _O_TORQUE, _O_NORMAL, _O_FRICTION, _O_ENERGY,
 _O_SUBSTEPS, _O_LIFT, _O_SLIP, _O_ERR, _O_TARGET_PHI, _O_TARGET_PSI, _O_TARGET_RATE,
 _O_TARGET_TORQUE, _O_ERROR) = (_O[name] for name in (
    "reward", "phi", "phi_dot", "psi", "torque", "normal_force", "friction_force", "energy",
    "substeps", "liftoff_margin", "slip_margin", "error_estimate", "target_phi", "target_psi",
    "target_phi_dot", "target_torque", "position_error"))
(_F_TERMINATED, _F_LIFTING, _F_SLIPPING, _F_NONFINITE, _F_TOL_MET, _F_SUCCESS) = (
    _F[name] for name in ("terminated", "lifting", "slipping", "nonfinite", "tol_met",
                          "is_success"))


# The kernel works on blocks of rollers in a scratch vector of rows a compile-time number of
# elements apart (_B): the loop that computes the outcome then reads and writes one array at
# fixed offsets, which LLVM can prove free of overlap and runs in SIMD lanes (on the rows of
# the tables, whose distance is known only at run time, it would need an overlap check per pair
# of rows, and gives up). Rows are copied in and out of the scratch by one-row loops.
_B = 136  # a block's rollers and pad: 128 + 8 (rows not a power of two apart)
_BLOCK = 128
_N_OBS = len(OBSERVATION_FIELDS)
# scratch rows: the inputs, the outcome's computed rows, then the observation's values
(_B_PHI, _B_PHI_DOT, _B_FINITE, _B_LIFT, _B_SLIP, _B_ERR_IN, _B_TORQUE, _B_TARGET,
 _B_TARGET_RATE, _B_TARGET_TORQUE, _B_Q, _B_RATE) = range(12)
# the input rows' sources: the step's rows, then the context's
_B_STEP_ROWS = (_S_PHI, _S_PHI_DOT, _S_FINITE, _S_LIFT, _S_SLIP, _S_ERR)
_B_CONTEXT_ROWS = (_C_TORQUE, _C_TARGET, _C_TARGET_RATE, _C_TARGET_TORQUE, _C_Q, _C_PSI_RATE)
_B_OUT = len(_B_STEP_ROWS) + len(_B_CONTEXT_ROWS)  # the first computed row
assert _B_OUT == _B_RATE + 1
# the rows _outcome_block computes, in the order it writes them from _B_OUT on; each goes to
# the table's row or the flags' row of its name: (its scratch row after _B_OUT, that row)
_B_COMPUTED_NAMES = ("reward", "terminated", "psi", "lifting", "slipping", "nonfinite",
                     "error_estimate", "target_psi", "position_error", "is_success")
_B_COMPUTED = tuple((k, _O[name]) for k, name in enumerate(_B_COMPUTED_NAMES) if name in _O)
_B_COMPUTED_FLAGS = tuple((k, _F[name]) for k, name in enumerate(_B_COMPUTED_NAMES)
                          if name in _F)
assert len(_B_COMPUTED) + len(_B_COMPUTED_FLAGS) == len(_B_COMPUTED_NAMES)
_B_OBS = _B_OUT + len(_B_COMPUTED_NAMES)
_B_ROWS = _B_OBS + _N_OBS
_B_TARGET_OBS = _B_OBS + list(OBSERVATION_FIELDS).index("cos_psi_target")  # 5 fields on
# the outcome's rows that are the step's or the context's own numbers
_PASSED = ((_O_PHI, _S_PHI), (_O_PHI_DOT, _S_PHI_DOT), (_O_NORMAL, _S_NORMAL),
           (_O_FRICTION, _S_FRICTION), (_O_ENERGY, _S_ENERGY), (_O_SUBSTEPS, _S_SUBSTEPS),
           (_O_LIFT, _S_LIFT), (_O_SLIP, _S_SLIP))
_PASSED_CONTEXT = ((_O_TORQUE, _C_TORQUE), (_O_TARGET_PHI, _C_TARGET),
                   (_O_TARGET_RATE, _C_TARGET_RATE), (_O_TARGET_TORQUE, _C_TARGET_TORQUE))


@register_jitable(inline="always")
def _outcome_of(phi, phi_dot, failed, lift, slip, estimate, tau, target, target_rate,
                target_torque, q, rate, constants):
    """One roller's computed outcome, the values of _B_COMPUTED_NAMES in order (a flag as
    1.0 or 0.0), from its step (φ [rad], φ' [rad/s], failed, the margins, the error
    estimate) and its context (the formulas are :mod:`roller_gym.task`'s)."""
    band, margin, w_p = constants[_K_BAND], constants[_K_MARGIN], constants[_K_PRECISION]
    speed_margin, w_v = constants[_K_SPEED_MARGIN], constants[_K_SPEED_WEIGHT]
    w_u, success_speed = constants[_K_CONTROL_WEIGHT], constants[_K_SUCCESS_SPEED]
    max_torque, symmetric = constants[_K_MAX_TORQUE], constants[_K_SYMMETRIC]
    error = position_error(phi, target, q, symmetric)
    speed_error = phi_dot - target_rate
    reward = step_reward(error, speed_error, (tau - target_torque) / max_torque, band, margin,
                         w_p, speed_margin, w_v, w_u)
    lifting, slipping = lift <= 0.0, slip < 0.0
    return (trig.select(failed, 0.0, reward),  # a failed step earns nothing
            trig.select(lifting | slipping | failed, 1.0, 0.0),  # terminated
            rate * phi,  # ψ
            trig.select(lifting, 1.0, 0.0),
            trig.select(slipping, 1.0, 0.0),
            trig.select(failed, 1.0, 0.0),
            # inf where a finished step has no estimate (NaN from the integrator): info
            # values then compare equal across identical runs (Gymnasium's checker)
            trig.select((estimate != estimate) & (not failed), math.inf, estimate),
            rate * target,  # ψ*
            error,
            trig.select(step_success(error, speed_error, band, success_speed), 1.0, 0.0))


@register_jitable
def _outcome_block(b, m, constants):
    """The outcome of the block's m rollers in the scratch ``b`` (rows _B apart): from the
    input rows into the computed rows and the observation's rows."""
    with_target = constants[_K_OBSERVES_TARGET] != 0.0
    for i in range(m):
        phi, phi_dot, rate = b[_B_PHI * _B + i], b[_B_PHI_DOT * _B + i], b[_B_RATE * _B + i]
        o = _B_OUT * _B + i
        (b[o], b[o + _B], b[o + 2 * _B], b[o + 3 * _B], b[o + 4 * _B], b[o + 5 * _B],
         b[o + 6 * _B], b[o + 7 * _B], b[o + 8 * _B], b[o + 9 * _B]) = _outcome_of(
            phi, phi_dot, b[_B_FINITE * _B + i] == 0.0, b[_B_LIFT * _B + i],
            b[_B_SLIP * _B + i], b[_B_ERR_IN * _B + i], b[_B_TORQUE * _B + i],
            b[_B_TARGET * _B + i], b[_B_TARGET_RATE * _B + i], b[_B_TARGET_TORQUE * _B + i],
            b[_B_Q * _B + i], rate, constants)
        v = _B_OBS * _B + i
        (b[v], b[v + _B], b[v + 2 * _B], b[v + 3 * _B],
         b[v + 4 * _B]) = state_observation(phi, phi_dot, rate)
    # the target's fields, for a task that observes them: in a loop of their own, as a branch
    # in the loop above would be made a select, computing them always
    if with_target:
        for i in range(m):
            v = _B_TARGET_OBS * _B + i
            (b[v], b[v + _B], b[v + 2 * _B], b[v + 3 * _B],
             b[v + 4 * _B]) = target_observation(b[_B_TARGET * _B + i], b[_B_RATE * _B + i],
                                                 b[_B_TARGET_RATE * _B + i])


@register_jitable
def _outcome_one(result, context, constants, observed, out, flags, obs):
    """The outcome of a batch of one roller: :func:`_outcome_range`'s arithmetic without the
    blocks (the same bits, for a fraction of the cost of copying rows of one)."""
    phi, phi_dot, rate = result[_S_PHI, 0], result[_S_PHI_DOT, 0], context[_C_PSI_RATE, 0]
    target, target_rate = context[_C_TARGET, 0], context[_C_TARGET_RATE, 0]
    computed = _outcome_of(
        phi, phi_dot, result[_S_FINITE, 0] == 0.0, result[_S_LIFT, 0], result[_S_SLIP, 0],
        result[_S_ERR, 0], context[_C_TORQUE, 0], target, target_rate,
        context[_C_TARGET_TORQUE, 0], context[_C_Q, 0], rate, constants)
    for pair in _B_COMPUTED:
        out[pair[1], 0] = computed[pair[0]]
    for pair in _B_COMPUTED_FLAGS:
        flags[pair[1], 0] = computed[pair[0]] != 0.0
    for pair in _PASSED:
        out[pair[0], 0] = result[pair[1], 0]
    flags[_F_TOL_MET, 0] = result[_S_TOL_MET, 0] != 0.0
    for pair in _PASSED_CONTEXT:
        out[pair[0], 0] = context[pair[1], 0]
    _observe_row(obs, 0, phi, phi_dot, context, observed)


@register_jitable(inline="always")
def _observe_row(obs, i, phi, phi_dot, context, observed):
    """Row i of ``obs``: the ``observed`` fields of a roller at φ [rad], φ' [rad/s] under
    column i of ``context``."""
    seen = observation_values(phi, phi_dot, context[_C_TARGET, i], context[_C_PSI_RATE, i],
                              context[_C_TARGET_RATE, i])
    for j in range(observed.size):
        obs[i, j] = seen[observed[j]]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _observe(rows, phi, phi_dot, context, observed, obs):
    """The observation of rollers ``rows`` at φ [rad], φ' [rad/s] under their ``context``:
    what a step ending there writes (the batch of one's :func:`_observe_row`)."""
    for i in rows:
        _observe_row(obs, i, phi[i], phi_dot[i], context, observed)


@register_jitable(inline="always")
def _copy(dst, dst_start, src, src_start, m):
    """dst[dst_start + i] = src[src_start + i] for i < m, on rows (1-d arrays); the indices
    unsigned, so that no wraparound check keeps the loop out of SIMD lanes."""
    d, s = np.uint64(dst_start), np.uint64(src_start)
    for i in range(np.uint64(m)):
        dst[d + i] = src[s + i]


@register_jitable(inline="always")
def _copy_flag(dst, dst_start, src, src_start, m):
    """dst[dst_start + i] = src[src_start + i] != 0 for i < m: a row of 1.0/0.0 into a
    boolean row (as :func:`_copy`)."""
    d, s = np.uint64(dst_start), np.uint64(src_start)
    for i in range(np.uint64(m)):
        dst[d + i] = src[s + i] != 0.0


@intrinsic
def _store_streaming(typingctx, row, index, value):
    """row[index] = value (a 1-d array, an unsigned index) as a non-temporal store: a hint to
    the CPU that the line need not be read first nor kept in cache (the outcome's new tables,
    written whole and read, if at all, after the step)."""
    def codegen(context, builder, signature, args):
        rowty, _, valty = signature.args
        array = context.make_array(rowty)(context, builder, args[0])
        ptr = cgutils.get_item_pointer(context, builder, rowty, array, [args[1]],
                                       wraparound=False)
        store = builder.store(context.cast(builder, args[2], valty, rowty.dtype), ptr)
        store.set_metadata("nontemporal", builder.module.add_metadata(
            [llvm_ir.Constant(llvm_ir.IntType(32), 1)]))
        return context.get_dummy_value()

    return numba.types.void(row, index, value), codegen


@intrinsic
def _fence(typingctx):
    """A store fence: the streaming stores before it are seen by every core after it (they
    are weakly ordered otherwise), whatever the threading layer's own ordering. On x86 an
    ``sfence`` (a seq_cst fence compiles to a locked instruction there, which need not wait
    for them); elsewhere a full fence."""
    def codegen(context, builder, signature, args):
        if platform.machine().lower() in ("x86_64", "amd64"):  # numba compiles for its host
            builder.call(cgutils.get_or_insert_function(
                builder.module, llvm_ir.FunctionType(llvm_ir.VoidType(), []),
                "llvm.x86.sse.sfence"), [])
        else:
            builder.fence("seq_cst")
        return context.get_dummy_value()

    return numba.types.void(), codegen


@register_jitable(inline="always")
def _stream(dst, dst_start, src, src_start, m):
    """:func:`_copy` into a new table's row, by non-temporal stores (followed, once the
    rows are written, by :func:`_fence`)."""
    d, s = np.uint64(dst_start), np.uint64(src_start)
    for i in range(np.uint64(m)):
        _store_streaming(dst, d + i, src[s + i])


@register_jitable
def _outcome_range(lo, hi, result, context, constants, observed, out, flags, obs, b):
    """The outcome of rollers lo..hi−1 (see :class:`OutcomeKernel`), block by block in the
    scratch ``b`` (_B_ROWS · _B elements). The float rows go out by streaming stores: the
    tables are new (or written whole) every step, and a store that need not first read its
    cache line from memory costs less where the pass is bound by memory (large batches)."""
    for start in range(lo, hi, _BLOCK):
        m = min(_BLOCK, hi - start)
        for k in range(len(_B_STEP_ROWS)):
            _copy(b, k * _B, result[_B_STEP_ROWS[k]], start, m)
        for k in range(len(_B_CONTEXT_ROWS)):
            _copy(b, (len(_B_STEP_ROWS) + k) * _B, context[_B_CONTEXT_ROWS[k]], start, m)
        _outcome_block(b, m, constants)
        for pair in _B_COMPUTED:
            _stream(out[pair[1]], start, b, (_B_OUT + pair[0]) * _B, m)
        for pair in _B_COMPUTED_FLAGS:
            _copy_flag(flags[pair[1]], start, b, (_B_OUT + pair[0]) * _B, m)
        for pair in _PASSED:
            _stream(out[pair[0]], start, result[pair[1]], start, m)
        _copy_flag(flags[_F_TOL_MET], start, result[_S_TOL_MET], start, m)
        for pair in _PASSED_CONTEXT:
            _stream(out[pair[0]], start, context[pair[1]], start, m)
        for j in range(observed.size):  # field by field: the inner loop reads one row
            row = np.uint64((_B_OBS + observed[j]) * _B)
            for i in range(np.uint64(m)):
                obs[np.uint64(start) + i, j] = b[row + i]
    _fence()


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _outcome_loop(result, context, constants, observed, out, flags, obs, scratch):
    """Every roller's outcome (:func:`_outcome_range`), on one core, in ``scratch``; a batch
    of one by :func:`_outcome_one`."""
    if result.shape[1] == 1:
        _outcome_one(result, context, constants, observed, out, flags, obs)
    else:
        _outcome_range(0, result.shape[1], result, context, constants, observed, out, flags,
                       obs, scratch)


@numba.njit(cache=True, nogil=True, parallel=True, error_model="numpy")
def _outcome_parallel(result, context, constants, observed, out, flags, obs, scratch):
    """Every roller's outcome (:func:`_outcome_range`), in chunks on all cores (each chunk
    in a scratch of its own; ``scratch`` is unused)."""
    n = result.shape[1]
    for chunk in numba.prange((n + CHUNK - 1) // CHUNK):
        _outcome_range(chunk * CHUNK, min(n, (chunk + 1) * CHUNK), result, context, constants,
                       observed, out, flags, obs, np.empty(_B_ROWS * _B))


@register_jitable(inline="always")
def _advance_and_outcome(io, tab, cfg, result, chunk, context, constants, observed, out,
                         flags, obs):
    """A scheme's ``chunk`` (the physics, :attr:`~roller_gym.physics.integrators.Scheme.chunk`)
    and then the outcome (:func:`_outcome_range`) of each chunk of rollers in turn, chunks on
    all cores: the outcome reads the chunk's results while they are still in cache, and a
    step is one parallel pass instead of two."""
    n = io.shape[1]
    for c in numba.prange((n + CHUNK - 1) // CHUNK):
        lo, hi = c * CHUNK, min(n, (c + 1) * CHUNK)
        chunk(io, lo, hi, tab, cfg)
        _outcome_range(lo, hi, result, context, constants, observed, out, flags, obs,
                       np.empty(_B_ROWS * _B))


@register_jitable(inline="always")
def _then_outcome(io, tab, cfg, result, kernel, context, constants, observed, out, flags, obs,
                  scratch):
    """A scheme's serial ``kernel`` (the physics on one core) and then the outcome
    (:func:`_outcome_loop`'s), in one call: for a batch below PARALLEL_THRESHOLD and the
    single environment's roller, whose step is then one compiled call instead of two."""
    kernel(io, tab, cfg)
    _outcome_loop(result, context, constants, observed, out, flags, obs, scratch)


# One fused kernel per scheme's kernel, each a function of its own so that numba caches it.
_TAYLOR, _RK = SCHEMES["taylor"], SCHEMES["rk8"]
_TAYLOR_CHUNK, _RK_CHUNK = _TAYLOR.chunk, _RK.chunk
_TAYLOR_SERIAL, _RK_SERIAL = _TAYLOR.kernels()[0], _RK.kernels()[0]


@numba.njit(cache=True, nogil=True, parallel=True, error_model="numpy")
def _taylor_and_outcome(io, tab, cfg, result, context, constants, observed, out, flags, obs,
                        scratch):
    _advance_and_outcome(io, tab, cfg, result, _TAYLOR_CHUNK, context, constants, observed,
                         out, flags, obs)


@numba.njit(cache=True, nogil=True, parallel=True, error_model="numpy")
def _rk_and_outcome(io, tab, cfg, result, context, constants, observed, out, flags, obs,
                    scratch):
    _advance_and_outcome(io, tab, cfg, result, _RK_CHUNK, context, constants, observed, out,
                         flags, obs)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _taylor_then_outcome(io, tab, cfg, result, context, constants, observed, out, flags, obs,
                         scratch):
    _then_outcome(io, tab, cfg, result, _TAYLOR_SERIAL, context, constants, observed, out,
                  flags, obs, scratch)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _rk_then_outcome(io, tab, cfg, result, context, constants, observed, out, flags, obs,
                     scratch):
    _then_outcome(io, tab, cfg, result, _RK_SERIAL, context, constants, observed, out, flags,
                  obs, scratch)


#: The fused kernels by the stepper's kernel they run in place of (others: two calls). The
#: parallel ones leave ``scratch`` unused (a chunk's is its own), as _outcome_parallel does.
_FUSED = {_TAYLOR.kernels()[1]: _taylor_and_outcome, _RK.kernels()[1]: _rk_and_outcome,
          _TAYLOR_SERIAL: _taylor_then_outcome, _RK_SERIAL: _rk_then_outcome}


_STEP_ROWS = ROWS.index(STEP_FIELDS[0])  # a stepper's io: its result is the last rows
#: What _one_roller unpacks, in order (the stepper's io, tableau and cfg, then
#: OutcomeKernel._buffers()): the dtype and dimensions of each, checked when a step is bound.
_ONE_ARRAYS = ((np.float64, 2), (np.float64, 2), (np.float64, 1), (np.float64, 2),
               (np.float64, 1), (np.int64, 1), (np.float64, 2), (np.bool_, 2), (np.float32, 2),
               (np.float64, 1))
_ONE_DTYPES = tuple(dtype for dtype, _ in _ONE_ARRAYS)


@register_jitable(inline="always")
def _one_roller(phi, phi_dot, tau, packed, kernel):
    """The single environment's step: its roller's inputs and torque written, the physics
    and the outcome (:func:`_then_outcome`), and what the environment reads back, as
    :meth:`~roller_gym.physics.integrators.Stepper.bind` takes it: (missed, φ [rad],
    φ' [rad/s], reward, terminated). ``packed``: the stepper's buffers, then
    :meth:`OutcomeKernel._buffers`."""
    d = _ONE_DTYPES  # a 1-D array is its table's row 0
    io, tab, cfg = unpack(packed, 0, d[0]), unpack(packed, 1, d[1]), unpack(packed, 2, d[2])[0]
    context, constants = unpack(packed, 3, d[3]), unpack(packed, 4, d[4])[0]
    observed, out = unpack(packed, 5, d[5])[0], unpack(packed, 6, d[6])
    flags, obs = unpack(packed, 7, d[7]), unpack(packed, 8, d[8])
    scratch = unpack(packed, 9, d[9])[0]
    flat = io[:, 0]
    put_inputs(flat, phi, phi_dot, tau)
    context[_C_TORQUE, 0] = tau
    _then_outcome(io, tab, cfg, io[_STEP_ROWS:], kernel, context, constants, observed, out,
                  flags, obs, scratch)
    return (missed(flat), out[_O_PHI, 0], out[_O_PHI_DOT, 0], out[_O_REWARD, 0],
            flags[_F_TERMINATED, 0])


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _taylor_one(phi, phi_dot, tau, packed):
    return _one_roller(phi, phi_dot, tau, packed, _TAYLOR_SERIAL)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _rk_one(phi, phi_dot, tau, packed):
    return _one_roller(phi, phi_dot, tau, packed, _RK_SERIAL)


#: The single environment's compiled steps (:func:`_one_roller`) by the stepper's kernel.
_ONE = {_TAYLOR_SERIAL: _taylor_one, _RK_SERIAL: _rk_one}


@dataclass
class Outcome:
    """Reward, flags, info and observation of a step (arrays of rollers, or scalars where
    every input was a scalar)."""

    reward: Any
    terminated: Any
    info: dict[str, Any]
    observation: np.ndarray
    #: all of it as the kernel's table (OUTCOME_ROWS × rollers, float64; rollers flattened)
    table: np.ndarray
    #: and its flags (FLAG_ROWS × rollers, bool; rollers flattened)
    flags: np.ndarray


class OutcomeKernel:
    """The step's outcome for a fixed set of rollers, into buffers of its own: what both
    environments call once per step (and per reset).

    ``table`` (``OUTCOME_ROWS`` × rollers, float64), ``flags`` (``FLAG_ROWS`` × rollers,
    bool), ``observation`` (rollers × the task's observation size, float32) and ``context``
    (``CONTEXT_FIELDS`` × rollers, for the caller to fill) are its buffers; :meth:`run`
    overwrites the first three. With ``fresh``, every run writes a new ``table``, ``flags``
    and ``observation`` instead, which the caller may then hand out (see :func:`info_rows`).
    """

    def __init__(self, task: Any, num: int, fresh: bool = False) -> None:
        self.constants = task.constants
        self.observed = np.array([_FIELD_NUMBER[f] for f in task.observation],
                                 dtype=np.int64)
        self.context = row_table(len(CONTEXT_FIELDS), num)
        self.table = row_table(len(OUTCOME_ROWS), num)
        self.flags = flag_table(num)
        self.observation = np.empty((num, self.observed.size), dtype=np.float32)
        self.fresh = fresh
        self._kernel = _outcome_parallel if num >= PARALLEL_THRESHOLD else _outcome_loop
        self._scratch = np.empty(_B_ROWS * _B if num < PARALLEL_THRESHOLD else 0)

    def run(self, result: np.ndarray) -> np.ndarray:
        """The outcome of the rollers' ``result`` (STEP_FIELDS rows × rollers, float64) under
        the context in :attr:`context`; returns :attr:`table`."""
        self._renew()
        self._kernel(result, *self._buffers())
        return self.table

    def step(self, stepper: Stepper | BatchStepper, phi: Any, phi_dot: Any,
             tau: Any) -> np.ndarray:
        """A control step of the rollers (``stepper``'s, a Stepper or a BatchStepper, from φ
        [rad] and φ' [rad/s] under τ [N·m]) and its outcome, as :meth:`run` on
        ``stepper.run``'s result; in one compiled call where the stepper's kernel has a fused
        kernel (on all cores: one pass over chunks of rollers). Returns :attr:`table`."""
        fused = _FUSED.get(stepper.kernel)
        if fused is None:
            return self.run(stepper.run(phi, phi_dot, tau))
        self._renew()
        stepper.run(phi, phi_dot, tau, fused, *self._buffers())
        return self.table

    def observe(self, phi: np.ndarray, phi_dot: np.ndarray, rows: np.ndarray,
                obs: np.ndarray) -> None:
        """Write into ``obs`` (rollers × fields, float32) the observation of rollers ``rows``
        at φ [rad], φ' [rad/s] under :attr:`context`, as a step ending there gives it."""
        _observe(rows, phi, phi_dot, self.context, self.observed, obs)

    def bind(self, stepper: Stepper) -> Callable[[float, float, float], tuple]:
        """:meth:`step` for one Stepper, with the kernels and buffers looked up once: a
        function ``step(φ [rad], φ' [rad/s], τ [N·m])`` for the single environment, which
        also writes τ into :attr:`context` and returns what the environment reads back:
        (φ [rad], φ' [rad/s], reward, terminated) as Python float and bool. One compiled call
        where the stepper's kernel has one (:data:`_ONE`; not with ``NUMBA_DISABLE_JIT``,
        where nothing is compiled to unpack its arrays). Not for ``fresh`` buffers, which
        every step renews."""
        if self.fresh:
            raise ValueError("a fresh OutcomeKernel renews its buffers every step: use step()")
        one = _ONE.get(stepper.kernel)
        if one is not None and not numba.config.DISABLE_JIT:  # (interpreted: two calls)
            step = stepper.bind(one, *self._buffers())
            kinds = tuple((a.dtype.type, a.ndim) for a in step.arrays)
            assert kinds == _ONE_ARRAYS, f"_one_roller would misread {kinds}"
            return step
        advance, torque = stepper.bind(), self.context[_C_TORQUE]
        table, flags = self.table[:, 0], self.flags[:, 0]

        def step(phi: float, phi_dot: float, tau: float) -> tuple:
            torque[0] = tau
            self.run(advance(phi, phi_dot, tau))
            row = table.tolist()
            return row[_O_PHI], row[_O_PHI_DOT], row[_O_REWARD], bool(flags[_F_TERMINATED])

        return step

    def _buffers(self) -> tuple[np.ndarray, ...]:
        """What the kernels take after the step's result: the context, the task's numbers, the
        outcome's buffers and the scratch."""
        return (self.context, self.constants, self.observed, self.table, self.flags,
                self.observation, self._scratch)

    def _renew(self) -> None:
        if self.fresh:
            self.table = row_table(*self.table.shape, zeroed=False)
            self.flags = flag_table(self.flags.shape[1])
            self.observation = np.empty_like(self.observation)


def outcome(task: Any, result: Any, target: Any, q: Any, psi_rate: Any, tau: Any,
            target_rate: Any = 0.0, target_torque: Any = 0.0) -> Outcome:
    """What a step means for the task: the termination rule, the reward, the info and the
    observation (the environments run the same kernel through :class:`OutcomeKernel`).

    ``result`` is the integrator's StepResult (floats or arrays); the target enters as φ*
    [rad], its rate φ*' [rad/s] and its holding torque τ* [N·m] (:func:`target_torque`).
    The step terminates on lift-off, slip or a step that could not stay finite, each flagged
    in the info; a failed step earns no reward.
    """
    values = [getattr(result, f) for f in STEP_FIELDS]
    context = [tau, target, target_rate, target_torque, q, psi_rate]
    shape = np.broadcast(*values, *context).shape
    n = math.prod(shape)
    kernel = OutcomeKernel(task, n)
    table = result_table(result, shape)
    context_rows = kernel.context.reshape(len(context), *shape)
    for row, value in enumerate(context):  # broadcast as they are written
        context_rows[row] = value
    kernel.run(table.reshape(len(STEP_FIELDS), n))
    rows = info_rows(kernel.table, kernel.flags, tuple(INFO_KEYS), views=True)  # this call's
    scalar = shape == ()
    info = {k: v[0] if scalar else v if v.shape == shape else v.reshape(shape)
            for k, v in rows.items()}
    reward, terminated = kernel.table[_O_REWARD], kernel.flags[_F_TERMINATED]
    if scalar:
        return Outcome(reward[0], terminated[0], info, kernel.observation[0], kernel.table,
                       kernel.flags)
    return Outcome(reward.reshape(shape), terminated.reshape(shape), info,
                   kernel.observation.reshape(*shape, -1), kernel.table, kernel.flags)


def result_table(result: Any, shape: tuple[int, ...] = ()) -> np.ndarray:
    """``result`` (a StepResult or a :class:`RestState`, of floats or arrays broadcast to
    ``shape``) as a stepper's result table: STEP_FIELDS rows of ``shape``, float64."""
    table = np.empty((len(STEP_FIELDS), *shape))
    for row, field in enumerate(STEP_FIELDS):
        table[row] = getattr(result, field)  # broadcast as it is written
    return table


def flag_table(n: int) -> np.ndarray:
    """A boolean table of FLAG_ROWS rows of ``n`` rollers (zeroed), rows a cache line more
    than ``n`` apart (as :func:`~roller_gym.physics.integrators.row_table`)."""
    return np.zeros((len(FLAG_ROWS), n + 64), dtype=bool)[:, :n]


def info_rows(table: np.ndarray, flags: np.ndarray, keys: tuple[str, ...],
              views: bool = False, only: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """The info arrays of ``keys`` from an outcome's ``table`` and ``flags``, each of its
    INFO_KEYS type: new arrays, or with ``views`` the float and boolean rows themselves (for
    tables never written again); with ``only`` (column indices), new arrays of those columns'
    values and 0 (False) in the others, as Gymnasium's vector infos leave unmasked entries."""
    info = {}
    for key in keys:
        kind = INFO_KEYS[key][0]
        row = (flags if kind is bool else table)[INFO_ROW[key]]
        if only is not None:
            info[key] = np.zeros(row.shape, dtype=kind)
            info[key][only] = row[only]
        else:
            info[key] = row if views and kind is not int else row.astype(kind)
    return info


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


def at_start(scene: Scene, phi: np.ndarray, phi_dot: np.ndarray) -> RestState:
    """The contact forces, energy and margins of start states under zero torque."""
    a, normal, friction, energy, lift, slip = contact_state(scene, phi, phi_dot, 0.0)
    n = len(phi)
    return RestState(phi, phi_dot, a, np.zeros(n, np.int64), np.ones(n, bool), normal,
                     friction, energy, lift, slip)


def state_option(value: Any, scene: Scene, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(φ, φ') arrays of n from ``reset(options={"state": (φ [rad], φ' [rad/s])})``.

    Raises:
        ValueError: not a pair of finite real numbers, or a state at which the roller does
            not roll under zero torque (N <= 0 or |F| > μN): such an episode could not start.
    """
    pair = tuple(value) if isinstance(value, tuple | list | np.ndarray) else None
    if (pair is None or len(pair) != 2
            or not all(isinstance(x, int | float | np.integer | np.floating)
                       and not isinstance(x, bool | np.bool_) for x in pair)
            or not all(math.isfinite(x) for x in pair)):
        raise ValueError(
            f"options['state']={value!r} must be a pair (phi [rad], phi_dot [rad/s]) of "
            "finite real numbers"
        )
    phi, phi_dot = np.full(n, float(pair[0])), np.full(n, float(pair[1]))
    with np.errstate(all="ignore"):
        start = at_start(scene, phi, phi_dot)
        rolls = (start.liftoff_margin > 0) & (start.slip_margin >= 0)
    if not rolls.all():
        raise ValueError(
            f"options['state']={value!r}: the roller does not roll there under zero torque "
            f"(N/(m g) = {float(np.min(start.liftoff_margin)):.3g}, "
            f"(μN − |F|)/(m g) = {float(np.min(start.slip_margin)):.3g}; both must be "
            "> 0 and >= 0): choose a state on the surface with less speed"
        )
    return phi, phi_dot
