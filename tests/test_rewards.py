"""Rewards that rank policies as success does: for every task, on 100 seeded episodes, the
reward of resting (or moving with the target) is largest on the target and falls strictly
with the error out to twice the success band, keeping at most 0.9 of it at the band's edge
and 0.75 at twice the band. RollerSwing's energy objective obeys the same numbers in its
energy error.

The holding torque at each offset is computed here from PHYSICS.md (τ = m g (r sin ψ +
e sin φ) at rest), so the test drives the task's reward with the torques a policy that
rests there must apply.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
import roller_gym
from roller_gym import rewards

IDS = list(roller_gym.ENV_IDS)
#: The tasks with the default objective (the shared formula this file writes out).
DEFAULT_IDS = [i for i in IDS
               if roller_gym.task.get_task(i).reward is roller_gym.task.Task.reward]
#: Offsets [rad of φ] from the target at which the roller rests.
OFFSETS = np.linspace(-0.6, 0.6, 4801)


def holding(scene, phi):
    """The torque [N·m] that holds the roller at rest at φ (PHYSICS.md, cylinder form)."""
    m, r, R, e, g = (float(getattr(scene, f)) for f in ("m", "r", "R", "e", "g"))
    psi = r * phi / (R - r)
    return m * g * (r * np.sin(psi) + e * np.sin(phi))


def rest_rewards(task, scene, target, rate=0.0):
    """The task's reward at rest at target + OFFSETS (moving with the target if it moves),
    holding there with the torque that takes; and the errors the task measures there."""
    q = r_over = float(scene.r) / (float(scene.R) - float(scene.r))
    phi = target + OFFSETS
    tau = holding(scene, phi)
    error = task.error(phi, np.full_like(phi, target), q)
    step = {"position_error": error, "phi_dot": np.full_like(phi, rate),
            "target_phi_dot": rate, "torque": tau, "target_torque": holding(scene, target),
            "action": tau / task.max_torque}
    reachable = np.abs(tau) <= task.max_torque
    assert r_over > 0
    return np.where(reachable, task.step_reward(step), -np.inf), error


#: What resting off the target may keep of the reward on it, at the band's edge and at twice
#: the band (the rewards must see the success band: a policy is paid for precision).
AT_EDGE, AT_TWICE = 0.9, 0.75


def falls_strictly(reward, error, band):
    """Whether the reward falls strictly as |error| grows from 0 to 2·band, on each side,
    where the roller can rest (its holding torque within the limit: ``reward`` finite)."""
    inside = (np.abs(error) <= 2.0 * band) & np.isfinite(reward)
    for side in (error >= 0, error <= 0):
        keep = inside & side
        order = np.argsort(np.abs(error[keep]))
        if not np.all(np.diff(reward[keep][order]) < 0):
            return False
    return True


@pytest.mark.parametrize("env_id", DEFAULT_IDS)
def test_resting_pays_strictly_less_as_the_error_grows(env_id):
    """At rest with the holding torque, the reward falls strictly from the target to twice
    the band; at the band's edge it keeps at most AT_EDGE of the reward on the target, at
    twice the band at most AT_TWICE, and nothing pays more than resting on the target."""
    env = gym.make(env_id)
    task = env.unwrapped.task
    band = task.success_band
    checked = 0
    for seed in range(100):
        _, info = env.reset(seed=seed)
        scene = env.unwrapped.scene  # the episode's (drawn per episode by some tasks)
        for target in {info["target_phi"], *((-info["target_phi"],) if task.symmetric_target
                                             else ())}:
            reward, error = rest_rewards(task, scene, target, info["target_phi_dot"])
            at_target = reward[np.argmin(np.abs(OFFSETS))]
            assert at_target == pytest.approx(reward.max(), rel=1e-12), (seed, target)
            assert falls_strictly(reward, error, band), (seed, target)
            for side in (-1.0, 1.0):
                for times, keeps in ((1.0, AT_EDGE), (2.0, AT_TWICE)):
                    off = reward[np.argmin(np.abs(error - side * times * band))]
                    assert off <= keeps * at_target, (seed, target, side, times, off)
            checked += 1
    assert checked >= 100


def test_swing_pays_strictly_less_as_the_energy_error_grows():
    """RollerSwing's objective is in the energy: at any fixed torque its reward falls
    strictly as |E/E* − 1| grows out to twice its success band, with the same shares kept
    at the band's edge and at twice the band as the position tasks'."""
    task = roller_gym.task.get_task("RollerSwing")()
    band = task.energy_band
    relative = np.linspace(-2.0 * band, 2.0 * band, 801)
    target_energy = 0.37  # J; the reward reads E/E* only
    for torque in (0.0, 0.5 * task.max_torque, -task.max_torque):
        reward = np.asarray(task.step_reward({"energy": target_energy * (1.0 + relative),
                                              "target_energy": target_energy,
                                              "torque": torque}))
        at_target = reward[np.argmin(np.abs(relative))]
        assert at_target == pytest.approx(reward.max(), rel=1e-12)
        assert falls_strictly(reward, relative, band)
        for times, keeps in ((1.0, AT_EDGE), (2.0, AT_TWICE)):
            for side in (-1.0, 1.0):
                assert reward[np.argmin(np.abs(relative - side * times * band))] \
                    <= keeps * at_target


def test_balance_pays_most_at_the_unstable_rest_position():
    """In Balance the target is the unstable rest position ±φ_b: resting there needs no
    torque at all, and its reward is the largest of all rest positions nearby."""
    env = gym.make("roller_gym/RollerBalance-v2")
    task, scene = env.unwrapped.task, env.unwrapped.scene
    phi_b = task.default_target(scene)
    assert abs(holding(scene, phi_b)) < 1e-9
    for target in (phi_b, -phi_b):
        reward, error = rest_rewards(task, scene, target)
        assert reward[np.argmin(np.abs(OFFSETS))] == pytest.approx(1.0, abs=1e-12)
        assert abs(error[int(np.argmax(reward))]) <= 1e-3


def test_tolerance_is_one_inside_the_band_and_near_outside():
    x = np.array([-0.3, -0.05, 0.0, 0.04, 0.05, 0.06, 0.3])
    got = rewards.tolerance(x, 0.05, 0.2)
    np.testing.assert_array_equal(got[1:5], 1.0)
    for xi, g in zip(x[[0, 5, 6]], got[[0, 5, 6]], strict=True):
        assert g == pytest.approx(math.exp(math.log(0.1) * ((abs(xi) - 0.05) / 0.2) ** 2))
    assert rewards.tolerance(0.25, 0.05, 0.2) == pytest.approx(0.1)


def documented_reward(task, info):
    """The reward as the task's docs write it, from a step's info, in plain Python floats:
    (0.4 tol(ε, b, m_p) + 0.6 near(ε, 3b)) (0.5 + 0.5 near(φ' − φ*', 5)) (0.8 + 0.2 near(
    (τ − τ*)/max_torque, 1)), written here apart from the package's compiled formula."""
    def near(x, m):
        return math.exp(math.log(0.1) * (x / m) ** 2)

    def tol(x, b, m):
        return 1.0 if abs(x) <= b else near(abs(x) - b, m)

    e, b = float(info["position_error"]), task.success_band
    w_p, w_v, w_u = task.precision_weight, task.speed_weight, task.control_weight
    position = (1 - w_p) * tol(e, b, task.position_margin) + w_p * near(e, 3 * b)
    speed = near(float(info["phi_dot"]) - float(info["target_phi_dot"]), task.speed_margin)
    control = near((float(info["torque"]) - float(info["target_torque"])) / task.max_torque,
                   1.0)
    return position * (1 - w_v + w_v * speed) * (1 - w_u + w_u * control)


