"""Bias and structure: the multi-scale tile test and the structured-error detectors, under one error rate.

The tile test is :func:`mcrt.stats.onesample.multiscale_test`; the detectors
of :mod:`mcrt.grade.structure` (misregistration, blur, correlated noise,
too-dark pixels, patches of pixels off together) and the per-object test of :mod:`mcrt.grade.objects` join
its family with their shares of ``alpha``. Another
detector joins the same way: one more (name, p-values, relevant, share) in
``extra``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mcrt.grade import feedback as fb
from mcrt.grade.objects import MIN_PIXELS, baseline_shares, object_tests, structure_family
from mcrt.grade.regions import short_text
from mcrt.grade.score import LUMINANCE, metrics
from mcrt.grade.stages.noise import removed
from mcrt.grade.stages.state import Grading, Hand, Level
from mcrt.grade.structure import detect as detect_structure
from mcrt.grade.structure import families as structure_families
from mcrt.stats.onesample import Noise, multiscale_test


@dataclass
class Tested:
    """The tests' results on the graded image (the exposure stage may replace them by the rescaled image's)."""

    bt: object  # mcrt.stats.onesample.MultiScaleTest, the detectors' results in bt.extra
    st: object  # mcrt.grade.structure's measurements
    img: np.ndarray  # the image they tested
    objects: object = None  # mcrt.grade.objects.ObjectTests of the image
    shape: tuple | None = None  # the per-object structure family (name, p-values, relevant, share)
    patches: np.ndarray | None = None  # (H, W) the pixels of the patches found off together (mcrt.grade.structure)


def flagged(bt) -> bool:
    """Any tile test or structured-error test rejected and relevant."""
    return bool(bt.penalised_any or any(np.any(v) for v in bt.extra.values()))


def test(g: Grading, hand: Hand, lvl: Level, img: np.ndarray, resid: np.ndarray, noise: Noise) -> Tested:
    """The structure detectors and the tile tests of one image, as one family."""
    a, th, ctx, R = g.a, g.th, g.ctx, hand.R
    # The detectors' weights must not depend on either image's noise: the model's variance stands in for the
    # reference's own (a heavy-tailed pixel's variance estimate is low exactly where its mean is).
    weight_var = lvl.model_ps / lvl.samples + lvl.model_ps / hand.ref.spp
    # Second moment of the lower-tail bound: E[X^2] / n = sigma^2 / n + mu^2 / n (structure.py).
    st = detect_structure(resid, R, lvl.clip_mask, weight_var, noise.model + noise.reference + R**2 / lvl.samples,
                          base=ctx.baseline.mean if hand.cam == a.camera else None, labels=ctx.labels[hand.cam],
                          pair=hand.imgs[0] - hand.imgs[1] if hand.n_r == 2 else None)
    # Beside the tiles, a test per object (mcrt.grade.objects): a small change confined to one object loses points.
    K = len(ctx.label_names) - 1
    objs = object_tests(resid, R, lvl.clip_mask, noise, ctx.labels[hand.cam], K)
    shape = structure_family(resid, R, lvl.clip_mask, noise, ctx.labels[hand.cam], K, th.min_effect,
                             shares=baseline_shares(ctx, hand.cam, hand.R, hand.ref, lvl.clip_mask,
                                                    unsampled=bool(lvl.unsampled)),
                             image=np.where(lvl.clip_mask[..., None], img, 0.0))
    # A relevant bias is tested (beyond min_effect), not a zero one: correct samplers are a few tenths of a per
    # cent off the reference on whole surfaces, which large tiles and objects resolve at high spp (mcrt.stats.onesample).
    # The structure within objects is judged by each object's share of the image's noise tails in mcrt's diagnosis
    # render, whose tails are those of thousands of samples: a tracer without light sampling at a few hundred spp or
    # fewer has far heavier tails on the surfaces the light reaches (a pixel's few samples that found the light), and
    # correct renders of it fail that test; its objects' means are tested all the same.
    shapes = [] if lvl.unsampled else [shape]
    bt = multiscale_test(resid, R, lvl.clip_mask, noise, a.tiles, alpha=th.alpha, min_effect=th.min_effect,
                         full_effect=th.full_effect, relevant=True,
                         extra=structure_families(st, th) + [objs.family(th.min_effect, relevant=True)] + shapes)
    found = bt.extra.get("patches", np.zeros(2, bool))
    return Tested(bt, st, img, objs, shape, (st.patch_maps & found[:, None, None]).any(axis=0))


def record(g: Grading, hand: Hand, lvl: Level, t: Tested) -> dict:
    """The tests' details, the feedback figures and the error metrics (informational); returns the metrics."""
    bt = t.bt
    g.details["bias_test"] = _bias_details(bt)
    _figures(g, t.img, hand.R, bt)
    m = metrics(t.img, hand.R, lvl.clip_mask, lvl.noise.model + lvl.noise.reference)
    fmap = m.pop("_flip_map", None)
    if fmap is not None:
        g.figures["flip"] = np.asarray(fmap)
    m["excess_rms"] = bt.excess_rms
    g.details["metrics"] = m
    g.details["structure"] = _structure_details(t.st, bt)
    if t.objects is not None:  # raw p-values (the false-alarm report's calibration table), untested ones left out
        ok = t.objects.n >= MIN_PIXELS
        g.details["structure"]["p_objects"] = t.objects.p[ok].ravel().tolist()
        g.details["structure"]["p_objects_relevant"] = t.objects.relevant_p(bt.min_effect)[ok].ravel().tolist()
        g.details["structure"]["p_object_structure"] = np.asarray(t.shape[1])[ok].tolist()
        lum_ref = t.objects.ref @ LUMINANCE
        g.details["structure"]["objects_rel"] = {
            g.ctx.label_names[k]: float((t.objects.diff[k] @ LUMINANCE) / lum_ref[k])
            for k in np.flatnonzero(ok) if lum_ref[k] > 0}
    return m


