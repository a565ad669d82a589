"""Train PPO or SAC on Ray RLlib: the roller-gym tasks, unchanged, on a local Ray or a cluster.

Needs the ``rllib`` extra (its own environment, see README: RLlib pins its Gymnasium)::

    roller-gym train-rllib --algo PPO --env roller_gym/RollerStabilize-v2 --iterations 20
    roller-gym train-rllib --algo SAC --num-env-runners 1 --envs-per-runner 4
    roller-gym train-rllib --env-kwarg dt=0.02 --env-kwarg 'randomize={"m": [0.8, 1.2]}'
    roller-gym train-rllib --address HEAD_IP:6379 --num-env-runners 16   # a cluster

With no ``--address`` a local Ray is started on this machine (all its CPUs, or
``--num-cpus``); with one, the script joins that running cluster (``auto``: the cluster
this node belongs to). Every node of a cluster needs roller-gym and the same extra installed.
Ray's clusters use token authentication by default: to join one, set ``RAY_AUTH_MODE=token``
and give the head's token (``ray get-auth-token`` there) as ``RAY_AUTH_TOKEN``.

Top to bottom: parse the arguments, start or join Ray, register the tasks with Ray's
registry, build the algorithm's configuration, train while printing progress, save a
checkpoint. The environments are made by ``gymnasium.make`` inside the env runners, exactly
as a user makes them; ``--vectorize native`` gives each runner the task's native vector
environment (``gymnasium.make_vec``) instead of Gymnasium's SyncVectorEnv of single ones.
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import os
import sys
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
from roller_gym import ENV_IDS
from roller_gym.extras import install_line
from roller_gym.scripts.arguments import (
    THREADS_MAX,
    at_least,
    checked_env_kwargs,
    program_parser,
    real_in,
)

VECTORIZE_MODES = {"sync": "sync", "async": "async", "native": "vector_entry_point"}


class _DefaultsHelp(argparse.ArgumentDefaultsHelpFormatter):
    """An option's help with its default, unless that is None or empty (its help says what
    then happens)."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        if action.default is None or action.default == []:
            return action.help
        return super()._get_help_string(action)


def build_parser() -> argparse.ArgumentParser:
    p = program_parser("train-rllib", __doc__.split("\n\n")[0], formatter_class=_DefaultsHelp)
    p.add_argument("--algo", choices=["PPO", "SAC"], default="PPO", help="RLlib's algorithm")
    p.add_argument("--env", choices=ENV_IDS, default="roller_gym/RollerStabilize-v2",
                   help="the task")
    p.add_argument("--env-kwarg", action="append", default=[], metavar="KEY=VALUE",
                   help="a keyword argument of gymnasium.make (VALUE is a Python literal if it "
                        "parses, else a string), e.g. dt=0.02, scene=paper; repeat for more")
    p.add_argument("--iterations", type=at_least(1), default=10, help="training iterations")
    p.add_argument("--num-env-runners", type=at_least(0), default=2,
                   help="sampling actors (Ray processes), 1 CPU each; 0 samples in the driver")
    p.add_argument("--envs-per-runner", type=at_least(1), default=1,
                   help="environments each runner steps as one vector")
    p.add_argument("--vectorize", choices=list(VECTORIZE_MODES), default="sync",
                   help="how a runner vectorizes its environments: Gymnasium's sync or async "
                        "vector of single environments, or the task's native vector env")
    p.add_argument("--train-batch-size", type=at_least(1), default=None,
                   help="PPO: env steps per iteration (default 4000); SAC: replay minibatch "
                        "(default 256)")
    p.add_argument("--minibatch-size", type=at_least(1), default=128, help="PPO's SGD minibatch")
    p.add_argument("--num-epochs", type=at_least(1), default=10,
                   help="PPO's epochs over each batch")
    p.add_argument("--lr", type=real_in(0.0, 1.0, open_low=True), default=3e-4,
                   help="the learning rate, in (0, 1]")
    p.add_argument("--gamma", type=real_in(0.0, 1.0), default=0.99,
                   help="the discount factor, in [0, 1]")
    p.add_argument("--hidden", type=at_least(1), nargs="+", default=[64, 64],
                   help="hidden layer sizes of the networks")
    p.add_argument("--address", default=None,
                   help="a running Ray cluster to join (HOST:PORT, 'auto', or ray://HOST:PORT "
                        "with ray[client]); default: start a local Ray on this machine")
    p.add_argument("--num-cpus", type=at_least(1, THREADS_MAX), default=None,
                   help="CPUs of the local Ray (default: all of this machine's)")
    p.add_argument("--checkpoint-dir", type=Path, default=None,
                   help="where to save the checkpoint (default runs/rllib-ALGO-ENV)")
    p.add_argument("--torch-threads", type=at_least(1, THREADS_MAX), default=1,
                   help="torch threads of the learner (in this process); small networks gain "
                        "nothing from more, and on a busy machine more threads are much slower")
    p.add_argument("--seed", type=at_least(0, 2**32 - 1), default=0,
                   help="the seed of training (at most 2**32 - 1, as torch's and NumPy's)")
    return p


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    return build_parser().parse_args(argv)


