"""Results over training seeds: evaluate every trained agent, aggregate with rliable, write a page.

    roller-gym results --runs runs/results            # evaluate every run found, then render
    roller-gym results --render                       # render again from the results file

``make results`` trains SAC, TD3 and PPO on every task with five seeds (``roller-gym train
--seed S --log-folder runs/results/seedS``, two processes at a time) and then runs the first
line. Read top to bottom:

1. **Find** every rl-zoo3 experiment under ``--runs`` (any depth) of each algorithm and task.
2. **Evaluate** each trained agent (its final model, acting deterministically) and the
   baselines (the classical controller, zero torque, random actions) on the same episodes,
   ``env.reset(seed=s)`` for s < ``--episodes``. A run's score is its mean return over them
   and its success rate. The periodic evaluations rl-zoo3 made during training
   (``evaluations.npz``) are read for the learning curves.
3. **Save** everything to ``docs/results/results.json`` (with the machine, versions, command).
4. **Render** from that file alone (``--render``: seconds): per task, the interquartile mean
   (IQM) over seeds of return and success with 95 % stratified-bootstrap intervals; over the
   tasks, the IQM of the return normalized by the classical controller's, performance
   profiles and the probability of improvement over the classical controller; learning
   curves with interval bands; and the training steps to each task's reward threshold.
   Writes ``docs/RESULTS.md`` and the plots in ``docs/results/``.
"""

from __future__ import annotations

import argparse
import datetime
import json
import multiprocessing
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import roller_gym
from roller_gym.agents.hyperparams import ALGOS
from roller_gym.agents.policies import BASELINES, baseline, evaluation_env, load_policy, read_config
from roller_gym.bench.records import package_versions
from roller_gym.scripts.arguments import at_least, output_folder, program_parser, stage
from roller_gym.scripts.evaluate import (  # its targets, read here from the intervals
    BASELINE_LABELS,
    RETURN_TOLERANCE,
    SUCCESS_TARGET,
    classical_label,
    evaluate,
)
from roller_gym.task import get_task


def build_parser() -> argparse.ArgumentParser:
    p = program_parser("results", __doc__)
    p.add_argument("--runs", default="runs/results", metavar="LOG_FOLDER",
                   help="where the training runs are (searched at any depth for rl-zoo3 "
                        "experiments <algo>/<env name>_<N>; default runs/results)")
    p.add_argument("--env", nargs="+", default=list(roller_gym.ENV_IDS),
                   choices=roller_gym.ENV_IDS, help="the tasks (default: all)")
    p.add_argument("--algos", nargs="+", default=list(ALGOS), choices=ALGOS,
                   help="the algorithms (default: sac td3 ppo)")
    p.add_argument("--episodes", type=at_least(1), default=100,
                   help="evaluation episodes per agent (default 100)")
    p.add_argument("--workers", type=at_least(1), default=2,
                   help="evaluation processes (default 2)")
    p.add_argument("--results", default="docs/results/results.json",
                   help="the results file (default docs/results/results.json)")
    p.add_argument("--report", default="docs/RESULTS.md",
                   help="the page to write (default docs/RESULTS.md); plots go beside the "
                        "results file")
    p.add_argument("--train-wall-s", type=float, default=None,
                   help="the wall time [s] the trainings took, for the page (make results "
                        "passes it)")
    p.add_argument("--render", action="store_true",
                   help="only render the page from the results file (no evaluation)")
    return p


# -- 1. find ---------------------------------------------------------------------------------


def find_runs(log_folder: str | Path, algo: str, env_id: str) -> list[Path]:
    """Every rl-zoo3 experiment folder of ``algo`` on ``env_id`` under ``log_folder``."""
    runs = []
    for args_file in sorted(Path(log_folder).rglob(f"{algo}/*_*/*/args.yml")):
        run_dir = args_file.parent.parent
        try:
            config = read_config(run_dir)
        except FileNotFoundError:
            continue
        if config["env"] == env_id and Path(config["model"]).is_file():
            runs.append(run_dir)
    return runs


# -- 2. evaluate -----------------------------------------------------------------------------