def findings(g: Grading, hand: Hand, lvl: Level, t: Tested) -> dict[str, str]:
    """Feedback for each structured error found (rejected and relevant): registration, filter, pixels, the values in
    other places, patches."""
    from mcrt.grade.scoring import wrong_surfaces

    st, bt = t.st, t.bt
    out, ex = {}, bt.extra
    reg = st.registration
    if reg is not None and ex.get("registration", np.zeros(1, bool)).any():
        out["registration"] = fb.registration_text(reg, bt.shape, g.th.min_shift)
    blur = ex.get("blur", np.zeros(1, bool)).any()
    # A wrong camera or surface leaves structure beyond any first-order fit (correlated, edge-like): named
    # as what it is, not also as a filter.
    secondary = "registration" in out or bool(
        bt.penalised_any and wrong_surfaces(bt, g.th, g.ctx.labels[hand.cam], g.ctx.label_names))
    smoothed = blur or ex.get("correlation", np.zeros(1, bool)).any()
    if not secondary and smoothed:
        out["filter"] = fb.filter_text(st, blur, lvl.spp_eff, hand.spp)
    elif smoothed and (times := removed(lvl, hand, g.ctx.labels[hand.cam])) is not None:
        # A filter that keeps edges also leaves a bias on surfaces; the noise it took out of them tells it apart.
        out["denoised"] = fb.denoised_text(st, times, lvl.spp_nominal)
    if "pixels" in ex and ex["pixels"].any():
        out["pixels"] = fb.pixels_text(ex["pixels"].reshape(bt.shape + (3,)).any(axis=2))
    if flagged(bt):
        # The noise of the declared spp, not the measured one: values in other places measure as noise themselves.
        declared = lvl.model_ps / max(hand.spp or g.a.min_spp, 1)
        moved = values_elsewhere(t.img, hand.R, declared + lvl.noise.reference, lvl.clip_mask)
        if moved is not None:
            out["places"] = fb.places_text(*moved)
    if t.patches is not None and t.patches.any():
        labels = g.ctx.labels[hand.cam]
        names = [g.ctx.label_names[k] for k in np.unique(labels[t.patches])]
        effects = [float(e) for e, f in zip(st.patch_effect, ex["patches"]) if f]
        out["patches"] = fb.patches_text(t.patches, effects, names)
    return out


#: How many times the pixels' differences must exceed their sorted values' (and the noise's) for the image to be read
#: as a correct render's values in other places (:func:`values_elsewhere`).
PLACES_RATIO = 10.0


def values_elsewhere(img: np.ndarray, ref: np.ndarray, var: np.ndarray, mask: np.ndarray) -> tuple[float, float] | None:
    """(pixel by pixel, sorted): the mean absolute luminance differences of the image and the reference, each
    relative to the reference's mean, where the image holds the reference's values in other places: its values,
    sorted, match the reference's, and pixel by pixel they differ PLACES_RATIO times as much, and as much beside the
    noise (each pixel's expected absolute noise, sqrt(2 / pi) sd). None otherwise. Luminance is clipped at 2 first, so
    that the light's pixels (20) weigh as bright ones, not forty times a wall (a permutation keeps them all)."""
    lum = np.minimum(np.nan_to_num(img, nan=0.0) @ LUMINANCE, 2.0)[mask]
    lref = np.minimum(ref @ LUMINANCE, 2.0)[mask]
    if lum.size == 0 or lref.mean() <= 0:
        return None
    scale = lref.mean()
    pixels = float(np.mean(np.abs(lum - lref))) / scale
    ordered = float(np.mean(np.abs(np.sort(lum) - np.sort(lref)))) / scale
    noise = float(np.mean(np.sqrt(2.0 / np.pi * np.maximum(var, 0.0)[mask] @ LUMINANCE**2))) / scale
    return (pixels, ordered) if pixels >= PLACES_RATIO * max(ordered, noise) else None


