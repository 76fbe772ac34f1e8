"""Confidence interval of a binomial proportion (false-alarm and detection rates)."""

from __future__ import annotations

from scipy import stats as _sps

__all__ = ["binomial_interval"]


def binomial_interval(k: int, n: int, level: float = 0.95) -> tuple[float, float]:
    r"""Clopper-Pearson (exact) confidence interval for a binomial proportion.

    With a = 1 - level:

    .. math::

        lo = B^{-1}(a/2;\ k,\ n - k + 1), \qquad
        hi = B^{-1}(1 - a/2;\ k + 1,\ n - k),

    where B^{-1} is the beta quantile (scipy.stats.beta.ppf), lo = 0 for
    k = 0 and hi = 1 for k = n. Example: k = 0, n = 10 gives
    (0, 0.3085) at 95 %.

    Parameters
    ----------
    k : int
        Number of successes (for example false alarms), 0 <= k <= n.
    n : int
        Number of trials, n >= 1.
    level : float
        Confidence level in (0, 1).
    """
    if n < 1 or not 0 <= k <= n:
        raise ValueError(f"need 0 <= k <= n and n >= 1, got k={k}, n={n}")
    if not 0 < level < 1:
        raise ValueError(f"level must be in (0, 1), got {level}")
    a = 1.0 - level
    lo = 0.0 if k == 0 else float(_sps.beta.ppf(a / 2, k, n - k + 1))
    hi = 1.0 if k == n else float(_sps.beta.ppf(1 - a / 2, k + 1, n - k))
    return lo, hi
