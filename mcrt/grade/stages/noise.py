"""Noise: the hand-in's noise level against mcrt's at the declared spp, and the noise model the tests use.

The level is measured before the bias test (its noise model needs it) and
judged after it (a biased image's noise says nothing about its sample
count, unless a cause claimed for the bias leaves noise alone: then that
noise is judged); noise correlated between neighbours (a filter) fails it, and so does noise
that repeats between pixels apart (the same random numbers:
:func:`shared_numbers`, where the image is not biased). The
tile spreads of one render hold its bias as well as its noise (a light
moved by 0.7 measures as hundreds of times the expected noise): beyond
the limit, the noise model follows a measured excess up to
:data:`NOISE_BODY` times the expected noise, and further only as far as
the body of the high-passed residual (:func:`body_ratio`) bears it out;
the measured excess itself is judged by the noise criterion. Two renders
whose noise is the same (one seed: :func:`same_pair`) cannot measure the
noise: the first is graded alone, with the model noise, and the noise
criterion fails saying so. Excess
noise on unbiased tiles is told apart from a deterministic error that
cancels within tiles by ranking the catalogue at pixel level, by its noise
pattern and by its amount of noise (:mod:`mcrt.grade.explain.catalogue`).

The limit on the variance ratio (the rubric's ``noise.max_ratio``) is set
from the spread of correct renderers' ratios, the least efficient correct
estimators included (Russian roulette from the first bounce), with a margin:
``mcrt grade-false-alarms`` measures the spread and the margin. It cannot
catch every claim: a hand-in whose estimator is more efficient than mcrt's
(a stratified or low-discrepancy sampler) may claim a few times the samples
it took, and at 16 spp the ratio of one render is itself noisy (heavy tails).
"""

from __future__ import annotations

import numpy as np

from scipy import ndimage
from scipy import stats as _sps

from mcrt.grade.feedback import repeats_text, spp_text
from mcrt.grade.filtertest import second_differences, surface_runs
from mcrt.grade.score import LUMINANCE, noise_ratio
from mcrt.grade.stages.state import Grading, Hand, Level
from mcrt.grade.structure import beside_emitters
from mcrt.stats.onesample import Noise

#: The most a render's noise variance may exceed what the body of its high-passed residual shows
#: (:func:`body_ratio`, or the expected noise if more), as a multiple of it: heavy tails put a correct render's
#: tile spread above its body, a bias puts it far above (the grading-accuracy and false-alarm reports show both
#: classes; tests/test_feedback.py holds a moved light and correct renders at 16 and 64 spp on either side). An
#: excess up to this multiple of the expected noise is credited to noise whatever the body (a filter lowers the
#: body and raises the spread).
NOISE_BODY = 20.0
#: How much less noisy than mcrt at the declared spp an image may be before the feedback remarks on it and the
#: bias test's noise model follows the image (with this margin) rather than the declaration. Correct estimators
#: are often more efficient than mcrt (stratified and low-discrepancy samplers); this bound is not the rubric's
#: ``noise.max_ratio``, which judges the other side (a hand-in noisier than its declared spp allows).
MORE_EFFICIENT = 4.0
#: Below this ratio of the noise in two renders' difference to one render's noise (:func:`same_pair`), the two share
#: their noise (one seed, or one render saved twice). Both are medians of thousands of squared normalised second
#: differences (relative standard error a few per cent at 64 x 64); for independent renders the ratio is about 1 for
#: Gaussian noise and above it for heavy-tailed noise (the median of a difference of two heavy-tailed variates' squares
#: exceeds one's), so a ratio of 0.1 is many standard errors below any independent pair: tests/test_intake_pairs.py
#: holds a proper pair and a pair whose noise is correlated by 0.99 on either side.
SAME_PAIR_RATIO = 0.1
#: How much more closely the noise must follow the shape of a tracer's without light sampling than mcrt's
#: (:func:`unsampled_shape`: the difference of the two slopes) for it to be judged as that tracer's. A tracer that
#: finds the light only by bouncing into it is correct and far noisier where the light is direct, while noise of
#: fewer samples keeps mcrt's shape at any level; ``mcrt grade-false-alarms`` reports the statistic of correct renders
#: of both kinds on either side of this bound.
UNSAMPLED_SHAPE = 0.7
#: The least body of the noise (:func:`body_ratio`) against that tracer's model at the declared spp for the noise to be
#: judged as its: a correct one's is near 1, less at few samples (heavy tails shrink the median), while a bias under
#: noise of mcrt's shape, which the shape alone can take for it, gives far less (the false-alarm report shows correct
#: renders' bodies; tests/test_explain_programs.py's bounce drawn otherwise with the floor brighter is such a bias).
UNSAMPLED_BODY = 0.2
#: The least body of the noise (:func:`body_ratio`) at the declared spp, in what a claimed cause leaves, for that noise
#: to be judged beside the cause (:func:`_beside_claim`). Heavy tails put a correct render's body well below 1 at its
#: spp (the median of squared second differences is far below their mean), so a body of 1 is noise several times
#: the declared spp's, not a bias the cause left: tests/test_feedback.py holds a wrong albedo at 16 spp (claimed
#: beside it) and at 256 (not).
BESIDE_BODY = 1.0
#: The most a claimed cause may change a pixel's value, relative, for the noise there to be judged as the
#: reference's (:func:`_beside_claim`): a pixel's noise grows with its value, by about as much.
UNCHANGED = 0.1
#: The body of a correct render's noise at its spp (:func:`body_ratio`, in ``details["noise"]["body"]``) at a few
#: hundred spp, about: heavy tails put the median of squared second differences far below their mean, the more so
#: at fewer samples (at thousands the tails thin and it grows, which only makes :func:`removed` the stricter there).
CORRECT_BODY = 0.2
#: How many times less than :data:`CORRECT_BODY` the body of the noise must be for the noise to be judged taken out
#: (:func:`removed`): mistakes that leave the noise in place but lessen it (a path cut short) stay within about
#: twice, filters that keep edges go beyond five times; the bound lies between, and tests/test_grade.py holds a
#: total-variation denoiser beyond it and mistakes of the scene and camera within it.
REMOVED = 3.0
#: Fewest second differences :func:`unsampled_shape` fits, and :func:`least_body` judges on a surface.
MIN_DIFFERENCES = 64
#: The largest share of the image's second differences that are exactly 0 (:func:`tied_share`) for its excess to be
#: read as the noise of a tracer without light sampling: a tracer's noise leaves neighbouring pixels unequal, even
#: through an 8-bit file, while a coarse rounding (a web palette) ties many of them, and its errors, larger where the
#: light is, have that tracer's shape (tests/test_grade.py). Nor is it read as fewer samples beside a claimed cause
#: (:func:`_beside_claim`), nor its want of noise as a denoiser's (:func:`removed`).
MAX_TIES = 0.1