def make_env(env_id: str, env_config: dict[str, Any]) -> gym.Env | gym.vector.VectorEnv:
    """Ray's env creator: ``gymnasium.make(env_id, **env_config)``, in whatever process runs it.

    ``import roller_gym`` is here, not at the top, so that it runs in each remote env runner (on
    any node): it registers the tasks with Gymnasium in that process. RLlib passes
    ``num_envs`` only with ``--vectorize native`` (its VECTOR_ENTRY_POINT mode).
    """
    import roller_gym  # noqa: F401  (registers the tasks with Gymnasium)

    kwargs = dict(env_config)  # RLlib's EnvContext is a dict: its items are our kwargs
    num_envs = kwargs.pop("num_envs", None)
    if num_envs is None:
        return gym.make(env_id, **kwargs)
    return gym.make_vec(env_id, num_envs=num_envs, vectorization_mode="vector_entry_point",
                        **kwargs)


def register_tasks() -> None:
    """Register every task with Ray's registry (Gymnasium's registry is not Ray's)."""
    from ray import cloudpickle
    from ray.tune.registry import register_env

    if __name__ != "__main__":  # imported (by a test): ship make_env's code, not its name,
        cloudpickle.register_pickle_by_value(sys.modules[__name__])  # to the remote runners
    for env_id in ENV_IDS:
        register_env(env_id, functools.partial(make_env, env_id))


def build_config(args: argparse.Namespace, env_kwargs: dict[str, Any]) -> Any:
    """The AlgorithmConfig (new API stack) of PPO or SAC from the command line."""
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.rllib.algorithms.sac import SACConfig
    from ray.rllib.core.rl_module.default_model_config import DefaultModelConfig

    config = PPOConfig() if args.algo == "PPO" else SACConfig()
    config = (
        config.environment(args.env, env_config=env_kwargs)
        .framework("torch")
        .env_runners(
            num_env_runners=args.num_env_runners,
            num_envs_per_env_runner=args.envs_per_runner,
            gym_env_vectorize_mode=VECTORIZE_MODES[args.vectorize],
            num_cpus_per_env_runner=1,
        )
        .learners(num_learners=0)  # one learner, in the driver process
        .rl_module(model_config=DefaultModelConfig(fcnet_hiddens=list(args.hidden),
                                                   fcnet_activation="tanh"))
        .debugging(seed=args.seed)
    )
    if args.algo == "PPO":
        batch = args.train_batch_size or 4000
        config = config.training(
            train_batch_size_per_learner=batch,
            minibatch_size=min(args.minibatch_size, batch),
            num_epochs=args.num_epochs,
            lr=args.lr,
            gamma=args.gamma,
            lambda_=0.95,
            clip_param=0.2,
        )
    else:
        config = config.training(
            train_batch_size_per_learner=args.train_batch_size or 256,
            actor_lr=args.lr,
            critic_lr=args.lr,
            alpha_lr=args.lr,
            gamma=args.gamma,
            num_steps_sampled_before_learning_starts=1000,
            replay_buffer_config={"type": "PrioritizedEpisodeReplayBuffer",
                                  "capacity": 100_000, "alpha": 0.6, "beta": 0.4},
        ).reporting(min_time_s_per_iteration=0, min_sample_timesteps_per_iteration=1000)
    return config


