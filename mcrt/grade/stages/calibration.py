"""Calibration: the image's orientation and camera, and its encoding (a transfer curve on the values).

A detected mistake is undone for the later stages; grading continues on the
corrected image only when ``grading.grade_corrected`` is true.
"""

from __future__ import annotations

import numpy as np

from mcrt.grade import checks as ck
from mcrt.grade.score import quantisation_variance
from mcrt.grade.stages.state import Grading, Hand
from mcrt.image_files import srgb_oetf


def _orientation_causes(transform: str) -> str:
    """What turns or flips an image: the writer's order of rows and columns, or the camera's vectors."""
    if "90 degrees" in transform:  # a quarter turn is the camera rolled: the scene's up along another axis
        return ("row 0 must be the top of the image and column 0 its left: check the camera's up vector (a quarter "
                "turn is an up vector along another axis, such as +y where the scene's is +z) and the order in which "
                "you write rows and columns")
    return ("row 0 must be the top of the image and column 0 its left: check the order in which you write rows and "
            "columns (and whether your camera's up and right vectors point the right way)")


def orientation(g: Grading, hand: Hand, declared_camera: str | None) -> None:
    """The best of {cameras} x {flips, rotations} by rank correlation (``orientation``, ``camera``)."""
    a, rub = g.a, g.rubric
    ori = ck.detect_orientation(hand.imgs[0], {c: e.mean for c, e in g.ctx.references.items()}, a.camera,
                                g.th.orientation_margin)
    g.details["orientation"] = {"camera": ori.camera, "transform": ori.transform,
                                "rank_correlations_luminance_chroma": ori.correlations,
                                "rank_correlations_edges": ori.edges}
    if ori.transform != "identity":
        inv = ck.TRANSFORMS[ori.transform][1]
        hand.imgs, hand.qvar, hand.mask = [inv(i) for i in hand.imgs], [inv(q) for q in hand.qvar], inv(hand.mask)
        rub.failed("orientation", f"the image is {ori.transform} compared with the reference (rank correlation "
                   f"{ori.correlations[f'{ori.camera}/{ori.transform}'][0]:.2f} after undoing it, "
                   f"{ori.correlations[f'{a.camera}/identity'][0]:.2f} as handed in); {_orientation_causes(ori.transform)}")
        hand.corrected.append("orientation")
    elif not ori.resembles:
        rub.passed("orientation", "could not be checked: the image does not resemble the scene from any camera")
    else:
        rub.passed("orientation", "as expected (top row first, left column first)")
    if ori.camera != a.camera:
        rub.failed("camera", f"this is the view of the {ori.camera!r} camera, the assignment asks for {a.camera!r}"
                   + (" (the near and far cameras are swapped)" if {ori.camera, a.camera} == {"near", "far"} else "")
                   + (f"; your manifest says {declared_camera!r}" if declared_camera else ""))
        hand.corrected.append("camera")
    else:
        rub.passed("camera", f"the {a.camera!r} camera, as asked")
    hand.cam = ori.camera
    hand.ref = g.ctx.references[hand.cam]
    hand.R = hand.ref.mean.astype(np.float64)
    hand.diag_imgs = [i.copy() for i in hand.imgs]
    hand.transform = ori.transform


def confirm_camera(g: Grading, hand: Hand) -> None:
    """Another camera's view was the closest (:func:`orientation`), but graded against that camera's reference the
    image still fails the bias test: it may be that camera's view with another mistake, or no camera of the scene,
    only nearer one than the other (a field of view or an eye off resembles a camera further back or nearer; the
    explanation stage, whose renders are the assigned camera's, cannot tell). The camera criterion says both in
    place of naming the other camera's view."""
    t = g.rubric.results.get("unbiased")
    cam = g.rubric.results.get("camera")
    if hand.cam == g.a.camera or t is None or t.status != "failed" or cam is None or cam.status != "failed":
        return
    manifest = cam.output.split("; your manifest says ", 1)
    g.rubric.failed("camera", f"the view is nearer the {hand.cam!r} camera's than the {g.a.camera!r} camera's the "
                    f"assignment asks for, but graded against the {hand.cam!r} camera's reference it still differs (the "
                    f"bias test fails): it is the {hand.cam!r} camera's view with another mistake, or neither camera's; "
                    f"check the camera's eye, direction and field of view against the {g.a.camera!r} camera's"
                    + (f"; your manifest says {manifest[1]}" if len(manifest) == 2 else ""))
    g.details["orientation"]["camera_confirmed"] = False