def measure(g: Grading, hand: Hand, clip_mask: np.ndarray) -> Level:
    """Noise level: 1 / (samples per grade pixel) of an mcrt-like estimator, and the verdict it would get."""
    a, ctx = g.a, g.ctx
    model_ps = ctx.model_var[hand.cam].astype(np.float64)  # mcrt per-sample variance at the grade resolution
    ref_noise = hand.ref.var.astype(np.float64) / hand.ref.spp
    if hand.n_r == 2:
        _pair_check(g, hand, clip_mask, model_ps, ref_noise)
    imgs, qvar, n_r = hand.imgs, hand.qvar, hand.n_r
    img = imgs[0] if n_r == 1 else 0.5 * (imgs[0] + imgs[1])
    q = qvar[0] if n_r == 1 else 0.25 * (qvar[0] + qvar[1])
    pair = 0.25 * (imgs[0] - imgs[1]) ** 2 if n_r == 2 else None
    if pair is not None:
        pair = np.where(np.isfinite(pair), pair, 0.0)
    resid = np.where(hand.mask[..., None], img - hand.R, 0.0)
    per = n_r * hand.k_down**2
    nominal = hand.spp or a.min_spp
    ratio = noise_ratio(resid, hand.R, clip_mask, model_ps, ref_noise + q, hand.base_tile, pair)
    # Noisier than the declared spp allows: the noise of fewer samples, or of a correct tracer without light
    # sampling, which the shape of the noise tells apart (unsampled_shape), where the excess is in the noise's body
    # (a few pixels far off, black ones written over a correct render, raise the spread but not the body).
    unsampled, shape, body_un = 0.0, None, None
    model_un = ctx.model_var_unsampled.get(hand.cam)
    body = body_ratio(resid, model_ps / (nominal * per) + ref_noise + q, clip_mask, ctx.labels[hand.cam])
    if model_un is not None:  # measured always: the false-alarm report shows it for every correct render
        shape = unsampled_shape(resid, model_ps / (nominal * per) + ref_noise + q,
                                model_un / (nominal * per) + ref_noise + q, clip_mask, ctx.labels[hand.cam])
        excess = min(nominal * per * ratio, body)
        noisy = clip_mask & (model_un @ LUMINANCE**2 > 0)  # the light's own pixels hold no noise to tie
        if excess > g.th.max_noise_ratio and shape > UNSAMPLED_SHAPE and tied_share(img, noisy, ctx.labels[hand.cam]) \
                <= MAX_TIES:
            body_un = body_ratio(resid, model_un / (nominal * per) + ref_noise + q, clip_mask, ctx.labels[hand.cam])
        if body_un is not None and body_un >= UNSAMPLED_BODY:
            un_ratio = noise_ratio(resid, hand.R, clip_mask, model_un.astype(np.float64), ref_noise + q,
                                   hand.base_tile, pair)
            unsampled = ratio / un_ratio if un_ratio > 0 else 0.0  # as many times less noisy with light sampling
            model_ps, ratio = model_un.astype(np.float64), un_ratio
    spp_eff = _spp(ratio, per)
    # Away from the light's edges too: a sub-pixel change of its outline (the light a little lower) is many noise
    # deviations there and reads as noise of far fewer samples; the verdict says where the excess is.
    away = clip_mask & ~beside_emitters(model_ps @ LUMINANCE**2, clip_mask)
    spp_away = _spp(noise_ratio(resid, hand.R, away, model_ps, ref_noise + q, hand.base_tile, pair), per)
    # ... and away from every sharp edge: the view or an object a fraction of a pixel off, or each pixel's samples
    # spread otherwise over it, changes every outline by many noise deviations at a high spp.
    smooth = away & ~sharp_edges(hand.R, model_ps / (nominal * per) + ref_noise + q, clip_mask)
    spp_smooth = _spp(noise_ratio(resid, hand.R, smooth, model_ps, ref_noise + q, hand.base_tile, pair), per)
    # The difference of two renders holds no bias; one render's tile spreads hold it as well as the noise.
    if unsampled:
        body = body_ratio(resid, model_ps / (nominal * per) + ref_noise + q, clip_mask, ctx.labels[hand.cam])
    spp_broad = spp_eff if pair is not None else _broad(nominal, spp_eff, body)
    g.details["noise"] = {"spp_declared": hand.spp, "renders": n_r,
                          "spp_effective": None if not np.isfinite(spp_eff) else spp_eff,
                          "spp_broad": None if not np.isfinite(spp_broad) else spp_broad,
                          "spp_away_from_light_edges": None if not np.isfinite(spp_away) else spp_away,
                          "spp_away_from_edges": None if not np.isfinite(spp_smooth) else spp_smooth,
                          "body": body if np.isfinite(body) else None, "unsampled_shape": shape, "unsampled_body": body_un,
                          "unsampled": unsampled or None}
    spp = hand.spp
    # var_ratio, spp_model and the verdict are set by _declared or _undeclared.
    lvl = Level(img=img, q=q, pair=pair, resid=resid, clip_mask=clip_mask, model_ps=model_ps, ref_noise=ref_noise,
                per=per, spp_eff=spp_eff, var_ratio=0.0, spp_nominal=spp or a.min_spp, spp_model=0,
                verdict=("passed", "", False), spp_broad=spp_broad, spp_away=spp_away, spp_smooth=spp_smooth,
                smooth=smooth, unsampled=unsampled)
    if spp:
        _declared(g, lvl, spp)
    else:
        _undeclared(g, lvl)
    g.details["noise"]["spp_model"] = lvl.spp_model
    lvl.noise = Noise(model=model_ps / (lvl.spp_model * per) + q, reference=ref_noise, pair=pair)
    return lvl


