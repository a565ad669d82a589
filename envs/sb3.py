"""A stable-baselines3 ``VecEnv`` over the native vector environment.

SB3 cannot take a Gymnasium ``VectorEnv``, and its ``make_vec_env`` builds N single
environments stepped one by one in Python. :class:`RollerVecEnv` gives SB3 the native
batch instead: every ``step`` advances the N rollers in one compiled call. It follows
``DummyVecEnv``'s conventions exactly (automatic reset, ``info["terminal_observation"]``,
``info["TimeLimit.truncated"]``, seeds ``seed + i``), so with the same seeds it gives the
same episodes as ``DummyVecEnv`` over single environments, and it works under
``VecNormalize``, ``VecMonitor`` and ``VecCheckNan``::

    from roller_gym.sb3 import RollerVecEnv
    from stable_baselines3 import PPO

    env = RollerVecEnv("roller_gym/RollerStabilize-v2", n_envs=16, seed=0)
    PPO("MlpPolicy", env).learn(100_000)

Importing this module needs stable-baselines3 (the ``train`` extra).
"""

from __future__ import annotations

import pickle
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode
from roller_gym.episode import INFO_KEYS, check_option_names, state_option, vector_seeds
from roller_gym.extras import missing
from roller_gym.physics.integrators import DEFAULT_INTEGRATOR
from roller_gym.physics.scene import shown, whole_number
from roller_gym.vector_env import BATCH_INTEGRATORS

try:
    from stable_baselines3.common.vec_env import DummyVecEnv
    from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices
except ModuleNotFoundError as error:  # (the base install has no stable-baselines3)
    raise missing("stable_baselines3", "train", "roller_gym.sb3") from error

__all__ = ["RollerVecEnv", "from_env_fns"]

#: Wrappers that ``gymnasium.make`` and SB3's ``make_vec_env`` add, which the native batch
#: does itself (``from_env_fns`` falls back to DummyVecEnv over any other wrapper).
#: ``PatchedTimeLimit`` is the ``TimeLimit`` of a process that imported rl-zoo3: it sets
#: ``info["TimeLimit.truncated"]`` as :class:`RollerVecEnv` does.
_PLAIN_WRAPPERS = {"Monitor", "TimeLimit", "PatchedTimeLimit", "OrderEnforcing",
                   "PassiveEnvChecker"}
#: The attributes set_attr sets per sub-environment: the state (φ [rad], φ' [rad/s]).
_STATE = ("phi", "phi_dot")
#: Attributes whose sub-environment's value the native batch holds under another name.
_SINGLE = {"observation_space": "single_observation_space",
           "action_space": "single_action_space"}


def _attribute_name(name: Any, call: str) -> None:
    """A TypeError naming ``call`` (get_attr, set_attr, env_method) unless ``name`` is a
    str."""
    if not isinstance(name, str):
        raise TypeError(f"{call}({shown(name)}, ...): the attribute's name must be a str, not "
                        f"{type(name).__name__}")


def _attribute(base: Any, name: Any, call: str) -> Any:
    """``base``'s attribute ``name`` for ``call`` (get_attr, env_method): an AttributeError
    (what SB3's ``has_attr`` catches) or a TypeError that names the call and the name."""
    _attribute_name(name, call)
    try:
        return getattr(base, name)
    except AttributeError:
        raise AttributeError(f"{call}({shown(name)}): the native batch ({type(base).__name__}) "
                             f"has no attribute {shown(name)}") from None


