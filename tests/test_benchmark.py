"""The work-precision benchmark (``roller_gym.bench``): it measures, renders and judges.

* The verdicts, each on synthetic results that meet and that miss its target.
* Rendering: from a results file alone, with the measuring functions disabled and MuJoCo not
  importable, the page has every section, table and plot.
* ``roller-gym benchmark --quick`` (``--out`` a temporary folder) writes the results file, the
  page and the plots; its RK4 errors fall as the tolerance tightens and as the substeps grow.
* The cost measurement (``roller_gym.bench.cost``): its search for the smallest fixed substep
  count against a threshold it must find and a linear scan, its references against DOP853 on
  each roller alone.
* The MuJoCo model of the scene (``roller_gym.bench.mujoco_roller``) and our physics agree: at
  the tuned settings MuJoCo's trajectory matches our DOP853 reference within a stated
  tolerance, and converges to it as the timestep shrinks. Two independent models of the same
  system agreeing is a cross-check of both.

No timing is asserted: the targets are reported by the benchmark, not tested.
"""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
from itertools import pairwise
from pathlib import Path

import numpy as np
import pytest
from roller_gym.bench import cost, maintainers, records, report, verdicts
from roller_gym.physics import Scene, preset
from roller_gym.physics import equations as eq
from roller_gym.physics import integrators as integ
from roller_gym.scripts import benchmark
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[1]

SECTIONS = ("## Summary", "## Machine and command", "## How it is measured",
            "## 1. Work-precision", "### Energy at zero torque", "## 2. MuJoCo on the same scene",
            "## 3. The environments' error", "## 4. Hard cases",
            "## 5. Cost of the error control")
PLOTS = ("work_precision.png", "work_precision_local.png", "energy.png")
INF, NAN = math.inf, math.nan


def _table_rows(text: str, heading: str) -> list[list[str]]:
    """The rows of the first Markdown table after ``heading``, as lists of cells."""
    start = text.index(heading)
    rows = []
    for line in text[start:].splitlines()[1:]:
        if line.startswith("|"):
            rows.append([c.strip() for c in line.strip("|").split("|")])
        elif rows:
            break
    return rows[2:]  # without the header and the separator


# -- synthetic results ----------------------------------------------------------------------------
def _run(family: str, label: str, setting: float, err: float, seconds: float,
         local: float | None = None, ours: bool = True) -> dict:
    return {"family": family, "label": label, "setting": setting, "ours": ours,
            "seconds": seconds, "finite": math.isfinite(err), "error": [err, 10 * err],
            "local_error": [err / 10 if local is None else local, err],
            "substeps": {"min": 1, "median": 2.0, "mean": 2.5, "max": 6},
            "lifting": 3 if ours else None, "slipping": 4 if ours else None,
            "degree": 18 if family.startswith("taylor") else None}


def _scene(name: str, default_err: float, default_seconds: float, own_error: float = 1e-12,
           predictable_s: float = INF, blowup_s: float = INF) -> dict:
    """A scene of 200 control steps of 0.05 s: ours, DOP853 and MuJoCo, whose tuned family's
    error falls as cost⁻²."""
    runs = [
        _run("euler", "×1", 1, 0.5, 1e-4), _run("euler", "×10", 10, 0.05, 1e-3),
        _run("rk4", "×1", 1, 1e-3, 2e-4), _run("rk4", "×4", 4, 4e-6, 8e-4),
        _run("rk4 auto", "tol 1e-06", 1e-6, 1e-5, 3e-4),
        _run("rk4 auto", "tol 1e-08", 1e-8, 1e-7, 6e-4),
        _run("rk8", "×1", 1, 1e-6, 2e-4), _run("rk8", "×4", 4, INF, 8e-4),
        _run("rk8 auto", "tol 1e-06", 1e-6, 1e-7, 2e-4),
        _run("rk8 auto", "tol 1e-08", 1e-8, default_err, default_seconds),
        _run("midpoint", "×1", 1, 1e-2, 5e-4),
        _run("dop853", "tol 1e-06", 1e-6, 1e-6, 1e-2, local=NAN),
        _run("MuJoCo default", "2 ms", 25, 0.5, 2e-3, local=1e-2, ours=False),
        *(_run("MuJoCo tuned", f"{50 / n:g} ms", n, 1e-6 / (n / 25) ** 2, 0.02 * n / 25,
               ours=False) for n in (25, 100, 400, 1600)),
    ]
    energy = [{"label": label, "seconds": 0.01, "finite": True,
               "blowup_s": blow, "max": 1e-3, "end": 1e-4,
               "curve": {"t": [0.05, 0.5, 5.0], "value": [1e-9, 1e-6, 1e-3]}}
              for label, blow in (("euler ×1 (Pendulum's scheme)", INF),
                                  ("rk8 auto tol 1e-08 (default)", blowup_s))]
    return {"name": name, "note": f"the scene {name}", "mu": 1.0, "steps": 200,
            "reference": {"seconds": 0.5, "steps": 4000, "own_error": [own_error, own_error],
                          "predictable_s": predictable_s, "max_abs_phi": 1.2,
                          "max_abs_phi_dot": 13.0},
            "default": 9, "runs": runs, "energy": energy}


