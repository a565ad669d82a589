"""The results page (``docs/RESULTS.md``) from the per-task results files of ``roller-gym results``.

Three steps, each reading only the previous one's output:

1. :func:`load`: the per-task files (``<folder>/tasks/<task>.json``; what one holds:
   :mod:`roller_gym.scripts.results`), whichever exist.
2. :func:`summarize`: every number the page shows, computed from them (rliable's statistics,
   :mod:`roller_gym.agents.stats`) into one JSON-able dict, written beside them as
   ``summary.json``. Deterministic: the same files give the same summary, byte for byte.
3. :func:`page` and :func:`plot`: the Markdown text and the figures from the summary alone.
   No number on the page is typed here: the targets, the confidence, the seeds and the
   notes come from the summary.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from roller_gym import file_name
from roller_gym.scripts.evaluate import (
    BASELINE_LABELS,
    RETURN_TOLERANCE,
    SEED_SUCCESS_FLOOR,
    SUCCESS_TARGET,
)
from roller_gym.task import TIERS

#: The per-task files' layout version; :func:`load` reads this one only.
FORMAT = 2
#: The entries every task file has (``roller-gym results`` writes them; "kept" is optional).
RECORD_KEYS = ("format", "task", "date", "command", "machine", "versions", "episodes",
               "evaluation_seeds", "reward_threshold", "classical", "tier", "success_band",
               "evaluation_s", "train_wall_s", "evaluations")
#: The algorithms in the order the page lists them.
ALGO_ORDER = ("sac", "td3", "ppo")
#: The training evaluations whose success is shown beside the final model's.
LAST_EVALUATIONS = 3


def task_files(folder: Path) -> Path:
    """The folder of the per-task results files under ``folder``."""
    return Path(folder) / "tasks"


def load(folder: Path) -> list[dict[str, Any]]:
    """Every per-task results file under ``folder``, in the order of the registry (a task's
    earlier versions too: :func:`latest` picks what the page aggregates)."""
    import roller_gym

    records = []
    # by task name, whatever its version (a page may hold results of an earlier version)
    order = {_version(env_id)[0]: i for i, env_id in enumerate(roller_gym.ENV_IDS)}
    for path in sorted(task_files(folder).glob("*.json"),
                       key=lambda p: (order.get(_version(p.stem)[0], len(order)), p.stem)):
        records.append(read_task_file(path))
    return records


def read_task_file(path: Path) -> dict[str, Any]:
    """One task's results file, read and checked to be of this :data:`FORMAT` (SystemExit
    naming the file otherwise)."""
    try:
        record = json.loads(Path(path).read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise SystemExit(f"{path}: not a readable results file ({exc}); measure the task "
                         "again with roller-gym results --env ...") from None
    found = record.get("format") if isinstance(record, dict) else type(record).__name__
    if found != FORMAT:
        raise SystemExit(f"{path}: format {found!r}, not {FORMAT}; measure the task again with "
                         "roller-gym results --env ...")
    missing = [key for key in RECORD_KEYS if key not in record]
    if missing:
        raise SystemExit(f"{path}: a results file without {', '.join(missing)}; measure the "
                         "task again with roller-gym results --env ...")
    return record


def _version(task: str) -> tuple[str, int]:
    """(name, version) of a task ID (``roller_gym/RollerHold-v2`` -> ("RollerHold", 2))."""
    name, version = file_name(task).rsplit("-v", 1)
    return name, int(version)


def latest(records: list[dict[str, Any]]) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """The records of each task's latest version measured, and those of the earlier versions
    they supersede (a new version changes the reward or the dynamics: the page compares
    algorithms on the latest only)."""
    newest: dict[str, int] = {}
    for r in records:
        name, version = _version(r["task"])
        newest[name] = max(version, newest.get(name, version))
    latest_ids = set(newest.items())
    current = [r for r in records if _version(r["task"]) in latest_ids]
    return current, [r for r in records if _version(r["task"]) not in latest_ids]


def _iv(values: tuple[float, float, float]) -> list[float | None]:
    """An interval as JSON: inf (never) as None."""
    return [float(v) if math.isfinite(v) else None for v in values]


def _last_successes(curve: dict[str, Any] | None) -> list[float] | None:
    """The success rates of the last training evaluations (None where not logged)."""
    if not curve or not curve.get("successes"):
        return None
    return [float(np.mean(s)) for s in curve["successes"][-LAST_EVALUATIONS:]]


def _task_summary(record: dict[str, Any], targets: dict[str, float]) -> dict[str, Any]:
    from roller_gym.agents import stats

    threshold = record["reward_threshold"]["value"]
    by: dict[str, list[dict[str, Any]]] = {}
    for e in record["evaluations"]:
        by.setdefault(e["name"], []).append(e)
    classical = by["classical"][0]["return_mean"]
    runs = [e for e in record["evaluations"] if "seed" in e]
    row: dict[str, Any] = {
        "tier": record["tier"], "date": record["date"][:10], "machine": record["machine"],
        "versions": record["versions"], "command": record["command"],
        "episodes": record["episodes"], "evaluation_seeds": record["evaluation_seeds"],
        "threshold": record["reward_threshold"], "classical": record["classical"],
        "success_band": record["success_band"], "runs": len(runs),
        "kept": {a: d[:10] for a, d in record.get("kept", {}).items()},
        "train_process_h": sum(e.get("wall_time_s") or 0.0 for e in runs) / 3600,
        "train_wall_h": (record["train_wall_s"] / 3600 if record.get("train_wall_s")
                         else None),
        "evaluation_process_min": sum(e.get("evaluation_s") or 0.0
                                      for e in record["evaluations"]) / 60,
        "baselines": {n: {"label": record["classical"] if n == "classical"
                          else BASELINE_LABELS[n], "return": by[n][0]["return_mean"],
                          "success": by[n][0]["success_rate"]}
                      for n in ("classical", *BASELINE_LABELS) if n in by},
        "algos": {}, "pairs": [],
    }
    for algo in [a for a in ALGO_ORDER if a in by]:
        seeds = sorted(by[algo], key=lambda e: e["seed"])
        returns = np.array([e["return_mean"] for e in seeds])
        success = np.array([e["success_rate"] for e in seeds])
        steps = np.array([stats.steps_to_threshold(e["curve"]["timesteps"],
                                                   e["curve"]["returns"], threshold)
                          if e.get("curve") else math.nan for e in seeds])
        per_seed = [{"seed": e["seed"], "return": e["return_mean"], "success": e["success_rate"],
                     "last_successes": _last_successes(e.get("curve")),
                     "final_error": e["final_error_mean"],
                     "steps": float(s) if math.isfinite(s) else None,
                     "success_ok": e["success_rate"] >= targets["seed_success_floor"],
                     "return_ok": e["return_mean"] >= threshold}
                    for e, s in zip(seeds, steps, strict=True)]
        a = {"return_iqm": _iv(stats.interval(returns)),
             "success_iqm": _iv(stats.interval(success)),
             "poi_vs_classical": _iv(stats.probability_of_improvement(returns, [classical])),
             "seeds": per_seed, "curves": int(np.sum(~np.isnan(steps))),
             "sustained": int(np.sum(np.isfinite(steps)))}
        curved = steps[~np.isnan(steps)]
        a["steps_median"] = (_iv(stats.interval(curved, statistic=stats.median_batch))
                             if curved.size else None)
        a["success_met"] = (all(s["success_ok"] for s in per_seed)
                            and a["success_iqm"][0] >= targets["success_iqm"])
        a["return_met"] = all(s["return_ok"] for s in per_seed) and a["return_iqm"][1] >= threshold
        a["curve"] = _curve_band([e["curve"] for e in seeds if e.get("curve")])
        row["algos"][algo] = a
    names = list(row["algos"])
    for i, x in enumerate(names):
        for y in names[i + 1:]:
            row["pairs"].append({"a": x, "b": y, "poi": _iv(stats.probability_of_improvement(
                [s["return"] for s in row["algos"][x]["seeds"]],
                [s["return"] for s in row["algos"][y]["seeds"]]))})
    return row


def _curve_band(curves: list[dict[str, Any]]) -> dict[str, list[float]] | None:
    """The IQM over seeds of each periodic evaluation's mean return, with its interval."""
    from roller_gym.agents import stats

    if not curves:
        return None
    n = min(len(c["timesteps"]) for c in curves)
    means = np.array([np.mean(np.asarray(c["returns"][:n], dtype=float), axis=1)
                      for c in curves])
    band = np.array([stats.interval(means[:, j]) for j in range(n)])
    return {"timesteps": curves[0]["timesteps"][:n], "iqm": band[:, 0].tolist(),
            "lower": band[:, 1].tolist(), "upper": band[:, 2].tolist(),
            "episodes": len(curves[0]["returns"][0])}