class RollerVecEnv(VecEnv):
    """N sub-environments of a roller-gym task as one SB3 ``VecEnv``.

    Args:
        env_id: a registered task ID, e.g. ``"roller_gym/RollerStabilize-v2"``.
        n_envs: the number of sub-environments.
        seed: the seed of sub-environment 0 (sub-environment i gets ``seed + i``), as
            ``make_vec_env(env_id, n_envs, seed=seed)``; None for fresh seeds.
        monitor: also report each ended episode's return, length and time in
            ``info["episode"]`` (``{"r", "l", "t"}``), as SB3's ``Monitor`` does for the single
            environments of ``make_vec_env``; a path (``".../name"``) also writes them to
            ``name.monitor.csv`` in Monitor's format.
        **env_kwargs: the environment's keyword arguments (``scene``, ``dt``,
            ``max_torque``, ``randomize``, ``max_episode_steps``, …).
    """

    def __init__(self, env_id: str, n_envs: int = 1, seed: int | None = None,
                 monitor: bool | str = False, **env_kwargs: Any) -> None:
        if isinstance(n_envs, bool) or not isinstance(n_envs, int | np.integer) or n_envs < 1:
            raise ValueError(f"n_envs={shown(n_envs)} must be a positive integer")
        if not isinstance(monitor, bool | str):
            raise ValueError(f"monitor={shown(monitor)} must be True, False or a path (str)")
        _check_seed(seed, int(n_envs))  # before anything is built
        fixed = {"num_envs", "vectorization_mode", "autoreset_mode"} & set(env_kwargs)
        if fixed:
            raise ValueError(f"{', '.join(sorted(fixed))}: RollerVecEnv sets these itself "
                             "(n_envs sub-environments of the native batch, autoreset on the "
                             "same step as SB3 expects); leave them out")
        if not (isinstance(env_id, str) and env_id.rpartition(":")[2].startswith("roller_gym/")):
            raise ValueError(f"env_id={shown(env_id)} is not a roller-gym task ID "
                             "('roller_gym/<Task>-v<N>'): RollerVecEnv batches roller-gym's "
                             "tasks only; for other environments use SB3's make_vec_env")
        registered = sorted(i for i in gym.registry if i.startswith("roller_gym/"))
        if env_id.rpartition(":")[2] not in registered:
            raise ValueError(f"env_id={shown(env_id)} is not a registered roller-gym task ID; "
                             f"registered: {', '.join(registered)}")
        self.venv = gym.make_vec(env_id, num_envs=n_envs, vectorization_mode="vector_entry_point",
                                 autoreset_mode=AutoresetMode.SAME_STEP, **env_kwargs)
        base = self.venv.unwrapped
        self.render_mode = base.render_mode
        super().__init__(base.num_envs, base.single_observation_space,
                         base.single_action_space)
        if seed is not None:
            self.seed(seed)
        self._actions: np.ndarray | None = None
        self._own: set[str] = set()  # attributes set_attr added
        self.monitor = bool(monitor)
        self._returns = np.zeros(self.num_envs)
        self._lengths = np.zeros(self.num_envs, dtype=np.int64)
        self._start = time.time()
        self._writer = None
        if isinstance(monitor, str):
            from stable_baselines3.common.monitor import ResultsWriter

            try:
                self._writer = ResultsWriter(monitor, header={"t_start": self._start,
                                                              "env_id": env_id})
            except OSError as exc:
                self.close()
                raise ValueError(f"monitor={shown(monitor)} cannot be written: "
                                 f"{exc.strerror or exc} (give a path in a writable folder)"
                                 ) from None

    # -- SB3's VecEnv API ----------------------------------------------------------------
    def seed(self, seed: int | None = None) -> Sequence[int | None]:
        """Seed the next reset: sub-environment i with ``seed`` + i (SB3's rule; None: a
        random seed)."""
        _check_seed(seed, self.num_envs)
        return super().seed(None if seed is None else int(seed))

    def reset(self) -> np.ndarray:
        """Every sub-environment starts a new episode, with the seeds and options set by
        ``seed()`` and ``set_options()`` (each sub-environment its own, as DummyVecEnv)."""
        n = self.num_envs
        seeds = self._pending_seeds()
        groups = _option_groups(self._options, n)
        # one reset per group of sub-environments that share options: all of them, or none
        # where a later group's options are refused (the batch as it was before the first)
        snapshot = pickle.dumps(self.venv) if len(groups) > 1 else None
        infos: list[dict[str, Any]] = [{} for _ in range(n)]
        try:
            for options, mask in groups:
                if len(groups) > 1:  # the sub-environments that share these options
                    options = {**(options or {}), "reset_mask": mask}
                obs, info = self.venv.reset(seed=seeds, options=options)
                rows = _rows(info, n)
                for i in np.flatnonzero(mask):
                    infos[i] = rows[i]
        except Exception:
            if snapshot is not None:
                self.venv.__dict__.update(pickle.loads(snapshot).__dict__)
            raise
        self.reset_infos = infos
        self._returns[:], self._lengths[:] = 0.0, 0
        self._reset_seeds()
        self._reset_options()
        return obs

    def _pending_seeds(self) -> list[int | None] | None:
        """The seeds ``seed()`` set for the next reset (None: none set), as the batch's
        ``reset(seed=...)`` takes them."""
        return None if all(s is None for s in self._seeds) else list(self._seeds)

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions  # checked (and clipped) by the batch's step, naming them

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        obs, reward, terminated, truncated, info = self.venv.step(self._actions)
        dones = terminated | truncated
        infos = _rows(info, self.num_envs)
        ended = np.flatnonzero(dones)
        if ended.size:
            final = _rows(info["final_info"], self.num_envs)
            for i in ended:
                self.reset_infos[i] = infos[i]  # the next episode's first info
                infos[i] = final[i]
                infos[i]["terminal_observation"] = info["final_obs"][i]
        for i, (te, tr) in enumerate(zip(terminated.tolist(), truncated.tolist(), strict=True)):
            infos[i]["TimeLimit.truncated"] = tr and not te
        if self.monitor:
            self._returns += reward
            self._lengths += 1
            elapsed = round(time.time() - self._start, 6)
            for i in ended:
                infos[i]["episode"] = {"r": round(float(self._returns[i]), 6),
                                       "l": int(self._lengths[i]), "t": elapsed}
                if self._writer is not None:
                    self._writer.write_row(infos[i]["episode"])
            self._returns[ended], self._lengths[ended] = 0.0, 0
        return obs, reward.astype(np.float32), dones, infos

    def close(self) -> None:
        if self._writer is not None:
            self._writer.close()
        self.venv.close()

    def get_images(self) -> Sequence[np.ndarray | None]:
        frames = self.venv.render()
        return list(frames) if frames is not None else [None] * self.num_envs

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        """The attribute of each sub-environment in ``indices``: an array of the native batch
        with one entry per sub-environment (``phi``, ``target``, …) gives each its own; the
        spaces are a sub-environment's; anything else is the batch's one value."""
        index = list(self._get_indices(indices))
        value = _attribute(self.venv.unwrapped, _SINGLE.get(attr_name, attr_name), "get_attr")
        if self._per_env(value):
            return [value[i].item() if value.ndim == 1 else value[i] for i in index]
        return [value] * len(index)

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        """Set an attribute of the sub-environments in ``indices``: the state (``phi`` [rad],
        ``phi_dot`` [rad/s]) of each, or an attribute of your own (one value, for all of
        them). The native batch's own attributes (its settings and bookkeeping: the target,
        the step counts, ``max_episode_steps``, ``autoreset_mode``, …) are fixed: set them
        where the batch is made or through ``set_options`` and ``reset``."""
        index = list(self._get_indices(indices))
        base = self.venv.unwrapped
        _attribute_name(attr_name, "set_attr")
        if attr_name in _STATE:
            current = getattr(base, attr_name)
            new = current.copy()
            new[index] = self._entries(attr_name, value, current, len(index))
            phi, phi_dot = (new, base.phi_dot) if attr_name == "phi" else (base.phi, new)
            scenes = base.scenes
            for i in index:  # a state a reset could start from: it rolls (as reset checks)
                try:
                    state_option((float(phi[i]), float(phi_dot[i])), scenes[i], 1,
                                 base.config.dt)
                except ValueError as error:
                    raise ValueError(f"set_attr({shown(attr_name)}, value={shown(value)}): the "
                                     "state of "
                                     f"sub-environment {i} would be refused by a reset: "
                                     f"{error}") from None
            current[index] = new[index]
        elif (hasattr(base, attr_name) or hasattr(base.config, attr_name)
              or hasattr(base.task, attr_name)) and attr_name not in self._own:
            # (also the settings of its config and task, max_torque or dt: fixed, as the rest)
            raise ValueError(
                f"set_attr({shown(attr_name)}, indices={shown(indices)}): {shown(attr_name)} is "
                "the native "
                f"batch's own, one value for the whole batch of {self.num_envs} "
                "sub-environments or its bookkeeping, and is not set this way: give settings "
                "where the batch is made (RollerVecEnv(..., name=value)), a target or a "
                "scene through set_options and reset; set_attr sets the state "
                f"({', '.join(_STATE)}) and attributes of your own")
        elif sorted(index) == list(range(self.num_envs)):
            setattr(base, attr_name, value)
            self._own.add(attr_name)
        else:
            raise ValueError(
                f"set_attr({shown(attr_name)}, indices={shown(indices)}): {shown(attr_name)} is "
                "one value for "
                f"the whole native batch of {self.num_envs} sub-environments, so it can only "
                f"be set for all of them (indices=None)")

    def set_options(self, options: list[dict] | dict | None = None) -> None:
        """The next reset's options: one dict for every sub-environment, or a list of
        ``num_envs`` (dicts or None), as SB3's."""
        each = options if isinstance(options, list) else [options] * self.num_envs
        if len(each) != self.num_envs or not all(o is None or isinstance(o, dict)
                                                 for o in each):
            raise ValueError(f"options={shown(options)} must be None, a dict, or a list of "
                             f"{self.num_envs} (one per sub-environment) dicts or None")
        if any(o and "reset_mask" in o for o in each):
            raise ValueError(f"options={shown(options)}: SB3's reset() starts every "
                             "sub-environment; a reset_mask does not apply here")
        for o in each:  # (here, not at every later reset)
            check_option_names(o or {})
        seeds = self._pending_seeds()
        for group, mask in _option_groups(each, self.num_envs):  # their values too, for
            if group:  # the next reset's episodes (with the seeds set before)
                self.venv.check_options(group, mask, seeds)
        super().set_options(options)

    def _get_indices(self, indices: VecEnvIndices) -> list[int]:
        """SB3's indices (None: all; an int; a list of ints), each in [0, num_envs)."""
        index = list(range(self.num_envs)) if indices is None else (
            [indices] if not isinstance(indices, list | tuple | range | np.ndarray)
            else list(indices))
        if not all(whole_number(i) and 0 <= i < self.num_envs for i in index):
            raise ValueError(f"indices={shown(indices)} must be None (all), an integer or a list "
                             f"of integers in [0, {self.num_envs}): the sub-environments")
        return [int(i) for i in index]

    def env_method(self, method_name: str, *method_args: Any, indices: VecEnvIndices = None,
                   **method_kwargs: Any) -> list[Any]:
        """Call a method of the native batch (once, for all sub-environments: the result is
        repeated for each). ``indices`` may only name all of them."""
        index = list(self._get_indices(indices))
        if sorted(index) != list(range(self.num_envs)):
            raise ValueError(
                f"env_method({shown(method_name)}, indices={shown(indices)}): the native batch's "
                f"methods act on all {self.num_envs} sub-environments at once, so indices "
                f"may only be None (all of them); DummyVecEnv over single environments calls "
                f"each on its own")
        method = _attribute(self.venv.unwrapped, method_name, "env_method")
        if not callable(method):
            raise TypeError(f"env_method({shown(method_name)}): the native batch's "
                            f"{shown(method_name)} is not a method (get_attr reads it)")
        return [method(*method_args, **method_kwargs)] * len(index)

    @staticmethod
    def _entries(attr_name: str, value: Any, current: np.ndarray, count: int) -> np.ndarray:
        """``value`` as ``count`` entries of the state ``current`` (φ [rad] or φ' [rad/s]):
        real numbers, one, or one per index (whether the state rolls is checked after)."""
        new = np.asarray(value)
        if (np.ma.isMaskedArray(value) or new.dtype.kind not in "iuf" or new.ndim > 1
                or (new.ndim and len(new) != count)):
            raise ValueError(f"set_attr({shown(attr_name)}, value={shown(value)}): "
                             f"{shown(attr_name)} holds "
                             "finite real numbers, one per sub-environment; give one, or one "
                             f"for each of the {count} indices")
        return new

    def _per_env(self, value: Any) -> bool:
        """Whether ``value`` is an array with one entry per sub-environment."""
        return isinstance(value, np.ndarray) and value.ndim >= 1 and \
            value.shape[0] == self.num_envs

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper],
                       indices: VecEnvIndices = None) -> list[bool]:
        """True for SB3's ``Monitor`` when ``monitor`` is on (the batch reports episodes as
        it does), else False: the sub-environments carry no wrappers."""
        from stable_baselines3.common.monitor import Monitor

        return [self.monitor and wrapper_class is Monitor] * len(self._get_indices(indices))


