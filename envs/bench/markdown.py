"""What the benchmarks' pages share: Markdown tables, dates and ratios in words, and the block
that says on what machine, when and by which command the results were measured and how to
measure them again.
"""

from __future__ import annotations

import datetime
from typing import Any

Results = dict[str, Any]


def md_table(header: list[str], rows: list[list[str]]) -> list[str]:
    """A Markdown table's lines."""
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    return out


def date(iso: str) -> str:
    """An ISO date and time as the pages write it (``2026-01-01 09:00 UTC``)."""
    try:
        return datetime.datetime.fromisoformat(iso).strftime("%Y-%m-%d %H:%M %Z").strip()
    except ValueError:
        return iso


def faster(ratio: float) -> str:
    """A speed ratio in words: "4% faster", "2% slower" or "as fast" (within 0.5%)."""
    if abs(ratio - 1) < 0.005:
        return "as fast"
    return f"{abs(ratio - 1):.0%} {'faster' if ratio > 1 else 'slower'}"


def machine_section(results: Results, rerun: str, results_file: str) -> list[str]:
    """The "Machine and command" section: the CPU, cores, OS, Python and versions recorded
    with the results, the date, the command that measured them, and how to measure and
    render again (``rerun``: Markdown); ``results_file``: the JSON, relative to the page."""
    m = results["machine"]
    versions = ", ".join(f"{k} {v or '(not installed)'}" for k, v in m["versions"].items())
    return [
        "## Machine and command", "",
        f"- CPU: {m['cpu']}, {m['cores']} cores ({m['os']}), Python {m['python']}",
        f"- {versions}",
        f"- Date: {date(results['date'])} (timings are best-of-repeats, and only ratios "
        "measured in this run are compared)",
        f"- Command: `{results['command']}`; the numbers are in "
        f"[`{results_file}`]({results_file}). {rerun}", "",
    ]
