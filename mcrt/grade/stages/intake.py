"""Intake: a hand-in's manifest, the choice of its images, and reading them (the ``readable`` criterion)."""

from __future__ import annotations

from pathlib import Path

from mcrt.grade import checks as ck
from mcrt.grade.stages.state import Grading, Hand
from mcrt.grade.submissions import Submission, choose_images, read_manifest

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
    names = ", ".join(Path(f).name for f in loaded.files)
    container = _CONTAINERS.get(Path(loaded.files[0]).suffix.lower(), "PNG")
    h, w = loaded.images[0].shape[:2]
    rub.passed("readable", f"read {names} ({_kinds(container).get(loaded.fmt, loaded.fmt)}, {w}x{h}"
               f"{', two independent renders' if len(loaded.images) == 2 else ''})")
    spp = manifest.spp or loaded.spp_file
    g.details["spp_source"] = "manifest" if manifest.spp else "file" if loaded.spp_file else "not declared"
    if manifest.camera and manifest.camera != g.a.camera:
        g.notes.append(f"the manifest says camera {manifest.camera!r}; the assignment asks for {g.a.camera!r}")
    return Hand(loaded, spp), manifest.camera


def in_memory(g: Grading, images, spp: int | None, fmt: str) -> Hand:
    """Renders already in memory ((H, W, 3) linear float arrays, one or two): code mode's whole-render check."""
    import numpy as np

    imgs = [np.asarray(i, np.float64) for i in images[:2]]
    loaded = ck.Loaded(imgs, [f"render {k + 1}" for k in range(len(imgs))], fmt)
    g.rubric.passed("readable", f"{len(loaded.images)} render(s) returned in memory")
    return Hand(loaded, spp)
