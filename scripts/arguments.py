"""What the command-line programs parse alike, written once."""

from __future__ import annotations

import argparse
import ast
import inspect
import math
import os
import re
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

__all__ = ["COUNT_MAX", "THREADS_MAX", "at_least", "check_env_kwargs", "checked_env_kwargs",
           "key_values", "output_folder", "plain", "program_parser", "real_in", "stage"]


_ROLE = re.compile(r":\w+:`(~?)([^`]*)`")


def plain(text: str) -> str:
    """``text`` with its reST markup as a terminal shows it: ````code```` as ``code``, a
    role ``:mod:`~a.b``` as its name (the last part where ``~``)."""
    text = _ROLE.sub(lambda m: m.group(2).rsplit(".", 1)[-1] if m.group(1) else m.group(2),
                     text)
    return re.sub(r"``(.+?)``", r"\1", text, flags=re.S)


class _PlainParser(argparse.ArgumentParser):
    """An ArgumentParser whose help is :func:`plain` text."""

    def format_help(self) -> str:
        return plain(super().format_help())


def program_parser(command: str, doc: str, **kwargs: Any) -> argparse.ArgumentParser:
    """The parser of ``roller-gym COMMAND``: its description the first paragraph of ``doc``
    (the program's docstring), its epilog the rest, then the extra the command needs and how
    to install it (so that ``--help``, which works without the extra, says so)."""
    from roller_gym.scripts.cli import extra_note

    description, _, rest = doc.strip().partition("\n\n")
    epilog = "\n\n".join(part for part in (rest.rstrip(), extra_note(command)) if part)
    return _PlainParser(description=description, epilog=epilog,
                        **{"formatter_class": argparse.RawDescriptionHelpFormatter, **kwargs})


def stage(command: str, message: str) -> None:
    """One line of progress on stderr (``roller-gym evaluate: ...``), printed at once, for the
    stages of a program that runs longer than a few seconds."""
    print(f"roller-gym {command}: {message}", file=sys.stderr, flush=True)


def key_values(items: list[str], option: str, separator: str = "=",
               example: str = "max_torque=0.6") -> dict[str, Any]:
    """``["max_torque=0.6", "scene=floor"]`` -> ``{"max_torque": 0.6, "scene": "floor"}``:
    values are Python literals where they parse as one (``0.6``, ``(0.8, 1.2)``,
    ``{"m": (0.8, 1.2)}``, ``None``), else strings.

    Raises:
        SystemExit: an item is not KEY<separator>VALUE, or a key is given twice; the message
            names ``option`` and gives ``example``.
    """
    out: dict[str, Any] = {}
    for item in items:
        key, sep, value = item.partition(separator)
        if not sep or not key:
            raise SystemExit(f"{option}: {item!r} is not KEY{separator}VALUE (e.g. {example})")
        if key in out:
            raise SystemExit(f"{option}: {key!r} is given twice; give each key once")
        try:
            out[key] = ast.literal_eval(value)
        except (ValueError, SyntaxError):
            out[key] = value
    return out


#: The keyword arguments gymnasium.make takes itself, besides the environment's.
MAKE_KWARGS = ("max_episode_steps", "disable_env_checker")


def checked_env_kwargs(env_id: str, items: list[str], option: str) -> dict[str, Any]:
    """The keyword arguments of ``gymnasium.make(env_id, ...)`` in ``items`` (as
    :func:`key_values`), checked by building the environment once with them, so that a value
    the environment refuses ends the program with the environment's own message before any
    training library starts (where it would end in a traceback from that library's setup).

    Raises:
        SystemExit: an item is not KEY=VALUE, or the environment refuses the arguments; the
            message names ``option``.
    """
    kwargs = key_values(items, option)
    check_env_kwargs(env_id, kwargs, option)
    return kwargs


