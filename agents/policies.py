"""Loading policies and playing episodes: the one evaluation path every policy shares.

A *policy* is anything with stable-baselines3's ``predict(observation, deterministic=True)
-> (action, state)``: a trained model (:class:`TrainedPolicy`, which applies the saved
observation normalization), or a controller of :mod:`roller_gym.agents.classical`.

A training run (``roller-gym train``, or ``python -m rl_zoo3.train`` with the same
hyperparameter files) is an rl-zoo3 experiment folder::

    runs/<algo>/<env name>_<N>/          (env name: the task ID with "/" -> "-")
        <env name>.zip                   the final model
        best_model.zip                   the best model of the periodic evaluations
        evaluations.npz                  the periodic evaluations (the learning curve)
        rl_model_<steps>_steps.zip       checkpoints
        batch.monitor.csv                the training episodes (of the native batch;
                                         0.monitor.csv, ... over DummyVecEnv)
        <env name>/config.yml            the hyperparameters the run used
        <env name>/args.yml              the command-line arguments (algo, env, seed, ...)
        <env name>/vecnormalize.pkl      the normalization statistics (if the run normalized)

:func:`find_run` picks the latest experiment of an (algorithm, task) in a log folder, as
rl-zoo3's ``enjoy`` does; :func:`read_config` and :func:`load_policy` read one.
"""

from __future__ import annotations

import csv
import json
import pickle
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from roller_gym.agents.classical import (
    Controller,
    Informed,
    RandomPolicy,
    ZeroTorque,
    controller_for,
)
from roller_gym.agents.hyperparams import CLASSICAL
from roller_gym.extras import install_line, missing
from roller_gym.physics.scene import shown
from roller_gym.task import get_task

__all__ = [
    "BASELINES",
    "Episode",
    "Policy",
    "TrainedPolicy",
    "algorithm_class",
    "baseline",
    "baselines_for",
    "evaluation_env",
    "find_run",
    "load_policy",
    "read_config",
    "rollout",
]

#: The baselines of the results table, by name ("informed" only where the task's scene
#: varies unobserved: :func:`baselines_for`).
BASELINES = ("classical", "zero", "random", "informed")


def baselines_for(env_id: str) -> tuple[str, ...]:
    """The baselines a task is compared with: the classical controller, zero torque and
    random actions, and where the task draws its scene per episode unobserved
    (``Task.scene_ranges``) the classical controller informed of each episode's scene."""
    varies = get_task(env_id).scene_ranges is not None
    return tuple(b for b in BASELINES if b != "informed" or varies)

Policy = Any  # anything with predict(observation, deterministic=True) -> (action, state)


#: How to get the packages that train and read training runs.
ZOO_HINT = install_line("zoo") + " (in a clone of the repository)"

# Reading a run needs PyYAML and stable-baselines3, not rl-zoo3 itself: importing rl_zoo3
# replaces Gymnasium's TimeLimit wrapper for the whole process (rl_zoo3.gym_patches), which a
# library function must not do to its caller.


#: Saved objects a policy that only acts does not need, replaced at loading (as rl-zoo3's
#: enjoy script does): rl-zoo3's schedules are pickled objects of rl_zoo3, which unpickling
#: would import.
ACTING_ONLY: dict[str, Any] = {
    "learning_rate": 0.0,
    "lr_schedule": lambda _: 0.0,
    "clip_range": lambda _: 0.0,
}


def algorithm_class(algo: str) -> type:
    """The stable-baselines3 class of ``"sac"``, ``"td3"`` or ``"ppo"``."""
    from stable_baselines3 import PPO, SAC, TD3

    classes = {"sac": SAC, "td3": TD3, "ppo": PPO}
    if algo.lower() not in classes:
        raise ValueError(f"algo={shown(algo)} is not one of {', '.join(classes)}")
    return classes[algo.lower()]


