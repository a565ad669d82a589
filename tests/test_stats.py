"""The statistics over training seeds (roller_gym.agents.stats) on input whose answer is known."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

stats = pytest.importorskip("roller_gym.agents.stats")


def test_iqm_is_the_mean_of_the_middle_half():
    rng = np.random.default_rng(0)
    x = rng.permutation(np.arange(1.0, 9.0)).reshape(4, 2)  # 1..8 in a random order
    assert stats.iqm(x) == pytest.approx(np.mean([3, 4, 5, 6]))
    outlier = np.array([1.0, 2.0, 3.0, 4.0, 1e9])  # one seed far off moves the IQM by little
    assert stats.iqm(outlier[:, None]) == pytest.approx(3.0)


@pytest.mark.parametrize("shape", [(5, 1), (5, 4), (7, 3), (3, 2), (10, 5)])
def test_iqm_of_a_batch_is_rliables_on_each_member(shape):
    from rliable import metrics

    batch = np.random.default_rng(sum(shape)).normal(size=(6, *shape))
    assert stats.iqm_batch(batch) == pytest.approx(
        [metrics.aggregate_iqm(b) for b in batch], rel=1e-12)


def _ordered_resamples(columns):
    """Every ordered resample of every column (runs drawn with replacement within each),
    enumerated directly: the exact bootstrap distribution with equal weights."""
    per = [list(itertools.product(range(len(c)), repeat=len(c))) for c in columns]
    for choice in itertools.product(*per):
        yield [np.asarray(c)[list(i)] for c, i in zip(columns, choice, strict=True)]


def test_exact_bootstrap_of_two_runs_by_hand():
    # resamples of (0, 1): (0, 0), (0, 1), (1, 0), (1, 1), means 0, 1/2, 1/2, 1, each 1/4:
    # the 2.5 % quantile is 0 and the 97.5 % one is 1
    assert stats.interval(np.array([0.0, 1.0]), statistic=lambda x: x.mean(axis=(1, 2))) == (
        0.5, 0.0, 1.0)


@pytest.mark.parametrize("runs", [4, 5, 6])
def test_exact_bootstrap_is_the_enumeration_of_every_ordered_resample(runs):
    scores = np.random.default_rng(runs).normal(size=runs)
    assert stats.is_exact([runs])
    values = [stats.iqm(r[0][:, None]) for r in _ordered_resamples([scores])]
    expected = np.quantile(values, [0.025, 0.975], method="inverted_cdf")
    est, lo, hi = stats.interval(scores)
    assert est == pytest.approx(stats.iqm(scores[:, None]))
    assert (lo, hi) == pytest.approx(tuple(expected), rel=1e-12)


def test_exact_bootstrap_resamples_within_each_task():
    scores = np.array([[0.0, 10.0], [1.0, 30.0], [5.0, 20.0]])  # 3 runs, 2 tasks
    values = [np.mean(np.column_stack(r)) for r in _ordered_resamples(list(scores.T))]
    expected = np.quantile(values, [0.025, 0.975], method="inverted_cdf")
    _, lo, hi = stats.interval(scores, statistic=lambda x: x.mean(axis=(1, 2)))
    assert (lo, hi) == pytest.approx(tuple(expected), rel=1e-12)


def test_random_bootstrap_where_resamples_are_many_agrees_with_rliables():
    from rliable import library as rly
    from rliable import metrics

    scores = np.random.default_rng(3).normal(size=(5, 3))
    assert not stats.is_exact([5, 5, 5])  # 126³ distinct resamples: drawn at random
    est, lo, hi = stats.interval(scores, reps=20_000)
    np.random.seed(0)  # rliable resamples with NumPy's global generator
    point, ci = rly.get_interval_estimates(
        {"a": scores}, lambda s: np.array([metrics.aggregate_iqm(s)]), reps=5_000)
    assert est == pytest.approx(point["a"][0], rel=1e-12)
    width = hi - lo
    assert lo == pytest.approx(ci["a"][0, 0], abs=0.05 * width)
    assert hi == pytest.approx(ci["a"][1, 0], abs=0.05 * width)


def test_intervals_are_degenerate_for_equal_runs_and_shift_with_the_scores():
    assert stats.interval(np.full((5, 3), 0.7)) == pytest.approx((0.7, 0.7, 0.7))
    scores = np.random.default_rng(1).normal(10.0, 2.0, size=(20, 2))
    est, lo, hi = stats.interval(scores)
    assert lo < est < hi
    shifted = stats.interval(scores + 5.0)  # the same resamples: the same interval, moved
    assert shifted == pytest.approx((est + 5.0, lo + 5.0, hi + 5.0), rel=1e-12)
    assert stats.interval(scores) == (est, lo, hi)  # reproducible: seeded resamples


def test_intervals_cover_the_mean_of_normal_samples_about_95_percent_of_the_time():
    rng = np.random.default_rng(2)
    hits = sum(lo <= 0.0 <= hi for lo, hi in (
        stats.interval(rng.normal(0.0, 1.0, (40, 1)), statistic=lambda x: x.mean(axis=(1, 2)),
                       seed=s, reps=500)[1:]
        for s in range(200)))
    assert 0.88 <= hits / 200 <= 0.99  # 95 % nominal; the percentile bootstrap is a bit short


def _pairs(x, y):
    """P(X > Y) on one task by counting the pairs (ties one half)."""
    return np.mean([1.0 if a > b else 0.5 if a == b else 0.0 for a in x for b in y])


def test_probability_of_improvement_is_mann_whitney_u_over_n_m():
    from scipy.stats import mannwhitneyu

    rng = np.random.default_rng(4)
    x, y = rng.integers(0, 4, size=(5, 3)).astype(float), rng.integers(0, 4, size=(4, 3))
    u = [mannwhitneyu(x[:, t], y[:, t]).statistic / (5 * 4) for t in range(3)]  # ties: 1/2
    assert stats.probability_of_improvement(x, y)[0] == pytest.approx(np.mean(u), rel=1e-12)
    assert stats.probability_of_improvement(x, y)[0] == pytest.approx(
        np.mean([_pairs(x[:, t], y[:, t]) for t in range(3)]), rel=1e-12)


def test_probability_of_improvement_interval_is_the_exact_one_on_a_task():
    x, y = np.array([1.0, 3.0, 2.0]), np.array([2.0, 0.5])
    values = [_pairs(a, b) for a, b in _ordered_resamples([x, y])]  # 27 x 4 resamples
    expected = np.quantile(values, [0.025, 0.975], method="inverted_cdf")
    est, lo, hi = stats.probability_of_improvement(x, y)
    assert est == pytest.approx(_pairs(x, y))
    assert (lo, hi) == pytest.approx(tuple(expected), rel=1e-12)


def test_probability_of_improvement():
    y = np.array([[1.0, 1.0]])  # one deterministic controller, two tasks
    assert stats.probability_of_improvement(np.full((5, 2), 2.0), y) == pytest.approx(
        (1.0, 1.0, 1.0))
    assert stats.probability_of_improvement(np.full((5, 2), 1.0), y)[0] == pytest.approx(0.5)
    # task 1: 3 of 4 runs above; task 2: 1 of 4 above: P = (0.75 + 0.25) / 2
    x = np.array([[2.0, 0.0], [2.0, 0.0], [2.0, 0.0], [0.0, 2.0]])
    assert stats.probability_of_improvement(x, y)[0] == pytest.approx(0.5)
    x = np.array([[2.0, 2.0], [2.0, 2.0], [2.0, 0.0], [0.0, 2.0]])
    assert stats.probability_of_improvement(x, y)[0] == pytest.approx(0.75)
    with pytest.raises(ValueError, match="same tasks"):
        stats.probability_of_improvement(x, np.ones((2, 3)))


def test_performance_profile_counts_runs_above_each_tau():
    out = stats.performance_profile({"a": np.array([[0.5, 1.5], [1.5, 2.5]])},
                                    np.array([0.0, 1.0, 2.0, 3.0]))
    assert out["a"]["profile"] == pytest.approx([1.0, 0.75, 0.25, 0.0])


@pytest.mark.parametrize(("means", "expected"), [
    ([1, 5, 6, 7], 200),  # crosses at 200 and stays
    ([5, 1, 6, 7], 300),  # crosses at 100, falls back, sustained from 300
    ([5, 6, 7, 4], float("inf")),  # above until the last evaluation: never sustained
    ([5, 5, 5, 5], 100),  # at the threshold from the start
    ([6, np.nan, 6, 6], 300),  # a failed evaluation counts as below
    ([1, 2, 3, 4], float("inf")),
])
def test_steps_to_threshold_is_the_sustained_crossing(means, expected):
    t = np.array([100, 200, 300, 400])
    returns = np.column_stack([np.array(means, float) - 1.0, np.array(means, float) + 1.0])
    assert stats.steps_to_threshold(t, returns, 5.0) == expected
