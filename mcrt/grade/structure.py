r"""Structured errors the tile test cannot see: misregistration, blur or denoising, wrong pixels.

A tile mean is blind to an error whose mean over the tile is zero: a camera
shifted by a fraction of a pixel, a field of view a few per cent off or a
blur move energy *within* a tile. Three detectors look at the residual
:math:`r_i = S_i - R_i` pixel by pixel (luminance for the first two, each
channel for the third); each gives p-values that join the tile tests in one
weighted Holm family (:func:`mcrt.stats.adjust_p_values_weighted`), so that
the whole verdict keeps the family-wise error rate ``alpha``.

**Registration and blur** (a regression of the residual on what each mistake
would do to the image). With B the diagnosis baseline (an mcrt render of the
assigned camera whose noise is independent of both S and R) and its central
differences :math:`B_x, B_y` about the image centre (c_x, c_y), a sub-pixel
shift :math:`(\delta_x, \delta_y)`, a zoom s (field of view), a roll
:math:`\theta` and a blur of variance :math:`\sigma^2` give to first order

.. math::

    r \approx \delta_x B_x + \delta_y B_y + s\,[(x - c_x) B_x + (y - c_y) B_y]
        + \theta\,[(x - c_x) B_y - (y - c_y) B_x] + \tfrac{\sigma^2}{2}\,\Delta B
        + \sum_k a_k\,B\,[\mathrm{label} = k],

the last sum a brightness factor per visible surface (a nuisance, so that a
wall of the wrong brightness is not taken for a shifted camera). The
coefficients are fitted by weighted least squares (weights
:math:`1/v_i`, mcrt's noise model); their covariance is the
heteroscedasticity-consistent sandwich (HC3: each squared residual divided by
:math:`(1 - h_{ii})^2`), which needs no noise model to be right, only pixels
whose noise is independent: any estimator, sampler or sample count. The
registration test is the Wald statistic of :math:`(\delta_x, \delta_y, s,
\theta)` against :math:`\chi^2_4`, the blur test that of :math:`\sigma^2`
against :math:`\chi^2_1`. Pan and tilt of the camera are shifts to first order.

**Correlated noise** (denoising). A Monte-Carlo render's pixels are
independent; a filter makes neighbours alike. With :math:`e_i` the residual
less the fit above, in units of the model noise, the self-normalised
lag-one statistic

.. math::

    T = \frac{\sum_{(i,j)} e_i e_j}{\sqrt{\sum_{(i,j)} e_i^2 e_j^2}}

over horizontally and vertically adjacent pairs is N(0, 1) when the pixels are
independent with mean 0, whatever their variances (its denominator estimates
the variance of its numerator); a filter makes it large and positive
(one-sided test). A bias left in the residual (a wrong material on one
object) also makes neighbours alike, so T is read on what is left of the
structure: the difference of two renders, or a high-pass residual within
each surface (:mod:`mcrt.grade.filtertest`). Its effect size is the lag-one
correlation beyond what independent noise gives.

**Pixels too dark to be noise.** A pixel of n non-negative samples X can
fall short of its mean only so far: :math:`P(\bar X \le \mu - t) \le
\exp(-n t^2 / (2\,E[X^2]))` (the lower-tail bound for non-negative variables,
which holds however heavy the upper tail), with :math:`E[X^2]/n = \sigma^2/n
+ \mu^2/n`. Each pixel and channel darker than the reference gets that bound
as its p-value (reference and quantisation noise added to the variance).
Too-bright pixels are not tested one by one: a correct render's fireflies
make any brightness possible.

**A patch of pixels off together** (a shadow missing, a highlight where
there is none). A change over a few dozen pixels hides in the tiles it
touches (their spread takes it for noise) and in the objects it is a small
part of; its pixels are far off the reference, all the same way, and
touch. With :math:`z_i` each pixel's luminance residual over its noise
(the same weights' variance), the pixels beyond :data:`PATCH_Z` on one side
are grouped into 4-connected patches (for each threshold of :data:`PATCH_Z`:
a few pixels far off, or many a little). A Monte-Carlo render's pixels are
independent, so a given connected set of s pixels is all beyond with
probability :math:`q^s`, q the chance that one is; at most :math:`s
\lambda^s` connected sets of s pixels hold a given pixel
(:data:`PATCH_ANIMALS`), so over N pixels the largest patch has

.. math::

    P(\text{a patch of } s \text{ or more}) \le N\, s\, (\lambda q)^s

(the union bound over lattice animals). q is not assumed: it is each
surface's own share of pixels beyond, at its upper 99.9 % confidence bound
(Clopper-Pearson), the largest over surfaces (the model fits some surfaces
less well than others; small ones are pooled, and all pixels together
count too), counted outside the patch tested (which would raise its own
surface's share), at least a Gaussian's. Fireflies stand alone and
heavy tails raise q, which the bound follows; a patch of dozens is beyond
either. The least bound over the thresholds, times their number
(Bonferroni), is each side's p-value; the two sides are two tests, relevant
where the patch's mean relative difference is ``min_pixel_effect``.

Each detector also has a relevance threshold (as the tile test's
``min_effect``): a significant but negligible structure is not penalised.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage
from scipy import stats as _sps

from mcrt.grade.filtertest import noise_correlation
from mcrt.stats import LUMINANCE_WEIGHTS

LUMINANCE = np.asarray(LUMINANCE_WEIGHTS)

#: Relevance thresholds (defaults of the rubric's ``unbiased`` table).
MIN_SHIFT = 0.05  # grade pixels of shift (or of displacement at the image's edge for zoom and roll)
MIN_BLUR = 0.1  # sigma^2 of the fitted blur (a Gaussian of that variance), in grade pixels^2
MIN_CORRELATION = 0.05  # lag-one correlation of the residual noise
MIN_PIXEL_EFFECT = 0.25  # relative darkening of a pixel
TARGET_SHIFT = 0.5  # grade pixels: the displacement beyond which the first-order model is not trusted (weights)
MIN_LABEL_PIXELS = 32  # a surface seen by fewer pixels gets no brightness factor of its own
PATCH_Z = (3.0, 4.0, 6.0)  # |z| beyond which a pixel belongs to a patch: each is tried (module docstring)
PATCH_CONFIDENCE = 0.999  # the upper confidence bound on each surface's share of pixels beyond PATCH_Z
PATCH_GROUP = 256  # surfaces of fewer pixels are pooled for that bound
#: A bound on the growth constant of lattice animals (fixed polyominoes): there are at most PATCH_ANIMALS^s of s
#: cells (Klarner and Rivest 1973 bound the constant by 4.65; their count is supermultiplicative, so the constant
#: bounds every term), hence at most s PATCH_ANIMALS^s holding a given cell.
PATCH_ANIMALS = 4.65


@dataclass
class Registration:
    """Fitted first-order camera error, in grade pixels (shift), relative (zoom) and radians (roll)."""

    shift: tuple[float, float]  # (x, y): the image shows the scene moved by this much
    zoom: float  # s: the image is magnified by 1 + s about its centre (a narrower field of view)
    roll: float  # theta: rotated counter-clockwise on screen by this angle
    edge_displacement: float  # largest displacement of a pixel the fit implies (grade pixels)
    p: float
    wald: float


@dataclass
class Structure:
    """The detectors' results; p-values raw (the grader adjusts them with the tile tests)."""

    registration: Registration | None = None
    blur: float = 0.0  # sigma^2 (grade pixels^2) of a Gaussian blur; negative: sharpened
    p_blur: float = 1.0
    correlation: float = 0.0  # lag-one correlation of the residual noise
    p_correlation: float = 1.0
    t_correlation: float = 0.0
    correlation_axis: str = ""  # the direction the noise is correlated along: '' both, 'rows' or 'columns' alone
    pixel_p: np.ndarray | None = None  # (H, W, 3) lower-tail bounds (1 where not tested)
    pixel_effect: np.ndarray | None = None  # (H, W, 3) relative darkening
    patch_p: np.ndarray | None = None  # (2,) the bound of the largest patch brighter, darker (module docstring)
    patch_maps: np.ndarray | None = None  # (2, H, W) its pixels
    patch_effect: np.ndarray | None = None  # (2,) its mean relative luminance difference (signed)
    notes: list[str] = field(default_factory=list)

    def families(self) -> list[tuple[str, np.ndarray]]:
        """(name, raw p-values) of each detector, for the joint multiple-testing correction."""
        out = []
        if self.registration is not None:
            out += [("registration", np.array([self.registration.p])), ("blur", np.array([self.p_blur]))]
        out.append(("correlation", np.array([self.p_correlation])))
        if self.pixel_p is not None:
            out.append(("pixels", self.pixel_p.ravel()))
        if self.patch_p is not None:
            out.append(("patches", self.patch_p))
        return out

    def relevant(self, name: str, *, min_shift: float = MIN_SHIFT, min_blur: float = MIN_BLUR,
                 min_correlation: float = MIN_CORRELATION, min_pixel: float = MIN_PIXEL_EFFECT) -> np.ndarray:
        """Which tests of detector ``name`` are large enough to matter (same shape as its p-values)."""
        if name == "registration":
            return np.array([self.registration.edge_displacement >= min_shift])
        if name == "blur":
            return np.array([abs(self.blur) >= min_blur])
        if name == "correlation":
            return np.array([self.correlation >= min_correlation])
        if name == "patches":
            return np.abs(self.patch_effect) >= min_pixel
        return (self.pixel_effect >= min_pixel).ravel()


