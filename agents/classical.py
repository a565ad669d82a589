"""Classical controllers with the ``predict`` of a stable-baselines3 model.

* :class:`LQR`: a linear-quadratic regulator about the target rest position, with the
  holding torque as feedforward (RollerStabilize, RollerHold).
* :class:`EnergySwingUp`: pumps the energy up to that of the unstable rest position, then
  hands over to an LQR there (RollerBalance).
* :class:`EnergyPump`: pumps the energy toward that of a target swing (RollerSwing).
* :class:`ZeroTorque` and :class:`RandomPolicy`: the floor of the results table.

Each acts from the observation only (the state is decoded by
:func:`roller_gym.agents.observation.decode_observation`), so one evaluation loop serves these and
trained models alike: ``action, _ = policy.predict(obs, deterministic=True)``, for one
observation (shape (d,) -> action (1,)) or a batch ((n, d) -> (n, 1)).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from roller_gym.agents.observation import decode_observation
from roller_gym.physics import Scene, energy, equations, holding_torque, linearize
from roller_gym.physics.scene import shown
from roller_gym.task import Task, wrap_rate
from scipy.linalg import expm, solve_discrete_are

__all__ = ["CONTROLLERS", "LQR", "Controller", "EnergyPump", "EnergySwingUp", "Informed",
           "RandomPolicy", "ZeroTorque", "controller_for"]


class Controller:
    """The interface shared with stable-baselines3 models: :meth:`predict`."""

    def act(self, observation: np.ndarray) -> np.ndarray:
        """Actions in [−1, 1] of shape (n, 1) for observations of shape (n, d)."""
        raise NotImplementedError

    def predict(
        self,
        observation: np.ndarray,
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, None]:
        """The action for an observation, as ``stable_baselines3``'s ``model.predict``.

        Args:
            observation: one observation (shape (d,)) or a batch (shape (n, d)).
            state: unused (no recurrent state); accepted for compatibility.
            episode_start: unused; accepted for compatibility.
            deterministic: unused (the controllers are deterministic, except
                :class:`RandomPolicy`); accepted for compatibility.

        Returns:
            (actions, None): actions in [−1, 1], float32, of shape (1,) for one observation
            or (n, 1) for a batch.
        """
        obs = np.asarray(observation, dtype=np.float64)
        single = obs.ndim == 1
        actions = self.act(obs.reshape(1, -1) if single else obs).astype(np.float32)
        return (actions[0] if single else actions), None


class ZeroTorque(Controller):
    """Applies no torque: the roller swings freely (the uncontrolled baseline)."""

    def act(self, observation: np.ndarray) -> np.ndarray:
        return np.zeros((observation.shape[0], 1))


class RandomPolicy(Controller):
    """Uniform random actions in [−1, 1].

    Args:
        seed: the seed of its own generator (the same seed gives the same actions).
    """

    def __init__(self, seed: int | None = 0) -> None:
        self.rng = np.random.default_rng(seed)

    def act(self, observation: np.ndarray) -> np.ndarray:
        return self.rng.uniform(-1.0, 1.0, (observation.shape[0], 1))


def _task_settings(env: gym.Env | Any, scene: Scene | None = None
                   ) -> tuple[Scene, float, float]:
    """(scene, max_torque [N·m], dt [s]) of a (possibly wrapped) roller environment; the
    scene its construction names (:attr:`~roller_gym.config.EnvConfig.nominal_scene`), unless
    ``scene`` is given."""
    base = env.unwrapped
    return (base.config.nominal_scene if scene is None else scene, float(base.task.max_torque),
            float(base.config.dt))


class LQR(Controller):
    """A discrete-time LQR about a rest position φ*, with the holding torque as feedforward.

    About φ*, the holding torque τ* = dV/dφ(φ*) keeps the roller at rest; the physics
    layer's exact Jacobians (A, B) = ``linearize(scene, φ*, 0, τ*)`` are discretized with
    a zero-order hold over the control step dt (the environment holds the torque constant
    over a step), and the gain K comes from the discrete algebraic Riccati equation with
    Bryson's weights Q = diag(1/position_scale², 1/speed_scale²), R = 1/torque_scale².
    The action is clip((τ* − K x)/max_torque, −1, 1), x = (position error [rad],
    φ' [rad/s]), the error measured as in the task (one turn of ψ either way). Gains are
    computed once per target and cached (RollerHold draws a target per episode).

    Args:
        task: the task (``env.unwrapped.task``): its observation is decoded by field name,
            and its error measure is the one the LQR drives to zero.
        scene: the scalar scene (``env.unwrapped.config.scene``).
        max_torque: the torque [N·m] of an action of ±1.
        dt: the control step [s].
        target: the rest position φ* [rad]; None reads it from the observation (tasks that
            observe their target, such as RollerHold).
        position_scale: the acceptable position error [rad] (Bryson's rule).
        speed_scale: the acceptable speed [rad/s].
        torque_scale: the acceptable torque deviation from τ* [N·m].
    """

    def __init__(
        self,
        task: Task,
        scene: Scene,
        max_torque: float,
        dt: float,
        target: float | None = 0.0,
        position_scale: float = 0.1,
        speed_scale: float = 1.0,
        torque_scale: float = 0.5,
    ) -> None:
        if scene.batch_size is not None:
            raise ValueError("LQR takes a scalar scene")
        self.task = task
        self.scene, self.max_torque, self.dt = scene, float(max_torque), float(dt)
        self.target = None if target is None else float(target)
        self.Q = np.diag([1.0 / position_scale**2, 1.0 / speed_scale**2])
        self.R = np.array([[1.0 / torque_scale**2]])
        self.q = wrap_rate(scene)
        self._cache: dict[float, tuple[float, np.ndarray, np.ndarray]] = {}

    @classmethod
    def from_env(cls, env: gym.Env | Any, scene: Scene | None = None, **weights: float) -> LQR:
        """The LQR for a RollerStabilize or RollerHold environment (target 0 or observed).

        Args:
            env: the environment (wrappers allowed); its scene, max_torque and dt are used.
            scene: the scene to design for instead of the environment's nominal one.
            **weights: ``position_scale``, ``speed_scale``, ``torque_scale`` (see the class).
        """
        scene, max_torque, dt = _task_settings(env, scene)
        base = env.unwrapped
        target = None if base.task.observes_target else base.task.default_target(scene)
        return cls(base.task, scene, max_torque, dt, target=target, **weights)

    #: Targets closer than this [rad] share their gains (a moving target's in particular).
    gain_resolution = 1e-3

    def gains(self, target: float) -> tuple[float, np.ndarray, np.ndarray]:
        """(τ* [N·m], K (1, 2), P (2, 2)) about the rest position ``target`` [rad] (gains
        computed at ``target`` rounded to :attr:`gain_resolution`, and cached)."""
        key = round(float(target) / self.gain_resolution) * self.gain_resolution
        if key not in self._cache:
            tau_star = float(holding_torque(self.scene, key))
            A, B = linearize(self.scene, key, 0.0, tau_star)
            # Zero-order hold: expm([[A, B], [0, 0]] dt) = [[Ad, Bd], [0, 1]].
            M = np.zeros((3, 3))
            M[:2, :2], M[:2, 2:] = A, B
            E = expm(M * self.dt)
            Ad, Bd = E[:2, :2], E[:2, 2:]
            try:
                P = solve_discrete_are(Ad, Bd, self.Q, self.R)
                K = np.linalg.solve(self.R + Bd.T @ P @ Bd, Bd.T @ P @ Ad)
            except (np.linalg.LinAlgError, ValueError) as error:
                raise ValueError(
                    f"LQR: no gains for {shown(self.scene)} about phi*={key:g} rad with "
                    f"dt={self.dt:g} s (scipy: {error}); its linearized motion, A = "
                    f"{np.array2string(A.ravel(), precision=3)} (row by row), B = "
                    f"{np.array2string(B.ravel(), precision=3)} per N·m, is too far from the "
                    "weights' scales for the Riccati equation (a torque of next to no "
                    "effect, or a motion far faster than dt)") from None
            if not (np.all(np.isfinite(K)) and np.all(np.isfinite(P))):
                raise ValueError(f"LQR: the gains for {shown(self.scene)} about phi*={key:g} "
                                 f"rad are not finite: K={K}")
            self._cache[key] = (tau_star, K, P)
        return self._cache[key]

    def error(self, phi: np.ndarray, target: np.ndarray) -> np.ndarray:
        """The position error [rad] to the rest position ``target``, as the task measures it."""
        return self.task.error_to(phi, target, self.q)

    def torque(self, phi: np.ndarray, phi_dot: np.ndarray, target: np.ndarray,
               target_rate: np.ndarray | float = 0.0) -> np.ndarray:
        """The unsaturated torque τ*(φ*) − K x [N·m] for states and targets of shape (n,),
        x = (error, φ' − φ*'): the holding torque at the target as feedforward, and the
        feedback on the error in position and in speed (a moving target: tracking)."""
        key = np.round(target / self.gain_resolution)
        gains = np.empty((phi.shape[0], 2))
        for k in np.unique(key):
            gains[key == k] = self.gains(k * self.gain_resolution)[1][0]
        x0 = self.error(phi, target)
        x1 = phi_dot - target_rate
        return holding_torque(self.scene, target) - gains[:, 0] * x0 - gains[:, 1] * x1

    def act(self, observation: np.ndarray) -> np.ndarray:
        s = decode_observation(observation, self.scene, self.task)
        if self.target is not None:
            target, rate = np.full_like(s.phi, self.target), 0.0
        elif s.target_phi is not None:
            target, rate = s.target_phi, s.target_phi_dot
        else:
            raise ValueError("LQR(target=None) needs observations that carry the target")
        tau = self.torque(s.phi, s.phi_dot, target, rate)
        return np.clip(tau / self.max_torque, -1.0, 1.0)[:, None]


class EnergySwingUp(Controller):
    """Energy pumping up to the unstable rest position ±φ_b, then an LQR there (Balance).

    With E = ½ J_I φ'² + V(φ) and dE/dt = τ φ', the torque
    τ = clip(energy_gain · (E_b − E) · φ', ±max_torque) only ever moves E toward
    E_b = V(φ_b), the energy of resting at the unstable position: the roller swings higher
    each half-period until it creeps toward ±φ_b. Once the state is within the LQR's
    capture region about the nearer of ±φ_b (|error| <= capture_angle and
    |φ'| <= capture_speed), the :class:`LQR` about it takes over.

    Args:
        scene: the scalar scene.
        max_torque: the torque [N·m] of an action of ±1.
        dt: the control step [s].
        target: φ_b > 0 [rad], the unstable rest position (−φ_b counts as well).
        energy_gain: the gain k of the energy pump τ = k (E_b − E) φ' [N·m·s/(J·rad)].
        capture_angle: the handover band in position [rad].
        capture_speed: the handover band in speed [rad/s].
        **weights: the LQR's ``position_scale``, ``speed_scale``, ``torque_scale``.
    """

    def __init__(
        self,
        task: Task,
        scene: Scene,
        max_torque: float,
        dt: float,
        target: float,
        energy_gain: float = 20.0,
        capture_angle: float = 0.5,
        capture_speed: float = 1.5,
        **weights: float,
    ) -> None:
        self.scene, self.max_torque = scene, float(max_torque)
        self.target = abs(float(target))
        self.energy_target = float(energy(scene, self.target, 0.0))
        self.energy_gain = float(energy_gain)
        self.capture_angle, self.capture_speed = float(capture_angle), float(capture_speed)
        self.lqr = LQR(task, scene, max_torque, dt, target=self.target, **weights)

    @classmethod
    def from_env(cls, env: gym.Env | Any, scene: Scene | None = None,
                 **kwargs: float) -> EnergySwingUp:
        """The swing-up for a RollerBalance environment (target φ_b from its task).

        Args:
            env: the environment (wrappers allowed).
            **kwargs: the other arguments of the class.
        """
        scene, max_torque, dt = _task_settings(env, scene)
        task = env.unwrapped.task
        return cls(task, scene, max_torque, dt, task.default_target(scene), **kwargs)

    def act(self, observation: np.ndarray) -> np.ndarray:
        s = decode_observation(observation, self.scene, self.lqr.task)
        up = self.lqr.error(s.phi, self.target)
        down = self.lqr.error(s.phi, -self.target)
        target = np.where(np.abs(up) <= np.abs(down), self.target, -self.target)
        error = np.minimum(np.abs(up), np.abs(down))
        pump = self.energy_gain * (self.energy_target - energy(self.scene, s.phi, s.phi_dot))
        tau = pump * s.phi_dot
        captured = (error <= self.capture_angle) & (np.abs(s.phi_dot) <= self.capture_speed)
        if captured.any():
            tau[captured] = self.lqr.torque(s.phi[captured], s.phi_dot[captured],
                                            target[captured])
        return np.clip(tau / self.max_torque, -1.0, 1.0)[:, None]


class EnergyPump(Controller):
    """Energy shaping toward a target swing (RollerSwing): with E = ½ J_I φ'² + V(φ) and
    dE/dt = τ φ', the torque τ = max_torque · clip(energy_gain · (E* − E), ±1) · sgn(φ')
    (sgn 0 = +1, so that it starts from rest) only ever moves E toward E* = V(φ*), the
    energy of a swing that turns back at the observed amplitude φ*. Designed on the nominal
    scene, from the observation alone.

    The gain is at least 1/(2 max_torque ω* dt), ω* = sqrt(2 E*/J_I(0)) the swing's fastest
    speed: there a step of the torque the error asks for moves E by half the error, so the
    pump closes in without overshooting. Below it, in scenes whose swings hold far less
    than a joule (``tight_fit``: 1e-3 J), the pump stalls short of the success band.

    Args:
        task: the task (its observation carries the target).
        scene: the scalar scene.
        max_torque: the torque [N·m] of an action of ±1.
        energy_gain: the pump's gain [1/J], where it exceeds the floor above.
        dt: the control step [s] (for the floor).
    """

    def __init__(self, task: Task, scene: Scene, max_torque: float,
                 energy_gain: float = 20.0, dt: float = 0.05) -> None:
        self.task, self.scene, self.max_torque = task, scene, float(max_torque)
        self.energy_gain, self.dt = float(energy_gain), float(dt)
        m, r, kappa, e, k, _, _ = scene.params
        self._inertia = float(equations.inertia(0.0, m, r, kappa, e, k))  # J_I(0) [kg·m²]

    @classmethod
    def from_env(cls, env: gym.Env | Any, scene: Scene | None = None,
                 **kwargs: float) -> EnergyPump:
        """The pump for a RollerSwing environment (wrappers allowed)."""
        scene, max_torque, dt = _task_settings(env, scene)
        return cls(env.unwrapped.task, scene, max_torque, **{"dt": dt, **kwargs})

    def gain(self, target_energy: np.ndarray) -> np.ndarray:
        """The pump's gain [1/J] toward the target energy E* [J]."""
        speed = np.sqrt(2.0 * np.maximum(target_energy, 0.0) / self._inertia)
        step = 2.0 * self.max_torque * speed * self.dt  # [J] per unit push, doubled
        return np.maximum(self.energy_gain, 1.0 / np.where(step > 0, step, np.inf))

    def act(self, observation: np.ndarray) -> np.ndarray:
        s = decode_observation(observation, self.scene, self.task)
        if s.target_phi is None:
            raise ValueError("EnergyPump needs observations that carry the target")
        target_energy = energy(self.scene, s.target_phi, 0.0)
        error = target_energy - energy(self.scene, s.phi, s.phi_dot)
        push = np.clip(self.gain(target_energy) * error, -1.0, 1.0)
        return (push * np.where(s.phi_dot >= 0.0, 1.0, -1.0))[:, None]


#: The classical controllers by the name a task gives in ``Task.classical``, with the
#: label the results tables use.
CONTROLLERS: dict[str, tuple[type[Controller], str]] = {
    "lqr": (LQR, "LQR"),
    "swing_up": (EnergySwingUp, "energy swing-up + LQR"),
    "energy_pump": (EnergyPump, "energy pump"),
}


class Informed(Controller):
    """The task's classical controller designed anew for each episode's true scene, read
    from the environment (which an agent does not see): the reference that shows what a
    task whose scene is drawn per episode and hidden allows, beside the classical
    controller designed on the nominal scene (:func:`controller_for`).

    Args:
        env: a roller-gym environment (wrappers allowed): it is read at every action.
        **kwargs: the controller's weights and gains, as for :func:`controller_for`.
    """

    def __init__(self, env: gym.Env | Any, **kwargs: float) -> None:
        self.env, self.kwargs = env, kwargs
        self._scene: Scene | None = None
        self._inner: Controller | None = None

    def act(self, observation: np.ndarray) -> np.ndarray:
        scene = self.env.unwrapped.scene
        if scene is not self._scene or self._inner is None:
            controller, _ = CONTROLLERS[self.env.unwrapped.task.classical]
            self._scene = scene
            self._inner = controller.from_env(self.env, scene=scene, **self.kwargs)
        return self._inner.act(observation)


def controller_for(env: gym.Env | Any, **kwargs: float) -> Controller:
    """The classical controller of a roller task (the one its ``Task.classical`` names),
    built from the environment's task, scene, torque limit and control step.

    Args:
        env: a roller-gym environment (wrappers allowed).
        **kwargs: the controller's weights and gains (see :class:`LQR`,
            :class:`EnergySwingUp`).
    """
    controller, _ = CONTROLLERS[env.unwrapped.task.classical]
    return controller.from_env(env, **kwargs)
