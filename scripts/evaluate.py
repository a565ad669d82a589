"""Evaluate trained agents and the baselines on the same seeded episodes; tables and plots.

    roller-gym evaluate --env roller_gym/RollerStabilize-v2 \\
        --models runs/sac/roller_gym-RollerStabilize-v2_1
    roller-gym evaluate --env roller_gym/RollerStabilize-v2 roller_gym/RollerHold-v2 \\
        roller_gym/RollerBalance-v2 roller_gym/RollerTrack-v1 \\
        --runs runs --out results --report results/REPORT.md

The trained models are experiment folders of ``roller-gym train`` (or of ``python -m
rl_zoo3.train`` with roller-gym's hyperparameter files): named with --models, or the latest
one of every algorithm in the log folder --runs.

Every policy (each trained model, the classical controller: LQR or the energy swing-up, zero
torque, random actions) plays the episodes ``env.reset(seed=s)`` for s in range(--episodes),
so all face the same start states and targets. Per task it prints and writes (into --out):

* ``evaluation.md``: the tables of all tasks (mean ± std return, success rate, final
  |position error|, mean |τ|, training steps and wall time) and whether the targets are met;
  ``<env>.md`` and ``<env>.json``: one task's table and its numbers;
* ``<env>-learning.png``: the learning curves (periodic evaluations during training)
  against the baselines' mean returns;
* ``<env>-trajectories.png``: episode 0 of every policy, side by side.

``--report`` assembles the tasks' tables, the targets and the plots into one
Markdown file. These are one training seed's results; ``roller-gym results`` (``make
results``) trains several seeds and writes ``docs/RESULTS.md`` with rliable's intervals.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import roller_gym  # registers the tasks
from roller_gym import file_name
from roller_gym.agents.classical import CONTROLLERS
from roller_gym.agents.hyperparams import ALGOS
from roller_gym.agents.policies import (
    BASELINES,
    baseline,
    baselines_for,
    evaluation_env,
    find_run,
    load_policy,
    read_config,
    rollout,
)
from roller_gym.scripts.arguments import (
    at_least,
    output_file,
    output_folder,
    program_parser,
    stage,
)
from roller_gym.task import get_task

#: How the baselines are named in the tables.
BASELINE_LABELS = {"informed": "classical, informed of each episode's scene",
                   "zero": "zero torque", "random": "random"}
#: Target: SAC's mean return within 5 % of the classical controller's below it (a task's
#: reward threshold is the classical controller's mean return less this share).
RETURN_TOLERANCE = 0.05
#: Target: SAC succeeds in at least this share of the episodes (over seeds: the IQM).
SUCCESS_TARGET = 0.95
#: Target over seeds: every seed succeeds in at least this share of the episodes.
SEED_SUCCESS_FLOOR = 0.8


def build_parser() -> argparse.ArgumentParser:
    p = program_parser("evaluate", __doc__)
    p.add_argument("--env", nargs="+", default=["roller_gym/RollerStabilize-v2"],
                   choices=roller_gym.ENV_IDS,
                   help="the task(s) (default roller_gym/RollerStabilize-v2)")
    p.add_argument("--models", nargs="*", default=[],
                   help="experiment folders of roller-gym train to evaluate (one task), e.g. "
                        "runs/sac/roller_gym-RollerStabilize-v2_1")
    p.add_argument("--runs", default=None, metavar="LOG_FOLDER",
                   help="for every task, take the latest experiment of each algorithm in this "
                        "log folder of roller-gym train (<LOG_FOLDER>/<algo>/<env name>_<N>)")
    p.add_argument("--algos", nargs="+", default=list(ALGOS), choices=ALGOS,
                   help="with --runs: the algorithms to take (default: sac td3 ppo)")
    p.add_argument("--baselines", nargs="*", default=None, choices=BASELINES,
                   help="baselines to compare (default: classical zero random, and informed "
                        "where the task's scene varies unobserved)")
    p.add_argument("--episodes", type=at_least(1), default=100,
                   help="episodes per policy (default 100)")
    p.add_argument("--best", action="store_true",
                   help="evaluate best_model.zip (best periodic evaluation) instead of the final "
                        "model")
    p.add_argument("--out", default="results", help="output directory (default results)")
    p.add_argument("--report", default=None, help="also write this Markdown report")
    p.add_argument("--notes", default=None, help="Markdown appended to the report as its notes")
    return p


def evaluate(env: gym.Env, policy: Any, episodes: int, first_seed: int = 0) -> dict[str, Any]:
    """The metrics of ``policy`` over the episodes reset with seeds first_seed ..
    first_seed + episodes − 1, and each episode's return, success and final |position
    error| [rad]."""
    returns, successes, final_errors, torques, terminated = [], [], [], [], 0
    first = None
    for seed in range(first_seed, first_seed + episodes):
        ep = rollout(env, policy, seed)
        first = ep if first is None else first
        returns.append(ep.total_return)
        successes.append(ep.success)
        final_errors.append(abs(ep.error[-1]))
        torques.append(np.abs(ep.torque))
        terminated += ep.terminated
    return {
        "return_mean": float(np.mean(returns)),
        "return_std": float(np.std(returns)),
        "success_rate": float(np.mean(successes)),
        "final_error_mean": float(np.mean(final_errors)),
        "torque_mean": float(np.mean(np.concatenate(torques))),
        "terminated": int(terminated),
        "episodes": episodes,
        "returns": [float(r) for r in returns],
        "successes": [bool(x) for x in successes],
        "final_errors": [float(x) for x in final_errors],
        "trajectory": {"time": first.time.tolist(), "phi": first.phi.tolist(),
                       "phi_dot": first.phi_dot.tolist(), "torque": first.torque.tolist(),
                       "target_phi": first.target_phi, "terminated": first.terminated},
    }


def classical_label(env_id: str) -> str:
    """The name of the task's classical controller in the tables."""
    return CONTROLLERS[get_task(env_id).classical][1]


