"""rl-zoo3 in the test process, without its side effect on the other tests.

Importing ``rl_zoo3`` replaces Gymnasium's ``TimeLimit`` wrapper for the whole process
(``rl_zoo3.gym_patches``: every time-limited environment then adds ``"TimeLimit.truncated"``
to its info). :func:`import_rl_zoo3` imports it and puts Gymnasium's wrapper back, so tests
that compare infos see Gymnasium's own behaviour whatever ran before them.
"""

from __future__ import annotations

import importlib
import importlib.util
from types import ModuleType

import gymnasium
import gymnasium.envs.registration
import gymnasium.wrappers
import gymnasium.wrappers.common
import pytest

HAVE_RL_ZOO3 = importlib.util.find_spec("rl_zoo3") is not None
NEEDS_RL_ZOO3 = pytest.mark.skipif(
    not HAVE_RL_ZOO3, reason="rl-zoo3 is not installed (the zoo extra; CI installs it)")

_PATCHED = [(gymnasium.wrappers, "TimeLimit"), (gymnasium.wrappers.common, "TimeLimit"),
            (gymnasium.envs.registration, "TimeLimit")]


def import_rl_zoo3(name: str = "rl_zoo3") -> ModuleType:
    """``importlib.import_module(name)`` (a module of rl-zoo3), Gymnasium's TimeLimit kept."""
    absent = object()
    saved = [(owner, attr, getattr(owner, attr, absent)) for owner, attr in _PATCHED]
    try:
        return importlib.import_module(name)
    finally:
        for owner, attr, value in saved:
            if value is absent:
                if hasattr(owner, attr):
                    delattr(owner, attr)
            else:
                setattr(owner, attr, value)
