"""Statistics over training seeds, as rliable recommends (Agarwal et al., 2021, "Deep
Reinforcement Learning at the Edge of the Statistical Precipice").

A *score matrix* has one row per training run (seed) and one column per task. Every estimate
comes with a 95 % stratified-bootstrap confidence interval (percentile method): the runs are
resampled with replacement within each task, as rliable's ``StratifiedBootstrap`` does.

* **Exact where the seeds are few.** A stratum of n runs has C(2n − 1, n) distinct resamples
  (multisets), each drawn with probability n! / (∏ c_i! · nⁿ) (c_i: how often run i is in
  it). Where the product of these counts over the strata is at most :data:`REPS`, every
  resample is enumerated with its probability: the exact bootstrap distribution (5 seeds on
  one task: 126 resamples; two algorithms of 5 seeds on one task: 126² = 15,876). Otherwise
  :data:`REPS` = 50,000 resamples are drawn at random (rliable's default), seeded.
* The interval's ends are the inverted-CDF quantiles of that distribution (the smallest value
  whose cumulative probability reaches 2.5 % and 97.5 %), as
  ``numpy.quantile(..., method="inverted_cdf")`` of every resample.
* IQM: the interquartile mean, rliable's ``aggregate_iqm`` (scipy's ``trim_mean`` cutting
  25 % each side of all entries); robust to one outlying seed, more efficient than the median.
* Probability of improvement P(X > Y): rliable's, the Mann–Whitney U statistic / (n·m) per
  task (ties count one half), averaged over tasks; its interval resamples X's and Y's runs
  independently within each task (rliable's ``StratifiedIndependentBootstrap``).

The functions take plain arrays and return plain numbers, so that a results file can hold
them and a test can check them on input whose answer is known. The statistics are computed on
every resample at once (arrays of resamples × runs × tasks): a page's intervals take seconds.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Mapping, Sequence
from fractions import Fraction

import numpy as np
from rliable import metrics

__all__ = [
    "CONFIDENCE",
    "REPS",
    "Interval",
    "bootstrap",
    "interval",
    "iqm",
    "iqm_batch",
    "is_exact",
    "median_batch",
    "performance_profile",
    "probability_of_improvement",
    "steps_to_threshold",
]

#: Random resamples where the exact bootstrap would need more (rliable's default, 50,000);
#: also the most distinct resamples the exact bootstrap enumerates.
REPS = 50_000
#: Coverage of the intervals.
CONFIDENCE = 0.95

Interval = tuple[float, float, float]  # (estimate, lower, upper)
#: A statistic of a batch of resampled score matrices: (K, runs, tasks) -> (K,) or (K, d).
Batch = Callable[[np.ndarray], np.ndarray]


def iqm_batch(x: np.ndarray) -> np.ndarray:
    """The interquartile mean of each ``x[k]`` over all its entries, as scipy's
    ``trim_mean(x[k], 0.25, axis=None)`` (rliable's ``aggregate_iqm``): int(N/4) entries cut
    at each end of the N sorted ones."""
    flat = np.sort(np.asarray(x, dtype=float).reshape(len(x), -1), axis=1)
    cut = int(0.25 * flat.shape[1])
    return flat[:, cut:flat.shape[1] - cut].mean(axis=1)


def median_batch(x: np.ndarray) -> np.ndarray:
    """The median of each ``x[k]`` over all its entries (inf allowed: a run that never did)."""
    return np.median(np.asarray(x, dtype=float).reshape(len(x), -1), axis=1)


def iqm(scores: np.ndarray) -> float:
    """The interquartile mean of all entries of ``scores`` (runs × tasks): rliable's."""
    return float(metrics.aggregate_iqm(np.asarray(scores, dtype=float)))


def _multisets(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Every distinct resample of n runs (indices, sorted) and how many of the nⁿ ordered
    resamples it stands for (n! / ∏ c_i!)."""
    idx = np.array(list(itertools.combinations_with_replacement(range(n), n)), dtype=np.intp)
    counts = np.apply_along_axis(np.bincount, 1, idx, minlength=n)
    mult = np.array([math.factorial(n) // math.prod(math.factorial(c) for c in row)
                     for row in counts], dtype=np.int64)
    return idx.reshape(-1, n), mult


def is_exact(sizes: Sequence[int], reps: int = REPS) -> bool:
    """Whether strata of these run counts get the exact bootstrap: their distinct resamples,
    ∏ C(2n − 1, n), number at most ``reps``."""
    return math.prod(math.comb(2 * n - 1, n) for n in sizes) <= reps


def _resamples(sizes: Sequence[int], seed: int, reps: int
               ) -> tuple[list[np.ndarray], np.ndarray]:
    """Row indices into each stratum for every resample, and the resamples' weights
    (integers: multiplicities for the exact bootstrap, ones for the random one)."""
    if is_exact(sizes, reps):
        per = [_multisets(n) for n in sizes]
        grid = np.indices([len(m) for _, m in per]).reshape(len(per), -1)
        weights = np.ones(grid.shape[1], dtype=np.int64)
        for (_, mult), g in zip(per, grid, strict=True):
            weights = weights * mult[g]
        return [idx[g] for (idx, _), g in zip(per, grid, strict=True)], weights
    rng = np.random.default_rng(seed)
    return [rng.integers(0, n, size=(reps, n)) for n in sizes], np.ones(reps, dtype=np.int64)


def _quantile(values: np.ndarray, weights: np.ndarray, q: Fraction) -> np.ndarray:
    """The smallest value (per column) whose cumulative weight reaches q of the total, in
    integer arithmetic (no rounding at the quantile's edge)."""
    order = np.argsort(values, axis=0, kind="stable")
    cum = np.cumsum(weights[order], axis=0)
    total = int(weights.sum())
    first = np.argmax(cum * q.denominator >= total * q.numerator, axis=0)
    return np.take_along_axis(values, order, axis=0)[first, np.arange(values.shape[1])]


def bootstrap(strata: Sequence[np.ndarray], statistic: Callable[[list[np.ndarray]], np.ndarray],
              seed: int = 0, reps: int = REPS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A statistic of the strata (1-D arrays of runs) and its percentile interval.

    ``statistic`` maps a list of resampled strata, each (K, n_i), to (K,) or (K, d); it is
    called once on the data (K = 1) and once on every resample. Exact where
    :func:`is_exact`, else ``reps`` random resamples seeded by ``seed``. Returns the
    estimate, the lower and the upper ends, each of shape (d,) (d = 1 for a scalar)."""
    strata = [np.asarray(s, dtype=float) for s in strata]
    point = np.asarray(statistic([s[None, :] for s in strata]), dtype=float).reshape(1, -1)
    idx, weights = _resamples([len(s) for s in strata], seed, reps)
    values = np.asarray(statistic([s[i] for s, i in zip(strata, idx, strict=True)]),
                        dtype=float).reshape(len(weights), -1)
    tail = (1 - Fraction(str(CONFIDENCE))) / 2
    return point[0], _quantile(values, weights, tail), _quantile(values, weights, 1 - tail)


def _matrix(scores: np.ndarray) -> np.ndarray:
    scores = np.asarray(scores, dtype=float)
    return scores[:, None] if scores.ndim == 1 else scores


def _stacked(resampled: list[np.ndarray]) -> np.ndarray:
    """Resampled task columns, each (K, runs), as (K, runs, tasks)."""
    return np.stack(resampled, axis=-1)


def interval(scores: np.ndarray, statistic: Batch = iqm_batch, seed: int = 0,
             reps: int = REPS) -> Interval:
    """``statistic`` of the score matrix (runs × tasks; a 1-D array is one task) and its
    95 % stratified-bootstrap interval (the runs resampled within each task)."""
    scores = _matrix(scores)
    est, lo, hi = bootstrap(list(scores.T), lambda r: statistic(_stacked(r)), seed, reps)
    return float(est[0]), float(lo[0]), float(hi[0])


def performance_profile(scores: Mapping[str, np.ndarray], taus: np.ndarray, seed: int = 0,
                        reps: int = REPS) -> dict[str, dict[str, list[float]]]:
    """For each algorithm, the share of runs (over all tasks) whose score exceeds each τ of
    ``taus``, with its 95 % interval: ``{algo: {"profile", "lower", "upper"}}``."""
    taus = np.asarray(taus, dtype=float)
    out = {}
    for algo, s in scores.items():
        est, lo, hi = bootstrap(
            list(_matrix(s).T), lambda r: (_stacked(r).reshape(len(r[0]), -1)[:, :, None]
                                           > taus).mean(axis=1), seed, reps)
        out[algo] = {"profile": est.tolist(), "lower": lo.tolist(), "upper": hi.tolist()}
    return out


def _poi_batch(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """P(X > Y) of each resample: x (K, n, tasks), y (K, m, tasks) -> (K,)."""
    gt = (x[:, :, None, :] > y[:, None, :, :]).mean(axis=(1, 2))
    eq = (x[:, :, None, :] == y[:, None, :, :]).mean(axis=(1, 2))
    return (gt + 0.5 * eq).mean(axis=-1)


def probability_of_improvement(x: np.ndarray, y: np.ndarray, seed: int = 0,
                               reps: int = REPS) -> Interval:
    """P(X > Y): the probability that a run of X scores above a run of Y on a task drawn at
    random (ties count one half), averaged over tasks; with its 95 % interval. ``x`` and
    ``y`` are score matrices (runs × tasks; 1-D: one task) with the same tasks; the run
    counts may differ."""
    x, y = _matrix(x), _matrix(y)
    if x.shape[1] != y.shape[1]:
        raise ValueError(f"x and y: {x.shape[1]} and {y.shape[1]} tasks (columns); they must "
                         "have the same tasks")
    tasks = x.shape[1]
    _, lo, hi = bootstrap([*x.T, *y.T], lambda r: _poi_batch(_stacked(r[:tasks]),
                                                             _stacked(r[tasks:])), seed, reps)
    return float(metrics.probability_of_improvement(x, y)), float(lo[0]), float(hi[0])


def steps_to_threshold(timesteps: np.ndarray, returns: np.ndarray, threshold: float) -> float:
    """The *sustained* crossing: the training step of the first periodic evaluation from which
    on every evaluation's mean return is at or above ``threshold``; inf if the last one is
    below it (the run never sustained it). ``returns``: one row per evaluation (its
    episodes)."""
    timesteps = np.asarray(timesteps)
    means = np.asarray(returns, dtype=float).reshape(len(timesteps), -1).mean(axis=1)
    below = np.flatnonzero(~(means >= threshold))  # NaN counts as below
    start = below[-1] + 1 if below.size else 0
    return float(timesteps[start]) if start < len(timesteps) else float("inf")
