"""Grading one student's image: checks, the noise-fair bias test, diagnosis.

:func:`grade_submission` runs the criteria of the rubric in order
(:data:`mcrt.grade.assignment.CRITERIA`) on one :class:`Submission` against a
prepared :class:`~mcrt.grade.expected.Context` and returns a
:class:`StudentResult`; it never raises on bad student data (a crash inside
it is reported by the caller as a graded failure). :func:`grade_image` grades
an image already in memory (code mode's whole-render check).

Order of work, and what each step does to the image:

1. readable: read one or two renders (EXR, PFM, HDR, PNG); nothing else can
   be graded without it.
2. resolution: the asked-for size; an integer multiple or divisor is graded
   after box filtering (exact for a box pixel filter) and loses these points;
   anything else stops grading.
3. finite, non_negative: NaN/inf pixels are left out of the bias test (above
   ``finite.max_fraction`` grading stops); negative values are kept.
4. orientation, camera: the best of {cameras} x {flips, rotations} by rank
   correlation; a detected mistake is undone.
5. linear: a gamma or sRGB curve on HDR data is detected and decoded; an
   8-bit image is decoded per hand-in pixel with the curve it was written
   with (:func:`mcrt.grade.checks.detect_png_curve`: sRGB, gamma 2.2, square
   root, linear), its clipped pixels left out of every statistic.
6. A graded image smaller than one tile gets no points for exposure, noise
   and unbiased: nothing can be tested.
7. noise: the noise level against mcrt's at the declared spp (or the spp
   the noise suggests) and the minimum spp; noise correlated between
   neighbours (a filter) fails it.
8. unbiased: the multi-scale tile test of :mod:`mcrt.grade.score` and the
   structured-error detectors of :mod:`mcrt.grade.structure`
   (misregistration, blur, correlated noise, too-dark pixels) under one
   family-wise error rate; when it fails, a constant brightness factor is
   tried (exposure). Points by kind (:meth:`_Grader._loss`): the camera
   (a misregistration also fails ``camera``) or a surface wrong over most of
   its pixels is major, a filtered image loses ``filter_loss``, a mistake in
   at most ``minor_area`` of the image only ``minor_loss``.
9. exposure: a factor beyond ``exposure.max_stops``, or any constant factor
   that alone explains the failure, loses these points.
10. metrics: RMSE, SSIM, FLIP (clipped pixels left out), informational.

Steps 4, 5 and 9 correct the image for the later steps only when
``grading.grade_corrected`` is true; otherwise the later criteria score 0.
"""

from __future__ import annotations

import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mcrt.grade import checks as ck
from mcrt.grade.adequacy import Scene2D, judge
from mcrt.grade.assignment import Assignment, Criterion
from mcrt.grade.diagnose import (
    describe_tiles,
    rank_mutants,
    short_text,
    signature_region,
)
from mcrt.grade.expected import Context, coarsen, grading_settings
from mcrt.grade.objects import object_tests
from mcrt.grade.score import (
    LUMINANCE,
    Noise,
    bias_test,
    metrics,
    noise_ratio,
    quantisation_variance,
    scale_stats,
)
from mcrt.grade.structure import detect as detect_structure
from mcrt.grade.structure import families as structure_families
from mcrt.grade.submissions import Submission, choose_images, read_manifest

STATUS_GRADED = "graded"
STATUS_ERROR = "error"
STATUS_TIMEOUT = "timeout"


@dataclass
class TestResult:
    name: str
    title: str
    score: float
    max_score: float
    output: str
    visibility: str = "visible"
    status: str = "passed"  # passed, failed, info, not graded


@dataclass
class StudentResult:
    student: str
    status: str
    score: float
    max_score: float
    tests: list[TestResult]
    summary: str
    notes: list[str] = field(default_factory=list)
    diagnosis: list[dict] = field(default_factory=list)
    details: dict = field(default_factory=dict)
    figures: dict = field(default_factory=dict)  # name -> uint8 image, for feedback
    elapsed: float = 0.0


class _Rubric:
    """Collects test results in rubric order; a blocked rubric scores the rest 0."""

    def __init__(self, a: Assignment):
        self.a = a
        self.results: dict[str, TestResult] = {}
        self.blocked: str | None = None

    def _crit(self, name: str) -> Criterion:
        return self.a.criterion(name)

    def set(self, name: str, status: str, output: str, loss: float = 0.0) -> None:
        c = self._crit(name)
        lost = 1.0 if status == "failed" and loss == 0.0 else loss
        if status in ("passed", "info"):
            lost = 0.0
        score = round(c.points * (1.0 - min(max(lost, 0.0), 1.0)), 4)
        self.results[name] = TestResult(name, c.title, score, c.points, output, c.visibility, status)

    def passed(self, name: str, output: str) -> None:
        self.set(name, "passed", output)

    def failed(self, name: str, output: str, loss: float = 1.0) -> None:
        self.set(name, "failed", output, loss)

    def block(self, reason: str) -> None:
        if self.blocked is None:
            self.blocked = reason

    def finish(self) -> list[TestResult]:
        out = []
        for c in self.a.rubric:
            if c.name in self.results:
                out.append(self.results[c.name])
            else:
                why = f"not graded: {self.blocked}" if self.blocked else "not graded"
                out.append(TestResult(c.name, c.title, 0.0, c.points, why, c.visibility, "not graded"))
        return out


def _num(x: float) -> str:
    return f"{x:.2f}".rstrip("0").rstrip(".")


def _fmt_pct(x: float) -> str:
    return f"{100 * x:.2g} %" if abs(x) < 0.1 else f"{100 * x:.0f} %"


def _spp_text(spp: float) -> str:
    return f"{spp:.0f}" if spp >= 10 else f"{spp:.1f}"


# --------------------------------------------------------------------------
# Entry points
# --------------------------------------------------------------------------


def grade_submission(sub: Submission, ctx: Context) -> StudentResult:
    """Grade one hand-in (see the module docstring)."""
    t0 = time.perf_counter()
    g = _Grader(ctx, sub.student)
    try:
        g.run_files(sub)
    except MemoryError:
        g.rubric.block("the grader ran out of memory on this image")
        g.notes.append("grading stopped: out of memory")
    res = g.result()
    res.elapsed = time.perf_counter() - t0
    return res


def grade_image(student: str, ctx: Context, images: list[np.ndarray], *, spp: int | None, fmt: str = "float",
                notes: list[str] | None = None) -> StudentResult:
    """Grade renders already in memory ((H, W, 3) linear float arrays, one or two)."""
    t0 = time.perf_counter()
    g = _Grader(ctx, student)
    g.notes += list(notes or [])
    loaded = ck.Loaded([np.asarray(i, np.float64) for i in images[:2]], [f"render {k + 1}" for k in range(len(images[:2]))], fmt)
    g.rubric.passed("readable", f"{len(loaded.images)} render(s) returned in memory")
    g.run_loaded(loaded, spp, None)
    res = g.result()
    res.elapsed = time.perf_counter() - t0
    return res