def _pair(a: str, b: str, poi: tuple[float, float, float]) -> dict[str, Any]:
    """P(a > b) with its interval, and whether they differ: the interval excludes one half."""
    return {"a": a, "b": b, "poi": _iv(poi), "differs": bool(poi[1] > 0.5 or poi[2] < 0.5)}


def _overall(tasks: dict[str, dict[str, Any]]) -> dict[str, Any] | None:
    """Over the tasks where every algorithm has runs: returns normalized by the classical
    controller's, success, and the probabilities of improvement."""
    from roller_gym.agents import stats

    algos = [a for a in ALGO_ORDER if all(a in t["algos"] for t in tasks.values())]
    if not tasks or not algos:
        return None
    names = list(tasks)
    seeds = min(len(tasks[t]["algos"][a]["seeds"]) for a in algos for t in names)

    def matrix(algo: str, key: str, scale: bool = False) -> np.ndarray:
        return np.array([[tasks[t]["algos"][algo]["seeds"][i][key]
                          / (tasks[t]["baselines"]["classical"]["return"] if scale else 1.0)
                          for t in names] for i in range(seeds)])

    norm = {a: matrix(a, "return", scale=True) for a in algos}
    # up to the best run's score (a tier whose agents pass the classical controller), at least 1.1
    top = max(1.1, math.ceil(10 * max(float(s.max()) for s in norm.values())) / 10)
    taus = np.linspace(0.0, top, 45)
    return {
        "tasks": names, "seeds": seeds,
        "normalized_iqm": {a: _iv(stats.interval(s)) for a, s in norm.items()},
        "success_iqm": {a: _iv(stats.interval(matrix(a, "success"))) for a in algos},
        "poi_vs_classical": {a: _iv(stats.probability_of_improvement(s, np.ones((1, len(names)))))
                             for a, s in norm.items()},
        "pairs": [_pair(x, y, stats.probability_of_improvement(norm[x], norm[y]))
                  for i, x in enumerate(algos) for y in algos[i + 1:]],
        "taus": taus.tolist(), "profiles": stats.performance_profile(norm, taus),
    }


