"""The base install (no extras), simulated in a subprocess of this environment.

The test environment has every extra installed; a user of ``pip install .`` has only the
base dependencies (gymnasium, numpy, scipy, numba) and theirs. :func:`extra_only_modules`
names the top-level modules of every installed distribution outside that closure (read from
the installed metadata), and :func:`run_cli` runs ``roller-gym`` in a subprocess where
importing any of them fails as if it were not installed (``sys.modules[name] = None``).
Nothing is uninstalled. :func:`pyproject_extra` reads what an extra adds from
pyproject.toml itself, independently of the package's own reading of its metadata.
"""

from __future__ import annotations

import functools
import re
import subprocess
import sys
import tomllib
from importlib import metadata
from pathlib import Path

from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parents[1]


def _canonical(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


@functools.cache
def base_distributions() -> frozenset[str]:
    """The distributions ``pip install .`` installs: roller-gym's requirements without an
    extra marker, and theirs, recursively (canonical names)."""
    seen: set[str] = set()
    todo = ["roller-gym"]
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        try:
            requires = metadata.requires(name) or []
        except metadata.PackageNotFoundError:
            continue
        for line in requires:
            req = Requirement(line)
            if req.marker is None or req.marker.evaluate({"extra": ""}):
                todo.append(_canonical(req.name))
    return frozenset(seen)


@functools.cache
def extra_only_modules() -> tuple[str, ...]:
    """The top-level import names that only the extras install."""
    base = base_distributions()
    return tuple(sorted(
        module for module, dists in metadata.packages_distributions().items()
        if not module.startswith("_") and module not in sys.stdlib_module_names
        and module != "roller_gym" and not any(_canonical(d) in base for d in dists)))


def run_cli(argv: list[str], blocked: tuple[str, ...] | None = None, cwd: Path | None = None,
            timeout: float = 600) -> subprocess.CompletedProcess:
    """``roller-gym ARGV`` in a subprocess where the modules ``blocked`` (default: every
    module only an extra installs) cannot be imported."""
    blocked = extra_only_modules() if blocked is None else blocked
    code = (f"import sys\nfor name in {list(blocked)!r}:\n"
            "    if name not in sys.modules:\n        sys.modules[name] = None\n"
            "from roller_gym.scripts.cli import main\n"
            f"main({argv!r})")
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=cwd, timeout=timeout)


def pyproject_extra(extra: str) -> list[str]:
    """The distributions the extras ``extra`` (``"zoo,plots"``) name in pyproject.toml, its
    references to roller-gym's own extras expanded."""
    table = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"]
    out: list[str] = []
    for name in extra.split(","):
        for line in table[name]:
            req = Requirement(line)
            if _canonical(req.name) == "roller-gym":
                out += [d for d in pyproject_extra(",".join(sorted(req.extras))) if d not in out]
            elif req.name not in out:
                out.append(req.name)
    return out


def pyproject_version() -> str:
    """The version pyproject.toml declares."""
    return tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