def _cost_row(method: str, tol: float, variant: str, median: float, p99: float) -> dict:
    stats = {"median": median, "p99": p99, "max": p99 + 1, "mean": median}
    return {"variant": variant, "method": method, "tol": tol, "steps": 300, "measured": 290,
            "skipped": {"reference uncertain": 8, "automatic step not finite": 0,
                        "no fixed count up to 200,000 meets tol": 2},
            "ratio": stats, "auto_substeps": {"median": 40.0, "p99": 900.0, "max": 1e3,
                                              "mean": 120.0},
            "fixed_substeps": {"median": 20.0, "p99": 400.0, "max": 600.0, "mean": 60.0},
            "within_tol": 0.99, "within_tol_where_met": 1.0, "worst_error_over_tol": 3.0,
            "tol_not_met": 4}


def synthetic_results() -> dict:
    """Results that meet the error and MuJoCo targets; a second scene is chaotic and blows up
    at zero torque; rk8's substep counts meet their target, rk4's miss it in the median."""
    return {
        "study": "work-precision",
        "machine": {"cpu": "a CPU", "cores": 2, "os": "an OS", "python": "3.11",
                    "versions": {"roller-gym": "0.1.0", "mujoco": None}},
        "date": "2026-01-01T00:00:00+00:00", "command": "roller-gym benchmark",
        "elapsed_s": 700.0, "quick": False,
        "settings": {"dt": 0.05, "tolerance": 1e-8, "method": "rk8", "max_torque": 0.5,
                     "reference_tol": 1e-13, "target_error": 1e-6, "seed": 0, "slow_s": 1.0,
                     "parallel_threshold": 2048, "taylor_degrees": [10, 18],
                     "taylor_lower_above": 0.1,
                     "mujoco": {"default": {"timestep": 0.002, "integrator": "Euler",
                                            "solref": [0.02, 1.0],
                                            "solimp": [0.9, 0.95, 0.001, 0.5, 2.0],
                                            "tolerance": 1e-8, "iterations": 100,
                                            "refsafe": True},
                                "tuned": {"integrator": "RK4",
                                          "solimp": [0.9999, 0.9999, 0.001, 0.5, 2.0],
                                          "tolerance": 1e-15, "iterations": 200,
                                          "refsafe": False, "timeconst_per_timestep": 0.5,
                                          "dampratio": 1.0},
                                "arm_mass": 1e-14}},
        "config": {"quick": False, "horizon_s": 10.0, "repeats": 5, "energy_horizon_s": 1000.0,
                   "vector_error_envs": 16},
        "scenes": [_scene("paper", 1e-9, 4e-4),
                   _scene("tight_fit", 1e-4, 1e-3, own_error=1.0, predictable_s=2.0,
                          blowup_s=12.5)],
        "environments": {"env_error": [5e-10, 2e-9], "vector_error": [5e-10, 2e-9],
                         "vector_error_envs": 16},
        "cost": {
            "settings": {"dt": 0.05, "steps": 300, "trajectories": 40, "trajectory_steps": 6,
                         "seed": 1, "trajectories_dropped": 0, "reference_tol": 1e-13,
                         "uncertainty_share": 0.1, "max_fixed": 200_000,
                         "verdict_variant": "stateless"},
            "rows": [_cost_row("rk8", 1e-8, "stateless", 1.5, 3.5),
                     _cost_row("rk8", 1e-8, "carried", 1.4, 3.0),
                     _cost_row("rk4", 1e-6, "stateless", 6.0, 3.9),
                     _cost_row("rk4", 1e-6, "carried", 5.0, 20.0)],
            "command": "roller-gym benchmark", "date": "2026-01-01T00:00:00+00:00",
            "elapsed_s": 90.0,
        },
    }