def error_result(student: str, a: Assignment, status: str, message: str, detail: str = "", *,
                 criteria: list[tuple[str, float, str]] | None = None) -> StudentResult:
    """A zero-score result for a student whose grading crashed or timed out.

    ``criteria`` (name, points, title) defaults to the image rubric.
    """
    crit = criteria if criteria is not None else [(c.name, c.points, c.title) for c in a.rubric]
    tests = [TestResult(n, t, 0.0, p, f"not graded: {message}", "visible", "not graded") for n, p, t in crit]
    return StudentResult(student, status, 0.0, sum(p for _, p, _ in crit), tests, f"Not graded: {message}",
                         notes=[detail] if detail else [], details={"error": message, "traceback": detail})


# --------------------------------------------------------------------------
# The grader
# --------------------------------------------------------------------------


class _Grader:
    def __init__(self, ctx: Context, student: str):
        self.ctx0 = ctx
        self.ctx = ctx
        self.a = ctx.assignment
        self.th = self.a.thresholds
        self.student = student
        self.rubric = _Rubric(self.a)
        self.notes: list[str] = []
        self.details: dict = {}
        self.figures: dict = {}
        self.diagnosis: list[dict] = []
        self.headline = ""
        self._chi0 = 0.0
        self.encoding = "linear"
        self.corrected: list[str] = []
        self.explanation = None  # mcrt.grade.explain.Explanation, when the image was explained
        self.adequacy = None  # mcrt.grade.adequacy.Adequacy of what the explanation says

    # -- files ---------------------------------------------------------------
    def run_files(self, sub: Submission) -> None:
        manifest = read_manifest(sub.manifest_path)
        self.notes += sub.notes + manifest.warnings
        if manifest.notes:
            self.details["student_notes"] = manifest.notes
        paths, choice_notes = choose_images(sub, manifest)
        self.notes += choice_notes
        if not paths:
            self.rubric.failed("readable", sub.problem or "no image found")
            self.rubric.block("no readable image")
            return
        loaded, err = ck.read_renders(paths, bool(manifest.linear))
        if loaded is None:
            msg = err if not sub.problem else f"{sub.problem}; {err}"
            self.rubric.failed("readable", msg)
            self.rubric.block("the image could not be read")
            return
        self.notes += loaded.notes
        names = ", ".join(Path(f).name for f in loaded.files)
        # Integer images of every container (PNG, PPM, BMP, TGA) share the formats png8 and png16; name the container.
        container = {".ppm": "PPM", ".pgm": "PGM", ".pnm": "PNM", ".bmp": "BMP", ".tga": "TGA"}.get(
            Path(loaded.files[0]).suffix.lower(), "PNG")
        kinds = {"float": "32-bit float", "half": "16-bit half float", "rgbe": "RGBE", "png8": f"8-bit sRGB {container}",
                 "png16": f"16-bit sRGB {container}", "png8-linear": f"8-bit linear {container}",
                 "png16-linear": f"16-bit linear {container}"}
        h, w = loaded.images[0].shape[:2]
        self.rubric.passed("readable", f"read {names} ({kinds.get(loaded.fmt, loaded.fmt)}, {w}x{h}"
                           f"{', two independent renders' if len(loaded.images) == 2 else ''})")
        spp = manifest.spp or loaded.spp_file
        self.details["spp_source"] = "manifest" if manifest.spp else "file" if loaded.spp_file else "not declared"
        if manifest.camera and manifest.camera != self.a.camera:
            self.notes.append(f"the manifest says camera {manifest.camera!r}; the assignment asks for {self.a.camera!r}")
        self.run_loaded(loaded, spp, manifest.camera)

    # -- images --------------------------------------------------------------
    def run_loaded(self, loaded: ck.Loaded, spp: int | None, declared_camera: str | None) -> None:
        a, th, rub = self.a, self.th, self.rubric
        h, w = loaded.images[0].shape[:2]

        # Resolution.
        plan = ck.plan_resolution(h, w, a.height, a.width, a.grade_height, a.grade_width)
        if not plan.gradeable:
            rub.failed("resolution", plan.message)
            rub.block("the image's resolution cannot be compared with the reference")
            return
        (rub.passed if plan.ok else rub.failed)("resolution", plan.message)
        self.ctx = coarsen(self.ctx0, plan.coarsen)
        self.k_down = plan.down
        n_r = len(loaded.images)

        # Finite and non-negative (at the hand-in resolution).
        n_bad, frac, msg = ck.check_finite(loaded.images[0] if n_r == 1 else np.stack(loaded.images).sum(axis=0))
        if n_bad == 0:
            rub.passed("finite", msg)
        elif frac <= th.max_nonfinite_fraction:
            rub.failed("finite", msg + "; they were left out of the bias test")
        else:
            rub.failed("finite", msg + f"; more than {_fmt_pct(th.max_nonfinite_fraction)} of the image, so it cannot be graded")
            rub.block("too many NaN or infinite pixels")
            return
        ref0 = self.ctx.references[a.camera]
        tol = th.negative_tolerance * float(np.mean(np.abs(ref0.mean)))
        n_neg, msg = 0, "no negative values"
        for k_img, im in enumerate(loaded.images):
            n_k, msg_k = ck.check_negative(im, tol)
            if n_k:
                n_neg, msg = n_k, (msg_k if k_img == 0 else f"second render: {msg_k}")
                break
        (rub.passed if n_neg == 0 else rub.failed)("non_negative", msg)

        imgs = [ck.box_down(i, plan.down) for i in loaded.images]
        mask = np.all([np.isfinite(i).all(axis=2) for i in imgs], axis=0)
        qvar = [ck.box_down(quantisation_variance(i, loaded.fmt), plan.down) / plan.down**2 for i in loaded.images]

        # Orientation and camera.
        ori = ck.detect_orientation(imgs[0], {c: e.mean for c, e in self.ctx.references.items()}, a.camera,
                                    th.orientation_margin)
        self.details["orientation"] = {"camera": ori.camera, "transform": ori.transform,
                                       "rank_correlations_luminance_chroma": ori.correlations}
        corrected = []
        if ori.transform != "identity":
            inv = ck.TRANSFORMS[ori.transform][1]
            imgs, qvar, mask = [inv(i) for i in imgs], [inv(q) for q in qvar], inv(mask)
            rub.failed("orientation", f"the image is {ori.transform} compared with the reference (rank correlation "
                       f"{ori.correlations[f'{ori.camera}/{ori.transform}'][0]:.2f} after undoing it, "
                       f"{ori.correlations[f'{a.camera}/identity'][0]:.2f} as handed in); row 0 must be the top of the "
                       "image and column 0 its left: check the order in which you write rows and columns (and whether "
                       "your camera's up and right vectors point the right way)")
            corrected.append("orientation")
        elif not ori.resembles:
            rub.passed("orientation", "could not be checked: the image does not resemble the scene from any camera")
        else:
            rub.passed("orientation", "as expected (top row first, left column first)")
        if ori.camera != a.camera:
            rub.failed("camera", f"this is the view of the {ori.camera!r} camera, the assignment asks for {a.camera!r}"
                       + (" (the near and far cameras are swapped)" if {ori.camera, a.camera} == {"near", "far"} else "")
                       + (f"; your manifest says {declared_camera!r}" if declared_camera else ""))
            corrected.append("camera")
        else:
            rub.passed("camera", f"the {a.camera!r} camera, as asked")
        cam = ori.camera
        ref = self.ctx.references[cam]
        R = ref.mean.astype(np.float64)
        diag_imgs = [i.copy() for i in imgs]

        # Encoding.
        base_tile = next((t for t in a.tiles if t > 0), 8)
        self.png_safe = None
        if loaded.fmt.startswith("png"):
            self.png_safe = _png_unclipped(R, self.ctx.model_var[cam].astype(np.float64), spp or a.min_spp)
            imgs, qvar = self._png_curve(loaded, plan, ori, R, mask & self.png_safe, base_tile, corrected)
        else:
            imgs, qvar = self._hdr_encoding(loaded, plan, imgs, qvar, R, mask, base_tile, corrected)

        if corrected and not a.grade_corrected:
            rub.block(f"the image had to be corrected ({', '.join(corrected)}) and this assignment grades only images "
                      "that need no correction")
            return
        self.corrected = corrected
        self._grade_statistics(imgs, qvar, mask, R, ref, cam, spp, n_r, loaded.fmt, diag_imgs)

    def _png_curve(self, loaded, plan, ori, R, mask, tile, corrected):
        """A display image's transfer curve (:func:`mcrt.grade.checks.detect_png_curve`), decoded per hand-in pixel."""
        rub, fmt = self.rubric, loaded.fmt
        declared = "linear" if fmt.endswith("linear") else "srgb"
        inv = ck.TRANSFORMS[ori.transform][1]
        codes = [inv(ck.png_codes(i, fmt)) for i in loaded.images]
        cands = {c: [ck.box_down(dec(x), plan.down) for x in codes] for c, (dec, _) in ck.PNG_CURVES.items()}
        enc = ck.detect_png_curve({c: v[0] for c, v in cands.items()}, R, mask, tile, declared)
        curve = enc.curve
        self.details["encoding"] = {"detected": curve, "declared": declared, "curve_chi2": {k: round(v, 2) for k, v in enc.chi2.items()}}
        qvar = [ck.box_down(ck.curve_quantisation_variance(x, curve, fmt), plan.down) / plan.down**2 for x in codes]
        what = ck.PNG_CURVES[curve][1]
        if curve == declared:
            rub.passed("linear", "sRGB-encoded image, decoded to linear" if curve == "srgb" else "linear image, as declared")
        elif curve == "linear":
            rub.failed("linear", "the PNG holds linear values but PNGs are read as sRGB-encoded: declare `linear = true` in "
                       "your manifest, or encode with the sRGB curve before writing 8-bit files")
            corrected.append("linear")
        elif declared == "linear":
            rub.failed("linear", f"the manifest declares the image linear, but its values follow {what}; it was decoded "
                       "with that curve: leave `linear` out of the manifest for a gamma-encoded image")
            corrected.append("linear")
        else:
            text = (f"written with {what} rather than the sRGB curve; decoded with it (the sRGB curve is the standard "
                    "one for 8-bit files)")
            if self.th.png_gamma_loss > 0:
                rub.failed("linear", text, loss=self.th.png_gamma_loss)
                corrected.append("linear")
            else:
                rub.passed("linear", text)
        return cands[curve], qvar

    def _hdr_encoding(self, loaded, plan, imgs, qvar, R, mask, base_tile, corrected):
        """A gamma or sRGB curve on data that should be linear radiance (:func:`mcrt.grade.checks.detect_encoding`)."""
        rub = self.rubric
        enc = ck.detect_encoding(imgs[0], R, mask, loaded.fmt, base_tile)
        self.details["encoding"] = {"detected": enc.kind, "spreads": {k: round(v, 4) for k, v in enc.spreads.items()}}
        self.encoding = enc.kind
        if enc.kind != "linear":
            rub.failed("linear", enc.message)
            dec = ck.ENCODINGS[enc.kind][0]
            imgs = [dec(i) for i in imgs]
            qvar = [quantisation_variance(i, loaded.fmt) / plan.down**2 for i in imgs]
            corrected.append("linear")
        else:
            rub.passed("linear", "linear radiance")
        return imgs, qvar

    # -- statistics ------------------------------------------------------------
    def _grade_statistics(self, imgs, qvar, mask, R, ref, cam, spp, n_r, fmt, diag_imgs) -> None:
        a, th, rub, ctx = self.a, self.th, self.rubric, self.ctx
        k2 = self.k_down**2
        model_ps = ctx.model_var[cam].astype(np.float64)  # mcrt per-sample variance at the grade resolution
        ref_noise = ref.var.astype(np.float64) / ref.spp
        img = imgs[0] if n_r == 1 else 0.5 * (imgs[0] + imgs[1])
        q = qvar[0] if n_r == 1 else 0.25 * (qvar[0] + qvar[1])
        pair = 0.25 * (imgs[0] - imgs[1]) ** 2 if n_r == 2 else None
        if pair is not None:
            pair = np.where(np.isfinite(pair), pair, 0.0)
        base_tile = next((t for t in a.tiles if t > 0), 8)
        gh, gw = R.shape[:2]
        if gh < base_tile or gw < base_tile:
            self._too_small(gh, gw, base_tile)
            return
        # Display images: pixels the 8-bit range may have clipped are left out of every statistic.
        clip_mask = mask if self.png_safe is None else mask & self.png_safe
        n_clip = int(np.count_nonzero(mask & ~clip_mask))
        if n_clip:
            self.notes.append(f"{n_clip} pixels whose expected value is near or above 1 (or next to such a pixel) were "
                              "left out: an 8-bit image clips them (hand in EXR, PFM or HDR to have them graded)")

        # Noise level: 1 / (samples per grade pixel) of an mcrt-like estimator.
        resid = np.where(mask[..., None], img - R, 0.0)
        ratio = noise_ratio(resid, R, clip_mask, model_ps, ref_noise + q, base_tile, pair)
        per = n_r * k2  # hand-in renders x pixels per grade pixel
        spp_eff = (1.0 / ratio) / per if np.isfinite(ratio) and ratio > 0 else float("inf")
        self.details["noise"] = {"spp_declared": spp, "renders": n_r, "spp_effective": None if not np.isfinite(spp_eff) else spp_eff}
        # The verdict waits for the bias test: a biased image's noise says nothing about its sample count.
        spp_nominal = spp or a.min_spp  # what the noise is judged against
        if spp:
            spp_model = spp
            var_ratio = spp / spp_eff if np.isfinite(spp_eff) else 0.0
            if spp < a.min_spp:
                noise_verdict = ("failed", f"you declared {spp} samples per pixel; the assignment asks for at least {a.min_spp}", True)
            elif var_ratio > th.max_noise_ratio:
                # Trust the noise, not the declaration: a render whose noise belongs to fewer samples would
                # otherwise be judged with too small a noise model.
                spp_model = max(1, min(spp, int(spp_eff)))
                noise_verdict = ("failed", (f"the image is {var_ratio:.1f} times noisier (relative variance) than mcrt with "
                                            f"the declared {spp} spp, like mcrt with about {_spp_text(spp_eff)} spp; render "
                                            "more samples, check the spp you declared, or reduce your estimator's variance "
                                            "(next-event estimation)"), False)
            else:
                extra = ""
                if 0 < var_ratio < 1 / th.max_noise_ratio:
                    extra = (f"; it is less noisy than mcrt at {spp} spp (like about {_spp_text(spp_eff)} spp): more samples "
                             "than declared, a better estimator, or a denoiser")
                noise_verdict = ("passed", f"noise consistent with {spp} spp (like mcrt with about {_spp_text(spp_eff)} spp){extra}", False)
            if 0 < var_ratio < 1 / th.max_noise_ratio**2 and np.isfinite(spp_eff):
                # Far less noise than the declared spp implies: the noise model follows the image (with a
                # margin), so that declaring few samples cannot hide a bias behind an inflated noise model.
                spp_model = max(spp_model, int(spp_eff / th.max_noise_ratio))
                self.notes.append(f"the declared {spp} spp does not match the image's noise (like mcrt with about "
                                  f"{_spp_text(spp_eff)} spp); the bias test assumed {spp_model} spp")
        else:
            var_ratio = a.min_spp / spp_eff if np.isfinite(spp_eff) else 0.0
            spp_model = max(1, min(a.spp, int(spp_eff))) if np.isfinite(spp_eff) else a.spp
            if var_ratio > th.max_noise_ratio:
                noise_verdict = ("failed", (f"spp not declared, and the noise is like mcrt with about {_spp_text(spp_eff)} "
                                            f"spp, far fewer than the {a.min_spp} asked for at least; render more samples (and "
                                            "declare them in a manifest)"), False)
            else:
                noise_verdict = ("passed", (f"spp not declared (add a manifest with `spp = N`); the noise is like mcrt "
                                            f"with about {_spp_text(spp_eff)} spp"), False)
        self.details["noise"]["spp_model"] = spp_model

        noise = Noise(model=model_ps / (spp_model * per) + q, reference=ref_noise, pair=pair)
        kw = {"alpha": th.alpha, "min_effect": th.min_effect, "full_effect": th.full_effect}
        samples = spp_model * per

        # The detectors' weights must not depend on either image's noise: the model's variance stands in for the
        # reference's own (a heavy-tailed pixel's variance estimate is low exactly where its mean is).
        weight_var = model_ps / samples + model_ps / ref.spp

        def structure(res, nz):
            # Second moment of the lower-tail bound: E[X^2] / n = sigma^2 / n + mu^2 / n (structure.py).
            st = detect_structure(res, R, clip_mask, weight_var, nz.model + nz.reference + R**2 / samples,
                                  base=ctx.baseline.mean if cam == a.camera else None, labels=ctx.labels[cam],
                                  pair=imgs[0] - imgs[1] if n_r == 2 else None)
            objs = object_tests(res, R, clip_mask, nz, ctx.labels[cam], len(ctx.label_names) - 1)
            return st, structure_families(st, th) + [objs.family(th.min_effect)]

        st, fam = structure(resid, noise)
        bt = bias_test(resid, R, clip_mask, noise, a.tiles, **kw, extra=fam)
        k = ck.estimate_scale(img, R, clip_mask, base_tile)
        stops = float(np.log2(k)) if k > 0 else float("inf")
        scaled = None
        if _flagged(bt) and abs(k - 1) > th.min_effect:
            ks = ck.nice_scale(k)
            img_s = img / ks
            pair_s = pair / ks**2 if pair is not None else None
            noise_s = Noise(model=model_ps / (spp_model * per) + q / ks**2, reference=ref_noise, pair=pair_s)
            resid_s = np.where(clip_mask[..., None], img_s - R, 0.0)
            st_s, fam_s = structure(resid_s, noise_s)
            bts = bias_test(resid_s, R, clip_mask, noise_s, a.tiles, **kw, extra=fam_s)
            if not _flagged(bts):
                scaled = (ks, bts, img_s, st_s)
        self.details["exposure"] = {"ratio": k, "stops": stops}
        if scaled is not None:
            ks = scaled[0]
            f_ = ks if ks >= 1 else 1 / ks
            how = f"{f_:g}" if f_ == round(f_) else f"{f_:.3g}"
            rub.failed("exposure", f"the whole image is {how} times {'brighter' if ks > 1 else 'darker'} than the reference "
                       f"({stops:+.2f} stops); {'divided' if ks > 1 else 'multiplied'} by {how} it passes the bias test, so only a constant factor is "
                       "wrong: an exposure or display scale applied before saving, or a constant missing in the "
                       "estimator (1/pi, the light's radiance or area)")
            e = self._explain(img, R, clip_mask, noise, cam, base_tile)
            if e is not None and e.named is not None and e.named.family not in ("scale", "light_radiance"):
                rub.results["exposure"].output += f". Not quite a constant, though: {e.sentence[0].lower()}{e.sentence[1:]}"
            if a.grade_corrected:
                bt, img, st = scaled[1], scaled[2], scaled[3]
                self.corrected.append("exposure")
        elif abs(stops) > th.max_exposure_stops:
            rub.failed("exposure", f"the image is {k:.3g} times as bright as the reference overall ({stops:+.2f} stops, "
                       f"more than the {th.max_exposure_stops:g} allowed); no constant factor makes it match, so "
                       "see the bias test for where it differs")
        else:
            rub.passed("exposure", f"overall brightness {k:.3g} times the reference's ({stops:+.2f} stops)")

        # The bias test's verdict.
        pooled = "two renders (pair, spread and model noise)" if n_r == 2 else "one render (spread and model noise)"
        sizes = [f"{t}x{t}" for t in [s.tile for s in bt.scales] if t > 0]
        sizes = (", ".join(sizes[:-1]) + " and " + sizes[-1] if len(sizes) > 1 else "".join(sizes)) + " pixel tiles"
        if any(s.tile == 0 for s in bt.scales):
            sizes += " and the whole image"
        family = (f"{sizes}, RGB; Holm at a family-wise error rate of {th.alpha:g}; "
                  f"relative effects of {_fmt_pct(th.min_effect)} or more")
        self.details["bias_test"] = _bias_details(bt)
        self._figures(img, R, bt, mask)
        m = metrics(img, R, clip_mask, noise.model + noise.reference)
        fmap = m.pop("_flip_map", None)
        if fmap is not None:
            self.figures["flip"] = np.asarray(fmap)
        m["excess_rms"] = bt.excess_rms
        self.details["metrics"] = m
        self.details["structure"] = _structure_details(st, bt)
        found = self._structure_findings(st, bt, cam, spp_eff, spp)
        if not _flagged(bt):
            rub.passed("unbiased", f"no significant bias: none of {bt.n_tests} tile tests is significant ({family}); noise from {pooled}. "
                       f"At your noise a tile would need a bias of about {_fmt_pct(bt.min_detectable)} to show; "
                       f"bias beyond noise: {_fmt_pct(bt.excess_rms)} RMS. No misregistration, blur or wrong pixels "
                       "either (tested with the tiles at the same error rate)")
            self.headline = "No significant bias."
        else:
            lines, where, diag = [], "", []
            if bt.penalised_any:
                n_pen = sum(int(np.count_nonzero(s.penalised)) for s in bt.scales)
                where = self._where(bt, cam)
                lines.append(f"biased: {n_pen} of {bt.n_tests} tile tests are significant ({family})."
                             + (f" {where[0].upper() + where[1:]}." if where else ""))
                diag = self._diagnose(diag_imgs, mask, R, ref, cam, noise, base_tile)
                if self.explanation is not None:
                    lines.append(self.explanation.sentence)
                elif diag:
                    lines.append(f"Most consistent with {short_text(diag[0].text)} ({diag[0].name})"
                                 + (f", or {short_text(diag[1].text)} ({diag[1].name})" if len(diag) > 1 else "") + ".")
            if not bt.penalised_any and cam == a.camera and self._explain(img, R, clip_mask, noise, cam, base_tile):
                lines.append(self.explanation.sentence)
            named = self.explanation.named if self.explanation is not None else None
            if named is not None and named.family not in _camera_families():
                # The misregistration test fits first-order image motion, which also absorbs part of a
                # change that is not motion (a missing object, a cut path depth): where a cause outside
                # the camera explains the difference, the camera is not blamed beside it.
                found.pop("registration", None)
            if named is not None and named.family != "blur":
                # Likewise the residual of any structured mistake is correlated between neighbours:
                # where another cause explains it, the image is not also called filtered.
                found.pop("filter", None)
            if named is None and self.adequacy is not None and self.adequacy.verdict != "adequate":
                self._findings_rule(found, bt, img, R, clip_mask, noise, structure)
            loss, why = self._loss(bt, cam, registration="registration" in found, filtered="filter" in found,
                                   major=named.key if named is not None and named.family in _major_families() else None)
            lines += [found[k] + "." for k in found]
            lines.append(f"Bias beyond noise: {_fmt_pct(bt.excess_rms)} RMS; {_fmt_pct(loss)} of these points lost ({why}).")
            rub.failed("unbiased", " ".join(lines), loss=loss)
            self.headline = where[0].upper() + where[1:] + "." if where else "Biased."
            if self.explanation is not None and (self.explanation.named is not None or not found or (
                    self.adequacy is not None and self.adequacy.verdict in ("partial", "none"))):
                self.headline = self.explanation.headline
            elif diag and self.explanation is None:
                self.headline = f"{where[0].upper() + where[1:] if where else 'Biased'}: consistent with {short_text(diag[0].text)}."
            elif found:
                self.headline = next(iter(found.values())).split(":")[0] + "."
        if "registration" in found:
            rub.failed("camera", found["registration"])
        status, text, firm = noise_verdict
        if "filter" in found:
            status, text, firm = "failed", found["filter"], True
        if status == "failed" and not firm and _flagged(bt):
            status, text = "passed", (f"not judged: the image is biased, so its noise cannot be compared with a correct "
                                      f"renderer's (it is like mcrt with about {_spp_text(spp_eff)} spp)")
        elif status == "failed" and not firm:
            # Excess pixel-to-pixel deviation with unbiased tiles: noise, or a deterministic error that
            # cancels within tiles (aliasing). Only the catalogue at pixel level can tell.
            diag = self._diagnose(diag_imgs, mask, R, ref, cam, noise, base_tile, pixel_level=True)
            nd = self._diagnose_noise(resid, R, mask, noise, cam, base_tile, spp_model * per)
            if _conclusive_chi2(diag, self._chi0 if diag else 0.0, self.details.get("diagnosis", {}).get("terms", 0)):
                text += (f". The excess is not random: pixel by pixel it matches {short_text(diag[0].text)} "
                         f"({diag[0].name}), which removes {100 * diag[0].explained:.0f} % of the mismatch (the rest is noise)")
                self.headline = f"Deviations that cancel within tiles: consistent with {short_text(diag[0].text)}."
            elif _conclusive(nd):
                text += (f". Where the noise is, matches {short_text(nd[0].text)} ({nd[0].name}) better than a correct "
                         f"renderer (it explains {100 * nd[0].explained:.0f} % of the mismatch)")
                self.headline = f"Too noisy in a telling pattern: consistent with {short_text(nd[0].text)}."
                self.diagnosis = [c.to_dict() for c in nd[:5]]
                self.details["diagnosis"] = {"level": "noise pattern"}
                self.figures.pop("mutant_rel_tiles", None)
            elif _conclusive(lv := self._diagnose_noise_level(var_ratio, resid, R, mask, cam,
                                                              model_ps / (spp_nominal * per) + ref_noise + q, spp_model * per)):
                text += (f". The mean is right but the noise is not: {short_text(lv[0].text)} ({lv[0].name}) multiplies "
                         f"the variance by about {lv[0].amplitude:.0f} with rare, very bright samples and leaves the mean "
                         f"nearly unchanged")
                self.headline = f"Right mean, far too much noise: consistent with {short_text(lv[0].text)}."
                self.diagnosis = [dict(c.to_dict(), amplitude=None, variance_inflation=c.amplitude) for c in lv[:5]]
                self.details["diagnosis"] = {"level": "noise level"}
                self.figures.pop("mutant_rel_tiles", None)
            else:
                self.diagnosis = []
                self.figures.pop("mutant_rel_tiles", None)
        rub.set("noise", status, text)
        if self.encoding in ("srgb", "gamma2.2") and not any(d["mutant"] == "gamma_output" for d in self.diagnosis[:1]):
            gm = self.ctx.mutant_texts.get("gamma_output", "Output gamma-encoded (sRGB) instead of linear radiance.")
            self.diagnosis.insert(0, {"mutant": "gamma_output", "description": gm, "explained": None, "amplitude": None,
                                      "where": "the whole image", "chi2": None, "chi2_best_amplitude": None})
        mtxt = (f"RMSE {m['rmse']:.4g} ({_fmt_pct(m['relative_rmse'])} of the mean; noise alone would give about "
                f"{m['noise_rmse']:.4g})")
        if m.get("ssim") is not None:
            mtxt += f", SSIM {m['ssim']:.3f}"
        if m.get("flip") is not None:
            mtxt += f", FLIP {m['flip']:.3f}"
        mtxt += f", bias beyond noise {_fmt_pct(bt.excess_rms)} RMS. These grow with noise and are not graded."
        rub.set("metrics", "info", mtxt)

    # -- structured errors and points ---------------------------------------------
    def _too_small(self, gh: int, gw: int, tile: int) -> None:
        """A graded image smaller than one tile of the bias test: the bias criteria get no points."""
        msg = (f"not tested: the graded image is {gw}x{gh} pixels, smaller than one {tile}x{tile} tile of the bias test, "
               f"so nothing about it can be tested; hand in {self.a.width}x{self.a.height} pixels")
        for name in ("exposure", "noise", "unbiased"):
            self.rubric.failed(name, msg)
        self.rubric.set("metrics", "info", "not computed: the image is too small to compare")
        self.headline = "Too small to test."

    def _wrong_surfaces(self, bt, cam) -> list[str]:
        """Surfaces most of whose pixels (``major_coverage``) are off by at least ``full_effect``."""
        th, lab = self.th, self.ctx.labels[cam]
        off = bt.pixel_effect >= th.full_effect
        out = []
        for k in np.unique(lab):
            sel = lab == k
            if sel.sum() >= 8 and float(np.mean(off[sel])) >= th.major_coverage:
                out.append(self.ctx.label_names[int(k)])
        return out

    def _loss(self, bt, cam, *, registration: bool, filtered: bool, major: str | None = None) -> tuple[float, str]:
        """Share of the unbiased points lost, as a TA would: by the kind of mistake, then by its extent.

        ``registration``, ``filtered``: the misregistration and filter findings stand (they are dropped
        where the explanation names another cause); ``major``: what the explanation names where it is a
        major kind of mistake whatever its share of the image (an object missing, a colour, the camera).
        """
        th, ex = self.th, bt.extra
        tile_loss = bt.loss(th.min_loss) if bt.penalised_any else 0.0
        pix = ex["pixels"].reshape(bt.shape + (3,)).any(axis=2) if "pixels" in ex else np.zeros(bt.shape, bool)
        area = float(np.mean((bt.pixel_effect > 0) | pix))
        surfaces = self._wrong_surfaces(bt, cam) if bt.penalised_any else []
        if registration or surfaces or major:
            what = ("; ".join(surfaces[:3]) + (" look wrong" if len(surfaces) > 1 else " looks wrong") if surfaces
                    else major if major else "the camera")
            return max(th.major_loss, tile_loss), f"a major mistake ({what}): at least {_fmt_pct(th.major_loss)}"
        if filtered:
            return max(th.filter_loss, tile_loss), f"a filtered image: at least {_fmt_pct(th.filter_loss)}"
        if area <= th.minor_area:
            return th.minor_loss, f"a minor mistake, {_fmt_pct(area)} of the image: {_fmt_pct(th.minor_loss)}"
        if not bt.penalised_any:
            return min(1.0, th.min_loss + (1.0 - th.min_loss) * area), "wrong pixels over part of the image"
        return tile_loss, f"{_fmt_pct(th.min_loss)} for any significant bias plus the share of the image it covers"

    def _structure_findings(self, st, bt, cam, spp_eff: float, spp: int | None) -> dict[str, str]:
        """Feedback for each structured error found (rejected and relevant): registration, filter, pixels."""
        out, ex = {}, bt.extra
        reg = st.registration
        if reg is not None and ex.get("registration", np.zeros(1, bool)).any():
            h, w = bt.shape
            radius = 0.5 * float(np.hypot(h - 1, w - 1))
            parts = []
            if np.hypot(*reg.shift) >= self.th.min_shift:
                parts.append(f"shifted by ({reg.shift[0]:+.2f}, {reg.shift[1]:+.2f}) pixels (right, down)")
            if abs(reg.zoom) * radius >= self.th.min_shift:
                parts.append(f"a field of view about {_fmt_pct(abs(reg.zoom))} {'wider' if reg.zoom > 0 else 'narrower'} "
                             "(in tan(fov/2))")
            if abs(reg.roll) * radius >= self.th.min_shift:
                parts.append(f"rotated by about {np.degrees(abs(reg.roll)):.2g} degrees")
            out["registration"] = ("the camera does not match the reference: the image is " + ", ".join(parts or ["misregistered"])
                                   + f" (up to {reg.edge_displacement:.2f} pixels at the border; a first-order fit, "
                                   f"p = {reg.p:.2g}); check the pixel centre ((i + 0.5) / width), the field of view "
                                   "(horizontal, in degrees) and the camera's eye, look-at and up vectors")
        blur = ex.get("blur", np.zeros(1, bool)).any()
        # A wrong camera or surface leaves structure beyond any first-order fit (correlated, edge-like): named
        # as what it is, not also as a filter.
        secondary = "registration" in out or bool(bt.penalised_any and self._wrong_surfaces(bt, cam))
        if not secondary and (blur or ex.get("correlation", np.zeros(1, bool)).any()):
            how = [f"neighbouring pixels' noise is correlated ({st.correlation:.2f})"] if st.correlation > 0 else []
            if blur:
                how.append(f"edges are {'softened' if st.blur > 0 else 'sharpened'} as by a filter of about "
                           f"{np.sqrt(abs(st.blur)):.2g} pixels")
            low = (f"; its noise is like {_spp_text(spp_eff)} spp where {spp} were declared" if spp and np.isfinite(spp_eff)
                   and spp_eff > 4 * spp else "")
            out["filter"] = ("the image was filtered (blurred, denoised or resampled): " + " and ".join(how) + low
                             + "; a Monte-Carlo render's pixels are independent: hand in the unfiltered render")
        if "pixels" in ex and ex["pixels"].any():
            pix = ex["pixels"].reshape(bt.shape + (3,)).any(axis=2)
            first = np.argwhere(pix)[0]
            out["pixels"] = (f"{int(pix.sum())} pixels are darker than any correct render's noise allows (the first at row "
                             f"{int(first[0])}, column {int(first[1])}): rays that miss geometry (cracks between triangles, "
                             "a hit test's epsilon) or shadow rays that hit the surface they start from")
        return out

    # -- where and why -----------------------------------------------------------
    def _where(self, bt, cam) -> str:
        s = bt.base
        flagged = s.penalised.any(axis=2)
        if not flagged.any():  # only larger scales fired: describe the base tiles with the largest |t|
            lum_t = np.abs(s.t @ LUMINANCE)
            flagged = s.valid & (lum_t >= max(2.0, np.percentile(lum_t[s.valid], 75) if s.valid.any() else 2.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            rel = np.where(np.abs(s.ref @ LUMINANCE) > 0, (s.diff @ LUMINANCE) / np.abs(s.ref @ LUMINANCE), 0.0)
        return describe_tiles(rel, flagged, bt.shape, s.tile, self.ctx.labels[cam], self.ctx.label_names,
                              self.ctx.direct_fraction[cam])

    def _diagnose(self, diag_imgs, mask, R, ref, cam, noise, tile, pixel_level: bool = False):
        """Rank the catalogue (mcrt.grade.diagnose) against the image as handed in (after flips only).

        Tile-level by default (the bias test's first scale and its noise);
        ``pixel_level`` compares single pixels with the model noise alone,
        for deviations that cancel within tiles (aliasing: no pixel jitter).
        """
        from mcrt.grade.diagnose import rel_lum

        ctx = self.ctx
        if cam != self.a.camera or not ctx.mutants:
            self.notes.append("no bug diagnosis: the catalogue's images exist for the assigned camera only")
            return []
        img = diag_imgs[0] if len(diag_imgs) == 1 else 0.5 * (diag_imgs[0] + diag_imgs[1])
        resid = np.where(mask[..., None], img - R, 0.0)
        unit = 1 if pixel_level else tile
        s = scale_stats(resid, R, mask, noise, unit, min_n=1 if pixel_level else 2)
        shape = R.shape[:2]
        labels, names, direct = ctx.labels[cam], ctx.label_names, ctx.direct_fraction[cam]
        r_t = _tile_means(R, mask, tile)

        def signature(name):
            return rel_lum(_tile_means(ctx.mutants[name].mean - ctx.baseline.mean, mask, tile), r_t)

        def where_fn(name):
            return signature_region(signature(name), shape, tile, labels, names, direct, self.th.min_effect)

        cands, chi0 = rank_mutants(s.diff, s.var, s.ref, s.valid, ctx.mutants, ctx.baseline, mask, unit,
                                   ctx.mutant_texts, where_fn)
        self.details["diagnosis"] = {"level": "pixel" if pixel_level else f"{tile}x{tile} tiles", "chi2_none": chi0,
                                     "terms": int(np.count_nonzero(s.valid)) * 3}
        self._chi0 = chi0
        self.diagnosis = [c.to_dict() for c in cands[:5]]
        best = cands[0]
        self.figures["mutant_rel_tiles"] = signature(best.name)
        self.figures["mutant_name"] = best.name
        if not pixel_level:
            self._explain(img, R, mask, noise, cam, tile)
        return cands[:2]

    def _explain(self, img, R, mask, noise, cam, tile):
        """Fit the parametric mistakes of :mod:`mcrt.grade.explain` (the catalogue among them) to the image.

        When none explains most of the difference the diagnosis is left
        empty: no bug is named.
        """
        from mcrt.grade.diagnose import change_region, rel_lum
        from mcrt.grade.explain import explain

        ctx = self.ctx
        basis = getattr(ctx, "explain", None)
        if basis is None or cam != basis.camera or basis.base.shape != R.shape:
            return None
        labels, names, direct = ctx.labels[cam], ctx.label_names, ctx.direct_fraction[cam]

        def where_fn(dm):
            return change_region(dm, R, mask, tile, labels, names, direct, self.th.min_effect)

        e = explain(img, R, noise.model + noise.reference, mask, basis, mutants=ctx.mutants, baseline=ctx.baseline,
                    texts=ctx.mutant_texts, where_fn=where_fn, tile=tile)
        e, self.adequacy = judge(e, img, R, mask, noise, self._scene2d(cam),
                                 extra_var=lambda c: self._candidate_var(c, basis))
        self.explanation = e
        self.details["explanation"] = dict(e.to_dict(), adequacy=self.adequacy.to_dict())
        if self.adequacy.map is not None:
            self.figures["objects_rel"] = self.adequacy.map
        if e.named is not None:
            self.diagnosis = [c.to_dict() for c in e.candidates[:5]]
            self.figures["mutant_rel_tiles"] = rel_lum(_tile_means(e.named.delta, mask, tile), _tile_means(R, mask, tile))
            self.figures["mutant_name"] = e.named.key
        else:
            self.diagnosis = []
            self.figures.pop("mutant_rel_tiles", None)
            self.figures.pop("mutant_name", None)
        return e

    def _findings_rule(self, found, bt, img, R, mask, noise, structure) -> None:
        """The adequacy rule for the checks' own findings, where no cause is adequate (mcrt.grade.adequacy).

        A structured remainder makes neighbours alike, moves edges and darkens
        pixels: the filter finding stands only if the noise is still
        correlated in what the best candidate leaves, the camera finding only
        if that candidate is the camera's, the wrong-pixels finding (cracks,
        shadow rays) only if its pixels are a minor share of the image.
        """
        from mcrt.grade.adequacy import PARTIAL
        from mcrt.grade.structure import SHARES

        best = self.explanation.candidates[0] if self.explanation.candidates else None
        if best is None or best.family not in _camera_families():
            found.pop("registration", None)
        if "pixels" in found and bt.extra["pixels"].reshape(bt.shape + (3,)).any(axis=2).mean() > self.th.minor_area:
            # Cracks and shadow-ray misses darken a few pixels; many dark pixels are part of a wider difference.
            found.pop("pixels")
        if "filter" in found and best is not None and best.delta is not None and best.explained >= PARTIAL:
            rest = np.where(mask[..., None], img - R - best.delta, 0.0)
            st, _ = structure(rest, noise)
            th = self.th
            if not (st.p_correlation <= th.alpha * SHARES["correlation"] and st.correlation >= th.min_correlation):
                found.pop("filter", None)

    def _scene2d(self, cam):
        th = self.th
        return Scene2D(tuple(self.a.tiles), th.alpha, th.min_effect, th.full_effect, self.ctx.labels[cam],
                       self.ctx.label_names)

    def _candidate_var(self, c, basis):
        """The noise of a candidate's predicted change: its expected images' (catalogue) or the basis renders'."""
        if c.catalogue and c.key in self.ctx.mutants:
            m, b = self.ctx.mutants[c.key], self.ctx.baseline
            return m.var.astype(np.float64) / m.spp + b.var.astype(np.float64) / b.spp
        return basis.var.astype(np.float64) / basis.spp

    def _diagnose_noise(self, resid, R, mask, noise, cam, tile, samples):
        """Rank the catalogue by its noise pattern (:func:`mcrt.grade.diagnose.rank_noise`)."""
        from mcrt.grade.diagnose import rank_noise

        ctx = self.ctx
        if cam != self.a.camera or not ctx.mutants:
            return []
        s = scale_stats(resid, R, mask, noise, tile)
        n3 = np.maximum(s.n, 1.0)[..., None]
        ref_share = _tile_means(noise.reference, mask, tile)
        spread = np.maximum(s.var_spread * n3 - ref_share, 0.0)
        cands, _ = rank_noise(spread, s.n, s.valid, s.ref + s.diff, ctx.mutants, ctx.baseline, mask, tile, samples,
                              ctx.mutant_texts)
        return cands[:2]

    def _diagnose_noise_level(self, var_ratio, resid, R, mask, cam, var_nominal, samples):
        """Rank the catalogue by the amount of noise (:func:`mcrt.grade.diagnose.rank_noise_level`), among
        the bugs whose mean bias would not show at this noise.

        Only for noise in rare outliers, where most pixels keep the noise of
        the declared spp. The measure is the median pixel's squared residual
        against mcrt's variance at the nominal spp (``var_nominal``), over the
        median of a chi-square with one degree of freedom (``bulk``). A bug
        is named only if ``bulk`` stays below var_ratio^(1/4) and below half
        of what a correct renderer with the image's effective sample count
        (``samples``) gives: a correct mcrt render at that count (at most 64
        spp, scaled) is made and measured the same way. Too few samples
        raise the median pixel's residual with the whole noise, though less
        than the variance when a pixel's samples are heavy-tailed, by an
        amount that depends on the scene: hence a simulated render, not a
        formula.
        """
        from mcrt.grade.diagnose import catalogue_power, rank_noise_level
        from mcrt.render import render

        ctx = self.ctx
        if not ctx.mutants or not np.isfinite(var_ratio) or var_ratio <= 1.0:
            return []

        def bulk_of(r):
            with np.errstate(divide="ignore", invalid="ignore"):
                z2 = r**2 / var_nominal
            z2 = z2[mask[..., None].repeat(3, axis=2) & np.isfinite(z2)]
            return float(np.median(z2)) / 0.4549 if z2.size else np.inf  # 0.4549: median of chi-square(1)

        bulk = bulk_of(resid)
        noise = self.details.setdefault("noise", {})
        noise["bulk_ratio"] = bulk
        if not bulk < var_ratio**0.25:
            return []
        a = self.a
        n_sim = int(min(max(round(samples), 1), 64))
        scene = a.load_scene()
        sim = render(scene, grading_settings(scene, cam, R.shape[1], R.shape[0], a.max_depth, n_sim, a.seed + 3),
                     progress=False)
        bulk_few = bulk_of(np.where(mask[..., None], sim.mean.astype(np.float64) - R, 0.0)) * n_sim / max(samples, 1e-9)
        noise["bulk_ratio_fewer_samples"] = bulk_few
        if not bulk < 0.5 * bulk_few:
            return []
        hidden = {p["mutant"] for p in catalogue_power(ctx, samples) if not p["detectable"]}
        return rank_noise_level(var_ratio, ctx.mutants, ctx.baseline, mask, ctx.mutant_texts, hidden)[:2]

    def _figures(self, img, R, bt, mask) -> None:
        s = bt.base
        lum_ref = np.abs(s.ref @ LUMINANCE)
        with np.errstate(divide="ignore", invalid="ignore"):
            rel = np.where(lum_ref > 0, (s.diff @ LUMINANCE) / np.maximum(lum_ref, 1e-300), 0.0)
        tl = np.take_along_axis(np.nan_to_num(s.t, posinf=1e9, neginf=-1e9),
                                np.argmax(np.abs(np.nan_to_num(s.t, posinf=1e9, neginf=-1e9)), axis=2)[..., None], axis=2)[..., 0]
        self.figures.update(submission=np.nan_to_num(img, nan=0.0, posinf=0.0, neginf=0.0).astype(np.float32),
                            reference=R.astype(np.float32), tile=int(s.tile if s.tile > 0 else max(bt.shape)),
                            rel_tiles=rel, t_tiles=tl, penalised=s.penalised.any(axis=2))

    # -- result --------------------------------------------------------------------
    def result(self) -> StudentResult:
        tests = self.rubric.finish()
        score = round(sum(t.score for t in tests), 4)
        max_score = sum(t.max_score for t in tests)
        failed = [t for t in tests if t.status in ("failed", "not graded") and t.max_score > 0]
        shown = f"{score:.2f}".rstrip("0").rstrip(".")
        if not failed:
            summary = f"Full marks: {shown}/{max_score:g}. " + (self.headline or "")
        else:
            first = failed[0]
            if self.rubric.blocked:
                summary = f"{shown}/{max_score:g}; nothing after '{first.title}' could be graded."
            else:
                lost = ", ".join(f"{t.title.split(' (')[0].lower()} (-{_num(t.max_score - t.score)})" for t in failed)
                summary = f"{shown}/{max_score:g}; points lost: {lost}."
            if first.name != "unbiased":
                summary += f" {first.title}: {first.output.split('; ')[0]}."
            if self.headline and self.headline != "No significant bias.":
                summary += f" {self.headline}"
        return StudentResult(self.student, STATUS_GRADED, score, max_score, tests, summary.strip(), self.notes,
                             self.diagnosis, self.details, self.figures)


def _conclusive_chi2(cands, chi0: float, terms: int) -> bool:
    r"""Pixel-level ranking: the best mutant lowers chi^2 by far more than noise could (5 sd of a chi^2
    with ``terms`` degrees of freedom) and three times as much as the next one, and it beats a correct
    renderer with fewer samples than declared.

    That last rival has the model's noise times a factor s, fitted to the
    image (s = chi0 / terms); in Gaussian deviance, -2 ln L + const, it scores
    :math:`chi0 / s + terms \ln s = terms (1 + \ln(chi0 / terms))` against
    the mutant's chi^2 at the declared noise. A correct render with a
    sixteenth of its declared samples has chi0 near 16 terms: a mutant that
    removes a few per cent of that is not a diagnosis.
    """
    if not cands or terms <= 0:
        return False
    gain1 = chi0 - cands[0].chi2
    gain2 = chi0 - cands[1].chi2 if len(cands) > 1 else 0.0
    fewer_samples = terms * (1.0 + np.log(max(chi0 / terms, 1.0)))
    return gain1 > 5.0 * np.sqrt(2.0 * terms) and gain1 > 3.0 * max(gain2, 0.0) and cands[0].chi2 < fewer_samples


def _conclusive(cands) -> bool:
    """The best candidate explains at least 30 % and twice as much as the next one."""
    return bool(cands) and cands[0].explained >= 0.3 and (len(cands) < 2 or cands[0].explained >= 2 * max(cands[1].explained, 0.0))


def _camera_families() -> frozenset:
    from mcrt.grade.explain import CAMERA_FAMILIES  # explain loads on first use, as in _Grader._explain

    return CAMERA_FAMILIES


def _major_families() -> frozenset:
    from mcrt.grade.explain import MAJOR_FAMILIES

    return MAJOR_FAMILIES


def _flagged(bt) -> bool:
    """Any tile test or structured-error test rejected and relevant."""
    return bool(bt.penalised_any or any(np.any(v) for v in bt.extra.values()))


def _structure_details(st, bt) -> dict:
    reg = st.registration
    out = {"correlation": st.correlation, "p_correlation": st.p_correlation, "blur_variance": st.blur,
           "p_blur": st.p_blur, "penalised": {k: int(np.count_nonzero(v)) for k, v in bt.extra.items()}}
    if reg is not None:
        out["registration"] = {"shift": list(reg.shift), "zoom": reg.zoom, "roll": reg.roll,
                               "edge_displacement": reg.edge_displacement, "p": reg.p}
    return out


def _png_unclipped(R, model_ps, spp: int) -> np.ndarray:
    """Grade pixels an 8-bit image cannot have clipped: expected value plus 3 sd of a hand-in pixel below 1,
    and not next to a pixel that is not (a grade pixel's hand-in pixels may see a brighter neighbour)."""
    from scipy import ndimage

    sd = np.sqrt(model_ps / max(spp, 1))  # a hand-in pixel's noise: its per-sample variance is at most a grade pixel's
    bright = np.any(R + 3 * sd >= 1.0, axis=2)
    return ~ndimage.binary_dilation(bright, structure=np.ones((3, 3), bool))


def _tile_means(x, mask, tile):
    from mcrt.grade.diagnose import tile_means

    return tile_means(np.asarray(x, np.float64), mask, tile)


def _bias_details(bt) -> dict:
    out = {"alpha": bt.alpha, "min_effect": bt.min_effect, "n_tests": bt.n_tests, "penalised": bt.penalised_any,
           "severity": bt.severity, "excess_rms": bt.excess_rms, "min_detectable_effect": bt.min_detectable,
           "worst": bt.worst, "scales": []}
    for s in bt.scales:
        out["scales"].append({
            "tile": s.tile, "tiles": list(s.n.shape), "rejected": int(np.count_nonzero(s.rejected)),
            "penalised": int(np.count_nonzero(s.penalised)),
            "max_abs_t": float(np.max(np.abs(np.nan_to_num(s.t[s.valid], posinf=1e300, neginf=-1e300)))) if s.valid.any() else 0.0,
        })
    return out


def format_exception() -> str:
    return traceback.format_exc(limit=20)
