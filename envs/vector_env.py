"""The native vector environment: N rollers advanced together by the batched physics.

``gymnasium.make_vec(ID, num_envs=N)`` builds it (registered as the tasks'
``vector_entry_point``). A step costs a fixed number of Python operations whatever N is:
the actions are checked as one array; the batch stepper advances every roller, and reward,
termination, info and observation follow (:class:`roller_gym.episode.OutcomeKernel`, the
one the single environment runs on its one roller): one compiled call for taylor, rk8 and
rk4 (on all cores a pass over chunks of rollers, each chunk's physics and then its outcome),
two for the others. The episode starts of autoreset are drawn ahead, many at once, by the
episode core (:mod:`roller_gym.episode`), and copied out when needed. Sub-environment i, seeded
``seed + i``, reproduces the single environment seeded ``seed + i`` exactly.

Autoreset (``autoreset_mode=``, Gymnasium's three modes):

* ``NEXT_STEP`` (the default): the step after an episode ends returns the first
  observation of the next, with reward 0, both flags False and the reset's info;
* ``SAME_STEP``: the step that ends an episode returns the first observation of the next;
  the last observation is in ``info["final_obs"]`` (an object array, None where no episode
  ended) and the last info in ``info["final_info"]``, each with its ``_`` mask;
* ``DISABLED``: no autoreset; call ``reset(options={"reset_mask": mask})`` for the ended ones.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any, ClassVar

import numba
import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from roller_gym import clients, episode, validation
from roller_gym.config import EnvConfig, Settings, resolve_scene, takes_settings
from roller_gym.physics import Scene
from roller_gym.physics.integrators import INTEGRATORS, BatchStepper
from roller_gym.physics.integrators.layout import check_memory
from roller_gym.physics.scene import shown
from roller_gym.task import Task, get_task, psi_rate, wrap_rate

__all__ = ["RollerVectorEnv"]

#: The integrators of the batch: all but scipy's DOP853, a reference for one roller.
BATCH_INTEGRATORS = tuple(m for m in INTEGRATORS if m != "dop853")

_ROW = {name: i for i, name in enumerate(episode.OUTCOME_ROWS)}
_FLAG = {name: i for i, name in enumerate(episode.FLAG_ROWS)}
_CONTEXT = {name: i for i, name in enumerate(episode.CONTEXT_FIELDS)}


@dataclass
class _Starts:
    """Episode starts of some sub-environments, ready to apply, a row each: their scene,
    their target's parameters, the step context they start with (a row of CONTEXT_FIELDS),
    their outcome at the start (a row of OUTCOME_ROWS and one of FLAG_ROWS: the state and the
    reset info) and their observation. A row is a sub-environment's, so that taking a few of
    many (an autoreset) reads a few cache lines each."""

    scene: Scene
    target_params: np.ndarray
    context: np.ndarray
    table: np.ndarray
    flags: np.ndarray
    observation: np.ndarray

    def put(self, idx: np.ndarray, starts: _Starts, size: int) -> None:
        """Replace those of sub-environments ``idx`` by ``starts`` (self holds all ``size``)."""
        if starts.scene is not self.scene:
            self.scene = episode.put(self.scene, idx, starts.scene, size)
        self.target_params[idx] = starts.target_params
        self.context[idx], self.table[idx] = starts.context, starts.table
        self.flags[idx] = starts.flags
        self.observation[idx] = starts.observation


_NONE = np.uint64(2**64 - 1)  # an episode number no start is drawn for
# The rows of the outcome's table and flags from _INFO on are the info (before it: the
# reward, and the terminated flag).
_INFO = 1
assert set(episode.OUTCOME_ROWS[_INFO:] + episode.FLAG_ROWS[_INFO:]) == set(episode.INFO_KEYS)
_PHI_ROW, _PHI_DOT_ROW = _ROW["phi"], _ROW["phi_dot"]


# The copies of an episode start, compiled: an autoreset starts a few hundred of many
# sub-environments, whose rows are scattered over the tables (a loop over them, rather than a
# dozen fancy-indexed copies and their temporaries).
@numba.njit(cache=True, nogil=True)
def _start_rows(idx, rows, context, target_params, table, observation,  # the starts'
                env_context, env_target_params, phi, phi_dot, steps, env_observation):
    """Sub-environment idx[k] takes row rows[k] of the starts (a row per start: its step
    context, target parameters, outcome and observation) as its context, target parameters,
    state φ [rad], φ' [rad/s] and observation; its step count is 0."""
    for k in range(idx.size):
        i, j = idx[k], rows[k]
        for c in range(context.shape[1]):
            env_context[c, i] = context[j, c]
        for c in range(target_params.shape[1]):
            env_target_params[i, c] = target_params[j, c]
        for c in range(observation.shape[1]):
            env_observation[i, c] = observation[j, c]
        phi[i], phi_dot[i], steps[i] = table[j, _PHI_ROW], table[j, _PHI_DOT_ROW], 0


