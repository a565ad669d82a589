"""The results page (roller_gym.scripts.results_page) on constructed task files whose answers
are worked out here by hand, and the committed page against its stored files."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rliable")
results_page = pytest.importorskip("roller_gym.scripts.results_page")

DOCS = Path(__file__).resolve().parents[1] / "docs"
TASK = "roller_gym/RollerHold-v2"


def _run(name, seed, ret, success, means=(0.0, 200.0, 200.0), last=(1.0, 1.0, 1.0)):
    """A run's evaluation: 10 episodes per periodic evaluation, with these mean returns and
    (in the last three) these success rates."""
    successes = [[False] * 10] * (len(means) - 3) + [[i < 10 * x for i in range(10)]
                                                     for x in last]
    return {"env": TASK, "name": name, "seed": seed, "run_dir": "runs/x", "return_mean": ret,
            "success_rate": success, "final_error_mean": 0.01 * (seed + 1),
            "trained_steps": 1000 * len(means), "wall_time_s": 600.0, "evaluation_s": 6.0,
            "curve": {"timesteps": [1000 * (i + 1) for i in range(len(means))],
                      "returns": [[m - 1.0, m + 1.0] for m in means],
                      "successes": successes}}


def _record(runs, threshold=190.0, task=TASK, tier="base"):
    baselines = [{"env": task, "name": n, "return_mean": r, "success_rate": x,
                  "evaluation_s": 1.0}
                 for n, r, x in (("classical", 200.0, 1.0), ("zero", 10.0, 0.0),
                                 ("random", 1.0, 0.0))]
    runs = [dict(r, env=task) for r in runs]
    return {"format": results_page.FORMAT, "task": task, "date": "2026-01-01T00:00:00+00:00",
            "command": "roller-gym results", "machine": "x86_64, 2 CPU cores, Linux",
            "versions": {"numpy": "2.4.6"}, "episodes": 100, "evaluation_seeds": [0, 99],
            "reward_threshold": {"value": threshold, "classical_return": 200.0,
                                 "calibration_seeds": [10000, 10099], "registered": 184.1},
            "classical": "LQR", "tier": tier, "success_band": 0.05, "evaluation_s": 60.0,
            "train_wall_s": 3600.0, "evaluations": baselines + runs}


def _algo(summary, algo):
    return summary["tasks"][TASK]["algos"][algo]


@pytest.mark.parametrize(("success", "met"), [
    ([1.0, 1.0, 1.0, 1.0, 0.79], False),  # IQM 100 %, but one seed below the 80 % floor
    ([0.9, 0.9, 0.9, 0.9, 0.9], False),  # every seed above the floor, IQM 90 % < 95 %
    ([0.96, 1.0, 0.8, 1.0, 0.97], True),  # floor met by all (80 % counts), IQM 97.7 %
])
def test_success_target_is_judged_on_every_seed_and_on_the_iqm(success, met):
    runs = [_run("sac", s, 195.0, x) for s, x in enumerate(success)]
    a = _algo(results_page.summarize([_record(runs)]), "sac")
    assert a["success_met"] is met
    assert [s["success_ok"] for s in a["seeds"]] == [x >= 0.8 for x in success]
    middle = sorted(success)[1:4]  # five seeds: one cut at each end
    assert a["success_iqm"][0] == pytest.approx(np.mean(middle))


def test_return_target_needs_every_seed_at_the_threshold():
    runs = [_run("sac", s, r, 1.0) for s, r in enumerate([195.0, 196.0, 197.0, 198.0, 150.0])]
    a = _algo(results_page.summarize([_record(runs)]), "sac")
    assert [s["return_ok"] for s in a["seeds"]] == [True] * 4 + [False]
    assert a["return_met"] is False
    assert a["return_iqm"][0] == pytest.approx(196.0)  # (195 + 196 + 197) / 3


def test_sustained_crossing_and_the_last_evaluations_per_seed():
    curves = [(0.0, 195.0, 195.0, 195.0), (195.0, 100.0, 195.0, 195.0),
              (195.0, 195.0, 195.0, 100.0)]  # from 2k; from 3k (a dip); never (falls at the end)
    runs = [_run("sac", s, 195.0, 1.0, means=m, last=(1.0, 0.3, 0.0))
            for s, m in enumerate(curves)]
    a = _algo(results_page.summarize([_record(runs)]), "sac")
    assert [s["steps"] for s in a["seeds"]] == [2000.0, 3000.0, None]
    assert a["sustained"] == 2 and a["curves"] == 3
    assert a["steps_median"][0] == pytest.approx(3000.0)  # median of 2k, 3k, never
    assert all(s["last_successes"] == pytest.approx([1.0, 0.3, 0.0]) for s in a["seeds"])


def test_pairwise_probability_of_improvement_counts_the_pairs():
    sac, td3 = [195.0, 196.0, 191.0], [194.0, 196.0, 199.0, 190.0]
    runs = ([_run("sac", s, r, 1.0) for s, r in enumerate(sac)]
            + [_run("td3", s, r, 1.0) for s, r in enumerate(td3)])
    summary = results_page.summarize([_record(runs)])
    (pair,) = summary["tasks"][TASK]["pairs"]
    # 12 pairs: 195 beats 194 and 190; 196 beats 194 and 190, ties 196; 191 beats 190
    assert (pair["a"], pair["b"]) == ("sac", "td3")
    assert pair["poi"][0] == pytest.approx((2 + 2.5 + 1) / 12)
    assert pair["poi"][1] <= pair["poi"][0] <= pair["poi"][2]


def _numbers(text):
    return re.findall(r"\d+(?:\.\d+)?", text)


def _leaves(x):
    if isinstance(x, dict):
        for v in x.values():
            yield from _leaves(v)
    elif isinstance(x, list):
        for v in x:
            yield from _leaves(v)
    else:
        yield x


def test_every_number_on_the_page_is_in_the_summary(tmp_path):
    runs = [_run(algo, s, 190.0 + 2 * s + k, x, last=(1.0, 0.9, 0.3))
            for k, algo in enumerate(("sac", "td3", "ppo")) for s, x in enumerate(
                [1.0, 0.95, 0.7, 1.0, 0.85])]
    (tmp_path / "tasks").mkdir()
    (tmp_path / "tasks" / "RollerHold-v2.json").write_text(json.dumps(_record(runs)))
    summary = results_page.render(tmp_path, tmp_path / "RESULTS.md")
    text = (tmp_path / "RESULTS.md").read_text()
    leaves = list(_leaves(summary))
    for s in sorted((v for v in leaves if isinstance(v, str)), key=len, reverse=True):
        text = text.replace(s, " ")  # dates, versions, the machine, task names
    shown = set()
    for v in leaves:
        if isinstance(v, bool) or not isinstance(v, int | float):
            continue
        for scaled in (v, 100 * v, v / 1000):  # as it is, in percent, in thousands of steps
            shown |= {f"{scaled:.{d}f}" for d in range(4)}
    stray = [n for n in _numbers(text) if n not in shown]
    assert not stray, f"numbers on the page that are not in the summary: {stray}"


def test_rendering_again_from_the_stored_files_gives_the_same_bytes(tmp_path):
    runs = [_run("sac", s, 195.0 + s, 1.0) for s in range(5)]
    (tmp_path / "tasks").mkdir()
    (tmp_path / "tasks" / "RollerHold-v2.json").write_text(json.dumps(_record(runs)))
    results_page.render(tmp_path, tmp_path / "RESULTS.md")
    first = (tmp_path / "RESULTS.md").read_bytes(), (tmp_path / "summary.json").read_bytes()
    results_page.render(tmp_path, tmp_path / "RESULTS.md")
    assert ((tmp_path / "RESULTS.md").read_bytes(),
            (tmp_path / "summary.json").read_bytes()) == first


def test_the_committed_page_is_the_rendering_of_the_committed_task_files():
    summary = results_page.summarize(results_page.load(DOCS / "results"))
    stored = json.loads((DOCS / "results" / "summary.json").read_text())
    assert json.loads(json.dumps(summary)) == stored
    assert results_page.page(stored, "results") == (DOCS / "RESULTS.md").read_text()


def test_a_newer_version_supersedes_the_earlier_ones_results(tmp_path):
    """A task measured in two versions: the page aggregates the newer only, and names the
    earlier one (its ID and date) as superseded; the earlier's numbers are not on it."""
    (tmp_path / "tasks").mkdir()
    old = _record([_run("sac", s, 150.0 + s, 0.5) for s in range(5)])
    old["task"], old["date"] = "roller_gym/RollerHold-v1", "2025-12-31T00:00:00+00:00"
    new = _record([_run("sac", s, 195.0 + s, 1.0) for s in range(5)])
    for record in (old, new):
        name = record["task"].split("/")[1]
        (tmp_path / "tasks" / f"{name}.json").write_text(json.dumps(record))
    summary = results_page.render(tmp_path, tmp_path / "RESULTS.md")
    assert list(summary["tasks"]) == [TASK] and summary["tiers"]["base"]["tasks"] == [TASK]
    assert summary["superseded"] == [{"task": "roller_gym/RollerHold-v1", "date": "2025-12-31"}]
    text = (tmp_path / "RESULTS.md").read_text()
    assert "`roller_gym/RollerHold-v1` (measured 2025-12-31)" in text
    assert "## roller_gym/RollerHold-v1" not in text and "152.0" not in text


