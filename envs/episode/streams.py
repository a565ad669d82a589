"""Counter-based random streams: every random draw of an episode start is a pure function.

``uniform(seed, episode, draw)`` is SplitMix64's mixing function applied to a counter that
combines the sub-environment's seed, the number of the episode since that seed was set, and
the draw's fixed index (as counter-based generators such as Philox or Squares do): each triple
gives an independent 53-bit uniform in [0, 1). So sub-environment i of a vector env seeded
``s`` makes exactly the draws of a single env seeded ``s + i``, and a batch of episode starts
is a handful of array operations, with no generator object per sub-environment.
"""

from __future__ import annotations

import numba
import numpy as np
from numba.extending import register_jitable

__all__ = ["random_seed", "uniform"]

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)


@register_jitable
def _mix(x):
    """SplitMix64's finalizer on uint64 (wrapping arithmetic)."""
    x = (x ^ (x >> np.uint64(30))) * _M1
    x = (x ^ (x >> np.uint64(27))) * _M2
    return x ^ (x >> np.uint64(31))


@numba.vectorize(["float64(uint64, uint64, uint64)"], cache=True, nopython=True)
def _uniform(seed, episode, draw):
    """The uniform of one (seed, episode, draw): a NumPy ufunc, so it broadcasts."""
    s = _mix(seed + _GOLDEN)
    x = _mix(s + episode * _GOLDEN)
    x = _mix(x + (draw + np.uint64(1)) * _M1)
    return np.float64(x >> np.uint64(11)) * 2.0**-53


def uniform(seed: np.ndarray, episode: np.ndarray, draw: np.ndarray | int) -> np.ndarray:
    """Uniforms in [0, 1): one per element of the broadcast (seed, episode, draw), a
    counter-based stream (SplitMix64's finalizer, compiled)."""
    return _uniform(np.asarray(seed, dtype=np.uint64), np.asarray(episode, dtype=np.uint64),
                    np.asarray(draw, dtype=np.uint64))


def random_seed() -> int:
    """A fresh seed from the operating system's entropy (for ``reset()`` with no seed)."""
    return int(np.random.SeedSequence().generate_state(1, np.uint64)[0] >> np.uint64(1))