@numba.njit(cache=True, nogil=True)
def _start_info(idx, rows, table, flags, env_table, env_flags):
    """The info rows (from _INFO on) of sub-environments idx[k] in a step's outcome: those of
    row rows[k] of the starts' ``table`` and ``flags``."""
    for k in range(idx.size):
        i, j = idx[k], rows[k]
        for c in range(_INFO, table.shape[1]):
            env_table[c, i] = table[j, c]
        for c in range(_INFO, flags.shape[1]):
            env_flags[c, i] = flags[j, c]


def _masks(keys: Sequence[str], n: int, where: np.ndarray | None = None) -> dict[str, Any]:
    """The ``_key`` masks of a vector info: for each key an array of its own (the rows of one
    allocation; a caller, or Gymnasium's ``_add_info``, may write into one), True for every
    sub-environment, or for those in ``where`` only."""
    if where is None:
        rows = np.ones((len(keys), n), dtype=bool)
    else:
        rows = np.zeros((len(keys), n), dtype=bool)
        rows[:, where] = True
    return dict(zip((f"_{k}" for k in keys), rows, strict=True))


#: Memory [bytes] a sub-environment's arrays take, at most (its tables of outcome, starts
#: drawn ahead and stepper, with every info key; rounded up).
BYTES_PER_ENV = 4096


def _some(idx: np.ndarray) -> str:
    """Sub-environment numbers for a message: the first ten, and how many more."""
    more = f" and {idx.size - 10} more" if idx.size > 10 else ""
    return f"{idx[:10].tolist()}{more}"


def _context_row(name: str, doc: str) -> property:
    """A row of the step's context table (a view: written in place, never rebound)."""
    return property(lambda self: self._outcome.context[_CONTEXT[name]], doc=doc)


def _autoreset_mode(value: AutoresetMode | str) -> AutoresetMode:
    """An AutoresetMode from itself, its name (``"SAME_STEP"``, any case) or its value."""
    for mode in AutoresetMode:
        if value is mode or (isinstance(value, str) and value.upper() in (
                mode.name, mode.value.upper())):
            return mode
    allowed = ", ".join(f"AutoresetMode.{m.name}" for m in AutoresetMode)
    raise ValueError(f"autoreset_mode={shown(value)} is not allowed: pass one of {allowed} "
                     "(or its name, e.g. 'next_step')")


@takes_settings(before=("num_envs", "task"),
                after=("max_episode_steps", "autoreset_mode"))