def test_a_task_file_of_another_format_is_refused_with_its_name(tmp_path):
    (tmp_path / "tasks").mkdir()
    (tmp_path / "tasks" / "RollerHold-v2.json").write_text(json.dumps({"format": 1}))
    with pytest.raises(SystemExit, match=r"RollerHold-v2\.json: format 1, not 2"):
        results_page.load(tmp_path)


def test_the_threshold_is_calibrated_on_its_own_seeds_apart_from_the_evaluation():
    import gymnasium as gym
    from roller_gym.agents.policies import baseline, rollout
    from roller_gym.scripts import results

    assert set(results.CALIBRATION_SEEDS).isdisjoint(range(100))  # the evaluation's seeds
    seeds = range(10_000, 10_002)
    got = results.calibrate(TASK, seeds)
    env = gym.make(TASK)
    returns = [rollout(env, baseline("classical", env, seed=0), s).total_return for s in seeds]
    assert got["classical_return"] == pytest.approx(np.mean(returns), rel=1e-12)
    assert got["value"] == pytest.approx(0.95 * np.mean(returns), rel=1e-12)
    assert got["calibration_seeds"] == [10_000, 10_001]
    assert got["registered"] == gym.spec(TASK).reward_threshold
    evaluated = [rollout(env, baseline("classical", env, seed=0), s).total_return for s in (0, 1)]
    assert not np.allclose(returns, evaluated)  # other episodes than the evaluation's first


