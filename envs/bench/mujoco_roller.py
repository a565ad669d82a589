"""The roller scene in MuJoCo, modelled as well as a general-purpose engine allows.

MuJoCo has no rolling-without-slipping constraint between a cylinder and a concave
cylinder, so the scene of ``docs/PHYSICS.md`` is built from two joints and a coupling,
in the x-z plane (gravity −z; our y is MuJoCo's z):

* a body ``arm`` hinged at the fixed cylinder's axis O. Its hinge axis is −y, so its joint
  angle is ψ (counter-clockwise, seen with x to the right and z up);
* a child body ``roller`` at distance R − r from O along the arm (O1), hinged to the arm
  about +y: its joint angle q is the roller's rotation *relative to the arm*. The roller's
  absolute rotation, clockwise positive, is φ = q − ψ;
* the roller's inertial: mass m at ``pos = (0, 0, −e)`` (C below O1 when φ = 0), inertia
  m k² about C;
* rolling without slipping, (R − r) ψ = r φ, written in the joints: q = φ + ψ = (R/r) ψ, a
  joint equality constraint ``q = (R/r) ψ`` (``polycoef="0 R/r 0 0 0"``). It is soft, as
  every MuJoCo constraint is; ``solref``/``solimp`` set how soft;
* the arm would be massless, but MuJoCo rejects a moving body without mass: it carries a
  mass of 1e-14 kg at O and a moment of inertia of max(1e-12 m (R − r)², 1e-14 kg·m²),
  a relative change below ~1e-8 in the dynamics (tight fit) and ~1e-12 elsewhere;
* the drive τ: a motor on a site of the roller with gear (0, 0, 0, 0, 1, 0), a pure couple
  about +y on the roller (power τφ', as in PHYSICS.md; a motor on the joint q would also
  push the arm back and deliver τ q' instead).

The same construction holds on top of a drum (R < 0: the arm, of length R − r < 0, points
up). On a flat floor (R = ∞) the arm becomes a slide joint x along the floor with the
roller hinged at height r (φ absolute) and the coupling x = r φ. A scene with a huge but
finite R (e.g. 1e12 m) cannot be built with an arm of that length (positions of 1e12 m in
double precision lose everything below 1e-4 m); it is built as the floor, which differs
from it by ~r/R in the dynamics.

Damping at the roller's axle (``Scene.damping``) is not modelled (all presets have none).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np
from roller_gym.physics import Scene

__all__ = ["DEFAULT", "HUGE_R", "MujocoRoller", "MujocoSettings", "roller_xml", "tuned"]

#: The arm's moment of inertia about O, relative to the roller's m (R − r)² (MuJoCo rejects a
#: massless moving body), and the floor for it and the arm's mass at O [kg, kg·m²] (MuJoCo's
#: mjMINVAL is 1e-15).
ARM = 1e-12
ARM_MIN = 1e-14
#: Beyond this |R| [m] the scene is built as the floor (see the module docs).
HUGE_R = 1e6


@dataclass(frozen=True)
class MujocoSettings:
    """The MuJoCo options that decide accuracy and cost.

    Attributes:
        timestep: the MuJoCo step [s]; the control step must be a multiple of it.
        integrator: ``"Euler"`` (semi-implicit, MuJoCo's default), ``"RK4"``,
            ``"implicit"`` or ``"implicitfast"``.
        solref: the equality constraint's reference (timeconst [s], dampratio [-]), or
            (−stiffness, −damping) when negative.
        solimp: the equality constraint's impedance (dmin, dmax, width [m], midpoint, power).
        tolerance: the constraint solver's tolerance [-].
        iterations: the constraint solver's maximum iterations.
        refsafe: MuJoCo's safety clamp timeconst >= 2 timestep (True is MuJoCo's default).
    """

    timestep: float = 0.002
    integrator: str = "Euler"
    solref: tuple[float, float] = (0.02, 1.0)
    solimp: tuple[float, float, float, float, float] = (0.9, 0.95, 0.001, 0.5, 2.0)
    tolerance: float = 1e-8
    iterations: int = 100
    refsafe: bool = True

    def with_timestep(self, timestep: float) -> MujocoSettings:
        """A copy with another timestep [s]."""
        return MujocoSettings(
            timestep, self.integrator, self.solref, self.solimp, self.tolerance,
            self.iterations, self.refsafe,
        )


#: MuJoCo's own defaults (timestep 2 ms, semi-implicit Euler, soft constraint).
DEFAULT = MujocoSettings()
#: The constraint's time constant per timestep in :func:`tuned`: the stiffest the RK4
#: integrator keeps stable (the constraint's critically damped pair has eigenvalues near
#: −1/timeconst; RK4 is stable on the real axis up to 2.78/timestep; 0.3 diverged in tests).
TUNED_TIMECONST = 0.5


def tuned(timestep: float) -> MujocoSettings:
    """Settings tuned for accuracy at ``timestep`` [s].

    RK4; the stiffest equality constraint that stays stable: timeconst = 0.5 timestep
    (MuJoCo's safety clamp ``refsafe``, timeconst >= 2 timestep, turned off: that clamp
    costs a factor 16 in error), critical damping, impedance 0.9999 (MuJoCo's maximum);
    solver tolerance 1e-15 and 200 iterations. The constraint's violation, and so the
    error, then falls as timestep² (validated against DOP853 in the benchmark).
    """
    return MujocoSettings(
        timestep=timestep,
        integrator="RK4",
        solref=(TUNED_TIMECONST * timestep, 1.0),
        solimp=(0.9999, 0.9999, 0.001, 0.5, 2.0),
        tolerance=1e-15,
        iterations=200,
        refsafe=False,
    )


def _fmt(x: float) -> str:
    return repr(float(x))


def roller_xml(scene: Scene, settings: MujocoSettings = DEFAULT) -> str:
    """The MJCF of ``scene`` (a scalar :class:`~roller_gym.physics.Scene`) under ``settings``."""
    if scene.batch_size is not None:
        raise ValueError("roller_xml() takes a scalar scene")
    if float(scene.damping) != 0.0:
        raise ValueError("the MuJoCo model does not include axle damping (Scene.damping)")
    m, r, R, e, k, g = (float(getattr(scene, f)) for f in ("m", "r", "R", "e", "k", "g"))
    J = m * k * k
    arm_m = _fmt(ARM_MIN)
    arm_j = _fmt(max(ARM * m * (R - r) ** 2, ARM_MIN) if math.isfinite(R) else ARM_MIN)
    solref = " ".join(_fmt(x) for x in settings.solref)
    solimp = " ".join(_fmt(x) for x in settings.solimp)
    # No contacts; no silent reset to the initial state when the simulation blows up.
    flags = '<flag contact="disable" autoreset="disable"' + (
        "" if settings.refsafe else ' refsafe="disable"'
    ) + "/>"
    roller_body = f"""
          <inertial pos="0 0 {_fmt(-e)}" mass="{_fmt(m)}"
                    diaginertia="{_fmt(J)} {_fmt(J)} {_fmt(J)}"/>
          <geom type="cylinder" size="{_fmt(r)} {_fmt(0.2 * r)}" zaxis="0 1 0"
                contype="0" conaffinity="0"/>
          <site name="drive" pos="0 0 0"/>"""
    if math.isinf(R) or abs(R) >= HUGE_R:
        body = f"""
      <body name="roller" pos="0 0 {_fmt(r)}">
        <joint name="x" type="slide" axis="1 0 0"/>
        <joint name="q" type="hinge" axis="0 1 0"/>{roller_body}
      </body>"""
        coupling = f'joint1="x" joint2="q" polycoef="0 {_fmt(r)} 0 0 0"'
    else:
        body = f"""
      <body name="arm" pos="0 0 0">
        <joint name="psi" type="hinge" axis="0 -1 0"/>
        <inertial pos="0 0 0" mass="{arm_m}" diaginertia="{arm_j} {arm_j} {arm_j}"/>
        <body name="roller" pos="0 0 {_fmt(-(R - r))}">
          <joint name="q" type="hinge" axis="0 1 0"/>{roller_body}
        </body>
      </body>"""
        coupling = f'joint1="q" joint2="psi" polycoef="0 {_fmt(R / r)} 0 0 0"'
    return f"""<mujoco model="roller">
  <compiler angle="radian" inertiafromgeom="false"/>
  <option timestep="{_fmt(settings.timestep)}" integrator="{settings.integrator}"
          gravity="0 0 {_fmt(-g)}" tolerance="{_fmt(settings.tolerance)}"
          iterations="{settings.iterations}">
    {flags}
  </option>
  <worldbody>{body}
  </worldbody>
  <equality>
    <joint {coupling} solref="{solref}" solimp="{solimp}"/>
  </equality>
  <actuator>
    <motor name="tau" site="drive" gear="0 0 0 0 1 0" ctrllimited="false"/>
  </actuator>
</mujoco>
"""


class MujocoRoller:
    """One roller in MuJoCo, stepped per control step at constant torque, read as (φ, φ').

    Args:
        scene: a scalar scene.
        settings: the MuJoCo options.
    """

    def __init__(self, scene: Scene, settings: MujocoSettings = DEFAULT) -> None:
        self.scene = scene
        self.settings = settings
        self.model = mujoco.MjModel.from_xml_string(roller_xml(scene, settings))
        self.data = mujoco.MjData(self.model)
        R, r = float(scene.R), float(scene.r)
        self.floor = math.isinf(R) or abs(R) >= HUGE_R
        # (first joint, q) per unit φ: the floor's x = r φ; the arm's ψ = r φ/(R − r), q = φ + ψ.
        if self.floor:
            self._per_phi = np.array([r, 1.0])
        else:
            psi = r / (R - r)
            self._per_phi = np.array([psi, 1.0 + psi])

    def reset(self, phi: float, phi_dot: float) -> None:
        """Put the roller at φ [rad], φ' [rad/s], on the constraint."""
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[:] = self._per_phi * phi
        self.data.qvel[:] = self._per_phi * phi_dot
        mujoco.mj_forward(self.model, self.data)

    @property
    def diverged(self) -> bool:
        """True once MuJoCo met a NaN, an inf or a huge value (its own instability check)."""
        bad = (mujoco.mjtWarning.mjWARN_BADQACC, mujoco.mjtWarning.mjWARN_BADQVEL,
               mujoco.mjtWarning.mjWARN_BADQPOS)
        return any(self.data.warning[w].number > 0 for w in bad) or not (
            np.isfinite(self.data.qpos).all() and np.isfinite(self.data.qvel).all()
        )

    def state(self) -> tuple[float, float]:
        """(φ [rad], φ' [rad/s]): the roller's absolute rotation and its rate."""
        qpos, qvel = self.data.qpos, self.data.qvel
        if self.floor:
            return float(qpos[1]), float(qvel[1])
        return float(qpos[1] - qpos[0]), float(qvel[1] - qvel[0])

    def steps_per(self, dt: float) -> int:
        """MuJoCo steps in a control step of ``dt`` [s] (which must be a multiple)."""
        n = round(dt / self.settings.timestep)
        if n < 1 or abs(n * self.settings.timestep - dt) > 1e-9 * dt:
            raise ValueError(f"dt={dt} s is not a multiple of timestep={self.settings.timestep}")
        return n

    def step(self, tau: float, nstep: int) -> None:
        """Advance ``nstep`` MuJoCo steps at the drive torque τ [N·m]."""
        self.data.ctrl[0] = tau
        mujoco.mj_step(self.model, self.data, nstep)

    def run(self, phi0: float, phi_dot0: float, torques: np.ndarray, dt: float) -> np.ndarray:
        """The states (φ, φ') after each control step of ``dt`` [s]: shape (len(torques)+1, 2).

        A run that diverges stops there; its remaining rows are NaN.
        """
        n = self.steps_per(dt)
        out = np.full((len(torques) + 1, 2), np.nan)
        self.reset(phi0, phi_dot0)
        out[0] = self.state()
        for i, tau in enumerate(torques):
            self.step(float(tau), n)
            if self.diverged:
                break
            out[i + 1] = self.state()
        return out
