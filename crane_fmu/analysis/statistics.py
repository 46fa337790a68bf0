"""Statistics of a paired design: quantiles with bootstrap intervals, paired differences, the Wilcoxon test.

Every contender runs the same cases, so two contenders' figures pair up case by case. A figure that
was never reached (*never*: no arrival) counts as larger than every finite one (``inf``); two *never*
in the same case are equal.

- :func:`describe`: the median and the 90th percentile of a sample, each with its 95 % bootstrap
  confidence interval (scipy.stats.bootstrap's percentile method, bit for bit, a fixed seed: the same rows give
  the same board). A quantile is the smallest value with at least that share of the cases at or below it
  (numpy's ``inverted_cdf``): always a figure some case had, and *never* when more than that share
  of the cases never reached it.
- :func:`compare_paired`: the median paired difference with its bootstrap interval, and the two-sided
  Wilcoxon signed-rank test (scipy.stats.wilcoxon; cases with equal figures carry no evidence and
  are left out, as Wilcoxon did; no case left: p = 1).
- :data:`RULE`: two contenders differ where p < :data:`ALPHA`, the one whose figures rank lower
  (Wilcoxon's rank sums) being better; else they tie.
"""

import functools
import math
from collections import namedtuple

import numpy as np

ALPHA = 0.05
CONFIDENCE = 0.95
RESAMPLES = 9999
SEED = 20261201  # the bootstrap's draws: the same rows give the same intervals
QUANTILES = (0.5, 0.9)

Description = namedtuple("Description", "median median_low median_high p90 p90_low p90_high")
Description.__doc__ = "The median and the 90th percentile of a sample, each with its 95 % confidence interval."
Paired = namedtuple("Paired", "difference low high p better")
Paired.__doc__ = ("A paired comparison of a with b: the median of a - b with its 95 % interval, the Wilcoxon p-value, "
                  "and ``better``: -1 when a is significantly lower (better), 1 when b is, 0 a tie.")
RULE = (f"two contenders differ on the paired design where the two-sided Wilcoxon signed-rank test of their "
        f"paired figures gives p < {ALPHA:g} (cases with equal figures left out; *never* above every finite "
        f"figure), the one with the lower figures being better; otherwise they tie")


def _values(sample):
    return np.array([math.inf if v is None else float(v) for v in sample])


def _quantiles(x, axis=-1):
    """numpy's quantiles (``inverted_cdf``) of :data:`QUANTILES` along ``axis``: each is one of the values, the one
    np.quantile picks, found by np.partition (the same values; three times as fast on the bootstrap's resamples)."""
    x = np.moveaxis(np.asarray(x), axis, -1)
    ranks = _ranks(x.shape[-1])
    part = np.partition(x, ranks, axis=-1)
    return np.stack([part[..., k] for k in ranks])


@functools.cache
def _ranks(n):
    """The places in a sorted sample of ``n`` of the values np.quantile (``inverted_cdf``) gives: asked of it."""
    return [int(k) for k in np.quantile(np.arange(n), QUANTILES, method="inverted_cdf")]


def _finite_stand_ins(x):
    """``(y, back)``: ``x`` (along its last axis) with +-inf replaced by values beyond each row's finite ones, and
    the function that reads a bound nearer a stand-in than the finite values back as +-inf (and one off the
    finite range by rounding back onto it). The statistics here are order statistics, which such stand-ins leave
    in place; scipy's bootstrap needs finite values."""
    finite = np.isfinite(x)
    any_finite = finite.any(axis=-1, keepdims=True)
    top = np.where(any_finite, np.max(np.where(finite, x, -math.inf), axis=-1, keepdims=True), 0.0)
    bottom = np.where(any_finite, np.min(np.where(finite, x, math.inf), axis=-1, keepdims=True), 0.0)
    margin = np.maximum(1.0, top - bottom)
    y = np.where(x == math.inf, top + margin, np.where(x == -math.inf, bottom - margin, x))

    def back(bound):  # a bound of each row's statistic (the rows on its last axis; one row: any shape)
        t, b, m = ((v.reshape(()) if top.size == 1 else v[..., 0]) for v in (top, bottom, margin))
        return np.where(bound > t + m / 2, math.inf, np.where(bound < b - m / 2, -math.inf, np.clip(bound, b, t)))

    return y, back


def _interval(x, ranks):
    """Percentile bootstrap (that of scipy.stats.bootstrap, bit for bit) of the order statistics of places ``ranks``
    (0: the smallest) of the samples along the last axis of ``x``: ``(low, high)``, each of shape
    ``(len(ranks), *x.shape[:-1])``."""
    x = np.asarray(x, dtype=float)
    if np.all(x == x[..., :1]):  # one value in every sample: every resample gives it
        value = np.stack([np.sort(x, axis=-1)[..., k] for k in ranks])
        return value, value
    y, back = _finite_stand_ins(np.atleast_2d(x))
    low, high = bootstrap_order_statistics(y if x.ndim > 1 else y[0], ranks)
    return back(low), back(high)


