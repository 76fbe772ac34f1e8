r"""One-sample multi-scale tile test: has an image the expected value of a reference, given a noise model?

The question is whether an image S (in grading: a student's render) has the expected value of the
reference R, when S is one Monte-Carlo render of unknown quality at a modest
sample count. Pixels are pooled into tiles at several scales (the assignment's
``tiles``, 0 = the whole image); for each tile t of n valid pixels and each
channel the residuals r_i = s_i - R_i give

.. math::

    D_t = \frac{1}{n} \sum_i r_i, \qquad
    V_t = \max\Big(V^{model}_t,\; V^{pair}_t,\; \frac{S_t^2}{n}\Big),
    \qquad t = D_t / \sqrt{V_t}, \quad \nu = n - 1,

three estimates of the variance of D_t, of which the largest is used:

* model: :math:`\frac{1}{n^2}\sum_i (\sigma^2_i / spp + q_i^2/12 + \sigma^2_{R,i} / spp_R)`,
  mcrt's per-sample variance sigma^2 at the student's sample count (the
  declared one, or the one the noise suggests), the quantisation step q of
  the file format, and the reference's own noise. It covers rare paths the
  student's render happened to miss (a tile without its caustic sample is
  too dark, and its own spread cannot show it);
* pair (two renders a, b): :math:`\frac{1}{n^2}\sum_i ((a_i - b_i)^2/4 + \sigma^2_{R,i}/spp_R)`,
  the noise the student's own estimator has, whatever it is;
* spread: the sample variance S_t^2 of the residuals within the tile, which
  holds every noise source of both images (and any variation of a bias,
  which only makes the test more cautious). It keeps a firefly from looking
  like a bias: a single huge sample inflates S_t^2 as much as D_t.

Tiles where all three are 0 (pixels that see only the light) are compared
for equality. What the grade's bias test (``relevant=True``) tests is a *relevant* bias: the null hypothesis of
tile t is :math:`|E[D_t]| \le \delta |\bar R_t|` with :math:`\delta` =
``min_effect``, and its p-value the least favourable one,
:math:`p_t = S((|D_t| - \delta |\bar R_t|)/\sqrt{V_t}) + S((|D_t| + \delta |\bar R_t|)/\sqrt{V_t})`
(:func:`relevant_p`; S Student's survival function with :math:`\nu`
degrees of freedom; :math:`\delta = 0` is the two-sided test of a zero
bias, kept in ``ScaleResult.p``). The p-values of all tiles, scales and
channels form one family, corrected by Holm (:func:`mcrt.stats.adjust_p_values`)
at level ``alpha``; a test is *penalised* where it is rejected (its
relative effect :math:`|D_t| / |\bar R_t|` is then at least ``min_effect``).
Testing a zero bias and comparing the estimate with ``min_effect`` after
would not hold the level for an image whose bias is below ``min_effect``:
at high spp a large tile's mean is known to a tenth of a per cent, correct
samplers differ from the reference by a few tenths on whole surfaces
(Mitsuba's ``ldsampler``; ``mcrt grade-false-alarms`` reports them), and
noise lifts such an estimate past the threshold.

Other detectors' tests join the same family (``multiscale_test(..., extra=...)``; in grading the
structured-error detectors of :mod:`mcrt.grade.structure`): weighted Holm
(:func:`mcrt.stats.adjust_p_values_weighted`) gives each detector its share
of ``alpha`` and the tiles the rest, of which the whole image's tests get
:data:`WHOLE_SHARE` and the other tiles equal parts.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import stats as _sps

from mcrt.stats.multiple import adjust_p_values_weighted
from mcrt.stats.tiles import tile_box, tile_sums

CHANNELS = ("R", "G", "B")
#: Share of the tiles' part of ``alpha`` that the whole image's tests (tile 0) get, the rest going to the other tiles
#: in equal parts. A bias over the whole image (a light's radiance, light reaching the ceiling that should not) is
#: the commonest mistake and the whole image its most powerful test; among hundreds of equally weighted tiles it
#: would need the p-value of an 8 x 8 tile, and a bias of a per cent at 256 spp would go unseen.
WHOLE_SHARE = 0.1



@dataclass
class Noise:
    """Per-pixel variances (H, W, 3) of the student's pixel means, by source; None if absent."""

    model: np.ndarray  # sigma^2 / spp + q^2 / 12
    reference: np.ndarray  # sigma_R^2 / spp_R
    pair: np.ndarray | None = None  # (a - b)^2 / 4