def _check_seed(seed: Any, n: int) -> None:
    """SB3's seed: None or one integer in range (sub-environment i gets seed + i), checked by
    the vector environments' rule (:func:`vector_seeds`) and refusing its list of seeds."""
    vector_seeds(seed, n)
    if seed is not None and not isinstance(seed, int | np.integer):
        raise ValueError(f"seed={shown(seed)} must be None or an integer: SB3 seeds "
                         "sub-environment i with seed + i (a list of seeds is not SB3's)")


def from_env_fns(env_fns: list[Any], **vec_env_kwargs: Any) -> VecEnv:
    """A ``vec_env_cls`` for SB3's ``make_vec_env`` (and rl-zoo3's
    ``ExperimentManager.default_vec_env_cls``): for environments of one roller-gym task made
    alike (one ID, the same keyword arguments and time limit, no wrappers but the plain ones),
    the native batch (:class:`RollerVecEnv` reporting episodes as ``Monitor`` does);
    ``DummyVecEnv`` for anything else: other tasks, environments that differ, wrappers of
    their own, no time limit (``max_episode_steps=-1``), or an integrator the batch does not
    take (``"dop853"``). Like ``DummyVecEnv`` it takes no other keyword arguments.

    Raises:
        ValueError: ``env_fns`` is not a non-empty list of functions making environments of
            one observation space and one action space (SB3 stacks their observations and
            hands each the same actions), or ``vec_env_kwargs`` are given.
    """
    if not isinstance(env_fns, list | tuple) or not env_fns:
        raise ValueError(f"env_fns={shown(env_fns)} must be a non-empty list of functions that "
                         "each make an environment")
    if vec_env_kwargs:
        raise ValueError(f"from_env_fns takes no keyword arguments (got "
                         f"{', '.join(sorted(vec_env_kwargs))}), as DummyVecEnv takes none")
    probes = []
    for i, fn in enumerate(env_fns):
        env = fn() if callable(fn) else None
        if not isinstance(env, gym.Env):
            got = f"made {shown(env)}" if callable(fn) else "is not callable"
            raise ValueError(f"env_fns[{i}]={shown(fn)} must be a function that makes an "
                             f"environment (it {got})")
        probes.append(_probe(env))
        for name, space, first_space in zip(("observation", "action"), probes[i][6],
                                            probes[0][6], strict=True):
            if space != first_space:
                raise ValueError(f"env_fns[{i}]={shown(fn)} makes an environment whose {name} "
                                 f"space {space} differs from env_fns[0]'s, {first_space}: the "
                                 "environments of one vector env must share their observation "
                                 "and action spaces")
    first = probes[0]
    native = (all(_same(p[:3], first[:3]) and p[3] <= _PLAIN_WRAPPERS for p in probes)
              and first[0] is not None and first[0].startswith("roller_gym/")
              and first[1].get("integrator", DEFAULT_INTEGRATOR) in BATCH_INTEGRATORS
              and first[2] is not None)  # (None: made without a time limit)
    monitor = next((p[4] for p in probes if p[4] is not None), True)
    for p in probes:  # the probes' own Monitor files: never written to
        if native and p[5] is not None:
            p[5].unlink(missing_ok=True)
    if native:
        return RollerVecEnv(first[0], n_envs=len(env_fns), monitor=monitor,
                            max_episode_steps=first[2], **first[1])
    return DummyVecEnv(list(env_fns))


