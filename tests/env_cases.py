"""What the environments' tests share: each task's documented numbers, and the physics.

The independent source for the physics is :func:`model`, written here from
``docs/PHYSICS.md`` in its cylinder form (R − r, not the code's curvature form); the
documented numbers (episode lengths, default torques, observation layout, reward) are
copied from the docstrings of ``envs/__init__.py`` and the task modules.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import roller_gym
from roller_gym import Scene
from roller_gym.rest import reach

# From the docstrings: steps per episode, default max_torque [N·m], observation size,
# default preset.
DOCUMENTED = {
    "roller_gym/RollerStabilize-v2": {"steps": 200, "max_torque": 0.5, "obs": 5, "scene": "paper",
                                      "band": 0.05, "margin": 2.0},
    "roller_gym/RollerHold-v2": {"steps": 200, "max_torque": 1.0, "obs": 9, "scene": "paper",
                                 "band": 0.05, "margin": 2.0},
    "roller_gym/RollerBalance-v2": {"steps": 400, "max_torque": 0.4, "obs": 5, "scene": "balance",
                                    "band": 0.1, "margin": 3.0},
    "roller_gym/RollerTrack-v1": {"steps": 400, "max_torque": 1.0, "obs": 10, "scene": "paper",
                                  "band": 0.05, "margin": 1.0},
    # an objective of its own: the relative energy error's band, its margin and the wide
    # term's margin and weight
    "roller_gym/RollerSwing-v1": {"steps": 400, "max_torque": 0.1, "obs": 9, "scene": "paper",
                                  "energy_band": 0.1, "energy_margin": 0.4, "reach_margin": 2.0,
                                  "reach_weight": 0.2},
    "roller_gym/RollerHoldRandomized-v2": {"steps": 200, "max_torque": 1.0, "obs": 9,
                                           "scene": "paper", "band": 0.05, "margin": 2.0},
    "roller_gym/RollerBalanceWeak-v0": {"steps": 400, "max_torque": 0.1, "obs": 5,
                                        "scene": "balance", "band": 0.1, "margin": 3.0},
}
IDS = list(roller_gym.ENV_IDS)


def balances(env_id: str) -> bool:
    """Whether the task balances at an unstable rest position (its documented scene is the
    preset "balance", whose unstable rest positions roll): its scenes must have one."""
    return DOCUMENTED[env_id]["scene"] == "balance"


def posable(env_id: str, scene: str) -> bool:
    """Whether the task can be posed on the preset ``scene``: a balancing task needs an
    unstable rest position that rolls (not the floor's or the drum's); a swing, target
    swings that roll (not the preset "rim_mass"'s, which lift off) and a swing the control
    step resolves (not "tight_fit"'s, 1.5 steps per period at the default dt); the tasks
    that bring the roller down not "drum", whose starts past the barrier are pushed off, nor
    RollerStabilize (0.5 N·m) "rim_mass", whose farthest must slip on the way in (both
    roller_gym.descent); the others any preset (a swing on the drum, in the well its
    eccentric mass makes at the top)."""
    if balances(env_id):
        return scene not in ("floor", "drum")
    if "RollerSwing" not in env_id and scene == "drum":
        return False
    if "RollerStabilize" in env_id and scene == "rim_mass":
        return False
    return not ("RollerSwing" in env_id and scene in ("rim_mass", "tight_fit"))


def randomizable(env_id: str) -> bool:
    """Whether the task takes ``randomize`` ranges: RollerSwing checks its scenes one by one
    (the rolling of its target swings, the barrier), which no proof over a range covers."""
    return "RollerSwing" not in env_id


# -- the physics, from PHYSICS.md ------------------------------------------------------
def model(scene: Scene, phi: float, phi_dot: float, tau: float) -> dict[str, float]:
    """ψ, θ, φ'', N, F, E of PHYSICS.md at (φ, φ') under τ (the presets have no damping).

    Written in the cylinder form with R − r; the floor (R = inf) is its limit (the terms
    with 1/(R − r) or (R − r)(1 − cos ψ) vanish, r R/(R − r) → r).
    """
    m, r, R, e, k, g = (float(getattr(scene, name)) for name in ("m", "r", "R", "e", "k", "g"))
    assert float(scene.damping) == 0.0
    floor = math.isinf(R)
    psi = 0.0 if floor else r * phi / (R - r)
    theta = phi if floor else R * phi / (R - r)
    coriolis = e * r if floor else e * r * R / (R - r)
    phi_ddot = (
        tau / m - coriolis * phi_dot**2 * math.sin(theta)
        - g * (r * math.sin(psi) + e * math.sin(phi))
    ) / (k**2 + e**2 + r**2 - 2 * e * r * math.cos(theta))
    centripetal = 0.0 if floor else r**2 / (R - r)
    normal = m * (g * math.cos(psi) + centripetal * phi_dot**2
                  + e * (phi_ddot * math.sin(theta) + phi_dot**2 * math.cos(theta)))
    friction = m * (g * math.sin(psi) + (r - e * math.cos(theta)) * phi_ddot
                    + e * phi_dot**2 * math.sin(theta))
    j_i = m * (k**2 + r**2 + e**2 - 2 * r * e * math.cos(theta))
    height = 0.0 if floor else (R - r) * (1 - math.cos(psi))
    energy = 0.5 * j_i * phi_dot**2 + m * g * (height + e * (1 - math.cos(phi)))
    return {"psi": psi, "theta": theta, "phi_ddot": phi_ddot, "normal": normal,
            "friction": friction, "energy": energy}


def psi_rate(scene: Scene) -> float:
    """dψ/dφ = r/(R − r) (0 on the floor)."""
    R, r = float(scene.R), float(scene.r)
    return 0.0 if math.isinf(R) else r / (R - r)


def act(a: float) -> np.ndarray:
    return np.array([a], dtype=np.float32)


def check_info_physics(env, info: dict, tau: float) -> None:
    """The info's state, ψ, forces and energy against :func:`model` at that state."""
    scene = env.unwrapped.scene
    ref = model(scene, info["phi"], info["phi_dot"], tau)
    weight = float(scene.m * scene.g)
    assert info["psi"] == pytest.approx(ref["psi"], rel=1e-12, abs=1e-12)
    assert info["normal_force"] == pytest.approx(ref["normal"], rel=1e-9, abs=1e-9 * weight)
    assert info["friction_force"] == pytest.approx(ref["friction"], rel=1e-9, abs=1e-9 * weight)
    assert info["energy"] == pytest.approx(ref["energy"], rel=1e-9, abs=1e-12)


def controller_wins(env, controller, seeds=range(4)) -> int:
    """In how many episodes (one per seed) ``controller`` ends with ``is_success``."""
    wins = 0
    for seed in seeds:
        obs, info = env.reset(seed=seed)
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(controller.act(obs[None])[0])
            done = terminated or truncated
        wins += bool(info["is_success"])
    return wins


def farthest_at_rest(task, scene: Scene, points: int = 4001) -> float:
    """|φ| [rad] of the farthest start at rest the task's draw accepts in ``scene``, on a
    grid of ``points`` over its start range: a start the simulations can take."""
    u = np.linspace(0.5, 1.0, points)[None, :]
    phi, _ = task.start_candidates(u, np.full_like(u, 0.5), scene)
    return float(np.abs(phi[task.start_accepted(phi, np.zeros_like(phi), scene)]).max())


def cell_width(task, scene: Scene) -> float:
    """|φ| [rad] between neighbouring candidates of the task's start range: a cell of
    roller_gym.start_set's covering."""
    return float(reach(scene, task.start_angle)) / (task.start_points - 1)