@dataclass
class ScaleResult:
    """One scale of the bias test; arrays (tiles_y, tiles_x, 3)."""

    tile: int  # 0: whole image
    n: np.ndarray  # valid pixels per tile (tiles_y, tiles_x)
    diff: np.ndarray  # D_t
    ref: np.ndarray  # mean reference over the tile's valid pixels
    var: np.ndarray  # V_t
    var_model: np.ndarray
    var_spread: np.ndarray
    var_pair: np.ndarray | None
    t: np.ndarray
    p: np.ndarray
    rel: np.ndarray  # D_t / |R_t|
    valid: np.ndarray  # (tiles_y, tiles_x) tiles with n >= 2
    rel_scale: np.ndarray | None = None  # the brightness rel is relative to: |ref|, at least a floor
    p_adj: np.ndarray | None = None
    rejected: np.ndarray | None = None
    penalised: np.ndarray | None = None


@dataclass
class MultiScaleTest:
    scales: list[ScaleResult]
    alpha: float
    min_effect: float
    n_tests: int
    shape: tuple[int, int]
    penalised_any: bool = False
    severity: float = 0.0  # share of the image, weighted by min(1, |rel| / full_effect)
    pixel_effect: np.ndarray | None = None  # (H, W) largest |rel| of a penalised test covering each pixel
    excess_rms: float = 0.0  # bias RMS beyond noise at the first scale, relative to the mean reference
    min_detectable: float = 0.0  # median relative effect a base tile must have to reach significance
    worst: dict = field(default_factory=dict)
    extra: dict = field(default_factory=dict)  # other detector -> its rejected and relevant tests (bool array)

    @property
    def base(self) -> ScaleResult:
        return self.scales[0]


def scale_stats(resid: np.ndarray, ref: np.ndarray, mask: np.ndarray, noise: Noise, tile: int, min_n: int = 2) -> ScaleResult:
    """Tile statistics of one scale (see the module docstring); ``mask`` (H, W) marks valid pixels.

    Tiles with fewer than ``min_n`` valid pixels are marked invalid (1 for
    single pixels, whose variance then comes from the model and pair only).
    """
    m = mask[..., None].astype(np.float64)
    r = np.where(m > 0, resid, 0.0)
    n = tile_sums(mask.astype(np.float64), tile)
    n3 = n[..., None]
    with np.errstate(divide="ignore", invalid="ignore"):
        safe = np.maximum(n3, 1.0)
        d = tile_sums(r, tile) / safe
        rm = tile_sums(np.where(m > 0, ref, 0.0), tile) / safe
        vr = tile_sums(noise.reference * m, tile) / safe**2
        vm = tile_sums(noise.model * m, tile) / safe**2 + vr
        vp = tile_sums(noise.pair * m, tile) / safe**2 + vr if noise.pair is not None else None
        ss = tile_sums(r * r, tile)
        s2 = np.maximum(ss - safe * d * d, 0.0) / np.maximum(n3 - 1.0, 1.0)
        vs = s2 / safe
        v = np.maximum(vm, vs)
        if vp is not None:
            v = np.maximum(v, vp)
        scale_ref = np.abs(rm)
        zero_var = v <= 0
        equal = np.abs(d) <= 1e-6 * np.maximum(scale_ref, 1e-12)
        t = np.where(zero_var, np.where(equal, 0.0, np.copysign(np.inf, d)), d / np.sqrt(np.where(zero_var, 1.0, v)))
        df = np.maximum(n3 - 1.0, 1.0) * np.ones_like(d)
        p = np.where(np.isinf(t), 0.0, 2.0 * _sps.t.sf(np.abs(t), df))
        p = np.where(zero_var & equal, 1.0, p)
        floor = 1e-3 * max(float(np.mean(np.abs(ref[mask]))) if mask.any() else 0.0, 1e-12)
        rel = d / np.maximum(scale_ref, floor)
    valid = n >= min_n
    return ScaleResult(tile, n, d, rm, v, vm, vs, vp, t, np.minimum(p, 1.0), rel, valid,
                       rel_scale=np.maximum(scale_ref, floor))