@pytest.fixture
def results() -> dict:
    return synthetic_results()


# -- the verdicts -------------------------------------------------------------------------------
def test_verdict_error_judges_the_environment_and_the_integrator(results: dict) -> None:
    (v,) = verdicts.verdict_error(results)
    assert v.met is True and v.sentence == "**met**"
    assert v.measured == "5.0e-10 rad through the environment, 1.0e-09 rad in the stepper"
    results["environments"]["env_error"][0] = 2e-6
    (v,) = verdicts.verdict_error(results)
    assert v.met is False and v.miss == "error 2.0 × the bound"
    assert v.sentence.startswith("**missed**")
    results["environments"]["env_error"][0] = 5e-10
    results["scenes"][0]["runs"][9]["error"][0] = 3e-6  # the default run on the paper scene
    (v,) = verdicts.verdict_error(results)
    assert v.met is False and v.miss == "error 3.0 × the bound"


def test_verdict_mujoco_meets_misses_and_cannot_tell(results: dict) -> None:
    # MuJoCo tuned reaches 1e-9 rad between its 400 and 1600 steps per control step, at
    # 0.032 × 4^0.49 = 0.0632 s per simulated s (log-log interpolation), against our 4e-5.
    (v,) = verdicts.verdict_mujoco(results)
    assert v.met is True and v.measured.startswith("1,581 ×") and "interpolated" in v.measured
    results["scenes"][0]["runs"][9]["seconds"] = 0.04  # ours 100 times slower: 16 ×
    (v,) = verdicts.verdict_mujoco(results)
    assert v.met is False and v.miss == "0.16 of the target"
    for run in verdicts.family(results["scenes"][0], "MuJoCo tuned"):
        run["error"][0] = 1e-3  # its error stops falling: no cost at our error
    (v,) = verdicts.verdict_mujoco(results)
    assert v.met is None and v.sentence == "**not judged**: not reached: its error stops falling"


def test_verdict_cost_judges_median_and_99th_percentile_of_the_stateless_steps(
        results: dict) -> None:
    rk8, rk4 = verdicts.verdict_cost(results)  # the stateless rows only, in order
    assert rk8.target.startswith("rk8 tol 1e-08: automatic substeps ≤ 2 × ")
    assert rk8.met is True and rk8.measured.startswith("median 1.50 ×, 99th percentile 3.50 ×")
    assert "over 290 hard steps (10 skipped)" in rk8.measured and "99.0 %" in rk8.measured
    assert rk4.met is False and rk4.miss == "median 6.00 × (3.00 × the target)"
    rows = results["cost"]["rows"]
    rows[0]["ratio"]["p99"] = 4.5  # past 4 × at the 99th percentile only
    rows[0]["ratio"]["median"] = 2.0  # exactly at the bound: met
    (rk8, _) = verdicts.verdict_cost(results)
    assert rk8.met is False and rk8.miss == "99th percentile 4.50 × (1.12 × the target)"
    rows[1]["ratio"] = {"median": 1.0, "p99": 1.0, "max": 1.0, "mean": 1.0}  # carried: unjudged
    assert verdicts.verdict_cost(results)[0].met is False
    rows[0]["measured"] = 0
    assert verdicts.verdict_cost(results)[0].met is None
    del results["cost"]  # a results file from before the measurement: nothing to judge
    assert verdicts.verdict_cost(results) == []


