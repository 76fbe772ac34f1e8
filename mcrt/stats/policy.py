r"""The comparison policy: which per-sample variance each side of a comparison brings.

The Welch tile test (:func:`mcrt.stats.twosample.compare_images`) divides the
difference of two tile means by the standard error built from each side's
*estimated* per-sample variance. Which estimate is fair depends on what the
two images are, so every comparison names a policy:

``'independent'`` (the default)
    Two independent renders, each with its own per-sample variance and
    sample count, as given: two renderers (an NEE tracer against an MIS path
    tracer), two seeds, two sample counts of the same order. The estimators
    may differ, so neither side's variance says anything about the other's.

``'reference-floor'``
    A render (A, the image under test) against a high-spp reference (B) of
    the *same estimator*, such as a committed Mitsuba reference. A's
    per-sample variance is raised to B's wherever it is lower
    (:func:`floor_variance`):

    .. math::

        \sigma^2_{A,i} \leftarrow \max(\sigma^2_{A,i},\ \sigma^2_{B,i}).

    Why: under "same image" both sides sample one distribution per pixel and
    share one per-sample variance :math:`\sigma^2_i`. With heavy-tailed
    samples (fireflies, caustics) a low-spp render usually misses the rare
    high-weight paths, so its mean *and* its variance estimate come out low
    together. Against a reference with :math:`n_B \gg n_A` the standard error
    is dominated by :math:`\sigma^2_{A,i}/n_A`, so an underestimated
    :math:`\sigma^2_{A,i}` inflates :math:`|t|` exactly where the mean is
    low, and correct renders are rejected. The reference's estimate, from
    many samples, is the better one of the shared variance; taking the larger
    of the two only widens the standard error (the test loses a little power,
    never validity). Do not use it between different estimators (their
    variances differ under the null too) or between two low-spp renders
    (neither estimate is the better one).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from mcrt.film import RenderResult
from mcrt.stats.errors import StatsError
from mcrt.stats.twosample import EXACT_RTOL, Comparison, compare_images

__all__ = ["POLICIES", "compare", "floor_variance"]

#: Policy name -> what it does to the inputs (one line, printed by ``mcrt compare``).
POLICIES = {
    "independent": "each image keeps its own per-sample variance",
    "reference-floor": "image A's per-sample variance is raised to image B's where lower "
                       "(B is a high-spp reference of the same estimator)",
}


def floor_variance(tested: RenderResult, reference: RenderResult) -> RenderResult:
    r"""``tested`` with each pixel's per-sample variance raised to the reference's where lower.

    :math:`\sigma^2_{tested,i} \leftarrow \max(\sigma^2_{tested,i}, \sigma^2_{reference,i})`,
    per pixel and channel; mean and spp are unchanged. This is the rule of
    the ``'reference-floor'`` policy (see the module docstring for when it
    applies); compare through :func:`compare` rather than calling it by hand.

    Raises
    ------
    StatsError
        Either render lacks its per-sample variance, or their shapes differ.
    """
    if tested.variance is None or reference.variance is None:
        raise StatsError("a variance floor needs both renders' per-sample variance")
    if tested.variance.shape != reference.variance.shape:
        raise StatsError(f"images differ in shape: tested {tested.variance.shape}, reference {reference.variance.shape}")
    return replace(tested, variance=np.maximum(tested.variance, reference.variance))


def compare(
    image_test: RenderResult,
    image_ref: RenderResult,
    *,
    policy: str = "independent",
    alpha: float = 0.01,
    tile: int = 8,
    channels: str = "rgb",
    correction: str = "holm",
    min_spp: int = 2,
    rtol: float | tuple[float, ...] = EXACT_RTOL,
    atol: float | tuple[float, ...] = 0.0,
) -> Comparison:
    """Compare a render with another under a named policy.

    ``policy='independent'`` is :func:`compare_images` on the two renders as
    given; ``policy='reference-floor'`` first applies :func:`floor_variance`
    to ``image_test`` with ``image_ref`` as the reference. Use
    ``'independent'`` for two independent renders (any two renderers, seeds
    or comparable sample counts) and ``'reference-floor'`` for a render
    against a high-spp reference of the same estimator; the module docstring
    says why.

    Parameters
    ----------
    image_test : RenderResult
        The render under test (side A: positive t means it is brighter).
    image_ref : RenderResult
        The other render (side B); the reference under ``'reference-floor'``.
    policy : {'independent', 'reference-floor'}
    alpha, tile, channels, correction, min_spp, rtol, atol
        As in :func:`compare_images` (``rtol``: the relative difference
        accepted between noiseless tiles, float32 rounding by default, one
        number or one per channel; ``atol``: an absolute margin, 0 by default).

    Returns
    -------
    Comparison
        With :attr:`Comparison.policy` set to ``policy``.

    Raises
    ------
    ValueError
        Unknown policy (or an invalid option of :func:`compare_images`).
    StatsError
        Inputs that cannot be compared.
    """
    if policy not in POLICIES:
        raise ValueError(f"policy must be one of {', '.join(POLICIES)}, got {policy!r}")
    if policy == "reference-floor":
        image_test = floor_variance(image_test, image_ref)
    c = compare_images(image_test, image_ref, alpha=alpha, tile=tile, channels=channels, correction=correction,
                       min_spp=min_spp, rtol=rtol, atol=atol)
    return replace(c, policy=policy)
