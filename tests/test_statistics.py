"""The paired design's statistics on made-up samples with known answers.

The answers are computed here without the code under test: quantiles by their definition, the exact
bootstrap distribution of an order statistic from the binomial distribution, the Wilcoxon p-value by
enumerating every assignment of signs to the ranks.
"""

import itertools
import math

import numpy as np
import pytest
from scipy.stats import binom

from crane_fmu.analysis import statistics

TEN = [3.0, 9.0, 1.0, 7.0, 5.0, 10.0, 2.0, 8.0, 4.0, 6.0]  # 1..10, unordered


def test_quantiles_are_figures_some_case_had():
    """The median of 1..10 is 5 (the smallest value with at least half the cases at or below it), the 90th
    percentile 9; with 4 of 13 cases *never*, the median is the 7th of 13 sorted values (7.0: 9 finite values
    below the four never) and the 90th percentile is never."""
    d = statistics.describe(TEN)
    assert (d.median, d.p90) == (5.0, 9.0)
    d = statistics.describe([1, 2, 3, None, None, None, 4, 5, 6, 7, 8, 9, None])
    assert (d.median, d.p90, d.p90_high) == (7.0, math.inf, math.inf)
    assert statistics.describe([None] * 5).median == math.inf
    assert statistics.describe([2.5] * 5) == (2.5,) * 6  # one value: the interval is that value