def encoding(g: Grading, hand: Hand) -> None:
    """The ``linear`` criterion: a display image's curve, or a curve on data that should be linear radiance."""
    a = g.a
    hand.base_tile = next((t for t in a.tiles if t > 0), 8)
    if hand.loaded.fmt.startswith("png"):
        times_256 = _codes_times_256(hand.loaded)
        hand.png_safe = _png_unclipped(hand.R, g.ctx.model_var[hand.cam].astype(np.float64), hand.spp or a.min_spp)
        hand.imgs, hand.qvar = _png_curve(g, hand)
        wrapped = _wrapped(g, hand)
        wrong = {k: v for k, v, found in (("times_256", TIMES_256, times_256), ("wrapped", WRAPPED, wrapped),
                                          ("white_zero", WHITE_ZERO, not wrapped and _white_zero(g, hand)),
                                          ("rounded_first", ROUNDED_FIRST, _rounded_first(g, hand)),
                                          ("cast_first", CAST_FIRST, _cast_first(hand.loaded)))
                 if found}
        _codes_failed(g, wrong)
    else:
        _hdr_encoding(g, hand)
        k = _decimals(hand.loaded)
        _codes_failed(g, {f"decimals_{k}": DECIMALS.format(k=k, step=f"{10.0 ** -k:g}")} if k else {})


def _codes_failed(g: Grading, wrong: dict[str, str]) -> None:
    """Fail ``linear`` for the file's code mistakes (key -> words), put before what the curve's test said of the
    values; nothing where there are none."""
    if not wrong:
        return
    g.details.setdefault("encoding", {})["codes"] = list(wrong)
    t = g.rubric.results.get("linear")
    before = [t.output] if t is not None and t.status == "failed" else []
    g.rubric.failed("linear", "; also, ".join(list(wrong.values()) + before))


TIMES_256 = ("every 16-bit code is a multiple of 256: 8-bit codes times 256, where 16 bits hold them times 257 (white "
             "is 65535, not 65280), so every value is 0.4 % dark and white is never reached; graded as the 8-bit "
             "codes they are: write the render's values at 16 bits (round(v * 65535)), or the 8-bit codes times 257")
WRAPPED = ("the pixels that should be white (the light and its reflections, far above 1) hold the codes that values "
           "past 1 give when cast to 8 bits without a clip (they wrap round past 255): clip to [0, 1] before "
           "converting to 8 bits")

WHITE_ZERO = ("the pixels that should be white (the light and its reflections, far above 1) hold 0: the top code "
              "overflowed (a value of 1 times 256, or times 65536 at 16 bits, wraps to 0 in the file's integers), "
              "a NaN was written as 0 (a value past the end of a lookup table, such as interp1d's NaN fill value, "
              "cast to an integer), or those pixels were never drawn; scale by 255 (65535 at 16 bits) and clip to "
              "[0, 1] before any lookup and the cast")

ROUNDED_FIRST = ("the dark codes are only those that linear values rounded to 8 bits give through the curve (none of "
                 "1-12 where the sRGB curve is the file's, then 13, 22, 28, ...): the values were rounded to 8 bits "
                 "before the curve (a 256-entry table on 8-bit linear values), so the shadows are in coarse steps; "
                 "apply the curve to the floating-point values, then round to 8 bits")
