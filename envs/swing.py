"""roller_gym/RollerSwing-v1: keep the roller swinging at a given amplitude.

A roller rolls without slipping inside a fixed cylinder (the preset ``"paper"``). It starts
at rest near the bottom. Each episode draws an amplitude ψ* on the wall; the agent must
pump the roller up until it swings between ±ψ*, and keep it swinging there: neither at rest
nor spinning over the top. What counts is the roller's energy E against E* = V(φ*), the
energy of a swing that turns back at φ* (the potential energy there; V = 0 at the bottom):
a swing of that amplitude has that energy at every point of it.

## Action space

``Box(-1, 1, (1,), float32)``: the torque τ = action · ``max_torque`` [N·m] (default
0.1 N·m: a few pumps reach the target swing), positive in the sense of φ. Out-of-range
actions are clipped; NaN or inf raise ``ValueError``.

## Observation space

``Box(-1, 1, (9,), float32)``:

=====  ======================  ==================================================
index  field                   meaning
=====  ======================  ==================================================
0      ``cos_psi``             cos ψ: where the roller is on the surface (ψ = 0 at the bottom)
1      ``sin_psi``             sin ψ
2      ``cos_phi``             cos φ: how the roller is turned
3      ``sin_phi``             sin φ
4      ``speed``               tanh(φ' / 10 rad/s): the angular speed
5      ``cos_psi_target``      cos ψ*: the amplitude on the wall
6      ``sin_psi_target``      sin ψ*
7      ``cos_phi_target``      cos φ*: the roller's rotation at the amplitude
8      ``sin_phi_target``      sin φ*
=====  ======================  ==================================================

## Reward

In [0, 1] per step, with ε_E = E/E* − 1 the relative energy error (−1 at rest at the
bottom, 0 on the target swing):
``(0.8 near(ε_E, 0.4) + 0.2 near(ε_E, 2)) · (0.8 + 0.2 near(τ/max_torque, 1))``,
``near(x, m) = exp(ln(0.1) (x/m)²)``. The reward falls strictly as |ε_E| grows: at the
success band's edge (|ε_E| = 0.1) it is 0.89 of the reward on the target, at twice the
band 0.65. The wide term pays 0.11 at rest at the bottom and rises with every pump, so
that the way up is rewarded before the target swing is reached. Coasting on the target
swing (τ = 0) pays most: no torque is needed to keep a swing of the target's energy.

## Starting state

At rest, ψ uniform in ±5° (redrawn until the roller rolls there under every torque of the
limit); the amplitude φ* uniform in [45 %, 85 %] of the range where friction can hold the
roller at rest (|F| <= 0.9 μN, :func:`roller_gym.task.hold_ranges` without a torque limit)
and the potential rises from the bottom on, on either side; the upper end is lowered
where a swing with the success band's highest energy, 1.1 E*, would pass over the
potential's first barrier (the floor, larger cylinders). On larger cylinders (R of 2 m and
more at the defaults) the starts are kept where the potential is at most half the smallest
target's energy, so that no start has the target swing's energy.

## Scenes

Checked at construction, each scene of a vector env too: every target swing has energy
(E* > 0), rolls all the way within the success band under any torque of the limit
(N > 0, |F| <= 0.9 μN), the pump outruns the damping (c times the mean |φ'| over the
largest target's swing at most 0.8 max_torque), the torque can bring the largest target's
energy within 0.3 of the episode at its most power (:func:`roller_gym.bounds.energy_time`
<= 0.3 · 400 · dt), and the control step resolves the swing (ω0·dt < π, ω0 its small
oscillations' angular frequency). No ``randomize`` range is accepted: these are checked per
scene, and no proof over a range of scenes covers them yet.

## Episode end

* Terminated: the roller slips (|F| > μN) or leaves the wall (N <= 0) during a step, or a
  step could not stay finite (``info["nonfinite"]``).
* Truncated: 400 steps (20 s at the default dt = 0.05 s).
* ``info["is_success"]``: |ε_E| <= 0.1, the roller swings with the energy of the target
  amplitude within 10 %.

## Arguments

``gymnasium.make("roller_gym/RollerSwing-v1", scene=..., dt=..., max_torque=...,
tolerance=..., integrator=..., substeps=..., randomize=..., render_mode=...)``: see
:class:`roller_gym.roller_env.RollerEnv`.

## Version History

* v1: the reward's wide term (0.2 near(ε_E, 2)) pays for the energy gained on the way up:
  without it the reward at rest was 6e-7 and TD3 never learned to pump on 1 or 2 of 5
  seeds. Later within v1: the amplitudes stop where the potential stops rising and where
  1.1 E* would pass the first barrier (larger cylinders, the presets "balance", "floor" and
  "drum"), starts stay below half the smallest target's energy, and scenes whose target
  swings cannot roll or be pumped against the damping ("rim_mass") are refused, as are
  ``randomize`` ranges; the default scene's episodes are drawn bit for bit as before.
* v0: the first version.
"""

