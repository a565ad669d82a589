"""Best-of-repeats timing, written once for every benchmark.

Every comparison is timed in one process, interleaved: each repeat runs every candidate once
in turn, so that a shared machine's drift hits them alike, and each candidate keeps its
shortest time (other processes slow a run down, never speed it up). The figures to compare
are ratios of such times.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Hashable, Mapping
from typing import Any

#: ``skip(key, repeat, best_so_far)``: True to leave that repeat of a candidate out.
Skip = Callable[[Hashable, int, float], bool]


def clocked(run: Callable[[], Any]) -> Callable[[], float]:
    """A callable that runs ``run()`` and returns its wall time [s]."""

    def once() -> float:
        start = time.perf_counter()
        run()
        return time.perf_counter() - start

    return once


def best(times: Mapping[Hashable, Callable[[], float]], repeats: int,
         skip: Skip | None = None) -> dict[Hashable, float]:
    """The shortest of ``repeats`` interleaved measurements [s] of each candidate: each
    callable measures itself and returns its time (so that it can leave out what is not to
    be timed, such as resets). ``skip`` leaves repeats out (e.g. of slow candidates)."""
    out = dict.fromkeys(times, float("inf"))
    for rep in range(repeats):
        for key, fn in times.items():
            if skip is not None and skip(key, rep, out[key]):
                continue
            out[key] = min(out[key], fn())
    return out


def best_time(run: Callable[[], Any], repeats: int) -> float:
    """The shortest of ``repeats`` wall times [s] of ``run()``."""
    return best({0: clocked(run)}, repeats)[0]


def progress(line: str) -> None:
    """Say on stderr which measurement starts (stdout stays for the results)."""
    print(line, file=sys.stderr, flush=True)