def _evaluate_job(job: tuple[str, str, str | None, int]) -> dict[str, Any]:
    """One agent or baseline on the task's seeded episodes (run in a worker process)."""
    import torch

    torch.set_num_threads(1)
    env_id, name, run_dir, episodes = job
    start = time.perf_counter()
    if run_dir is None:  # a baseline
        env = gym.make(env_id)
        out = {"env": env_id, "name": name, **evaluate(env, baseline(name, env, seed=0),
                                                       episodes)}
    else:
        config = read_config(run_dir)
        env = evaluation_env(env_id, config["env_kwargs"])
        out = {"env": env_id, "name": name, "run_dir": str(run_dir), "seed": config["seed"],
               "trained_steps": config["trained_steps"], "wall_time_s": config["wall_time_s"],
               **evaluate(env, load_policy(run_dir), episodes)}
        curve = Path(run_dir) / "evaluations.npz"
        if curve.is_file():
            data = np.load(curve)
            out["curve"] = {"timesteps": data["timesteps"].tolist(),
                            "returns": data["results"].tolist()}
    env.close()
    out.pop("trajectory", None)
    out["evaluation_s"] = time.perf_counter() - start
    print(f"{env_id:28s} {name:10s} seed {out.get('seed', '-')!s:>3s}: return "
          f"{out['return_mean']:7.1f}, success {out['success_rate']:4.0%} "
          f"({out['evaluation_s']:.0f} s)", flush=True)
    return out


def measure(args: argparse.Namespace) -> dict[str, Any]:
    """Evaluate every run and baseline; the contents of the results file."""
    stage("results", f"finding the runs under {args.runs}")
    baselines, runs = [], []
    for env_id in args.env:
        baselines += [(env_id, name, None, args.episodes) for name in BASELINES]
        for algo in args.algos:
            runs += [(env_id, algo, str(d), args.episodes) for d in find_runs(args.runs, algo,
                                                                              env_id)]
    if not runs:
        raise SystemExit(f"--runs {args.runs!r}: no trained runs found (train with "
                         "roller-gym train --log-folder ...)")
    stage("results", f"evaluating {len(runs)} runs and {len(baselines)} baselines on "
                     f"{args.episodes} episodes each, {args.workers} processes at a time (a "
                     "line per agent as it finishes)")
    start = time.perf_counter()
    with multiprocessing.get_context("spawn").Pool(args.workers) as pool:
        evaluations = pool.map(_evaluate_job, baselines + runs, chunksize=1)
    versions = package_versions(("roller-gym", "gymnasium", "stable-baselines3", "rl_zoo3",
                                 "torch", "rliable", "numpy"))
    return {
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "command": "roller-gym results " + " ".join(sys.argv[1:]),
        "machine": f"{platform.machine()}, {os.cpu_count()} CPU cores, {platform.platform()}",
        "versions": versions,
        "episodes": args.episodes,
        "evaluation_s": time.perf_counter() - start,
        "train_wall_s": args.train_wall_s,
        "tasks": {env_id: {"reward_threshold": gym.spec(env_id).reward_threshold,
                           "classical": classical_label(env_id),
                           "success_band": get_task(env_id).success_band}
                  for env_id in args.env},
        "evaluations": evaluations,
    }


# -- 4. render -------------------------------------------------------------------------------


