"""Grading one student's image: the stages of :mod:`mcrt.grade.stages`, in order.

:func:`grade_submission` runs the criteria of the rubric in order
(:data:`mcrt.grade.assignment.CRITERIA`) on one :class:`Submission` against a
prepared :class:`~mcrt.grade.expected.Context` and returns a
:class:`StudentResult`; it never raises on bad student data (a crash inside
it is reported by the caller as a graded failure). :func:`grade_image` grades
an image already in memory (code mode's whole-render check).

Order of work, and what each step does to the image:

1. readable (:mod:`.stages.intake`): read one or two renders (EXR, PFM, HDR,
   PNG); nothing else can be graded without it.
2. resolution (:mod:`.stages.formats`): the asked-for size; an integer
   multiple or divisor is graded after box filtering (exact for a box pixel
   filter) and loses these points; anything else stops grading.
3. finite, non_negative: NaN/inf pixels are left out of the bias test (above
   ``finite.max_fraction`` grading stops); negative values are kept.
4. orientation, camera (:mod:`.stages.calibration`): the best of {cameras} x
   {flips, rotations} by rank correlation; a detected mistake is undone.
5. linear: a gamma or sRGB curve on HDR data is detected and decoded; an
   8-bit image is decoded per hand-in pixel with the curve it was written
   with (:func:`mcrt.grade.checks.detect_png_curve`: sRGB, gamma 2.2, square
   root, linear), its clipped pixels left out of every statistic.
6. A graded image smaller than one tile gets no points for exposure, noise
   and unbiased: nothing can be tested.
7. noise (:mod:`.stages.noise`): the noise level against mcrt's at the
   declared spp (or the spp the noise suggests) and the minimum spp; noise
   correlated between neighbours (a filter) fails it.
8. unbiased (:mod:`.stages.bias`): the multi-scale tile test of
   :mod:`mcrt.stats.onesample` and the structured-error detectors of
   :mod:`mcrt.grade.structure` (misregistration, blur, correlated noise,
   too-dark pixels) under one family-wise error rate; when it fails, a
   constant brightness factor is tried (:mod:`.stages.exposure`) and the
   mistake is explained (:mod:`.stages.explanation`). Points by kind
   (:func:`mcrt.grade.scoring.unbiased_loss`): the camera (a
   misregistration also fails ``camera``) or a surface wrong over most of
   its pixels is major, a filtered image loses ``filter_loss``, a mistake in
   at most ``minor_area`` of the image only ``minor_loss``.
9. exposure: a factor beyond ``exposure.max_stops``, or any constant factor
   that alone explains the failure, loses these points.
10. metrics: RMSE, SSIM, FLIP (clipped pixels left out), informational.

Steps 4, 5 and 9 correct the image for the later steps only when
``grading.grade_corrected`` is true; otherwise the later criteria score 0.
Where step 5 decoded a file with another curve than its format declares
and step 8 then explains it as the render's values at other places (a
memory layout, rows out of order), the curve fitted better only because
the values are elsewhere: the hand-in is graded again decoded as declared,
and that reading stands where it finds the values moved too.
The points are added up by :mod:`mcrt.grade.scoring`, the summary is worded
by :mod:`mcrt.grade.feedback`, and :mod:`mcrt.grade.outputs` writes them out.
"""

from __future__ import annotations

import time
import traceback

import numpy as np

from mcrt.grade.assignment import Assignment
from mcrt.grade.expected import Context
from mcrt.grade.feedback import fmt_pct
from mcrt.grade.scoring import STATUS_ERROR, STATUS_GRADED, STATUS_TIMEOUT, StudentResult, TestResult
from mcrt.grade.stages import bias, calibration, exposure, formats, intake, noise
from mcrt.grade.stages.state import Grading, Hand
from mcrt.grade.submissions import Submission

__all__ = ["STATUS_ERROR", "STATUS_GRADED", "STATUS_TIMEOUT", "StudentResult", "TestResult", "error_result",
           "format_exception", "grade_image", "grade_submission"]


def grade_submission(sub: Submission, ctx: Context) -> StudentResult:
    """Grade one hand-in (see the module docstring)."""
    t0 = time.perf_counter()

    def reading(as_declared: bool) -> Grading:
        g = Grading(ctx, sub.student)
        g.as_declared = as_declared
        try:
            hand, declared_camera = intake.read(g, sub)
            if hand is not None:
                _grade(g, hand, declared_camera)
        except MemoryError:
            g.rubric.block("the grader ran out of memory on this image")
            g.notes.append("grading stopped: out of memory")
        return g

    res = _as_declared_if_moved(reading).result()
    res.elapsed = time.perf_counter() - t0
    return res


def grade_image(student: str, ctx: Context, images: list[np.ndarray], *, spp: int | None, fmt: str = "float",
                notes: list[str] | None = None) -> StudentResult:
    """Grade renders already in memory ((H, W, 3) linear float arrays, one or two)."""
    t0 = time.perf_counter()

    def reading(as_declared: bool) -> Grading:
        g = Grading(ctx, student)
        g.as_declared = as_declared
        g.notes += list(notes or [])
        hand = intake.in_memory(g, images, spp, fmt)
        if hand is not None:
            _grade(g, hand, None)
        return g

    res = _as_declared_if_moved(reading).result()
    res.elapsed = time.perf_counter() - t0
    return res


