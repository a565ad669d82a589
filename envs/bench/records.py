"""The benchmarks' results files: what was measured, on which machine, by which command.

A results file is plain JSON (numbers, strings, lists, dicts); a non-finite number (a
diverged run's error, a horizon never left) is written as the string ``"inf"``, ``"-inf"`` or
``"nan"``. :func:`save_results` and :func:`load_results` write and read one; :func:`machine`
is the record of the machine, the OS, Python and the packages' versions that every results
file carries.
"""

from __future__ import annotations

import datetime
import importlib.metadata
import json
import math
import os
import platform
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

Results = dict[str, Any]


def now() -> str:
    """The date and time (UTC, ISO 8601, to the second) a measurement starts."""
    return datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")


def _encode(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): _encode(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_encode(v) for v in x]
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return "nan" if math.isnan(x) else ("inf" if x > 0 else "-inf")
    return x


def _decode(x: Any) -> Any:
    if isinstance(x, dict):
        return {k: _decode(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_decode(v) for v in x]
    if x in ("inf", "-inf", "nan"):
        return float(x)
    return x


def _dumps(x: Any, level: int = 0, width: int = 100) -> str:
    """JSON, indented by one space a level; what fits in ``width`` and every list of numbers
    on one line."""
    one = json.dumps(x, ensure_ascii=False, allow_nan=False)
    numbers = isinstance(x, list) and all(isinstance(v, int | float) for v in x)
    if not isinstance(x, dict | list) or numbers or level + len(one) <= width:
        return one
    pad, inner = " " * level, " " * (level + 1)
    if isinstance(x, dict):
        body = ",\n".join(f"{inner}{json.dumps(k, ensure_ascii=False)}: {_dumps(v, level + 1)}"
                          for k, v in x.items())
        return "{\n" + body + "\n" + pad + "}"
    body = ",\n".join(inner + _dumps(v, level + 1) for v in x)
    return "[\n" + body + "\n" + pad + "]"


def save_results(results: Results, path: Path) -> None:
    """Write ``results`` to ``path`` as JSON (strict: non-finite numbers as strings)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(_dumps(_encode(results)) + "\n")


def load_results(path: Path) -> Results:
    """The results saved at ``path`` (non-finite numbers as floats again)."""
    return _decode(json.loads(Path(path).read_text()))


def machine() -> dict[str, Any]:
    """The machine measured on: the CPU as Linux names it (with its family, model, clock and
    widest SIMD, which set the kernels' speed: a virtual machine's name alone can hide them),
    its cores, the OS, Python and the packages' versions."""
    cpu = platform.processor() or platform.machine()
    try:
        info: dict[str, str] = {}
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            key, _, value = line.partition(":")
            if not key.strip():
                break  # the first processor's block is enough
            info.setdefault(key.strip(), value.strip())
        flags = info.get("flags", "").split()
        simd = next((name for flag, name in (("avx512f", "AVX-512"), ("avx2", "AVX2"))
                     if flag in flags), "no AVX2")
        cpu = (f"{info.get('model name', cpu)} (family {info.get('cpu family', '?')} model "
               f"{info.get('model', '?')}, {float(info.get('cpu MHz', 'nan')):.0f} MHz, {simd})")
    except (OSError, ValueError):
        pass
    versions = package_versions(("roller-gym", "gymnasium", "numpy", "numba",
                                 "stable-baselines3", "torch"))
    return {"cpu": cpu, "cores": os.cpu_count(), "os": platform.platform(),
            "python": platform.python_version(), "versions": versions}


def package_versions(dists: Sequence[str]) -> dict[str, str | None]:
    """The installed version of each distribution, None where it is not installed."""
    versions: dict[str, str | None] = {}
    for dist in dists:
        try:
            versions[dist] = importlib.metadata.version(dist)
        except importlib.metadata.PackageNotFoundError:
            versions[dist] = None
    return versions
