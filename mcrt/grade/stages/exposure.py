"""Exposure: a constant brightness factor that alone explains a failing bias test, or one beyond the limit.

When the tests fail, the image divided by the nearest "nice" factor is
tested again; if that passes, only a constant factor is wrong and the
``exposure`` criterion says so (and, with ``grade_corrected``, the later
criteria grade the rescaled image).
"""

from __future__ import annotations

import numpy as np

from mcrt.grade import checks as ck
from mcrt.grade.stages import bias
from mcrt.grade.stages.state import Grading, Hand, Level
from mcrt.stats.onesample import Noise


def stage(g: Grading, hand: Hand, lvl: Level, t: bias.Tested) -> bias.Tested:
    """The ``exposure`` criterion; returns the tests the later criteria use (the rescaled image's, when corrected)."""
    from mcrt.grade.stages.explanation import explain

    a, th, rub = g.a, g.th, g.rubric
    k = ck.estimate_scale(lvl.img, hand.R, lvl.clip_mask, hand.base_tile)
    stops = float(np.log2(k)) if k > 0 else float("inf")
    scaled = _rescaled(g, hand, lvl, k) if bias.flagged(t.bt) and abs(k - 1) > th.min_effect else None
    g.details["exposure"] = {"ratio": k, "stops": stops}
    if scaled is not None:
        ks = scaled[0]
        f_ = ks if ks >= 1 else 1 / ks
        how = f"{f_:g}" if f_ == round(f_) else f"{f_:.3g}"
        rub.failed("exposure", f"the whole image is {how} times {'brighter' if ks > 1 else 'darker'} than the reference "
                   f"({stops:+.2f} stops); {'divided' if ks > 1 else 'multiplied'} by {how} it passes the bias test, so only a constant factor is "
                   "wrong: an exposure or display scale applied before saving, or a constant missing in the "
                   "estimator (1/pi, the light's radiance or area)")
        e = explain(g, hand, lvl.img, lvl.clip_mask, lvl.noise)
        if e is not None and e.named is not None and e.named.family not in ("scale", "light_radiance"):
            rub.results["exposure"].output += f". Not quite a constant, though: {e.sentence[0].lower()}{e.sentence[1:]}"
        if a.grade_corrected:
            g.corrected.append("exposure")
            return scaled[1]
    elif abs(stops) > th.max_exposure_stops:
        rub.failed("exposure", f"the image is {k:.3g} times as bright as the reference overall ({stops:+.2f} stops, "
                   f"more than the {th.max_exposure_stops:g} allowed); no constant factor makes it match, so "
                   "see the bias test for where it differs")
    else:
        rub.passed("exposure", f"overall brightness {k:.3g} times the reference's ({stops:+.2f} stops)")
    return t


def _rescaled(g: Grading, hand: Hand, lvl: Level, k: float) -> tuple[float, bias.Tested] | None:
    """The image divided by the nearest nice factor, tested again; None when it still fails, or where the image is
    black in patches or lines the light reaches (:func:`mcrt.grade.explain.pixels.black_holes`), which no factor
    lights: the bias test's tiles average rows never written with the rest (three rows in four black read as a
    quarter of the light)."""
    from mcrt.grade.explain.pixels import black_holes
    from mcrt.grade.explain.pixels import directly_lit

    basis = getattr(g.ctx, "explain", None)
    if basis is not None and basis.camera == hand.cam and basis.base.shape == hand.R.shape and \
            black_holes(lvl.img, hand.R, lvl.clip_mask, directly_lit(basis)) is not None:
        return None
    ks = ck.nice_scale(k)
    img_s = lvl.img / ks
    pair_s = lvl.pair / ks**2 if lvl.pair is not None else None
    noise_s = Noise(model=lvl.model_ps / lvl.samples + lvl.q / ks**2, reference=lvl.ref_noise, pair=pair_s)
    resid_s = np.where(lvl.clip_mask[..., None], img_s - hand.R, 0.0)
    ts = bias.test(g, hand, lvl, img_s, resid_s, noise_s)
    return None if bias.flagged(ts.bt) else (ks, ts)
