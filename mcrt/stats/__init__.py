"""Statistical tests that decide whether renders and samplers are right.

One job per module:

* :mod:`mcrt.stats.tiles`: sums and means of an image over tiles (every
  pooled statistic goes through them);
* :mod:`mcrt.stats.twosample`: the two-sample Welch test of tile means,
  :func:`compare_images`, and its result :class:`Comparison`;
* :mod:`mcrt.stats.onesample`: the one-sample multi-scale tile test of an
  image against a reference's expected value under a noise model,
  :func:`~mcrt.stats.onesample.multiscale_test` (grading's bias test);
* :mod:`mcrt.stats.policy`: the comparison policy, :func:`compare` with
  ``policy='independent'`` or ``'reference-floor'`` (the variance floor,
  :func:`floor_variance`, against a high-spp reference);
* :mod:`mcrt.stats.multiple`: Holm, Bonferroni and Benjamini-Hochberg
  (:func:`adjust_p_values`, :func:`reject`), weighted Holm (:func:`adjust_p_values_weighted`);
* :mod:`mcrt.stats.goodness`: chi-square goodness of fit with pooling
  (:func:`chi2_gof`, for sampling routines);
* :mod:`mcrt.stats.interval`: the Clopper-Pearson interval
  (:func:`binomial_interval`, for false-alarm and detection rates);
* :mod:`mcrt.stats.errors`: :class:`StatsError`, :class:`ZeroPdfError`.

Reading image files, printing verdicts and writing heat maps and JSON
reports is :mod:`mcrt.compare`'s job; the pytest assertion is
:mod:`mcrt.pytest_plugin`'s.
"""

from mcrt.stats.errors import StatsError, ZeroPdfError
from mcrt.stats.goodness import chi2_gof
from mcrt.stats.interval import binomial_interval
from mcrt.stats.multiple import CORRECTIONS, adjust_p_values, adjust_p_values_weighted, reject
from mcrt.stats.policy import POLICIES, compare, floor_variance
from mcrt.stats.tiles import tile_box, tile_counts, tile_means, tile_sums
from mcrt.stats.twosample import LUMINANCE_WEIGHTS, Comparison, TileResult, compare_images

__all__ = [
    "StatsError",
    "ZeroPdfError",
    "LUMINANCE_WEIGHTS",
    "TileResult",
    "Comparison",
    "compare_images",
    "POLICIES",
    "compare",
    "floor_variance",
    "CORRECTIONS",
    "adjust_p_values",
    "adjust_p_values_weighted",
    "reject",
    "chi2_gof",
    "binomial_interval",
    "tile_sums",
    "tile_counts",
    "tile_means",
    "tile_box",
]
