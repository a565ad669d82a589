"""The reward vocabulary: a few named terms, each bounded in [0, 1], written once.

As in dm_control's ``rewards.tolerance``: a term is 1 at its target and decays smoothly
(a Gaussian) to ``value_at_margin`` at distance ``margin`` from it. A task's reward is a
product of such terms, so it stays in [0, 1]. Each function is plain arithmetic on NumPy's
ufuncs and :mod:`roller_gym.physics.trig`'s exp, so the same source serves a float, an array
(the tests, analyses) and, compiled by numba and inlined, the environments' per-step kernel
(:func:`roller_gym.episode.outcome`), whose loop over rollers then runs in SIMD lanes.
"""

from __future__ import annotations

import math

import numpy as np
from roller_gym.physics import trig
from roller_gym.physics.compiling import inlined

__all__ = ["blend", "near", "tolerance", "wrap_angle"]


@inlined
def near(x, margin, value_at_margin=0.1):
    """exp(ln(value_at_margin)·(x/margin)²): 1 at x = 0, ``value_at_margin`` at |x| = margin."""
    t = x / margin
    # t * t: inf (term 0) where ** would overflow; log(0.1) is folded where compiled
    return trig.exp(math.log(value_at_margin) * (t * t))


@inlined
def tolerance(x, bound, margin, value_at_margin=0.1):
    """1 where |x| <= ``bound``; outside, :func:`near` of the distance to the bound, so
    ``value_at_margin`` at |x| = bound + margin (dm_control's ``tolerance`` with a
    Gaussian sigmoid): being anywhere inside the band pays fully, just outside it costs."""
    return near(np.maximum(np.abs(x) - bound, 0.0), margin, value_at_margin)


@inlined
def blend(term, weight):
    """1 − w + w·term: a term that pulls the reward down by at most ``weight``."""
    return 1.0 - weight + weight * term


@inlined
def wrap_angle(x):
    """x wrapped into [−π, π) [rad]."""
    return x - 2.0 * math.pi * np.floor((x + math.pi) / (2.0 * math.pi))