def _read_yaml(path: Path) -> Any:
    """A YAML file rl-zoo3 wrote. It dumps OrderedDicts (python/object tags) and reads them
    back with the unsafe loader; so do we, on the user's own run folder."""
    try:
        import yaml
    except ImportError:
        raise missing("yaml", "zoo", "reading training runs") from None
    with path.open() as f:
        try:
            return yaml.load(f, Loader=yaml.UnsafeLoader)
        except yaml.YAMLError as error:
            raise ValueError(f"{path} is not a YAML file rl-zoo3 wrote: {error}") from None


def find_run(log_folder: str | Path, algo: str, env_id: str) -> Path | None:
    """The latest rl-zoo3 experiment ``<log_folder>/<algo>/<env name>_<N>`` of ``algo`` on
    ``env_id`` (the largest N whose ``args.yml`` names ``env_id``), or None if there is none."""
    found = []
    for args_file in Path(log_folder, algo.lower()).glob("*_*/*/args.yml"):
        run_dir = args_file.parent.parent
        run_id = run_dir.name.rpartition("_")[2]
        if run_id.isdigit() and _read_yaml(args_file)["env"] == env_id:
            found.append((int(run_id), run_dir))
    return max(found)[1] if found else None


def _monitor_wall_time(run_dir: Path) -> float | None:
    """Seconds from the first monitor's start to the last episode's end over the episode
    monitors (stable-baselines3's ``*.monitor.csv``) of ``run_dir``; None if no episode ended."""
    from stable_baselines3.common.monitor import get_monitor_files

    starts, ends = [], []
    for name in get_monitor_files(str(run_dir)):
        with open(name) as f:
            t_start = float(json.loads(f.readline().lstrip("#"))["t_start"])
            rows = list(csv.DictReader(f))
        starts.append(t_start)
        if rows:
            ends.append(t_start + float(rows[-1]["t"]))
    return max(ends) - min(starts) if ends else None


def read_config(run_dir: str | Path) -> dict[str, Any]:
    """What produced the training run in ``run_dir`` (an rl-zoo3 experiment folder).

    Returns:
        ``algo``, ``env`` (the task ID), ``env_kwargs``, ``seed``, ``hyperparams`` (rl-zoo3's
        ``config.yml``: the hyperparameters as used), ``model`` (the final model's path),
        ``params_dir`` (where ``config.yml`` lies), ``trained_steps`` (environment steps the
        final model was trained for), ``wall_time_s`` (seconds from the creation of the
        training environments to the end of the last training episode; None if no episode
        ended).

    Raises:
        FileNotFoundError: ``run_dir`` holds no ``*/args.yml`` (not an rl-zoo3 experiment).
    """
    from stable_baselines3.common.save_util import load_from_zip_file

    run_dir = Path(run_dir)
    found = sorted(run_dir.glob("*/args.yml"))
    if not found:
        raise FileNotFoundError(
            f"run_dir={shown(str(run_dir))} holds no <env name>/args.yml: it is not an experiment "
            "folder of roller-gym train / rl_zoo3.train (they look like runs/sac/"
            "roller_gym-RollerStabilize-v2_1)")
    params_dir = found[0].parent
    hyperparams = dict(_read_yaml(params_dir / "config.yml"))
    args = _read_yaml(found[0])
    model = run_dir / f"{params_dir.name}.zip"
    data, _, _ = load_from_zip_file(model, device="cpu", load_data=True,
                                    custom_objects=ACTING_ONLY)
    wall_time = _monitor_wall_time(run_dir)
    return {
        "algo": args["algo"],
        "env": args["env"],
        # As rl-zoo3 decides: the hyperparameters' env_kwargs, else the command line's.
        "env_kwargs": dict(hyperparams.get("env_kwargs") or args.get("env_kwargs") or {}),
        "seed": args["seed"],
        "hyperparams": hyperparams,
        "model": str(model),
        "params_dir": str(params_dir),
        "trained_steps": int(data["num_timesteps"]),
        "wall_time_s": wall_time,
    }