def summarize(records: list[dict[str, Any]]) -> dict[str, Any]:
    """Every number the page shows, from the per-task records (of each task's latest
    version; the earlier versions' IDs and dates are listed as superseded)."""
    from roller_gym.agents import stats

    targets = {"success_iqm": SUCCESS_TARGET, "seed_success_floor": SEED_SUCCESS_FLOOR,
               "return_tolerance": RETURN_TOLERANCE}
    current, earlier = latest(records)
    tasks = {r["task"]: _task_summary(r, targets) for r in current}
    tiers = {tier: _overall({k: t for k, t in tasks.items() if t["tier"] == tier})
             for tier in TIERS}
    return {"confidence": stats.CONFIDENCE, "reps": stats.REPS, "targets": targets,
            "last_evaluations": LAST_EVALUATIONS, "tasks": tasks,
            "tiers": {tier: o for tier, o in tiers.items() if o is not None},
            "superseded": [{"task": r["task"], "date": r["date"][:10]} for r in earlier]}


# -- the page ----------------------------------------------------------------------------


def _pct(x: float | None) -> str:
    return "–" if x is None else f"{x:.0%}"


def _fmt(iv: list[float | None], pct: bool = False, digits: int = 1) -> str:
    """An estimate and its interval: ``1.0 [0.9, 1.1]`` (or in percent)."""
    f = _pct if pct else (lambda v: f"{v:.{digits}f}")
    return f"{f(iv[0])} [{f(iv[1])}, {f(iv[2])}]"


