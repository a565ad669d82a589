"""The task seam: the outcome record declared once and written whole, each task's own
objective paid by the compiled kernel, kernels recompiled when a source they inline changes,
and the existing tasks' outcomes bit for bit those recorded before the seam was cut."""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import roller_gym
from roller_gym import episode
from roller_gym.episode import record
from roller_gym.physics.integrators import PARALLEL_THRESHOLD, STEP_FIELDS, row_table

IDS = list(roller_gym.ENV_IDS)
DATA = Path(__file__).parent / "data"


# -- the record ---------------------------------------------------------------------------
def test_every_output_is_an_input_passed_on_or_computed_and_every_quantity_has_a_source():
    inputs = set(STEP_FIELDS) | set(record.CONTEXT_FIELDS)
    for name in (*record.OUTCOME_ROWS, *record.FLAG_ROWS):
        assert (name in record.COMPUTED) != (name in inputs and name not in record.COMPUTED)
    for name in record.QUANTITIES:
        assert name in inputs or name in record.COMPUTED, name
    assert record.Step._fields == tuple(record.QUANTITIES)
    # the row numbers are the declarations' order
    assert [getattr(record.O, n) for n in record.OUTCOME_ROWS] == list(
        range(len(record.OUTCOME_ROWS)))
    assert {k: record.INFO_ROW[k] for k in record.INFO_KEYS} == {
        k: (record.FLAG_ROWS if kind is bool else record.OUTCOME_ROWS).index(k)
        for k, (kind, _) in record.INFO_KEYS.items()}


def _outcome(task, n, fill, rng_seed=3):
    """The outcome of n random rollers into buffers (table, flags, observation, scratch) first
    filled with ``fill``: an output the kernel does not write keeps it."""
    rng = np.random.default_rng(rng_seed)
    result = row_table(len(STEP_FIELDS), n)  # a stepper's layout, as the kernels are compiled for
    result[:] = rng.normal(size=result.shape)
    result[STEP_FIELDS.index("finite")] = rng.uniform(size=n) < 0.9
    result[STEP_FIELDS.index("tol_met")] = rng.uniform(size=n) < 0.5
    kernel = episode.OutcomeKernel(task, n)
    kernel.context[:] = rng.normal(size=kernel.context.shape)
    kernel.context[list(record.CONTEXT_FIELDS).index("target_energy")] += 3.0  # away from 0
    kernel.table[:] = fill
    kernel.flags[:] = bool(fill)
    kernel.observation[:] = fill
    kernel._scratch[:] = fill
    kernel.run(result)
    return kernel.table.copy(), kernel.flags.copy(), kernel.observation.copy()


@pytest.mark.parametrize("size", [1, 300, PARALLEL_THRESHOLD + 5])
@pytest.mark.parametrize("task_id", IDS)
def test_every_declared_output_is_written(task_id, size):
    """Whatever the buffers held before, the kernel writes every row of the outcome's table
    and flags and every observed field, for a roller alone, a batch on one core and one on
    all cores: two runs over buffers filled with different values agree bit for bit."""
    task = gym.spec(task_id).make().unwrapped.task
    first = _outcome(task, size, 1.0e300)
    second = _outcome(task, size, 0.0)
    for a, b in zip(first, second, strict=True):
        np.testing.assert_array_equal(a, b)
    assert not np.isin(first[0], [1.0e300]).any() and not np.isin(first[2], [1.0e300]).any()


@pytest.mark.parametrize("task_id", IDS)
def test_the_environments_pay_the_tasks_own_objective(task_id):
    """The reward and success the single and the vector environment report are the task's
    own ``reward(s, k)`` and ``success(s, k)`` run in Python on the step's quantities."""
    env = gym.make(task_id)
    task = env.unwrapped.task
    vec = gym.make_vec(task_id, num_envs=3)
    _, info = env.reset(seed=2)
    vec.reset(seed=2)
    rng = np.random.default_rng(2)
    for _ in range(40):
        action = rng.uniform(-1, 1, 1).astype(np.float32)
        _, reward, terminated, _, info = env.step(action)
        _, vreward, _, _, vinfo = vec.step(np.repeat(action[None], 3, axis=0))
        if terminated:
            break
        quantities = {**info, "target_energy": env.unwrapped._outcome.context[
            list(record.CONTEXT_FIELDS).index("target_energy"), 0]}
        assert reward == task.step_reward(quantities)
        assert info["is_success"] == task.step_success(quantities)
        assert vreward[0] == reward and vinfo["is_success"][0] == info["is_success"]


