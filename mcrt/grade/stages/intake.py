"""Intake: a hand-in's manifest, the choice of its images, and reading them (the ``readable`` criterion).

A PFM whose header declares the other byte order than its data are written in is read in the data's order and
loses the ``readable`` points (:func:`_byte_order`), as an undeclared encoding loses ``linear``'s."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mcrt.grade import checks as ck
from mcrt.grade.stages.state import Grading, Hand
from mcrt.grade.submissions import Submission, choose_images, read_manifest

#: A float value read from a PFM is implausible as radiance outside these magnitudes (or not finite): a float whose
#: bytes are read in the wrong order has its low mantissa byte as the exponent, so most such values are far beyond
#: either bound, while any renderer's radiance (zeros apart) lies well within them.
PLAUSIBLE = (1e-30, 1e30)
#: The share of values implausible as read per the header beyond which the other byte order is tried.
WRONG_ORDER_SHARE = 0.01

#: Integer images of every container (PNG, PPM, BMP, TGA) share the formats png8 and png16; the container by suffix.
_CONTAINERS = {".ppm": "PPM", ".pgm": "PGM", ".pnm": "PNM", ".bmp": "BMP", ".tga": "TGA"}


def _kinds(container: str) -> dict[str, str]:
    return {"float": "32-bit float", "half": "16-bit half float", "rgbe": "RGBE", "png8": f"8-bit sRGB {container}",
            "png16": f"16-bit sRGB {container}", "png8-linear": f"8-bit linear {container}",
            "png16-linear": f"16-bit linear {container}"}


def read(g: Grading, sub: Submission) -> tuple[Hand | None, str | None]:
    """The hand-in's renders and the camera its manifest declares; (None, None) when nothing could be read."""
    rub = g.rubric
    manifest = read_manifest(sub.manifest_path)
    g.notes += sub.notes + manifest.warnings
    if manifest.notes:
        g.details["student_notes"] = manifest.notes
    paths, choice_notes = choose_images(sub, manifest)
    g.notes += choice_notes
    if not paths:
        rub.failed("readable", sub.problem or "no image found")
        rub.block("no readable image")
        return None, None
    loaded, err = ck.read_renders(paths, bool(manifest.linear))
    if loaded is None:
        msg = err if not sub.problem else f"{sub.problem}; {err}"
        rub.failed("readable", msg)
        rub.block("the image could not be read")
        return None, None
    g.notes += loaded.notes
    swapped = _byte_order(g, paths, loaded)
    names = ", ".join(Path(f).name for f in loaded.files)
    container = _CONTAINERS.get(Path(loaded.files[0]).suffix.lower(), "PNG")
    h, w = loaded.images[0].shape[:2]
    read_text = (f"read {names} ({_kinds(container).get(loaded.fmt, loaded.fmt)}, {w}x{h}"
                 f"{', two renders' if len(loaded.images) == 2 else ''})")
    if swapped:  # a repairable file mistake: these points lost, the rest graded on the repaired render
        rub.failed("readable", f"{swapped}; {read_text}")
    else:
        rub.passed("readable", read_text)
    spp = manifest.spp or loaded.spp_file
    g.details["spp_source"] = "manifest" if manifest.spp else "file" if loaded.spp_file else "not declared"
    if manifest.camera and manifest.camera != g.a.camera:
        g.notes.append(f"the manifest says camera {manifest.camera!r}; the assignment asks for {g.a.camera!r}")
    hand = Hand(loaded, spp)
    if swapped:
        hand.corrected.append("byte order")
    return hand, manifest.camera


def implausible_share(img: np.ndarray) -> float:
    """The share of an image's values that no radiance has: not finite, or a non-zero magnitude outside
    :data:`PLAUSIBLE`."""
    with np.errstate(invalid="ignore", over="ignore"):
        a = np.abs(np.asarray(img, np.float64))
        bad = ~np.isfinite(a) | (a > PLAUSIBLE[1]) | ((a > 0) & (a < PLAUSIBLE[0]))
    return float(np.count_nonzero(bad)) / max(bad.size, 1)


