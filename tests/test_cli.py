"""The ``roller-gym`` console command: every subcommand's --help explains every option of its
program's parser, bad commands fail clearly, and train -> evaluate -> replay work end to end
through the installed entry point."""

from __future__ import annotations

import argparse
import importlib
import json
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
from base_install import extra_only_modules, pyproject_extra, pyproject_version, run_cli
from packaging.version import Version
from roller_gym.scripts.cli import COMMANDS
from zoo import NEEDS_RL_ZOO3

#: Where pip finds torch's CPU build, as the README gives it.
CPU_INDEX = "--extra-index-url https://download.pytorch.org/whl/cpu"

#: The console script pip installs next to the interpreter (pip install -e . / a wheel).
ENTRY_POINT = Path(sys.executable).with_name("roller-gym")


def roller_gym(*args: str, cwd: Path | None = None, check: bool = True,
               timeout: float = 900) -> subprocess.CompletedProcess:
    assert ENTRY_POINT.is_file(), (
        f"{ENTRY_POINT} is missing: install the package (pip install -e .) so that "
        "[project.scripts] creates it")
    return subprocess.run([str(ENTRY_POINT), *args], capture_output=True, text=True,
                          check=check, cwd=cwd, timeout=timeout)


class _ParserCapturedError(Exception):
    def __init__(self, parser: argparse.ArgumentParser) -> None:
        self.parser = parser


def program_parser(command: str, monkeypatch) -> argparse.ArgumentParser:
    """The parser a command's program builds: run its main() until it parses its arguments."""
    try:
        program = importlib.import_module(f"roller_gym.scripts.{COMMANDS[command].module}")
    except ImportError as exc:
        pytest.skip(f"roller-gym {command} needs {exc.name}, not installed here")

    def capture(self, *args, **kwargs):
        raise _ParserCapturedError(self)

    monkeypatch.setattr(argparse.ArgumentParser, "parse_args", capture)
    with pytest.raises(_ParserCapturedError) as caught:
        program.main([])
    return caught.value.parser


@pytest.mark.parametrize("command", list(COMMANDS))
def test_help_lists_and_explains_every_option_of_the_programs_parser(command, monkeypatch):
    parser = program_parser(command, monkeypatch)
    monkeypatch.undo()
    out = roller_gym(command, "--help").stdout
    assert out.startswith(f"usage: roller-gym {command} ")
    actions = [a for a in parser._actions if not isinstance(a, argparse._HelpAction)]
    assert actions
    for action in actions:
        names = action.option_strings or [action.metavar or action.dest]
        for name in names:
            assert name in out, f"roller-gym {command} --help does not show {name}"
        assert action.help and action.help.strip(), f"{command} {names[0]} has no help text"
        # The explanation is printed (argparse wraps it; compare its first words).
        assert " ".join(action.help.split()[:3]).split("%")[0].strip() in " ".join(out.split())


def test_top_level_help_names_every_command():
    out = roller_gym("--help").stdout
    for name, command in COMMANDS.items():
        assert name in out and command.summary.split(";")[0] in " ".join(out.split())


@pytest.mark.parametrize("argv", [["frobnicate"], ["trian", "--steps", "3"]])
def test_an_unknown_command_fails_naming_it_and_the_allowed_ones(argv):
    result = roller_gym(*argv, check=False)
    assert result.returncode == 2 and result.stdout == ""
    assert f"invalid choice: '{argv[0]}'" in result.stderr
    for name in COMMANDS:
        assert f"'{name}'" in result.stderr


def test_no_command_fails_asking_for_one():
    result = roller_gym(check=False)
    assert result.returncode == 2 and "required: COMMAND" in result.stderr


def test_an_unknown_option_before_the_command_is_named():
    """(It was reported as a missing COMMAND.)"""
    result = roller_gym("--nope", "train", check=False)
    assert result.returncode == 2 and "unrecognized option '--nope'" in result.stderr
    for name in COMMANDS:
        assert name in result.stderr


@pytest.mark.parametrize(("command", "argv", "message"), [
    ("train", ["--steps", "-5"], "argument --steps: '-5' is not an integer >= 1"),
    ("train", ["--steps", "0"], "argument --steps: '0' is not an integer >= 1"),
    ("train", ["--checkpoints", "-1"], "argument --checkpoints: '-1' is not an integer >= 0"),
    ("train", ["--seed", str(2**32)],  # NumPy's legacy seeding, which rl-zoo3 calls
     f"argument --seed: '{2**32}' is not an integer >= 0 and <= {2**32 - 1}"),
    ("train", ["--eval-freq", "x"], "argument --eval-freq: 'x' is not an integer >= 1"),
    ("evaluate", ["--episodes", "0"], "argument --episodes: '0' is not an integer >= 1"),
    # past a C long (OverflowError in rl-zoo3 or torch once training ran), or past the threads
    # any machine has
    ("train", ["--threads", "1" + "0" * 400], "argument --threads: '1000"),
    ("train", ["--threads", "5000"], "argument --threads: '5000' is not an integer >= 1 and "
                                     "<= 1024"),
    ("train", ["--eval-episodes", str(2**63)], f"argument --eval-episodes: '{2**63}' is not"),
    ("train", ["--steps", "9" * 23], f"is not an integer >= 1 and <= {2**63 - 1} (2**63 - 1)"),
    # an episode's seed: the environments take any up to 2**64 - 1
    ("replay", ["classical", "--seed", str(2**64)],
     f"argument --seed: '{2**64}' is not an integer >= 0 and <= {2**64 - 1}"),
    ("train-rllib", ["--seed", str(2**32)], f"argument --seed: '{2**32}' is not an integer"),
    ("results", ["--train-wall-s", "nan"], "argument --train-wall-s: 'nan' is not a number in"),
    ("results", ["--train-wall-s", "-5"], "argument --train-wall-s: '-5' is not a number in"),
])
def test_counts_out_of_range_are_refused_naming_the_option(command, argv, message,
                                                           monkeypatch, capsys):
    parser = program_parser(command, monkeypatch)
    monkeypatch.undo()
    with pytest.raises(SystemExit):
        parser.parse_args(argv)
    assert message in capsys.readouterr().err


