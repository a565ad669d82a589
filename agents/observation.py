"""The state of the roller recovered from an observation, read by field name.

A task's observation lists named fields (:data:`roller_gym.task.OBSERVATION_FIELDS`):
cos ψ, sin ψ, cos φ, sin φ, tanh(φ'/10 rad/s) and, in tasks with a target, cos ψ*, sin ψ*,
cos φ*, sin φ*. With the wrap rate q = rκ/(1 − rκ) (ψ = qφ),

* φ' = 10 · atanh(speed) [rad/s];
* φ: ψ/q gives a coarse φ over one turn of ψ either way, and (cos φ, sin φ) the exact
  φ mod 2π; the coarse value picks the turn: φ = φ_mod + 2π·round((φ_coarse − φ_mod)/2π).
  On the floor ψ stays 0 and φ is known modulo 2π only (as in the task's error).

Every function takes one observation (shape (d,)) or a batch (shape (n, d)).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from roller_gym.physics import Scene
from roller_gym.task import SPEED_SCALE, Task, psi_rate

__all__ = ["DecodedState", "decode_angle", "decode_observation"]

# tanh(φ'/10) rounds to ±1 in float32 beyond ≈ 89 rad/s; clip so that atanh stays finite.
_TANH_LIMIT = 1.0 - 1e-7


def decode_angle(cos_psi, sin_psi, cos_phi, sin_phi, rate: float) -> np.ndarray:
    """φ [rad] from (cos ψ, sin ψ) and (cos φ, sin φ), with ψ = rate·φ (rate 0: the floor).

    Args:
        cos_psi, sin_psi: cos ψ and sin ψ (floats or arrays).
        cos_phi, sin_phi: cos φ and sin φ.
        rate: dψ/dφ = rκ/(1 − rκ) of the scene (:func:`roller_gym.task.psi_rate`).

    Returns:
        φ [rad] within one turn of ψ either way (φ in [−π, π) on the floor).
    """
    phi_mod = np.arctan2(np.asarray(sin_phi, float), np.asarray(cos_phi, float))
    if rate == 0.0:
        return phi_mod
    coarse = np.arctan2(np.asarray(sin_psi, float), np.asarray(cos_psi, float)) / rate
    return phi_mod + 2.0 * np.pi * np.round((coarse - phi_mod) / (2.0 * np.pi))


@dataclass(frozen=True)
class DecodedState:
    """The state read from observations (arrays of shape (n,)).

    Attributes:
        phi: the rotation φ [rad].
        phi_dot: the angular speed φ' [rad/s].
        target_phi: the target φ* [rad], or None when the task does not observe its target.
        target_phi_dot: the target's rate φ*' [rad/s]: 0 for a rest position, None when the
            task does not observe its target.
    """

    phi: np.ndarray
    phi_dot: np.ndarray
    target_phi: np.ndarray | None
    target_phi_dot: np.ndarray | None = None


def decode_observation(observation: np.ndarray, scene: Scene,
                       task: type[Task] | Task) -> DecodedState:
    """Recover (φ, φ', φ*) from observations of ``task`` played in ``scene``.

    Args:
        observation: one observation (shape (d,)) or a batch (shape (n, d)).
        scene: the scalar scene the observations come from (it sets the wrap rate q).
        task: the task (its class or instance), whose ``observation`` names the columns.

    Returns:
        A :class:`DecodedState` of arrays of shape (n,) (n = 1 for a single observation).
    """
    obs = np.asarray(observation, dtype=np.float64)
    obs = obs.reshape(1, -1) if obs.ndim == 1 else obs
    size = len(task.observation)
    if obs.ndim != 2 or obs.shape[1] != size:
        raise ValueError(
            f"observation of shape {np.shape(observation)} is not ({size},) or (n, {size}), "
            f"the observation of {task.name}"
        )

    def column(field: str) -> np.ndarray:
        return obs[:, task.index(field)]

    rate = psi_rate(scene)
    phi = decode_angle(column("cos_psi"), column("sin_psi"), column("cos_phi"),
                       column("sin_phi"), rate)
    speed = np.clip(column("speed"), -_TANH_LIMIT, _TANH_LIMIT)
    phi_dot = SPEED_SCALE * np.arctanh(speed)
    target = target_rate = None
    if "cos_psi_target" in task.observation:
        target = decode_angle(column("cos_psi_target"), column("sin_psi_target"),
                              column("cos_phi_target"), column("sin_phi_target"), rate)
        target_rate = np.zeros_like(target)
    if "target_speed" in task.observation:
        speed = np.clip(column("target_speed"), -_TANH_LIMIT, _TANH_LIMIT)
        target_rate = SPEED_SCALE * np.arctanh(speed)
    return DecodedState(phi, phi_dot, target, target_rate)
