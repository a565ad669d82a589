"""Results over training seeds: evaluate every trained agent of a task, aggregate, write a page.

    roller-gym results --runs runs/results/RollerHold-v2 --env roller_gym/RollerHold-v2
    roller-gym results --render-only                  # the page again from the stored files
    roller-gym results --calibrate                    # the reward thresholds, on their seeds

``make results TASKS="<task ID> ..."`` trains SAC, TD3 and PPO with five seeds on each task in
turn (``roller-gym train --seed S``, two processes at a time) and runs the first line for it:
one task is one piece of the suite, rerun on its own. Read top to bottom:

1. **Find** every rl-zoo3 experiment under ``--runs`` (any depth) of each algorithm and task.
2. **Calibrate** the task's reward threshold: the classical controller's mean return on the
   calibration episodes (``env.reset(seed=s)``, s = 10000 … 10099, :data:`CALIBRATION_SEEDS`)
   less 5 %, on seeds apart from the evaluation's (``--calibrate`` prints it for every task).
3. **Evaluate** each trained agent (its final model, acting deterministically) and the
   baselines (the classical controller, zero torque, random actions) on the same episodes,
   ``env.reset(seed=s)`` for s < ``--episodes``: each episode's return, success and final
   |position error|. The periodic evaluations rl-zoo3 made during training
   (``evaluations.npz``: each episode's return and, from ``info["is_success"]``, success)
   are kept for the learning curves, the sustained crossing and the last evaluations'
   success.
4. **Save** the task's record to ``<--out>/tasks/<task>.json`` (with the machine, versions,
   command, seeds), replacing that task's earlier one; with ``--keep-stored``, the earlier
   one's runs of the algorithms not in ``--algos`` stay, marked with the date they were
   measured (a round retrained one algorithm at a time).
5. **Render** the page from every task file under ``--out``
   (:mod:`roller_gym.scripts.results_page`): ``<--out>/summary.json``, the figures, and
   ``--report``.
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
from roller_gym import file_name
from roller_gym.agents.hyperparams import ALGOS
from roller_gym.agents.policies import (
    baseline,
    baselines_for,
    evaluation_env,
    load_policy,
    read_config,
)
from roller_gym.bench.records import package_versions
from roller_gym.scripts import results_page
from roller_gym.scripts.arguments import (
    at_least,
    output_file,
    output_folder,
    program_parser,
    real_in,
    stage,
)
from roller_gym.scripts.evaluate import RETURN_TOLERANCE, classical_label, evaluate
from roller_gym.task import get_task

#: The episodes that calibrate the reward thresholds: apart from the evaluation's (0 … 99).
CALIBRATION_SEEDS = range(10_000, 10_100)


def build_parser() -> argparse.ArgumentParser:
    p = program_parser("results", __doc__)
    p.add_argument("--runs", default="runs/results", metavar="LOG_FOLDER",
                   help="where the training runs are (searched at any depth for rl-zoo3 "
                        "experiments <algo>/<env name>_<N>; default runs/results)")
    p.add_argument("--env", nargs="+", default=list(roller_gym.ENV_IDS),
                   choices=roller_gym.ENV_IDS, help="the tasks to measure (default: all)")
    p.add_argument("--algos", nargs="+", default=list(ALGOS), choices=ALGOS,
                   help="the algorithms (default: sac td3 ppo)")
    p.add_argument("--episodes", type=at_least(1), default=100,
                   help="evaluation episodes per agent, seeds 0 … episodes − 1 (default 100)")
    p.add_argument("--workers", type=at_least(1), default=2,
                   help="evaluation processes (default 2)")
    p.add_argument("--out", default="docs/results",
                   help="the results folder: the task files go to <out>/tasks/, the summary "
                        "and the figures to <out>/ (default docs/results)")
    p.add_argument("--report", default="docs/RESULTS.md",
                   help="the page to write (default docs/RESULTS.md)")
    p.add_argument("--train-wall-s", type=real_in(0.0, 1e9), default=None,
                   help="the wall time [s] the task's trainings took, for the page (make "
                        "results passes it)")
    p.add_argument("--keep-stored", action="store_true",
                   help="keep the runs of the algorithms not in --algos from the task's stored "
                        "file under --out, evaluating only --algos' runs anew (a round retrained "
                        "one algorithm at a time); refused unless the stored file has the same "
                        "reward threshold, baselines, episodes and package versions")
    p.add_argument("--render-only", "--render", action="store_true", dest="render_only",
                   help="only render the page from the task files under --out (no evaluation)")
    p.add_argument("--calibrate", action="store_true",
                   help="only print each --env task's reward threshold calibrated on the "
                        f"seeds {CALIBRATION_SEEDS.start}–{CALIBRATION_SEEDS.stop - 1} (the "
                        "classical controller's mean return less 5 %%), beside the registered "
                        "one")
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


# -- 2. calibrate ----------------------------------------------------------------------------


def calibrate(env_id: str, seeds: range = CALIBRATION_SEEDS) -> dict[str, Any]:
    """The task's reward threshold: the classical controller's mean return on the episodes
    ``env.reset(seed=s)`` for s in ``seeds``, less :data:`RETURN_TOLERANCE` of it."""
    env = gym.make(env_id)
    metrics = evaluate(env, baseline("classical", env, seed=0), len(seeds), seeds.start)
    env.close()
    mean = metrics["return_mean"]
    return {"value": mean - RETURN_TOLERANCE * abs(mean), "classical_return": mean,
            "calibration_seeds": [seeds.start, seeds.stop - 1],
            "registered": gym.spec(env_id).reward_threshold}


# -- 3. evaluate -----------------------------------------------------------------------------


def _evaluate_job(job: tuple[str, str, str | None, int]) -> dict[str, Any]:
    """One agent or baseline on the task's seeded episodes (run in a worker process)."""
    import torch

    torch.set_num_threads(1)
    env_id, name, run_dir, episodes = job
    start = time.perf_counter()
    if name == "calibration":
        return {"name": name, **calibrate(env_id)}
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
                            "returns": data["results"].tolist(),
                            # SB3's EvalCallback: info["is_success"] at each episode's end
                            "successes": (data["successes"].astype(bool).tolist()
                                          if "successes" in data else None)}
    env.close()
    out.pop("trajectory", None)
    out["evaluation_s"] = time.perf_counter() - start
    print(f"{env_id:28s} {name:10s} seed {out.get('seed', '-')!s:>3s}: return "
          f"{out['return_mean']:7.1f}, success {out['success_rate']:4.0%} "
          f"({out['evaluation_s']:.0f} s)", flush=True)
    return out