def _k(steps: float | None) -> str:
    """Training steps in thousands (one decimal below 10k), or "never"."""
    if steps is None:
        return "never"
    return f"{steps / 1000:.{0 if steps >= 10_000 else 1}f}k"


def _seeds(span: list[int] | None) -> str:
    return f"{span[0]}–{span[1]}"


def _verdict(met: bool) -> str:
    return "**met**" if met else "**missed**"


def _targets(algo: str, a: dict[str, Any], threshold: float, t: dict[str, float]) -> str:
    n = len(a["seeds"])
    ok_s = sum(s["success_ok"] for s in a["seeds"])
    ok_r = sum(s["return_ok"] for s in a["seeds"])
    return (f"{algo.upper()}: success {_verdict(a['success_met'])} ({ok_s}/{n} seeds ≥ "
            f"{t['seed_success_floor']:.0%}, IQM {_pct(a['success_iqm'][0])} against ≥ "
            f"{t['success_iqm']:.0%}); return {_verdict(a['return_met'])} ({ok_r}/{n} seeds ≥ "
            f"{threshold:.1f}, the IQM interval's lower end {a['return_iqm'][1]:.1f}).")


def _task_section(task: str, row: dict[str, Any], summary: dict[str, Any]) -> list[str]:
    th = row["threshold"]
    t = summary["targets"]
    ci = f"{summary['confidence']:.0%} CI"
    cal = (f"the classical controller's ({row['classical']}) mean return on the calibration "
           f"seeds {_seeds(th['calibration_seeds'])} ({th['classical_return']:.1f}) less "
           f"{t['return_tolerance']:.0%}; the registered `reward_threshold` is "
           f"{th['registered']:.1f}" if th["calibration_seeds"] else
           "the task's registered `reward_threshold`; this round did not calibrate it on seeds "
           "apart from the evaluation's")
    wall = (f", {row['train_wall_h']:.1f} h of wall time" if row["train_wall_h"] else "")
    if row["kept"]:  # a round retrained one algorithm at a time
        new = [a.upper() for a in row["algos"] if a not in row["kept"]]
        wall += f" for {' and '.join(new)}'s runs" if wall else ""
        dates: dict[str, list[str]] = {}
        for a, d in row["kept"].items():
            dates.setdefault(d, []).append(f"{a.upper()}'s")
        wall += "".join(f"; {' and '.join(a)} runs kept from the measurement of {d}"
                        for d, a in dates.items())
    lines = [
        f"## {task}", "",
        f"Measured {row['date']} on {row['machine']}: {row['runs']} training runs "
        f"({row['train_process_h']:.1f} h of process time{wall}), evaluation "
        f"{row['evaluation_process_min']:.0f} min of process time. Versions: "
        + ", ".join(f"{k} {v}" for k, v in row["versions"].items() if v) + ".", "",
        f"Evaluation seeds {_seeds(row['evaluation_seeds'])} ({row['episodes']} episodes per "
        f"agent). Reward threshold {th['value']:.1f}: {cal}.", "",
        "Targets: " + " ".join(_targets(a, x, th["value"], t) for a, x in row["algos"].items()),
        "",
        f"| policy | return, IQM [{ci}] | success, IQM [{ci}] | P(return > classical) "
        f"| steps to the sustained threshold, median [{ci}] |",
        "|---|---:|---:|---:|---|"]
    for algo, a in row["algos"].items():
        m = a["steps_median"]
        steps = ("–" if m is None else f"{_k(m[0])} [{_k(m[1])}, {_k(m[2])}] "
                 f"({a['sustained']}/{a['curves']} seeds sustained it)")
        lines.append(f"| {algo.upper()} | {_fmt(a['return_iqm'])} | {_fmt(a['success_iqm'], True)}"
                     f" | {_fmt(a['poi_vs_classical'], True)} | {steps} |")
    for b in row["baselines"].values():
        lines.append(f"| {b['label']} | {b['return']:.1f} | {_pct(b['success'])} | – | – |")
    if row["pairs"]:
        lines += ["", f"| | P(return of the first > the second's) [{ci}] |", "|---|---:|"]
        lines += [f"| {p['a'].upper()} vs {p['b'].upper()} | {_fmt(p['poi'], True)} |"
                  for p in row["pairs"]]
    lines += ["", f"Per seed (success of the final model on the evaluation seeds; beside it, of "
                  f"the last {summary['last_evaluations']} periodic evaluations during "
                  "training):", "",
              "| agent | seed | return | success | success, last training evaluations "
              "| mean final \\|position error\\| [rad] | sustained the threshold from | "
              "targets (success, return) |",
              "|---|---:|---:|---:|---|---:|---:|---|"]
    for algo, a in row["algos"].items():
        for s in a["seeds"]:
            last = ("not logged" if s["last_successes"] is None
                    else ", ".join(_pct(x) for x in s["last_successes"]))
            lines.append(f"| {algo.upper()} | {s['seed']} | {s['return']:.1f} "
                         f"| {_pct(s['success'])} | {last} | {s['final_error']:.3f} "
                         f"| {_k(s['steps'])} | {'✓' if s['success_ok'] else '✗'} "
                         f"{'✓' if s['return_ok'] else '✗'} |")
    lines.append("")
    for algo, a in row["algos"].items():
        short = [s for s in a["seeds"] if not s["success_ok"]]
        if short:
            band = (f" (the success band is ±{row['success_band']:.3g} rad)"
                    if row["success_band"] is not None else "")
            lines += [f"{algo.upper()}'s seeds below the success floor of "
                      f"{t['seed_success_floor']:.0%}: " + "; ".join(
                          f"seed {s['seed']}: success {_pct(s['success'])}, return "
                          f"{s['return']:.1f}, mean final |position error| {s['final_error']:.3f}"
                          " rad" for s in short) + band + ".", ""]
    return lines