def unsampled_shape(resid: np.ndarray, var_sampled: np.ndarray, var_unsampled: np.ndarray, mask: np.ndarray,
                    labels: np.ndarray) -> float:
    """Whether the noise has the shape of a tracer's without light sampling rather than mcrt's: the slope of log d^2
    on log s_u^2 less that on log s^2, fitted together by least squares, where d is a second difference of the
    residual's luminance within one surface (a smooth bias cancels) and s^2, s_u^2 its variance under each model
    (v0 + 4 v1 + v2). Noise of either shape at any level gives its own model the larger slope (a level only moves
    the intercept); NaN with too few differences."""
    lum = LUMINANCE**2
    vs, vu = var_sampled @ lum, var_unsampled @ lum
    keep = mask & (vs > 0) & (vu > 0)
    runs = surface_runs(np.stack([np.where(keep, resid @ LUMINANCE, 0.0), vs, vu], axis=-1), keep, labels, 3)
    (e0, e1, e2), (s0, s1, s2), (u0, u1, u2) = runs[..., 0].T, runs[..., 1].T, runs[..., 2].T
    d = e0 - 2 * e1 + e2
    nz = d != 0
    y = np.log(d[nz] ** 2)
    if y.size < MIN_DIFFERENCES:
        return float("nan")
    x = np.column_stack([np.ones_like(y), np.log((s0 + 4 * s1 + s2)[nz]), np.log((u0 + 4 * u1 + u2)[nz])])
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    return float(coef[2] - coef[1])


def tied_share(img: np.ndarray, mask: np.ndarray, labels: np.ndarray) -> float:
    """The share of the image's second differences within one surface (luminance) that are exactly 0: neighbours of
    equal value, which a tracer's noise leaves unequal and a coarse rounding (a palette, a banded encoding) makes.
    Runs of black pixels are left out: at a few samples a tracer without light sampling leaves pixels whose paths all
    missed the light at 0."""
    runs = surface_runs(np.where(mask, np.nan_to_num(img) @ LUMINANCE, 0.0), mask, labels, 3)
    e0, e1, e2 = runs[(runs != 0).any(axis=1)].T  # black runs left out: paths that found no light
    d = e0 - 2 * e1 + e2
    return float(np.count_nonzero(d == 0)) / d.size if d.size else 1.0


