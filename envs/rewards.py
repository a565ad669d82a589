"""The reward vocabulary: a few named terms, each bounded in [0, 1], written once.

As in dm_control's ``rewards.tolerance``: a term is 1 at its target and decays smoothly
(a Gaussian) to ``value_at_margin`` at distance ``margin`` from it. A task's reward is a
product of such terms, so it stays in [0, 1]. Each function takes floats (computed with
:mod:`math`, the single environment's fast path) or arrays (NumPy, the vector environment)
— the same formula either way, through :func:`xp`.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["near", "product", "tolerance", "wrap_angle", "xp"]

_LOG_VALUE_AT_MARGIN = math.log(0.1)


def xp(x):
    """The module that computes on ``x``: :mod:`math` for a Python float, else NumPy."""
    return math if type(x) is float else np


def near(x, margin, value_at_margin: float = 0.1):
    """exp(ln(value_at_margin)·(x/margin)²): 1 at x = 0, ``value_at_margin`` at |x| = margin."""
    scale = _LOG_VALUE_AT_MARGIN if value_at_margin == 0.1 else math.log(value_at_margin)
    t = x / margin
    return xp(x).exp(scale * (t * t))  # t * t: inf (term 0) where ** would overflow


def tolerance(x, bound, margin, value_at_margin: float = 0.1):
    """1 where |x| <= ``bound``; outside, :func:`near` of the distance to the bound, so
    ``value_at_margin`` at |x| = bound + margin (dm_control's ``tolerance`` with a
    Gaussian sigmoid): being anywhere inside the band pays fully, just outside it costs."""
    outside = xp(x).maximum(abs(x) - bound, 0.0) if type(x) is not float else max(
        abs(x) - bound, 0.0)
    return near(outside, margin, value_at_margin)


def product(*weighted_terms):
    """∏ (1 − w + w·term) over ``(term, w)`` pairs: each term pulls the reward down by at most w."""
    out = 1.0
    for term, weight in weighted_terms:
        out = out * (1.0 - weight + weight * term)
    return out


def wrap_angle(x):
    """x wrapped into [−π, π) [rad]."""
    return x - 2.0 * math.pi * xp(x).floor((x + math.pi) / (2.0 * math.pi))
