"""The ``roller-gym`` command: one subcommand per program of ``roller_gym.scripts``.

    roller-gym train [options]        train SAC, TD3 or PPO with rl-zoo3
    roller-gym evaluate [options]     trained agents against the classical baselines
    roller-gym replay RUN [options]   one episode to a GIF
    roller-gym benchmark [options]    speed against accuracy, peers in the same run (--render:
                                      the page again from its results file)
    roller-gym train-rllib [options]  PPO or SAC on Ray RLlib
    roller-gym COMMAND --help         the options of a command, and the extra it needs
    roller-gym --version              the installed version

Each subcommand runs ``roller_gym.scripts.<program>.main`` with the remaining arguments, so
``roller-gym train --algo td3`` and ``python -m roller_gym.scripts.train --algo td3`` are
the same. A program is imported only when its command runs, and imports the packages of its
extra only after parsing its arguments: every ``--help`` works with the base install and
names the extra (:func:`extra_note`), and a command whose extra is not installed says in one
line which one to install.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence
from typing import NamedTuple

from roller_gym import extras


class Command(NamedTuple):
    """A subcommand: its module in ``roller_gym.scripts``, what it does, and the extra that
    installs what it needs."""

    module: str
    summary: str
    extra: str


COMMANDS: dict[str, Command] = {
    "train": Command("train", "train SAC, TD3 or PPO on a task with rl-zoo3", "zoo"),
    "evaluate": Command("evaluate", "evaluate trained agents and the classical baselines; "
                        "tables and plots", "zoo,plots"),
    "results": Command("results", "evaluate every training seed, aggregate with rliable, "
                       "write the results page", "results"),
    "replay": Command("replay", "render one episode of a policy to a GIF or MP4",
                      "zoo,render"),
    "benchmark": Command("benchmark", "speed against accuracy: integrators, MuJoCo, "
                         "throughput; --render redraws docs/BENCHMARKS.md from its results",
                         "bench,plots"),
    "train-rllib": Command("train_rllib", "train PPO or SAC on Ray RLlib (its own "
                           "environment)", "rllib"),
}


def extra_note(name: str) -> str:
    """The lines a command's ``--help`` ends with: the extra it needs, how to install it and
    what it adds."""
    extra = COMMANDS[name].extra
    packages = extras.packages(extra)
    adds = f"\n  (it adds {', '.join(packages)})" if packages else ""
    return (f"roller-gym {name} needs the extra [{extra}]; in a clone of the repository: "
            f"{extras.install_line(extra)}{adds}")


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser: the command's name only (its options are the program's)."""
    from roller_gym import __version__

    width, extra_width = max(map(len, COMMANDS)), max(len(c.extra) for c in COMMANDS.values())
    listing = "\n".join(f"  {name:{width}s}  {f'[{c.extra}]':{extra_width + 2}s}  {c.summary}"
                        for name, c in COMMANDS.items())
    p = argparse.ArgumentParser(
        prog="roller-gym",
        description="roller-gym's programs: training, evaluation, replay, benchmark.",
        epilog=f"commands (and the extra each needs):\n{listing}\n\n"
               "`roller-gym COMMAND --help` lists a command's options "
               f"(it works without the command's extra); in a clone of the repository, "
               f"{extras.install_line('EXTRA')} installs an extra.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    p.add_argument("command", choices=list(COMMANDS), metavar="COMMAND",
                   help=f"one of: {', '.join(COMMANDS)}")
    return p


def main(argv: Sequence[str] | None = None) -> None:
    """Run ``roller-gym COMMAND [options]`` (``argv``: the arguments after ``roller-gym``)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    if argv and argv[0].startswith("-") and argv[0] not in ("-h", "--help", "--version"):
        parser.error(f"unrecognized option {argv[0]!r}: a COMMAND comes first (one of "
                     f"{', '.join(COMMANDS)}), then its options; or -h, --help, --version")
    if not argv or argv[0].startswith("-"):  # no command: --help, or an error naming them
        parser.parse_args(argv[:1])
    name = parser.parse_args(argv[:1]).command
    command = COMMANDS[name]
    # The program's usage lines read "roller-gym COMMAND ...": argparse names a program
    # after sys.argv[0].
    saved = sys.argv[0]
    sys.argv[0] = f"roller-gym {name}"
    try:  # a program imports what only some of its options need when they are given
        importlib.import_module(f"roller_gym.scripts.{command.module}").main(argv[1:])
    except ImportError as exc:  # a package of an extra that is not installed
        if exc.name is None or exc.name.split(".")[0] == "roller_gym":
            raise
        raise SystemExit(f"roller-gym {name} needs {exc.name!r}, which is not installed: "
                         f"{extras.install_line(command.extra)} (in a clone of the "
                         "repository)") from None
    finally:
        sys.argv[0] = saved


if __name__ == "__main__":
    main()
