"""Format checks: the resolution, NaN and infinite pixels, negative values."""

from __future__ import annotations

import numpy as np

from mcrt.grade import checks as ck
from mcrt.grade.expected import coarsen
from mcrt.grade.feedback import fmt_pct
from mcrt.grade.score import quantisation_variance
from mcrt.grade.stages.state import Grading, Hand


def check(g: Grading, hand: Hand) -> bool:
    """Grade the format criteria and bring the images to the grade resolution; False when grading stops."""
    a, rub, loaded = g.a, g.rubric, hand.loaded
    h, w = loaded.images[0].shape[:2]
    plan = ck.plan_resolution(h, w, a.height, a.width, a.grade_height, a.grade_width)
    if not plan.gradeable:
        rub.failed("resolution", plan.message)
        rub.block("the image's resolution cannot be compared with the reference")
        return False
    (rub.passed if plan.ok else rub.failed)("resolution", plan.message)
    g.ctx = coarsen(g.ctx0, plan.coarsen)
    hand.plan = plan
    if not _finite(g, loaded.images):
        return False
    _non_negative(g, loaded.images)
    hand.imgs = [ck.box_down(i, plan.down) for i in loaded.images]
    hand.mask = np.all([np.isfinite(i).all(axis=2) for i in hand.imgs], axis=0)
    hand.qvar = [ck.box_down(quantisation_variance(i, loaded.fmt), plan.down) / plan.down**2 for i in loaded.images]
    return True


def _finite(g: Grading, images) -> bool:
    """NaN and infinite pixels (at the hand-in resolution): left out of the bias test, or too many to grade."""
    th, rub = g.th, g.rubric
    n_bad, frac, msg = ck.check_finite(images[0] if len(images) == 1 else np.stack(images).sum(axis=0))
    if n_bad == 0:
        rub.passed("finite", msg)
    elif frac <= th.max_nonfinite_fraction:
        rub.failed("finite", msg + "; they were left out of the bias test")
    else:
        rub.failed("finite", msg + f"; more than {fmt_pct(th.max_nonfinite_fraction)} of the image, so it cannot be graded")
        rub.block("too many NaN or infinite pixels")
        return False
    return True


def _non_negative(g: Grading, images) -> None:
    """Negative values beyond a tolerance relative to the reference's mean (the first render that has any)."""
    ref0 = g.ctx.references[g.a.camera]
    tol = g.th.negative_tolerance * float(np.mean(np.abs(ref0.mean)))
    n_neg, msg = 0, "no negative values"
    for k_img, im in enumerate(images):
        n_k, msg_k = ck.check_negative(im, tol)
        if n_k:
            n_neg, msg = n_k, (msg_k if k_img == 0 else f"second render: {msg_k}")
            break
    (g.rubric.passed if n_neg == 0 else g.rubric.failed)("non_negative", msg)