# -- recorded outcomes --------------------------------------------------------------------
RECORDED = DATA / "outcomes.npz"


def run_outcomes(env_ids) -> dict[str, np.ndarray]:
    """The outcomes recorded: per task, 150 seeded steps of the single environment under
    random actions (observation, reward, terminated, every info value), and 40 steps of
    vector environments of 5 and of 2,100 sub-environments (on all cores)."""
    out = {}
    for env_id in env_ids:
        name = roller_gym.file_name(env_id)
        rng = np.random.default_rng(7)
        env = gym.make(env_id)
        obs, info = env.reset(seed=11)
        rows, infos = [np.concatenate([obs.astype(float), [0.0, 0.0]])], {k: [v] for k, v in
                                                                          info.items()}
        for _ in range(150):
            obs, r, term, trunc, info = env.step(rng.uniform(-1, 1, size=1).astype(np.float32))
            rows.append(np.concatenate([obs.astype(float), [r, float(term)]]))
            for k, v in info.items():
                infos[k].append(v)
            if term or trunc:
                obs, info = env.reset()
                rows.append(np.concatenate([obs.astype(float), [0.0, 0.0]]))
                for k, v in info.items():
                    infos[k].append(v)
        out[f"{name}/single"] = np.array(rows)
        out.update({f"{name}/single/{k}": np.array(v, dtype=float) for k, v in infos.items()})
        for n in (5, 2100):
            vec = gym.make_vec(env_id, num_envs=n)
            obs, info = vec.reset(seed=3)
            rng = np.random.default_rng(n)
            got = {"obs": [obs], "reward": [], "terminated": []}
            got.update({k: [info[k]] for k in info if not k.startswith("_")})
            for _ in range(40):
                obs, r, term, _, info = vec.step(rng.uniform(-1, 1, (n, 1)).astype(np.float32))
                for k, v in (("obs", obs), ("reward", r), ("terminated", term), *(
                        (k, info[k]) for k in got if k not in ("obs", "reward", "terminated"))):
                    got[k].append(v)
            out.update({f"{name}/vec{n}/{k}": np.array(v, dtype=float) for k, v in got.items()})
    return out


def digest(array: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(array, dtype=float).tobytes()).hexdigest()


@pytest.mark.slow
def test_the_tasks_outcomes_are_bit_for_bit_those_recorded():
    """Stabilize, Hold and Track give bit for bit the outcomes recorded before the objective
    became the task's own (tests/data/outcomes.npz: the arrays of the single env and of 5
    sub-environments, and the digest of those of 2,100), recorded under the task versions
    before the rewards that see the success band: every value but the reward is unchanged,
    and the reward is the task's formula (run in Python) of the recorded step. Balance's
    target, the unstable rest position, comes since from a compiled bisection that agrees
    with the recording's scipy root to 4.4e-16 rad: its arrays agree to 1e-12, and its
    digests are not compared."""
    recorded = np.load(RECORDED)
    names = sorted({key.split("/")[0] for key in recorded.files})
    env_ids = {name: next(i for i in IDS if i.split("/")[1].split("-v")[0]
                          == name.split("-v")[0]) for name in names}
    assert len(env_ids) == 4
    now = run_outcomes(list(env_ids.values()))
    for key in recorded.files:
        name, rest = key.split("/", 1)
        env_id = env_ids[name]
        task = gym.make(env_id).unwrapped.task
        new_key = f"{roller_gym.file_name(env_id)}/{rest}"
        got, want = now[new_key.removesuffix("/digest")], recorded[key]
        exact = not name.startswith("RollerBalance")
        if rest == "single":  # obs..., reward, terminated: the reward is the new formula
            info = {k.split("/")[-1]: recorded[k] for k in recorded.files
                    if k.startswith(f"{name}/single/")}
            stepped = want[:, -2] != 0.0  # a reset's row holds reward 0, a step's more
            assert stepped.sum() >= 150
            expected = np.where(stepped, task.step_reward(info), 0.0)
            np.testing.assert_allclose(got[:, -2], expected, rtol=1e-12, err_msg=key)
            got, want = np.delete(got, -2, axis=1), np.delete(want, -2, axis=1)
        elif rest == "vec5/reward":
            info = {k.split("/")[-1]: recorded[k][1:] for k in recorded.files
                    if k.startswith(f"{name}/vec5/") and k.count("/") == 2}
            expected = np.where(want != 0.0, task.step_reward(info), 0.0)  # 0: a reset
            np.testing.assert_allclose(got, expected, rtol=1e-12, err_msg=key)
            continue
        elif rest == "vec2100/reward/digest":
            continue  # the reward changed: the formula is checked on the two above
        if rest.endswith("/digest"):
            if exact:
                assert digest(got) == str(want), key
        elif exact:
            np.testing.assert_array_equal(got, want, err_msg=key)
        else:
            np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12, err_msg=key)


