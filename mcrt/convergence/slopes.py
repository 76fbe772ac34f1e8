"""The log-log slope fit of the convergence report.

A metric that falls as spp^s (or time^s) is a straight line in log-log
axes: :func:`fit_slope` is ordinary least squares of log(metric) against
log(spp) (or log(time)) over every render (each seed a point), with a
confidence interval from Student's t on n - 2 degrees of freedom. An
unbiased estimator's RMSE falls as spp^-1/2, its relMSE as spp^-1.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np


@dataclass(frozen=True)
class SlopeFit:
    """log(y) = intercept + slope log(x), with a ``level`` (default 95 %) confidence interval on the slope."""

    slope: float
    intercept: float
    stderr: float
    ci_low: float
    ci_high: float
    n: int
    level: float = 0.95

    def contains(self, value: float) -> bool:
        return self.ci_low <= value <= self.ci_high

    def predict(self, x) -> np.ndarray:
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            return np.exp(self.intercept + self.slope * np.log(np.asarray(x, dtype=np.float64)))

    def to_dict(self) -> dict:
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in asdict(self).items()}


def fit_slope(x, y, *, level: float = 0.95) -> SlopeFit:
    """Least-squares line through (log x, log y), with a ``level`` confidence interval on its slope.

    Points with non-positive or non-finite x or y are dropped. With fewer than
    three points left the interval is infinite (n - 2 = 0 degrees of freedom
    leave no estimate of the scatter); with fewer than two the fit is NaN.
    """
    from scipy import stats

    x = np.asarray(x, dtype=np.float64).ravel()
    y = np.asarray(y, dtype=np.float64).ravel()
    if x.shape != y.shape:
        raise ValueError(f"fit_slope: x has {x.size} values, y has {y.size}")
    ok = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0)
    lx, ly = np.log(x[ok]), np.log(y[ok])
    n = int(lx.size)
    nan = float("nan")
    if n < 2 or np.ptp(lx) == 0:
        return SlopeFit(nan, nan, nan, nan, nan, n, level)
    xm, ym = lx.mean(), ly.mean()
    sxx = float(np.sum((lx - xm) ** 2))
    slope = float(np.sum((lx - xm) * (ly - ym)) / sxx)
    intercept = float(ym - slope * xm)
    if n < 3:
        return SlopeFit(slope, intercept, float("inf"), -float("inf"), float("inf"), n, level)
    resid = ly - (intercept + slope * lx)
    s2 = float(np.sum(resid**2)) / (n - 2)
    se = math.sqrt(s2 / sxx)
    t = float(stats.t.ppf(0.5 + level / 2, n - 2))
    return SlopeFit(slope, intercept, se, slope - t * se, slope + t * se, n, level)