def test_the_round_of_make_results_covers_every_registered_task():
    """`make results` (its TASKS) trains on every registered task, each at its one version."""
    import roller_gym

    makefile = (DOCS.parent / "Makefile").read_text()
    listed = re.search(r"^TASKS := ((?:.*\\\n)*.*)$", makefile, re.M).group(1)
    assert sorted(listed.replace("\\", " ").split()) == sorted(roller_gym.ENV_IDS)


def test_each_tier_is_aggregated_over_its_own_tasks_and_says_which_algorithms_differ(tmp_path):
    """A base task and a hard one: two aggregates, each over its own task. On the hard one SAC
    beats TD3 on every seed (P = 1, an interval that excludes one half) and ties PPO seed for
    seed (P = one half): the page says the first pair differs and the second does not."""
    hard = "roller_gym/RollerHoldRandomized-v2"
    base_runs = [_run(a, s, 195.0 + s, 1.0) for a in ("sac", "td3", "ppo") for s in range(5)]
    hard_runs = ([_run("sac", s, 150.0 + s, 0.8) for s in range(5)]
                 + [_run("td3", s, 100.0 + s, 0.3) for s in range(5)]
                 + [_run("ppo", s, 150.0 + s, 0.8) for s in range(5)])
    (tmp_path / "tasks").mkdir()
    for record in (_record(base_runs), _record(hard_runs, task=hard, tier="hard")):
        name = record["task"].split("/")[1]
        (tmp_path / "tasks" / f"{name}.json").write_text(json.dumps(record))
    summary = results_page.render(tmp_path, tmp_path / "RESULTS.md")
    assert summary["tiers"]["base"]["tasks"] == [TASK]
    assert summary["tiers"]["hard"]["tasks"] == [hard]
    pairs = {(p["a"], p["b"]): p for p in summary["tiers"]["hard"]["pairs"]}
    assert pairs["sac", "td3"]["poi"] == [1.0, 1.0, 1.0] and pairs["sac", "td3"]["differs"]
    assert pairs["sac", "ppo"]["poi"][0] == 0.5 and not pairs["sac", "ppo"]["differs"]
    assert pairs["td3", "ppo"]["poi"] == [0.0, 0.0, 0.0] and pairs["td3", "ppo"]["differs"]
    # over the classical return of 200: SAC's IQM of 150 … 154 drops one seed at each end
    assert summary["tiers"]["hard"]["normalized_iqm"]["sac"][0] == pytest.approx(152.0 / 200)
    text = (tmp_path / "RESULTS.md").read_text()
    hard_part = text[text.index("## Over the hard tier"):text.index(f"## {TASK}")]
    assert "These algorithms differ" in hard_part
    assert "SAC and TD3 (100% [100%, 100%])" in hard_part
    assert "These do not: SAC and PPO (50%" in hard_part
    assert (tmp_path / "aggregate.png").exists() and (tmp_path / "aggregate-hard.png").exists()