from __future__ import annotations

import math

import numpy as np
from roller_gym import rewards
from roller_gym.bounds import pump_time
from roller_gym.physics import Scene, energy, equations, small_oscillation_frequency
from roller_gym.physics.integrators import SCENE_FIELDS, scene_arrays
from roller_gym.physics.scene import shown
from roller_gym.rest import barrier_energy, last_within, orbit_mean_speed, orbit_speed
from roller_gym.task import Task, hold_ranges, objective, per_scene, reach, register

__all__ = ["SwingTask"]


@register
class SwingTask(Task):
    name = "RollerSwing"
    version = 1
    observation = ("cos_psi", "sin_psi", "cos_phi", "sin_phi", "speed", "cos_psi_target",
                   "sin_psi_target", "cos_phi_target", "sin_phi_target")
    classical = "energy_pump"
    descends = False  # the target lies up where the energy is pumped
    symmetric_target = True  # ±φ*: the swing turns back at both
    max_episode_steps = 400
    default_max_torque = 0.1
    reward_threshold = 340.4  # the energy pump's mean return on seeds 10000–10099 (358.3) − 5 %
    #: Success: |E/E* − 1| <= energy_band; the reward's widths: energy_margin (precision) and
    #: reach_margin (a slope from rest on), the latter weighing reach_weight.
    energy_band = 0.1
    energy_margin = 0.4
    reach_margin = 2.0
    reach_weight = 0.2
    control_weight = 0.2
    #: The amplitude's range, as shares of :meth:`amplitude_ranges` on its side.
    amplitude_shares = (0.45, 0.85)
    #: A start's potential energy is at most this share of the smallest target's E*.
    start_energy_share = 0.5
    #: The damping's mean torque over the largest target's swing, c·mean|φ'|, is at most
    #: this share of max_torque, as the swing-ups' (the energy pump wins 6 of 6 at 0.93 of
    #: it on ``paper``, 4 of 6 at 1.1: ``docs/MAINTAINERS.md``).
    damping_share = 0.8
    start_rule = ("at rest, ψ within ±5° (|φ| <= 64 turns) and the potential at most half the "
                  "smallest target's energy")
    start_speed = 0.0
    parameters = ("energy_band", "energy_margin", "reach_margin", "reach_weight",
                  "control_weight", "max_torque",
                  "symmetric_target", "observes_target")

    @staticmethod
    @objective
    def reward(s, k):
        """(1 − reach_weight) near(E/E* − 1, energy_margin) + reach_weight near(E/E* − 1,
        reach_margin), less up to control_weight for torque."""
        error = s.energy / s.target_energy - 1.0
        energy = ((1.0 - k.reach_weight) * rewards.near(error, k.energy_margin)
                  + k.reach_weight * rewards.near(error, k.reach_margin))
        return energy * rewards.blend(rewards.near(s.torque / k.max_torque, 1.0),
                                      k.control_weight)

    @staticmethod
    @objective
    def success(s, k):
        """The energy within energy_band of the target swing's, relative to it."""
        return np.abs(s.energy / s.target_energy - 1.0) <= k.energy_band

    def infeasible(self, scene: Scene, dt: float | None = None) -> str | None:
        """:meth:`Task.infeasible`, and with the control step ``dt`` [s] the swing resolved:
        its small oscillations' angular frequency ω0 = sqrt(V''(0) / J_I(0)) [rad/s] gives
        at least two control steps per period, ω0·dt < π (a torque held over a step acts in
        phase with fewer than that only by aliasing: the energy pump fails there)."""
        reason = super().infeasible(scene, dt)
        if reason is not None or dt is None:
            return reason
        try:
            omega = float(small_oscillation_frequency(scene))
        except ValueError:  # no oscillation about the bottom (d²V/dφ² <= 0): none to resolve
            return None
        if not omega * dt < math.pi:
            return (f"dt={dt:g} s is too long for the swing of {shown(scene)}: its small "
                    f"oscillations have ω0 = {omega:.4g} rad/s, so ω0·dt = {omega * dt:.3g} >= "
                    "π, fewer than two control steps per period, and a torque held over a "
                    f"step cannot act in phase with the swing; use dt < π/ω0 = "
                    f"{math.pi / omega:.3g} s or a looser fit (a larger R)")
        return None

    def check_scene(self, scene: Scene) -> None:
        """The scene poses every target swing drawn (checked on a grid of amplitudes on both
        sides, up to :meth:`top_shares`): E* > 0 [J], so that E/E* − 1 is defined (not where
        the potential is flat, a concentric roller on the floor, or falls from the bottom
        on, a drum with its mass center too near the axle); the swing within the success
        band rolls all the way, N > 0 and |F| <= 0.9 μN under any torque of the limit
        (:meth:`rolling_margins`); and the pump at max_torque outruns the damping over the
        largest target's swing, c·mean|φ'| <= damping_share·max_torque
        (:func:`roller_gym.rest.orbit_mean_speed`)."""
        low, high = self.amplitude_ranges(scene)
        lo = self.amplitude_shares[0]
        tops = [float(t[0]) for t in self.top_shares(scene)]
        if min(tops) < lo:
            raise ValueError(
                f"{shown(scene)} lets the smallest target swing (amplitude {lo:.0%} of "
                f"[{float(low[0]):.4g}, {float(high[0]):.4g}] rad, the range friction holds and "
                "the potential rises in), with the success band's energy, pass over the "
                "potential's barrier: use a deeper well (a larger e on the floor, friction "
                "inside a cylinder)")
        amplitudes = np.concatenate([np.linspace(lo, tops[0], 65) * low[0],
                                     np.linspace(lo, tops[1], 65) * high[0]])
        target_energy = np.asarray(energy(scene, amplitudes, 0.0))
        if not np.all(target_energy > 0.0):
            worst = int(np.argmin(np.where(np.isnan(target_energy), -np.inf, target_energy)))
            raise ValueError(
                f"{shown(scene)} gives a target swing no energy: E* = "
                f"{float(target_energy[worst]):.3g} J at the amplitude phi* = "
                f"{float(amplitudes[worst]):.4g} rad (the range friction holds and the "
                f"potential rises in is "
                f"[{float(low[0]):.4g}, {float(high[0]):.4g}] rad), and the reward E/E* − 1 "
                "needs E* > 0: use an eccentric mass, e > 0 on the floor or "
                "e > r²|κ|/(1 + r|κ|) on a drum (κ = 1/R), or friction (mu > 0) inside a "
                "cylinder"
            )
        lift, slip, _ = self.rolling_margins(scene, amplitudes[::4])
        if lift <= 0.0 or slip < 0.0:
            raise ValueError(
                f"{shown(scene)} poses target swings that cannot roll: on the swing of the "
                f"success band's energy, N/(m g) falls to {lift:.3g} (<= 0: lift-off) or "
                f"(0.9 mu N − |F|)/(m g) to {slip:.3g} (< 0: slip); use more friction (mu), a "
                "mass center nearer the axle (smaller e) or a smaller max_torque")
        widest = float(np.max(np.abs(amplitudes)))
        speed = orbit_mean_speed(scene, widest, float(energy(scene, widest, 0.0)))
        if scene.damping * speed > self.damping_share * self.max_torque:
            raise ValueError(
                f"damping={scene.damping:g} N·m·s/rad of {shown(scene)} takes "
                f"{scene.damping * speed:.3g} N·m on average over the largest target swing "
                f"(amplitude {widest:.4g} rad, mean speed {speed:.3g} rad/s), more than "
                f"{self.damping_share:g} of max_torque={self.max_torque:g} N·m: the pump "
                f"cannot reach the target swing; use damping <= "
                f"{self.damping_share * self.max_torque / speed:.3g} or a larger max_torque")

    def rolling_margins(self, scene: Scene, amplitudes: np.ndarray) -> tuple[float, float, float]:
        """(least N/(m g), least (0.9 μN − |F|)/(m g), fastest |φ'| [rad/s]) over the swings
        of the scalar ``scene`` that turn back at ``amplitudes`` [rad], with the target's
        energy and the success band's highest, either way round, under torques −max_torque,
        0 and max_torque: 129 points of φ between the turning points (V is even in φ)."""
        m, r, kappa, e, k, g, c = scene.params
        top = np.abs(np.asarray(amplitudes, float))[:, None, None]
        level = np.asarray(energy(scene, top, 0.0)) * np.array([1.0, 1.0 + self.energy_band]
                                                               )[None, :, None]
        phi = top * np.linspace(-1.0, 1.0, 129)[None, None, :]
        speed = orbit_speed(scene, phi, level)
        lift, slip = math.inf, math.inf
        for phi_dot in (speed, -speed):
            for tau in (-self.max_torque, 0.0, self.max_torque):
                accel = equations.accel(phi, phi_dot, tau, m, r, kappa, e, k, g, c)
                normal, friction = equations.contact_forces(phi, phi_dot, accel, m, r, kappa,
                                                            e, g)
                lift = min(lift, float(np.min(normal)) / (m * g))
                slip = min(slip, float(np.min(0.9 * scene.mu * normal - np.abs(friction)))
                           / (m * g))
        return lift, slip, float(np.max(speed))

    def top_shares(self, scene: Scene) -> tuple[np.ndarray, np.ndarray]:
        """The largest amplitude shares (low side, high side; one per roller) of
        :meth:`amplitude_ranges`: amplitude_shares' upper end, lowered where a swing with the
        success band's highest energy, (1 + energy_band)·V(φ*), would pass over the
        potential's barrier (:func:`barrier_energy`) and spin over the top."""
        low, high = self.amplitude_ranges(scene)
        hi = self.amplitude_shares[1]
        barrier = per_scene(barrier_energy, scene)
        rows = dict(zip(SCENE_FIELDS, scene_arrays(scene), strict=True))
        m, r, kappa, e, g = (rows[f] for f in ("m", "r", "kappa", "e", "g"))
        tops = []
        for side in (low, high):
            def over(share: np.ndarray, side: np.ndarray = side) -> np.ndarray:
                return ((1.0 + self.energy_band)
                        * equations.potential(share * side, m, r, kappa, e, g) > barrier)
            top = np.full_like(side, hi)  # the potential rises on the side's range
            capped = over(top)  # (a reset's cost: bisect only where some roller needs it)
            tops.append(np.where(capped, last_within(over, np.zeros_like(side), top), hi)
                        if capped.any() else top)
        return tops[0], tops[1]

    def pump_time(self, scene: Scene) -> tuple[float, float, float]:
        """(1 − energy_band)·E* [J] of the largest target (the least energy that succeeds),
        the fastest speed ω [rad/s] of its swing in the band (at the bottom), and
        :func:`roller_gym.bounds.pump_time` [s] to it from the most a start has (at rest at
        :meth:`start_limits`; within the swing's well V >= 0)."""
        low, high = self.amplitude_ranges(scene)
        top = max(float(t[0]) * abs(float(side[0]))
                  for t, side in zip(self.top_shares(scene), (low, high), strict=True))
        speed = self.rolling_margins(scene, np.array([top]))[2]
        needed = (1.0 - self.energy_band) * float(energy(scene, top, 0.0))
        start = float(energy(scene, float(self.start_limits(scene)[0]), 0.0))
        return needed, speed, pump_time(scene, start, needed, self.max_torque)

    def amplitude_ranges(self, scene: Scene) -> tuple[np.ndarray, np.ndarray]:
        """The ranges [low, high] [rad of φ] the amplitudes are shares of, one per roller: where
        friction holds the roller at rest and the potential rises from the bottom on
        (:func:`roller_gym.task.hold_ranges` without a torque limit, ``rising``), so that a
        swing of energy E* = V(φ*) turns back at ±φ*, before any barrier of the potential."""
        return hold_ranges(scene, math.inf, rising=True)

    def sample_targets(self, u: np.ndarray, scene: Scene) -> np.ndarray:
        low, high = self.amplitude_ranges(scene)
        lo = self.amplitude_shares[0]
        top_low, top_high = self.top_shares(scene)
        wide = np.abs(2.0 * u - 1.0)  # the side from u's half
        return np.where(u < 0.5, (lo + (top_low - lo) * wide) * low,
                        (lo + (top_high - lo) * wide) * high)

    def default_target(self, scene: Scene) -> float:
        top = float(self.top_shares(scene)[1][0])
        return float(self.amplitude_ranges(scene)[1][0]) * (self.amplitude_shares[0] + top) / 2

    def start_candidates(
        self, u_phi: np.ndarray, u_dot: np.ndarray, scene: Scene
    ) -> tuple[np.ndarray, np.ndarray]:
        limit = np.reshape(self.start_limits(scene), (-1, 1))
        return limit * (2.0 * u_phi - 1.0), 0.0 * u_dot

    def start_limits(self, scene: Scene) -> np.ndarray:
        """How far [rad of φ] from the bottom a start lies, one per roller: ψ within ±5°
        (:func:`roller_gym.task.reach`), and no further than where the potential reaches
        start_energy_share of the smallest target's energy E*: a start at rest never has
        the target swing's energy (success needs pumping). The latter by bisection on the
        rising potential (60 halvings), only where the former reaches past it."""
        angle = np.reshape(reach(scene, math.radians(5.0)), -1).astype(float)
        low, high = self.amplitude_ranges(scene)
        rows = dict(zip(SCENE_FIELDS, scene_arrays(scene), strict=True))
        m, r, kappa, e, g = (rows[f] for f in ("m", "r", "kappa", "e", "g"))

        def potential(phi: np.ndarray) -> np.ndarray:
            return equations.potential(phi, m, r, kappa, e, g)

        smallest = self.amplitude_shares[0] * np.minimum(-low, high)
        level = self.start_energy_share * np.minimum(
            potential(self.amplitude_shares[0] * low), potential(smallest))
        def over(phi: np.ndarray) -> np.ndarray:
            return potential(phi) > level

        above = np.minimum(angle, smallest)  # (the potential rises on [0, smallest])
        capped = over(above)
        return (np.where(capped, last_within(over, np.zeros_like(smallest), above), angle)
                if capped.any() else angle)