CAST_FIRST = ("every code is 0 or 255: the values were cast to integers before they were scaled by 255 (a cast turns "
              "everything below 1 into 0, and the light into 1); scale by 255, round, then cast")

DECIMALS = ("every value is a multiple of {step}: the values were rounded to {k} decimals before saving (as "
            "round(v, {k}) does), so the shadows are in steps of {step}; save the floating-point values as they are")

#: The dark codes the test of :func:`_rounded_first` looks at, and how many it needs.
_DARK_CODES, _MIN_DARK = (1, 40), 20


def _codes_times_256(loaded) -> bool:
    """A 16-bit display file whose every code is a multiple of 256 (and not all 0): 8-bit codes times 256. A render
    written at 16 bits has that by chance with probability 256^-N; the images are replaced by the 8-bit codes' reading
    (``loaded.fmt`` png8), so quantisation and clipping are an 8-bit file's."""
    if not loaded.fmt.startswith("png16"):
        return False
    codes = [np.rint(ck.png_codes(i, loaded.fmt) * 65535).astype(np.int64) for i in loaded.images]
    if any(np.any(c % 256) for c in codes) or max(int(c.max()) for c in codes) == 0:
        return False
    decode = ck.PNG_CURVES["linear" if loaded.fmt.endswith("linear") else "srgb"][0]
    loaded.images = [decode(c / (256 * 255.0)) for c in codes]
    loaded.fmt = loaded.fmt.replace("png16", "png8")
    return True


#: Curves that are the sRGB curve copied wrongly, not a display encoding chosen: they lose the criterion's points
#: whatever ``png_gamma_loss`` (which accepts a gamma of 2.2 or 2) says.
MISTAKEN_CURVES = ("gamma2.4", "inverted2.2")

#: The codes a transfer curve gives a value (the inverses of mcrt.grade.checks.PNG_CURVES' decodings).
_ENCODE = {"srgb": srgb_oetf, "gamma2.2": lambda x: x ** (1 / 2.2), "gamma2": np.sqrt,
           "gamma2.4": lambda x: x ** (1 / 2.4), "linear": lambda x: x, "inverted2.2": lambda x: x ** 2.2}


def _wrapped(g: Grading, hand: Hand) -> bool:
    """8-bit codes cast without a clip: the pixels whose expected value is far above 1 (the reference minus 4 sd of a
    hand-in pixel at least 1.5 in every channel, so a correct file holds the top code there) mostly do not hold it,
    and hold the code ``round(encode(R) * 255) mod 256`` instead (within 2 codes and 3 sd). Only where at least 3
    such pixels are seen at the grade resolution itself (each hand-in pixel is a grade pixel)."""
    loaded, curve = hand.loaded, (g.details.get("encoding") or {}).get("detected")
    if not loaded.fmt.startswith("png8") or hand.plan.down != 1 or curve not in _ENCODE:
        return False
    sd = np.sqrt(g.ctx.model_var[hand.cam].astype(np.float64) / max(hand.spp or g.a.min_spp, 1))
    must = np.all(hand.R - 4 * sd >= 1.5, axis=2) & hand.mask
    if np.count_nonzero(must) < 3:
        return False
    enc = _ENCODE[curve]
    codes = np.rint(ck.TRANSFORMS[hand.transform][1](ck.png_codes(loaded.images[0], loaded.fmt)) * 255)[must]
    R, s = hand.R[must], sd[must]
    wrapped = np.rint(enc(R) * 255) % 256
    tol = 2 + 3 * 255 * (enc(R + s) - enc(np.maximum(R - s, 0))) / 2
    off = np.abs(codes - wrapped)
    match = np.all(np.minimum(off, 256 - off) <= tol, axis=-1)
    return bool(np.mean(np.any(codes < 250, axis=-1)) >= 0.5 and np.mean(match) >= 0.8)