@pytest.mark.parametrize("env_id", DEFAULT_IDS)
def test_the_environments_pay_the_documented_reward(env_id):
    """The reward the single and the vector environment return (one compiled kernel) is the
    documented formula evaluated here on the step's info, and the position error is the
    wrapped distance to the target (to the nearer of ±φ* where the task is symmetric)."""
    env = gym.make(env_id)
    task = env.unwrapped.task
    vec = gym.make_vec(env_id, num_envs=3)
    _, vinfo = vec.reset(seed=5)
    env.reset(seed=5)
    rng = np.random.default_rng(5)
    for _ in range(25):
        u = rng.uniform(-1, 1)
        _, reward, terminated, _, info = env.step(np.array([u], np.float32))
        if terminated:
            break
        assert reward == pytest.approx(documented_reward(task, info), rel=1e-12, abs=1e-15)
        q = env.unwrapped._q  # 0: no period of the pose to wrap by (a drawn scene)
        wrap = [((q * (info["phi"] - t) + math.pi) % (2 * math.pi) - math.pi) / q if q
                else info["phi"] - t for t in
                ((info["target_phi"], -info["target_phi"]) if task.symmetric_target
                 else (info["target_phi"],))]
        assert abs(info["position_error"]) == pytest.approx(min(abs(w) for w in wrap),
                                                            rel=1e-9, abs=1e-12)
    _, vreward, vterm, _, vinfo = vec.step(rng.uniform(-1, 1, (3, 1)).astype(np.float32))
    for i in np.flatnonzero(~vterm):
        row = {k: vinfo[k][i] for k in ("position_error", "phi_dot", "target_phi_dot",
                                         "torque", "target_torque")}
        assert vreward[i] == pytest.approx(documented_reward(task, row), rel=1e-12, abs=1e-15)