def test_every_verdict_is_in_the_list() -> None:
    assert set(verdicts.WORK_PRECISION) == {verdicts.verdict_error, verdicts.verdict_mujoco,
                                            verdicts.verdict_cost}


def test_cost_at_error_interpolates_and_extrapolates() -> None:
    pts = [(1e-2, 1.0), (1e-4, 10.0), (1e-6, 100.0)]  # error falls 100 × per 10 × cost
    cost, how = verdicts.cost_at_error(pts, 1e-5)
    assert how == "interpolated" and cost == pytest.approx(10 ** 1.5)
    cost, how = verdicts.cost_at_error(pts, 1e-8)
    assert how == "extrapolated" and cost == pytest.approx(1000.0)
    cost, how = verdicts.cost_at_error(pts, 1.0)
    assert how == "reached at its cheapest setting" and cost == 1.0
    cost, how = verdicts.cost_at_error([(1e-2, 1.0), (1e-2, 2.0)], 1e-3)
    assert math.isnan(cost) and how.startswith("not reached")
    cost, how = verdicts.cost_at_error(pts, 1e-20)  # too far to extrapolate
    assert math.isnan(cost) and how.startswith("not reached")


# -- rendering --------------------------------------------------------------------------------
def test_results_file_is_strict_json_and_reads_back(results: dict, tmp_path: Path) -> None:
    path = report.results_path(tmp_path)
    records.save_results(results, path)
    text = path.read_text()

    def refuse(name: str) -> None:
        raise AssertionError(f"{name} is not JSON")

    json.loads(text, parse_constant=refuse)  # no NaN or Infinity literals
    back = records.load_results(path)
    assert back["scenes"][0]["runs"][7]["error"] == [INF, INF]
    assert math.isnan(back["scenes"][0]["runs"][11]["local_error"][0])
    assert back["environments"] == results["environments"]


def test_render_from_the_results_file_alone(results: dict, tmp_path: Path,
                                            monkeypatch: pytest.MonkeyPatch) -> None:
    workprecision = pytest.importorskip("roller_gym.bench.workprecision")

    def no_measuring(*args, **kwargs):
        raise AssertionError("rendering measured")

    for name in ("measure", "measure_scene", "measure_energy", "measure_environments",
                 "measure_cost"):
        monkeypatch.setattr(workprecision, name, no_measuring)
    monkeypatch.setattr(cost, "measure", no_measuring)
    records.save_results(results, report.results_path(tmp_path))
    benchmark.main(["--render", "--out", str(tmp_path)])
    page = (tmp_path / "BENCHMARKS.md").read_text()
    for section in SECTIONS:
        assert section in page, section
    for png in PLOTS:
        assert (tmp_path / "benchmarks" / png).stat().st_size > 10_000
        assert f"(benchmarks/{png})" in page
    assert "{" not in page and "None" not in page and not re.search(r"\bnan\b", page)
    assert "ours is **1,581 ×** as fast at equal error (interpolated)" in page
    assert ("over random hard control steps: rk8 1.50 × / 3.50 × (tol 1e-08), rk4 6.00 × / "
            "3.90 × (tol 1e-06).") in page
    assert "target" not in page.lower()  # the targets are the maintainers' page's
    judged = _table_rows((tmp_path / "MAINTAINERS.md").read_text(), "## Work-precision")
    assert [row[2] for row in judged] == ["**met**", "**met**", "**met**",
                                          "**missed**: median 6.00 × (3.00 × the target)"]
    costs = _table_rows(page, "## 5. Cost of the error control")
    assert [r[:3] for r in costs] == [["rk8", "1e-08", "stateless ★"], ["rk8", "1e-08", "carried"],
                                     ["rk4", "1e-06", "stateless ★"], ["rk4", "1e-06", "carried"]]
    assert costs[0][3:9] == ["290 of 300", "reference uncertain 8; no fixed count up to 200,000 "
                            "meets tol 2", "1.50", "3.50", "4.50", "120 / 60"]
    assert costs[0][9:] == ["99.0 % (100.0 %)", "3.0e+00", "4"]
    assert ("**Cost of the error control, rk4 at tol 1e-06**: median 6.00 ×"
            in maintainers.render(results, None))
    rows = _table_rows(page, "### paper:")
    assert len(rows) == len(results["scenes"][0]["runs"])
    assert rows[9][:3] == ["rk8 auto ★", "tol 1e-08", "1.0e-09"]
    assert rows[7][2] == "diverged" and rows[11][4] == ""
    assert "**The motion is chaotic under these torques**" in page
    assert "not comparable: chaotic after 2 s" in page
    assert "**blew up** in tight_fit (rk8 auto tol 1e-08 (default) at t = 12.5 s)" in page
    hard = _table_rows(page, "## 4. Hard cases")
    assert [r[0] for r in hard] == ["paper", "tight_fit"]
    assert hard[0][8] == "3 lift-off, 4 slip (μ = 1)"
    assert "Generated by `roller-gym benchmark` in 700 s" in page


