"""The check of ``roller-gym train --hyperparams``: every key rl-zoo3 or the algorithm takes has
a rule (:data:`RULES`), and a value is refused by name before rl-zoo3 starts, where a wrong one
would end in a traceback from rl-zoo3, stable-baselines3 or torch, or train silently on nonsense.

Values that rl-zoo3 evaluates as Python (``policy_kwargs``, ``replay_buffer_class``, ...) are
evaluated the same way and the object they make is built once (a policy, a replay buffer, a
wrapped environment, the callbacks), so what would fail in training fails here, by name.
"""

from __future__ import annotations

import ast
import inspect
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from roller_gym.agents.policies import algorithm_class
from roller_gym.physics.scene import finite_real
from roller_gym.scripts.arguments import key_values

#: The entries of a hyperparameter file that rl-zoo3 reads itself (rl_zoo3.exp_manager);
#: the others are keyword arguments of the algorithm's class.
ZOO_KEYS = ("n_timesteps", "n_envs", "normalize", "env_wrapper", "vec_env_wrapper", "callback",
            "frame_stack", "noise_type", "noise_std", "monitor_kwargs", "env_kwargs")
#: The algorithm's keyword arguments rl-zoo3 sets itself, from train's own options.
ZOO_SETS = ("env", "tensorboard_log", "seed", "verbose", "device")
#: The largest count a hyperparameter may take (a larger buffer could not be allocated).
HYPERPARAM_COUNT_MAX = 10**9
#: The most observations frame_stack may stack (the tasks' episodes are 200–400 steps).
FRAME_STACK_MAX = 1000
#: The counts an SB3 or rl-zoo3 callback keeps as attributes, each an integer >= 1 (0 ends the
#: first call in a ZeroDivisionError, a float or a negative one never fires).
CALLBACK_COUNTS = ("save_freq", "eval_freq", "n_eval_episodes", "n_steps", "max_episodes",
                   "gradient_steps")
#: The policies for the tasks' observations (a vector: a Box), by rl-zoo3's alias.
POLICIES = ("MlpPolicy",)


@dataclass(frozen=True)
class Given:
    """What a rule may read besides its value: the algorithm, the task's ID (None: the
    environment is not built) and every hyperparameter given with it."""

    algo: str
    env_id: str | None
    values: dict[str, Any]


#: A rule: whether a value is allowed (a rule may raise ValueError saying why not), and what is.
Rule = tuple[Callable[[Any, Given], bool], str]


def accepted_keys(algo: str) -> list[str]:
    """The hyperparameters ``--hyperparams`` takes for ``algo``: rl-zoo3's own and the
    algorithm class's keyword arguments but those train sets itself."""
    return [*ZOO_KEYS, *(name for name in inspect.signature(algorithm_class(algo)).parameters
                         if name not in ZOO_SETS and not name.startswith("_"))]


def checked_hyperparams(algo: str, items: list[str], env_id: str | None = None
                        ) -> dict[str, Any]:
    """``--hyperparams`` (``KEY:VALUE`` items) as a dict, each key one that rl-zoo3 reads or a
    keyword argument of the algorithm's class, each value allowed by its rule in
    :data:`RULES`; with ``env_id``, wrappers are applied to the task's environment too.

    Raises:
        SystemExit: naming ``--hyperparams``, the item, what was wrong and what is allowed.
    """
    values = key_values(items, "--hyperparams", ":", example="learning_rate:3e-4")
    accepted = accepted_keys(algo)
    given = Given(algo, env_id, values)
    for key, value in values.items():
        if key in ZOO_SETS:
            raise SystemExit(f"--hyperparams: {key!r} is set by roller-gym train from its own "
                             "options (--seed, --verbose, --log-folder), not by --hyperparams")
        if key not in accepted:
            raise SystemExit(f"--hyperparams: {key!r} is not a hyperparameter of {algo}; "
                             f"allowed: {', '.join(sorted(accepted))}")
        if key in ("noise_type", "noise_std") and algo == "ppo":
            raise SystemExit(f"--hyperparams: {key} is not allowed: PPO takes no action noise "
                             "(it explores through its policy's own distribution)")
        if key == "ent_coef" and isinstance(value, str) and algo != "sac":
            raise SystemExit(f"--hyperparams: ent_coef:{value!r} is not allowed: 'auto' is "
                             f"SAC's; {algo}'s ent_coef is a number >= 0")
        check, allowed = RULES[key]
        try:
            ok, why = check(value, given), ""
        except ValueError as error:
            ok, why = False, f" ({error})"
        if not ok:
            raise SystemExit(f"--hyperparams: {key}:{value!r} is not allowed: it must be "
                             f"{allowed}{why}")
    return values