def test_a_tier_where_no_interval_excludes_one_half_says_so(tmp_path):
    runs = [_run(a, s, 195.0 + s, 1.0) for a in ("sac", "td3") for s in range(5)]
    summary = results_page.summarize([_record(runs)])
    (pair,) = summary["tiers"]["base"]["pairs"]
    assert pair["poi"][0] == 0.5 and not pair["differs"]
    assert "No pair of algorithms differs here" in results_page.page(summary, "results")


def test_a_task_of_an_unknown_tier_is_refused_at_registration():
    from roller_gym.hold import HoldTask
    from roller_gym.task import register

    class Odd(HoldTask):
        name = "RollerOddTier"
        tier = "medium"

    with pytest.raises(ValueError, match=r"RollerOddTier.tier is 'medium'; it must be one of"):
        register(Odd)


def _retrained_td3():
    """A stored round of SAC, TD3 and PPO, and an evaluation of TD3's runs retrained since."""
    stored = _record([_run(a, s, 195.0 + s, 1.0) for a in ("sac", "td3", "ppo")
                      for s in range(5)])
    fresh = _record([_run("td3", s, 180.0 + s, 0.5) for s in range(5)])
    fresh["date"], fresh["train_wall_s"] = "2026-02-02T00:00:00+00:00", 1800.0
    return stored, fresh