def measure(args: argparse.Namespace, env_id: str) -> dict[str, Any]:
    """Calibrate the task's threshold, evaluate its runs and baselines: its task file."""
    stage("results", f"{env_id}: finding the runs under {args.runs}")
    runs = [(env_id, algo, str(d), args.episodes) for algo in args.algos
            for d in find_runs(args.runs, algo, env_id)]
    if not runs:
        raise SystemExit(f"--runs {args.runs!r}: no trained runs of {env_id} found (train with "
                         "roller-gym train --log-folder ...)")
    jobs = [(env_id, "calibration", None, 0),
            *((env_id, name, None, args.episodes) for name in baselines_for(env_id)), *runs]
    stage("results", f"{env_id}: calibrating the reward threshold on seeds "
                     f"{CALIBRATION_SEEDS.start}–{CALIBRATION_SEEDS.stop - 1}, evaluating "
                     f"{len(runs)} runs and {len(baselines_for(env_id))} baselines on "
                     f"{args.episodes} episodes each, {args.workers} processes at a time (a "
                     "line per agent as it finishes)")
    start = time.perf_counter()
    with multiprocessing.get_context("spawn").Pool(args.workers) as pool:
        threshold, *evaluations = pool.map(_evaluate_job, jobs, chunksize=1)
    threshold.pop("name")
    task = get_task(env_id)
    return {
        "format": results_page.FORMAT,
        "task": env_id,
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "command": args.command,
        "machine": f"{platform.machine()}, {os.cpu_count()} CPU cores, {platform.platform()}",
        "versions": package_versions(("roller-gym", "gymnasium", "stable-baselines3",
                                      "rl_zoo3", "torch", "numpy")),
        "episodes": args.episodes,
        "evaluation_seeds": [0, args.episodes - 1],
        "reward_threshold": threshold,
        "classical": classical_label(env_id),
        "tier": task.tier,
        "success_band": task.success_band if "success_band" in task.parameters else None,
        "evaluation_s": time.perf_counter() - start,
        "train_wall_s": args.train_wall_s,
        "evaluations": evaluations,
    }


