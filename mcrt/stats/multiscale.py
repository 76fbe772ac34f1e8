r"""Multi-scale tile test: the Welch tile tests of several tile sizes in one family-wise level.

A difference confined to a few pixels (an edge moved by a fraction of a
pixel, a highlight) averages out in 8x8 tiles; a faint difference spread over
the image hides in small ones. :func:`compare_multiscale` runs
:func:`mcrt.stats.policy.compare` at every tile size of ``tiles`` (0: the
whole image) and adjusts all their p-values together by weighted Holm
(:func:`mcrt.stats.multiple.adjust_p_values_weighted`): each scale gets an
equal share of ``alpha``, split evenly over its tests, so the family-wise
error rate over every tile, channel and scale is at most ``alpha`` under any
dependence between scales. Tests of noiseless tiles (zero variance on both
sides, compared for equality within ``rtol``) are in the family too, and
reported apart (:attr:`MultiScale.noiseless_rejected`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mcrt.film import RenderResult
from mcrt.stats.multiple import adjust_p_values_weighted
from mcrt.stats.policy import compare
from mcrt.stats.twosample import EXACT_RTOL, Comparison

__all__ = ["MultiScale", "compare_multiscale", "scales_for"]


def scales_for(h: int, w: int, tiles=(2, 4, 8, 16, 32, 0)) -> list[int]:
    """The tile edges used on an h x w image: those of ``tiles`` smaller than the image, and 0 (the whole image)."""
    return sorted({t for t in tiles if 0 < t < max(h, w)}) + ([0] if 0 in tiles else [])


@dataclass(repr=False)
class MultiScale:
    """Outcome of :func:`compare_multiscale`: one :class:`Comparison` per scale, adjusted together.

    ``rejected[k]`` and ``p_adjusted[k]`` are the joint decisions of scale
    ``tiles[k]`` (shaped like its comparison's arrays); a scale's own
    ``Comparison.rejected`` is its Holm decision alone and is not used.
    """

    alpha: float
    tiles: list[int]
    comparisons: list[Comparison]
    p_adjusted: list[np.ndarray]
    rejected: list[np.ndarray]
    rtol: float | tuple[float, ...] = EXACT_RTOL
    atol: float | tuple[float, ...] = 0.0
    notes: list[str] = field(default_factory=list)

    @property
    def n_tests(self) -> int:
        return int(sum(r.size for r in self.rejected))

    @property
    def n_rejected(self) -> int:
        return int(sum(np.count_nonzero(r) for r in self.rejected))

    @property
    def noiseless_rejected(self) -> int:
        """Rejected tests of noiseless tiles (a difference without noise: an offset of the reference, ...)."""
        return int(sum(np.count_nonzero(r & c.deterministic) for r, c in zip(self.rejected, self.comparisons)))

    @property
    def noisy_rejected(self) -> int:
        return self.n_rejected - self.noiseless_rejected

    @property
    def passed(self) -> bool:
        return self.n_rejected == 0

    def largest_noiseless_difference(self) -> float:
        """The largest |symmetric relative difference| of a noiseless test (rejected or accepted within rtol)."""
        vals = [np.abs(c.rel_diff[c.deterministic]).max() for c in self.comparisons if c.deterministic.any()]
        return float(max(vals)) if vals else 0.0

    def by_scale(self) -> dict[str, int]:
        """Rejected tests per scale, e.g. ``{'2x2': 3, '8x8': 1}`` (scales without a rejection left out)."""
        out = {}
        for t, r in zip(self.tiles, self.rejected):
            n = int(np.count_nonzero(r))
            if n:
                out["whole" if t == 0 else f"{t}x{t}"] = n
        return out

    def headline(self) -> str:
        verdict = "consistent" if self.passed else "DIFFERENT"
        sizes = ", ".join("whole image" if t == 0 else f"{t}x{t}" for t in self.tiles)
        text = (f"{verdict}: {self.n_rejected} of {self.n_tests} tests rejected at FWER {self.alpha:g} "
                f"(weighted Holm over tiles {sizes})")
        if self.noiseless_rejected:
            text += f"; {self.noiseless_rejected} of them noiseless, up to {100 * self.largest_noiseless_difference():.3g} %"
        return text


def compare_multiscale(a: RenderResult, b: RenderResult, *, tiles=(2, 4, 8, 16, 32, 0), alpha: float = 0.01,
                       policy: str = "independent", channels: str = "rgb",
                       rtol: float | tuple[float, ...] = EXACT_RTOL, atol: float | tuple[float, ...] = 0.0,
                       min_spp: int = 2) -> MultiScale:
    """Compare ``a`` with ``b`` at every tile size of :func:`scales_for` in one family-wise level ``alpha``.

    ``policy``, ``channels``, ``rtol``, ``atol`` and ``min_spp`` are those of
    :func:`mcrt.stats.policy.compare`, applied at each scale. Returns a
    :class:`MultiScale`.
    """
    h, w = a.mean.shape[:2]
    scales = scales_for(h, w, tiles)
    comps = [compare(a, b, policy=policy, alpha=alpha, tile=t if t > 0 else max(h, w), channels=channels, rtol=rtol,
                     atol=atol, min_spp=min_spp) for t in scales]
    p = np.concatenate([c.p_values.ravel() for c in comps])
    weights = np.concatenate([np.full(c.p_values.size, 1.0 / (len(comps) * c.p_values.size)) for c in comps])
    adj = adjust_p_values_weighted(p, weights)
    out_adj, out_rej, k = [], [], 0
    for c in comps:
        n = c.p_values.size
        pa = adj[k:k + n].reshape(c.p_values.shape)
        out_adj.append(pa)
        out_rej.append(pa <= alpha)
        k += n
    return MultiScale(alpha=float(alpha), tiles=scales, comparisons=comps, p_adjusted=out_adj, rejected=out_rej,
                      rtol=comps[0].rtol, atol=comps[0].atol)