class TrainedPolicy:
    """A saved stable-baselines3 model with the observation normalization and the frame
    stacking it was trained with (rl-zoo3's ``normalize`` and ``frame_stack``: normalized,
    then stacked as ``VecFrameStack`` stacks, the newest frame last and zeros before an
    episode's first).

    Args:
        model: the loaded model (``SAC.load(...)`` etc.).
        normalizer: the saved ``VecNormalize`` (its statistics only), or None.
        config: the run's configuration (:func:`read_config`); its hyperparameters'
            ``frame_stack`` sets the frames stacked.
    """

    def __init__(self, model: Any, normalizer: Any = None,
                 config: dict[str, Any] | None = None) -> None:
        self.model, self.normalizer, self.config = model, normalizer, dict(config or {})
        self.frames = int(self.config.get("hyperparams", {}).get("frame_stack") or 1)
        self._stack: np.ndarray | None = None

    def predict(
        self,
        observation: np.ndarray,
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        """As ``model.predict``, on observations normalized and stacked as in training: pass
        ``episode_start`` (True at an episode's first observation) where frames are stacked."""
        observation = np.asarray(observation)
        if self.normalizer is not None:
            observation = self.normalizer.normalize_obs(observation)
        if self.frames > 1:
            observation = self._stacked(observation, episode_start)
        return self.model.predict(observation, state, episode_start, deterministic)

    def _stacked(self, observation: np.ndarray, episode_start: np.ndarray | None) -> np.ndarray:
        size = observation.shape[-1]
        batch = observation.reshape(-1, size)
        if self._stack is None:
            starts = np.ones(len(batch), bool)
        elif episode_start is None:
            starts = np.zeros(len(batch), bool)
        else:
            starts = np.asarray(episode_start, bool).reshape(-1)
        if self._stack is None or self._stack.shape[0] != len(batch):
            self._stack = np.zeros((len(batch), size * self.frames), batch.dtype)
        self._stack = np.roll(self._stack, -size, axis=1)
        self._stack[starts] = 0.0
        self._stack[:, -size:] = batch
        return self._stack.reshape(*observation.shape[:-1], size * self.frames).copy()


def load_policy(run_dir: str | Path, best: bool = False, device: str = "cpu") -> TrainedPolicy:
    """Load the model a training run saved (and its normalization statistics), to act: its
    learning-rate and clipping schedules are not restored (:data:`ACTING_ONLY`).

    Args:
        run_dir: the rl-zoo3 experiment folder (see :func:`read_config`).
        best: load ``best_model.zip`` (the best periodic evaluation) instead of the final
            model.
        device: the torch device.
    """
    run_dir = Path(run_dir)
    config = read_config(run_dir)
    path = run_dir / "best_model.zip" if best else Path(config["model"])
    model = algorithm_class(config["algo"]).load(path, device=device,
                                                 custom_objects=ACTING_ONLY)
    normalizer = None
    stats = Path(config["params_dir"]) / "vecnormalize.pkl"
    if stats.is_file():
        with stats.open("rb") as f:
            normalizer = pickle.load(f)  # VecNormalize without its venv: statistics only
        normalizer.training = False
    return TrainedPolicy(model, normalizer, config)


def baseline(name: str, env: gym.Env, seed: int = 0) -> Controller:
    """A baseline policy for ``env``.

    Args:
        name: ``"classical"`` (LQR on Stabilize and Hold, the energy swing-up on Balance,
            with the settings of :data:`roller_gym.agents.hyperparams.CLASSICAL`, designed on
            the environment's nominal scene), ``"informed"`` (the same, designed anew on each
            episode's true scene: :class:`roller_gym.agents.classical.Informed`), ``"zero"``
            (no torque) or ``"random"`` (uniform actions).
        env: the environment the policy will act in (its scene, torque limit and dt).
        seed: the seed of the random policy.
    """
    if name in ("classical", "informed"):
        spec_id = env.spec.id if env.spec is not None else None
        weights = CLASSICAL.get(spec_id, {})
        return controller_for(env, **weights) if name == "classical" else Informed(env,
                                                                                   **weights)
    if name == "zero":
        return ZeroTorque()
    if name == "random":
        return RandomPolicy(seed)
    raise ValueError(f"baseline {shown(name)} is not one of {', '.join(BASELINES)}")


#: The info keys :func:`rollout` reads at every step.
ROLLOUT_INFO_KEYS = ("phi", "phi_dot", "position_error", "torque", "is_success", "target_phi")


def evaluation_env(env_id: str, env_kwargs: dict[str, Any], **kwargs: Any) -> gym.Env:
    """The environment a training run is evaluated or replayed in: ``gymnasium.make(env_id)``
    with the run's ``env_kwargs`` (and ``kwargs``, e.g. ``render_mode``), and every info key.
    A run may have trained with fewer (``info_keys``, to step faster); :func:`rollout` reads
    the state from the info."""
    kept = {k: v for k, v in env_kwargs.items() if k != "info_keys"}
    return gym.make(env_id, **kept, **kwargs)


@dataclass(frozen=True)
class Episode:
    """One episode, step by step (arrays over the steps, t = dt, 2 dt, ...).

    Attributes:
        time: time [s] at the end of each step.
        phi, phi_dot: the state [rad, rad/s] after each step.
        error: the task's position error [rad] after each step.
        torque: the torque applied during each step [N·m].
        reward: the reward of each step.
        total_return: the sum of the rewards.
        success: ``info["is_success"]`` at the last step.
        terminated: whether the episode ended early (slip, lift-off, non-finite).
        target_phi: the episode's target rest position φ* [rad] (Balance: φ_b; −φ_b
            counts as well).
        frames: rendered frames (only with ``render=True``).
    """

    time: np.ndarray
    phi: np.ndarray
    phi_dot: np.ndarray
    error: np.ndarray
    torque: np.ndarray
    reward: np.ndarray
    total_return: float
    success: bool
    terminated: bool
    target_phi: float
    frames: list[np.ndarray] | None = None


def rollout(env: gym.Env, policy: Policy, seed: int, render: bool = False) -> Episode:
    """Play one episode of ``policy`` in ``env`` from ``env.reset(seed=seed)``.

    Args:
        env: a roller environment (``gymnasium.make(ID, ...)``; ``render_mode="rgb_array"``
            to collect frames).
        policy: anything with ``predict(observation, deterministic=True)``.
        seed: the reset seed (the same seed gives the same start state and target).
        render: collect ``env.render()`` frames (the first before the first step).

    Raises:
        ValueError: ``env`` was made without an info key of :data:`ROLLOUT_INFO_KEYS`
            (``info_keys``); :func:`evaluation_env` makes a run's environment with all.
    """
    chosen = env.unwrapped.config.info_keys
    missing = [key for key in ROLLOUT_INFO_KEYS if key not in chosen]
    if missing:
        raise ValueError(f"env: rollout reads the info keys {', '.join(missing)}, which env "
                         f"was made without (info_keys={list(chosen)}); make it with every "
                         "key (leave info_keys out) or with these added")
    obs, info = env.reset(seed=seed)
    frames = [env.render()] if render else None
    rows: list[tuple[float, ...]] = []
    dt = float(env.unwrapped.config.dt)
    done = terminated = False
    state, start = None, np.array([True])  # a recurrent policy's state; the episode's start
    while not done:
        action, state = policy.predict(obs, state, episode_start=start, deterministic=True)
        start = np.array([False])
        obs, reward, terminated, truncated, info = env.step(action)
        done = terminated or truncated
        rows.append((info["phi"], info["phi_dot"], info["position_error"], info["torque"],
                     float(reward)))
        if render:
            frames.append(env.render())
    data = np.array(rows, dtype=float).T
    return Episode(
        time=dt * np.arange(1, data.shape[1] + 1),
        phi=data[0], phi_dot=data[1], error=data[2], torque=data[3], reward=data[4],
        total_return=float(data[4].sum()), success=bool(info["is_success"]),
        terminated=bool(terminated), target_phi=float(info["target_phi"]), frames=frames,
    )
