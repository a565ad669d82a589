"""The first step from an empty compile cache, against a warm one and against Pendulum-v1.

    python -m roller_gym.bench.firstuse                 # every case, writes the JSON
    python -m roller_gym.bench.firstuse --cases single  # some cases

numba compiles the environments' kernels on their first use and caches them on disk
(``__pycache__`` next to the package, or ``NUMBA_CACHE_DIR``, or a user-wide folder where
the package's folder is read-only). Each case of :data:`CASES` runs in a fresh Python process
with a fresh, empty ``NUMBA_CACHE_DIR`` (cold), then once more in another process on the
cache the first one filled (warm). A process reports the seconds from its start to the end of
its first step (``first_s``: the import, ``gym.make`` or ``gym.make_vec``, ``reset`` and one
``step``) and the import's share (``import_s``). Writes ``<out>/benchmarks/firstuse.json``
with the machine's cores and load, draws the throughput page (which shows them) again, and
prints a table. The machine's load changes compile
times several-fold: compare figures of one run, and read its load.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

TASK = "roller_gym/RollerStabilize-v2"
#: What each case builds and steps once, a Python expression run in the child (``gym`` is
#: gymnasium; ``roller_gym`` is imported before the import mark, except for Pendulum-v1).
CASES = {
    "single": f"gym.make({TASK!r})",
    "vector_64": f"gym.make_vec({TASK!r}, num_envs=64, vectorization_mode='vector_entry_point')",
    "vector_4096": f"gym.make_vec({TASK!r}, num_envs=4096, "
                   "vectorization_mode='vector_entry_point')",
    "pendulum": "gym.make('Pendulum-v1')",
}
#: The targets [s] of a cold first step on an idle machine, by case.
TARGETS = {"single": 10.0, "vector_64": 20.0, "vector_4096": 20.0}
#: The keys of each case's record in the results file.
RECORD_KEYS = ("cold", "warm")
#: The keys of each run's record (seconds, and the child's stderr lines).
RUN_KEYS = ("import_s", "first_s", "process_s", "stderr")

_CHILD = """
import time
_t0 = time.perf_counter()
import json, sys
import gymnasium as gym
{imports}
_t1 = time.perf_counter()
env = {make}
env.reset(seed=0)
env.step(env.action_space.sample())
_t2 = time.perf_counter()
print(json.dumps({{"import_s": _t1 - _t0, "first_s": _t2 - _t0}}))
"""


def run_case(name: str, cache_dir: str) -> dict[str, Any]:
    """Run case ``name`` in a fresh process with ``NUMBA_CACHE_DIR=cache_dir``: its
    :data:`RUN_KEYS` (``process_s``: the process's wall time, interpreter start included)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir)
    start = time.perf_counter()
    imports = "" if name == "pendulum" else "import roller_gym  # noqa: F401"
    code = _CHILD.format(make=CASES[name], imports=imports)
    proc = subprocess.run([sys.executable, "-c", code], env=env,
                          capture_output=True, text=True, check=False)
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        raise RuntimeError(f"case {name!r} failed ({proc.returncode}):\n{proc.stderr}")
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    return {"import_s": out["import_s"], "first_s": out["first_s"], "process_s": wall,
            "stderr": [line for line in proc.stderr.splitlines() if line.strip()]}


def machine() -> dict[str, Any]:
    """The CPU, the cores (all, and those this process may use), the load averages and the
    versions."""
    import numba
    from roller_gym.bench import records

    return {"cpu": records.machine()["cpu"], "cpu_count": os.cpu_count(),
            "usable_cores": len(os.sched_getaffinity(0)),
            "load_average": list(os.getloadavg()), "platform": platform.platform(),
            "python": platform.python_version(), "numba": numba.__version__}


def measure(cases: list[str]) -> dict[str, Any]:
    """Each case cold (an empty cache of its own) and then warm (that cache filled)."""
    results: dict[str, Any] = {"date": datetime.datetime.now(datetime.UTC).isoformat(
        timespec="seconds"), "command": "python -m roller_gym.bench.firstuse "
        + " ".join(sys.argv[1:]), "machine_before": machine(), "targets_s": TARGETS,
        "cases": {}}
    for name in cases:
        with tempfile.TemporaryDirectory(prefix="firstuse-") as cache:
            cold = run_case(name, cache)
            warm = run_case(name, cache)
        results["cases"][name] = {"cold": cold, "warm": warm, "load_after": list(os.getloadavg())}
        print(f"  {name}: cold {cold['first_s']:.1f} s, warm {warm['first_s']:.1f} s "
              f"(load {os.getloadavg()[0]:.1f})", file=sys.stderr)
    results["machine_after"] = machine()
    return results


def check(results: dict[str, Any]) -> None:
    """Raise ValueError where ``results`` lacks a key :func:`measure` writes."""
    for key in ("date", "command", "machine_before", "machine_after", "targets_s", "cases"):
        if key not in results:
            raise ValueError(f"results lack {key!r}")
    for name, record in results["cases"].items():
        if name not in CASES:
            raise ValueError(f"unknown case {name!r}; known: {', '.join(CASES)}")
        for kind in RECORD_KEYS:
            missing = [k for k in RUN_KEYS if k not in record.get(kind, {})]
            if missing:
                raise ValueError(f"case {name!r}, {kind}: lacks {missing}")


def table(results: dict[str, Any]) -> str:
    """The results as a text table: seconds to the first step, cold and warm."""
    lines = [f"{'case':<12} {'cold [s]':>9} {'warm [s]':>9} {'import [s]':>10} "
             f"{'target [s]':>10}  load after"]
    for name, rec in results["cases"].items():
        target = TARGETS.get(name)
        lines.append(f"{name:<12} {rec['cold']['first_s']:9.1f} {rec['warm']['first_s']:9.1f} "
                     f"{rec['cold']['import_s']:10.1f} "
                     f"{'' if target is None else f'{target:.0f}':>10}  "
                     f"{rec['load_after'][0]:.1f}")
    m = results["machine_before"]
    lines.append(f"{m['usable_cores']} usable cores of {m['cpu_count']}; load before "
                 f"{m['load_average'][0]:.1f}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        prog="python -m roller_gym.bench.firstuse",
        description="Seconds to the first step from an empty numba cache (each case in a "
                    "fresh process with a fresh NUMBA_CACHE_DIR), then warm.")
    parser.add_argument("--cases", nargs="+", choices=tuple(CASES), default=list(CASES),
                        help="the cases to run (default: all)")
    parser.add_argument("--out", type=Path, default=Path("docs"),
                        help="writes <out>/benchmarks/firstuse.json (default: docs)")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args(argv)
    results = measure(args.cases)
    check(results)
    if not args.no_write:
        path = args.out / "benchmarks" / "firstuse.json"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(results, indent=1) + "\n")
        print(f"wrote {path}", file=sys.stderr)
        from roller_gym.bench import records, throughput, throughput_report

        measured = args.out / throughput.RESULTS_FILE
        if measured.exists():  # the throughput page shows these figures: draw it again
            for page in throughput_report.write(records.load_results(measured), args.out):
                print(f"wrote {page}", file=sys.stderr)
    print(table(results))


if __name__ == "__main__":
    main()