def test_a_task_may_not_override_what_the_kernel_computes_for_every_task():
    """The environments compute the position error and the observation in their compiled
    kernel for every task: a task overriding one of them is refused at registration, naming
    the method, instead of being silently ignored; an objective that is not a static method
    of (s, k) is refused too."""
    from roller_gym.stabilize import StabilizeTask
    from roller_gym.task import TASKS, register

    class Wrong(StabilizeTask):
        name = "RollerWrongTest"

        def error(self, phi, target, q):
            return 0.0

    with pytest.raises(ValueError, match=r"RollerWrongTest overrides error: "):
        register(Wrong)

    class Greedy(StabilizeTask):
        name = "RollerGreedyTest"

        def reward(self, step):
            return 1.0

    with pytest.raises(ValueError, match=r"RollerGreedyTest.reward must be a static method"):
        register(Greedy)
    assert "RollerGreedyTest" not in TASKS and "RollerWrongTest" not in TASKS


@pytest.mark.parametrize("size", ["serial", "parallel"])
@pytest.mark.parametrize("task_id", IDS)
def test_the_outcome_of_a_roller_is_the_same_alone_and_in_a_batch(task_id, size):
    """A roller alone (the single environment's path, without the batch's blocks) gets bit
    for bit the outcome (every info row, flag and the observation) it gets in a batch on one
    core and in one large enough to run on all cores (``PARALLEL_THRESHOLD`` rollers), for
    steps that failed, lifted, slipped or have no error estimate too."""
    from roller_gym import episode
    from roller_gym.physics.integrators import (
        PARALLEL_THRESHOLD,
        STEP_FIELDS,
        as_row_table,
        row_table,
    )

    task = gym.spec(task_id).make().unwrapped.task
    n = 300 if size == "serial" else PARALLEL_THRESHOLD + 5
    rng = np.random.default_rng(3)
    result = row_table(len(STEP_FIELDS), n)  # a stepper's layout, as the kernels are compiled for
    result[:] = rng.normal(size=result.shape)
    finite = STEP_FIELDS.index("finite")
    result[finite] = rng.uniform(size=n) < 0.9
    result[STEP_FIELDS.index("error_estimate"), rng.uniform(size=n) < 0.2] = np.nan
    big = episode.OutcomeKernel(task, n)
    big.context[:] = rng.normal(size=big.context.shape)
    big.run(result)
    for i in rng.choice(n, 40, replace=False):
        one = episode.OutcomeKernel(task, 1)
        one.context[:] = big.context[:, i:i + 1]
        one.run(as_row_table(result[:, i:i + 1]))
        np.testing.assert_array_equal(one.table[:, 0], big.table[:, i])
        np.testing.assert_array_equal(one.flags[:, 0], big.flags[:, i])
        np.testing.assert_array_equal(one.observation[0], big.observation[i])