def same_pair(a: np.ndarray, b: np.ndarray, R: np.ndarray, var: np.ndarray, mask: np.ndarray,
              labels: np.ndarray) -> tuple[bool, float]:
    """(whether two renders share their noise, the ratio of their difference's noise to one render's).

    The ratio is the body (:func:`body_ratio`) of (a - b) / sqrt(2) over that of a - R: about 1 or more for
    independent renders (the difference of two holds twice one's noise variance; :data:`SAME_PAIR_RATIO`), about
    1 - rho times that for renders whose noise is correlated by rho, 0 for identical ones. Second differences within surfaces cancel a smooth bias, so a biased pair is judged by
    its noise alone. They share it when identical, or when the ratio is below :data:`SAME_PAIR_RATIO`."""
    keep = mask & np.isfinite(a).all(axis=2) & np.isfinite(b).all(axis=2)
    if np.array_equal(np.where(keep[..., None], a, 0.0), np.where(keep[..., None], b, 0.0)):
        return True, 0.0
    one = body_ratio(np.where(keep[..., None], a - R, 0.0), var, keep, labels)
    diff = body_ratio(np.where(keep[..., None], (a - b) / np.sqrt(2.0), 0.0), var, keep, labels)
    ratio = diff / one if one > 0 and np.isfinite(one) else float("nan")
    return bool(ratio < SAME_PAIR_RATIO), ratio


def _pair_check(g: Grading, hand: Hand, clip_mask, model_ps, ref_noise) -> None:
    """Two renders whose noise is the same (one seed): the pair cannot measure the noise, so the first is graded
    alone with the noise model of one render, and the noise criterion says why (:func:`verdict`)."""
    nominal = hand.spp or g.a.min_spp
    var = model_ps / (nominal * hand.k_down**2) + ref_noise + hand.qvar[0]
    same, ratio = same_pair(hand.imgs[0], hand.imgs[1], hand.R, var, clip_mask, g.ctx.labels[hand.cam])
    g.details["pair"] = {"same_noise": same, "noise_ratio": None if not np.isfinite(ratio) else round(ratio, 4)}
    if not same:
        return
    what = ("your two renders are identical" if ratio == 0 else
            f"your two renders' noise is nearly the same (the difference of the two has {ratio:.2g} times the "
            f"noise variance of independent renders, below {SAME_PAIR_RATIO:g} they are taken as one seed)")
    g.details["pair"]["text"] = (f"{what}: render them with different seeds (the difference of two independent "
                                 "renders measures the noise); the noise was taken from the model of one render "
                                 "instead, and the first render was graded alone")
    for lst in (hand.imgs, hand.qvar, hand.diag_imgs):
        del lst[1:]


def body_ratio(resid: np.ndarray, var: np.ndarray, mask: np.ndarray, labels: np.ndarray, *, min_n: int = 1) -> float:
    """The body of the noise over the model's: the median squared second difference within a surface over a
    Gaussian's, in luminance, normalised by the model's variance ``var`` (a ramp of bias cancels; a step at an
    object's border is never crossed; an edge inside one holds a few differences, which the median ignores).
    Heavy tails make it smaller than the variance ratio: it bounds how much of a measured excess is noise. Infinite
    with no differences, NaN with fewer than ``min_n``."""
    keep = mask & (var @ LUMINANCE**2 > 0)
    v = np.where(keep, var @ LUMINANCE**2, 0.0)
    x1, _, _ = second_differences(np.where(keep, resid @ LUMINANCE, 0.0), v, keep, labels)
    if x1.size < min_n:
        return float("nan")
    return float(np.median(x1 * x1) / _sps.chi2.ppf(0.5, 1)) if x1.size else float("inf")


def _broad(nominal: int, spp_eff: float, body: float) -> float:
    """The samples per pixel of the noise a single render's excess may be credited with (module docstring); an
    image with no measurable noise (spp_eff infinite: a noise-free or constant hand-in) has infinitely many."""
    excess = min(nominal / spp_eff, NOISE_BODY * max(1.0, body))
    return nominal / excess if excess > 0 else float("inf")


def _spp(ratio: float, per: int) -> float:
    return (1.0 / ratio) / per if np.isfinite(ratio) and ratio > 0 else float("inf")


def _follows_noise(lvl: Level, nominal: int, max_ratio: float) -> bool:
    """Whether the noise model may follow the measured noise: the excess is broad (module docstring)."""
    return np.isfinite(lvl.spp_broad) and nominal / lvl.spp_broad > max_ratio


