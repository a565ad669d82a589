"""The throughput page, ``docs/THROUGHPUT.md``, and its plot, rendered from the throughput
study's results file (no measuring; :mod:`roller_gym.bench.throughput` measures). The page
says what was measured, against which peers, on which machine and how to measure again; the
targets and their verdicts are the maintainers' page's (:mod:`roller_gym.bench.maintainers`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from roller_gym.bench import maintainers, plots
from roller_gym.bench.markdown import faster, machine_section
from roller_gym.bench.plots import THROUGHPUT_PLOT
from roller_gym.bench.throughput import PEERS, REPLAY_EVERY, RESULTS_FILE, TASK
from roller_gym.episode import INFO_KEYS

Results = dict[str, Any]

PAGE = "THROUGHPUT.md"
#: The first-use benchmark's results (:mod:`roller_gym.bench.firstuse`), in the docs folder.
FIRST_USE_FILE = Path("benchmarks") / "firstuse.json"


def _share_repeats(results: Results) -> str:
    """The repeats the share outside the physics kernel took (as one number, or a list)."""
    counts = sorted({v["outside_kernel_repeats"] for v in results["vector"].values()})
    return " or ".join(str(c) for c in counts)


def _first_use(first: Results) -> list[str]:
    """The page's section on the first step from an empty compile cache."""
    from roller_gym.bench.firstuse import CASES

    load = first["machine_before"]["load_average"][0]
    cpu = f" of {first['machine_before']['cpu']}" if "cpu" in first["machine_before"] else ""
    lines = ["## The first step", "",
             "Seconds from a fresh process's start to the end of its first step (the import, "
             "the make, `reset` and one `step`): with an empty numba cache (cold: the kernels "
             "are compiled, and cached on disk) and then on the cache that run filled (warm), "
             f"measured {first['date'][:10]} on {first['machine_before']['usable_cores']} "
             f"cores{cpu} at a load average of {load:.1f} before the run (compile times differ "
             "from one CPU to another several-fold), by "
             "`python -m roller_gym.bench.firstuse` (which writes "
             f"`{FIRST_USE_FILE.as_posix()}`; compile times grow several-fold on a busy "
             "machine).", "",
             "| first step of | cold cache, s | warm cache, s | of which the import (cold), s |",
             "|---|---:|---:|---:|"]
    for name, rec in first["cases"].items():
        lines.append(f"| `{CASES[name]}` | {rec['cold']['first_s']:.1f} | "
                     f"{rec['warm']['first_s']:.1f} | {rec['cold']['import_s']:.1f} |")
    return [*lines, ""]