def relevant_p(s: ScaleResult, min_effect: float) -> np.ndarray:
    """p-values of the null hypothesis |bias| <= ``min_effect`` |mean reference| of each tile and channel of one
    scale (module docstring): the least favourable point of the null, Student's t with n - 1 degrees of freedom.
    A tile without noise (the light) is rejected where it differs by more than ``min_effect``."""
    bound = min_effect * np.abs(s.rel_scale)
    ad = np.abs(s.diff)
    zero_var = s.var <= 0
    sd = np.sqrt(np.where(zero_var, 1.0, s.var))
    df = np.maximum(s.n[..., None] - 1.0, 1.0) * np.ones_like(s.diff)
    with np.errstate(invalid="ignore"):
        p = _sps.t.sf((ad - bound) / sd, df) + _sps.t.sf((ad + bound) / sd, df)
    p = np.where(zero_var, np.where(s.p <= 0.0, np.where(ad > bound, 0.0, 1.0), 1.0), p)
    return np.minimum(np.where(min_effect > 0, p, s.p), 1.0)


def bias_scales(tiles, h: int, w: int) -> list[int]:
    """The scales :func:`multiscale_test` runs for an h x w image: ``tiles`` less those that cover the whole
    image when 0 (the whole image) is also among them (the same test twice)."""
    return [t for t in tiles if not (t > 0 and t >= max(h, w) and 0 in tiles)]


def _tile_weights(scales: list[ScaleResult], share: float, whole_share: float) -> np.ndarray:
    """Weighted Holm's weights of the tile tests, in :func:`multiscale_test`'s order: ``share`` split equally, or,
    when the whole image is among other scales, ``whole_share`` of it to the whole image's tests."""
    counts = [int(np.count_nonzero(s.valid)) * 3 for s in scales]
    whole = [s.tile == 0 for s in scales]
    n_whole = sum(c for c, w in zip(counts, whole) if w)
    n_rest = sum(counts) - n_whole
    if not (whole_share > 0 and n_whole and n_rest):
        return np.full(sum(counts), share / max(sum(counts), 1))
    return np.concatenate([np.full(c, share * (whole_share / n_whole if w else (1.0 - whole_share) / n_rest))
                           for c, w in zip(counts, whole)])


