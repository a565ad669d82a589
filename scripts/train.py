"""Train a stable-baselines3 agent (SAC, TD3 or PPO) on a roller-gym task.

    python scripts/train.py                     # SAC on roller_gym/RollerStabilize-v0
    python scripts/train.py --algo ppo --env roller_gym/RollerHold-v0
    python scripts/train.py --algo td3 --env roller_gym/RollerBalance-v0 --steps 50000 --seed 1
    python scripts/train.py --env-kwargs max_torque=0.6 scene=solid_disc

The hyperparameters, default steps included, come from ``agents/hyperparams.py``. The run
directory (default ``runs/<algo>-<env>``) receives the final model (``model.zip``), the
configuration that produced it (``config.json``), the periodic evaluations
(``evaluations.npz``, the learning curve; ``best_model.zip``), checkpoints, the episode
monitor logs, the normalization statistics if any, and TensorBoard logs
(``tensorboard --logdir runs``). ``scripts/evaluate.py`` reads it.
"""

from __future__ import annotations

import argparse
import ast
import json
import platform
import shutil
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import roller_gym  # registers the tasks
import stable_baselines3
import torch
from roller_gym import file_name
from roller_gym.agents.hyperparams import ALGOS, hyperparams
from roller_gym.agents.policies import algorithm_class
from stable_baselines3.common.callbacks import CheckpointCallback, EvalCallback
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.noise import NormalActionNoise
from stable_baselines3.common.vec_env import VecNormalize

#: The entries of the hyperparameters this script reads; the rest go to the algorithm.
SCRIPT_KEYS = ("total_steps", "n_envs", "normalize", "action_noise_std")


