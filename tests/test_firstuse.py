"""The first-use benchmark's command and results file (no timing here: the benchmark times)."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest
from roller_gym.bench import firstuse

RESULTS_FILE = Path(__file__).resolve().parents[1] / "docs" / "benchmarks" / "firstuse.json"


def test_help_names_every_case(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as stop:
        firstuse.main(["--help"])
    assert stop.value.code == 0
    text = capsys.readouterr().out
    assert all(case in text for case in firstuse.CASES)


def test_the_committed_results_hold_each_case_cold_and_warm() -> None:
    results = json.loads(RESULTS_FILE.read_text())
    firstuse.check(results)  # raises on a missing key
    assert results["cases"] and set(results["cases"]) <= set(firstuse.CASES)
    for record in results["cases"].values():
        for kind in firstuse.RECORD_KEYS:
            run = record[kind]
            assert 0 < run["import_s"] <= run["first_s"] <= run["process_s"]
    assert results["machine_before"]["cpu_count"] >= 1
    assert len(results["machine_before"]["load_average"]) == 3


def test_check_names_what_a_record_lacks() -> None:
    results = json.loads(RESULTS_FILE.read_text())
    broken = copy.deepcopy(results)
    del broken["cases"]["single"]["warm"]["first_s"]
    with pytest.raises(ValueError, match=r"single.*warm.*first_s"):
        firstuse.check(broken)
    broken = copy.deepcopy(results)
    broken["cases"]["cartpole"] = broken["cases"]["single"]
    with pytest.raises(ValueError, match="unknown case 'cartpole'"):
        firstuse.check(broken)
