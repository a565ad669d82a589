"""The compiled kernels' disk cache where the package's folder is read-only (a Docker image,
a shared site-packages): numba then caches in the user-wide folder (``$XDG_CACHE_HOME/numba``),
so that a second process (a Ray worker, a SubprocVecEnv child) loads the kernels instead of
compiling them again: those of a single env, of a small vector env and of one on all cores
(PARALLEL_THRESHOLD sub-environments).

Each process runs a read-only copy of the package with an empty user-wide cache of the
test's own; as root, whom file permissions do not stop, the copy is mounted read-only in a
mount namespace of the process's own (skipped where that is not possible).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
import roller_gym
from roller_gym.physics.integrators import PARALLEL_THRESHOLD

TASK = "roller_gym/RollerStabilize-v2"

# The child: a single env, a vector env on one core and one on all cores, one step each; reports the
# package's folder, whether it could write there, the package's compiles (numba's events)
# and its dispatchers loaded from the cache (whether each runs on all cores).
_CHILD = f"""
import json, sys, tempfile
from numba.core import event
compiled = []
class Listen(event.Listener):
    def on_start(self, ev):
        f = ev.data["dispatcher"].py_func
        if f.__module__.startswith("roller_gym"):
            compiled.append(f.__module__ + "." + f.__qualname__)
    def on_end(self, ev):
        pass
event.register("numba:compile", Listen())
import gymnasium as gym
import numba
import roller_gym
folder = roller_gym.__path__[0]
try:
    tempfile.TemporaryFile(dir=folder).close()
    writable = True
except OSError:
    writable = False
envs = (gym.make({TASK!r}), gym.make_vec({TASK!r}, num_envs=4,
                                          vectorization_mode="vector_entry_point"),
        gym.make_vec({TASK!r}, num_envs={PARALLEL_THRESHOLD},
                     vectorization_mode="vector_entry_point"))
for env in envs:
    env.reset(seed=0)
    env.step(env.action_space.sample())
hits = {{}}
for env in envs:  # the task's kernels (made per task, not module attributes)
    k = env.unwrapped._outcome.kernels
    for value in (k.loop, k.parallel, *k.fused.values(), *k.one.values()):
        if hasattr(value, "c_functions"):  # the parallel fused kernel's C functions
            for c in value.c_functions():
                if c.cache_hits:
                    hits["c." + c.__qualname__] = False
        elif sum(value.stats.cache_hits.values()):
            hits["task." + value.py_func.__qualname__] = bool(value.targetoptions.get("parallel"))
for name, module in list(sys.modules.items()):
    if name.startswith("roller_gym"):
        for attr, value in vars(module).items():
            if isinstance(value, numba.core.dispatcher.Dispatcher):
                n = sum(value.stats.cache_hits.values())
                if n:
                    hits[name + "." + attr] = bool(value.targetoptions.get("parallel"))
print(json.dumps({{"folder": folder, "writable": writable, "compiled": compiled,
                  "hits": hits}}))
"""


def _read_only_copy(root: Path) -> Path:
    """A copy of the package (no caches) as ``root/site/roller_gym``, read-only."""
    site = root / "site"
    shutil.copytree(Path(roller_gym.__file__).parent, site / "roller_gym",
                    ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
    for path in sorted(site.rglob("*"), reverse=True):
        path.chmod(0o555 if path.is_dir() else 0o444)
    site.chmod(0o555)
    return site


def _run(site: Path, cache: Path) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(PYTHONPATH=str(site), XDG_CACHE_HOME=str(cache))
    command = [sys.executable, "-c", _CHILD]
    if os.geteuid() == 0:  # root writes anywhere: mount the copy read-only
        command = ["unshare", "-m", "sh", "-c", 'mount --bind -o ro "$0" "$0" && exec "$@"',
                   str(site), *command]
    proc = subprocess.run(command, env=env, capture_output=True, text=True, cwd=cache,
                          check=False)
    if proc.returncode != 0 and os.geteuid() == 0 and "mount" in proc.stderr:
        pytest.skip(f"no read-only mount for root here: {proc.stderr.strip()}")
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.slow
def test_a_read_only_package_caches_user_wide() -> None:
    root = Path(tempfile.mkdtemp(prefix="roller-gym-readonly-"))
    try:
        site, cache = _read_only_copy(root), root / "cache"
        cache.mkdir()
        first = _run(site, cache)
        assert first["folder"] == str(site / "roller_gym")  # the copy, not the checkout
        assert not first["writable"]
        assert first["compiled"], "an empty cache, yet nothing was compiled"
        assert not list((site / "roller_gym").rglob("*.nbi"))  # nothing beside the package
        assert list((cache / "numba").rglob("*.nbi")), "nothing cached user-wide"
        second = _run(site, cache)
        assert second["compiled"] == []  # every kernel loaded from the first one's cache
        assert second["hits"], "nothing loaded from the cache"
        assert any(second["hits"].values()), "no parallel kernel loaded from the cache"
        assert any(name.startswith("c.") for name in second["hits"]), "no C function loaded"
    finally:
        for path in root.rglob("*"):
            if path.is_dir():
                path.chmod(0o755)
        root.chmod(0o755)
        shutil.rmtree(root)
