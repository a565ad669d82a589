"""The throughput benchmark's verdicts and pages, on synthetic results (no measuring), and
its replay of the environment's steps through the physics kernel alone."""

from __future__ import annotations

import copy

import pytest
from roller_gym.bench import maintainers, throughput, throughput_report, verdicts

RESULTS = {
    "machine": {"cpu": "a CPU", "cores": 2, "os": "an OS", "python": "3.11",
                "versions": {"gymnasium": "1.4.0", "numba": None}},
    "date": "2026-01-01T00:00:00+00:00", "command": "python -m roller_gym.bench.throughput",
    "quick": False,
    "vector": {"4096": {"ours": 3e6, "CartPoleVectorEnv": 10e6, "kernel": 4e6,
                        "outside_kernel_share": 0.25, "outside_kernel_repeats": 7},
               "65536": {"ours": 1e6, "CartPoleVectorEnv": 10e6, "kernel": 2e6,
                         "outside_kernel_share": 0.5, "outside_kernel_repeats": 7}},
    "start_seconds": {"65536": 0.3},
    "single": {"ours": 150e3, "Pendulum-v1": 100e3},
    "ppo": {"RollerVecEnv": 2000.0, "DummyVecEnv": 1000.0},
    "peers_missing": {"EnvPool Pendulum-v1": "not measured: envpool is not installed"},
}


def test_the_page_shows_the_first_step_of_each_case_cold_and_warm():
    """The first-use benchmark's figures, where given, are a section of the page: one row per
    case, named by what the case runs, with its cold and warm seconds and the machine's load;
    without them, no such section."""
    from roller_gym.bench.firstuse import CASES

    run = {"import_s": 1.5, "first_s": 0.0, "process_s": 0.0, "stderr": []}
    first = {"date": "2026-01-02T03:04:05+00:00",
             "machine_before": {"usable_cores": 2, "cpu_count": 2, "load_average": [0.5, 0, 0]},
             "cases": {name: {"cold": {**run, "first_s": 10.0 + i}, "warm": {**run, "first_s": 2.0},
                              "load_after": [0.5, 0, 0]}
                       for i, name in enumerate(CASES)}}
    page = throughput_report.render(RESULTS, first)
    assert "## The first step" in page and "at a load average of 0.5" in page
    for i, name in enumerate(CASES):
        assert f"| `{CASES[name]}` | {10 + i:.1f} | 2.0 | 1.5 |" in page
    assert "## The first step" not in throughput_report.render(RESULTS)


def test_verdicts_compare_each_ratio_with_its_target():
    judged = {v.target: (v.value, v.met) for v in verdicts.throughput_verdicts(RESULTS)}
    vec = {what: v for what, v in judged.items() if "CartPoleVectorEnv" in what}
    assert sorted(vec.values()) == [(0.1, False), (pytest.approx(0.3), True)]
    assert [v for w, v in judged.items() if "outside the physics kernel" in w] == [(0.5, False)]
    assert [v for w, v in judged.items() if "reset" in w] == [(0.3, False)]
    assert [v for w, v in judged.items() if "Pendulum" in w] == [(1.5, True)]
    assert set(verdicts.THROUGHPUT) == {
        verdicts.verdict_vector, verdicts.verdict_envpool, verdicts.verdict_outside_kernel,
        verdicts.verdict_start, verdicts.verdict_single}


def test_a_verdict_turns_with_its_measurement():
    better = copy.deepcopy(RESULTS)
    better["vector"]["65536"]["ours"] = 5e6
    better["single"]["ours"] = 140e3
    (v,) = [v for v in verdicts.verdict_vector(better) if "65,536" in v.target]
    assert v.value == pytest.approx(0.5) and v.met
    (single,) = verdicts.verdict_single(better)
    assert single.met is False and single.miss == "speed 0.93 of the target"


def test_render_has_every_section_and_no_gap():
    page = throughput_report.render(RESULTS)
    for heading in ("# Throughput", "## Machine and command", "## The vector environment",
                    "## One environment and SB3", "## Peers not measured"):
        assert heading in page
    assert "| 65,536 | 1,000,000 | 10,000,000 | 0.100 | 2,000,000 | 50% |" in page
    assert "the fastest of 7 repeats of each" in page  # the share's, as measured
    assert "(benchmarks/throughput.png)" in page and "`make throughput`" in page
    assert "a CPU, 2 cores (an OS), Python 3.11" in page
    assert "{" not in page and "None" not in page
    assert "target" not in page.lower()  # the targets are the maintainers' page's