def _byte_order(g: Grading, paths: list[str], loaded) -> str | None:
    """A PFM whose header's sign declares the wrong byte order (little-endian data under a positive scale, as x86
    programs that write 1.0 produce): its data read as declared are implausible (over :data:`WRONG_ORDER_SHARE` of
    the values) and in the other order every value is plausible; or a 16-bit PNG written little-endian
    (:func:`_png16_byte_order`). The render is replaced by the other order's reading (a stated repair, as an
    undeclared encoding is decoded) and the message for ``readable`` returned."""
    from mcrt.image_files import ImageError, pfm_scale, read_pfm

    said = []
    for k, p in enumerate(paths[: len(loaded.images)]):
        if loaded.fmt.startswith("png16"):
            said += _png16_byte_order(g, p, loaded, k)
        if Path(p).suffix.lower() != ".pfm" or implausible_share(loaded.images[k]) <= WRONG_ORDER_SHARE:
            continue
        try:
            other, scale = read_pfm(p, swap_byte_order=True), pfm_scale(p)
        except (ImageError, OSError, ValueError):
            continue
        if implausible_share(other) > 0:
            continue
        loaded.images[k] = np.asarray(other, np.float64)
        name = Path(loaded.files[k]).name
        g.details.setdefault("byte_order", []).append({"file": name, "scale": scale})
        declared, actual = ("big", "little") if scale > 0 else ("little", "big")
        fix = ("write -1.0 (little-endian) in the header, as x86 programs should" if actual == "little"
               else "write 1.0 (big-endian) in the header, or write the floats little-endian under -1.0")
        said.append(f"{name}: the PFM's header scale {scale:.1f} declares {declared}-endian data, but the "
                    f"data are {actual}-endian: {fix}; graded as read {actual}-endian")
    return "; ".join(said) or None


def _png16_byte_order(g: Grading, path: str, loaded, k: int) -> list[str]:
    """A 16-bit PNG whose samples were written little-endian (a program's uint16 buffer written as it lies in an x86
    machine's memory; PNG is big-endian): as read it resembles no view of the scene (its high bytes are the samples'
    low bytes, noise), and byte-swapped it does (luminance rank correlation with the reference of at least
    :data:`mcrt.grade.checks.RESEMBLES`). The render is replaced by the swapped reading and the message returned."""
    from mcrt.image_files import ImageError, read_png

    ref = g.ctx.references[g.a.camera].mean
    if ref.shape != loaded.images[k].shape or ck.resemblance(loaded.images[k], ref) >= ck.RESEMBLES:
        return []
    try:
        other = read_png(path, linear=loaded.fmt == "png16-linear", swap_byte_order=True)
    except (ImageError, OSError, ValueError):
        return []
    if ck.resemblance(other, ref) < ck.RESEMBLES:
        return []
    loaded.images[k] = np.asarray(other, np.float64)
    name = Path(loaded.files[k]).name
    g.details.setdefault("byte_order", []).append({"file": name, "png16": "little-endian"})
    return [f"{name}: the 16-bit PNG's samples are little-endian (each sample's two bytes swapped; PNG stores them "
            "big-endian): write them with a PNG library, or byteswap() a uint16 array before writing; graded with "
            "the bytes swapped back"]


def in_memory(g: Grading, images, spp: int | None, fmt: str) -> Hand | None:
    """Renders already in memory ((H, W, 3) linear float arrays, one or two): code mode's whole-render check.

    None, with "readable" failed, when one is not an (H, W, 3) image with at least one pixel."""
    import numpy as np

    empty = next((np.shape(i) for i in images[:2] if np.ndim(i) != 3 or np.shape(i)[2] != 3 or 0 in np.shape(i)), None)
    if empty is not None:  # the hand-in's problem, said as such (not a crash of the grader)
        g.rubric.failed("readable", f"the render has shape {empty}; an image is (height, width, 3) with at least one pixel")
        g.rubric.block("no image to grade")
        return None
    imgs = [np.asarray(i, np.float64) for i in images[:2]]
    loaded = ck.Loaded(imgs, [f"render {k + 1}" for k in range(len(imgs))], fmt)
    g.rubric.passed("readable", f"{len(loaded.images)} render(s) returned in memory")
    return Hand(loaded, spp)