def _as_declared_if_moved(reading) -> Grading:
    """``reading(False)``, or ``reading(True)`` (the file decoded as declared) where the first decoded it with another
    curve and then found the render's values moved, and the second finds them moved too
    (:func:`.stages.calibration.read_as_declared`)."""
    g = reading(False)
    if calibration.read_as_declared(g):
        again = reading(True)
        if calibration.moved_claim(again):
            return again
    return g


def error_result(student: str, a: Assignment, status: str, message: str, detail: str = "", *,
                 criteria: list[tuple[str, float, str]] | None = None) -> StudentResult:
    """A zero-score result for a student whose grading crashed or timed out.

    ``criteria`` (name, points, title) defaults to the image rubric.
    """
    crit = criteria if criteria is not None else [(c.name, c.points, c.title) for c in a.rubric]
    tests = [TestResult(n, t, 0.0, p, f"not graded: {message}", "visible", "not graded") for n, p, t in crit]
    return StudentResult(student, status, 0.0, sum(p for _, p, _ in crit), tests, f"Not graded: {message}",
                         notes=[detail] if detail else [], details={"error": message, "traceback": detail})


def format_exception() -> str:
    return traceback.format_exc(limit=20)


def _grade(g: Grading, hand: Hand, declared_camera: str | None) -> None:
    """Formats, calibration, then the statistics (the stages after intake)."""
    if not formats.check(g, hand):
        return
    calibration.orientation(g, hand, declared_camera)
    calibration.encoding(g, hand)
    if hand.corrected and not g.a.grade_corrected:
        g.rubric.block(f"the image had to be corrected ({', '.join(hand.corrected)}) and this assignment grades only "
                       "images that need no correction")
        return
    g.corrected = hand.corrected
    _statistics(g, hand)


def _statistics(g: Grading, hand: Hand) -> None:
    """Noise, bias and structure, exposure, explanation, and the informational metrics."""
    gh, gw = hand.R.shape[:2]
    if gh < hand.base_tile or gw < hand.base_tile:
        _too_small(g, gh, gw, hand.base_tile)
        return
    # Display images: pixels the 8-bit range may have clipped are left out of every statistic.
    clip_mask = hand.mask if hand.png_safe is None else hand.mask & hand.png_safe
    n_clip = int(np.count_nonzero(hand.mask & ~clip_mask))
    if n_clip:
        g.notes.append(f"{n_clip} pixels whose expected value is near or above 1 (or next to such a pixel) were "
                       "left out: an 8-bit image clips them (hand in EXR, PFM or HDR to have them graded)")
    lvl = noise.measure(g, hand, clip_mask)
    t = bias.test(g, hand, lvl, lvl.img, lvl.resid, lvl.noise)
    t = exposure.stage(g, hand, lvl, t)
    m = bias.record(g, hand, lvl, t)
    found = bias.findings(g, hand, lvl, t)
    bias.verdict(g, hand, lvl, t, found)
    calibration.confirm_camera(g, hand)
    if "registration" in found:
        g.rubric.failed("camera", found["registration"])
    noise.verdict(g, hand, lvl, t.bt, found, bias.flagged(t.bt))
    calibration.judge_encoding(g, hand, bias.flagged(t.bt))
    if g.encoding in ("srgb", "gamma2.2") and not any(d["mutant"] == "gamma_output" for d in g.diagnosis[:1]):
        gm = g.ctx.mutant_texts.get("gamma_output", "Output gamma-encoded (sRGB) instead of linear radiance.")
        g.diagnosis.insert(0, {"mutant": "gamma_output", "description": gm, "explained": None, "amplitude": None,
                               "where": "the whole image", "chi2": None, "chi2_best_amplitude": None})
    _metrics(g, m, t.bt)


def _metrics(g: Grading, m: dict, bt) -> None:
    text = (f"RMSE {m['rmse']:.4g} ({fmt_pct(m['relative_rmse'])} of the mean; noise alone would give about "
            f"{m['noise_rmse']:.4g})")
    if m.get("ssim") is not None:
        text += f", SSIM {m['ssim']:.3f}"
    if m.get("flip") is not None:
        text += f", FLIP {m['flip']:.3f}"
    text += f", bias beyond noise {fmt_pct(bt.excess_rms)} RMS. These grow with noise and are not graded."
    g.rubric.set("metrics", "info", text)


def _too_small(g: Grading, gh: int, gw: int, tile: int) -> None:
    """A graded image smaller than one tile of the bias test: the bias criteria get no points."""
    msg = (f"not tested: the graded image is {gw}x{gh} pixels, smaller than one {tile}x{tile} tile of the bias test, "
           f"so nothing about it can be tested; hand in {g.a.width}x{g.a.height} pixels")
    for name in ("exposure", "noise", "unbiased"):
        g.rubric.failed(name, msg)
    g.rubric.set("metrics", "info", "not computed: the image is too small to compare")
    g.headline = "Too small to test."