def check_env_kwargs(env_id: str, kwargs: dict[str, Any], option: str) -> None:
    """Check the keyword arguments ``kwargs`` of ``gymnasium.make(env_id, ...)`` by building
    the environment once with them (see :func:`checked_env_kwargs`).

    Raises:
        SystemExit: the environment refuses them; the message names ``option``.
    """
    import gymnasium as gym
    from gymnasium.envs.registration import load_env_creator

    spec = gym.spec(env_id)
    creator = spec.entry_point
    creator = creator if callable(creator) else load_env_creator(creator)
    params = inspect.signature(creator).parameters
    allowed = [name for name in (*params, *MAKE_KWARGS) if name not in spec.kwargs]
    unknown = [key for key in kwargs if key not in allowed]
    if unknown and all(p.kind is not p.VAR_KEYWORD for p in params.values()):
        raise SystemExit(f"{option}: {unknown[0]!r} is not an argument of {env_id}; "
                         f"allowed: {', '.join(allowed)}")
    # (Gymnasium's make fails on a render_mode that is not a string: AttributeError)
    mode, modes = kwargs.get("render_mode"), getattr(creator, "metadata", {}).get(
        "render_modes", ())
    if mode is not None and mode not in modes:
        raise SystemExit(f"{option}: render_mode={mode!r} is not allowed: it must be None or "
                         f"one of {', '.join(map(repr, modes))}")
    steps = kwargs.get("max_episode_steps", 1)
    if not (isinstance(steps, int) and not isinstance(steps, bool) and steps >= 1):
        raise SystemExit(f"{option}: max_episode_steps={steps!r} is not allowed: it must be an "
                         "integer >= 1 (training and evaluation need episodes that end)")
    try:
        gym.make(env_id, **kwargs).close()
    except (TypeError, ValueError) as exc:
        raise SystemExit(f"{option}: {exc}") from None


#: The largest count any option takes unless it says otherwise: what a C long holds (the
#: libraries a count reaches convert it to one).
COUNT_MAX = 2**63 - 1
#: The most threads an option may ask for.
THREADS_MAX = 1024


def at_least(least: int, most: int = COUNT_MAX) -> Callable[[str], int]:
    """An argparse ``type``: an integer of at least ``least`` and at most ``most``, else
    argparse's error naming the option, the value and what is allowed."""
    allowed = f"an integer >= {least} and <= {most}" + (" (2**63 - 1)" if most == COUNT_MAX
                                                         else "")

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = least - 1
        if value < least or value > most:
            raise argparse.ArgumentTypeError(f"{text!r} is not {allowed}")
        return value

    parse.__name__ = allowed
    return parse


def real_in(low: float, high: float, *, open_low: bool = False) -> Callable[[str], float]:
    """An argparse ``type``: a finite real number in [low, high] ((low, high] with
    ``open_low``), else argparse's error naming the option, the value and what is allowed."""
    allowed = f"a number in {'(' if open_low else '['}{low:g}, {high:g}]"

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not (low < value <= high if open_low else low <= value <= high):
            raise argparse.ArgumentTypeError(f"{text!r} is not {allowed}")
        return value

    parse.__name__ = allowed
    return parse


def output_file(path: str | Path, option: str) -> Path:
    """The file ``path``, checked now to be writable (its folder created, as
    :func:`output_folder`; the file opened for writing and, if it did not exist, removed
    again), so that a program ends at its start, naming ``option``, not after its work."""
    file = Path(path)
    output_folder(file.parent, option)
    existed = file.exists()
    try:
        with open(file, "ab"):
            pass
    except OSError as exc:
        raise SystemExit(f"{option}: cannot write {str(file)!r}: {exc.strerror or exc}") from None
    if not existed:
        file.unlink()
    return file


def output_folder(path: str | Path, option: str) -> Path:
    """The folder ``path``, created now with its parents and checked to be writable, so that
    a program that writes there ends at its start, naming ``option``, rather than after its
    work."""
    folder = Path(path)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise SystemExit(f"{option}: cannot create the folder {str(folder)!r}: "
                         f"{exc.strerror or exc}") from None
    if not os.access(folder, os.W_OK):
        raise SystemExit(f"{option}: the folder {str(folder)!r} is not writable")
    return folder