def test_evaluate_with_nothing_to_evaluate_says_so(tmp_path):
    pytest.importorskip("matplotlib")
    from roller_gym.scripts.evaluate import main

    with pytest.raises(SystemExit, match="nothing to evaluate on roller_gym/RollerStabilize-v2 "
                                         r"\(--runs .* holds no run of it\)"):
        main(["--runs", str(tmp_path), "--baselines", "--out", str(tmp_path / "out")])


def test_evaluate_refuses_a_runs_folder_that_does_not_exist(tmp_path, capsys):
    """A mistyped --runs is an error naming it (it exited 0 after evaluating the baselines,
    as if the runs had not trained)."""
    from roller_gym.scripts.evaluate import main

    missing = str(tmp_path / "nothing-here")
    with pytest.raises(SystemExit) as exit_info:
        main(["--runs", missing, "--out", str(tmp_path / "out")])
    assert exit_info.value.code == 2
    assert f"--runs {missing!r}: no such folder" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_version_is_pyprojects_from_the_command_and_the_package():
    import roller_gym as package

    version = pyproject_version()
    assert package.__version__ == version
    assert roller_gym("--version").stdout.strip() == f"roller-gym {version}"


def test_version_without_installed_metadata_is_a_valid_unknown_version():
    code = ("import importlib.metadata as md\n"
            "def missing(name):\n    raise md.PackageNotFoundError(name)\n"
            "md.version = missing\n"
            "import roller_gym; print(roller_gym.__version__)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=300).stdout.strip()
    assert out == "0+unknown"
    assert Version(out) < Version(pyproject_version())  # PEP 440, below any release


@pytest.mark.parametrize("command", list(COMMANDS))
def test_every_help_works_with_the_base_install_and_names_its_extra(command):
    """With only the base install's packages importable, ``--help`` prints the command's
    usage and ends naming its extra, the pip line that installs it from a clone and the
    packages it adds (as pyproject.toml lists them)."""
    assert "matplotlib" in extra_only_modules() and "numba" not in extra_only_modules()
    result = run_cli([command, "--help"])
    assert result.returncode == 0, result.stderr
    out = " ".join(result.stdout.split())
    assert out.startswith(f"usage: roller-gym {command} ")
    extra = COMMANDS[command].extra
    assert f'roller-gym {command} needs the extra [{extra}]' in out
    assert f'pip install ".[{extra}]"' in out
    for package in pyproject_extra(extra):
        assert package in out, f"{command} --help does not name {package}"
    # plain text in a terminal, not the docstrings' reST (``code``, :mod:`name`)
    assert "``" not in out and not re.search(r":\w+:`", out), out


@pytest.mark.parametrize(("argv", "missing"), [
    (["train", "--steps", "10"], "rl_zoo3"),
    (["evaluate", "--baselines", "zero", "--episodes", "1", "--out", "{tmp}"], "matplotlib"),
    (["results", "--runs", "{tmp}"], "matplotlib"),
    (["replay", "zero", "--env", "roller_gym/RollerStabilize-v2", "--out", "{tmp}/x.gif"],
     "imageio"),
    (["benchmark", "--quick", "--out", "{tmp}"], None),
    (["train-rllib", "--iterations", "1"], "ray"),
])
def test_every_command_without_its_extra_says_in_one_line_what_to_install(argv, missing,
                                                                          tmp_path):
    result = run_cli([a.replace("{tmp}", str(tmp_path)) for a in argv])
    extra = COMMANDS[argv[0]].extra
    assert result.returncode == 1, result.stderr
    assert "Traceback" not in result.stderr
    # (a kernel's first use announces its compile on stderr: not the message's line)
    (line,) = [x for x in result.stderr.strip().splitlines()
               if not x.startswith("roller_gym: compiling")]
    assert f'pip install ".[{extra}]"' in line
    if missing is not None:  # named, as a module or a distribution
        assert missing.replace("_", "-") in line.replace("_", "-")
    # an extra with torch: the index of its CPU build (else pip takes the CUDA one)
    assert (CPU_INDEX in line) == ("torch" in pyproject_extra(extra)), line


def test_importing_the_sb3_bridge_without_its_extra_says_what_to_install():
    """roller_gym.sb3 with the base install ended in stable-baselines3's ModuleNotFoundError;
    it now names itself, the module and the pip line (with torch's CPU index)."""
    code = ("import sys\nfor name in ('stable_baselines3', 'torch'):\n"
            "    sys.modules[name] = None\n"
            "try:\n    import roller_gym.sb3\n"
            "except ImportError as e:\n    print(e.name, '|', e)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=300).stdout.strip()
    name, message = out.split(" | ")
    assert name == "stable_baselines3"
    assert message.startswith("roller_gym.sb3 needs stable_baselines3, which is not installed")
    assert f'pip install ".[train]" {CPU_INDEX}' in message


def test_replay_refuses_an_output_it_cannot_write_before_rendering(tmp_path):
    """An --out in a folder that exists but cannot hold files ended in a traceback after the
    whole episode was rendered; now one line names --out first, and leaves nothing behind."""
    blocked = tmp_path / "file"
    blocked.write_text("")
    (tmp_path / "folder.gif").mkdir()
    for out in (blocked / "x.gif", tmp_path / "folder.gif"):  # under a file; a folder
        result = roller_gym("replay", "zero", "--env", "roller_gym/RollerStabilize-v2",
                            "--out", str(out), check=False)
        assert result.returncode == 1 and "Traceback" not in result.stderr, result.stderr
        assert result.stderr.strip().startswith("--out: cannot"), result.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file", "folder.gif"]


def test_a_report_that_cannot_be_written_is_refused_before_the_work(tmp_path):
    """--report in a folder that exists but cannot hold it (here: under a file) ended in a
    traceback after the evaluation; now one line names --report first."""
    blocked = tmp_path / "file"
    blocked.write_text("")
    for argv in (["evaluate", "--episodes", "1", "--baselines", "zero", "--out",
                  str(tmp_path / "e")],
                 ["results", "--render-only", "--out", str(tmp_path / "r")]):
        result = roller_gym(*argv, "--report", str(blocked / "x.md"), check=False)
        assert result.returncode == 1 and "Traceback" not in result.stderr, result.stderr
        assert result.stderr.strip().splitlines()[-1].startswith("--report: cannot"), argv


def test_replay_without_pygame_says_in_one_line_what_to_install(tmp_path):
    """pygame is imported only to draw: its absence is reported as one line too."""
    result = run_cli(["replay", "zero", "--env", "roller_gym/RollerStabilize-v2", "--out",
                      str(tmp_path / "x.gif")], blocked=("pygame",))
    assert result.returncode == 1 and "Traceback" not in result.stderr
    (line,) = result.stderr.strip().splitlines()
    assert "'pygame'" in line and 'pip install ".[zoo,render]"' in line


@NEEDS_RL_ZOO3
def test_train_show_command_is_rl_zoo3_with_the_shipped_file():
    from roller_gym.agents.hyperparams import config_file

    out = roller_gym("train", "--algo", "ppo", "--steps", "3000", "--show-command").stdout
    words = out.split()
    assert words[1:3] == ["-m", "roller_gym.scripts.zoo_train"]
    assert words[words.index("-conf") + 1] == str(config_file("ppo"))
    assert words[words.index("--gym-packages") + 1] == "roller_gym"
    # PPO's 3,000 steps become whole rollouts of 8 x 256: 4,096.
    assert words[words.index("--n-timesteps") + 1] == "4096"


@NEEDS_RL_ZOO3
def test_train_refuses_more_checkpoints_than_steps():
    """A checkpoint every 1000 // 5000 = 0 steps meant rl-zoo3 saved none, silently."""
    result = roller_gym("train", "--algo", "sac", "--steps", "1000", "--checkpoints", "5000",
                        "--show-command", check=False)
    assert result.returncode == 1 and "Traceback" not in result.stderr
    assert ("--checkpoints 5000: more checkpoints than the run's 1000 steps; give at most 1000"
            in result.stderr)
    words = roller_gym("train", "--algo", "sac", "--steps", "1000", "--checkpoints", "1000",
                       "--show-command").stdout.split()
    assert words[words.index("--save-freq") + 1] == "1"


@NEEDS_RL_ZOO3
def test_train_show_command_run_as_printed_trains_on_the_native_batch(tmp_path):
    """The printed command, run as it is in a shell, trains through the native batch as
    ``roller-gym train`` does: the batch's episode monitor is written, and no monitor of
    single environments under DummyVecEnv (``0.monitor.csv``, ``1.monitor.csv``)."""
    shown = roller_gym("train", "--steps", "300", "--eval-freq", "150", "--eval-episodes", "1",
                       "--verbose", "0", "--hyperparams", "n_envs:2", "--show-command",
                       cwd=tmp_path).stdout
    subprocess.run(shown, shell=True, check=True, cwd=tmp_path, capture_output=True,
                   timeout=900)
    (run_dir,) = (tmp_path / "runs" / "sac").iterdir()
    assert (run_dir / "batch.monitor.csv").is_file()
    assert not list(run_dir.glob("[0-9]*.monitor.csv"))


@NEEDS_RL_ZOO3
def test_train_hyperparams_reach_rl_zoo3_as_checked(tmp_path):
    """rl-zoo3 evaluates each ``-params`` value as Python: a string such as a linear schedule
    (``lin_5e-4``, as written in the hyperparameter files) must reach it as that string, read
    back here by rl-zoo3's own parser, not as a name it cannot evaluate."""
    from rl_zoo3.utils import StoreDict

    printed = roller_gym("train", "--algo", "td3", "--hyperparams", "learning_rate:lin_5e-4",
                         "policy_kwargs:dict(net_arch=[8])", "batch_size:64", "--show-command",
                         cwd=tmp_path).stdout
    argv = shlex.split(printed)
    start = argv.index("--hyperparams") + 1
    end = next((i for i in range(start, len(argv)) if argv[i].startswith("--")), len(argv))
    parser = argparse.ArgumentParser()
    parser.add_argument("--hyperparams", nargs="+", action=StoreDict)
    given = parser.parse_args(["--hyperparams", *argv[start:end]]).hyperparams
    assert given == {"learning_rate": "lin_5e-4", "policy_kwargs": "dict(net_arch=[8])",
                     "batch_size": 64}


@NEEDS_RL_ZOO3
def test_train_evaluate_replay_end_to_end(tmp_path):
    env_id = "roller_gym/RollerStabilize-v2"
    roller_gym("train", "--env", env_id, "--steps", "300", "--eval-freq", "150",
               "--eval-episodes", "1", "--verbose", "0", cwd=tmp_path)
    # rl-zoo3's experiment folder: no colon, no folder per namespace.
    (run_dir,) = (tmp_path / "runs" / "sac").iterdir()
    assert run_dir.name == "roller_gym-RollerStabilize-v2_1"
    # trained on the native batch (roller_gym.sb3), which wrote the episode of 200 steps
    assert not (run_dir / "0.monitor.csv").exists()  # (the probe's, of no episode)
    header, columns, *episodes = (run_dir / "batch.monitor.csv").read_text().splitlines()
    assert header.startswith("#{") and columns == "r,l,t"  # SB3 Monitor's format
    assert [row.split(",")[1] for row in episodes] == ["200"]

    roller_gym("evaluate", "--env", env_id, "--runs", "runs", "--episodes", "3",
               "--out", "results", "--report", "RESULTS.md", cwd=tmp_path)
    out = tmp_path / "results"
    table = (out / "RollerStabilize-v2.md").read_text()
    for label in ("SAC", "LQR", "zero torque", "random"):
        assert f"| {label} |" in table
    assert "| SAC | 300 |" in table  # the steps the run trained, read from its model
    numbers = json.loads((out / "RollerStabilize-v2.json").read_text())
    assert [p["name"] for p in numbers["policies"]] == ["sac", "classical", "zero", "random"]
    lqr = numbers["policies"][1]
    assert lqr["success_rate"] == 1.0 and len(lqr["returns"]) == 3
    for plot in ("learning", "trajectories"):
        assert (out / f"RollerStabilize-v2-{plot}.png").stat().st_size > 10_000
    assert "Target:" in (tmp_path / "RESULTS.md").read_text()

    roller_gym("replay", str(run_dir), "--out", "replay.gif", cwd=tmp_path)
    assert (tmp_path / "replay.gif").read_bytes()[:6] == b"GIF89a"
    bad = roller_gym("replay", "no-such-run", check=False, cwd=tmp_path)
    assert bad.returncode == 1 and "no-such-run" in bad.stderr and "classical" in bad.stderr


@pytest.mark.parametrize(("item", "expected"), [
    ("max_torque=0.6", {"max_torque": 0.6}),
    ("scene=floor", {"scene": "floor"}),
    ("randomize={'m': (0.8, 1.2)}", {"randomize": {"m": (0.8, 1.2)}}),
    ('randomize={"m": [0.8, 1.2]}', {"randomize": {"m": [0.8, 1.2]}}),
    ("substeps=None", {"substeps": None}),
    ("name=a=b", {"name": "a=b"}),
])
def test_key_values_reads_python_literals_else_strings(item, expected):
    from roller_gym.scripts.arguments import key_values

    assert key_values([item], "--env-kwargs") == expected


def test_key_values_refuses_an_item_that_is_not_key_value_naming_the_option():
    from roller_gym.scripts.arguments import key_values

    with pytest.raises(SystemExit, match="--env-kwarg: 'scene' is not KEY=VALUE"):
        key_values(["scene"], "--env-kwarg")
    with pytest.raises(SystemExit, match="--hyperparams: '=1' is not KEY:VALUE"):
        key_values(["=1"], "--hyperparams", ":")
    assert key_values(["n_envs:2"], "--hyperparams", ":") == {"n_envs": 2}
    with pytest.raises(SystemExit, match="--env-kwargs: 'dt' is given twice; give each key once"):
        key_values(["dt=0.05", "dt=0.1"], "--env-kwargs")


def test_train_refuses_a_log_folder_it_cannot_create_before_rl_zoo3_starts(monkeypatch):
    pytest.importorskip("rl_zoo3")
    import rl_zoo3.train
    from roller_gym.scripts import train

    monkeypatch.setattr(rl_zoo3.train, "train", lambda: pytest.fail("rl-zoo3 started"))
    with pytest.raises(SystemExit, match="--log-folder: cannot create the folder '/proc/x'"):
        train.main(["--log-folder", "/proc/x", "--steps", "64"])


def test_train_and_train_rllib_parse_env_kwargs_with_the_one_parser():
    from roller_gym.scripts import arguments

    for module in ("train", "train_rllib"):
        try:
            program = importlib.import_module(f"roller_gym.scripts.{module}")
        except ImportError as exc:
            pytest.skip(f"{module} needs {exc.name}, not installed here")
        assert program.checked_env_kwargs is arguments.checked_env_kwargs, module


@NEEDS_RL_ZOO3
def test_train_passes_env_kwargs_to_rl_zoo3_as_python_literals():
    from roller_gym.scripts import train

    args = train.build_parser().parse_args(
        ["--env-kwargs", "max_torque=0.6", "scene=floor", "randomize={'m': (0.8, 1.2)}"])
    argv = train.zoo_arguments(args, "conf.yml")
    at = argv.index("--env-kwargs")
    assert argv[at + 1:at + 4] == ["max_torque:0.6", "scene:'floor'",
                                   "randomize:{'m': (0.8, 1.2)}"]


@NEEDS_RL_ZOO3
@pytest.mark.parametrize(("item", "message"), [
    ("max_torque=-1", "--env-kwargs: max_torque=-1 is out of range"),
    ("bogus=3", "--env-kwargs: 'bogus' is not an argument of roller_gym/RollerStabilize-v2; "
                "allowed: scene, dt, max_torque,"),
    # (Gymnasium's make failed on it: AttributeError, 'int' object has no attribute 'endswith')
    ("render_mode=1", "--env-kwargs: render_mode=1 is not allowed: it must be None or one of "
                      "'human', 'rgb_array'"),
    ("dt=1" + "0" * 400, r"--env-kwargs: dt=10+\.\.\.0+ is out of range"),
    # (no time limit: a 600-step run's first evaluation never ended)
    ("max_episode_steps=-1", "--env-kwargs: max_episode_steps=-1 is not allowed: it must be an "
                             "integer >= 1"),
])
@pytest.mark.parametrize("show", [[], ["--show-command"]])
def test_train_refuses_env_kwargs_the_env_refuses_before_rl_zoo3_starts(item, message, show,
                                                                       tmp_path, monkeypatch):
    """A value the environment refuses ends ``train`` with the environment's message, and
    rl-zoo3's training is never entered (it would end in a traceback from its setup); with
    ``--show-command`` too, which would print a command that fails."""
    import rl_zoo3.train
    from roller_gym.scripts import train

    def never():
        raise AssertionError("rl-zoo3 started")

    monkeypatch.setattr(rl_zoo3.train, "train", never)
    with pytest.raises(SystemExit, match=message):
        train.main(["--env-kwargs", item, "--log-folder", str(tmp_path), *show])


@pytest.mark.parametrize(("item", "message"), [
    ("max_torque=-1", "--env-kwarg: max_torque=-1 is out of range"),
    ("bogus=3", "--env-kwarg: 'bogus' is not an argument of"),
])
def test_train_rllib_refuses_env_kwargs_the_env_refuses_before_ray_starts(item, message,
                                                                         monkeypatch):
    """The same for ``train-rllib``: the environment's message, and Ray never imported (here a
    stand-in that fails if it is)."""
    from roller_gym.scripts import train_rllib

    monkeypatch.setitem(sys.modules, "ray", None)  # importing it would raise ImportError
    with pytest.raises(SystemExit, match=message):
        train_rllib.main(["--env-kwarg", item])


@NEEDS_RL_ZOO3
@pytest.mark.parametrize(("algo", "item", "message"), [
    ("sac", "n_envs:0", "--hyperparams: n_envs:0 is not allowed: it must be an integer >= 1"),
    ("sac", "n_envs:-2", "--hyperparams: n_envs:-2 is not allowed"),
    ("ppo", "n_timesteps:2.5", "--hyperparams: n_timesteps:2.5 is not allowed"),
    ("ppo", "n_timesteps:1e400", "--hyperparams: n_timesteps:inf is not allowed"),
    ("sac", "n_envs:True", "--hyperparams: n_envs:True is not allowed"),
    # (make_vec_env's TypeError on a float; ZeroDivisionError; OverflowError)
    ("sac", "n_envs:2.0", "--hyperparams: n_envs:2.0 is not allowed"),
    ("ppo", "n_steps:0", "--hyperparams: n_steps:0 is not allowed"),
    ("sac", "n_envs:" + "1" * 400, "--hyperparams: n_envs:1{400} is not allowed"),
    ("ppo", "batch_size:-1", "--hyperparams: batch_size:-1 is not allowed"),
    ("sac", "bogus_key:3", "--hyperparams: 'bogus_key' is not a hyperparameter of sac; allowed: "
                           ".*learning_rate"),
    ("ppo", "buffer_size:10", "'buffer_size' is not a hyperparameter of ppo"),  # SAC's, not PPO's
    ("td3", "seed:3", "'seed' is set by roller-gym train from its own options"),
    ("sac", "bogus", r"--hyperparams: 'bogus' is not KEY:VALUE \(e.g. learning_rate:3e-4\)"),
    # (NameError, "Maximum allowed dimension exceeded", AssertionError in rl-zoo3 or SB3; the
    # environment's arguments given here skipped the check of --env-kwargs)
    ("sac", "learning_rate:abc", "--hyperparams: learning_rate:'abc' is not allowed: it must "
                                 "be a number in \\(0, 1\\], or lin_<number>"),
    ("sac", "learning_rate:-1e-3", "--hyperparams: learning_rate:-0.001 is not allowed"),
    ("sac", "buffer_size:" + "1" * 400, "--hyperparams: buffer_size:1{400} is not allowed"),
    ("sac", "frame_stack:0", "--hyperparams: frame_stack:0 is not allowed"),
    ("sac", "env_kwargs:{'dt':0}", "--hyperparams env_kwargs: dt=0 is out of range"),
    ("sac", "env_kwargs:3", "--hyperparams: env_kwargs:3 is not allowed: it must be a dict"),
    # (a torch TypeError, NaN then a ValueError, SB3's ValueError, an AssertionError, rl-zoo3's
    # KeyError or NameError once training ran; gamma 5 trained silently)
    ("sac", "gamma:abc", r"--hyperparams: gamma:'abc' is not allowed: it must be a number in "
                         r"\(0, 1\]"),
    ("sac", "gamma:5.0", "--hyperparams: gamma:5.0 is not allowed"),
    ("td3", "tau:-1", "--hyperparams: tau:-1 is not allowed"),
    ("ppo", "policy:Nope", "--hyperparams: policy:'Nope' is not allowed: it must be "
                           "MlpPolicy: the tasks' observations are vectors"),
    ("sac", "train_freq:-3", "--hyperparams: train_freq:-3 is not allowed"),
    ("td3", "noise_type:weird", "--hyperparams: noise_type:'weird' is not allowed"),
    ("sac", "noise_type:normal", "--hyperparams: noise_type needs noise_std"),
    ("ppo", "normalize:maybe", "--hyperparams: normalize:'maybe' is not allowed"),
    ("sac", "ent_coef:auto_abc", "--hyperparams: ent_coef:'auto_abc' is not allowed"),
    ("sac", "ent_coef:auto_0", "--hyperparams: ent_coef:'auto_0' is not allowed"),
    ("ppo", "ent_coef:auto", "--hyperparams: ent_coef:'auto' is not allowed: 'auto' is SAC's"),
    ("ppo", "noise_std:0.1", "--hyperparams: noise_std is not allowed: PPO takes no action"),
    ("sac", "normalize:dict(bogus=1)", "--hyperparams: normalize:'dict\\(bogus=1\\)' is not"),
    ("sac", "normalize:dict(", "--hyperparams: normalize:'dict\\(' is not allowed"),
    ("sac", "policy:MultiInputPolicy", "--hyperparams: policy:'MultiInputPolicy' is not allowed: "
                                       "it must be MlpPolicy: the tasks' observations are vectors"),
    # (SAC trained on with a NaN target entropy, with SDE on for a "maybe"; torch's or SB3's
    # TypeError, rl-zoo3's NameError or ModuleNotFoundError once the run had started)
    ("sac", "target_entropy:nan", "--hyperparams: target_entropy:'nan' is not allowed: it must be "
                                  "'auto' or a number"),
    ("sac", "use_sde:maybe", "--hyperparams: use_sde:'maybe' is not allowed: it must be True or "
                             "False"),
    ("ppo", "normalize_advantage:1", "--hyperparams: normalize_advantage:1 is not allowed"),
    ("sac", "policy_kwargs:dict(net_arch=[-1])", "--hyperparams: policy_kwargs:'dict\\(net_arch="
                                                 "\\[-1\\]\\)' is not allowed: .*building "
                                                 "the policy raised"),
    ("ppo", "policy_kwargs:dict(bogus=1)", "policy_kwargs:'dict\\(bogus=1\\)' is not allowed: "
                                           ".*building the policy raised TypeError"),
    ("td3", "policy_kwargs:dict(", "policy_kwargs:'dict\\(' is not allowed: .*it does not "
                                   "evaluate"),
    ("sac", "policy_kwargs:3", "--hyperparams: policy_kwargs:3 is not allowed"),
    ("sac", "env_wrapper:no.such.Wrapper", "--hyperparams: env_wrapper:'no.such.Wrapper' is not "
                                           "allowed: .*building the wrapper raised "
                                           "ModuleNotFoundError"),
    ("sac", "env_wrapper:{'gymnasium.wrappers.TimeLimit': {'bogus': 1}}",
     "env_wrapper:.* is not allowed: .*building the wrapped environment raised TypeError"),
    ("sac", "env_wrapper:gymnasium.wrappers.ClipAction", "env_wrapper:'gymnasium.wrappers."
                                                         "ClipAction' is not allowed: .*actions "
                                                         "with finite bounds"),
    ("ppo", "vec_env_wrapper:stable_baselines3.common.vec_env.Nope",
     "vec_env_wrapper:.* is not allowed: .*building the wrapper raised AttributeError"),
    ("sac", "callback:no.such.Callback", "--hyperparams: callback:'no.such.Callback' is not "
                                         "allowed: .*building the callbacks raised"),
    ("sac", "callback:{'stable_baselines3.common.callbacks.StopTrainingOnMaxEpisodes': "
            "{'bogus': 1}}", "callback:.* is not allowed: .*building the callbacks raised"),
    # (a ZeroDivisionError at the callback's first call, once training had started)
    ("sac", "callback:{'stable_baselines3.common.callbacks.CheckpointCallback': "
            "{'save_freq': 0, 'save_path': 'ckpt'}}",
     "callback:.* is not allowed: .*CheckpointCallback's save_freq=0 must be an integer >= 1"),
    ("td3", "callback:{'rl_zoo3.callbacks.SaveVecNormalizeCallback': "
            "{'save_freq': 2.5, 'save_path': 'ckpt'}}",
     "callback:.* is not allowed: .*SaveVecNormalizeCallback's save_freq=2.5 must be"),
    ("sac", "gradient_steps:0", "--hyperparams: gradient_steps:0 is not allowed: it must be an "
                                "integer >= 1 and <= 1e\\+09, or -1"),
    ("td3", "policy_delay:0", "--hyperparams: policy_delay:0 is not allowed"),
    ("td3", "target_policy_noise:-0.1", "--hyperparams: target_policy_noise:-0.1 is not allowed"),
    ("ppo", "clip_range_vf:None", "--hyperparams: clip_range_vf:None is not allowed: .*leave it "
                                  "out for no clipping"),
    ("ppo", "target_kl:0", "--hyperparams: target_kl:0 is not allowed"),
    ("ppo", "sde_sample_freq:0", "--hyperparams: sde_sample_freq:0 is not allowed"),
    ("sac", "action_noise:0.1", "--hyperparams: action_noise:0.1 is not allowed: it must be left "
                                "out: rl-zoo3 makes it from noise_type and noise_std"),
    ("sac", "optimize_memory_usage:True", "--hyperparams: optimize_memory_usage:True is not "
                                          "allowed: .*building ReplayBuffer raised ValueError"),
    ("sac", "replay_buffer_class:HerReplayBuffer", "replay_buffer_class:'HerReplayBuffer' is "
                                                   "not allowed: .*observations are vectors"),
    ("td3", "replay_buffer_kwargs:dict(bogus=1)", "replay_buffer_kwargs:.* is not allowed: "
                                                  ".*building ReplayBuffer raised TypeError"),
    ("ppo", "rollout_buffer_class:RolloutBuffer", "rollout_buffer_class:'RolloutBuffer' is not "
                                                  "allowed: it must be left out"),
    ("ppo", "rollout_buffer_kwargs:{'gamma': 0.5}", "rollout_buffer_kwargs:.* is not allowed"),
    ("sac", "normalize_kwargs:{}", "'normalize_kwargs' is not a hyperparameter of sac"),
    # (trained on nonsense: clip_obs -1 mapped every observation to -1; gamma 5 ran; NaN in
    # torch; a zero-sized layer trained a policy blind to its input; SB3's AssertionError
    # or numpy's MemoryError, some after training had started; Monitor's keywords dropped)
    ("ppo", "normalize:dict(clip_obs=-1.0)", "normalize:.* is not allowed: .*its clip_obs=-1.0 "
                                             "must be a number > 0"),
    ("sac", "normalize:dict(gamma=5.0)", "normalize:.* is not allowed: .*its gamma=5.0 must be"),
    ("ppo", "normalize:dict(epsilon=-1.0)", "normalize:.* is not allowed: .*its epsilon=-1.0"),
    ("sac", "policy_kwargs:dict(net_arch=[0])", "policy_kwargs:.* is not allowed: .*a layer of no "
                                                "units"),
    ("ppo", "policy_kwargs:dict(log_std_init=float('nan'))", "policy_kwargs:.* is not allowed: "
                                                             ".*not all finite"),
    ("ppo", "learning_rate:1e9", "--hyperparams: learning_rate:1000000000.0 is not allowed: it "
                                 "must be a number in \\(0, 1\\]"),
    ("ppo", "batch_size:1", "--hyperparams: n_steps:.* and batch_size:1 are not allowed: PPO "
                            "needs"),
    ("sac", ("train_freq:[1, 'episode']", "n_envs:2"),
     "--hyperparams: train_freq:\\[1, 'episode'\\] with n_envs:2 is not allowed"),
    ("sac", "frame_stack:10000000", "--hyperparams: frame_stack:10000000 is not allowed: it must "
                                    "be an integer >= 1 and <= 1000"),
    ("sac", "batch_size:900000000", "--hyperparams batch_size=900000000 is too many: their "
                                    "arrays need about"),
    ("td3", "buffer_size:900000000", "--hyperparams buffer_size .*=900000000 is too many"),
    ("ppo", "vec_env_wrapper:{'stable_baselines3.common.vec_env.VecFrameStack': {'n_stack': 0}}",
     "vec_env_wrapper:.* is not allowed: .*non-empty vectors"),
    ("sac", "monitor_kwargs:dict(info_keywords=('is_success',))", "monitor_kwargs:.* is not "
                                                                  "allowed: it must be left out"),
    # (NaN in torch: an entropy coefficient or a noise scale past float32's range; numpy's
    # ValueError sampling a one-slot buffer that keeps the next observation in the next slot)
    ("sac", "ent_coef:auto_1e300", "--hyperparams: ent_coef:'auto_1e300' is not allowed"),
    ("ppo", "policy_kwargs:dict(log_std_init=100)", "policy_kwargs:.* is not allowed: "
                                                    ".*log_std_init=100 must be a number in "
                                                    "\\[-20, 20\\]"),
    ("sac", ("optimize_memory_usage:True", "buffer_size:1",
             "replay_buffer_kwargs:dict(handle_timeout_termination=False)"),
     "--hyperparams: buffer_size:1 with n_envs:1 and optimize_memory_usage:True is not "
     "allowed: .*needs buffer_size >= 2 x n_envs"),
    # (a TypeError at the first step of training; the OOM killer minutes in, with no message)
    ("sac", "env_wrapper:[{'gymnasium.wrappers.TransformReward': {'func': 'x'}}]",
     "env_wrapper:.* is not allowed: .*stepping the wrapped environment raised TypeError"),
    ("ppo", "vec_env_wrapper:{'stable_baselines3.common.vec_env.VecNormalize': "
            "{'clip_obs': 'x'}}",
     "vec_env_wrapper:.* is not allowed: .*stepping the wrapped vector environment raised "
     "TypeError"),
    ("sac", "n_envs:100000000", "--hyperparams n_envs=100000000 is too many: their arrays "
                                "need about"),
    ("td3", "n_envs:100000000", "--hyperparams n_envs=100000000 is too many"),
])
def test_train_refuses_hyperparams_before_rl_zoo3_starts(algo, item, message, tmp_path,
                                                          monkeypatch):
    """A hyperparameter the algorithm has not, or a count that is not a positive integer, ends
    ``train`` naming it (rl-zoo3 would end in a traceback from SB3 or its own setup)."""
    import rl_zoo3.train
    from roller_gym.scripts import train

    monkeypatch.setattr(rl_zoo3.train, "train", lambda: pytest.fail("rl-zoo3 started"))
    with pytest.raises(SystemExit, match=message):
        items = list(item) if isinstance(item, tuple) else [item]  # (keys checked together)
        train.main(["--algo", algo, "--hyperparams", *items, "--log-folder", str(tmp_path)])


@NEEDS_RL_ZOO3
@pytest.mark.parametrize(("algo", "item"), [
    # forms rl-baselines3-zoo's own hyperparameter files use
    ("ppo", "clip_range:lin_0.2"), ("sac", "train_freq:[1, 'episode']"),
    ("sac", "normalize:\"{'norm_obs': True, 'norm_reward': False}\""),
    ("ppo", "normalize:dict(norm_obs=True)"), ("sac", "ent_coef:auto_0.1"),
    ("sac", "policy_kwargs:dict(net_arch=[64, 64], activation_fn=nn.Tanh)"),
    ("ppo", "policy_kwargs:dict(net_arch=dict(pi=[32], vf=[32]), log_std_init=-1)"),
    ("sac", "target_entropy:-1.0"), ("sac", "use_sde:True"), ("td3", "gradient_steps:-1"),
    ("sac", "env_wrapper:{'gymnasium.wrappers.RescaleAction': {'min_action': -2.0, "
            "'max_action': 2.0}}"),
    ("sac", "env_wrapper:[{'gymnasium.wrappers.TimeLimit': {'max_episode_steps': 50}}]"),
    ("ppo", "vec_env_wrapper:stable_baselines3.common.vec_env.VecMonitor"),
    ("sac", "callback:{'stable_baselines3.common.callbacks.StopTrainingOnMaxEpisodes': "
            "{'max_episodes': 5}}"),
    ("ppo", "callback:{'stable_baselines3.common.callbacks.CheckpointCallback': "
            "{'save_freq': 1000, 'save_path': 'checkpoints'}}"),
    ("td3", "optimize_memory_usage:True"),  # with the buffer's keyword arguments below
    ("ppo", "clip_range_vf:lin_0.2"), ("ppo", "target_kl:0.02"),
])
def test_train_takes_the_forms_of_rl_zoo3s_own_files(algo, item):
    from roller_gym.scripts import train

    items = [item]
    if item == "optimize_memory_usage:True":
        items.append("replay_buffer_kwargs:dict(handle_timeout_termination=False)")
    assert train.checked_hyperparams(algo, items, "roller_gym/RollerStabilize-v2")


@pytest.mark.parametrize("algo", ["sac", "td3", "ppo"])
def test_train_takes_as_many_environments_as_the_machine_holds(algo):
    """n_envs is checked against the memory of its environments with their share of the
    buffers; the shipped files' counts and 1,024 environments pass that check."""
    import roller_gym
    from roller_gym.agents.hyperparams import hyperparams
    from roller_gym.scripts import train

    for env_id in roller_gym.ENV_IDS:
        hp = hyperparams(algo, env_id)
        for n_envs in (hp.get("n_envs", 1), 1024):
            train.check_together(algo, {**hp, "n_envs": n_envs}, train._observation_size(env_id))


@NEEDS_RL_ZOO3
@pytest.mark.parametrize("algo", ["sac", "td3", "ppo"])
def test_every_hyperparameter_train_takes_has_a_rule(algo):
    """Every key ``--hyperparams`` takes (rl-zoo3's own and the algorithm class's keyword
    arguments, read from SB3 itself) has a rule: a new one (a newer SB3) fails here until it
    gets one in ``roller_gym.scripts.zoo_hyperparams.RULES``."""
    from roller_gym.scripts import zoo_hyperparams

    assert set(zoo_hyperparams.accepted_keys(algo)) <= set(zoo_hyperparams.RULES)


@NEEDS_RL_ZOO3
@pytest.mark.parametrize("algo", ["sac", "td3", "ppo"])
def test_every_shipped_hyperparameter_passes_trains_check(algo):
    """The check accepts every entry of the shipped hyperparameter files, for every task (the
    files are what rl-zoo3 has been trained with: a check refusing one of them is wrong)."""
    import roller_gym
    from roller_gym.agents.hyperparams import hyperparams
    from roller_gym.scripts import train

    for env_id in roller_gym.ENV_IDS:
        entries = hyperparams(algo, env_id)
        items = [f"{key}:{value!r}" for key, value in entries.items()]
        assert train.checked_hyperparams(algo, items).keys() == entries.keys()


def test_rollout_names_the_info_keys_an_env_was_made_without():
    """An environment made with fewer info keys is refused by rollout, naming the missing ones;
    evaluation_env makes a run's environment with every key, and the episode is the one of the
    environment made plainly."""
    import gymnasium as gym
    import numpy as np
    from roller_gym.agents import LQR
    from roller_gym.agents.policies import evaluation_env, rollout

    env_id = "roller_gym/RollerHold-v2"
    few = gym.make(env_id, info_keys=["is_success"])
    with pytest.raises(ValueError, match=r"rollout reads the info keys phi, phi_dot, "
                                         r"position_error, torque, target_phi.*info_keys="
                                         r"\['is_success'\]"):
        rollout(few, LQR.from_env(few), seed=0)
    env = evaluation_env(env_id, {"info_keys": ["is_success"], "max_torque": 0.9})
    plain = gym.make(env_id, max_torque=0.9)
    a, b = (rollout(e, LQR.from_env(e), seed=3) for e in (env, plain))
    assert a.total_return == b.total_return and np.array_equal(a.phi, b.phi)


@pytest.mark.parametrize("option", ["--out", "--report"])
def test_evaluate_refuses_a_folder_it_cannot_create_before_it_evaluates(option, tmp_path):
    pytest.importorskip("matplotlib")
    from roller_gym.scripts.evaluate import main

    blocker = tmp_path / "a_file"
    blocker.write_text("")
    target = blocker / "sub" / ("report.md" if option == "--report" else "")
    argv = ["--runs", str(tmp_path), "--baselines", "--out", str(tmp_path / "out")]
    argv += [option, str(target)] if option == "--report" else []
    if option == "--out":
        argv[-1] = str(target)
    with pytest.raises(SystemExit, match=f"{option}: cannot create the folder .*a_file/sub"):
        main(argv)


def test_replay_refuses_an_output_that_is_not_a_gif_or_mp4(monkeypatch, capsys):
    parser = program_parser("replay", monkeypatch)
    monkeypatch.undo()
    with pytest.raises(SystemExit):
        parser.parse_args(["zero", "--out", "x.png"])
    assert "argument --out: 'x.png' does not end in .gif or .mp4" in capsys.readouterr().err
    assert parser.parse_args(["zero", "--out", "x.GIF"]).out == Path("x.GIF")


def test_results_help_works_without_rliable_and_running_says_what_to_install(tmp_path):
    for argv, code, stream, text in ((["results", "--help"], 0, "stdout", "usage: roller-gym "
                                      "results"), (["results", "--runs", str(tmp_path)], 1,
                                                   "stderr", 'pip install ".[results]"')):
        result = run_cli(argv, blocked=("rliable",))
        assert result.returncode == code, result.stderr
        assert text in getattr(result, stream)
        assert "Traceback" not in result.stderr


def _stages(stderr: str, command: str) -> list[str]:
    prefix = f"roller-gym {command}: "
    return [line.removeprefix(prefix) for line in stderr.splitlines() if line.startswith(prefix)]


def test_evaluate_prints_a_line_per_stage_on_stderr(tmp_path):
    pytest.importorskip("matplotlib")
    result = roller_gym("evaluate", "--baselines", "zero", "random", "--episodes", "1",
                        "--out", str(tmp_path / "out"), cwd=tmp_path)
    stages = _stages(result.stderr, "evaluate")
    env_id = "roller_gym/RollerStabilize-v2"
    assert stages[0].startswith(f"{env_id}: making the environment")
    assert stages[1:] == [f"{env_id}: zero torque on 1 episodes", f"{env_id}: random on 1 episodes",
                          f"{env_id}: writing the table and plots into {tmp_path / 'out'}/"]
    assert "roller-gym evaluate:" not in result.stdout


def test_results_says_it_found_no_runs_before_evaluating_anything(tmp_path):
    pytest.importorskip("rliable")
    env_id = "roller_gym/RollerHold-v2"
    result = roller_gym("results", "--runs", str(tmp_path), "--env", env_id, "--out",
                        str(tmp_path / "r"), "--report", str(tmp_path / "RESULTS.md"),
                        check=False)
    assert result.returncode == 1 and "Traceback" not in result.stderr
    assert _stages(result.stderr, "results") == [f"{env_id}: finding the runs under {tmp_path}"]
    assert f"--runs {str(tmp_path)!r}: no trained runs of {env_id} found" in result.stderr
    assert not (tmp_path / "r" / "tasks").exists()


def test_results_render_prints_its_stage(tmp_path):
    pytest.importorskip("rliable")
    source = Path(__file__).resolve().parents[1] / "docs" / "results" / "tasks"
    (tmp_path / "r" / "tasks").mkdir(parents=True)
    name = "RollerHold-v1.json"  # one task: the page's bootstraps take time
    (tmp_path / "r" / "tasks" / name).write_text((source / name).read_text())
    report = tmp_path / "RESULTS.md"
    result = roller_gym("results", "--render-only", "--out", str(tmp_path / "r"),
                        "--report", str(report))
    assert _stages(result.stderr, "results") == [
        f"rendering {report} and its plots from the task files under {tmp_path / 'r' / 'tasks'}/"]
    assert report.read_text().startswith("# Results")


@NEEDS_RL_ZOO3
def test_files_that_are_not_what_the_commands_wrote_are_named(tmp_path):
    """A results file or a run's YAML that is not what roller-gym wrote ends the command with
    one line naming the file (it ended in a traceback: JSONDecodeError, KeyError, yaml's
    ScannerError)."""
    from roller_gym.scripts import benchmark, evaluate

    bench = tmp_path / "benchmarks"
    bench.mkdir()
    for text in ("{", '{"x": 1}'):
        (bench / "workprecision.json").write_text(text)
        with pytest.raises(SystemExit, match=r"workprecision.json is not a results file"):
            benchmark.main(["--render", "--out", str(tmp_path)])
    run = tmp_path / "run" / "roller_gym-RollerStabilize-v2"
    run.mkdir(parents=True)
    (run / "args.yml").write_text("env: roller_gym/RollerStabilize-v2\nalgo: sac\n")
    (run / "config.yml").write_text("a: [\n")
    with pytest.raises(SystemExit, match=r"config.yml is not a YAML file rl-zoo3 wrote"):
        evaluate.main(["--models", str(tmp_path / "run")])


def test_train_refuses_its_own_options_after_the_double_dash(capsys):
    """rl-zoo3 takes the last --env and --seed it is given: after --, they overrode
    train's own (a task trained on hyperparameters checked for another)."""
    from roller_gym.scripts import train

    with pytest.raises(SystemExit, match=r"after --: --env, --seed are set by roller-gym "
                                         r"train"):
        train.main(["--show-command", "--", "--env", "roller_gym/RollerHold-v2", "--seed", "5"])


@pytest.mark.parametrize(("option", "value"), [("--gamma", "5"), ("--lr", "nan"),
                                               ("--lr", "0")])
def test_train_rllib_refuses_a_discount_or_rate_out_of_range(option, value):
    result = roller_gym("train-rllib", option, value, check=False)
    assert result.returncode == 2 and f"argument {option}: '{value}' is not" in result.stderr


def test_benchmark_refuses_an_unwritable_out_before_measuring(monkeypatch):
    """It measured for minutes, then failed to write its results."""
    from roller_gym.scripts import benchmark

    with pytest.raises(SystemExit, match=r"--out: cannot create the folder '/proc/nonexistent"):
        benchmark.main(["--quick", "--out", "/proc/nonexistent/x"])