def _probe(env: gym.Env) -> tuple:
    """What decides the batch for one made environment (closed after): its ID, keyword
    arguments, time limit and wrappers' names, the Monitor folder's batch file, the
    probe's own Monitor file and its (observation, action) spaces."""
    wrappers, inner, monitor, probe_file = set(), env, None, None
    while isinstance(inner, gym.Wrapper):
        wrappers.add(type(inner).__name__)
        writer = getattr(inner, "results_writer", None)
        if writer is not None:  # make_vec_env's monitor_dir: write there too
            probe_file = Path(writer.file_handler.name)
            monitor = str(probe_file.parent / "batch")
        inner = inner.env
    spec = env.spec  # the outermost: it carries make()'s max_episode_steps
    spaces = env.observation_space, env.action_space  # the outermost's, as SB3 reads them
    env.close()
    if spec is None:
        return None, {}, None, wrappers, monitor, probe_file, spaces
    return (spec.id, dict(spec.kwargs), spec.max_episode_steps, wrappers, monitor, probe_file,
            spaces)


def _same(a: Any, b: Any) -> bool:
    """Whether two environments' arguments are equal, NumPy arrays among them (compared by
    value, where ``==`` gives an array)."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return (type(a) is type(b) and len(a) == len(b)
                and all(_same(x, y) for x, y in zip(a, b, strict=True)))
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return (isinstance(a, np.ndarray) and isinstance(b, np.ndarray)
                and a.dtype == b.dtype and np.array_equal(a, b))
    try:
        return bool(a == b)
    except (TypeError, ValueError):  # an object whose == is not a truth value
        return a is b


def _option_groups(options: list[dict | None], n: int) -> list[tuple[dict | None,
                                                                       np.ndarray]]:
    """The sub-environments' reset options as groups that share them: (options, mask), the
    empty ones (None or {}) as one group (SB3's ``set_options`` repeats one dict)."""
    groups: dict[int, tuple[dict | None, np.ndarray]] = {}
    for i in range(n):
        value = options[i] if options and options[i] else None
        key = 0 if value is None else id(value)
        groups.setdefault(key, (value, np.zeros(n, dtype=bool)))[1][i] = True
    return list(groups.values())


def _rows(info: dict[str, Any], n: int) -> list[dict[str, Any]]:
    """A vector info as one dict per sub-environment (Python scalars), SB3's layout."""
    keys = [k for k in INFO_KEYS if k in info]
    columns = [np.asarray(info[k]).tolist() for k in keys]
    return [dict(zip(keys, row, strict=True)) for row in zip(*columns, strict=True)] if keys \
        else [{} for _ in range(n)]