def test_render_of_results_without_the_cost_part(results: dict) -> None:
    del results["cost"]
    page = report.render(results)
    assert "## 5. Cost of the error control\n\nNot measured in this results file" in page
    assert "Cost of the error control (part 5)" not in page


def test_render_does_not_need_mujoco(results: dict, tmp_path: Path) -> None:
    records.save_results(results, report.results_path(tmp_path))
    code = ("import sys; sys.modules['mujoco'] = None\n"
            "from roller_gym.scripts.benchmark import main\n"
            f"main(['--render', '--out', {str(tmp_path)!r}])\n"
            "assert 'roller_gym.bench.workprecision' not in sys.modules")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "## 4. Hard cases" in (tmp_path / "BENCHMARKS.md").read_text()
    assert "missed: " in proc.stdout  # the verdicts printed


def test_render_without_a_results_file_says_how_to_make_one(tmp_path: Path) -> None:
    with pytest.raises(SystemExit, match=r"no results file at .*`roller-gym benchmark`"):
        benchmark.main(["--render", "--out", str(tmp_path)])
    with pytest.raises(SystemExit):
        benchmark.main(["--render", "--quick", "--out", str(tmp_path)])
    assert not (tmp_path / "BENCHMARKS.md").exists()


# -- the quick run --------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def wp():
    """roller_gym.bench.workprecision (it needs MuJoCo)."""
    return pytest.importorskip("roller_gym.bench.workprecision")


@pytest.fixture(scope="module")
def mjr():
    return pytest.importorskip("roller_gym.bench.mujoco_roller")