def _declared(g: Grading, lvl: Level, spp: int) -> None:
    a, th, spp_eff = g.a, g.th, lvl.spp_eff
    lvl.spp_model = spp
    lvl.var_ratio = var_ratio = spp / spp_eff if np.isfinite(spp_eff) else 0.0
    if spp < a.min_spp:
        lvl.verdict = ("failed", f"you declared {spp} samples per pixel; the assignment asks for at least {a.min_spp}", True)
    elif lvl.unsampled and var_ratio <= th.max_noise_ratio:
        lvl.verdict = ("passed", unsampled_text(spp, spp_eff, lvl.unsampled), False)
    elif var_ratio > th.max_noise_ratio:
        # Trust the noise, not the declaration, where the excess is broad: a render whose noise belongs to
        # fewer samples would otherwise be judged with too small a noise model.
        if _follows_noise(lvl, spp, th.max_noise_ratio):
            lvl.spp_model = max(1, min(spp, int(lvl.spp_broad)))
        lvl.verdict = ("failed", claim_text(var_ratio, spp, spp_eff, th.max_noise_ratio, unsampled=bool(lvl.unsampled)),
                       False)
        if (np.isfinite(lvl.spp_away) and spp / lvl.spp_away <= th.max_noise_ratio
                and lvl.spp_away >= EDGE_EXCESS * spp_eff):
            lvl.edge_excess = True
            lvl.verdict = ("failed", edge_text(var_ratio, spp, spp_eff, lvl.spp_away), False)
        elif (np.isfinite(lvl.spp_smooth) and spp / lvl.spp_smooth <= th.max_noise_ratio
              and lvl.spp_smooth >= EDGE_EXCESS * spp_eff):
            # Not edge_excess: the catalogue at pixel level may still tell which change of the edges it is (no jitter).
            lvl.verdict = ("failed", edges_text(var_ratio, spp, spp_eff, lvl.spp_smooth), False)
    else:
        extra = ""
        if 0 < var_ratio < 1 / MORE_EFFICIENT:
            extra = (f"; it is less noisy than mcrt at {spp} spp (like about {spp_text(spp_eff)} spp): more samples "
                     "than declared, a better estimator, or a denoiser")
        lvl.verdict = ("passed", f"noise consistent with {spp} spp (like mcrt with about {spp_text(spp_eff)} spp){extra}", False)
    if 0 < var_ratio < 1 / MORE_EFFICIENT**2 and np.isfinite(spp_eff):
        # Far less noise than the declared spp implies: the noise model follows the image (with a
        # margin), so that declaring few samples cannot hide a bias behind an inflated noise model.
        lvl.spp_model = max(lvl.spp_model, int(spp_eff / MORE_EFFICIENT))
        g.notes.append(f"the declared {spp} spp does not match the image's noise (like mcrt with about "
                       f"{spp_text(spp_eff)} spp); the bias test assumed {lvl.spp_model} spp")


def unsampled_text(spp: int, spp_eff: float, times: float) -> str:
    """The noise criterion's pass for noise shaped like a tracer's without light sampling (:func:`unsampled_shape`)."""
    return (f"noise consistent with {spp} spp of a tracer without light sampling (like mcrt without next-event "
            f"estimation at about {spp_text(spp_eff)} spp): the noise is largest where the light is direct, as when the "
            f"light is found only by bouncing into it; sampling the light at each diffuse bounce (next-event "
            f"estimation) would make it about {times:.0f}x less noisy at the same spp")


def claim_text(var_ratio: float, spp: int, spp_eff: float, max_ratio: float, *, unsampled: bool = False) -> str:
    """The noise criterion's failure for a declared spp, in the student's terms: how many times noisier than the
    declared spp should be, and what spp the noise is like (``unsampled``: of a tracer without light sampling,
    whose shape the noise has)."""
    times = f"{var_ratio:.1f}" if var_ratio < 10 else f"{var_ratio:.0f}"
    if unsampled:
        return (f"about {times}x noisier than {spp} spp should be even for a tracer without light sampling, whose "
                f"shape the noise has (largest where the light is direct): like mcrt without next-event estimation at "
                f"about {spp_text(spp_eff)} spp (up to {max_ratio:g}x is accepted); render more samples, check the spp "
                "you declared and that each pass or batch draws new random numbers, and sample the light at each "
                "diffuse bounce (next-event estimation), which makes the noise far smaller")
    return (f"about {times}x noisier than {spp} spp should be: like about {spp_text(spp_eff)} spp (noise "
            f"variance against mcrt's at {spp} spp; up to {max_ratio:g}x is accepted, for estimators less efficient "
            "than mcrt's); render more samples, check the spp you declared and that each pass or batch draws new random "
            "numbers (a seed of its own: passes that repeat one seed add no information), or reduce your estimator's "
            "variance (next-event estimation)")


def edge_text(var_ratio: float, spp: int, spp_eff: float, spp_away: float) -> str:
    """The noise criterion's failure where the excess lies on the light's outline alone: no claim of fewer samples."""
    return _excess_on("light's edges", "light's outline, which differs", var_ratio, spp, spp_eff, spp_away) + (
        "the light's position, size or shape a little off, the camera's view a little off (its field of view, place "
        "or direction: the light's outline is the image's sharpest edge, the first to show it), or its bright "
        "edge pixels changed after rendering (a firefly or outlier filter, a clamp)")


def _excess_on(away: str, on: str, var_ratio: float, spp: int, spp_eff: float, spp_away: float) -> str:
    """The words the noise criterion's failures open with where the excess lies on some pixels alone (``on``, with its
    verb) and away from them (``away``) the noise is as the declared spp gives."""
    times = f"{var_ratio:.1f}" if var_ratio < 10 else f"{var_ratio:.0f}"
    return (f"about {times}x the spread {spp} spp should give (like about {spp_text(spp_eff)} spp), but away from the "
            f"{away} the noise is as at {spp} spp (like about {spp_text(spp_away)}): the excess is on the {on} from the "
            "reference by more than noise, not noise of fewer samples: ")


