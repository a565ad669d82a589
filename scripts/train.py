"""Train a stable-baselines3 agent (SAC, TD3 or PPO) on a roller-gym task, with rl-zoo3.

    roller-gym train                            # SAC on roller_gym/RollerStabilize-v2
    roller-gym train --algo ppo --env roller_gym/RollerHold-v2
    roller-gym train --algo td3 --env roller_gym/RollerBalance-v2 --steps 50000 --seed 1
    roller-gym train --env-kwargs max_torque=0.6 scene=solid_disc
    roller-gym train --show-command             # the command it runs, and stop
    roller-gym train --algo td3 -- --save-replay-buffer   # after --: rl_zoo3.train's options

A thin front over rl-baselines3-zoo (``python -m rl_zoo3.train``, run on the native batch by
``python -m roller_gym.scripts.zoo_train``, which ``--show-command`` prints): it passes the
hyperparameter file of the algorithm (``roller_gym/agents/hyperparams/<algo>.yml``, default
steps included), ``--gym-packages roller_gym``, a fixed seed, periodic evaluations,
checkpoints, one torch thread and the CPU. rl-zoo3 builds the environments, the callbacks,
the normalization and the action noise, trains, and saves the experiment folder
``<log folder>/<algo>/<env name>_<N>`` (the final model, ``best_model.zip``,
``evaluations.npz``, checkpoints, episode monitors, and in ``<env name>/`` the configuration
it used, ``config.yml``); ``roller-gym evaluate`` and ``roller-gym replay`` read it.
TensorBoard logs go to ``<log folder>/tensorboard``.
"""

from __future__ import annotations

import argparse
import math
import shlex
import sys
from importlib.resources import as_file
from pathlib import Path

import numpy as np
import roller_gym  # registers the tasks
from roller_gym.agents.hyperparams import ALGOS, config_file, hyperparams
from roller_gym.agents.policies import ZOO_HINT, find_run
from roller_gym.scripts import zoo_train
from roller_gym.scripts.arguments import (
    THREADS_MAX,
    at_least,
    check_env_kwargs,
    checked_env_kwargs,
    output_folder,
    program_parser,
)
from roller_gym.scripts.zoo_hyperparams import check_together, checked_hyperparams

#: Algorithms that learn from whole rollouts of n_envs x n_steps environment steps.
ON_POLICY = ("ppo",)


def build_parser() -> argparse.ArgumentParser:
    p = program_parser("train", __doc__)
    p.add_argument("--algo", default="sac", choices=ALGOS, help="the algorithm (default sac)")
    p.add_argument("--env", default="roller_gym/RollerStabilize-v2", choices=roller_gym.ENV_IDS,
                   help="the task (default roller_gym/RollerStabilize-v2)")
    p.add_argument("--steps", type=at_least(1), default=None,
                   help="environment steps, all environments together (default: the "
                        "hyperparameter file's n_timesteps); PPO rounds up to whole rollouts")
    p.add_argument("--seed", type=at_least(0, 2**32 - 1), default=0,
                   help="the seed of training (default 0)")
    p.add_argument("--env-kwargs", nargs="+", default=[], metavar="KEY=VALUE",
                   help="keyword arguments of gymnasium.make, e.g. max_torque=0.6 scene=floor "
                        "(values are Python literals, else strings)")
    p.add_argument("--hyperparams", nargs="+", default=[], metavar="KEY:VALUE",
                   help="override entries of the hyperparameter file, e.g. learning_rate:3e-4 "
                        "n_envs:2 learning_rate:lin_3e-4 (values are Python literals, else "
                        "strings, as in the file)")
    p.add_argument("--log-folder", default="runs",
                   help="rl-zoo3's log folder: the run goes to <log folder>/<algo>/<env name>_<N> "
                        "(default runs)")
    p.add_argument("--eval-freq", type=at_least(1), default=None,
                   help="evaluate every this many steps (default: the run's steps / 20)")
    p.add_argument("--eval-episodes", type=at_least(1), default=10,
                   help="episodes per periodic evaluation (default 10)")
    p.add_argument("--checkpoints", type=at_least(0), default=5,
                   help="number of checkpoints over the run (default 5; 0: none)")
    p.add_argument("--threads", type=at_least(1, THREADS_MAX), default=1,
                   help="torch threads (default 1: small networks gain nothing from more)")
    p.add_argument("--verbose", type=int, default=1, choices=(0, 1, 2),
                   help="rl-zoo3's and stable-baselines3's output (0: none, 1: progress "
                        "tables, default; 2: debug)")
    p.add_argument("--progress", action="store_true", help="show a progress bar")
    p.add_argument("--show-command", action="store_true",
                   help="print the command this would run, and stop: python -m "
                        "roller_gym.scripts.zoo_train with rl_zoo3.train's options (python -m "
                        "rl_zoo3.train with the same options steps single environments through "
                        "DummyVecEnv instead of the native batch)")
    p.add_argument("zoo_args", nargs="*", metavar="-- OPTION",
                   help="after --: further options of python -m rl_zoo3.train, passed as they "
                        "are (python -m rl_zoo3.train --help lists them)")
    return p