def _white_zero(g: Grading, hand: Hand) -> bool:
    """A display file black where it must be white: of the pixels whose expected value is far above 1 with all their
    neighbours (the reference minus 4 sd of a hand-in pixel at least 1.5 in every channel, the set eroded by one
    pixel, so that every hand-in pixel within one is inside the light's image too), at least 3, and at least half of
    them hold the code 0 in every channel in most of their hand-in pixels. A correct file holds the top code there, a
    dark or tone-mapped one a code well above 0; 0 is what a top code that overflowed gives, or nothing drawn."""
    from scipy import ndimage

    loaded = hand.loaded
    sd = np.sqrt(g.ctx.model_var[hand.cam].astype(np.float64) / max(hand.spp or g.a.min_spp, 1))
    must = ndimage.binary_erosion(np.all(hand.R - 4 * sd >= 1.5, axis=2) & hand.mask, structure=np.ones((3, 3), bool))
    if np.count_nonzero(must) < 3:
        return False
    codes = ck.TRANSFORMS[hand.transform][1](ck.png_codes(loaded.images[0], loaded.fmt))
    zero = ck.box_down(np.all(codes == 0, axis=-1, keepdims=True).astype(np.float64), hand.plan.down)[..., 0]
    return zero.shape == must.shape and bool(np.mean(zero[must] > 0.5) >= 0.5)


def _decimals(loaded) -> int:
    """k where a float file's every value is a multiple of 10^-k (k = 1, 2, 3), within its precision, and at least
    50 non-zero values are small enough (below 10^(2-k)) for that to be no accident of the precision: values rounded
    to k decimals. A render's values are such a multiple, to a half float's precision, with a chance of about 1 in
    50 each. 0 where none."""
    if loaded.fmt not in ("float", "half"):
        return 0
    x = np.concatenate([np.asarray(i, np.float64).ravel() for i in loaded.images])
    x = np.abs(x[np.isfinite(x) & (x != 0)])
    for k in (1, 2, 3):
        step = 10.0 ** -k
        small = x[x < 100 * step]
        if small.size < 50:
            continue
        off = np.abs(small / step - np.rint(small / step)) * step
        if np.all(off <= small * 2.0 ** -10 + 1e-7):
            return k
    return 0


def _rounded_first(g: Grading, hand: Hand) -> bool:
    """An 8-bit file whose dark codes (1 to 40, in any channel) all lie among ``round(255 encode(k / 255))``: linear
    values rounded to 8 bits before the curve. Through the sRGB curve that leaves 5 of the 40 codes (13, 22, 28, 34,
    38), so a render encoded from floats has all of at least 20 such values there with a chance below 0.2^20 (its dark
    codes fall about as often on the others). Only for a curve that spreads the dark codes apart, leaving most of them
    out: not a linear file, nor a curve that darkens, which reaches every dark code (the test would have no power)."""
    loaded, curve = hand.loaded, (g.details.get("encoding") or {}).get("detected")
    if not loaded.fmt.startswith("png8") or curve not in _ENCODE:
        return False
    lo, hi = _DARK_CODES
    allowed = np.unique(np.rint(_ENCODE[curve](np.arange(256) / 255.0) * 255))
    if np.isin(np.arange(lo, hi + 1), allowed).mean() > 0.5:
        return False
    codes = np.concatenate([np.rint(ck.png_codes(i, loaded.fmt) * 255).ravel() for i in loaded.images])
    dark = codes[(codes >= lo) & (codes <= hi)]
    return dark.size >= _MIN_DARK and bool(np.all(np.isin(dark, allowed)))


def _cast_first(loaded) -> bool:
    """An 8-bit file whose every code is 0 or 255, with both present: values cast to integers, then scaled. A render
    of the room has most of its pixels in between."""
    if not loaded.fmt.startswith("png8"):
        return False
    codes = np.concatenate([np.rint(ck.png_codes(i, loaded.fmt) * 255).ravel() for i in loaded.images])
    return bool(np.all((codes == 0) | (codes == 255)) and np.any(codes == 0) and np.any(codes == 255))


