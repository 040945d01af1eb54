"""The statistics of multi-seed results, as the field reports them (Agarwal et al. 2021, "Deep RL at the edge of the
statistical precipice", the ``rliable`` library): the interquartile mean (IQM) of per-run scores and its percentile
bootstrap confidence interval over runs.

The IQM is the interquartile mean of runs (``scipy.stats.trim_mean(x, 0.25)``: ``int(0.25 n)`` dropped at each end,
so the middle 6 of 10 runs), and its interval is the percentile bootstrap over runs. With one task, rliable's
stratified bootstrap *is* this plain bootstrap over runs; it is written here in numpy rather than pulling in rliable,
whose pinned ``arch`` dependency is heavy, for the 15 lines it would save. The bootstrap's generator is seeded, so a
summary is reproducible. Used by the seed runner's summaries (:mod:`chopperscape.learn.summary`) and
ChopperScape-Bench's report.
"""

from __future__ import annotations

import numpy as np

#: Bootstrap resamples (rliable's default).
RESAMPLES = 50_000


def iqm(x: np.ndarray, axis: int = -1) -> np.ndarray:
    """Interquartile mean along `axis` (``scipy.stats.trim_mean(x, 0.25)``): the lowest and highest ``int(0.25 n)`` of
    the ``n`` values dropped, the rest averaged (the middle 6 of 10).

    >>> float(iqm(np.array([0.0, 10.0, 20.0, 30.0, 1000.0, -1000.0, 40.0, 50.0])))
    25.0
    """
    x = np.sort(np.asarray(x, dtype=np.float64), axis=axis)
    n = x.shape[axis]
    cut = int(0.25 * n)
    return np.take(x, np.arange(cut, n - cut), axis=axis).mean(axis=axis)


def bootstrap_ci(
    x: np.ndarray, stat=iqm, resamples: int = RESAMPLES, level: float = 0.95, seed: int = 0
) -> tuple[float, float]:
    """Percentile bootstrap interval of `stat` over runs (the last axis of `x` is the runs; earlier axes, such as
    points of a curve, are resampled together).

    >>> lo, hi = bootstrap_ci(np.array([5000.0, 6000.0, 6500.0, 7000.0]), resamples=2000)
    >>> bool(5000 <= lo <= hi <= 7000)
    True
    """
    x = np.asarray(x, dtype=np.float64)
    n = x.shape[-1]
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, n, size=(resamples, n))
    stats = stat(x[..., idx], axis=-1)  # (..., resamples)
    lo, hi = np.percentile(stats, [50 * (1 - level), 50 * (1 + level)], axis=-1)
    return lo, hi