@pytest.fixture(scope="module")
def quick_run(wp, tmp_path_factory: pytest.TempPathFactory) -> tuple[dict, str]:
    out = tmp_path_factory.mktemp("bench")
    proc = subprocess.run(
        [sys.executable, "-m", "roller_gym.scripts.benchmark", "--quick", "--out", str(out)],
        capture_output=True, text=True, timeout=600, cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    for png in PLOTS:
        assert (out / "benchmarks" / png).stat().st_size > 10_000
    return (records.load_results(report.results_path(out)),
            (out / "BENCHMARKS.md").read_text())


def test_quick_run_writes_the_results_with_machine_versions_and_command(wp, quick_run) -> None:
    results, _ = quick_run
    assert results["quick"] is True
    assert results["command"].startswith("roller-gym benchmark --quick --out ")
    assert results["machine"]["cores"] >= 1
    versions = results["machine"]["versions"]
    for dist in ("roller-gym", "numpy", "scipy", "mujoco"):
        assert versions[dist], dist
    assert [s["name"] for s in results["scenes"]] == list(results["config"]["scenes"])
    paper = results["scenes"][0]
    assert paper["steps"] == round(results["config"]["horizon_s"] / results["settings"]["dt"])
    default = paper["runs"][paper["default"]]
    assert default["family"] == f"{wp.DEFAULT_INTEGRATOR} auto"
    assert default["finite"] and 0 < default["error"][0] < 1e-6
    env = results["environments"]
    assert env["vector_error_envs"] == results["config"]["vector_error_envs"]
    assert 0 < env["env_error"][0] < 1e-6 and 0 < env["vector_error"][0] < 1e-6


def test_quick_run_measures_the_cost_of_every_error_controlled_setting(quick_run) -> None:
    """Part 5 of the quick run: a row per method, tolerance and variant; most steps measured;
    the ratio's median <= 99th percentile <= largest; and the automatic steps that report
    tol_met are within tol in at least 95 % of the steps."""
    results, _ = quick_run
    rows = results["cost"]["rows"]
    cfg = results["config"]["cost"]
    assert [(r["method"], r["tol"], r["variant"]) for r in rows] == [
        (m, t, v) for m in cfg["methods"] for t in cfg["tols"] for v in ("stateless", "carried")]
    for row in rows:
        assert row["measured"] >= 0.8 * row["steps"], row
        assert row["measured"] + sum(row["skipped"].values()) == row["steps"], row
        assert 0 < row["ratio"]["median"] <= row["ratio"]["p99"] <= row["ratio"]["max"], row
        assert row["fixed_substeps"]["median"] >= 1
        assert row["within_tol_where_met"] >= 0.95, row


def test_quick_report_has_every_section_and_finite_numbers(quick_run) -> None:
    _, page = quick_run
    for section in SECTIONS:
        assert section in page, section
    assert not re.search(r"\b(nan|NaN)\b", page)
    assert not re.search(r"\binf\b", page)
    assert "A `--quick` run" in page
    # the default scene's table: every error of ours is a finite number or "diverged"
    rows = _table_rows(page, "### paper:")
    assert len(rows) >= 10
    for row in rows:
        assert row[2] == "diverged" or math.isfinite(float(row[2])), row


def test_render_of_the_quick_results_is_the_quick_page(quick_run, tmp_path: Path) -> None:
    results, page = quick_run
    assert report.render(results) == page


def test_quick_report_rk4_errors_fall_as_the_tolerance_tightens(quick_run) -> None:
    _, page = quick_run
    rows = _table_rows(page, "### paper:")
    auto = [(float(r[1].split()[1]), float(r[2])) for r in rows if r[0].startswith("rk4 auto")]
    assert len(auto) >= 3
    auto.sort(reverse=True)  # loosest tolerance first
    errors = [e for _, e in auto]
    assert all(b < a for a, b in pairwise(errors)), auto
    # and the error stays within 100 times the tolerance per control step over the episode
    assert all(e <= 100 * tol for tol, e in auto), auto
    fixed = [(int(r[1].lstrip("×")), float(r[2])) for r in rows if r[0] == "rk4"]
    fixed.sort()
    errors = [e for _, e in fixed]
    assert all(b < a for a, b in pairwise(errors)), fixed


# -- the real checks: our physics against MuJoCo and DOP853 ------------------------------------
def step_through(scene: Scene, torques: np.ndarray, dt: float) -> float:
    """φ [rad] at the end of the torques, stepped by the default integrator from rest."""
    phi, phi_dot = 0.0, 0.0
    for tau in torques:
        r = integ.step(scene, phi, phi_dot, float(tau), dt, tolerance=1e-8)
        phi, phi_dot = r.phi, r.phi_dot
    return phi


def _reference(wp, scene: Scene, torques: np.ndarray, dt: float) -> np.ndarray:
    return wp.run_dop853(scene, [float(t) for t in torques], dt, 1e-13).states


def test_stepper_episode_matches_the_reference(wp) -> None:
    """An episode through the environments' stepper at default settings stays within 100 ×
    the tolerance of the DOP853 reference, and a coarse fixed-substep one does not."""
    scene, dt = preset("paper"), wp.DT
    torques = [float(t) for t in wp.episode_torques(40, seed=1)]
    ref = _reference(wp, scene, np.array(torques), dt)
    fine = integ.Stepper(scene, dt=dt, tolerance=wp.DEFAULT_TOL)
    coarse = integ.Stepper(scene, integrator="euler", dt=dt, tolerance=1e-8, substeps=1)
    err_fine = wp.global_error(wp.run_kernel(fine, torques).states, ref)
    err_coarse = wp.global_error(wp.run_kernel(coarse, torques).states, ref)
    assert err_fine[0] <= 100 * wp.DEFAULT_TOL, err_fine
    assert err_coarse[0] > 1e3 * err_fine[0], (err_coarse, err_fine)


@pytest.mark.parametrize(("name", "tolerance"), [("paper", 1e-9), ("floor", 1e-8),
                                                  ("drum", 1e-9)])
def test_mujoco_model_agrees_with_our_reference(wp, mjr, name: str, tolerance: float) -> None:
    """MuJoCo tuned (timestep 0.125 ms) stays within ``tolerance`` rad of our DOP853
    reference over 1 s of random torques, and its error falls as the timestep shrinks."""
    scene, dt = preset(name), 0.05
    torques = wp.episode_torques(20, seed=1)
    ref = _reference(wp, scene, torques, dt)
    errors = []
    for n in (100, 400):
        sim = mjr.MujocoRoller(scene, mjr.tuned(dt / n))
        states = sim.run(0.0, 0.0, torques, dt)
        assert not sim.diverged
        errors.append(np.abs(states - ref).max(axis=0))
    assert errors[1][0] <= tolerance, errors
    assert errors[1][1] <= 10 * tolerance, errors
    # the soft constraint's error falls as timestep²: 16 times for 4 times smaller steps
    assert errors[1][0] < errors[0][0] / 8, errors
    assert np.abs(ref[:, 0]).max() > 0.1  # the torques moved the roller


def test_mujoco_defaults_are_a_different_regime(wp, mjr) -> None:
    """At MuJoCo's defaults the soft constraint shows: over the same second of torques its
    error is at least 1000 × that of MuJoCo tuned (timestep 0.125 ms) and of our default
    integrator, both measured here against the DOP853 reference."""
    scene, dt = preset("paper"), 0.05
    torques = wp.episode_torques(20, seed=1)
    ref = _reference(wp, scene, torques, dt)
    default = np.abs(mjr.MujocoRoller(scene, mjr.DEFAULT).run(0.0, 0.0, torques, dt)
                     - ref).max(axis=0)[0]
    tuned = np.abs(mjr.MujocoRoller(scene, mjr.tuned(1.25e-4)).run(0.0, 0.0, torques, dt)
                   - ref).max(axis=0)[0]
    ours = abs(step_through(scene, torques, dt) - ref[-1, 0])
    assert default > 1000 * max(tuned, ours), (default, tuned, ours)


def test_synthetic_results_keep_the_shape_of_measured_ones(quick_run) -> None:
    """The synthetic results above have the keys of real ones (so the render tests test the
    real format)."""
    measured, _ = quick_run
    synthetic = synthetic_results()

    def keys(x: object, depth: int) -> set[str]:
        if not isinstance(x, dict) or depth == 0:
            return set()
        names = {k: "N" if k.isdigit() else k for k in x}  # sizes: the measured ones vary
        return set(names.values()) | {f"{names[k]}.{k2}" for k, v in x.items()
                                      for k2 in keys(v, depth - 1)}

    for part in ("settings", "environments"):
        assert keys(synthetic[part], 3) == keys(measured[part], 3), part
    assert set(synthetic["scenes"][0]) == set(measured["scenes"][0])
    assert set(synthetic["scenes"][0]["runs"][0]) == set(measured["scenes"][0]["runs"][0])
    assert set(synthetic["scenes"][0]["reference"]) == set(measured["scenes"][0]["reference"])
    assert set(synthetic["scenes"][0]["energy"][0]) == set(measured["scenes"][0]["energy"][0])
    assert set(synthetic["config"]) <= set(measured["config"])
    assert set(synthetic) == set(measured)
    assert set(synthetic["cost"]) == set(measured["cost"])
    assert set(synthetic["cost"]["settings"]) == set(measured["cost"]["settings"])
    assert keys(synthetic["cost"]["rows"][0], 2) == keys(measured["cost"]["rows"][0], 2)


# -- the cost measurement: the smallest fixed count and the references ---------------------------
def test_smallest_fixed_counts_finds_the_threshold_of_a_monotone_test() -> None:
    """Where meeting tol is ``count >= threshold``, the search returns each threshold (1,
    powers of two and their neighbours, the largest count) and 0 where none meets it."""
    most = 1000
    thresholds = np.array([1, 2, 3, 7, 8, 9, 255, 256, 257, 999, 1000, 1001, 5000])
    calls = []

    def meets(index: np.ndarray, counts: np.ndarray) -> np.ndarray:
        assert np.all((counts >= 1) & (counts <= most))
        calls.append(index.size)
        return counts >= thresholds[index]

    got = cost.smallest_fixed_counts(meets, thresholds.size, most)
    want = np.where(thresholds <= most, thresholds, 0)
    np.testing.assert_array_equal(got, want)
    assert len(calls) <= 2 * math.ceil(math.log2(most)) + 2  # doubling, then bisection


def _solve(scene: Scene, phi: float, w: float, tau: float, dt: float) -> np.ndarray:
    """DOP853 at rtol = atol = 1e-13 on ``equations.accel``, one roller alone."""
    sol = solve_ivp(lambda _t, y: [y[1], eq.accel(y[0], y[1], tau, *scene.params)], (0, dt),
                    [phi, w], method="DOP853", rtol=1e-13, atol=1e-13, max_step=dt / 50)
    return sol.y[:, -1]


def test_cost_row_gives_the_least_fixed_count_of_a_linear_scan() -> None:
    """One easy step (paper, rk4, tol 1e-10): the row's smallest fixed count is the first
    count of a linear scan whose error (against DOP853 run here, one roller alone) is within
    tol, and its ratio is the automatic count over it in right-hand-side evaluations (rk4's
    adaptive substep is a Bogacki–Shampine 5(4) step, its fixed substep a classical one)."""
    scene, (phi, w, tau), tol, dt = preset("paper"), (0.7, 2.0, 0.3), 1e-10, 0.05
    ref = _solve(scene, phi, w, tau, dt)

    def err(res: integ.StepResult) -> float:
        return max(abs(res.phi - ref[0]), abs(res.phi_dot - ref[1]))

    scan = next(n for n in range(1, 1000)
                if err(integ.step(scene, phi, w, tau, dt, integrator="rk4", substeps=n)) <= tol)
    assert scan & (scan - 1)  # not a power of two: the bisection decided it
    batch = Scene.stack([scene])
    a = [np.array([x]) for x in (phi, w, tau)]
    auto = integ.step(batch, *a, dt, integrator="rk4", tolerance=tol)
    row = cost.compare(batch, *a, auto, ref.reshape(2, 1), np.zeros(1), "rk4", tol)
    assert row["measured"] == 1 and row["fixed_substeps"]["max"] == scan
    per_auto, per_fixed = 7, 4  # the pair's 8 stages, the first the last substep's end; RK4's 4
    assert row["ratio"]["median"] == pytest.approx(auto.substeps[0] * per_auto
                                                   / (scan * per_fixed))
    assert row["within_tol"] == (err(auto) <= tol)


def test_cost_references_agree_with_one_roller_alone() -> None:
    """The benchmark's references (DOP853 on groups of rollers as one system) on 12 steps of
    its sample: where their stated uncertainty lets them judge tol = 1e-8 (at most tol/10),
    within tol/10 of DOP853 on each roller alone, and that is most of the steps."""
    scene, phi, w, tau = cost.adversarial_sample(12, 5)
    ref, unc = cost.references(scene, phi, w, tau)
    sure = np.flatnonzero(unc <= 1e-9)
    assert sure.size >= 9, unc
    for i in sure:
        alone = _solve(scene.item(int(i)), phi[i], w[i], tau[i], cost.DT)
        assert np.abs(ref[:, i] - alone).max() <= 1e-9, (i, ref[:, i], alone)