def _png_curve(g: Grading, hand: Hand):
    """A display image's transfer curve (:func:`mcrt.grade.checks.detect_png_curve`), decoded per hand-in pixel."""
    rub, th, loaded, plan = g.rubric, g.th, hand.loaded, hand.plan
    fmt = loaded.fmt
    declared = "linear" if fmt.endswith("linear") else "srgb"
    inv = ck.TRANSFORMS[hand.transform][1]
    codes = [inv(ck.png_codes(i, fmt)) for i in loaded.images]
    cands = {c: [ck.box_down(dec(x), plan.down) for x in codes] for c, (dec, _) in ck.PNG_CURVES.items()}
    enc = ck.detect_png_curve({c: v[0] for c, v in cands.items()}, hand.R, hand.mask & hand.png_safe, hand.base_tile,
                              declared)
    curve = declared if g.as_declared else enc.curve
    g.details["encoding"] = {"detected": curve, "declared": declared, "curve_chi2": {k: round(v, 2) for k, v in enc.chi2.items()}}
    qvar = [ck.box_down(ck.curve_quantisation_variance(x, curve, fmt), plan.down) / plan.down**2 for x in codes]
    what = ck.PNG_CURVES[curve][1]
    if curve != enc.curve:
        g.details["encoding"]["fitted"] = enc.curve
        rub.passed("linear", _as_declared_text(ck.PNG_CURVES[enc.curve][1]))
    elif curve == declared:
        rub.passed("linear", "sRGB-encoded image, decoded to linear" if curve == "srgb" else "linear image, as declared")
    elif curve == "linear":
        rub.failed("linear", "the PNG holds linear values but PNGs are read as sRGB-encoded: declare `linear = true` in "
                   "your manifest, or encode with the sRGB curve before writing 8-bit files")
        hand.corrected.append("linear")
    elif declared == "linear":
        rub.failed("linear", f"the manifest declares the image linear, but its values follow {what}; it was decoded "
                   "with that curve: leave `linear` out of the manifest for a gamma-encoded image")
        hand.corrected.append("linear")
    else:
        text = (f"written with {what} rather than the sRGB curve; decoded with it (the sRGB curve is the standard "
                "one for 8-bit files)")
        if curve in MISTAKEN_CURVES:  # no display encoding a program chooses: the sRGB curve copied wrongly
            rub.failed("linear", text)
            hand.corrected.append("linear")
        elif th.png_gamma_loss > 0:
            rub.failed("linear", text, loss=th.png_gamma_loss)
            hand.corrected.append("linear")
        else:
            rub.passed("linear", text)
    return cands[curve], qvar


def _hdr_encoding(g: Grading, hand: Hand) -> None:
    """A gamma or sRGB curve on data that should be linear radiance (:func:`mcrt.grade.checks.detect_encoding`)."""
    rub, fmt = g.rubric, hand.loaded.fmt
    enc = ck.detect_encoding(hand.imgs[0], hand.R, hand.mask, fmt, hand.base_tile)
    kind = "linear" if g.as_declared else enc.kind
    g.details["encoding"] = {"detected": kind, "spreads": {k: round(v, 4) for k, v in enc.spreads.items()}}
    g.encoding = kind
    if kind != enc.kind:
        g.details["encoding"]["fitted"] = enc.kind
        rub.passed("linear", _as_declared_text(f"the {enc.kind} curve"))
    elif enc.kind != "linear":
        rub.failed("linear", enc.message)
        dec = ck.ENCODINGS[enc.kind][0]
        hand.imgs = [dec(i) for i in hand.imgs]
        hand.qvar = [quantisation_variance(i, fmt) / hand.plan.down**2 for i in hand.imgs]
        hand.corrected.append("linear")
    else:
        rub.passed("linear", "linear radiance")