def zoo_arguments(args: argparse.Namespace, conf: str) -> list[str]:
    """The arguments of ``python -m rl_zoo3.train`` for ``args``, with the hyperparameter
    file ``conf``; ``--hyperparams`` and ``--env-kwargs`` checked first (SystemExit naming
    the option)."""
    given = checked_hyperparams(args.algo, args.hyperparams, args.env)
    hp = {**hyperparams(args.algo, args.env), **given}
    check_together(args.algo, hp, _observation_size(args.env))
    if "noise_type" in hp and "noise_std" not in hp:
        raise SystemExit("--hyperparams: noise_type needs noise_std (its standard deviation in "
                         "action units), e.g. noise_std:0.1")
    steps = int(args.steps or hp["n_timesteps"])
    if args.algo in ON_POLICY:
        # rl-zoo3's linear schedules go negative past the end: never overshoot the steps.
        rollout = int(hp["n_envs"]) * int(hp["n_steps"])
        steps = rollout * math.ceil(steps / rollout)
    if args.checkpoints > steps:  # a checkpoint every steps // checkpoints = 0 steps: none
        raise SystemExit(f"--checkpoints {args.checkpoints}: more checkpoints than the run's "
                         f"{steps} steps; give at most {steps} (0: none)")
    out = [
        "--algo", args.algo, "--env", args.env, "--gym-packages", "roller_gym",
        "-conf", conf, "--seed", str(args.seed), "--device", "cpu",
        "--num-threads", str(args.threads), "--log-folder", args.log_folder,
        "--tensorboard-log", str(Path(args.log_folder) / "tensorboard"),
        "--eval-freq", str(args.eval_freq or max(steps // 20, 1)),
        "--eval-episodes", str(args.eval_episodes),
        "--save-freq", str(steps // args.checkpoints if args.checkpoints > 0 else -1),
        "--verbose", str(args.verbose),
    ]
    if args.steps is not None or steps != int(hp["n_timesteps"]):
        out += ["--n-timesteps", str(steps)]
    # checked by building the environment once, before rl-zoo3 starts
    env_kwargs = checked_env_kwargs(args.env, args.env_kwargs, "--env-kwargs")
    if env_kwargs:  # rl-zoo3 evaluates each value as Python: pass its repr
        out += ["--env-kwargs", *(f"{k}:{v!r}" for k, v in env_kwargs.items())]
    if "env_kwargs" in hp:  # from --hyperparams: checked as --env-kwargs are
        check_env_kwargs(args.env, {**hp["env_kwargs"], **env_kwargs}, "--hyperparams env_kwargs")
    if given:  # as --env-kwargs: the values checked, as their repr (a string stays a string)
        out += ["--hyperparams", *(f"{k}:{v!r}" for k, v in given.items())]
    if args.progress:
        out.append("--progress")
    own = sorted({a.split("=")[0] for a in args.zoo_args} & set(OWN_OPTIONS))
    if own:
        raise SystemExit(f"after --: {', '.join(own)} are set by roller-gym train from its own "
                         "options (give them before --: --env, --algo, --seed, ...)")
    return out + list(args.zoo_args)


def _observation_size(env_id: str) -> int:
    """How many numbers a task's observation holds."""
    import gymnasium as gym

    env = gym.make(env_id)
    env.close()
    return int(np.prod(env.observation_space.shape))


#: rl_zoo3.train's options that roller-gym train sets itself (not to be given after --).
OWN_OPTIONS = ("--algo", "--env", "--gym-packages", "-conf", "--conf-file", "--seed", "--device",
               "--num-threads", "-f", "--log-folder", "-tb", "--tensorboard-log", "--eval-freq",
               "--eval-episodes", "--save-freq", "--verbose", "-n", "--n-timesteps",
               "--env-kwargs", "--hyperparams", "-params")


def main(argv: list[str] | None = None) -> Path | None:
    """Train with rl-zoo3; return the experiment folder (None with ``--show-command``)."""
    args = build_parser().parse_args(argv)
    try:
        import rl_zoo3.train  # noqa: F401
    except ImportError:
        raise SystemExit(f"roller-gym train runs rl-zoo3, which is not installed: "
                         f"{ZOO_HINT}") from None
    with as_file(config_file(args.algo)) as conf:
        zoo_argv = zoo_arguments(args, str(conf))
        if args.show_command:
            print(shlex.join([sys.executable, "-m", zoo_train.MODULE, *zoo_argv]))
            return None
        output_folder(args.log_folder, "--log-folder")
        zoo_train.train(zoo_argv)
    run_dir = find_run(args.log_folder, args.algo, args.env)
    print(f"\nrun saved in {run_dir}; evaluate it against the baselines with\n"
          f"  roller-gym evaluate --env {args.env} --models {run_dir}")
    return run_dir


if __name__ == "__main__":
    main()
