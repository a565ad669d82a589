"""The package as a pip user gets it: a non-editable wheel in a fresh virtual environment,
next to the PyPI packages ``envs`` and ``agents`` (whose top-level names roller-gym used to
install), used from outside the repository. (PyPI's ``agents`` needs tensorflow to import;
its files are checked instead.)"""

from __future__ import annotations

import site
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from base_install import pyproject_version

ROOT = Path(__file__).resolve().parents[1]


def run(*args: str | Path, cwd: Path) -> str:
    out = subprocess.run([str(a) for a in args], cwd=cwd, capture_output=True, text=True,
                         timeout=600)
    assert out.returncode == 0, f"{args}\n{out.stdout}\n{out.stderr}"
    return out.stdout


@pytest.fixture(scope="module")
def fresh_venv(tmp_path_factory) -> Path:
    """A new venv with the roller-gym wheel (no editable install) and ``envs`` and
    ``agents`` from PyPI; the third-party dependencies are this environment's (a .pth
    file), so that nothing heavy is installed twice."""
    tmp = tmp_path_factory.mktemp("wheel")
    run(sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
        "-w", tmp / "dist", ROOT, cwd=tmp)
    wheel = next((tmp / "dist").glob("roller_gym-*.whl"))
    venv = tmp / "venv"
    run(sys.executable, "-m", "venv", "--without-pip", venv, cwd=tmp)
    python = venv / "bin" / "python"
    target = run(python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])",
                 cwd=tmp).strip()
    Path(target, "_dependencies.pth").write_text(site.getsitepackages()[0] + "\n")
    pip = (sys.executable, "-m", "pip", "--python", python, "install", "-q", "--no-deps")
    run(*pip, wheel, cwd=tmp)
    run(*pip, "envs", "agents", cwd=tmp)
    return venv


def test_wheel_installs_one_import_name_beside_envs_and_agents(fresh_venv):
    python = fresh_venv / "bin" / "python"
    code = textwrap.dedent("""
        import importlib.metadata as md, importlib.util, pathlib, sys
        import gymnasium as gym
        import numpy as np
        import roller_gym, envs
        from roller_gym.agents import controller_for, rollout
        venv = pathlib.Path(sys.prefix)
        # PyPI's agents imports tensorflow when imported: check that its own files are
        # the ones installed under the name, whole, instead of importing it.
        spec = importlib.util.find_spec("agents")
        for origin in (roller_gym.__file__, envs.__file__, spec.origin):
            assert venv in pathlib.Path(origin).parents, origin
        assert not hasattr(envs, "ENV_IDS")
        for dist in ("envs", "agents"):
            for f in md.files(dist):
                assert pathlib.Path(f.locate()).exists(), f
        assert "tensorflow" in pathlib.Path(spec.origin).parent.joinpath(
            "algorithms", "ppo", "ppo.py").read_text()
        files = md.files("roller-gym")
        tops = {f.parts[0] for f in files if f.suffix == ".py"}
        assert tops == {"roller_gym"}, tops
        gym.register_envs(roller_gym)
        env = gym.make("roller_gym/RollerHold-v2")
        episode = rollout(env, controller_for(env), seed=0)
        assert episode.success
        vec = gym.make_vec("roller_gym/RollerStabilize-v2", num_envs=3)
        vec.reset(seed=0)
        vec.step(np.zeros((3, 1), np.float32))
        from roller_gym.agents.hyperparams import config_file
        assert "roller_gym/RollerStabilize-v2" in config_file("sac").read_text()
        print("ok")
    """)
    outside = fresh_venv.parent
    assert run(python, "-c", code, cwd=outside).strip() == "ok"
    # Uninstalling the other packages leaves roller-gym whole.
    run(sys.executable, "-m", "pip", "--python", python, "uninstall", "-y", "-q", "envs",
        "agents", cwd=outside)
    check = "import gymnasium as gym, roller_gym; gym.make('roller_gym/RollerTrack-v1')"
    run(python, "-c", check, cwd=outside)
    # The no-import form of the ID imports the package itself.
    run(python, "-c", "import gymnasium as gym; "
        "gym.make('roller_gym:roller_gym/RollerStabilize-v2').reset(seed=0)", cwd=outside)


def test_console_command_is_installed(fresh_venv):
    out = run(fresh_venv / "bin" / "roller-gym", "--help", cwd=fresh_venv.parent)
    for command in ("train", "evaluate", "replay", "benchmark"):
        assert command in out


def test_the_wheel_reports_pyprojects_version(fresh_venv):
    """``roller-gym --version`` and ``roller_gym.__version__`` of a non-editable install are
    pyproject.toml's version (read from the wheel's metadata)."""
    version = pyproject_version()
    outside = fresh_venv.parent
    assert run(fresh_venv / "bin" / "roller-gym", "--version",
               cwd=outside).strip() == f"roller-gym {version}"
    assert run(fresh_venv / "bin" / "python", "-c",
               "import roller_gym; print(roller_gym.__version__)",
               cwd=outside).strip() == version
