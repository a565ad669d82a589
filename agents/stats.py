"""Statistics over training seeds, with rliable (Agarwal et al., 2021, "Deep Reinforcement
Learning at the Edge of the Statistical Precipice").

A *score matrix* has one row per training run (seed) and one column per task. Every estimate
comes with a 95 % stratified-bootstrap confidence interval (the runs are resampled within each
task). The interquartile mean (IQM) is the mean of the middle half of the scores: robust to
one outlying seed, and more efficient than the median.

The functions take plain arrays and return plain numbers, so that a results file can hold
them and a test can check them on input whose answer is known.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator, Mapping

import numpy as np
from rliable import library as rly
from rliable import metrics

__all__ = [
    "Interval",
    "interval",
    "iqm",
    "performance_profile",
    "probability_of_improvement",
    "steps_to_threshold",
]

#: Bootstrap resamples (rliable's examples use 50,000 for papers; 2,000 keeps a run short and
#: the interval's ends stable to about 1 % of its width).
REPS = 2000
#: Coverage of the intervals.
CONFIDENCE = 0.95

Interval = tuple[float, float, float]  # (estimate, lower, upper)


@contextlib.contextmanager
def _seeded(seed: int) -> Iterator[None]:
    """NumPy's global generator seeded within, restored after: rliable's bootstrap resamples
    with ``np.random.choice`` (its ``random_state`` does not reach the resampling)."""
    state = np.random.get_state()
    np.random.seed(seed)
    try:
        yield
    finally:
        np.random.set_state(state)


def iqm(scores: np.ndarray) -> float:
    """The interquartile mean of all entries of ``scores`` (runs × tasks)."""
    return float(metrics.aggregate_iqm(np.asarray(scores, dtype=float)))


def interval(scores: np.ndarray, statistic: Callable[[np.ndarray], float] = iqm,
             seed: int = 0, reps: int = REPS) -> Interval:
    """``statistic`` of the score matrix (runs × tasks) and its 95 % stratified-bootstrap
    confidence interval (percentile method)."""
    scores = np.asarray(scores, dtype=float)
    if scores.ndim == 1:
        scores = scores[:, None]
    with _seeded(seed):
        point, ci = rly.get_interval_estimates(
            {"x": scores}, lambda s: np.array([statistic(s)]), reps=reps,
            confidence_interval_size=CONFIDENCE)
    return float(point["x"][0]), float(ci["x"][0, 0]), float(ci["x"][1, 0])


def performance_profile(scores: Mapping[str, np.ndarray], taus: np.ndarray, seed: int = 0,
                        reps: int = REPS) -> dict[str, dict[str, list[float]]]:
    """For each algorithm, the share of runs (over all tasks) whose score exceeds each τ of
    ``taus``, with its 95 % interval: ``{algo: {"profile", "lower", "upper"}}``."""
    with _seeded(seed):
        profile, ci = rly.create_performance_profile(
            {k: np.asarray(v, dtype=float) for k, v in scores.items()}, np.asarray(taus),
            reps=reps, confidence_interval_size=CONFIDENCE)
    return {k: {"profile": profile[k].tolist(), "lower": ci[k][0].tolist(),
                "upper": ci[k][1].tolist()} for k in profile}


def probability_of_improvement(x: np.ndarray, y: np.ndarray, seed: int = 0,
                               reps: int = REPS) -> Interval:
    """P(X > Y): the probability that a run of X scores above a run of Y on a task drawn at
    random (ties count one half), averaged over tasks; with its 95 % interval. ``x`` and
    ``y`` are score matrices (runs × tasks) with the same tasks; the run counts may differ."""
    x, y = np.atleast_2d(np.asarray(x, dtype=float)), np.atleast_2d(np.asarray(y, dtype=float))
    with _seeded(seed):
        point, ci = rly.get_interval_estimates(
            {"pair": (x, y)}, lambda a, b: np.array([metrics.probability_of_improvement(a, b)]),
            reps=reps, confidence_interval_size=CONFIDENCE)
    return float(point["pair"][0]), float(ci["pair"][0, 0]), float(ci["pair"][1, 0])


def steps_to_threshold(timesteps: np.ndarray, returns: np.ndarray, threshold: float) -> float:
    """The first training step at which the periodic evaluation's mean return reached
    ``threshold``; inf if it never did. ``returns``: one row per evaluation (its episodes)."""
    means = np.asarray(returns, dtype=float).reshape(len(timesteps), -1).mean(axis=1)
    reached = np.flatnonzero(means >= threshold)
    return float(timesteps[reached[0]]) if reached.size else float("inf")