def where(g: Grading, hand: Hand, bt) -> str:
    """Where the penalised base tiles lie, in words (the base tiles with the largest |t| when only larger scales fired)."""
    from mcrt.grade.regions import describe_tiles

    s = bt.base
    chosen = s.penalised.any(axis=2)
    if not chosen.any():
        lum_t = np.abs(s.t @ LUMINANCE)
        chosen = s.valid & (lum_t >= max(2.0, np.percentile(lum_t[s.valid], 75) if s.valid.any() else 2.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(np.abs(s.ref @ LUMINANCE) > 0, (s.diff @ LUMINANCE) / np.abs(s.ref @ LUMINANCE), 0.0)
    return describe_tiles(rel, chosen, bt.shape, s.tile, g.ctx.labels[hand.cam], g.ctx.label_names,
                          g.ctx.direct_fraction[hand.cam])


def _figures(g: Grading, img, R, bt) -> None:
    s = bt.base
    lum_ref = np.abs(s.ref @ LUMINANCE)
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(lum_ref > 0, (s.diff @ LUMINANCE) / np.maximum(lum_ref, 1e-300), 0.0)
    tl = np.take_along_axis(np.nan_to_num(s.t, posinf=1e9, neginf=-1e9),
                            np.argmax(np.abs(np.nan_to_num(s.t, posinf=1e9, neginf=-1e9)), axis=2)[..., None], axis=2)[..., 0]
    g.figures.update(submission=np.nan_to_num(img, nan=0.0, posinf=0.0, neginf=0.0).astype(np.float32),
                     reference=R.astype(np.float32), tile=int(s.tile if s.tile > 0 else max(bt.shape)),
                     rel_tiles=rel, t_tiles=tl, penalised=s.penalised.any(axis=2))


def _structure_details(st, bt) -> dict:
    reg = st.registration
    out = {"correlation": st.correlation, "p_correlation": st.p_correlation, "blur_variance": st.blur,
           "p_blur": st.p_blur, "penalised": {k: int(np.count_nonzero(v)) for k, v in bt.extra.items()}}
    if st.patch_p is not None:
        out["p_patches"] = st.patch_p.tolist()
        out["patch_pixels"] = st.patch_maps.sum(axis=(1, 2)).tolist()
    if reg is not None:
        out["registration"] = {"shift": list(reg.shift), "zoom": reg.zoom, "roll": reg.roll,
                               "edge_displacement": reg.edge_displacement, "p": reg.p}
    return out


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


def verdict(g: Grading, hand: Hand, lvl: Level, t: Tested, found: dict[str, str]) -> None:
    """The ``unbiased`` criterion: its verdict, the explanation of a failure, and the points it loses."""
    th, bt = g.th, t.bt
    pooled = "two renders (pair, spread and model noise)" if hand.n_r == 2 else "one render (spread and model noise)"
    family = fb.bias_family_text(bt, th)
    if not flagged(bt):
        g.rubric.passed("unbiased", f"no significant bias: none of {bt.n_tests} tile tests is significant ({family}); "
                        f"noise from {pooled}. At your noise a tile would need a bias of about "
                        f"{fb.fmt_pct(bt.min_detectable)} to show; bias beyond noise: {fb.fmt_pct(bt.excess_rms)} RMS. "
                        "No misregistration, blur or wrong pixels either (tested with the tiles at the same error rate)")
        g.headline = "No significant bias."
        return
    lines, where_text, diag = _explained(g, hand, lvl, t, family)
    named = g.explanation.named if g.explanation is not None else None
    if named is not None and named.family not in _families("CAMERA_FAMILIES"):
        # The misregistration test fits first-order image motion, which also absorbs part of a
        # change that is not motion (a missing object, a cut path depth): where a cause outside
        # the camera explains the difference, the camera is not blamed beside it.
        found.pop("registration", None)
    if named is not None:  # a cause that explains the difference says where the values went, if they moved
        found.pop("places", None)
    if named is not None and named.family != "blur":
        # Likewise the residual of any structured mistake is correlated between neighbours:
        # where another cause explains it, the image is not also called filtered.
        found.pop("filter", None)
    if named is not None:  # a claimed cause says what took the noise out, if anything did (a blur is no denoiser)
        found.pop("denoised", None)
    unexplained = named is None and g.explanation is not None and g.explanation.adequacy is not None
    if unexplained:
        _findings_rule(g, hand, lvl, t, found)
    from mcrt.grade.scoring import unbiased_loss

    major = named.name if named is not None and named.family in _families("MAJOR_FAMILIES") else None
    loss, why = unbiased_loss(bt, th, g.ctx.labels[hand.cam], g.ctx.label_names, registration="registration" in found,
                              filtered="filter" in found or "denoised" in found, major=major, patches=t.patches)
    lines += [found[k] + "." for k in found]
    lines.append(f"Bias beyond noise: {fb.fmt_pct(bt.excess_rms)} RMS; {fb.fmt_pct(loss)} of these points lost ({why}).")
    g.rubric.failed("unbiased", " ".join(lines), loss=loss)
    g.headline = where_text[0].upper() + where_text[1:] + "." if where_text else "Biased."
    if g.explanation is not None and (g.explanation.named is not None or not found or unexplained):
        g.headline = g.explanation.headline
    elif diag and g.explanation is None:
        g.headline = f"{where_text[0].upper() + where_text[1:] if where_text else 'Biased'}: consistent with {short_text(diag[0].text)}."
    elif found:
        g.headline = next(iter(found.values())).split(":")[0] + "."


def _findings_rule(g: Grading, hand: Hand, lvl: Level, t: Tested, found: dict[str, str]) -> None:
    """The adequacy rule for the checks' own findings, where no cause is claimed (mcrt.grade.adequacy).

    A structured remainder makes neighbours alike, moves edges and darkens
    pixels: the filter finding stands only if the noise is still
    correlated in what the best candidate leaves, the camera finding only
    if a candidate of the camera's is the best or tied with it (within
    TIE: which of the two is ahead is then chance) and explains a share
    worth mentioning (PARTIAL_SHARE: below it every reading ties with
    every other, and none says anything), the wrong-pixels
    finding (cracks, shadow rays) only if its pixels are a minor share of
    the image.
    """
    from mcrt.grade.adequacy import PARTIAL_SHARE
    from mcrt.grade.candidates import TIE
    from mcrt.grade.structure import SHARES

    bt, th, best = t.bt, g.th, g.explanation.best
    camera = _families("CAMERA_FAMILIES")
    if best is None or (best.family not in camera and not any(
            c.family in camera and c.explained >= max(best.explained - TIE, PARTIAL_SHARE)
            for c in g.explanation.candidates)):
        found.pop("registration", None)
    if "pixels" in found and bt.extra["pixels"].reshape(bt.shape + (3,)).any(axis=2).mean() > th.minor_area:
        found.pop("pixels")
    if "filter" in found and best is not None and best.change is not None and best.explained >= PARTIAL_SHARE:
        rest = np.where(lvl.clip_mask[..., None], t.img - hand.R - best.change, 0.0)
        st = test(g, hand, lvl, t.img, rest, lvl.noise).st
        if not (st.p_correlation <= th.alpha * SHARES["correlation"] and st.correlation >= th.min_correlation):
            found.pop("filter", None)


def _explained(g: Grading, hand: Hand, lvl: Level, t: Tested, family: str) -> tuple[list[str], str, list]:
    """Where the tile tests failed, and what explains it (the explanation stage)."""
    from mcrt.grade.stages.explanation import diagnose, explain

    bt, lines, where_text, diag = t.bt, [], "", []
    if bt.penalised_any:
        n_pen = sum(int(np.count_nonzero(s.penalised)) for s in bt.scales)
        where_text = where(g, hand, bt)
        lines.append(f"biased: {n_pen} of {bt.n_tests} tile tests are significant ({family})."
                     + (f" {where_text[0].upper() + where_text[1:]}." if where_text else ""))
        diag = diagnose(g, hand, lvl.noise)
        if g.explanation is not None:
            lines.append(g.explanation.sentence)
        elif diag:
            lines.append(f"Most consistent with {short_text(diag[0].text)} ({diag[0].name})"
                         + (f", or {short_text(diag[1].text)} ({diag[1].name})" if len(diag) > 1 else "") + ".")
    if not bt.penalised_any and hand.cam == g.a.camera and explain(g, hand, t.img, lvl.clip_mask, lvl.noise):
        lines.append(g.explanation.sentence)
    return lines, where_text, diag


def _families(name: str) -> frozenset:
    from mcrt.grade.explain import families  # the engine loads on first use

    return getattr(families, name)