#: A pixel whose noise variance is below this share of the image's median sees only an emitter (no noise).
NOISELESS = 1e-3


def beside_emitters(v: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(H, W) the pixels that see only an emitter (luminance variance ``v`` below :data:`NOISELESS` of the
    median over ``mask``) and their 8 neighbours: no noise, and a step at the emitter's edge that the noise model
    follows badly (a sub-pixel change of the edge is many noise deviations there)."""
    pos = v[mask & (v > 0)]
    floor = float(np.median(pos)) * NOISELESS if pos.size else 1e-12
    return ndimage.binary_dilation(mask & (v <= floor), structure=np.ones((3, 3), bool))


def _gradients(b: np.ndarray):
    """Central differences of an (H, W) image (one-sided at the border), and the 4-neighbour Laplacian."""
    p = np.pad(b, 1, mode="edge")
    gx = 0.5 * (p[1:-1, 2:] - p[1:-1, :-2])
    gy = 0.5 * (p[2:, 1:-1] - p[:-2, 1:-1])
    lap = p[1:-1, 2:] + p[1:-1, :-2] + p[2:, 1:-1] + p[:-2, 1:-1] - 4.0 * b
    return gx, gy, lap


def _design(base: np.ndarray, labels: np.ndarray | None):
    """Columns of the regression (module docstring): structure first (dx, dy, zoom, roll, blur), then nuisances."""
    h, w = base.shape
    gx, gy, lap = _gradients(base)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    cx, cy = 0.5 * (w - 1), 0.5 * (h - 1)
    x, y = xx - cx, yy - cy
    cols = [gx, gy, x * gx + y * gy, x * gy - y * gx, 0.5 * lap]
    lab = labels if labels is not None else np.zeros((h, w), np.int16)
    ks, counts = np.unique(lab, return_counts=True)
    small = np.isin(lab, ks[counts < MIN_LABEL_PIXELS])
    # Surfaces seen by a handful of pixels share one factor: a column of a few pixels has leverage
    # near 1 there, which makes the sandwich's (1 - h)^-2 explode.
    for k in ks[counts >= MIN_LABEL_PIXELS]:
        cols.append(np.where(lab == k, base, 0.0))
    if small.sum() >= MIN_LABEL_PIXELS:
        cols.append(np.where(small, base, 0.0))
    return np.stack([c.ravel() for c in cols], axis=1), float(np.hypot(cx, cy))


def _fit(X: np.ndarray, y: np.ndarray, wt: np.ndarray):
    """Weighted least squares with the HC3 sandwich covariance: (beta, cov, residual)."""
    sw = np.sqrt(wt)
    Xw = X * sw[:, None]
    keep = np.abs(Xw).sum(axis=0) > 0
    Xw, Xk = Xw[:, keep], X[:, keep]
    q, rr = np.linalg.qr(Xw)
    ok = np.abs(np.diag(rr)) > 1e-10 * max(float(np.abs(np.diag(rr)).max()), 1e-300)
    q, Xw, Xk = q[:, ok], Xw[:, ok], Xk[:, ok]
    idx = np.flatnonzero(keep)[ok]
    yw = y * sw
    beta_k, *_ = np.linalg.lstsq(Xw, yw, rcond=None)
    e = y - Xk @ beta_k
    lev = np.minimum(np.sum(q * q, axis=1), 0.99)
    bread = np.linalg.pinv(Xw.T @ Xw)
    u = Xw * (sw * e / (1.0 - lev))[:, None]
    cov_k = bread @ (u.T @ u) @ bread
    beta = np.zeros(X.shape[1])
    cov = np.zeros((X.shape[1], X.shape[1]))
    beta[idx] = beta_k
    cov[np.ix_(idx, idx)] = cov_k
    return beta, cov, e, idx


def _wald(beta: np.ndarray, cov: np.ndarray, sel: list[int]) -> tuple[float, float]:
    b, c = beta[sel], cov[np.ix_(sel, sel)]
    if not np.any(np.diag(c) > 0):
        return 0.0, 1.0
    wald = float(b @ np.linalg.pinv(c) @ b)
    return wald, float(_sps.chi2.sf(wald, len(sel)))


def detect(resid: np.ndarray, ref: np.ndarray, mask: np.ndarray, var: np.ndarray, second_moment: np.ndarray,
           *, base: np.ndarray | None, labels: np.ndarray | None, pair: np.ndarray | None = None) -> Structure:
    """Run the three detectors (module docstring) on one graded image.

    ``resid`` and ``ref`` are (H, W, 3); ``var`` (H, W, 3) is the variance of
    each pixel mean under the noise model (student and reference), which sets
    the weights: it must not depend on the noise of either image (the
    reference's own variance estimate does: with heavy tails it is low where
    the reference's mean is low, which biases a weighted fit);
    ``second_moment`` (H, W, 3) the bound's :math:`E[X^2]/n` plus the
    reference's and quantisation's variance; ``base`` (H, W, 3) the
    independent render the regression's columns are made from (None: no
    registration or blur test, e.g. for a camera without one); ``labels``
    the surface each pixel sees; ``pair`` (H, W, 3) the difference a - b of two renders handed in, whose
    noise the correlation test then reads (:mod:`mcrt.grade.filtertest`).
    """
    out = Structure()
    h, w = resid.shape[:2]
    v = np.maximum(var @ (LUMINANCE**2), 0.0)
    pos = v[mask & (v > 0)]
    floor = float(np.median(pos)) * NOISELESS if pos.size else 1e-12
    # Pixels that see only an emitter have no noise and a step at their edge that no first-order
    # term follows: they and their neighbours are left to the tile test (which compares them exactly).
    pixel_mask = mask
    mask = mask & ~beside_emitters(v, mask)
    r = np.where(mask, resid @ LUMINANCE, 0.0)
    wt = np.where(mask, 1.0 / np.maximum(v, floor), 0.0)
    e = r
    if base is not None and mask.sum() > 64:
        bl = np.asarray(base, np.float64) @ LUMINANCE
        X, radius = _design(bl, labels)
        # Weights from B alone (so the estimate stays unbiased): where a shift of TARGET_SHIFT would change
        # the pixel by far more than its noise (a sharp, bright edge: a reflection of the light), the
        # first-order model is off and that pixel would swamp the fit; it counts as if that were noise.
        gx, gy, lap = _gradients(bl)
        wt = np.where(mask, 1.0 / (np.maximum(v, floor) + TARGET_SHIFT**2 * (gx * gx + gy * gy)
                                   + (0.5 * TARGET_SHIFT**2 * lap) ** 2), 0.0)
        m = mask.ravel()
        beta, cov, e_m, _ = _fit(X[m], r.ravel()[m], wt.ravel()[m])
        wald, p = _wald(beta, cov, [0, 1, 2, 3])
        edge = float(np.hypot(beta[0], beta[1]) + (abs(beta[2]) + abs(beta[3])) * radius)
        # The fit of r = S - R on B_x: S(x) = R(x) + dx R'(x) ~ R(x + dx): the image shows the scene moved by -dx.
        out.registration = Registration((-float(beta[0]), -float(beta[1])), float(beta[2]), -float(beta[3]), edge, p, wald)
        _, out.p_blur = _wald(beta, cov, [4])
        out.blur = float(beta[4])
        e = np.zeros(h * w)
        e[m] = e_m
        e = e.reshape(h, w)
    pl = np.where(mask, pair @ LUMINANCE, 0.0) if pair is not None else None
    out.t_correlation, out.p_correlation, out.correlation, out.correlation_axis = noise_correlation(
        e, wt, mask, labels, pair=pl)

    # Pixels darker than the non-negative lower-tail bound allows.
    with np.errstate(divide="ignore", invalid="ignore"):
        deficit = np.maximum(-resid, 0.0)
        m3 = pixel_mask[..., None] & (second_moment > 0)
        p = np.where(m3, np.exp(-0.5 * deficit**2 / np.where(m3, second_moment, 1.0)), 1.0)
        eff = np.where(m3 & (np.abs(ref) > 0), deficit / np.maximum(np.abs(ref), 1e-300), 0.0)
    out.pixel_p = np.minimum(p, 1.0)
    out.pixel_effect = eff
    out.patch_p, out.patch_maps, out.patch_effect = patches(resid, ref, pixel_mask & ~beside_emitters(v, pixel_mask),
                                                            v, labels)
    return out


def patches(resid: np.ndarray, ref: np.ndarray, mask: np.ndarray, v: np.ndarray, labels: np.ndarray | None):
    """((2,) bounds, (2, H, W) maps, (2,) mean relative differences) of the largest patch brighter and darker
    (module docstring), the least bound over :data:`PATCH_Z` times their number (Bonferroni); ``v`` (H, W) is each
    pixel's luminance variance."""
    h, w = resid.shape[:2]
    lab = np.zeros((h, w), np.int64) if labels is None else np.asarray(labels)
    keep = mask & (v > 0)
    n = int(keep.sum())
    p, maps, eff = np.ones(2), np.zeros((2, h, w), bool), np.zeros(2)
    if n == 0:
        return p, maps, eff
    r = np.where(keep, resid @ LUMINANCE, 0.0)
    z = np.where(keep, r / np.sqrt(np.where(keep, v, 1.0)), 0.0)
    # (pixels, the fewest it needs): each large surface, the small ones pooled, and every kept pixel together, whatever
    # their number (with no surface large enough, a small image, the share is still measured, never assumed).
    ks, counts = np.unique(lab[keep], return_counts=True)
    groups = [(keep & (lab == k), PATCH_GROUP) for k in ks[counts >= PATCH_GROUP]]
    groups += [(keep & np.isin(lab, ks[counts < PATCH_GROUP]), PATCH_GROUP), (keep, 1)]
    lum_ref = ref @ LUMINANCE
    for side, sign in enumerate((1.0, -1.0)):
        for zt in PATCH_Z:
            beyond = sign * z > zt
            comp, count = ndimage.label(beyond)
            if count == 0:
                continue
            big = int(np.argmax(np.bincount(comp.ravel())[1:])) + 1
            patch = comp == big
            s = int(patch.sum())
            # The share beyond, from the pixels outside the patch tested (a patch would raise its own surface's).
            q = float(_sps.norm.sf(zt))
            for sel, need in groups:
                sel = sel & ~patch
                m = int(sel.sum())
                if m >= need:
                    b = int(np.count_nonzero(beyond & sel))
                    q = max(q, float(_sps.beta.ppf(PATCH_CONFIDENCE, b + 1, m - b)))
            # log of N s (lambda q)^s, which can underflow as a product
            bound = float(np.exp(min(0.0, np.log(n) + np.log(s) + s * np.log(PATCH_ANIMALS * q)))) * len(PATCH_Z)
            if bound < p[side]:
                p[side], maps[side] = min(bound, 1.0), patch
                ref_sum = float(np.sum(lum_ref[patch]))
                eff[side] = float(np.sum(r[patch])) / ref_sum if ref_sum > 0 else 0.0
    return p, maps, eff


#: Share of the family-wise error rate each detector gets; the tile tests keep the rest.
SHARES = {"registration": 0.05, "blur": 0.025, "correlation": 0.025, "pixels": 0.075, "patches": 0.025}


def families(st: Structure, th) -> list[tuple[str, np.ndarray, np.ndarray, float]]:
    """(name, raw p-values, relevant, share of alpha) of every detector, for :func:`mcrt.stats.onesample.multiscale_test`.

    ``th`` holds the relevance thresholds (:class:`mcrt.grade.assignment.Thresholds`).
    """
    kw = {"min_shift": th.min_shift, "min_blur": th.min_blur, "min_correlation": th.min_correlation,
          "min_pixel": th.min_pixel_effect}
    return [(name, p, st.relevant(name, **kw), SHARES[name]) for name, p in st.families()]