def multiscale_test(resid: np.ndarray, ref: np.ndarray, mask: np.ndarray, noise: Noise, tiles, *, alpha: float,
              min_effect: float, full_effect: float, extra=(), relevant: bool = False,
              whole_share: float = WHOLE_SHARE) -> MultiScaleTest:
    """Multi-scale tile test, Holm-corrected over every tile, scale and channel (module docstring).

    ``extra`` holds other detectors' tests that share the family-wise error
    rate: (name, raw p-values, relevant, share) with ``share`` the part of
    ``alpha`` the detector gets (the tile tests keep the rest). All tests
    are then adjusted together by weighted Holm, each test weighted by its
    group's share over the group's size; ``MultiScaleTest.extra`` maps each name
    to the tests that are rejected and relevant.

    ``relevant``: the tiles test a bias beyond ``min_effect`` (:func:`relevant_p`; the grade's bias test, which
    takes points), else a zero bias with the estimate compared with ``min_effect`` (a test that decides whether
    a remainder is noise, where rejecting more is the cautious side).

    ``whole_share``: the part of the tiles' share the whole image's tests get (:data:`WHOLE_SHARE`; 0: every
    tile of every scale weighs the same).
    """
    h, w = resid.shape[:2]
    scales = [scale_stats(resid, ref, mask, noise, tile) for tile in bias_scales(tiles, h, w)]
    ps = np.concatenate([(relevant_p(s, min_effect) if relevant else s.p)[s.valid].ravel() for s in scales]) \
        if scales else np.zeros(0)
    extra = [(name, np.asarray(p, np.float64).ravel(), np.asarray(rel, bool).ravel(), share)
             for name, p, rel, share in extra if np.size(p)]
    tile_share = 1.0 - sum(e[3] for e in extra)
    weights = [_tile_weights(scales, tile_share, whole_share)] + [np.full(e[1].size, e[3] / e[1].size) for e in extra]
    all_p = np.concatenate([ps] + [e[1] for e in extra])
    all_adj = adjust_p_values_weighted(all_p, np.concatenate(weights)) if all_p.size else all_p
    adj = all_adj[:ps.size]
    extra_pen, k_e = {}, ps.size
    for name, p, rel, _ in extra:
        extra_pen[name] = (all_adj[k_e:k_e + p.size] <= alpha) & rel
        k_e += p.size
    k = 0
    pix = np.zeros((h, w))
    any_pen = False
    worst = {}
    for s in scales:
        cnt = int(np.count_nonzero(s.valid)) * 3
        pa = np.ones_like(s.p)
        pa[s.valid] = adj[k:k + cnt].reshape(-1, 3)
        k += cnt
        s.p_adj = pa
        s.rejected = (pa <= alpha) & s.valid[..., None]
        s.penalised = s.rejected & (np.abs(s.rel) >= min_effect)
        for ty, tx in zip(*np.nonzero(s.penalised.any(axis=2))):
            any_pen = True
            y0, y1, x0, x1 = tile_box(h, w, s.tile, int(ty), int(tx))
            e = float(np.max(np.abs(s.rel[ty, tx][s.penalised[ty, tx]])))
            pix[y0:y1, x0:x1] = np.maximum(pix[y0:y1, x0:x1], e)
            c = int(np.argmax(np.where(s.penalised[ty, tx], np.abs(s.t[ty, tx]), -1)))
            if not worst or abs(s.t[ty, tx, c]) > abs(worst["t"]):
                worst = {"tile": s.tile, "ty": int(ty), "tx": int(tx), "box": [y0, y1, x0, x1], "channel": CHANNELS[c],
                         "t": float(s.t[ty, tx, c]), "p_adjusted": float(pa[ty, tx, c]), "rel": float(s.rel[ty, tx, c])}
    bt = MultiScaleTest(scales, alpha, min_effect, int(ps.size), (h, w), any_pen, extra=extra_pen)
    bt.pixel_effect = pix
    bt.severity = float(np.mean(np.minimum(1.0, pix / full_effect))) if any_pen else 0.0
    bt.worst = worst
    b = scales[0]
    ok = b.valid[..., None] & np.isfinite(b.var)
    if ok.any():
        excess = np.mean(np.where(ok, b.diff**2 - b.var, 0.0)) * b.diff.size / max(int(np.count_nonzero(ok)), 1)
        mref = float(np.mean(np.abs(ref[mask]))) if mask.any() else 1.0
        bt.excess_rms = float(np.sqrt(max(excess, 0.0)) / max(mref, 1e-12))
        # Relative effect a single base tile needs to clear Holm's first threshold.
        zcrit = float(_sps.norm.isf(alpha / max(ps.size, 1) / 2))
        with np.errstate(divide="ignore", invalid="ignore"):
            need = zcrit * np.sqrt(b.var) / np.abs(b.ref) + (min_effect if relevant else 0.0)
        need = need[ok & (np.abs(b.ref) > 0) & (b.var > 0)]
        bt.min_detectable = float(np.median(need)) if need.size else 0.0
    return bt

