"""roller_gym/RollerBalanceWeak-v0: swing up to the unstable rest position with a quarter
of RollerBalance's torque, then balance there.

The hard variant of RollerBalance: the torque limit is 0.1 N·m (RollerBalance: 0.4 N·m),
a tenth of the largest holding torque on the way up (≈ 0.96 N·m). The roller reaches the
top only by pumping energy back and forth over eight or nine half-swings (RollerBalance:
one or two), then must be caught and balanced by a torque that leaves little margin. Why
it is hard: the reward of reaching the top comes only after some 120 steps of pumping in
phase with the swing, which random exploration seldom strings together, so the task
measures exploration and credit assignment over a long horizon.

The classical reference is the energy swing-up + LQR of RollerBalance (``agents/classical``,
gains of ``agents/hyperparams``): on seeds 0–19 it succeeds in every episode, reaching the
band after about 6 s (return 303, RollerBalance's 362):
``roller-gym evaluate --env roller_gym/RollerBalanceWeak-v0``. Its pump is bang-bang, the
most energy a torque this small adds per swing, so the episodes are solvable.

## Action space

``Box(-1, 1, (1,), float32)``: τ = action · ``max_torque`` [N·m] (default 0.1 N·m).
Out-of-range actions are clipped; NaN or inf raise ``ValueError``.

## Observation space

``Box(-1, 1, (5,), float32)``, as RollerBalance's:

=====  ======================  ==================================================
index  field                   meaning
=====  ======================  ==================================================
0      ``cos_psi``             cos ψ: where the roller is on the surface (ψ = 0 at the bottom)
1      ``sin_psi``             sin ψ
2      ``cos_phi``             cos φ: how the roller is turned
3      ``sin_phi``             sin φ
4      ``speed``               tanh(φ' / 10 rad/s): the angular speed
=====  ======================  ==================================================

## Reward

As RollerBalance's, in [0, 1] per step, ε the error to the nearer unstable rest position
±φ_b (rad of φ), φ*' = 0 and τ* = 0 there:
``(0.4 tolerance(ε, 0.1 rad, 3 rad) + 0.6 near(ε, 0.3 rad))
· (0.5 + 0.5 near(φ' − φ*', 5 rad/s)) · (0.8 + 0.2 near((τ − τ*)/max_torque, 1))``
``near(x, m) = exp(ln(0.1) (x/m)²)``; ``tolerance(x, b, m)`` is 1 for |x| <= b and
``near(|x| − b, m)`` outside. At rest with τ* the reward falls strictly as |ε| grows: at
the band's edge it keeps 0.86 of the reward on the target, at twice the band 0.62.

## Starting state

At rest near the bottom: φ and φ' uniform in ±0.1 (rad, rad/s).

## Episode end

* Terminated: slip or lift-off during a step, or a step that could not stay finite.
* Truncated: 400 steps (20 s).
* ``info["is_success"]``: |ε| <= 0.1 rad and |φ'| <= 0.2 rad/s.

## Arguments

``gymnasium.make("roller_gym/RollerBalanceWeak-v0", scene=..., dt=..., max_torque=...,
tolerance=..., integrator=..., substeps=..., randomize=..., render_mode=...)``: see
:class:`roller_gym.roller_env.RollerEnv` (``max_torque=0.4`` gives RollerBalance).

## Version History

* v0: the first version.
"""

from __future__ import annotations

from roller_gym.balance import BalanceTask
from roller_gym.task import register

__all__ = ["BalanceWeakTask"]


@register
class BalanceWeakTask(BalanceTask):
    name = "RollerBalanceWeak"
    tier = "hard"
    version = 0
    default_max_torque = 0.1
    reward_threshold = 283.7  # the swing-up's mean return on seeds 10000–10099 (298.6) − 5 %