def summarize(results: dict[str, Any], algos: list[str]) -> dict[str, Any]:
    """The aggregates the page shows, from the results file's contents."""
    from roller_gym.agents import stats  # rliable: --help works without it
    tasks = list(results["tasks"])
    by = {(e["env"], e["name"]): [] for e in results["evaluations"]}
    for e in results["evaluations"]:
        by[(e["env"], e["name"])].append(e)
    algos = [a for a in algos if any((t, a) in by for t in tasks)]
    out: dict[str, Any] = {"tasks": {}, "algos": algos}
    for task in tasks:
        classical = by[(task, "classical")][0]["return_mean"]
        threshold = results["tasks"][task]["reward_threshold"]
        row: dict[str, Any] = {"baselines": {n: by[(task, n)][0] for n in BASELINES
                                             if (task, n) in by}, "algos": {}}
        for algo in algos:
            runs = sorted(by.get((task, algo), []), key=lambda e: e["seed"])
            if not runs:
                continue
            returns = np.array([e["return_mean"] for e in runs])
            success = np.array([e["success_rate"] for e in runs])
            steps = [stats.steps_to_threshold(np.array(e["curve"]["timesteps"]),
                                              np.array(e["curve"]["returns"]), threshold)
                     for e in runs if "curve" in e]
            row["algos"][algo] = {
                "seeds": [e["seed"] for e in runs],
                "final_error": [e["final_error_mean"] for e in runs],
                "returns": returns.tolist(), "success": success.tolist(),
                "return_iqm": stats.interval(returns),
                "success_iqm": stats.interval(success),
                "steps_to_threshold": steps,
                "steps_median": (stats.interval(np.array(steps), statistic=stats.median_batch)
                                 if steps else None),
                "poi_vs_classical": stats.probability_of_improvement(returns[:, None],
                                                                     np.array([[classical]])),
            }
        out["tasks"][task] = row
    # over the tasks: returns normalized by the classical controller's
    complete = [a for a in algos if all(a in out["tasks"][t]["algos"] for t in tasks)]
    seeds = min((len(out["tasks"][t]["algos"][a]["returns"]) for a in complete for t in tasks),
                default=0)
    norm = {a: np.array([[out["tasks"][t]["algos"][a]["returns"][i]
                          / out["tasks"][t]["baselines"]["classical"]["return_mean"]
                          for t in tasks] for i in range(seeds)]) for a in complete}
    ones = np.ones((1, len(tasks)))
    out["overall"] = {
        "seeds": seeds,
        "normalized_iqm": {a: stats.interval(s) for a, s in norm.items()},
        "success_iqm": {a: stats.interval(np.array([[out["tasks"][t]["algos"][a]["success"][i]
                                                     for t in tasks] for i in range(seeds)]))
                        for a in complete},
        "poi_vs_classical": {a: stats.probability_of_improvement(s, ones)
                             for a, s in norm.items()},
        "taus": np.linspace(0.0, 1.1, 45).tolist(),
    }
    out["overall"]["profiles"] = (stats.performance_profile(norm, np.array(out["overall"]["taus"]))
                                  if norm else {})
    return out


def target(task_row: dict[str, Any]) -> tuple[bool | None, str]:
    """Whether SAC meets the targets on a task, and the sentence saying so."""
    sac = task_row["algos"].get("sac")
    if sac is None:
        return None, "no SAC runs"
    classical = task_row["baselines"]["classical"]["return_mean"]
    success, lower = sac["success_iqm"][0], sac["return_iqm"][1]
    bound = (1 - RETURN_TOLERANCE) * classical
    met = success >= SUCCESS_TARGET and lower >= bound
    parts = [f"success IQM {success:.0%} (target ≥ {SUCCESS_TARGET:.0%}"
             + ("" if success >= SUCCESS_TARGET else f", short by {SUCCESS_TARGET - success:.0%}")
             + ")",
             f"return interval's lower end {lower:.1f} (target ≥ {bound:.1f}, classical − "
             f"{RETURN_TOLERANCE:.0%}"
             + ("" if lower >= bound else f", short by {bound - lower:.1f}") + ")"]
    return met, ("**met**" if met else "**missed**") + ": " + "; ".join(parts)


def _fmt(iv: tuple[float, float, float], pct: bool = False, digits: int = 1) -> str:
    """An estimate and its interval: ``1.0 [0.9, 1.1]`` (or in percent)."""
    spec = ".0%" if pct else f".{digits}f"
    return f"{iv[0]:{spec}} [{iv[1]:{spec}}, {iv[2]:{spec}}]"


def _steps(summary: dict[str, Any] | None, steps: list[float]) -> str:
    if summary is None:
        return "–"
    reached = sum(np.isfinite(steps))
    iv = [("never" if not np.isfinite(v) else f"{v / 1000:.0f}k") for v in summary]
    return f"{iv[0]} [{iv[1]}, {iv[2]}] ({reached}/{len(steps)} seeds reached it)"