def bootstrap_order_statistics(y, ranks, resamples=RESAMPLES, confidence=CONFIDENCE, seed=SEED):
    """``scipy.stats.bootstrap((y,), statistic, n_resamples=resamples, confidence_level=confidence,
    method="percentile", vectorized=True, axis=-1, rng=np.random.default_rng(seed)).confidence_interval`` for the
    statistic ``np.stack([np.partition(y, ranks, axis=-1)[..., k] for k in ranks])`` (the order statistics of places
    ``ranks`` of the samples along the last axis), bit for bit, six times as fast at the board's 64 cases.

    The same draws as scipy's (one ``(resamples, n)`` array of indices from the generator), but no resample is made
    or partitioned: each resample is how often it holds each case (a count per case), and its ``k``-th smallest value
    is the first in the sample's sorted order where those counts, summed in that order, exceed ``k``. Its interval is
    scipy's ``stats.quantile`` of the statistic's distribution, as scipy takes it.
    """
    from scipy import stats

    y = np.asarray(y, dtype=float)
    n = y.shape[-1]
    small, counts = _resample_counts(n, resamples, seed)
    rows = y.reshape(-1, n)
    theta = np.empty((len(ranks), len(rows), resamples))
    for m, row in enumerate(rows):
        order = np.argsort(row, kind="stable")
        summed = np.cumsum(counts[:, order], axis=1, dtype=small)
        for q, k in enumerate(ranks):
            theta[q, m] = row[order[np.argmax(summed > k, axis=1)]]
    theta = theta.reshape(len(ranks), *y.shape[:-1], resamples)
    alpha = np.asarray((1 - confidence) / 2, dtype=theta.dtype)
    bounds = stats.quantile(theta, np.stack((alpha, 1 - alpha), axis=-1), axis=-1)
    return bounds[..., 0], bounds[..., 1]


@functools.lru_cache(maxsize=4)
def _resample_counts(n, resamples, seed):
    """``(dtype, counts)``: how often each of ``resamples`` resamples (scipy's draws: one ``(resamples, n)`` array of
    indices from the generator of ``seed``) holds each of ``n`` cases, in the smallest type that holds n; drawn once
    for every statistic of a board (the same draws each time: read-only)."""
    draws = np.random.default_rng(seed).integers(0, n, (resamples, n))
    small = np.min_scalar_type(n)  # the counts summed along a resample reach n at most
    counts = np.bincount((np.arange(resamples)[:, None] * n + draws).ravel(), minlength=resamples * n)
    counts = counts.reshape(resamples, n).astype(small)
    counts.flags.writeable = False
    return small, counts


def describe_all(samples):
    """The :class:`Description` of each of ``samples`` (lists of the same cases; None: never), in one bootstrap."""
    x = np.array([_values(sample) for sample in samples])
    (median, p90), (low, high) = _quantiles(x), _interval(x, _ranks(x.shape[-1]))
    return [Description(float(median[i]), float(low[0][i]), float(high[0][i]), float(p90[i]), float(low[1][i]),
                        float(high[1][i])) for i in range(len(samples))]


def describe(sample):
    """The :class:`Description` of one sample (None: never; ``inf`` where a bound is never)."""
    return describe_all([sample])[0]


def differences(a, b):
    """``a - b`` case by case; two *never* (``inf``) are equal."""
    a, b = _values(a), _values(b)
    if len(a) != len(b):
        raise ValueError(f"paired samples must hold the same cases, got {len(a)} and {len(b)}")
    both = np.isinf(a) & np.isinf(b) & (a == b)
    return np.where(both, 0.0, a - np.where(both, 0.0, b))


def wilcoxon(a, b):
    """``(p, better)`` of the paired samples ``a`` and ``b``: the two-sided Wilcoxon signed-rank p-value over the
    cases whose figures differ (1 when none does) and the verdict of :data:`RULE` (-1: a better, 1: b, 0: a tie)."""
    from scipy import stats

    d = differences(a, b)
    nonzero = d[d != 0]
    if len(nonzero) == 0:
        return 1.0, 0
    p = float(stats.wilcoxon(nonzero, zero_method="wilcox", alternative="two-sided").pvalue)
    ranks = stats.rankdata(np.abs(nonzero))
    lower = ranks[nonzero < 0].sum() > ranks[nonzero > 0].sum()
    return p, ((-1 if lower else 1) if p < ALPHA else 0)


def _median(x, axis=-1):
    return np.quantile(x, 0.5, axis=axis, method="inverted_cdf")


def compare_paired(a, b):
    """The :class:`Paired` comparison of the paired samples ``a`` and ``b`` (the same cases in the same order)."""
    d = differences(a, b)
    (low,), (high,) = _interval(d, _ranks(len(d))[:1])  # the median: QUANTILES[0]
    p, better = wilcoxon(a, b)
    return Paired(float(_median(d)), float(low), float(high), p, better)