@pytest.mark.parametrize("method", ["taylor", "rk8", "rk4", "euler"])
def test_a_step_and_its_outcome_in_one_call_are_the_two_calls(method):
    """Where a scheme has a fused kernel (the physics, then the outcome, in one compiled
    call), a step gives bit for bit what the stepper's own kernel and then the outcome's
    give: for one roller (also through the single environment's bound step, which writes τ
    into the context itself and returns φ, φ', reward and terminated as Python numbers) and
    for a batch on one core."""
    from roller_gym import episode
    from roller_gym.hold import HoldTask
    from roller_gym.physics import integrators as integ

    task, scene, rng = HoldTask(), roller_gym.preset("paper"), np.random.default_rng(4)
    tol = 1e-4 if method == "euler" else 1e-8  # within euler's substeps
    for n in (1, 300):
        phi, phi_dot, tau = rng.uniform(-1, 1, (3, n))
        runs = []
        for way in ("fused", "two calls", "bound"):
            kernel = episode.OutcomeKernel(task, n)
            if n == 1:
                stepper = integ.Stepper(scene, integrator=method, dt=0.05, tolerance=tol)
            else:
                stepper = integ.BatchStepper(n, integrator=method, dt=0.05, tolerance=tol)
                stepper.set_scenes(scene)
            context = np.linspace(0.1, 0.6, len(episode.CONTEXT_FIELDS))[:, None]
            kernel.context[:] = context
            kernel.context[list(episode.CONTEXT_FIELDS).index("torque")] = tau  # as bound
            args = (phi[0], phi_dot[0], tau[0]) if n == 1 else (phi, phi_dot, tau)
            if way == "fused":
                kernel.step(stepper, *args)
            elif way == "two calls":
                kernel.run(stepper.run(*args))
            elif n == 1:
                kernel.context[:] = context  # τ not yet in it
                read = kernel.bind(stepper)(*args)  # writes τ into the context itself
                rows = {name: kernel.table[episode.OUTCOME_ROWS.index(name), 0]
                        for name in ("phi", "phi_dot", "reward")}
                terminated = kernel.flags[episode.FLAG_ROWS.index("terminated"), 0]
                assert read == (rows["phi"], rows["phi_dot"], rows["reward"], terminated)
                assert [type(x) for x in read] == [float, float, float, bool]
            else:
                continue
            runs.append((kernel.table.copy(), kernel.flags.copy(), kernel.observation.copy()))
        fused = kernel.kernels.fused.get(stepper.kernel)
        assert (fused is not None) == (method in ("taylor", "rk8", "rk4"))
        for other in runs[1:]:
            for a, b in zip(runs[0], other, strict=True):
                np.testing.assert_array_equal(a, b)


def test_streaming_stores_write_the_values_and_are_fenced():
    """The outcome writes its new tables by non-temporal stores (``_stream``), then fences
    them: compiled afresh here, a stream of rows writes exactly the values NumPy copies,
    into rows at any offset, and its code carries the non-temporal hint and the fence."""
    import numba
    from roller_gym.episode.outcome import _fence, _stream

    @numba.njit(nogil=True)
    def stream(dst, src, start, m):
        for r in range(src.shape[0]):
            _stream(dst[r], start, src[r], start, m)
        _fence()

    rng = np.random.default_rng(5)
    src = rng.normal(size=(3, 300))
    src[0, 7], src[1, 8], src[2, 9] = np.nan, np.inf, -0.0
    dst = np.zeros((3, 310))[:, 3:303]  # rows not aligned to a cache line
    stream(dst, src, 5, 290)
    np.testing.assert_array_equal(dst[:, 5:295], src[:, 5:295])
    assert np.signbit(dst[2, 9]) and not dst[:, :5].any() and not dst[:, 295:].any()
    llvm = next(iter(stream.inspect_llvm().values()))
    assert "!nontemporal" in llvm
    assert "llvm.x86.sse.sfence" in llvm or "fence seq_cst" in llvm