def plot(results: dict[str, Any], summary: dict[str, Any], folder: Path) -> None:
    """The learning curves, the IQM intervals and the performance profiles."""
    import matplotlib.pyplot as plt
    from roller_gym.agents import stats  # rliable: --help works without it

    tasks = list(summary["tasks"])
    colors = dict(zip(ALGOS, ("C0", "C1", "C2"), strict=False))
    fig, axes = plt.subplots(1, len(tasks), figsize=(4.2 * len(tasks), 3.6), squeeze=False)
    for ax, task in zip(axes[0], tasks, strict=True):
        for algo in summary["algos"]:
            runs = [e for e in results["evaluations"]
                    if e["env"] == task and e["name"] == algo and "curve" in e]
            if not runs:
                continue
            n = min(len(e["curve"]["timesteps"]) for e in runs)
            t = np.array(runs[0]["curve"]["timesteps"][:n])
            means = np.array([np.mean(e["curve"]["returns"][:n], axis=1) for e in runs])
            band = np.array([stats.interval(means[:, j]) for j in range(n)])
            ax.plot(t, band[:, 0], color=colors[algo], label=f"{algo.upper()} (IQM)")
            ax.fill_between(t, band[:, 1], band[:, 2], color=colors[algo], alpha=0.2)
        base = summary["tasks"][task]["baselines"]
        ax.axhline(base["classical"]["return_mean"], color="k", linestyle="--", linewidth=1,
                   label=results["tasks"][task]["classical"])
        ax.axhline(results["tasks"][task]["reward_threshold"], color="grey", linestyle=":",
                   linewidth=1, label="reward threshold")
        ax.set(title=task.split("/")[-1], xlabel="training steps", ylabel="evaluation return")
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(folder / "learning-curves.png", dpi=100)
    plt.close(fig)

    overall = summary["overall"]
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.6))
    for i, algo in enumerate(overall["normalized_iqm"]):
        for j, (key, label) in enumerate((("normalized_iqm", "return / classical"),
                                          ("success_iqm", "success"))):
            est, lo, hi = overall[key][algo]
            ax1.errorbar(est, i + 0.15 * j, xerr=[[est - lo], [hi - est]], fmt="os"[j],
                         color=colors[algo], label=label if i == 0 else None)
    ax1.set_yticks(range(len(overall["normalized_iqm"])),
                   [a.upper() for a in overall["normalized_iqm"]])
    ax1.axvline(1.0, color="k", linewidth=0.5)
    ax1.set(title="IQM over seeds and tasks (95 % CI)", xlabel="score")
    ax1.legend(fontsize=7)
    ax1.grid(alpha=0.3)
    taus = np.array(overall["taus"])
    for algo, prof in overall["profiles"].items():
        ax2.plot(taus, prof["profile"], color=colors[algo], label=algo.upper())
        ax2.fill_between(taus, prof["lower"], prof["upper"], color=colors[algo], alpha=0.2)
    ax2.set(title="performance profile", xlabel="τ (return / classical return)",
            ylabel="fraction of runs with score > τ")
    ax2.legend(fontsize=7)
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(folder / "aggregate.png", dpi=100)
    plt.close(fig)