#: How the page names each tier's aggregate, and what the tier is for.
TIER_TITLES = {
    "base": ("the base tasks", "the classical controller is the reference an agent should "
             "reach"),
    "hard": ("the hard tier", "the classical controller is not the ceiling: what it is for is "
             "to separate the algorithms"),
}


def _figure(tier: str) -> str:
    """The file name of a tier's aggregate figure."""
    return "aggregate.png" if tier == "base" else f"aggregate-{tier}.png"


def _separation(pairs: list[dict[str, Any]], confidence: float) -> str:
    """Which pairs of algorithms the probability of improvement tells apart (its interval
    excludes one half) and which it does not."""
    apart = [p for p in pairs if p["differs"]]
    together = [p for p in pairs if not p["differs"]]

    def names(ps: list[dict[str, Any]]) -> str:
        return ", ".join(f"{p['a'].upper()} and {p['b'].upper()} ({_fmt(p['poi'], True)})"
                         for p in ps)

    if not apart:
        return (f"No pair of algorithms differs here: every {confidence:.0%} interval of "
                "P(A > B) contains one half at this number of seeds.")
    text = (f"These algorithms differ (the {confidence:.0%} interval of P(A > B) excludes one "
            f"half): {names(apart)}.")
    return text + (f" These do not: {names(together)}." if together else "")


