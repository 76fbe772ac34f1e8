r"""Differences per object: a test beside the tiles, and how each object differs, in words and as a map.

A tile mixes the surfaces it covers; a small change confined to one object
(a sphere slightly too small, a reflection missing) can hide in tiles where
the object is a few pixels of many. Here the pixels are grouped by what they
see (:func:`mcrt.grade.expected.surface_labels`: each wall, the floor, the
ceiling, the light, the tetrahedron, the sphere) and each group's mean
residual is tested like a tile of the bias test (:func:`mcrt.stats.onesample.scale_stats`):

.. math::

    t_k = \bar r_k / \sqrt{V_k}, \qquad
    V_k = \max\Big(\frac{1}{n_k^2}\sum_{i \in k} (v^{model}_i + v^{ref}_i),\;
                   \frac{s_k^2}{n_k}\Big),

per channel, with :math:`n_k - 1` degrees of freedom. What joins the bias
test's Holm family as one more detector (``multiscale_test(..., extra=...)``,
share :data:`SHARE` of alpha) is not the test of a zero difference but of a
*relevant* one (:meth:`ObjectTests.family` with ``relevant=True``; a
remainder's test in :mod:`mcrt.grade.adequacy` keeps the test of a zero
difference, the cautious side for claiming a cause): the null hypothesis is
:math:`|\mu_k| \le \delta |\bar R_k|` with :math:`\delta` the relevance
threshold ``min_effect``, and its p-value is the least favourable one,

.. math::

    p_k = S\Big(\frac{|\bar r_k| - \delta |\bar R_k|}{\sqrt{V_k}}\Big)
        + S\Big(\frac{|\bar r_k| + \delta |\bar R_k|}{\sqrt{V_k}}\Big)

(:math:`S` Student's survival function; :math:`\delta = 0` gives the
two-sided test of :attr:`ObjectTests.p`). An object pools hundreds to
thousands of pixels, so its mean is known to a tenth of a per cent at high
spp: the test of a zero difference then rejects differences a correct
renderer has, of the order of ``min_effect`` (Mitsuba's ``ldsampler`` on
the floor and the ceiling; the false-alarm report, ``mcrt grade-false-alarms``,
shows each renderer's difference per object and the raw p-values of both tests),
and comparing the *estimate* with ``min_effect`` afterwards lets such a
difference through whenever noise lifts it past the threshold. Testing the
relevant difference keeps the family-wise level for every renderer whose
bias is below ``min_effect``.

:func:`describe` words how each object differs from the reference (darker,
brighter, less contrast, missing detail) and :func:`effect_map` gives the
map the feedback shows: each pixel the relative luminance difference of its
object, where that object's test is rejected.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats as _sps

from mcrt.grade.structure import beside_emitters
from mcrt.stats import LUMINANCE_WEIGHTS

LUMINANCE = np.asarray(LUMINANCE_WEIGHTS)
#: Share of the family-wise error rate the per-object test gets (the tiles keep the rest).
SHARE = 0.05
#: Share of the family-wise error rate of the per-object structure test (:func:`structure_family`).
STRUCTURE_SHARE = 0.01
#: Least excess share outside the body for the structure test to be relevant (see :func:`structure_family`).
MIN_EXCESS_SHARE = 0.15
#: The share of the image's squared z-scores counted as outside its noise's body (above their upper quartile).
OUTSIDE = 0.25
#: The image's upper tails each object's share is counted in (:func:`structure_family`): the body's edge, and two
#: further out, where a small object with a changed material (a glossy mirror) puts many of its few pixels.
TAILS = (OUTSIDE, 0.1, 0.025)
#: Fewest pixels an object needs to be tested on its own.
MIN_PIXELS = 4
#: Within an object, the reference's variation must be this many times its noise to speak of contrast or detail.
MIN_STRUCTURE = 4.0


@dataclass
class ObjectTests:
    """Per-object statistics; arrays (K, 3) over the K labels (rows of labels absent from the image have n = 0)."""

    n: np.ndarray  # (K,) pixels per label
    diff: np.ndarray  # mean residual
    ref: np.ndarray  # mean reference
    var: np.ndarray  # variance of the mean residual
    p: np.ndarray  # two-sided p-values of a zero difference (1 where untested)
    rel: np.ndarray  # diff / |ref|

    def relevant_p(self, min_effect: float) -> np.ndarray:
        """(K, 3) p-values of the null hypothesis |mean residual| <= ``min_effect`` |mean reference| (module
        docstring; 1 where untested). At ``min_effect`` 0 they are :attr:`p`."""
        ok = (self.n >= MIN_PIXELS)[:, None] & (self.var > 0)
        sd = np.sqrt(np.where(ok, self.var, 1.0))
        bound = min_effect * np.abs(self.ref)
        dof = np.maximum(self.n - 1.0, 1.0)[:, None]
        p = _sps.t.sf((np.abs(self.diff) - bound) / sd, dof) + _sps.t.sf((np.abs(self.diff) + bound) / sd, dof)
        return np.where(ok, np.minimum(p, 1.0), 1.0)

    def family(self, min_effect: float, relevant: bool = False) -> tuple[str, np.ndarray, np.ndarray, float]:
        """(name, p-values, relevant, share) for :func:`mcrt.stats.onesample.multiscale_test`'s ``extra``, relevant
        where the estimate is ``min_effect`` or more; ``relevant``: the test of a relevant difference
        (:meth:`relevant_p`; the grade's bias test, which takes points), else of a zero one (a remainder's test,
        where rejecting more is the cautious side)."""
        p = self.relevant_p(min_effect) if relevant else self.p
        return ("objects", p.ravel(), (np.abs(self.rel) >= min_effect).ravel(), SHARE)


def object_tests(resid: np.ndarray, ref: np.ndarray, mask: np.ndarray, noise, labels: np.ndarray,
                 n_labels: int) -> ObjectTests:
    """The per-object test of the module docstring; ``noise`` is the bias test's :class:`mcrt.stats.onesample.Noise`."""
    k = np.where(mask, labels, n_labels).ravel().astype(np.int64)
    r = resid.reshape(-1, 3).astype(np.float64)
    R = ref.reshape(-1, 3).astype(np.float64)
    vm = (noise.model + noise.reference).reshape(-1, 3).astype(np.float64)
    if noise.pair is not None:
        vm = np.maximum(vm, (noise.pair + noise.reference).reshape(-1, 3))

    def sums(x):
        return np.stack([np.bincount(k, x[:, c], minlength=n_labels + 1)[:n_labels] for c in range(3)], axis=1)

    n = np.bincount(k, minlength=n_labels + 1)[:n_labels].astype(np.float64)
    safe = np.maximum(n, 1.0)[:, None]
    d = sums(r) / safe
    rm = sums(R) / safe
    s2 = np.maximum(sums(r * r) - safe * d * d, 0.0) / np.maximum(safe - 1.0, 1.0)
    var = np.maximum(sums(vm) / safe**2, s2 / safe)
    ok = (n >= MIN_PIXELS)[:, None] & (var > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(ok, d / np.sqrt(np.where(ok, var, 1.0)), 0.0)
        rel = np.where(np.abs(rm) > 0, d / np.abs(rm), 0.0)
    p = np.where(ok, 2.0 * _sps.t.sf(np.abs(t), np.maximum(n - 1.0, 1.0)[:, None]), 1.0)
    return ObjectTests(n, d, rm, var, np.minimum(p, 1.0), np.where(ok, rel, 0.0))


def _outside(resid: np.ndarray, var: np.ndarray, mask: np.ndarray, labels: np.ndarray, n_labels: int):
    """Luminance z^2 over the kept pixels, the kept pixels, and the image's tails' edges (its z^2 quantiles at
    1 - :data:`TAILS`; the first is the body's upper quartile)."""
    keep = mask & (labels < n_labels) & (var > 0)
    # Pixels that see only an emitter have next to no noise, and a step at their edge that the noise model follows
    # badly at low spp: they and their neighbours are left to the object's mean test and the tiles (as in
    # mcrt.grade.structure).
    keep &= ~beside_emitters(var, mask & (labels < n_labels))
    r = resid @ LUMINANCE
    z2 = np.where(keep, r * r / np.where(keep, var, 1.0), 0.0)
    edges = np.quantile(z2[keep], 1.0 - np.asarray(TAILS)) if keep.any() else np.full(len(TAILS), np.inf)
    return z2, keep, edges


def structure_shares(base_resid: np.ndarray, var: np.ndarray, mask: np.ndarray, labels: np.ndarray,
                     n_labels: int) -> np.ndarray:
    """(K, len(TAILS)) each object's share in each of the image's tails in a correct render (``base_resid``:
    mcrt's diagnosis baseline less the reference; ``var`` its luminance variance), at least the tail's own share:
    the expected shares of :func:`structure_family`, where the noise model fits some objects less well than
    others."""
    z2, keep, edges = _outside(base_resid, var, mask, labels, n_labels)
    out = np.tile(np.asarray(TAILS, np.float64), (n_labels, 1))
    for k in range(n_labels):
        sel = keep & (labels == k)
        if sel.sum() >= MIN_PIXELS:
            out[k] = np.maximum(out[k], np.mean(z2[sel][:, None] > edges[None, :], axis=0))
    return out


def _brightness(image: np.ndarray, ref: np.ndarray, mask: np.ndarray, labels: np.ndarray, n_labels: int) -> np.ndarray:
    """(H, W) each pixel's object's mean luminance in ``image`` over the reference's (clipped to [1/20, 20])."""
    k = np.where(mask & (labels < n_labels), labels, n_labels).ravel().astype(np.int64)
    s = np.bincount(k, (image @ LUMINANCE).ravel(), minlength=n_labels + 1)
    r = np.bincount(k, (ref @ LUMINANCE).ravel(), minlength=n_labels + 1)
    ratio = np.clip(np.where(r > 0, s / np.where(r > 0, r, 1.0), 1.0), 0.05, 20.0)
    ratio[n_labels] = 1.0
    return ratio[np.minimum(labels, n_labels)]


def baseline_shares(ctx, cam: str, R: np.ndarray, ref, mask: np.ndarray, *, unsampled: bool = False) -> np.ndarray | None:
    """:func:`structure_shares` of the grading context's mcrt baseline (``ctx``: mcrt.grade.expected.Context) for
    camera ``cam`` against its reference (``R`` its mean, ``ref`` its Expected); None for another camera.
    ``unsampled``: of its render without light sampling (a hand-in whose noise has that shape)."""
    b, model = (ctx.unsampled, ctx.model_var_unsampled) if unsampled else (ctx.baseline, ctx.model_var)
    if cam != ctx.assignment.camera or b is None or b.mean.shape != R.shape:
        return None
    var = model[cam].astype(np.float64) / b.spp + ref.var.astype(np.float64) / ref.spp
    return structure_shares(b.mean.astype(np.float64) - R, var @ LUMINANCE**2, mask, ctx.labels[cam],
                            len(ctx.label_names) - 1)


def structure_family(resid: np.ndarray, ref: np.ndarray, mask: np.ndarray, noise, labels: np.ndarray,
                     n_labels: int, min_effect: float, shares: np.ndarray | None = None,
                     image: np.ndarray | None = None, tails: int = len(TAILS)) -> tuple[str, np.ndarray, np.ndarray, float]:
    r"""Zero-mean structure within each object, as a family for :func:`mcrt.stats.onesample.multiscale_test`.

    A change that averages out over an object (a mirror's reflection
    blurred: brighter here, darker there) escapes the test of its mean; its
    pixels' luminance z-scores :math:`z_i = r_i / \sqrt{v_i}` (the bias
    test's noise model) are then too large over the whole object. Neither
    their sum of squares nor a fixed threshold on them will do: Monte-Carlo
    noise is heavy-tailed (a few bright paths make a chi-square of correct
    renders reject), and the model's variance is right only to a factor of
    a few (correct renders at 1024 spp have 40 % of their :math:`z_i^2`
    above the upper quartile of a chi-square, at 16 spp 9 %). So each object
    is compared with the image: the pixels in each of the image's own upper
    tails (:data:`TAILS`: :math:`z_i^2` above its upper quartile, its 90th
    and its 97.5th percentile) are counted on each object and tested
    one-sided against Binomial(n, :math:`q_{k,t}`), the smallest of the
    three p-values times three (Bonferroni). The outer tails see a small
    object whose few pixels are far off (a glossy sphere for a mirror);
    the quartile, many pixels a little off. Noise of one calibration
    everywhere puts the tail's share t of each object in it; the model fits
    some objects less well than others (correct renders of Mitsuba and mcrt
    alike put a third of wall BC above the quartile), so
    :math:`q_{k,t}` is the share a correct render has (``shares``,
    :func:`structure_shares` of mcrt's diagnosis baseline), at least t. A
    hand-in brighter or darker
    on an object than the reference (``image``: a fall-off, a tone map)
    has its noise scaled with it: the model's variance there is scaled by
    the square of the object's brightness ratio. Relevant where the object's
    median :math:`|r_i|` is ``min_effect`` of its mean brightness and the
    share above the quartile exceeds :math:`q_{k,t}` by :data:`MIN_EXCESS_SHARE` (a
    structure a fitted cause leaves, a fraction of a per cent, shows at
    high spp in a few more pixels; a wrong material in most of them).
    """
    vm = (noise.model + noise.reference) @ LUMINANCE**2
    if noise.pair is not None:
        vm = np.maximum(vm, (noise.pair + noise.reference) @ LUMINANCE**2)
    if image is not None:
        vm = vm * _brightness(image, ref, mask, labels, n_labels) ** 2
    z2, keep, edges = _outside(resid, vm, mask, labels, n_labels)
    p0 = np.tile(np.asarray(TAILS, np.float64), (n_labels, 1)) if shares is None else shares
    r, p, rel = resid @ LUMINANCE, np.ones(n_labels), np.zeros(n_labels, bool)
    for k in range(n_labels):
        sel = keep & (labels == k)
        n = int(sel.sum())
        if n < MIN_PIXELS or not np.all(np.isfinite(edges)):
            continue
        out = np.count_nonzero(z2[sel][:, None] > edges[None, :], axis=0)
        p[k] = min(1.0, tails * float(np.min(_sps.binom.sf(out[:tails] - 1, n, p0[k, :tails]))))
        rel[k] = (out[0] / n - p0[k, 0] >= MIN_EXCESS_SHARE
                  and float(np.median(np.abs(r[sel]))) >= min_effect * abs(float(np.mean(ref[sel] @ LUMINANCE))))
    return ("object_structure", p, rel, STRUCTURE_SHARE)


def describe(S: np.ndarray, R: np.ndarray, mask: np.ndarray, noise_var: np.ndarray, labels: np.ndarray,
             k: int) -> list[str]:
    r"""How the image S differs from R on object ``k``: 'darker by 12 %', 'less contrast', 'missing detail'.

    Brightness is the mean luminance ratio. Contrast is the slope of S on R
    within the object (least squares on luminance, centred), spoken of only
    where R varies there by :data:`MIN_STRUCTURE` times its noise; detail
    is the same for the pixel-to-pixel differences (a Laplacian), which a
    blur or a missing reflection flattens.
    """
    sel = mask & (labels == k)
    if sel.sum() < MIN_PIXELS:
        return []
    s, r = S[sel] @ LUMINANCE, R[sel] @ LUMINANCE
    v = noise_var[sel] @ LUMINANCE**2
    out = []
    ms, mr = float(s.mean()), float(r.mean())
    if mr > 0 and ms <= 0:  # a remainder below zero: what it is compared with holds more light than the image
        out.append("black or darker (no light left)")
    elif mr > 0 and abs(ms / mr - 1) >= 0.01:
        out.append(f"{'darker' if ms < mr else 'brighter'} by {100 * abs(ms / mr - 1):.0f} %")
    rc, sc = r - mr, s - ms
    if float(np.sum(rc * rc)) > MIN_STRUCTURE**2 * float(np.sum(v)):
        slope = float(np.sum(sc * rc) / np.sum(rc * rc))
        if slope < 0.8:
            out.append(f"less contrast ({100 * max(slope, 0):.0f} % of the reference's variation)")
        elif slope > 1.25:
            out.append(f"more contrast ({100 * slope:.0f} % of the reference's variation)")
    lap_r, lap_s = _laplacian(R @ LUMINANCE), _laplacian(S @ LUMINANCE)
    inner = sel & _interior(labels == k)
    if inner.sum() >= MIN_PIXELS:
        er = float(np.sum(lap_r[inner] ** 2))
        es = float(np.sum(lap_s[inner] ** 2)) - 20.0 * float(np.sum(v[inner[sel]]))  # the Laplacian's noise: 20 v
        if er > MIN_STRUCTURE**2 * 20.0 * float(np.sum(v[inner[sel]])) and es < 0.4 * er:
            out.append("missing detail")
    return out


def _laplacian(x: np.ndarray) -> np.ndarray:
    p = np.pad(x, 1, mode="edge")
    return p[1:-1, 2:] + p[1:-1, :-2] + p[2:, 1:-1] + p[:-2, 1:-1] - 4.0 * x


def _interior(sel: np.ndarray) -> np.ndarray:
    """Pixels whose four neighbours are in ``sel`` too."""
    p = np.pad(sel, 1, mode="constant")
    return sel & p[1:-1, 2:] & p[1:-1, :-2] & p[2:, 1:-1] & p[:-2, 1:-1]


def flagged_objects(ot: ObjectTests, rejected: np.ndarray | None, *, tile_effect: np.ndarray | None = None,
                    labels: np.ndarray | None = None, mask: np.ndarray | None = None) -> list[int]:
    """Labels where a difference is established, largest share of it first.

    ``rejected`` (K, 3) marks the objects whose test is rejected and
    relevant; ``tile_effect`` (H, W), the relative effect of the penalised
    tiles covering each pixel (:attr:`mcrt.stats.onesample.MultiScaleTest.pixel_effect`),
    adds the objects by the effect summed over their pixels.
    """
    K = ot.n.size
    weight = np.zeros(K)
    if rejected is not None:
        hit = np.asarray(rejected, bool).reshape(K, 3).any(axis=1)
        weight += np.where(hit, np.abs(ot.rel @ LUMINANCE) * ot.n, 0.0)
    if tile_effect is not None and labels is not None:
        eff = np.where(mask, tile_effect, 0.0) if mask is not None else tile_effect
        for k in range(K):
            if ot.n[k] >= MIN_PIXELS:
                weight[k] += float(eff[labels == k].sum())
    order = [int(k) for k in np.argsort(-weight) if weight[k] > 0]
    top = weight[order[0]] if order else 0.0
    return [k for k in order if weight[k] >= 0.1 * top]


def effect_map(ot: ObjectTests, rejected: np.ndarray, labels: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(H, W) relative luminance difference of each pixel's object where its test is rejected (0 elsewhere)."""
    K = ot.n.size
    hit = np.asarray(rejected, bool).reshape(K, 3).any(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        rl = np.where(np.abs(ot.ref @ LUMINANCE) > 0, (ot.diff @ LUMINANCE) / np.abs(ot.ref @ LUMINANCE), 0.0)
    per = np.append(np.where(hit, rl, 0.0), 0.0)
    return np.where(mask, per[np.minimum(labels, K)], 0.0)


def join(items: list[str]) -> str:
    if len(items) <= 1:
        return "".join(items)
    return ", ".join(items[:-1]) + " and " + items[-1]


def sentence(S, R, mask, noise_var, labels, names, objects: list[int], limit: int = 3) -> str:
    """'on the ceiling (darker by 12 %) and the light (brighter by 30 %, missing detail)' for the objects given (at most ``limit``)."""
    parts = []
    for k in objects[:limit]:
        how = describe(S, R, mask, noise_var, labels, k)
        parts.append(names[k] + (f" ({', '.join(how)})" if how else ""))
    return "on " + join(parts) if parts else ""
