"""Render one episode of a policy to a GIF (or an MP4).

    roller-gym replay runs/sac/roller_gym-RollerStabilize-v2_1   # -> <that folder>/replay.gif
    roller-gym replay runs/sac/roller_gym-RollerHold-v2_1 --seed 3 --out hold.gif
    roller-gym replay classical --env roller_gym/RollerBalance-v2 --out balance.gif

The policy is an experiment folder of ``roller-gym train`` (its saved model, in the
environment it was trained in) or a baseline name (``classical``, ``zero``, ``random``, with
--env). The episode is ``env.reset(seed=--seed)``, as in ``roller-gym evaluate``. GIFs need only
Pillow; an ``.mp4`` needs imageio's ffmpeg plugin (``pip install imageio[ffmpeg]``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import gymnasium as gym
import roller_gym  # registers the tasks
from roller_gym import file_name
from roller_gym.agents.policies import (
    BASELINES,
    baseline,
    evaluation_env,
    load_policy,
    read_config,
    rollout,
)
from roller_gym.scripts.arguments import at_least, output_file, program_parser

#: The files replay writes.
VIDEO_SUFFIXES = (".gif", ".mp4")


def video_file(text: str) -> Path:
    """An argparse ``type``: a path ending in one of :data:`VIDEO_SUFFIXES`."""
    if Path(text).suffix.lower() not in VIDEO_SUFFIXES:
        raise argparse.ArgumentTypeError(f"{text!r} does not end in "
                                         f"{' or '.join(VIDEO_SUFFIXES)}")
    return Path(text)


def build_parser() -> argparse.ArgumentParser:
    p = program_parser("replay", __doc__)
    p.add_argument("policy", help="an experiment folder of roller-gym train, or one of: "
                                  f"{', '.join(BASELINES)}")
    p.add_argument("--env", default=None, choices=roller_gym.ENV_IDS,
                   help="the task (default: the run's; required for a baseline)")
    p.add_argument("--seed", type=at_least(0, 2**64 - 1), default=0,
                   help="the episode's reset seed (default 0)")
    p.add_argument("--out", default=None, type=video_file,
                   help="output .gif or .mp4 (default <run dir>/replay.gif, or "
                        "<policy>-<env>.gif for a baseline)")
    p.add_argument("--best", action="store_true", help="use the run's best_model.zip")
    p.add_argument("--fps", type=at_least(1), default=20,
                   help="frames per second (default 20 = 1/dt)")
    return p


def main(argv: list[str] | None = None) -> None:
    args = build_parser().parse_args(argv)
    import imageio.v2 as imageio  # the render extra: missing, say so before the episode
    import pygame  # noqa: F401

    if args.policy in BASELINES:
        if args.env is None:
            raise SystemExit(f"--env is needed to replay the baseline {args.policy!r}")
        env = gym.make(args.env, render_mode="rgb_array")
        policy = baseline(args.policy, env)
        out = Path(args.out or f"{args.policy}-{file_name(args.env)}.gif")
    else:
        try:
            config = read_config(args.policy)
        except (FileNotFoundError, ValueError) as exc:
            raise SystemExit(f"policy: {exc}; or give one of: {', '.join(BASELINES)}") from None
        if args.env is not None and args.env != config["env"]:
            raise SystemExit(f"{args.policy} was trained on {config['env']}, not {args.env}")
        env = evaluation_env(config["env"], config["env_kwargs"], render_mode="rgb_array")
        policy = load_policy(args.policy, best=args.best)
        out = Path(args.out or Path(args.policy) / "replay.gif")

    output_file(out, "--out")
    episode = rollout(env, policy, seed=args.seed, render=True)
    env.close()
    if out.suffix == ".gif":
        imageio.mimsave(out, episode.frames, duration=1000 / args.fps, loop=0)
    else:
        try:
            imageio.mimsave(out, episode.frames, fps=args.fps)
        except (ImportError, ValueError) as exc:
            raise SystemExit(f"cannot write {out}: {exc}\n(an .mp4 needs "
                             "`pip install imageio[ffmpeg]`; a .gif needs nothing more)") from None
    print(f"{len(episode.frames)} frames, return {episode.total_return:.1f}, success "
          f"{episode.success} -> {out}")


if __name__ == "__main__":
    main()
