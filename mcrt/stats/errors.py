"""The errors of :mod:`mcrt.stats`: inputs that cannot be compared."""

from __future__ import annotations

__all__ = ["StatsError", "ZeroPdfError"]


class StatsError(ValueError):
    """Inputs that cannot be compared (missing variance, too few samples,
    mismatched shapes, non-finite values). The CLI maps it to exit code 2."""


class ZeroPdfError(StatsError):
    """Samples landed in bins whose expected count is zero (p = 0).

    A sample drawn where the pdf is zero is a bug in the sampler, not a
    statistical fluctuation; catch this class to tell it from unusable input.
    """