def markdown_table(rows: list[dict[str, Any]]) -> str:
    lines = [
        "| policy | training steps | wall time | return (mean ± std) | success | "
        "final \\|error\\| [rad] | mean \\|τ\\| [N·m] |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        steps = f"{r['steps']:,}" if r.get("steps") else "–"
        wall = f"{r['wall_time_s'] / 60:.1f} min" if r.get("wall_time_s") else "–"
        lines.append(
            f"| {r['label']} | {steps} | {wall} | {r['return_mean']:.1f} ± {r['return_std']:.1f}"
            f" | {100 * r['success_rate']:.0f}% | {r['final_error_mean']:.3f} "
            f"| {r['torque_mean']:.3f} |"
        )
    return "\n".join(lines)


def target_check(env_id: str, rows: list[dict[str, Any]]) -> tuple[str, bool | None]:
    """The sentence on the target for this task, and whether it is met (None: no SAC)."""
    by_name = {r["name"]: r for r in rows}
    sac, classical = by_name.get("sac"), by_name.get("classical")
    if sac is None:
        return "Target: not checked (no SAC run evaluated).", None
    if classical is None:
        return "Target: not checked (no classical controller evaluated).", None
    bound = classical["return_mean"] - RETURN_TOLERANCE * abs(classical["return_mean"])
    met = sac["return_mean"] >= bound and sac["success_rate"] >= SUCCESS_TARGET
    return (f"Target: SAC succeeds in at least {SUCCESS_TARGET:.0%} of the episodes and its "
            f"mean return is at least the classical controller's − {RETURN_TOLERANCE:.0%} "
            f"= {bound:.1f}: **{'met' if met else 'missed'}** (SAC: "
            f"{sac['success_rate']:.0%}, {sac['return_mean']:.1f}; "
            f"{classical['label']}: {classical['return_mean']:.1f}).", met)


def plot_learning_curves(env_id: str, rows: list[dict[str, Any]], path: Path) -> None:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    for r in rows:
        if r.get("run_dir") and (Path(r["run_dir"]) / "evaluations.npz").is_file():
            data = np.load(Path(r["run_dir"]) / "evaluations.npz")
            mean, std = data["results"].mean(axis=1), data["results"].std(axis=1)
            ax.plot(data["timesteps"], mean, label=r["label"])
            ax.fill_between(data["timesteps"], mean - std, mean + std, alpha=0.2)
    for r, style in zip([r for r in rows if not r.get("run_dir")], ["--", ":", "-."],
                        strict=False):
        ax.axhline(r["return_mean"], color="k", linestyle=style, linewidth=1, label=r["label"])
    ax.set(xlabel="environment steps", ylabel="episode return (evaluation)",
           title=f"{env_id}: learning curves")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_trajectories(env_id: str, rows: list[dict[str, Any]], path: Path) -> None:
    import matplotlib.pyplot as plt

    quantities = [("phi", "φ [rad] (dashed: target)"), ("phi_dot", "φ' [rad/s]"),
                  ("torque", "τ [N·m]")]
    targets = [1.0, -1.0] if get_task(env_id).symmetric_target else [1.0]  # ±φ* both count
    fig, axes = plt.subplots(len(quantities), len(rows), sharex=True, sharey="row",
                             figsize=(2.6 * len(rows), 6.5), squeeze=False)
    for j, r in enumerate(rows):
        traj = r["trajectory"]
        for i, (key, label) in enumerate(quantities):
            ax = axes[i, j]
            ax.plot(traj["time"], traj[key], linewidth=1.2)
            ax.axhline(0.0, color="k", linewidth=0.5)
            if key == "phi":
                for sign in targets:
                    ax.axhline(sign * traj["target_phi"], color="g", linestyle="--",
                               linewidth=1)
            ax.grid(alpha=0.3)
            if j == 0:
                ax.set_ylabel(label)
        ended = f"\n(terminated at {traj['time'][-1]:.2f} s)" if traj["terminated"] else ""
        axes[0, j].set_title(r["label"] + ended, fontsize=9)
        axes[-1, j].set_xlabel("time [s]")
    fig.suptitle(f"{env_id}: episode 0 (seed 0) of each policy")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> None:
    parser = build_parser()
    args = parser.parse_args(argv)
    import matplotlib  # the plots extra: missing, say so first

    if args.notes is not None and not Path(args.notes).is_file():
        parser.error(f"--notes {args.notes!r}: no such file; it must be an existing Markdown "
                     "file (or leave --notes out for a report without notes)")
    if args.notes is not None and args.report is None:
        parser.error(f"--notes {args.notes!r} needs --report: the notes are appended to it")
    if args.runs is not None and not Path(args.runs).is_dir():
        parser.error(f"--runs {args.runs!r}: no such folder; it must be the log folder of "
                     "roller-gym train (or leave --runs out to evaluate the baselines only)")
    matplotlib.use("Agg")  # files only, no window
    out = output_folder(args.out, "--out")
    if args.report is not None:
        output_file(args.report, "--report")
    if args.models and len(args.env) > 1:
        raise SystemExit("--models names runs of one task; use --runs for several tasks")
    sections = []
    for env_id in args.env:
        # -- the policies: trained models, then the baselines -------------------------------
        run_dirs = [Path(m) for m in args.models]
        if args.runs:
            found = [find_run(args.runs, algo, env_id) for algo in args.algos]
            run_dirs += [d for d in found if d is not None]
        try:
            configs = [read_config(d) for d in run_dirs]
        except (FileNotFoundError, ValueError) as exc:
            raise SystemExit(f"--models: {exc}") from None
        for d, c in zip(run_dirs, configs, strict=True):
            if c["env"] != env_id:
                raise SystemExit(f"{d} was trained on {c['env']}, not {env_id}")
        env_kwargs = configs[0]["env_kwargs"] if configs else {}
        if any(c["env_kwargs"] != env_kwargs for c in configs):
            raise SystemExit(f"the runs of {env_id} differ in env_kwargs; evaluate them apart")
        stage("evaluate", f"{env_id}: making the environment (the first use after installing "
                          "compiles the physics: a minute or two)")
        env = evaluation_env(env_id, env_kwargs)
        if run_dirs:
            stage("evaluate", f"{env_id}: loading {len(run_dirs)} trained model(s)")
        policies: list[tuple[dict[str, Any], Any]] = []
        for d, c in zip(run_dirs, configs, strict=True):
            meta = {"name": c["algo"], "label": c["algo"].upper(), "run_dir": str(d),
                    "steps": c["trained_steps"], "wall_time_s": c["wall_time_s"]}
            policies.append((meta, load_policy(d, best=args.best)))
        for name in (baselines_for(env_id) if args.baselines is None else args.baselines):
            label = classical_label(env_id) if name == "classical" else BASELINE_LABELS[name]
            policies.append(({"name": name, "label": label}, baseline(name, env, seed=0)))
        if not policies:
            where = f" (--runs {args.runs!r} holds no run of it)" if args.runs else ""
            raise SystemExit(f"nothing to evaluate on {env_id}{where}: give --models, --runs "
                             f"with runs of it, or --baselines with at least one of "
                             f"{', '.join(BASELINES)}")
        if args.runs and not run_dirs:
            print(f"--runs {args.runs!r}: no run of {env_id} ({', '.join(args.algos)}); "
                  "evaluating the baselines only")

        # -- the same seeded episodes for every policy ----------------------------------
        rows = []
        for meta, policy in policies:
            stage("evaluate", f"{env_id}: {meta['label']} on {args.episodes} episodes")
            start = time.perf_counter()
            row = {**meta, **evaluate(env, policy, args.episodes)}
            rows.append(row)
            print(f"{env_id:20s} {row['label']:24s} return {row['return_mean']:7.1f} ± "
                  f"{row['return_std']:5.1f}  success {row['success_rate']:4.0%}  "
                  f"({time.perf_counter() - start:.0f} s)", flush=True)
        env.close()

        # -- table, numbers and plots ---------------------------------------------------
        stage("evaluate", f"{env_id}: writing the table and plots into {out}/")
        table = markdown_table(rows)
        check, _ = target_check(env_id, rows)
        print(f"\n{table}\n\n{check}\n")
        (out / f"{file_name(env_id)}.md").write_text(f"## {env_id}\n\n{table}\n\n{check}\n")
        (out / f"{file_name(env_id)}.json").write_text(json.dumps(
            {"env": env_id, "env_kwargs": env_kwargs, "episodes": args.episodes,
             "policies": rows}, indent=1) + "\n")
        plot_learning_curves(env_id, rows, out / f"{file_name(env_id)}-learning.png")
        plot_trajectories(env_id, rows, out / f"{file_name(env_id)}-trajectories.png")
        sections.append((env_id, table, check))

    (out / "evaluation.md").write_text("\n\n".join(
        f"## {env_id}\n\n{table}\n\n{check}" for env_id, table, check in sections) + "\n")
    if args.report:
        write_report(Path(args.report), out, sections, args)
        print(f"wrote {args.report}")
    print(f"wrote tables and plots into {out}/")


def write_report(path: Path, out: Path, sections: list[tuple[str, str, str]],
                 args: argparse.Namespace) -> None:
    rel = Path(os.path.relpath(out, path.parent))
    lines = [
        "# Results",
        "",
        "Sample agents on the tasks: SAC, TD3 and PPO (stable-baselines3, trained on the "
        "CPU) against each task's classical controller (LQR; on Balance an energy swing-up "
        "handing over to LQR), zero torque and random actions.",
        "",
        "Reproduce by training the agents with `roller-gym train` (rl-zoo3, with the "
        f"hyperparameter files of `agents/hyperparams/`) into `{args.runs}/`, then "
        f"`roller-gym evaluate --env {' '.join(args.env)} --runs {args.runs} "
        f"--out {args.out} --report {args.report}"
        + (f" --notes {args.notes}" if args.notes else "") + "`. One training seed per "
        "agent: `roller-gym results` trains several and reports intervals.",
        "",
        f"Every policy plays the same {args.episodes} episodes, `env.reset(seed=s)` for s = 0 "
        f"… {args.episodes - 1}, acting deterministically ({'best' if args.best else 'final'} "
        "model of each run). *Success*: `info[\"is_success\"]` at the episode's last step. "
        "*Final |error|*: the position error at the last step. *Mean |τ|*: over all steps. "
        "*Wall time*: the training run's, from its episode monitors "
        f"({platform.machine()}, {os.cpu_count()} CPU cores; torch on 1 thread).",
        "",
    ]
    for env_id, table, check in sections:
        lines += [f"## {env_id}", "", table, "", check, "",
                  f"![learning curves]({rel / f'{file_name(env_id)}-learning.png'})", "",
                  f"![trajectories]({rel / f'{file_name(env_id)}-trajectories.png'})", ""]
    if args.notes and Path(args.notes).is_file():
        lines += [Path(args.notes).read_text().rstrip(), ""]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines))


if __name__ == "__main__":
    main()
