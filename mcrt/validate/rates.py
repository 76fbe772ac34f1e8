"""Small statistics of a study: binomial rates and bounds, p-value uniformity, one trial's record."""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import numpy as np
from scipy import stats as _sps

from mcrt.stats import binomial_interval
from mcrt.validate.budget import LEVEL, P_BINS


def false_alarm_bound(n: int, alpha: float, level: float = 0.99) -> int:
    """Largest number of false alarms in ``n`` independent trials still consistent with level ``alpha``.

    The smallest k with P(K > k) <= 1 - level for K ~ Binomial(n, alpha): a
    correct renderer exceeds it with probability at most 1 - level. Example:
    n = 10, alpha = 0.01 gives 1 (P(K >= 2) = 0.43 %); n = 200 gives 6.
    """
    return int(_sps.binom.ppf(level, n, alpha))


def rate_row(hits: Iterable[bool]) -> dict[str, Any]:
    """Count, rate and Clopper-Pearson interval (at :data:`LEVEL`) of the true values in ``hits``."""
    hits = [bool(h) for h in hits]
    n, k = len(hits), int(sum(hits))
    lo, hi = binomial_interval(k, n, LEVEL) if n else (0.0, 1.0)
    return {"n": n, "k": k, "rate": k / n if n else float("nan"), "interval": [lo, hi]}


def uniformity(p: np.ndarray) -> dict[str, Any]:
    """Histogram, KS test and tail fractions of p-values that should be uniform on [0, 1]."""
    p = np.asarray(p, dtype=np.float64)
    out: dict[str, Any] = {"n": int(p.size)}
    if p.size == 0:
        return out
    counts, _ = np.histogram(p, bins=P_BINS, range=(0.0, 1.0))
    ks = _sps.kstest(p, "uniform")
    out.update(
        bins=P_BINS,
        counts=[int(c) for c in counts],
        ks_statistic=float(ks.statistic),
        ks_p=float(ks.pvalue),
        below={str(q): float(np.mean(p <= q)) for q in (0.05, 0.01, 0.001, 0.0001)},
    )
    return out


def null_max_t_quantiles(m: int, qs=(0.5, 0.9, 0.99)) -> dict[str, float]:
    """Quantiles of max |Z| over m independent standard normals: P(max < x) = (2 Phi(x) - 1)^m."""
    return {str(q): float(_sps.norm.isf((1 - q ** (1 / m)) / 2)) for q in qs}


def binomial_acceptance(n: int, alpha: float) -> list[int]:
    """The central 95 % range of Binomial(n, alpha)."""
    return [int(_sps.binom.ppf(0.025, n, alpha)), int(_sps.binom.isf(0.025, n, alpha))]


def trial(c, seed: int, opponent_seed: int | None) -> dict[str, Any]:
    """The record of one comparison ``c`` (a :class:`mcrt.stats.Comparison`) in a study's JSON."""
    m = c.max_abs_t
    t = abs(m.t)
    return {
        "seed": seed,
        "opponent_seed": opponent_seed,
        "rejected": not c.passed,
        "n_rejected": c.n_rejected,
        "max_abs_t": t if math.isfinite(t) else None,
        "max_abs_t_tile": [m.ty, m.tx, m.channel],
        "min_p": c.min_p,
        "min_p_adjusted": float(np.min(c.p_adjusted)),
        "global_rel_diff": [float(v) for v in c.global_rel_diff],
    }


def median_t(trials) -> float | None:
    """Median of max |t|; an unequal deterministic tile (|t| = inf) counts as larger than any finite t."""
    v = [float("inf") if tr["max_abs_t"] is None else tr["max_abs_t"] for tr in trials]
    if not v:
        return None
    m = float(np.median(v))
    return m if math.isfinite(m) else None