class RollerVectorEnv(VectorEnv):
    """N rollers, each with its own scene, target and random stream.

    Args:
        num_envs: the number of sub-environments.
        task: the task (a name of the registry, its ID, or its class).
        {settings}
        max_episode_steps: truncation; default the task's.
        autoreset_mode: ``AutoresetMode.NEXT_STEP`` (default), ``SAME_STEP`` or
            ``DISABLED`` (or their names as strings), as in Gymnasium's vector envs.
    """

    # The per-step numbers the outcome takes besides the integrator's (episode.CONTEXT_FIELDS)
    # are the environment's own state, kept in the outcome's context table.
    torque = _context_row("torque", "τ [N·m] of each sub-environment's last step (0 at a start)")
    target = _context_row("target_phi", "each sub-environment's target φ* [rad]")
    target_rate = _context_row("target_phi_dot", "how fast each target moves, φ*' [rad/s]")
    target_torque = _context_row("target_torque", "τ* [N·m] that holds each roller at φ*")
    target_energy = _context_row("target_energy", "E* [J] of each roller at rest at φ*")
    _q = _context_row("wrap_rate", "the rate q errors are wrapped by [-]")
    _psi_rate = _context_row("psi_rate", "dψ/dφ [-]")

    metadata: ClassVar[dict[str, Any]] = {
        "render_modes": ["rgb_array"],
        "render_fps": 20,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }
    def __init__(
        self,
        num_envs: int = 1,
        task: str | type[Task] = "RollerStabilize",
        *,
        max_episode_steps: int | None = None,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        **settings: Any,
    ) -> None:
        num_envs = validation.count("num_envs", num_envs)
        given = Settings.of(type(self), settings)
        check_memory("num_envs", num_envs, BYTES_PER_ENV)
        try:
            self._build(num_envs, task, given, max_episode_steps, autoreset_mode)
        except MemoryError:
            raise ValueError(f"num_envs={num_envs} is too many: the arrays of that many "
                             "sub-environments could not be allocated (out of memory); use "
                             "fewer") from None

    def _build(self, num_envs: int, task: str | type[Task], settings: Settings,
               max_episode_steps: int | None, autoreset_mode: AutoresetMode | str) -> None:
        scene, integrator = settings.scene, settings.integrator
        per_env = self._per_env_scenes(scene, num_envs)
        task_class = get_task(task, current=True)
        resolved = [resolve_scene(s, task_class.default_scene, f"scene[{i}]")
                    for i, s in enumerate(per_env)]
        self.config = EnvConfig.build(
            task_class, replace(settings, scene=None) if per_env else settings,
            render_modes=self.metadata["render_modes"], scenes=resolved or None)
        if integrator not in BATCH_INTEGRATORS:
            raise ValueError(f"integrator={shown(integrator)} is a reference for the single "
                             "environment; the vector environment takes one of "
                             f"{', '.join(map(repr, BATCH_INTEGRATORS))}")
        self.autoreset_mode = _autoreset_mode(autoreset_mode)
        self.metadata = {**type(self).metadata, "autoreset_mode": self.autoreset_mode}
        task = self.task = self.config.task
        if per_env:  # each distinct scene checked by EnvConfig.build
            self._base = Scene.stack(resolved)
        else:
            self._base = self.config.scene
        self.num_envs = num_envs
        self.render_mode = self.config.render_mode
        self.max_episode_steps = (task.max_episode_steps if max_episode_steps is None else
                                  validation.count("max_episode_steps", max_episode_steps))
        self.single_action_space = spaces.Box(-1.0, 1.0, (1,), np.float32)
        self.action_space = batch_space(self.single_action_space, num_envs)
        size = task.observation_size
        self.single_observation_space = spaces.Box(-1.0, 1.0, (size,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, num_envs)

        cfg = self.config
        self._stepper = BatchStepper(num_envs, integrator=cfg.integrator, dt=cfg.dt,
                                     tolerance=cfg.tolerance, substeps=cfg.substeps or None)
        self._scene = self._base  # a scalar Scene while every sub-environment shares it
        self._option_scene = np.zeros(num_envs, dtype=bool)  # in an episode of a scene option
        self._stepper.set_scenes(self._scene)
        # every step writes a new outcome table: its rows are handed out (reward, info)
        self._outcome = episode.OutcomeKernel(task, num_envs, fresh=True)
        self._q[:] = wrap_rate(self._scene)
        self._psi_rate[:] = psi_rate(self._scene)
        self.phi = np.zeros(num_envs)
        self.phi_dot = np.zeros(num_envs)
        self.target[:] = episode.per_scene_target(task, self._scene, num_envs)
        self._set_target_terms()
        self._target_params = np.repeat(self.target[:, None], task.target_size, axis=1)
        self.steps = np.zeros(num_envs, dtype=np.int64)
        self._done = np.zeros(num_envs, dtype=bool)
        self._seeds = np.zeros(num_envs, np.uint64)
        self._episodes = np.zeros(num_envs, np.uint64)
        self._has_seed = np.zeros(num_envs, dtype=bool)
        self._started = np.zeros(num_envs, dtype=bool)  # each has had an episode start
        self._ready = False  # all have
        self._ahead: _Starts | None = None  # the next start of each, drawn ahead (_restart)
        self._ahead_for = np.zeros(num_envs, np.uint64)  # the episode each was drawn for
        # the last observation: the step's own (new every step, handed out as it is; a reset
        # computes the one of the sub-environments it leaves alone anew), or the reset's
        self._obs = np.zeros((num_envs, size), dtype=np.float32)
        self._obs_handed_out = False
        self._renderers: list[Any] | None = None

    @staticmethod
    def _per_env_scenes(scene: Any, n: int) -> list[Any]:
        """The per-sub-environment scenes given, or [] when one scene serves all."""
        if isinstance(scene, Scene) and scene.batch_size is not None:
            if scene.batch_size != n:
                raise ValueError(
                    f"scene is a batch of {scene.batch_size} rollers; num_envs={n} needs {n}"
                )
            return [scene.item(i) for i in range(n)]
        if isinstance(scene, list | tuple):
            if len(scene) != n:
                raise ValueError(f"scene has {len(scene)} entries; num_envs={n} needs {n}")
            return list(scene)
        return []

    @property
    def scenes(self) -> list[Scene]:
        """Each sub-environment's scene of its current episode (scalar Scenes)."""
        if self._scene.batch_size is None:
            return [self._scene] * self.num_envs
        return [self._scene.item(i) for i in range(self.num_envs)]

    def _set_target_terms(self) -> None:
        """The context's rows that follow from the targets (episode.target_terms)."""
        for name, row in episode.target_terms(self._scene, self.target).items():
            self._outcome.context[_CONTEXT[name]] = row

    # -- episode starts ------------------------------------------------------------------
    def _draw(self, idx: np.ndarray, episodes: np.ndarray,
              options: Mapping[str, Any] | None) -> _Starts:
        """The starts of episodes ``episodes`` of sub-environments ``idx`` (not applied)."""
        base = self._base if self._base.batch_size is None else episode.take(
            self._base, idx, self.num_envs)
        start = episode.start_episodes(self.config, base, self._seeds[idx], episodes, options)
        c = {"torque": 0.0, "target_phi": start.target, "target_phi_dot": start.target_rate,
             **episode.target_terms(start.scene, start.target),
             "wrap_rate": wrap_rate(start.scene), "psi_rate": psi_rate(start.scene)}
        context = np.empty((idx.size, len(episode.CONTEXT_FIELDS)))
        for name, row in c.items():
            context[:, _CONTEXT[name]] = row
        out = episode.outcome(self.task, episode.at_start(start.scene, start.phi, start.phi_dot),
                              c)
        return _Starts(start.scene, start.target_params, context,
                       np.ascontiguousarray(out.table.T), np.ascontiguousarray(out.flags.T),
                       out.observation)

    def _apply(self, idx: np.ndarray, starts: _Starts, scene_option: bool,
               rows: np.ndarray | None = None) -> None:
        """Start the episodes of ``starts`` (its rows ``rows``; all, in order, if None) in
        sub-environments ``idx`` (``scene_option``: with the scene of a reset option, for
        these episodes only)."""
        rows = np.arange(idx.size) if rows is None else rows
        if self.config.randomize or scene_option or self._option_scene[idx].any():
            scene = episode.take(starts.scene, rows, len(starts.context))
            self._scene = episode.put(self._scene, idx, scene, self.num_envs)
            self._stepper.set_scenes(scene, idx)
        self._option_scene[idx] = scene_option
        _start_rows(idx, rows, starts.context, starts.target_params, starts.table,
                    starts.observation, self._outcome.context, self._target_params, self.phi,
                    self.phi_dot, self.steps, self._obs)
        self._stepper.forget(idx)  # a new episode does not continue the last one's substeps

    def reset(
        self,
        *,
        seed: int | Sequence[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset sub-environments: all, or those of ``options["reset_mask"]`` (a boolean
        array of ``num_envs``).

        ``seed``: an int gives sub-environment i the seed ``seed + i``; a list gives each its
        own, where None (like ``seed=None``) reseeds none: its episodes go on from its seed,
        as a single environment's ``reset(seed=None)`` (a fresh seed if it has none yet).
        Only the reset sub-environments take their seeds. ``options`` as in
        :meth:`roller_gym.roller_env.RollerEnv.reset`, for every reset sub-environment.
        """
        clients.check_caller(self, self.autoreset_mode)  # a client that miscounts this mode
        options = episode.reset_options(options)
        mask = episode.reset_mask(options.pop("reset_mask", None), self.num_envs)
        kept = self._streams()  # refused options leave every count as it was
        try:
            idx, starts = self._next_starts(mask, seed, options)
        except Exception:
            self._set_streams(kept)
            raise
        if isinstance(seed, int | np.integer):
            self._np_random, self._np_random_seed = seeding.np_random(int(seed))
        if self._obs_handed_out:  # the caller's, who may have changed it: the others' anew
            self._obs = np.empty_like(self._obs)
            self._outcome.observe(self.phi, self.phi_dot, np.flatnonzero(~mask), self._obs)
            self._obs_handed_out = False
        self._apply(idx, starts, options.get("scene") is not None)
        self._done[idx] = False
        if not self._ready:
            self._started[idx] = True
            self._ready = bool(self._started.all())
        return self._observation(), self._masked_info(starts, idx)

    def check_options(self, options: dict[str, Any] | None, mask: np.ndarray | None = None,
                      seed: int | Sequence[int | None] | None = None) -> None:
        """Raise ValueError where the next :meth:`reset` of the sub-environments of ``mask``
        (a boolean array of ``num_envs``; all if None) with ``seed`` (as reset's) would
        refuse ``options``: their next episodes drawn as that reset would draw them (a
        sub-environment without a seed yet: from a fresh seed, as there); nothing
        changes."""
        kept = self._streams()
        try:
            self._next_starts(episode.reset_mask(mask, self.num_envs), seed,
                              episode.reset_options(options))
        finally:
            self._set_streams(kept)

    def _next_starts(self, mask: np.ndarray, seed: int | Sequence[int | None] | None,
                     options: dict[str, Any]) -> tuple[np.ndarray, _Starts]:
        """(the rows of ``mask``, the starts of their next episodes), their streams moved on
        to them as :meth:`reset` with ``seed`` moves them: seeded rows start their streams
        anew, as do rows without a seed yet (a fresh one); the others go on to their next
        episode. Not undone if the draw is refused: see :meth:`_streams`."""
        n = self.num_envs
        seeds = episode.vector_seeds(seed, n) or [None] * n
        given = np.array([s is not None for s in seeds])
        anew = mask & (given | ~self._has_seed)
        if anew.any():
            rows = np.flatnonzero(anew)
            self._seeds[rows] = np.array(
                [episode.random_seed() if seeds[i] is None else seeds[i] for i in rows],
                dtype=np.uint64)
            self._episodes[rows] = 0
            self._ahead_for[rows] = _NONE  # those drawn ahead came from the old seeds
            self._has_seed[rows] = True
        self._episodes[mask & ~anew] += np.uint64(1)
        idx = np.flatnonzero(mask)
        return idx, self._draw(idx, self._episodes[idx], options)

    def _streams(self) -> list[tuple[str, np.ndarray]]:
        """Copies of the sub-environments' streams and episode counts, for
        :meth:`_set_streams` to put back."""
        return [(name, getattr(self, name).copy())
                for name in ("_seeds", "_episodes", "_ahead_for", "_has_seed")]

    def _set_streams(self, kept: list[tuple[str, np.ndarray]]) -> None:
        for name, value in kept:
            setattr(self, name, value)

    # -- a step --------------------------------------------------------------------------
    def step(
        self, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        if not self._ready:
            never = np.flatnonzero(~self._started)
            raise RuntimeError(
                f"call reset() before step(): sub-environments {_some(never)} have not started "
                f"an episode (reset() without a reset_mask starts every one)")
        if self.autoreset_mode == AutoresetMode.DISABLED and self._done.any():
            raise RuntimeError(
                f"step() with autoreset_mode=DISABLED: the episodes of sub-environments "
                f"{_some(np.flatnonzero(self._done))} have ended; start new ones first with "
                f"reset(options={{'reset_mask': mask}}) (mask: terminated | truncated)")
        tau = self.torque  # the context's row, written in place (as it is, if refused)
        validation.actions(actions, (self.num_envs, 1), self.task.max_torque, tau)
        self.steps += 1
        if self.task.moving_target:
            self.target[:], self.target_rate[:] = self.task.target_at(
                self._target_params, self.steps * self.config.dt)
            self._set_target_terms()
        # the physics and the outcome; a new table: its rows are handed out as they are
        table = self._outcome.step(self._stepper, self.phi, self.phi_dot, tau)
        flags, self._obs = self._outcome.flags, self._outcome.observation  # new: returned
        self._obs_handed_out = True
        reward = table[_ROW["reward"]]
        terminated = flags[_FLAG["terminated"]]
        truncated = self.steps >= self.max_episode_steps
        # the state, a copy: the outcome's rows are the info's, which the caller may change
        self.phi, self.phi_dot = table[_PHI_ROW].copy(), table[_PHI_DOT_ROW].copy()
        final: dict[str, Any] = {}
        if self.autoreset_mode == AutoresetMode.NEXT_STEP:
            # The sub-environments that ended last step start over now.
            restarted = np.flatnonzero(self._done)
            if restarted.size:
                self._restart(restarted, table, flags)
                reward[restarted] = 0.0
                terminated[restarted] = truncated[restarted] = False
            self._done = terminated | truncated
        elif self.autoreset_mode == AutoresetMode.SAME_STEP:
            ended = np.flatnonzero(terminated | truncated)
            if ended.size:
                final = self._final(ended, table, flags)
                self._restart(ended, table, flags)
        else:  # DISABLED: the ended ones wait for reset(options={"reset_mask": ...})
            self._done = terminated | truncated
        info = episode.info_rows(table, flags, self.config.info_keys, views=True)
        info.update(_masks(list(info), self.num_envs))
        info.update(final)
        return self._obs, reward, terminated, truncated, info

    def _final(self, ended: np.ndarray, table: np.ndarray,
               flags: np.ndarray) -> dict[str, Any]:
        """SAME_STEP's report of the episodes ``ended`` before they start over: their last
        observation and info (Gymnasium's layout: an object array, None where none ended;
        each with its ``_`` mask)."""
        masks = _masks(("final_obs", "final_info", *self.config.info_keys), self.num_envs,
                       ended)
        final_obs = np.full(self.num_envs, None, dtype=object)
        last = self._observation()
        for i in ended:  # per ended episode
            final_obs[i] = last[i]
        final_info = episode.info_rows(table, flags, self.config.info_keys, only=ended)
        final_info.update({f"_{k}": masks[f"_{k}"] for k in self.config.info_keys})
        return {"final_obs": final_obs, "_final_obs": masks["_final_obs"],
                "final_info": final_info, "_final_info": masks["_final_info"]}

    def _restart(self, idx: np.ndarray, table: np.ndarray, flags: np.ndarray) -> None:
        """Autoreset: new episodes in ``idx``, their reset info written into the info rows of
        the step's outcome ``table`` and ``flags``.

        A start is a pure function of the sub-environment's seed and episode number (the
        counter-based streams of :mod:`roller_gym.episode`), so the next start of every
        sub-environment is drawn ahead, many at once, and an autoreset only copies its
        sub-environments' starts out (the same numbers as drawing them then). The starts
        ahead are drawn again, for every sub-environment whose one is used up, when an
        autoreset needs a used one."""
        n, one = self.num_envs, np.uint64(1)
        if self._ahead is None:
            following = self._episodes + one
            self._ahead, self._ahead_for = self._draw(np.arange(n), following, None), following
        elif (self._ahead_for[idx] != self._episodes[idx] + one).any():
            following = self._episodes + one
            stale = np.flatnonzero(self._ahead_for != following)
            self._ahead.put(stale, self._draw(stale, following[stale], None), n)
            self._ahead_for[stale] = following[stale]
        self._episodes[idx] += np.uint64(1)
        self._apply(idx, self._ahead, False, rows=idx)
        _start_info(idx, idx, self._ahead.table, self._ahead.flags, table, flags)

    # -- observation and info ------------------------------------------------------------
    def _observation(self) -> np.ndarray:
        """The observation of every sub-environment's current state (a new array)."""
        return self._obs.copy()

    def _masked_info(self, starts: _Starts, idx: np.ndarray) -> dict[str, Any]:
        """A vector info whose rows ``idx`` hold the outcomes of ``starts`` and whose masks
        mark only them."""
        full = np.zeros((len(episode.OUTCOME_ROWS), self.num_envs))
        full[:, idx] = starts.table.T
        flags = episode.flag_table(self.num_envs)
        flags[:, idx] = starts.flags.T
        info = episode.info_rows(full, flags, self.config.info_keys, views=True)
        info.update(_masks(self.config.info_keys, self.num_envs, idx))
        return info

    # -- rendering -------------------------------------------------------------------------
    def render(self) -> tuple[np.ndarray, ...] | None:
        """One RGB frame per sub-environment (``render_mode="rgb_array"``)."""
        if self.render_mode is None:
            return None
        from roller_gym.rendering import Renderer

        if self._renderers is None:
            self._renderers = [Renderer("rgb_array", self.metadata["render_fps"])
                               for _ in range(self.num_envs)]
        scenes = self.scenes
        return tuple(
            r.draw(scenes[i], self.phi[i], self.target[i], self.torque[i],
                   self.task.max_torque, self.task.observes_target)
            for i, r in enumerate(self._renderers)
        )

    def close_extras(self, **kwargs: Any) -> None:
        for r in getattr(self, "_renderers", None) or []:  # also after a failed __init__
            r.close()
        self._renderers = None

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_renderers"] = None  # pygame surfaces do not pickle: draw again afterwards
        # The starts drawn ahead are drawn again when needed (the same numbers: a pure function
        # of the seeds), in the layout the kernels were compiled for, which pickling loses.
        state["_ahead"] = None
        return state