# -- no stale kernels ---------------------------------------------------------------------
PROBE = textwrap.dedent("""
    import gymnasium as gym, numpy as np, roller_gym
    assert roller_gym.__file__.startswith({root!r}), roller_gym.__file__
    env = gym.make("roller_gym/RollerStabilize-v2", integrator="euler", substeps=8)
    env.reset(seed=0)
    _, reward, _, _, info = env.step(np.array([0.3], np.float32))
    print(repr(float(reward)), repr(float(env.unwrapped.task.step_reward(info))))
""")


@pytest.mark.slow
def test_editing_an_inlined_source_recompiles_the_kernels(tmp_path):
    """A copy of the package, run twice with one numba cache: after the reward vocabulary's
    ``near`` (inlined into the compiled kernel, not in the kernel's own file) is edited to
    pay half, the environment pays the edited reward, as the Python path computes it."""
    package = tmp_path / "roller_gym"
    shutil.copytree(Path(roller_gym.__file__).parent, package,
                    ignore=shutil.ignore_patterns("__pycache__"))
    env = {**os.environ, "PYTHONPATH": str(tmp_path), "NUMBA_CACHE_DIR": str(tmp_path / "c")}

    def run() -> tuple[float, float]:
        out = subprocess.run([sys.executable, "-c", PROBE.format(root=str(package))],
                             env=env, capture_output=True, text=True, check=True, cwd=tmp_path)
        paid, python = map(float, out.stdout.split())
        return paid, python

    paid, python = run()
    assert paid == python
    again = run()  # from the cache
    assert again == (paid, python)
    rewards = package / "rewards.py"
    text = rewards.read_text()
    edited = text.replace("    return trig.exp(math.log(value_at_margin) * (t * t))",
                          "    return 0.5 * trig.exp(math.log(value_at_margin) * (t * t))")
    assert edited != text
    rewards.write_text(edited)
    new_paid, new_python = run()
    assert new_paid == new_python and new_paid < 0.9 * paid


def test_the_id_decides_the_task():
    """A ``task=`` that names another task than the ID's is refused, naming both, as is an
    ID of the same task at another version or namespace; the ID's own task (by name or ID)
    is accepted."""
    stabilize = "roller_gym/RollerStabilize-v2"
    for make in (gym.make, lambda i, **kw: gym.make_vec(i, num_envs=2, **kw)):
        with pytest.raises(ValueError, match=r"task='RollerHold' contradicts the ID "
                                             r"roller_gym/RollerStabilize-v2.*RollerHold-v2"):
            make(stabilize, task="RollerHold")
        env = make(stabilize, task=stabilize)
        assert type(env.unwrapped.task).name == "RollerStabilize"
        for other in ("RollerStabilize-v99", "x/RollerStabilize-v2"):  # (they were accepted)
            with pytest.raises(ValueError, match=rf"task='{other}' is not a registered ID"):
                make(stabilize, task=other)


def test_a_kernel_numba_cannot_cache_is_warned_about_not_a_crash():
    """numba warns, naming the kernel's file, where a compiled kernel cannot be cached (code
    it lifted out of nopython mode, dynamic globals); with the package's digest locator that
    warning raised AttributeError (seen under ``NUMBA_OPT=0``)."""
    import warnings
    from types import SimpleNamespace

    from numba.core import caching
    from numba.core.errors import NumbaWarning
    from roller_gym import kernel_cache
    from roller_gym.episode.outcome import observe

    func = observe.py_func
    locator = kernel_cache.DigestLocator.from_function(func, func.__code__.co_filename)
    assert isinstance(locator, kernel_cache.DigestLocator)
    impl = caching.CompileResultCacheImpl.__new__(caching.CompileResultCacheImpl)
    impl._locator, impl._lineno = locator, func.__code__.co_firstlineno
    uncachable = SimpleNamespace(lifted=[SimpleNamespace(can_cache=False)],
                                 fndesc=SimpleNamespace(qualname="observe"))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert impl.check_cachable(uncachable) is False
    assert [w.filename for w in caught if issubclass(w.category, NumbaWarning)] == [
        func.__code__.co_filename]