def render(results: Results, first_use: Results | None = None) -> str:
    """The Markdown page of a results file, with the first-use benchmark's ``first_use``
    where given (no measuring)."""
    peers = [p for p in PEERS if any(p in v for v in results["vector"].values())]
    lines = [
        "# Throughput", "",
        "How fast the environments step, against their peers: the vector environment "
        "(`gymnasium.make_vec`) over whole episodes against Gymnasium's `CartPoleVectorEnv`"
        + "".join(f", {p}" for p in peers) + "; one environment (`gymnasium.make`) against "
        "Pendulum-v1; stable-baselines3's PPO on the native batch against `DummyVecEnv`. "
        "Every figure is a best-of-repeats time measured in the same run as its peers': the "
        "ratios are the figures to read, as absolute speeds depend on the machine (below)."
        + (" **A quick (smoke) run**: it shows that the benchmark works, not what it finds."
           if results["quick"] else ""), "",
        f"![throughput](benchmarks/{THROUGHPUT_PLOT})", "",
        *machine_section(
            results, "`make throughput` measures again with the optional peers (EnvPool, "
            "Gymnasium's JAX Pendulum) in an environment of their own, `.venv-peers`, in "
            "about a minute; without them, `python -m roller_gym.bench.throughput measure "
            "--out docs`; `render` instead of `measure` draws this page and its plot again "
            "from the numbers.", RESULTS_FILE.as_posix()),
        "## The vector environment", "",
              "| sub-environments | ours, steps/s | CartPoleVectorEnv, steps/s | ratio | "
              "physics kernel alone, steps/s | share of a step outside the physics kernel | "
              "outside any compiled call |",
              "|---:|---:|---:|---:|---:|---:|---:|"]
    for n, v in results["vector"].items():
        compiled = v.get("outside_compiled_share")
        lines.append(f"| {int(n):,} | {v['ours']:,.0f} | {v['CartPoleVectorEnv']:,.0f} | "
                     f"{v['ours'] / v['CartPoleVectorEnv']:.3f} | {v['kernel']:,.0f} | "
                     f"{v['outside_kernel_share']:.0%} | "
                     + ("–" if compiled is None else f"{compiled:.0%}") + " |")
    steps = {v.get("ours_steps") for v in results["vector"].values()}
    lines += ["", (f"Ours and CartPole run {steps.pop()} steps per timed run (for ours a whole "
                   "episode of every sub-environment, its autoreset included), as a step's cost "
                   "depends on where the rollers are in an episode. "
                   if len(steps) == 1 and None not in steps else "")
              + "Every env's actions are drawn uniformly anew for every step and "
              "sub-environment, as an exploring agent's (a torque that changes every step "
              "costs the error control more substeps than a steady one). "
              "The kernel alone: `BatchStepper.run` repeated from one state. "
              "The share outside the physics kernel: every "
              f"{REPLAY_EVERY}th step of an episode through the environment replayed through "
              "the physics kernel alone, its time against the environment's step "
              "(observation, reward, info, autoreset and the copies are the rest), the "
              f"fastest of {_share_repeats(results)} repeats of each: of the episode through "
              "the environment, of the replays' sum. On all "
              "cores the step's outcome (reward, termination, info and observation) runs in "
              "the same compiled pass as the physics, chunk by chunk; the last column is the "
              "share outside that pass and any other compiled call (the environment's Python "
              "and NumPy), timed inside its own steps."]
    if all("ours_no_info" in v for v in results["vector"].values()):
        lines += ["", "The info's cost: the same steps with `info_keys=[]` run " + " and ".join(
            f"{faster(v['ours_no_info'] / v['ours'])} at {int(n):,}"
            for n, v in results["vector"].items())
            + f". Its {len(INFO_KEYS)} arrays are the rows of the step's own outcome tables, "
            "one of floats and one of booleans (new tables every step, so that they can be "
            "handed out as they are); the integer one is converted."]
    if peers:
        lines += ["", "Optional peers, in the same run:", "",
                  "| sub-environments | " + " | ".join(f"{p}, steps/s | ours / it" for p in peers)
                  + " |", "|---:|" + "---:|---:|" * len(peers)]
        for n, v in results["vector"].items():
            lines.append(f"| {int(n):,} | " + " | ".join(
                f"{v[p]:,.0f} | {v['ours'] / v[p]:.2f}" if p in v else "– | –" for p in peers)
                + " |")
    if all("unit_ns" in v for v in results["vector"].values()):
        unit = next(iter(results["vector"].values()))["unit"]
        lines += ["", "How close the kernel is to its arithmetic: one evaluation of φ'' per "
                  f"roller and one {unit} (the unit of the default integrator's substeps), "
                  "each the kernel's own compiled loop over rollers, timed alone on one core; "
                  f"and the kernel's cost per core against the {unit}s its substeps need (the "
                  "rest is rejected attempts where there are any, the contact margins at every "
                  "substep, the end state's fields and the outputs):", "",
                  f"| sub-environments | one φ'' evaluation, ns/roller | one {unit}, "
                  "ns/roller | substeps per step | kernel, core-ns/roller-step | "
                  f"kernel / its {unit}s |", "|---:|---:|---:|---:|---:|---:|"]
        for n, v in results["vector"].items():
            kernel_ns = 1e9 / v["kernel"] * v["kernel_threads"]
            lines.append(f"| {int(n):,} | {v['rhs_ns']:.2f} | {v['unit_ns']:.2f} | "
                         f"{v['substeps']:.2f} | {kernel_ns:.0f} | "
                         f"{kernel_ns / (v['unit_ns'] * v['units_per_step']):.1f} |")
    single, ppo = results["single"], results["ppo"]
    lines += ["", "## One environment and SB3", "",
              f"- `gymnasium.make(\"{TASK}\")`: {single['ours']:,.0f} steps/s; Pendulum-v1 "
              f"{single['Pendulum-v1']:,.0f} steps/s: "
              f"{single['ours'] / single['Pendulum-v1']:.2f} ×."
              + (f" With `info_keys=[]` (no info): {single['ours_no_info']:,.0f} steps/s, "
                 f"{single['ours_no_info'] / single['Pendulum-v1']:.2f} ×; the info's "
                 f"{len(INFO_KEYS)} typed "
                 f"values are {1 - single['ours'] / single['ours_no_info']:.0%} of a step."
                 if "ours_no_info" in single else ""),
              f"- SB3 PPO, 16 environments: {ppo['RollerVecEnv']:,.0f} training steps/s through "
              f"`roller_gym.sb3.RollerVecEnv`, {ppo['DummyVecEnv']:,.0f} through `DummyVecEnv` "
              f"of single environments: {ppo['RollerVecEnv'] / ppo['DummyVecEnv']:.2f} ×.",
              "- The environments' state error, and what each integrator costs for its "
              "error: [`BENCHMARKS.md`](BENCHMARKS.md).", ""]
    if first_use is not None:
        lines += _first_use(first_use)
    if results["peers_missing"]:
        lines += ["## Peers not measured", ""]
        lines += [f"- {name}: {why}." for name, why in results["peers_missing"].items()]
        lines.append("")
    return "\n".join(lines)


def write(results: Results, out: Path) -> list[Path]:
    """Render ``results`` into the docs folder ``out``: ``out/THROUGHPUT.md``, its plot, and
    the maintainers' page (its verdicts); the pages' paths. The first-use benchmark's
    results are on the page where ``out`` holds them."""
    out = Path(out)
    (out / "benchmarks").mkdir(parents=True, exist_ok=True)
    plots.plot_throughput(results, out / "benchmarks" / THROUGHPUT_PLOT)
    page = out / PAGE
    first = out / FIRST_USE_FILE
    page.write_text(render(results, json.loads(first.read_text()) if first.exists() else None))
    return [page, maintainers.write(out)]
