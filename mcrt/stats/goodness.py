"""Chi-square goodness of fit of binned samples against a pdf, with pooling of sparse bins."""

from __future__ import annotations

import numpy as np
from scipy import stats as _sps

from mcrt.stats.errors import StatsError, ZeroPdfError

__all__ = ["chi2_gof"]


def chi2_gof(observed_counts, expected_counts, *, min_expected: float = 5.0) -> tuple[float, int, float]:
    r"""Pearson chi-square goodness-of-fit test of binned samples against a pdf.

    .. math::

        X^2 = \sum_k \frac{(O_k - E_k)^2}{E_k}, \qquad
        p = P(\chi^2_{dof} \ge X^2),

    over the bins left after pooling. Bins whose expected count is below
    ``min_expected`` are merged into one pooled bin (the chi-square
    approximation needs E_k of at least about 5, as in Mitsuba's
    ``ChiSquareTest``); if the pooled bin's expectation is still below
    ``min_expected``, the regular bins with the smallest expectations are
    added to it until it reaches that level. Bins with E_k = 0 and O_k = 0
    carry no information and are dropped. ``dof`` = number of bins after
    pooling - 1. The expected counts are not rescaled: a pdf that does not
    integrate to one (sum E != sum O) is part of what the test detects.

    Parameters
    ----------
    observed_counts, expected_counts : array_like
        Counts per bin, same shape (any); expected counts are
        ``n_samples * integral of the pdf over the bin``.
    min_expected : float
        Pooling threshold.

    Returns
    -------
    statistic : float
    dof : int
    p_value : float

    Raises
    ------
    ZeroPdfError
        Some samples landed in bins with zero expected count (p = 0: a
        sample where the pdf is zero is a bug).
    StatsError
        Shapes differ, negative or non-finite counts, or fewer than two bins
        remain after pooling.
    """
    obs = np.asarray(observed_counts, dtype=np.float64)
    exp = np.asarray(expected_counts, dtype=np.float64)
    if obs.shape != exp.shape:
        raise StatsError(f"observed counts have shape {obs.shape}, expected counts {exp.shape}")
    obs, exp = obs.ravel(), exp.ravel()
    if not (np.all(np.isfinite(obs)) and np.all(np.isfinite(exp))):
        raise StatsError("counts must be finite")
    if np.any(obs < 0) or np.any(exp < 0):
        raise StatsError("counts must be non-negative")
    zero_hit = (exp == 0) & (obs > 0)
    if np.any(zero_hit):
        where = np.flatnonzero(zero_hit)
        shown = ", ".join(str(int(i)) for i in where[:10]) + (", ..." if where.size > 10 else "")
        raise ZeroPdfError(
            f"p = 0: {obs[zero_hit].sum():g} samples fell in {where.size} bins of zero expected count "
            f"(flat bin indices {shown}); a sample where the pdf is 0 is a bug"
        )
    keep = exp > 0
    obs, exp = obs[keep], exp[keep]
    order = np.argsort(exp, kind="stable")
    obs, exp = obs[order], exp[order]
    # Ascending expectations: the low bins form a prefix; extend it until the
    # pooled expectation reaches min_expected.
    n_low = int(np.searchsorted(exp, min_expected, side="left"))
    if n_low > 0:
        csum = np.cumsum(exp)
        n_pool = max(n_low, int(np.searchsorted(csum, min_expected, side="left")) + 1)
        n_pool = min(n_pool, exp.size)
        pooled_o, pooled_e = obs[:n_pool].sum(), exp[:n_pool].sum()
        obs = np.concatenate([[pooled_o], obs[n_pool:]])
        exp = np.concatenate([[pooled_e], exp[n_pool:]])
    if exp.size < 2:
        raise StatsError(f"only {exp.size} bin left after pooling at min_expected={min_expected:g}; use more samples")
    stat = float(np.sum((obs - exp) ** 2 / exp))
    dof = int(exp.size - 1)
    return stat, dof, float(_sps.chi2.sf(stat, dof))
