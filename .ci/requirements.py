"""Print the third-party requirements of roller-gym with the given extras, one per line, as
pyproject.toml declares them (an extra that names ``roller-gym[...]`` brings in those
extras). The Makefile installs them before the project itself, so that a venv's packages can
be installed beside another build of the tree.

    python3 .ci/requirements.py train,render
"""

from __future__ import annotations

import re
import sys
import tomllib
from pathlib import Path

PROJECT = tomllib.loads((Path(__file__).resolve().parents[1] / "pyproject.toml").read_text())
NAME = PROJECT["project"]["name"]
SELF = re.compile(rf"^{re.escape(NAME)}\[(?P<extras>[^\]]*)\]$")


def requirements(extras: list[str]) -> list[str]:
    """The base dependencies and those of ``extras``, self-references expanded, in order,
    each once."""
    optional = PROJECT["project"]["optional-dependencies"]
    out: list[str] = list(PROJECT["project"]["dependencies"])
    todo, seen = list(extras), set()
    while todo:
        extra = todo.pop(0).strip()
        if not extra or extra in seen:
            continue
        if extra not in optional:
            raise SystemExit(f"extras: {extra!r} is not an extra of {NAME}; "
                             f"its extras are {', '.join(sorted(optional))}")
        seen.add(extra)
        for req in optional[extra]:
            own = SELF.match(req.replace(" ", ""))
            if own:
                todo.extend(own["extras"].split(","))
            elif req not in out:
                out.append(req)
    return out


if __name__ == "__main__":
    print("\n".join(requirements(",".join(sys.argv[1:]).split(","))))