def test_keep_stored_replaces_the_retrained_algorithm_and_keeps_the_others_dated(tmp_path):
    from roller_gym.scripts.results import keep_stored

    stored, fresh = _retrained_td3()
    merged = keep_stored(fresh, stored, ["td3"], tmp_path / "x.json")
    runs = {(e["name"], e["seed"]): e["return_mean"] for e in merged["evaluations"]
            if "seed" in e}
    assert runs == {**{("td3", s): 180.0 + s for s in range(5)},
                    **{(a, s): 195.0 + s for a in ("sac", "ppo") for s in range(5)}}
    assert merged["kept"] == {"sac": stored["date"], "ppo": stored["date"]}
    # kept again later: each algorithm keeps the date it was measured, not the file's
    merged["date"] = "2026-03-03T00:00:00+00:00"
    again = keep_stored(fresh, merged, ["ppo"], tmp_path / "x.json")
    assert again["kept"] == {"td3": merged["date"], "sac": stored["date"]}
    # the page says which runs are new and from when the others are
    (tmp_path / "tasks").mkdir()
    (tmp_path / "tasks" / "RollerHold-v2.json").write_text(json.dumps(merged))
    results_page.render(tmp_path, tmp_path / "RESULTS.md")
    text = (tmp_path / "RESULTS.md").read_text()
    assert ("0.5 h of wall time for TD3's runs; SAC's and PPO's runs kept from the measurement "
            "of 2026-01-01)") in text


@pytest.mark.parametrize(("what", "change"), [
    ("reward threshold", lambda r: r["reward_threshold"].update(value=189.0)),
    ("baselines", lambda r: r["evaluations"][0].update(return_mean=201.0)),
    ("package versions", lambda r: r["versions"].update(numpy="2.5.0")),
    ("episodes", lambda r: r.update(episodes=50, evaluation_seeds=[0, 49])),
])
def test_keep_stored_refuses_a_stored_file_that_measured_something_else(tmp_path, what, change):
    from roller_gym.scripts.results import keep_stored

    stored, fresh = _retrained_td3()
    change(stored)
    with pytest.raises(SystemExit, match=rf"x\.json has other {what}.*not comparable"):
        keep_stored(fresh, stored, ["td3"], tmp_path / "x.json")
    with pytest.raises(SystemExit, match="no runs of an algorithm other than sac td3 ppo"):
        keep_stored(fresh, _retrained_td3()[0], ["sac", "td3", "ppo"], tmp_path / "x.json")


@pytest.mark.parametrize(("text", "message"), [
    ('{"format": 2', r"not a readable results file"),
    ("[1, 2]", r"format 'list', not 2"),
    ("{}", r"format None, not 2"),
    ('{"format": 2}', r"a results file without task, date,"),
])
def test_a_broken_task_file_is_refused_naming_it_before_any_evaluation(tmp_path, text,
                                                                        message):
    """A stored file that does not parse, or lacks what the page reads, ended in a traceback
    (JSONDecodeError, KeyError) after the whole evaluation; now before it, naming the file,
    for --keep-stored and --render-only alike."""
    from roller_gym.scripts import results

    (tmp_path / "tasks").mkdir()
    (tmp_path / "tasks" / "RollerHold-v2.json").write_text(text)
    with pytest.raises(SystemExit, match=r"RollerHold-v2\.json: " + message):
        results_page.load(tmp_path)
    with pytest.raises(SystemExit, match=r"RollerHold-v2\.json: " + message):
        results.main(["--runs", str(tmp_path / "nothing"), "--env", TASK, "--keep-stored",
                      "--out", str(tmp_path), "--report", str(tmp_path / "R.md")])


def test_a_task_file_records_the_command_as_it_was_typed(tmp_path, monkeypatch):
    """Through ``roller-gym results …`` the task file's command read "roller-gym results
    results …": the subcommand's name was taken from sys.argv as well."""
    from roller_gym.scripts import cli, results

    seen = []

    def measure(args, env_id):
        seen.append(args.command)
        raise SystemExit(0)

    monkeypatch.setattr(results, "measure", measure)
    monkeypatch.setattr("sys.argv", ["roller-gym", "results", "--env", TASK,
                                     "--out", str(tmp_path)])
    with pytest.raises(SystemExit):
        cli.main()
    assert seen == [f"roller-gym results --env {TASK} --out {tmp_path}"]