def _tier_section(tier: str, overall: dict[str, Any], summary: dict[str, Any],
                  figures: str) -> list[str]:
    """A tier's aggregate over its tasks."""
    title, purpose = TIER_TITLES[tier]
    ci = f"{summary['confidence']:.0%} CI"
    lines = [f"## Over {title}: {', '.join(file_name(t) for t in overall['tasks'])}", "",
             f"Here {purpose}. {overall['seeds']} seeds per algorithm and task; returns "
             "divided by the classical controller's on the same task.", "",
             "| algorithm | return / classical, IQM | success, IQM | P(better than "
             "classical) |", "|---|---:|---:|---:|"]
    lines += [f"| {a.upper()} | {_fmt(overall['normalized_iqm'][a], digits=3)} "
              f"| {_fmt(overall['success_iqm'][a], pct=True)} "
              f"| {_fmt(overall['poi_vs_classical'][a], pct=True)} |"
              for a in overall["normalized_iqm"]]
    lines += ["", f"| | P(A > B) over the tasks [{ci}] |", "|---|---:|"]
    lines += [f"| {p['a'].upper()} vs {p['b'].upper()} | {_fmt(p['poi'], True)} |"
              for p in overall["pairs"]]
    lines += ["", _separation(overall["pairs"], summary["confidence"]), "",
              f"![IQM and performance profiles]({figures}/{_figure(tier)})", ""]
    return lines


def page(summary: dict[str, Any], figures: str) -> str:
    """The Markdown page from the summary; ``figures``: the plots' folder relative to it."""
    t, tasks = summary["targets"], summary["tasks"]
    lines = [
        "# Results", "",
        "SAC, TD3 and PPO (stable-baselines3 through rl-zoo3, with the hyperparameter files of "
        "`agents/hyperparams/`) against each task's classical controller, zero torque and "
        "random actions, on " + ", ".join(f"`{k}`" for k in tasks) + ".", "",
        "- Every agent (final model, deterministic actions) and baseline plays the same "
        "episodes, `env.reset(seed=s)` for the evaluation seeds s of its task's section. A run's "
        "score is its mean return and its success rate (`info[\"is_success\"]` at the last "
        "step).",
        f"- Intervals: {summary['confidence']:.0%} stratified-bootstrap confidence intervals "
        "over the seeds (rliable's method, percentile ends): exact (every distinct resample "
        f"with its probability) where there are at most {summary['reps']} distinct resamples, "
        f"as for one task's seeds, else {summary['reps']} random resamples. IQM: the "
        "interquartile mean over the seeds.",
        f"- Targets, judged on every seed and on the IQM: *success* is met when every seed "
        f"succeeds in at least {t['seed_success_floor']:.0%} of the episodes and the success "
        f"IQM is at least {t['success_iqm']:.0%}; *return* when every seed's mean return and "
        "the lower end of the return IQM's interval reach the reward threshold.",
        "- The reward threshold is the classical controller's mean return less "
        f"{t['return_tolerance']:.0%}, on calibration seeds apart from the evaluation seeds "
        "(each section says which). *Steps to the sustained threshold*: the training step of "
        "the first periodic evaluation from which on every evaluation's mean return reaches "
        "the threshold; a run that falls below it again at the end never sustained it.",
        "- P(A > B), the probability of improvement: the chance that a run of A scores a "
        "higher return than a run of B on the same task (rliable's; ties count one half).",
        "",
        "Regenerate one task with `make results TASKS=\"<task ID>\"` (it trains every seed "
        "and algorithm on it, evaluates them, writes `docs/results/tasks/<task>.json` and "
        "renders this page from every task file there); render the page again from the "
        "stored files with `roller-gym results --render-only`.", ""]
    if summary.get("superseded"):
        lines += ["Results of earlier versions, superseded by the versions above and kept in "
                  "`docs/results/tasks/`: " + ", ".join(
                      f"`{s['task']}` (measured {s['date']})" for s in summary["superseded"])
                  + ".", ""]
    for tier, overall in summary["tiers"].items():
        lines += _tier_section(tier, overall, summary, figures)
    for task, row in tasks.items():
        lines += _task_section(task, row, summary)
    lines += ["## Learning curves", "",
              "The periodic evaluations during training (deterministic actions): the IQM over "
              "seeds of each evaluation's mean return and its interval; dashed, the classical "
              "controller's return; dotted, the reward threshold.", "",
              f"![learning curves]({figures}/learning-curves.png)", ""]
    return "\n".join(lines)