#: A pixel is on a sharp edge where the reference's luminance changes across EDGE_SHIFT of a pixel by more than the
#: noise deviation of the declared spp (:func:`sharp_edges`).
EDGE_SHIFT = 0.25
#: The excess is read as the edges' (the light's, or every sharp one) where the spread away from them is this many
#: times less (in spp) than over the whole image: fewer samples raise both alike, and a render a little past the limit
#: everywhere, which by chance measures a little less noisy away from the edges, is no edge changed.
EDGE_EXCESS = 1.5


def sharp_edges(R: np.ndarray, var: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(H, W) the pixels of ``mask`` where moving the reference ``R`` by :data:`EDGE_SHIFT` of a pixel changes its
    luminance by more than the noise deviation ``var`` (each pixel mean's variance) gives, and their 4 neighbours: where
    a change of the view, of an object's place or of each pixel's footprint a fraction of a pixel wide reads as noise."""
    lum = R @ LUMINANCE
    p = np.pad(lum, 1, mode="edge")
    grad = np.hypot(0.5 * (p[1:-1, 2:] - p[1:-1, :-2]), 0.5 * (p[2:, 1:-1] - p[:-2, 1:-1]))
    sd = np.sqrt(np.maximum(var @ LUMINANCE**2, 0.0))
    return ndimage.binary_dilation(mask & (EDGE_SHIFT * grad > sd)) & mask


def edges_text(var_ratio: float, spp: int, spp_eff: float, spp_smooth: float) -> str:
    """The noise criterion's failure where the excess lies on the image's sharp edges: no claim of fewer samples."""
    return _excess_on("image's sharp edges", "edges (the light's and the objects' outlines, the room's corners), which "
                      "differ", var_ratio, spp, spp_eff, spp_smooth) + (
        "the camera's view a fraction of a pixel off (its field of view, place or direction), each pixel's samples "
        "spread otherwise over it (too few sub-pixel positions, offsets not uniform over its square, a pixel filter "
        "other than a box), or the image resampled or filtered after rendering")


def misplaced_lines(img: np.ndarray, R: np.ndarray, var: np.ndarray, mask: np.ndarray) -> tuple[str, int, int] | None:
    """('rows' or 'columns', how many, of how many) of the lines of img that match a line of R a few places away
    better than their own (:func:`mcrt.grade.explain.layout.moved_lines`), or None where too few do."""
    from mcrt.grade.explain.layout import moved_lines

    w = np.where(mask[..., None] & np.isfinite(img), 1.0 / np.maximum(var, 1e-30), 0.0)
    found = moved_lines(np.where(w > 0, img, 0.0), R, w)
    return None if found is None else (found[0], int(np.count_nonzero(found[1] != np.arange(len(found[1])))),
                                       len(found[1]))


def lines_text(word: str, k: int, n: int) -> str:
    """The noise criterion's failure where lines of the image are out of order (:func:`misplaced_lines`)."""
    return (f"{k} of the image's {n} {word} match a neighbouring {word[:-1]} of the reference better than their own, "
            f"by far more than noise: {word} stored out of order (written in the order a pool of workers finished "
            f"them, or an index off by one for some of them), not noise of fewer samples")


def _undeclared(g: Grading, lvl: Level) -> None:
    a, th, spp_eff = g.a, g.th, lvl.spp_eff
    lvl.var_ratio = var_ratio = a.min_spp / spp_eff if np.isfinite(spp_eff) else 0.0
    # Below the limit the model follows the noise; beyond it, only a broad excess (else the broad estimate).
    follows = var_ratio <= th.max_noise_ratio or _follows_noise(lvl, a.min_spp, th.max_noise_ratio)
    spp_m = spp_eff if follows else lvl.spp_broad
    lvl.spp_model = max(1, min(a.spp, int(spp_m))) if np.isfinite(spp_m) else a.spp
    like = "mcrt without light sampling" if lvl.unsampled else "mcrt"
    if var_ratio > th.max_noise_ratio:
        lvl.verdict = ("failed", (f"spp not declared, and the noise is like {like} with about {spp_text(spp_eff)} "
                                  f"spp, far fewer than the {a.min_spp} asked for at least; render more samples (and "
                                  "declare them in a manifest)"), False)
    else:
        lvl.verdict = ("passed", (f"spp not declared (add a manifest with `spp = N`); the noise is like {like} "
                                  f"with about {spp_text(spp_eff)} spp"), False)


def verdict(g: Grading, hand: Hand, lvl: Level, bt, found: dict[str, str], flagged: bool) -> None:
    """The ``noise`` criterion, now that the bias test is known (``flagged``: it failed)."""
    from mcrt.grade.stages.explanation import explain_excess_noise

    status, text, firm = lvl.verdict
    for k in ("filter", "denoised"):
        if k in found:
            status, text, firm = "failed", found[k], True
    same = (g.details.get("pair") or {}).get("text")
    if same:  # a pair with one seed loses the noise points whatever else is found; a firm finding is kept beside it
        g.rubric.set("noise", "failed", same + (f"; also, {text}" if status == "failed" and firm else ""))
        return
    # The excess is lines out of order: no noise of fewer samples. Only where the bias test and the exposure passed:
    # against a biased or darker image every line's chi^2 is large, and a darker line's may be the smaller.
    biased = flagged or any(r.status == "failed" for n, r in g.rubric.results.items() if n in ("unbiased", "exposure"))
    if status == "failed" and not firm and not biased:
        lines = misplaced_lines(lvl.img, hand.R, lvl.model_ps / (lvl.spp_nominal * lvl.per) + lvl.ref_noise + lvl.q,
                                lvl.clip_mask)
        if lines is not None:
            g.rubric.set("noise", status, lines_text(*lines))
            return
    if not biased and not firm:
        # Noise that repeats between pixels apart (the same random numbers): the mean is right, the level may be too.
        found_rep = shared_numbers(g, hand, lvl)
        if found_rep is not None:
            g.rubric.set("noise", "failed", found_rep + (f"; also, {text}" if status == "failed" else ""))
            return
    beside = _beside_claim(g, hand, lvl) if status == "failed" and not firm and flagged and hand.spp else None
    if beside is not None:
        text = beside_text(beside, hand.spp, g.th.max_noise_ratio)
    elif status == "failed" and not firm and flagged:
        status, text = "passed", (f"not judged: the image is biased, so its noise cannot be compared with a correct "
                                  f"renderer's (it is like mcrt with about {spp_text(lvl.spp_eff)} spp)")
    elif status == "failed" and not firm:
        # Excess pixel-to-pixel deviation with unbiased tiles: noise, or a deterministic error that
        # cancels within tiles (aliasing). Only the catalogue at pixel level can tell. The bias test found no
        # bias, so the measured excess is taken as noise (rare huge samples have a narrow body: stages.noise).
        if np.isfinite(lvl.spp_eff) and lvl.spp_eff < lvl.spp_model:
            lvl.spp_model = max(1, int(lvl.spp_eff))
            lvl.noise = Noise(model=lvl.model_ps / (lvl.spp_model * lvl.per) + lvl.q, reference=lvl.ref_noise,
                              pair=lvl.pair)
        if not lvl.edge_excess:  # an outline that differs is no noise pattern of the catalogue's
            more = explain_excess_noise(g, hand, lvl)
            if g.details.get("noise", {}).get("excess_in_few_pixels"):
                text = few_pixels_text(lvl.var_ratio, lvl.spp_nominal)
            text += more
    g.rubric.set("noise", status, text)


def shared_numbers(g: Grading, hand: Hand, lvl: Level) -> str | None:
    """The finding of noise that repeats between pixels apart (:func:`mcrt.grade.copytest.repeats` on the luminance
    residual, its variance the noise model's), or None; its statistics go to ``details["noise"]["repeats"]``."""
    from mcrt.grade.copytest import repeats

    var = (lvl.noise.model + lvl.noise.reference) @ LUMINANCE**2
    r = repeats(lvl.resid @ LUMINANCE, var, lvl.clip_mask, g.ctx.labels[hand.cam])
    g.details.setdefault("noise", {})["repeats"] = r.to_dict()
    return repeats_text(r) if r.repeats else None


def _beside_claim(g: Grading, hand: Hand, lvl: Level) -> float | None:
    """The noise beside a claimed cause: where the explanation stage claims a cause (what it leaves passes the bias
    test) of a family that leaves each sample's noise alone (:func:`~mcrt.grade.explain.families.keeps_noise`), the spp
    that what it leaves is like, if that is more than the rubric's ratio below the declared spp and the noise exceeds
    :data:`BESIDE_BODY` on every surface (:func:`least_body`) where the cause changes each channel by at most
    :data:`UNCHANGED` of its value, and that is most of the image, and neighbouring pixels do not tie
    (:data:`MAX_TIES`: a coarse palette's rounding is noise-like too); None otherwise. There the scene is the
    reference's, and so is its noise, where the cause is local (a cause that changes the whole view, a light moved
    into the room, changes the noise where the mean hardly moves too). Every surface: fewer samples multiply every
    pixel's variance by one factor, while noise a mistake makes itself (samples binned by rounding, whose count
    varies) sits where it acts. The body as well as the spread: the remainder passed a test whose noise model may
    have followed the bias (:data:`NOISE_BODY`), and a median of second differences within surfaces holds no smooth
    bias."""
    from mcrt.grade.explain.families import keeps_noise

    e = g.explanation
    if e is None or e.named is None or not keeps_noise(e.named):
        return None
    labels = g.ctx.labels[hand.cam]
    if tied_share(lvl.img, lvl.clip_mask, labels) > MAX_TIES:  # a coarse rounding's errors, not fewer samples
        return None
    rem = np.where(lvl.clip_mask[..., None], e.remainder, 0.0)
    var = brightness_scaled(lvl.model_ps / (hand.spp * lvl.per) + lvl.ref_noise + lvl.q, lvl.img, hand.R,
                            lvl.clip_mask, labels, up=True)
    kept = lvl.clip_mask & (np.abs(lvl.resid - rem) <= UNCHANGED * np.abs(hand.R)).all(axis=2)  # each channel
    if 2 * np.count_nonzero(kept) < np.count_nonzero(lvl.clip_mask):
        return None
    noisy = kept & (lvl.model_ps @ LUMINANCE**2 > 0)  # the light's own pixels hold no noise to judge
    if not least_body((lvl.resid, rem), var, noisy, labels) > BESIDE_BODY:  # NaN: too few surfaces to judge
        return None
    # Away from the sharp edges: a first-order fit of a change of the view leaves its second order there.
    spp_eff = _spp(noise_ratio(rem, hand.R, lvl.smooth, lvl.model_ps, lvl.ref_noise + lvl.q, hand.base_tile,
                               lvl.pair), lvl.per)
    return spp_eff if hand.spp > g.th.max_noise_ratio * spp_eff else None


def least_body(readings, var: np.ndarray, mask: np.ndarray, labels: np.ndarray) -> float:
    """The least body of the noise (:func:`body_ratio`) over the surfaces with :data:`MIN_DIFFERENCES` second
    differences within ``mask``, each the smaller over ``readings`` (the residual against the reference holds what the
    cause changes there, the remainder after its predicted change the noise of the renders that predicted it: each
    can only add); NaN where fewer than two surfaces have that many."""
    bodies = [min(body_ratio(r, var, mask & (labels == k), labels, min_n=MIN_DIFFERENCES) for r in readings)
              for k in np.unique(labels[mask])]
    bodies = [b for b in bodies if np.isfinite(b)]
    return min(bodies) if len(bodies) >= 2 else float("nan")


def brightness_scaled(var: np.ndarray, img: np.ndarray, R: np.ndarray, mask: np.ndarray, labels: np.ndarray, *,
                      up: bool) -> np.ndarray:
    """``var`` with each surface's scaled by the square of the image's mean luminance there over the reference's,
    where that is more than 1 (``up``) or less (not ``up``): a surface brighter or darker than it should be (a larger
    light, a wrong albedo) may carry as much more or less noise, or not (a surface that lost its direct light keeps
    the indirect light's noise; a channel that took another's keeps that one's). Each use scales the way that keeps
    it from a claim the noise does not bear out."""
    lum, ref = np.nan_to_num(img) @ LUMINANCE, R @ LUMINANCE
    out = var.copy()
    for k in np.unique(labels[mask]):
        m = mask & (labels == k)
        r = float(ref[m].mean())
        if r > 0:
            f = (float(lum[m].mean()) / r) ** 2
            out[m] *= max(1.0, f) if up else min(1.0, f)
    return out


def removed(lvl: Level, hand: Hand, labels: np.ndarray) -> float | None:
    """How many times less noise the image holds within its surfaces than a correct render at the declared spp (or
    at the spp its spread is like, if more), if more than :data:`REMOVED`; None otherwise. The body of the noise
    (:func:`body_ratio`, each surface's model scaled down to its brightness: a darker surface is judged by its
    relative noise, a brighter one by the declared model's) against the body a correct render's heavy tails leave
    (:data:`CORRECT_BODY`): a filter that keeps edges (bilateral, total variation, a denoiser) takes the noise out
    of the surfaces, which no mistake of the scene or the estimator does. The spread guards the other reading: a
    render of more samples than declared holds less noise, and its spread says so, while a filter's bias keeps the
    spread up. Not where neighbouring pixels tie (:data:`MAX_TIES`): values clipped to one or rounded coarsely hold no
    noise either, and no filter made them so."""
    if tied_share(lvl.img, lvl.clip_mask, labels) > MAX_TIES:  # flattened by a clip or a rounding, not a filter
        return None
    spp = max(float(lvl.spp_nominal), lvl.spp_eff if np.isfinite(lvl.spp_eff) else 0.0)
    var = brightness_scaled(lvl.model_ps / (spp * lvl.per) + lvl.ref_noise + lvl.q, lvl.img, hand.R, lvl.clip_mask,
                            labels, up=False)
    body = body_ratio(lvl.resid, var, lvl.clip_mask, labels)
    times = CORRECT_BODY / body if body > 0 else float("inf")
    return times if times > REMOVED else None


def beside_text(spp_eff: float, spp: int, max_ratio: float) -> str:
    """The noise criterion's failure beside a claimed cause (:func:`_beside_claim`)."""
    return (f"beside the cause named under 'unbiased', about {spp / spp_eff:.0f}x noisier than {spp} spp should be "
            f"(measured on what that cause leaves, which is noise): like about {spp_text(spp_eff)} spp (up to "
            f"{max_ratio:g}x is accepted); render more samples, check the spp you declared and that each pass or batch "
            "draws new random numbers")


def few_pixels_text(var_ratio: float, spp: int) -> str:
    """The noise criterion's failure where most pixels are quieter than fewer samples would leave them
    (mcrt.grade.stages.explanation's bulk against a correct render's at the samples the variance implies): the excess
    is in a few pixels, and no claim of fewer samples is made."""
    times = f"{var_ratio:.1f}" if var_ratio < 10 else f"{var_ratio:.0f}"
    return (f"about {times}x the spread {spp} spp should give, but from a few pixels: most pixels deviate as little as "
            f"at {spp} spp or less, which fewer samples would not do. The excess is rare, very bright samples (a "
            "singularity: a division by a tiny distance or pdf) or a pattern the samples leave in a few places "
            "(samples that are not random: the light's or the pixel's sample points fixed, strata without jitter); "
            "look at the pixels far from the reference")