def parse_env_kwargs(items: list[str]) -> dict[str, Any]:
    """``["max_torque=0.6", "scene=floor"]`` -> ``{"max_torque": 0.6, "scene": "floor"}``
    (values are Python literals where they parse as one, else strings)."""
    out = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise SystemExit(f"--env-kwargs: {item!r} is not key=value")
        try:
            out[key] = ast.literal_eval(value)
        except (ValueError, SyntaxError):
            out[key] = value
    return out


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--algo", default="sac", choices=ALGOS, help="the algorithm (default sac)")
    p.add_argument("--env", default="roller_gym/RollerStabilize-v0", choices=roller_gym.ENV_IDS,
                   help="the task (default roller_gym/RollerStabilize-v0)")
    p.add_argument("--steps", type=int, default=None,
                   help="environment steps (default: the hyperparameters' total_steps)")
    p.add_argument("--seed", type=int, default=0, help="the seed of training (default 0)")
    p.add_argument("--n-envs", type=int, default=None,
                   help="parallel environments (default: the hyperparameters')")
    p.add_argument("--env-kwargs", nargs="*", default=[], metavar="KEY=VALUE",
                   help="keyword arguments of gymnasium.make, e.g. max_torque=0.6 scene=floor")
    p.add_argument("--run-dir", default=None, help="output directory (default runs/<algo>-<env>)")
    p.add_argument("--eval-freq", type=int, default=None,
                   help="evaluate every this many steps (default: total steps / 20)")
    p.add_argument("--eval-episodes", type=int, default=10,
                   help="episodes per periodic evaluation (default 10)")
    p.add_argument("--checkpoints", type=int, default=5,
                   help="number of checkpoints over the run (default 5; 0: none)")
    p.add_argument("--threads", type=int, default=1,
                   help="torch threads (default 1: small networks gain nothing from more)")
    p.add_argument("--no-progress-bar", action="store_true", help="no progress bar")
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> tuple[Path, Any]:
    """Train, save and return (the run directory, the trained model)."""
    args = parse_args(argv)
    # -- configuration ------------------------------------------------------------------
    hp = hyperparams(args.algo, args.env)
    total_steps = int(args.steps or hp["total_steps"])
    n_envs = int(args.n_envs or hp["n_envs"])
    normalize, noise_std = hp["normalize"], hp.get("action_noise_std")
    algo_kwargs = {k: v for k, v in hp.items() if k not in SCRIPT_KEYS}
    env_kwargs = parse_env_kwargs(args.env_kwargs)
    run_dir = Path(args.run_dir or f"runs/{args.algo}-{file_name(args.env)}")
    if run_dir.exists():  # a fresh run: never mix the logs of two runs
        shutil.rmtree(run_dir)
    run_dir.mkdir(parents=True)
    torch.set_num_threads(args.threads)
    eval_freq = args.eval_freq or max(total_steps // 20, 1)
    print(f"training {args.algo.upper()} on {args.env} for {total_steps} steps "
          f"({n_envs} env(s), seed {args.seed}) -> {run_dir}")

    # -- environments: training (with episode monitors) and periodic evaluation ---------
    env = make_vec_env(args.env, n_envs=n_envs, seed=args.seed, env_kwargs=env_kwargs,
                       monitor_dir=str(run_dir / "monitor"))
    eval_env = make_vec_env(args.env, n_envs=1, seed=args.seed + 10_000, env_kwargs=env_kwargs)
    if normalize:
        env = VecNormalize(env, **normalize)
        eval_env = VecNormalize(eval_env, training=False, norm_reward=False,
                                **{k: v for k, v in normalize.items() if k != "norm_reward"})

    # -- the model -------------------------------------------------------------------------
    if noise_std is not None:  # TD3 explores with Gaussian noise on its actions
        algo_kwargs["action_noise"] = NormalActionNoise(np.zeros(1), noise_std * np.ones(1))
    model = algorithm_class(args.algo)(
        "MlpPolicy", env, seed=args.seed, verbose=0, device="cpu",
        tensorboard_log=str(run_dir / "tb"), **algo_kwargs,
    )

    # -- training, with periodic evaluation and checkpoints ------------------------------
    callbacks = [EvalCallback(
        eval_env, n_eval_episodes=args.eval_episodes, eval_freq=max(eval_freq // n_envs, 1),
        log_path=str(run_dir), best_model_save_path=str(run_dir), deterministic=True,
        verbose=0,
    )]
    if args.checkpoints > 0:
        callbacks.append(CheckpointCallback(
            save_freq=max(total_steps // args.checkpoints // n_envs, 1),
            save_path=str(run_dir / "checkpoints"), name_prefix="model",
            save_vecnormalize=bool(normalize),
        ))
    start = time.perf_counter()
    model.learn(total_steps, callback=callbacks, progress_bar=not args.no_progress_bar,
                tb_log_name=args.algo)
    wall_time = time.perf_counter() - start

    # -- save the model with the configuration that produced it ---------------------------
    model.save(run_dir / "model.zip")
    if normalize:
        env.save(str(run_dir / "vecnormalize.pkl"))
    evaluations = np.load(run_dir / "evaluations.npz")
    config = {
        "algo": args.algo,
        "env": args.env,
        "env_kwargs": env_kwargs,
        "seed": args.seed,
        "total_steps": total_steps,
        "trained_steps": int(model.num_timesteps),
        "n_envs": n_envs,
        "normalize": normalize,
        "action_noise_std": noise_std,
        "hyperparams": {k: v for k, v in algo_kwargs.items() if k != "action_noise"},
        "wall_time_s": round(wall_time, 1),
        "final_eval_return": float(evaluations["results"][-1].mean()),
        "command": " ".join(["python", "scripts/train.py", *(sys.argv[1:] if argv is None
                                                              else argv)]),
        "versions": {
            "python": platform.python_version(),
            "stable_baselines3": stable_baselines3.__version__,
            "torch": torch.__version__,
        },
        "cpu": platform.processor() or platform.machine(),
    }
    (run_dir / "config.json").write_text(json.dumps(config, indent=2, default=repr) + "\n")
    env.close()
    eval_env.close()
    print(f"done in {wall_time:.0f} s; last evaluation: mean return "
          f"{config['final_eval_return']:.1f}; saved {run_dir / 'model.zip'}")
    return run_dir, model


if __name__ == "__main__":
    main()
