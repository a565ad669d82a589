"""The benchmark keeps working (``scripts/benchmark.py --quick``), and two real checks.

* The quick run writes a report with every section and only finite numbers, and its RK4
  errors fall as the tolerance tightens and as the substeps grow.
* The MuJoCo model of the scene (``roller_gym.bench.mujoco_roller``) and our physics agree: at
  the tuned settings MuJoCo's trajectory matches our DOP853 reference within a stated tolerance,
  and converges to it as the timestep shrinks. Two independent models of the same system
  agreeing is a cross-check of both.

No timing is asserted: the targets are reported by the benchmark, not tested.
"""

from __future__ import annotations

import math
import re
import subprocess
import sys
from itertools import pairwise
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]

mujoco = pytest.importorskip("mujoco")

from roller_gym.physics import Scene, preset  # noqa: E402
from roller_gym.physics import integrators as integ  # noqa: E402
from roller_gym.scripts import benchmark  # noqa: E402
from roller_gym.bench import mujoco_roller as mjr  # noqa: E402

SECTIONS = ("## Summary", "## Machine and command", "## How it is measured",
            "## 1. Work-precision", "### Energy at zero torque", "## 2. MuJoCo on the same scene",
            "## 3. Throughput", "## 4. Hard cases", "## The targets: what is met")


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


@pytest.fixture(scope="module")
def quick_report(tmp_path_factory: pytest.TempPathFactory) -> str:
    out = tmp_path_factory.mktemp("bench")
    proc = subprocess.run(
        [sys.executable, "-m", "roller_gym.scripts.benchmark", "--quick", "--out", str(out)],
        capture_output=True, text=True, timeout=600, cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    report = out / "BENCHMARKS.md"
    assert report.exists()
    for png in ("work_precision.png", "energy.png"):
        assert (out / "benchmarks" / png).stat().st_size > 10_000
    return report.read_text()


def test_quick_report_has_every_section_and_finite_numbers(quick_report: str) -> None:
    for section in SECTIONS:
        assert section in quick_report, section
    assert not re.search(r"\b(nan|NaN)\b", quick_report)
    assert not re.search(r"\binf\b", quick_report)
    assert "A `--quick` run" in quick_report
    # the default scene's table: every error of ours is a finite number or "diverged"
    rows = _table_rows(quick_report, "### paper:")
    assert len(rows) >= 10
    for row in rows:
        assert row[2] == "diverged" or math.isfinite(float(row[2])), row


def test_quick_report_rk4_errors_fall_as_the_tolerance_tightens(quick_report: str) -> None:
    rows = _table_rows(quick_report, "### paper:")
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


def step_through(scene: Scene, torques: np.ndarray, dt: float) -> float:
    """φ [rad] at the end of the torques, stepped by the default integrator from rest."""
    phi, phi_dot = 0.0, 0.0
    for tau in torques:
        r = integ.step(scene, phi, phi_dot, float(tau), dt, tol=1e-8)
        phi, phi_dot = r.phi, r.phi_dot
    return phi


def _reference(scene: Scene, torques: np.ndarray, dt: float) -> np.ndarray:
    return benchmark.run_dop853(scene, [float(t) for t in torques], dt, 1e-13).states


@pytest.mark.parametrize(("name", "tolerance"), [("paper", 1e-9), ("floor", 1e-8),
                                                  ("drum", 1e-9)])
def test_mujoco_model_agrees_with_our_reference(name: str, tolerance: float) -> None:
    """MuJoCo tuned (timestep 0.125 ms) stays within ``tolerance`` rad of our DOP853
    reference over 1 s of random torques, and its error falls as the timestep shrinks."""
    scene, dt = preset(name), 0.05
    torques = benchmark.episode_torques(20, seed=1)
    ref = _reference(scene, torques, dt)
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


def test_mujoco_defaults_are_a_different_regime() -> None:
    """At MuJoCo's defaults the soft constraint shows: over the same second of torques its
    error is at least 1000 × that of MuJoCo tuned (timestep 0.125 ms) and of our default
    integrator, both measured here against the DOP853 reference."""
    scene, dt = preset("paper"), 0.05
    torques = benchmark.episode_torques(20, seed=1)
    ref = _reference(scene, torques, dt)
    default = np.abs(mjr.MujocoRoller(scene, mjr.DEFAULT).run(0.0, 0.0, torques, dt)
                     - ref).max(axis=0)[0]
    tuned = np.abs(mjr.MujocoRoller(scene, mjr.tuned(1.25e-4)).run(0.0, 0.0, torques, dt)
                   - ref).max(axis=0)[0]
    ours = abs(step_through(scene, torques, dt) - ref[-1, 0])
    assert default > 1000 * max(tuned, ours), (default, tuned, ours)


def test_cost_at_error_interpolates_and_extrapolates() -> None:
    pts = [(1e-2, 1.0), (1e-4, 10.0), (1e-6, 100.0)]  # error falls 100 × per 10 × cost
    cost, how = benchmark.cost_at_error(pts, 1e-5)
    assert how == "interpolated" and cost == pytest.approx(10 ** 1.5)
    cost, how = benchmark.cost_at_error(pts, 1e-8)
    assert how == "extrapolated" and cost == pytest.approx(1000.0)
    cost, how = benchmark.cost_at_error(pts, 1.0)
    assert how == "reached at its cheapest setting" and cost == 1.0
    cost, how = benchmark.cost_at_error([(1e-2, 1.0), (1e-2, 2.0)], 1e-3)
    assert math.isnan(cost) and how.startswith("not reached")
    cost, how = benchmark.cost_at_error(pts, 1e-20)  # too far to extrapolate
    assert math.isnan(cost) and how.startswith("not reached")