@pytest.mark.quick
def test_the_quantiles_are_numpys_inverted_cdf_ones():
    """The order statistics picked by np.partition are np.quantile's (inverted_cdf) on samples of every size from 1
    to 130, with ties and never, along the last axis of a batch of resamples as the bootstrap passes them."""
    rng = np.random.default_rng(48)
    for n in range(1, 131):
        x = rng.standard_normal((3, 5, n))
        x[0, 0, : n // 3] = math.inf
        x[1] = np.round(x[1])
        assert np.array_equal(statistics._quantiles(x), np.quantile(x, statistics.QUANTILES, axis=-1,
                                                                    method="inverted_cdf")), n


def _exact_bootstrap_bounds(n, k, confidence=0.95):
    """Order-statistic indices (1-based) of the percentile bootstrap interval of the k-th smallest of n distinct
    values: the k-th smallest of a resample is <= the j-th value when at least k of its n draws are among the
    j smallest, P = 1 - binom.cdf(k - 1, n, j / n)."""
    cdf = [1 - binom.cdf(k - 1, n, j / n) for j in range(1, n + 1)]
    tail = (1 - confidence) / 2
    low = next(j for j, p in enumerate(cdf, 1) if p >= tail)
    high = next(j for j, p in enumerate(cdf, 1) if p >= 1 - tail)
    return low, high


@pytest.mark.parametrize("n", [10, 16, 64])
def test_the_bootstrap_interval_of_a_quantile_is_the_exact_bootstrap_one(n):
    """The median (k = n/2) and the 90th percentile (k = ceil(0.9 n)) of 1..n: each bound is the order statistic
    the exact bootstrap distribution gives, within one (9999 resamples and the interpolation between them)."""
    values = np.random.default_rng(n).permutation(np.arange(1.0, n + 1))
    d = statistics.describe(values)
    for q, low, high in ((0.5, d.median_low, d.median_high), (0.9, d.p90_low, d.p90_high)):
        exact_low, exact_high = _exact_bootstrap_bounds(n, math.ceil(q * n))
        assert abs(low - exact_low) <= 1 and abs(high - exact_high) <= 1, (q, low, high, exact_low, exact_high)


def _exact_wilcoxon(d):
    """Two-sided p-value of the signed-rank statistic by enumerating all 2^n sign assignments (no ties, no zeros):
    2 min(P(W+ <= w), P(W+ >= w)), at most 1."""
    ranks = np.argsort(np.argsort(np.abs(d))) + 1
    observed = ranks[np.asarray(d) > 0].sum()
    sums = [sum(r for r, s in zip(ranks, signs) if s) for signs in itertools.product((0, 1), repeat=len(d))]
    below = sum(s <= observed for s in sums) / len(sums)
    above = sum(s >= observed for s in sums) / len(sums)
    return min(1.0, 2 * min(below, above))


@pytest.mark.parametrize("d", [
    [1.5, -0.5, 2.0, 3.0, -1.0, 4.0, 5.0, 6.0],
    [-0.1, -0.2, -0.3, 0.4, -0.5, -0.6, -0.7, -0.8, -0.9, -1.0, -1.1, -1.2],
    [1.0, -2.0, 3.0, -4.0, 5.0, -6.0],
])
def test_the_wilcoxon_p_value_is_the_exact_one(d):
    b = np.linspace(3.0, 4.0, len(d))
    assert statistics.compare_paired(b + np.array(d), b).p == pytest.approx(_exact_wilcoxon(d), rel=1e-9)


def test_cases_with_equal_figures_are_left_out():
    """Zeros in the differences (and two *never* in one case) change nothing of the test."""
    d = [1.5, -0.5, 2.0, 3.0, -1.0, 4.0, 5.0, 6.0]
    b = list(np.linspace(3.0, 4.0, 8))
    with_ties = statistics.compare_paired([x + y for x, y in zip(b, d)] + [1.0, 2.0, None], b + [1.0, 2.0, None])
    assert with_ties.p == pytest.approx(_exact_wilcoxon(d), rel=1e-9)


@pytest.mark.parametrize("a, b, better, p", [
    (TEN, [x + 1 + 0.01 * x for x in TEN], -1, 2 / 2 ** 10),  # lower in all 10 cases: p = 2 / 2^10
    ([x + 1 + 0.01 * x for x in TEN], TEN, 1, 2 / 2 ** 10),  # the other way round
    (TEN[:5], [x + 1 for x in TEN[:5]], 0, 2 / 2 ** 5),  # lower in all of 5 cases: 0.0625 is not significant
    (TEN, TEN, 0, 1.0),  # the same figures: a tie
    ([None] * 8, TEN[:8], 1, 2 / 2 ** 8),  # never against finite figures in every case
    ([1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0], [1.5, 1.5, 3.5, 3.5, 5.5, 5.5, 7.5, 7.5], 0, None),  # +-0.5: a tie
])
def test_the_rule_on_made_up_samples(a, b, better, p):
    result = statistics.compare_paired(a, b)
    assert result.better == better
    if p is not None:
        assert result.p == pytest.approx(p, rel=1e-9)
    assert (result.p < statistics.ALPHA) == (better != 0)


def test_the_paired_difference_and_its_interval():
    """The differences 1..10 (in any order): median 5, and the exact bootstrap interval of the 5th of 10."""
    result = statistics.compare_paired([x + 10 for x in TEN], [10.0] * 10)
    low, high = _exact_bootstrap_bounds(10, 5)
    assert result.difference == 5.0 and abs(result.low - low) <= 1 and abs(result.high - high) <= 1
    assert statistics.compare_paired([None, 1.0], [1.0, 1.0]).difference in (0.0, math.inf)


def test_the_intervals_of_finite_figures_are_finite_and_within_them():
    """A bound the bootstrap's interpolation puts a rounding error outside the sample stays on it."""
    sample = [4.403, 3.52, 3.561, 4.179, 3.674, 3.654]
    d = statistics.describe(sample)
    assert all(min(sample) <= v <= max(sample) for v in d)


@pytest.mark.parametrize("n", [2, 10, 64, 300])
def test_the_bootstrap_is_scipys_bit_for_bit(n):
    """Our bootstrap of order statistics (no resample made) gives scipy.stats.bootstrap's percentile interval of the
    same statistic with the same seed, bit for bit: the median and the 90th percentile of a batch of samples with
    ties, stand-ins for *never* and a constant one, and the median of one sample (the paired difference), at sizes
    whose counts take one byte (up to 255 cases) and two."""
    from scipy import stats

    rng = np.random.default_rng(n)
    batch = rng.standard_normal((4, n))
    batch[1] = np.round(batch[1])  # ties
    batch[2, : n // 3] = 1e9  # never's stand-ins above every figure
    batch[3] = 2.5
    ranks = statistics._ranks(n)

    def scipys(y, statistic):
        result = stats.bootstrap((y,), statistic, n_resamples=statistics.RESAMPLES, method="percentile",
                                 confidence_level=statistics.CONFIDENCE, vectorized=True, axis=-1,
                                 rng=np.random.default_rng(statistics.SEED))
        return result.confidence_interval.low, result.confidence_interval.high

    ours = statistics.bootstrap_order_statistics(batch, ranks)
    for mine, theirs in zip(ours, scipys(batch, statistics._quantiles)):
        assert mine.shape == theirs.shape == (2, 4) and np.array_equal(mine, theirs), (mine, theirs)
    low, high = statistics.bootstrap_order_statistics(batch[0], ranks[:1])
    assert np.array_equal(np.concatenate([low, high]), np.array(scipys(batch[0], statistics._median)))