def render(results: dict[str, Any], report: Path, folder: Path, algos: list[str]) -> None:
    """Write the page and its plots from the results file's contents."""
    summary = summarize(results, algos)
    plot(results, summary, folder)
    rel = Path(os.path.relpath(folder, report.parent))
    overall = summary["overall"]
    runs = [e for e in results["evaluations"] if "seed" in e]
    train_s = sum(e.get("wall_time_s") or 0.0 for e in runs)
    lines = [
        "# Results",
        "",
        "SAC, TD3 and PPO (stable-baselines3 through rl-zoo3, with the hyperparameter files of "
        f"`agents/hyperparams/`) trained with {overall['seeds']} seeds on every task, against "
        "each task's classical controller (LQR; on Balance an energy swing-up handing over to "
        "LQR), zero torque and random actions.",
        "",
        f"Every agent (final model, deterministic actions) and baseline plays the same "
        f"{results['episodes']} episodes, `env.reset(seed=s)` for s = 0 … "
        f"{results['episodes'] - 1}. A run's score is its mean return over them and its "
        "success rate (`info[\"is_success\"]` at the last step). Intervals are 95 % "
        "stratified-bootstrap confidence intervals over the seeds (rliable); IQM is the "
        "interquartile mean over the seeds.",
        "",
        "Regenerate with `make results` (it trains every run, two at a time, then runs "
        "`roller-gym results`); render this page again from the committed results file with "
        "`roller-gym results --render`. "
        f"Measured {results['date'][:10]} on {results['machine'].split(',')[0]} with "
        f"{results['machine'].split(',')[1].strip()}: the {len(runs)} training runs took "
        f"{train_s / 3600:.1f} h of process time"
        + (f" ({results['train_wall_s'] / 3600:.1f} h of wall time, two at a time)"
           if results.get("train_wall_s") else "")
        + f", the evaluation {results['evaluation_s'] / 60:.0f} min. "
        "Versions: " + ", ".join(f"{k} {v}" for k, v in results["versions"].items() if v) + ".",
        "",
        "## Over all tasks",
        "",
        "Returns divided by the classical controller's return on the same task (1.0: as good "
        "as the classical controller).",
        "",
        "| algorithm | return / classical, IQM | success, IQM | P(better than classical) |",
        "|---|---:|---:|---:|",
    ]
    for algo in overall["normalized_iqm"]:
        lines.append(f"| {algo.upper()} | {_fmt(overall['normalized_iqm'][algo], digits=3)} "
                     f"| {_fmt(overall['success_iqm'][algo], pct=True)} "
                     f"| {_fmt(overall['poi_vs_classical'][algo], pct=True)} |")
    lines += ["", f"![IQM and performance profiles]({rel / 'aggregate.png'})", ""]
    for task, row in summary["tasks"].items():
        meta = results["tasks"][task]
        met, sentence = target(row)
        lines += [f"## {task}", "",
                  f"Reward threshold {meta['reward_threshold']:.1f} (the classical controller's "
                  "return less 5 %). SAC's targets: " + sentence + ".", "",
                  "| policy | return, IQM [95 % CI] | success, IQM [95 % CI] | P(return > "
                  "classical) | steps to the threshold, median [95 % CI] | per seed: return "
                  "(success) |",
                  "|---|---:|---:|---:|---|---|"]
        for algo, a in row["algos"].items():
            per_seed = ", ".join(f"{r:.1f} ({x:.0%})"
                                 for r, x in zip(a["returns"], a["success"], strict=True))
            lines.append(
                f"| {algo.upper()} | {_fmt(a['return_iqm'])} | {_fmt(a['success_iqm'], True)} "
                f"| {_fmt(a['poi_vs_classical'], True)} "
                f"| {_steps(a['steps_median'], a['steps_to_threshold'])} "
                f"| {per_seed} |")
        for name, b in row["baselines"].items():
            label = meta["classical"] if name == "classical" else BASELINE_LABELS[name]
            lines.append(f"| {label} | {b['return_mean']:.1f} | {b['success_rate']:.0%} | – "
                         "| – | – |")
        lines.append("")
        if met is False:
            sac = row["algos"]["sac"]
            short = [(seed, ret, x, err) for seed, ret, x, err in zip(
                sac["seeds"], sac["returns"], sac["success"], sac["final_error"], strict=True)
                if x < SUCCESS_TARGET]
            lines += ["SAC's seeds below the success target: " + "; ".join(
                f"seed {seed}: return {ret:.1f}, success {x:.0%}, mean final |error| "
                f"{err:.3f} rad" for seed, ret, x, err in short)
                + f" (the success band is ±{meta.get('success_band', float('nan')):.3g} rad).", ""]
    lines += ["## Learning curves", "",
              "The periodic evaluations during training (10 episodes each, deterministic "
              "actions): the IQM over seeds and its 95 % interval.", "",
              f"![learning curves]({rel / 'learning-curves.png'})", ""]
    notes = folder / "notes.md"  # written by hand: what the numbers mean
    if notes.is_file():
        lines += [notes.read_text().rstrip(), ""]
    report.parent.mkdir(parents=True, exist_ok=True)
    report.write_text("\n".join(lines))


def main(argv: list[str] | None = None) -> None:
    args = build_parser().parse_args(argv)
    import matplotlib  # the extra's packages: missing, say so before evaluating
    from roller_gym.agents import stats  # noqa: F401 (rliable)

    matplotlib.use("Agg")
    path = Path(args.results)
    output_folder(path.parent, "--results")
    output_folder(Path(args.report).parent, "--report")
    if args.render:
        if not path.is_file():
            raise SystemExit(f"--results {str(path)!r}: no such file (run without --render to "
                             "measure it)")
        results = json.loads(path.read_text())
    else:
        results = measure(args)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(results, indent=1) + "\n")
        print(f"wrote {path}")
    stage("results", f"rendering {args.report} and its plots (rliable's bootstrap intervals)")
    render(results, Path(args.report), path.parent, args.algos)
    print(f"wrote {args.report} and the plots in {path.parent}/")


if __name__ == "__main__":
    main()