def check_together(algo: str, hp: dict[str, Any], observation_size: int) -> None:
    """The checks of the hyperparameters that will train (the file's, then ``--hyperparams``)
    taken together: PPO's samples (a rollout and a minibatch of at least 2), episodic
    training on one environment, and the memory of the buffers (``observation_size``
    numbers per observation, before frame_stack) and of the environments with their share
    of the buffers.

    Raises:
        SystemExit: naming ``--hyperparams``, the values and what is allowed.
    """
    from roller_gym.physics.integrators.layout import check_memory
    from roller_gym.vector_env import BYTES_PER_ENV

    n_envs, stack = int(hp.get("n_envs", 1)), int(hp.get("frame_stack", 1))
    if algo == "ppo":
        rollout = n_envs * int(hp["n_steps"])
        if rollout < 2 or int(hp["batch_size"]) < 2:
            raise SystemExit(f"--hyperparams: n_steps:{hp['n_steps']} x n_envs:{n_envs} and "
                             f"batch_size:{hp['batch_size']} are not allowed: PPO needs a "
                             "rollout of at least 2 steps and minibatches of at least 2")
        entries, batch = rollout, 0
    else:
        freq = hp.get("train_freq", 1)
        if isinstance(freq, tuple | list) and freq[1] == "episode" and n_envs > 1:
            raise SystemExit(f"--hyperparams: train_freq:{freq!r} with n_envs:{n_envs} is not "
                             "allowed: training by episodes takes one environment (n_envs:1)")
        entries, batch = int(hp.get("buffer_size", 1_000_000)), int(hp.get("batch_size", 256))
        if hp.get("optimize_memory_usage") is True and entries // n_envs < 2:
            raise SystemExit(f"--hyperparams: buffer_size:{entries} with n_envs:{n_envs} and "
                             "optimize_memory_usage:True is not allowed: that buffer keeps "
                             "each environment's next observation in the next slot, so it "
                             "needs buffer_size >= 2 x n_envs")
        entries = max(entries // n_envs, 1) * n_envs  # SB3's slots: buffer_size // n_envs x n_envs
    # float32 observations (twice: the next ones too), actions, rewards and flags per entry
    size = 4 * (2 * observation_size * stack + 4)
    try:
        check_memory("--hyperparams buffer_size (or n_steps x n_envs)", entries, size)
        check_memory("--hyperparams batch_size", batch, 2 * size)
        # each environment with its share of the buffers. An environment of training's native
        # batch (from_env_fns, reset and stepped under VecNormalize) measured 4.0-4.2 kB at
        # tracemalloc's peak (1,024 and 4,096 of them), 4.2-5.6 kB of peak RSS (4,096-16,384):
        # BYTES_PER_ENV, no more. A DummyVecEnv's (wrapped environments, dop853) takes 59 kB.
        check_memory("--hyperparams n_envs", n_envs, BYTES_PER_ENV + entries // n_envs * size)
    except ValueError as error:
        raise SystemExit(str(error)) from None


def _real(low: float, high: float, open_low: bool = False) -> Callable[[Any, Given], bool]:
    """Whether a value is a real number in [low, high] ((low, high] with ``open_low``)."""
    return lambda v, _=None: (finite_real(v) and not isinstance(v, bool)
                              and (low < v if open_low else low <= v) and v <= high)


def _integer(low: int, high: int = HYPERPARAM_COUNT_MAX, whole_float: bool = False
             ) -> Callable[[Any, Given], bool]:
    """Whether a value is an integer in [low, high] (a whole float too with ``whole_float``:
    rl-zoo3 rounds n_timesteps)."""
    kinds = int | float if whole_float else int
    return lambda v, _=None: (isinstance(v, kinds) and not isinstance(v, bool) and finite_real(v)
                              and v == int(v) and low <= v <= high)


def _flag(value: Any, _: Given | None = None) -> bool:
    return isinstance(value, bool)


def _train_freq(value: Any, _: Given | None = None) -> bool:
    """Whether ``value`` is SB3's train_freq: an integer >= 1, or (integer, "step"/"episode")
    as a tuple or a list (rl-zoo3's files write both)."""
    if isinstance(value, tuple | list) and len(value) == 2 and value[1] in ("step", "episode"):
        value = value[0]
    return _integer(1)(value)


def _schedule(low: float, high: float = math.inf) -> Callable[[Any, Given], bool]:
    """Whether a value is a number in (low, high], or rl-zoo3's linear schedule
    "lin_<number>" from such a number down to 0."""
    number = _real(low, high, open_low=True)

    def check(value: Any, _: Given | None = None) -> bool:
        if isinstance(value, str) and value.startswith("lin_"):
            try:
                value = float(value[4:])
            except ValueError:
                return False
        return number(value)
    return check


def _ent_coef(value: Any, _: Given | None = None) -> bool:
    """Whether ``value`` is an entropy coefficient: a number >= 0, or SAC's "auto" or
    "auto_<initial value > 0>"."""
    if isinstance(value, str) and value.startswith("auto"):
        if value == "auto":
            return True
        try:
            return value[4] == "_" and _real(0.0, 1e9, open_low=True)(float(value[5:]))
        except (ValueError, IndexError):
            return False
    return _real(0.0, 1e9)(value)


def _target_entropy(value: Any, _: Given | None = None) -> bool:
    return value == "auto" or _real(-1e9, 1e9)(value)


def _evaluated(value: Any) -> Any:
    """A value as rl-zoo3 reads it: a text evaluated as Python in rl-zoo3's own namespace
    (where ``nn``, ``th`` and the SB3 classes are), anything else as it is.

    Raises:
        ValueError: the text does not evaluate.
    """
    if not isinstance(value, str):
        return value
    import rl_zoo3.exp_manager

    try:
        return eval(value, dict(vars(rl_zoo3.exp_manager)))  # (as rl-zoo3 does)
    except Exception as error:
        raise ValueError(f"it does not evaluate: {type(error).__name__}: {error}") from None


def _spaces() -> tuple[Any, Any]:
    """A vector observation and a torque action, as the tasks' (their sizes do not matter to
    what is checked here)."""
    import numpy as np
    from gymnasium import spaces

    return (spaces.Box(-1.0, 1.0, (3,), np.float32), spaces.Box(-1.0, 1.0, (1,), np.float32))


def _built(what: str, build: Callable[[], Any], doing: str = "building") -> Any:
    """``build()``; any error it raises as a ValueError saying what failed in ``doing`` it."""
    try:
        return build()
    except Exception as error:
        raise ValueError(f"{doing} {what} raised {type(error).__name__}: {error}") from None


def _policy_kwargs(value: Any, given: Given) -> bool:
    """Whether the policy's keyword arguments build the algorithm's MlpPolicy."""
    kwargs = _evaluated(value)
    if not isinstance(kwargs, dict):
        return False
    policy = algorithm_class(given.algo).policy_aliases[POLICIES[0]]
    observation, action = _spaces()
    if given.values.get("use_sde") is True:
        kwargs = {"use_sde": True, **kwargs}
    built = _built("the policy", lambda: policy(observation, action, lambda _: 1e-3, **kwargs))
    import torch

    parameters = list(built.parameters())
    if any(p.numel() == 0 for p in parameters):
        raise ValueError("the policy has a layer of no units: it cannot see the observation")
    if not all(bool(torch.isfinite(p).all()) for p in parameters):
        raise ValueError("the policy's initial parameters are not all finite")
    log_std = kwargs.get("log_std_init", 0.0)
    if not _real(-LOG_STD_MAX, LOG_STD_MAX)(log_std):
        raise ValueError(f"log_std_init={log_std!r} must be a number in [-{LOG_STD_MAX:g}, "
                         f"{LOG_STD_MAX:g}] (exp of it, the action noise's scale, overflows "
                         "float32 past about 88)")
    return True


#: The largest |log_std_init| a policy may start from (SAC's own clamp of log σ is [-20, 2]).
LOG_STD_MAX = 20.0


def _replay_buffer(value: Any, given: Given) -> bool:
    """Whether the replay buffer class and its keyword arguments (with optimize_memory_usage)
    build a small buffer for vector observations."""
    from stable_baselines3.common.buffers import DictReplayBuffer, ReplayBuffer

    cls = (_evaluated(given.values["replay_buffer_class"])
           if "replay_buffer_class" in given.values else ReplayBuffer)
    if not (isinstance(cls, type) and issubclass(cls, ReplayBuffer)
            and not issubclass(cls, DictReplayBuffer)):
        raise ValueError("the tasks' observations are vectors: a ReplayBuffer for them")
    kwargs = _evaluated(given.values.get("replay_buffer_kwargs", {}))
    if not isinstance(kwargs, dict):
        raise ValueError("replay_buffer_kwargs must be a dict")
    memory = given.values.get("optimize_memory_usage", False)
    observation, action = _spaces()
    _built(f"{cls.__name__}", lambda: cls(
        8, observation, action, device="cpu", optimize_memory_usage=memory, **kwargs))
    return True


def _normalize(value: Any, _: Given | None = None) -> bool:
    """Whether ``value`` is rl-zoo3's normalize: a bool, or VecNormalize's keyword arguments as
    a dict or its text ("dict(norm_obs=True)", "{'norm_obs': True}"), which rl-zoo3 evaluates."""
    if isinstance(value, bool):
        return True
    if isinstance(value, str):
        try:
            tree = ast.parse(value.strip(), mode="eval").body
            if (isinstance(tree, ast.Call) and isinstance(tree.func, ast.Name)
                    and tree.func.id == "dict" and not tree.args):
                value = {kw.arg: ast.literal_eval(kw.value) for kw in tree.keywords}
            else:
                value = ast.literal_eval(tree)
        except (ValueError, SyntaxError, TypeError):
            return False
    if not isinstance(value, dict):
        return False
    for key, item in value.items():
        rule = NORMALIZE_RULES.get(key)
        if rule is None:
            raise ValueError(f"{key!r} is not an argument of VecNormalize; allowed: "
                             f"{', '.join(NORMALIZE_RULES)}")
        if not rule[0](item):
            raise ValueError(f"its {key}={item!r} must be {rule[1]}")
    return True


#: VecNormalize's keyword arguments (but venv) and what each may be: a wrong one trained on
#: nonsense (clip_obs <= 0 maps every observation to one value) or failed in torch.
NORMALIZE_RULES: dict[str, tuple[Callable[[Any], bool], str]] = {
    "training": (lambda v: isinstance(v, bool), "True or False"),
    "norm_obs": (lambda v: isinstance(v, bool), "True or False"),
    "norm_reward": (lambda v: isinstance(v, bool), "True or False"),
    "clip_obs": (lambda v: _real(0.0, 1e9, open_low=True)(v), "a number > 0"),
    "clip_reward": (lambda v: _real(0.0, 1e9, open_low=True)(v), "a number > 0"),
    "gamma": (lambda v: _real(0.0, 1.0, open_low=True)(v), "a number in (0, 1]"),
    "epsilon": (lambda v: _real(0.0, 1.0, open_low=True)(v), "a number in (0, 1]"),
    "norm_obs_keys": (lambda v: v is None, "None (the observations are vectors)"),
}


def _wrapper(key: str) -> Callable[[Any, Given], bool]:
    """Whether rl-zoo3 finds the wrapper(s) named by ``value`` and, with a task, they wrap
    its environment (an ``env_wrapper``) or a one-environment DummyVecEnv of it, and the
    wrapped environment resets and takes a step (the action halfway between its bounds):
    a wrapper's own arguments (a reward function that is not one) fail only there."""
    def check(value: Any, given: Given) -> bool:
        from rl_zoo3.utils import get_wrapper_class

        wrap = _built("the wrapper", lambda: get_wrapper_class({key: value}, key))
        if wrap is None or given.env_id is None:
            return wrap is not None
        import gymnasium as gym
        import numpy as np
        from stable_baselines3.common.vec_env import DummyVecEnv

        if key == "env_wrapper":
            env = _built("the wrapped environment", lambda: wrap(gym.make(given.env_id)))
        else:
            env = _built("the wrapped vector environment",
                         lambda: wrap(DummyVecEnv([lambda: gym.make(given.env_id)])))
        try:
            spaces = env.observation_space, env.action_space
            if not all(isinstance(s, gym.spaces.Box) for s in spaces) or not (
                    np.all(np.isfinite(spaces[1].low)) and np.all(np.isfinite(spaces[1].high))
                    and spaces[0].shape and np.prod(spaces[0].shape) > 0):
                raise ValueError(f"the wrapped environment's spaces are {spaces[0]} and "
                                 f"{spaces[1]}; the algorithms take non-empty vectors, and "
                                 "actions with finite bounds")
            action = ((spaces[1].low + spaces[1].high) / 2).astype(spaces[1].dtype)
            if key == "env_wrapper":
                _built("the wrapped environment", lambda: (env.reset(seed=0), env.step(action)),
                       doing="stepping")
            else:
                _built("the wrapped vector environment",
                       lambda: (env.reset(), env.step(action[None])), doing="stepping")
        finally:
            env.close()
        return True
    return check


def _callback(value: Any, _: Given | None = None) -> bool:
    """Whether rl-zoo3 makes SB3 callbacks of ``value`` (a class path, a list of them, or
    ``{path: keyword arguments}``)."""
    from rl_zoo3.utils import get_callback_list
    from stable_baselines3.common.callbacks import BaseCallback

    made = _built("the callbacks", lambda: get_callback_list({"callback": value}))
    if not made or not all(isinstance(c, BaseCallback) for c in made):
        return False
    pending = list(made)
    while pending:  # each callback, and those it calls (EveryNTimesteps, CallbackList)
        callback = pending.pop()
        for name in CALLBACK_COUNTS:
            count = getattr(callback, name, 1)
            if not _integer(1)(count):
                raise ValueError(f"{type(callback).__name__}'s {name}={count!r} must be "
                                 f"{_COUNT} (it divides or counts the training's steps)")
        pending += [c for c in (getattr(callback, "callback", None),
                                *getattr(callback, "callbacks", ())) if c is not None]
    return True


def _env_kwargs(value: Any, _: Given | None = None) -> bool:
    """A dict; its values are checked by building the environment with them (train's
    ``check_env_kwargs``)."""
    return isinstance(value, dict)


def _refused(value: Any, _: Given | None = None) -> bool:
    return False


_COUNT = "an integer >= 1 and <= 1e+09"
#: Every hyperparameter ``--hyperparams`` takes, for any algorithm: its rule and what is
#: allowed. A key the algorithm class gains (a new SB3) without a rule here fails the tests.
RULES: dict[str, Rule] = {
    # counts (environments, steps, samples, stacked frames, intervals)
    **{key: (_integer(1), _COUNT) for key in (
        "n_envs", "n_steps", "batch_size", "n_epochs", "buffer_size",
        "target_update_interval", "policy_delay", "stats_window_size")},
    "frame_stack": (_integer(1, FRAME_STACK_MAX), f"an integer >= 1 and <= {FRAME_STACK_MAX}"),
    "n_timesteps": (_integer(1, whole_float=True), _COUNT),
    "learning_starts": (_integer(0), "an integer >= 0 and <= 1e+09"),
    "gradient_steps": (lambda v, _=None: v == -1 or _integer(1)(v),
                       "an integer >= 1 and <= 1e+09, or -1 (as many as environment steps)"),
    "sde_sample_freq": (lambda v, _=None: v == -1 or _integer(1)(v),
                        "an integer >= 1 and <= 1e+09, or -1 (only at a rollout's start)"),
    # numbers and schedules
    "gamma": (_real(0.0, 1.0, open_low=True), "a number in (0, 1]"),
    "tau": (_real(0.0, 1.0, open_low=True), "a number in (0, 1]"),
    "gae_lambda": (_real(0.0, 1.0), "a number in [0, 1]"),
    "learning_rate": (_schedule(0.0, 1.0), "a number in (0, 1], or lin_<number> (from it "
                      "down to 0)"),
    "clip_range": (_schedule(0.0, 1e9), "a number > 0, or lin_<number> (from it down to 0)"),
    "clip_range_vf": (_schedule(0.0, 1e9), "a number > 0, or lin_<number> (from it down to 0); "
                      "leave it out for no clipping of the value function"),
    "ent_coef": (_ent_coef, "a number in [0, 1e9], or for SAC 'auto' or 'auto_<initial "
                 "value in (0, 1e9]>'"),
    "target_entropy": (_target_entropy, "'auto' or a number (nats)"),
    "vf_coef": (_real(0.0, 1e9), "a number >= 0"),
    "max_grad_norm": (_real(0.0, 1e9, open_low=True), "a number > 0"),
    "target_kl": (lambda v, _=None: v is None or _real(0.0, 1e9, open_low=True)(v),
                  "a number > 0, or None (no early stop)"),
    "target_policy_noise": (_real(0.0, 1e9), "a number >= 0 (in action units)"),
    "target_noise_clip": (_real(0.0, 1e9), "a number >= 0 (in action units)"),
    "noise_std": (_real(0.0, 1e9, open_low=True), "a number > 0 (in action units)"),
    # switches and names
    **{key: (_flag, "True or False") for key in (
        "use_sde", "use_sde_at_warmup", "normalize_advantage")},
    "optimize_memory_usage": (lambda v, g: _flag(v) and _replay_buffer(v, g),
                              "True or False (True with replay_buffer_kwargs "
                              "dict(handle_timeout_termination=False))"),
    "train_freq": (_train_freq, "an integer >= 1, or (integer, 'step' or 'episode')"),
    "noise_type": (lambda v, _=None: v in ("normal", "ornstein-uhlenbeck"),
                   "'normal' or 'ornstein-uhlenbeck', with noise_std"),
    "policy": (lambda v, _=None: v in POLICIES,
               f"{' or '.join(POLICIES)}: the tasks' observations are vectors"),
    "action_noise": (_refused, "left out: rl-zoo3 makes it from noise_type and noise_std"),
    # keyword arguments and objects rl-zoo3 makes
    "normalize": (_normalize, "True, False or VecNormalize's keyword arguments (a dict, or its "
                  "text: 'dict(norm_obs=True)')"),
    "env_kwargs": (_env_kwargs, "a dict of the environment's keyword arguments (or use "
                   "--env-kwargs)"),
    "monitor_kwargs": (_refused, "left out: the native batch reports each episode's return, "
                       "length and time as Monitor does, and no info or reset keywords"),
    "policy_kwargs": (_policy_kwargs, "the policy's keyword arguments (a dict, or its text as "
                      "rl-zoo3 evaluates it: 'dict(net_arch=[64, 64], activation_fn=nn.Tanh)')"),
    "replay_buffer_class": (_replay_buffer, "a replay buffer class for vector observations, "
                            "its text as rl-zoo3 evaluates it (where the only one named is "
                            "HerReplayBuffer, for goals: leave it out)"),
    "replay_buffer_kwargs": (_replay_buffer, "the replay buffer's keyword arguments beyond "
                             "those the algorithm passes (a dict, or its text)"),
    "rollout_buffer_class": (_refused, "left out: rl-zoo3 passes it on as text, not a class"),
    "rollout_buffer_kwargs": (lambda v, _=None: v == {}, "{}: PPO passes every argument "
                              "RolloutBuffer takes"),
    "env_wrapper": (_wrapper("env_wrapper"), "a wrapper's import path, a list of them or "
                    "{path: keyword arguments}, that wraps the task's environment"),
    "vec_env_wrapper": (_wrapper("vec_env_wrapper"), "a VecEnvWrapper's import path, a list of "
                        "them or {path: keyword arguments}"),
    "callback": (_callback, "a callback's import path, a list of them or {path: keyword "
                 "arguments}, that rl-zoo3 makes into SB3 callbacks"),
}