def test_the_maintainers_page_has_the_verdicts_and_keeps_what_is_hand_written(tmp_path):
    page = maintainers.render(None, RESULTS, "## History\n\nnine runs")
    rows = [line for line in page.splitlines() if line.startswith("| vector env ≥ 0.25")]
    assert rows == ["| vector env ≥ 0.25 × CartPoleVectorEnv at 4,096 sub-environments | 0.3 × "
                    "(3,000,000 against 10,000,000 steps/s) | **met** |",
                    "| vector env ≥ 0.25 × CartPoleVectorEnv at 65,536 sub-environments | 0.1 × "
                    "(1,000,000 against 10,000,000 steps/s) | **missed**: 0.40 of the target "
                    "(2.5× too slow) |"]
    assert page.endswith(maintainers.HAND_WRITTEN + "\n## History\n\nnine runs\n")
    (tmp_path / "MAINTAINERS.md").write_text("stale\n" + maintainers.HAND_WRITTEN + "\nkept\n")
    records_path = tmp_path / throughput.RESULTS_FILE
    from roller_gym.bench import records

    records.save_results(RESULTS, records_path)
    written = maintainers.write(tmp_path).read_text()
    assert "stale" not in written and written.endswith(maintainers.HAND_WRITTEN + "\nkept\n")
    assert "| one environment ≥ 1.5 × Pendulum-v1's steps/s | 1.5 × Pendulum-v1" in written


def test_a_miss_just_below_its_target_does_not_read_as_the_target():
    """A ratio that rounds to its target at three digits is shown with the digits that tell
    it from the target: a miss never reads as the target itself."""
    near = copy.deepcopy(RESULTS)
    near["vector"]["65536"]["ours"] = 0.24996 * 10e6
    (v,) = [v for v in verdicts.verdict_vector(near) if "65,536" in v.target]
    assert v.measured.startswith("0.24996 × ") and v.met is False
    assert verdicts.shown(0.294, 0.25) == "0.294"
    assert verdicts.shown(0.25, 0.25) == "0.25"


def test_envpool_and_the_arithmetic_are_reported_where_measured():
    res = copy.deepcopy(RESULTS)
    res["vector"]["4096"].update({"EnvPool Pendulum-v1": 2e6, "rhs_ns": 10.0, "substeps": 1.0,
                                  "unit": "expansion", "unit_ns": 30.0,
                                  "units_per_step": 1.0, "kernel_threads": 2})
    res["vector"]["65536"].update({"EnvPool Pendulum-v1": 2e6, "rhs_ns": 10.0, "substeps": 1.0,
                                   "unit": "expansion", "unit_ns": 30.0,
                                   "units_per_step": 1.0, "kernel_threads": 2})
    ours = {v.target: (v.value, v.met) for v in verdicts.verdict_envpool(res)}
    assert sorted(ours.values()) == [(0.5, False), (1.5, True)]
    assert verdicts.verdict_envpool(RESULTS) == []  # not measured: no verdict
    page = throughput_report.render(res)
    assert "| 4,096 | 2,000,000 | 1.50 |" in page
    # kernel 4e6 roller-steps/s on 2 threads: 500 core-ns, against 1 expansion of 30 ns
    assert "| 4,096 | 10.00 | 30.00 | 1.00 | 500 | 16.7 |" in page
    assert "kernel / its expansions" in page


def test_the_physics_share_replays_the_steps_the_environment_took():
    """The physics' share of a vector step is timed by replaying steps kept from an episode:
    the replay must compute what the environment's step did (the same start, the same
    torque, the same carried sizes): its end state equals that of a second environment with
    the same seed and actions, after the same step."""
    import gymnasium as gym
    import numpy as np
    from roller_gym.physics.integrators import ROWS

    n, every = 5, 4
    actions = np.random.default_rng(1).uniform(-1, 1, (9, n, 1)).astype(np.float32)
    # rk8: its steps start from the sizes the last one carried, which the replay must keep
    made = [gym.make_vec(throughput.TASK, num_envs=n, integrator="rk8") for _ in range(2)]
    for env in made:
        env.reset(seed=3)
    kept = throughput.kept_steps(made[0], actions, every)
    after = []
    for k, a in enumerate(actions):
        made[1].step(a)
        if k % every == 0:
            after.append((made[1].unwrapped.phi.copy(), made[1].unwrapped.phi_dot.copy()))
    assert len(kept) == len(after) == 3
    stepper = made[0].unwrapped._stepper
    for io, (phi, phi_dot) in zip(kept, after, strict=True):
        throughput.replay(stepper, io)
        np.testing.assert_array_equal(stepper._io[ROWS.index("phi")], phi)
        np.testing.assert_array_equal(stepper._io[ROWS.index("phi_dot")], phi_dot)