def judge_encoding(g: Grading, hand: Hand, flagged: bool) -> None:
    """The encoding finding under the claim rule (:mod:`mcrt.grade.adequacy`), once the bias test is known.

    A curve is read off the image as the best of a few; on an image that,
    decoded with it, still differs from the reference beyond noise, with no
    cause that fits what is left (no claim of the explanation stage), that
    choice is no evidence of an encoding (an image with its rows sheared fits
    one curve a little better than another). The finding is then not judged,
    as the exposure criterion claims a factor only where it leaves an image
    that passes: the bias test's points go for the difference. Where the
    explanation claims the render's values at other places (:data:`MOVED`),
    the curve fitted better only because the tiles it compares hold other
    pixels' values: the file counts as encoded as declared, and the grader
    reads it again so decoded (:func:`read_as_declared`).
    """
    from mcrt.grade.candidates import CLAIMED

    if "linear" not in hand.corrected or not flagged:
        return
    e = g.explanation
    moved = moved_claim(g)
    if e is not None and e.verdict == CLAIMED and not moved:
        return
    detected = (g.details.get("encoding") or {}).get("detected", "")
    what = ck.PNG_CURVES.get(detected, (None, f"the {detected} curve"))[1]
    if moved:  # the grader reads the file again as declared (read_as_declared); this stands where that claims nothing
        g.rubric.passed("linear", _as_declared_text(what))
        g.details["encoding"].update(detected=g.details["encoding"].get("declared", "linear"), fitted=detected)
    else:
        g.rubric.passed("linear", f"not judged: the values fit {what} best, but decoded with it the "
                        "image still differs from the reference in a way no cause we tried explains, so the file's "
                        "encoding cannot be told apart from the rest of the difference")
        g.details["encoding"]["judged"] = False
    g.encoding = "linear"


#: The explanation's families that put the render's values at other places unchanged (a memory layout, lines or tiles
#: out of order or repeated): a curve fitted to such an image is no evidence of its encoding.
MOVED = frozenset({"stride", "layout", "lines_order", "tiles", "lines_aliased"})


def _as_declared_text(what: str) -> str:
    """The ``linear`` finding of a file read as declared where ``what`` (a curve's words) fits its values better."""
    return (f"encoded as declared: the values fit {what} better, but decoded as declared the image is the render's "
            "values at other places (the bias test's explanation), and noise")


def moved_claim(g: Grading) -> bool:
    """The explanation claims the render's values at other places (:data:`MOVED`)."""
    from mcrt.grade.candidates import CLAIMED

    e = g.explanation
    return e is not None and e.verdict == CLAIMED and e.named.family in MOVED


def read_as_declared(g: Grading) -> bool:
    """Whether to grade the hand-in again with the file decoded as declared: a first reading decoded it with another
    curve and its explanation then claimed moved values (:func:`judge_encoding`). That reading's noise, bias and
    exposure findings describe the file through the wrong curve (an image several times too bright, where decoded
    as declared it holds the render's own values), so the grader keeps the second reading where it claims moved
    values too."""
    return not g.as_declared and "fitted" in (g.details.get("encoding") or {}) and moved_claim(g)


def _png_unclipped(R, model_ps, spp: int) -> np.ndarray:
    """Grade pixels an 8-bit image cannot have clipped: expected value plus 3 sd of a hand-in pixel below 1,
    and not next to a pixel that is not (a grade pixel's hand-in pixels may see a brighter neighbour)."""
    from scipy import ndimage

    sd = np.sqrt(model_ps / max(spp, 1))  # a hand-in pixel's noise: its per-sample variance is at most a grade pixel's
    bright = np.any(R + 3 * sd >= 1.0, axis=2)
    return ~ndimage.binary_dilation(bright, structure=np.ones((3, 3), bool))