def keep_stored(record: dict[str, Any], stored: dict[str, Any], algos: list[str],
                where: Path) -> dict[str, Any]:
    """``record`` with the runs of the algorithms not in ``algos`` taken from ``stored``, the
    task's earlier file (at ``where``), each with the date it was measured (``record["kept"]``:
    algorithm -> date). Refused unless both measure the same thing: the same episodes, reward
    threshold, baselines' scores and package versions."""
    def baselines(r: dict[str, Any]) -> dict[str, tuple[float, float]]:
        return {e["name"]: (e["return_mean"], e["success_rate"])
                for e in r["evaluations"] if "seed" not in e}

    for what, get in (("format", lambda r: r["format"]),
                      ("episodes", lambda r: (r["episodes"], r["evaluation_seeds"])),
                      ("reward threshold", lambda r: r["reward_threshold"]),
                      ("baselines' returns and successes", baselines),
                      ("package versions", lambda r: r["versions"])):
        if get(stored) != get(record):
            raise SystemExit(f"--keep-stored: {where} has other {what} than this evaluation "
                             f"({get(stored)!r} against {get(record)!r}), so its runs are not "
                             "comparable; evaluate every algorithm's runs anew (without "
                             "--keep-stored)")
    kept = [e for e in stored["evaluations"] if "seed" in e and e["name"] not in algos]
    if not kept:
        raise SystemExit(f"--keep-stored: {where} has no runs of an algorithm other than "
                         f"{' '.join(algos)} to keep")
    earlier = stored.get("kept", {})
    return {**record, "evaluations": record["evaluations"] + kept,
            "kept": {e["name"]: earlier.get(e["name"], stored["date"]) for e in kept}}


def main(argv: list[str] | None = None) -> None:
    args = build_parser().parse_args(argv)
    # what was run, for the task file (roller-gym's own main passes the arguments after
    # the command; sys.argv then still holds the command's name)
    args.command = "roller-gym results " + " ".join(sys.argv[1:] if argv is None else argv)
    import matplotlib  # the extra's packages: missing, say so before evaluating
    from roller_gym.agents import stats  # noqa: F401 (rliable)

    matplotlib.use("Agg")
    if args.calibrate:
        for env_id in args.env:
            t = calibrate(env_id)
            print(f"{env_id:32s} reward threshold {t['value']:7.1f} (classical return "
                  f"{t['classical_return']:.1f} on seeds {t['calibration_seeds'][0]}–"
                  f"{t['calibration_seeds'][1]}); registered {t['registered']}", flush=True)
        return
    out = output_folder(args.out, "--out")
    output_file(args.report, "--report")
    if not args.render_only:
        for env_id in args.env:
            path = results_page.task_files(out) / f"{file_name(env_id)}.json"
            if args.keep_stored and not path.is_file():
                raise SystemExit(f"--keep-stored: no stored file {path} of {env_id} to keep "
                                 "runs from")
            # read before the evaluation, which takes long, so that a bad file ends it first
            stored = results_page.read_task_file(path) if args.keep_stored else None
            record = measure(args, env_id)
            if stored is not None:
                record = keep_stored(record, stored, args.algos, path)
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(json.dumps(record, indent=1) + "\n")
            print(f"wrote {path}")
    stage("results", f"rendering {args.report} and its plots from the task files under "
                     f"{results_page.task_files(out)}/")
    results_page.render(out, Path(args.report))
    print(f"wrote {args.report}, {out / 'summary.json'} and the plots in {out}/")


if __name__ == "__main__":
    main()