def plot(summary: dict[str, Any], folder: Path) -> None:
    """The learning curves and the aggregate estimates (IQMs, performance profiles)."""
    import matplotlib.pyplot as plt

    tasks = summary["tasks"]
    colors = dict(zip(ALGO_ORDER, ("C0", "C1", "C2"), strict=True))
    fig, axes = plt.subplots(1, max(len(tasks), 1), figsize=(4.2 * max(len(tasks), 1), 3.6),
                             squeeze=False)
    for ax, (task, row) in zip(axes[0], tasks.items(), strict=False):
        for algo, a in row["algos"].items():
            band = a["curve"]
            if band is None:
                continue
            ax.plot(band["timesteps"], band["iqm"], color=colors[algo],
                    label=f"{algo.upper()} (IQM)")
            ax.fill_between(band["timesteps"], band["lower"], band["upper"], color=colors[algo],
                            alpha=0.2)
        ax.axhline(row["baselines"]["classical"]["return"], color="k", linestyle="--",
                   linewidth=1, label=row["classical"])
        ax.axhline(row["threshold"]["value"], color="grey", linestyle=":", linewidth=1,
                   label="reward threshold")
        ax.set(title=task.split("/")[-1], xlabel="training steps", ylabel="evaluation return")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(folder / "learning-curves.png", dpi=100)
    plt.close(fig)

    for tier, overall in summary["tiers"].items():
        _plot_aggregate(overall, summary["confidence"], colors, folder / _figure(tier))


def _plot_aggregate(overall: dict[str, Any], confidence: float, colors: dict[str, str],
                    path: Path) -> None:
    """A tier's IQMs and performance profiles."""
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.6))
    algos = list(overall["normalized_iqm"])
    for i, algo in enumerate(algos):
        for j, (key, label) in enumerate((("normalized_iqm", "return / classical"),
                                          ("success_iqm", "success"))):
            est, lo, hi = overall[key][algo]
            ax1.errorbar(est, i + 0.15 * j, xerr=[[est - lo], [hi - est]], fmt="os"[j],
                         color=colors[algo], label=label if i == 0 else None)
    ax1.set_yticks(range(len(algos)), [a.upper() for a in algos])
    ax1.axvline(1.0, color="k", linewidth=0.5)
    ax1.set(title=f"IQM over seeds and tasks ({confidence:.0%} CI)", xlabel="score")
    ax1.legend(fontsize=7)
    ax1.grid(alpha=0.3)
    for algo, prof in overall["profiles"].items():
        ax2.plot(overall["taus"], prof["profile"], color=colors[algo], label=algo.upper())
        ax2.fill_between(overall["taus"], prof["lower"], prof["upper"], color=colors[algo],
                         alpha=0.2)
    ax2.set(title="performance profile", xlabel="τ (return / classical return)",
            ylabel="fraction of runs with score > τ")
    ax2.legend(fontsize=7)
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def render(folder: Path, report: Path) -> dict[str, Any]:
    """Summarize the task files under ``folder``, write ``summary.json`` and the plots there
    and the page to ``report``; return the summary."""
    import os

    records = load(folder)
    if not records:
        raise SystemExit(f"{task_files(folder)}: no task results files to render (measure one "
                         "with roller-gym results --env ...)")
    summary = summarize(records)
    (Path(folder) / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    plot(summary, Path(folder))
    report.parent.mkdir(parents=True, exist_ok=True)
    report.write_text(page(summary, Path(os.path.relpath(folder, report.parent)).as_posix()))
    return summary
