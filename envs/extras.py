"""The package's extras (pyproject.toml's ``optional-dependencies``): how to install one and
what it adds.

roller-gym is not published on PyPI yet, so an extra installs from a clone of the repository
(``pip install ".[zoo]"``); :func:`install_line` is the one place that says so, for every
message that tells a user what to install. What an extra adds is read from the installed
package's metadata (:func:`packages`), so it is pyproject.toml's list, not a copy of it.
"""

from __future__ import annotations

import importlib.metadata
import re

__all__ = ["TORCH_CPU_INDEX", "install_line", "missing", "packages"]

_REQUIREMENT = re.compile(r"^\s*([A-Za-z0-9][A-Za-z0-9._-]*)(?:\[([^\]]*)\])?")
_EXTRA_MARKER = re.compile(r"""extra\s*==\s*["']([^"']+)["']""")


#: Where pip finds torch's CPU build (PyPI's torch is the CUDA build on Linux).
TORCH_CPU_INDEX = "https://download.pytorch.org/whl/cpu"


def install_line(extra: str) -> str:
    """The pip command that installs the extras ``extra`` (``"zoo,plots"``), run in a clone
    of the repository; for an extra that installs torch, with the index of its CPU build."""
    if "torch" in packages(extra):
        return f'pip install ".[{extra}]" --extra-index-url {TORCH_CPU_INDEX}'
    return f'pip install ".[{extra}]"'


def packages(extra: str) -> list[str]:
    """The packages the extras ``extra`` (``"zoo,plots"``) add to the base install, roller-gym's
    own extras expanded (``zoo`` includes ``train``); empty if roller-gym's metadata is not
    installed."""
    try:
        requires = importlib.metadata.requires("roller-gym") or []
    except importlib.metadata.PackageNotFoundError:
        return []
    by_extra: dict[str, list[tuple[str, str]]] = {}
    for line in requires:
        requirement, _, marker = line.partition(";")
        found, name = _EXTRA_MARKER.search(marker), _REQUIREMENT.match(requirement)
        if found and name:
            by_extra.setdefault(found.group(1), []).append((name.group(1), name.group(2) or ""))
    out: list[str] = []

    def add(names: str, seen: set[str]) -> None:  # roller-gym's own extras first, in place
        for current in (e.strip() for e in names.split(",")):
            if current not in seen:
                seen.add(current)
                for name, extras in by_extra.get(current, []):
                    if name.replace("_", "-").lower() == "roller-gym":
                        add(extras, seen)
                    elif name not in out:
                        out.append(name)

    add(extra, set())
    return out


def missing(module: str, extra: str, what: str) -> ImportError:
    """The error to raise when ``module`` of ``extra`` is not installed: it names the module
    (``ImportError.name``, which ``roller-gym`` reads to answer in one line) and says what
    needs it and how to install it."""
    return ImportError(f"{what} needs {module}, which is not installed: {install_line(extra)} "
                       "(in a clone of the repository)", name=module)
