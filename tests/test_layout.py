"""The layout's promises: what each layer imports, and the README's two commands."""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def imported_modules(path: Path) -> set[str]:
    """The top-level names of every module a source file imports."""
    tree = ast.parse(path.read_text())
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module.split(".")[0])
    return names


@pytest.mark.parametrize("path", sorted((ROOT / "envs" / "physics").rglob("*.py")), ids=str)
def test_physics_knows_nothing_of_gymnasium_or_pygame(path: Path) -> None:
    assert not imported_modules(path) & {"gymnasium", "gym", "pygame"}


@pytest.mark.parametrize(
    "name", ["task.py", "rewards.py", "stabilize.py", "hold.py", "balance.py", "config.py"]
)
def test_tasks_know_nothing_of_pygame(name: str) -> None:
    assert "pygame" not in imported_modules(ROOT / "envs" / name)


def test_import_roller_gym_does_not_import_pygame() -> None:
    code = "import roller_gym, sys; print('pygame' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT)
    assert out.stdout.strip() == "False"


def test_readme_commands_are_make_targets_and_ci_runs_the_test_command() -> None:
    readme = (ROOT / "README.md").read_text()
    block = re.search(r"## Set-up: two commands.*?```bash\n(.*?)```", readme, re.S)
    assert block is not None, "README has no set-up block"
    commands = [line.split("#")[0].strip() for line in block.group(1).splitlines()]
    commands = [c for c in commands if c]
    assert commands == ["make run", "make test"]
    makefile = (ROOT / "Makefile").read_text()
    for target in ("run", "test"):
        assert re.search(rf"^{target}:", makefile, re.M), f"Makefile lacks '{target}:'"
    ci = (ROOT / ".ci" / "run").read_text()
    assert re.search(r"^make test$", ci, re.M), ".ci/run must call the README's test command"


def test_every_package_folder_is_installed() -> None:
    """A folder with an ``__init__.py`` under a mapped folder is in ``[tool.setuptools]
    packages``: a wheel would leave out one that is not (e.g. a module split into a package)."""
    import tomllib

    setup = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(setup["packages"])
    found = set()
    for name, folder in setup["package-dir"].items():
        for init in (ROOT / folder).rglob("__init__.py"):
            rel = init.parent.relative_to(ROOT / folder).parts
            if rel and any(".venv" in p or p.startswith("_") for p in rel):
                continue
            found.add(".".join((name, *rel)))
    assert "roller_gym.physics.integrators" in found
    assert found <= listed, f"not in [tool.setuptools] packages: {sorted(found - listed)}"


def test_no_source_file_of_the_package_exceeds_600_lines() -> None:
    """Each module holds one idea: none of the package's sources (envs/, agents/, scripts/) is
    over 600 lines, except a generated one that says so in its first line."""
    long = []
    for folder in ("envs", "agents", "scripts"):
        for path in (ROOT / folder).rglob("*.py"):
            lines = path.read_text().splitlines()
            if len(lines) > 600 and "generated" not in (lines[0] if lines else "").lower():
                long.append(f"{path.relative_to(ROOT)}: {len(lines)} lines")
    assert not long, long