def progress(result: dict[str, Any], env_steps_before: int) -> tuple[str, int]:
    """One line of progress from ``algo.train()``'s result, and the lifetime env steps."""
    from ray.rllib.utils.metrics import (
        ENV_RUNNER_RESULTS,
        EPISODE_LEN_MEAN,
        EPISODE_RETURN_MEAN,
        NUM_ENV_STEPS_SAMPLED_LIFETIME,
        NUM_EPISODES_LIFETIME,
    )

    runners = result.get(ENV_RUNNER_RESULTS, {})
    env_steps = int(runners.get(NUM_ENV_STEPS_SAMPLED_LIFETIME, 0))
    seconds = float(result.get("time_this_iter_s", math.nan))
    rate = (env_steps - env_steps_before) / seconds if seconds > 0 else math.nan
    line = (f"iter {result['training_iteration']:4d}  "
            f"return {runners.get(EPISODE_RETURN_MEAN, math.nan):8.2f}  "
            f"length {runners.get(EPISODE_LEN_MEAN, math.nan):6.1f}  "
            f"episodes {int(runners.get(NUM_EPISODES_LIFETIME, 0)):6d}  "
            f"env steps {env_steps:8d}  "
            f"time {seconds:6.1f} s  ({rate:7.0f} steps/s)")
    return line, env_steps


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    env_kwargs = checked_env_kwargs(args.env, args.env_kwarg, "--env-kwarg")  # before Ray starts
    try:
        import ray
        import torch
    except ImportError as e:
        raise SystemExit(f"{e}: the rllib extra is not installed; it needs its own "
                         f"environment (see README): {install_line('rllib')}") from None

    torch.set_num_threads(args.torch_threads)  # the env runners get 1 each from Ray
    # Start (no --address) or join (--address) Ray. "local" forces a new local instance
    # even if this machine already runs a cluster started by `ray start`.
    if args.address is None:
        ray.init(address="local", num_cpus=args.num_cpus or os.cpu_count(),
                 include_dashboard=False)
    else:  # a cluster with token authentication (Ray's default) needs RAY_AUTH_MODE=token
        ray.init(address=args.address)
    print(f"Ray: {ray.cluster_resources().get('CPU', 0):.0f} CPUs on "
          f"{len([n for n in ray.nodes() if n['Alive']])} node(s)")

    register_tasks()
    algo = build_config(args, env_kwargs).build_algo()
    print(f"{args.algo} on {args.env}{' ' + json.dumps(env_kwargs) if env_kwargs else ''}: "
          f"{args.num_env_runners} env runner(s) x {args.envs_per_runner} env(s) "
          f"({args.vectorize})")

    env_steps, start = 0, time.perf_counter()
    for _ in range(args.iterations):
        line, env_steps = progress(algo.train(), env_steps)
        print(line, flush=True)
    elapsed = time.perf_counter() - start
    print(f"{args.iterations} iterations, {env_steps} env steps in {elapsed:.1f} s "
          f"({env_steps / elapsed:.0f} env steps/s overall)")

    name = args.env.split("/")[-1]  # the task ID without its namespace
    checkpoint_dir = args.checkpoint_dir or Path("runs") / f"rllib-{args.algo}-{name}"
    saved = algo.save_to_path(str(checkpoint_dir.resolve()))
    print(f"checkpoint: {saved}\n  restore it (tasks registered with Ray first): "
          f"register_tasks(); Algorithm.from_checkpoint({str(saved)!r})")
    algo.stop()
    ray.shutdown()


if __name__ == "__main__":
    main()
