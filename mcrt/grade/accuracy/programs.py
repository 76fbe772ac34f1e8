r"""A third class of hand-ins: mistakes of students' programs, written apart from the grader's rules.

How it was written: from what goes wrong in students' ray tracers and in the
few lines that save their image, not from the grader. Its author did not
grade any of it nor read the grader's rules (only the cause words of the other
classes and of :data:`~mcrt.grade.accuracy.run.CAUSE_OF`, to reuse them). The mistakes were chosen to differ from the two other classes
(:mod:`~mcrt.grade.accuracy.cases`, :mod:`~mcrt.grade.accuracy.outside`):

* the array written in the wrong **orientation** (a PFM's rows written top
  to bottom, columns reversed, the array indexed ``[x, y]``);
* values written with the wrong **encoding** (gamma 2.2 in an EXR, linear
  codes in a 16-bit PNG, sRGB applied twice);
* **colour lost** (luminance written to all channels; a channel zeroed);
* a constant factor (an exposure for display; dividing by twice the spp);
* **direct light counted twice** (a direct-lighting pass added to a path
  tracer that has one; emission counted on every hit and by light sampling
  without MIS);
* the path depth off by one, or direct light only;
* the walls' colours shifted by one, floor and ceiling swapped;
* **bad pixels** (NaN written as 0; a tile never rendered);
* a **per-sample clamp** that removes fireflies and energy with them;
* fewer samples than declared;
* one each of: the ceiling missing, the sphere raised by its radius, the
  light twice as large at the same radiance, the light lowered, the light
  facing the ceiling, pixel centres at integer x only.

The correct hand-ins use other samplers, Russian roulette from the first
bounce, mcrt, and files students write by hand (PFM, 16-bit PNG, 8-bit PNG).
Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s
``edit`` and ``mitsuba_edit``), Mitsuba renders combined
(:func:`_with_render`, :func:`_clamped_samples`), or correct renders
post-processed and written with NumPy, Pillow and pypng the way students'
programs do (:data:`POSTS`, the ``writer`` functions). mcrt renders only
correct hand-ins.

Causes use the words of the other classes where the mistake really is that
cause; the keys new here (``orientation``, ``colour_lost``,
``direct_twice``, ``bad_pixels``, ``sample_clamp``, ``light_facing``)
describe mistakes no existing cause does, and the grader may name none.

**Held out**, fixed when the class was written, before any case was graded:
within each cause, in the order written below, the 2nd, 4th, ... case is held
out; the causes with a single case alternate among themselves in the order
written, the first not held out; the correct hand-ins alternate the same way.
:func:`held_out_rule` states the rule as code and the tests check the specs
against it.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import cases, outside
from mcrt.grade.accuracy.cases import Spec, light, moved
from mcrt.image_files import srgb_oetf
from mcrt.scene import Scene

#: The causes new in this class, as the report words them (the others are those of cases.CAUSES and outside.CAUSES).
NEW_CAUSES: dict[str, str] = {
    "orientation": "the image written flipped, mirrored or transposed",
    "colour_lost": "colour lost (one grey value in all channels, or a channel zeroed)",
    "direct_twice": "direct light counted twice",
    "bad_pixels": "pixels not computed (NaN written as 0, a tile left black)",
    "sample_clamp": "samples clamped (fireflies removed with their energy)",
    "light_facing": "the light emitting on the wrong side",
}



# --------------------------------------------------------------------------
# Files as students' programs write them (linear image in, file out)
# --------------------------------------------------------------------------

_LUMA = np.array([0.2126, 0.7152, 0.0722])  # Rec. 709 / sRGB luminance weights


def _srgb(x):
    return srgb_oetf(np.clip(x, 0.0, 1.0))


def _codes(x, bits: int) -> np.ndarray:
    top = (1 << bits) - 1
    return np.floor(np.clip(np.nan_to_num(x), 0.0, 1.0) * top + 0.5).astype(np.uint16 if bits > 8 else np.uint8)


def _write_pfm(image: np.ndarray, folder: Path, *, top_down: bool = False) -> Path:
    """A PFM as ``f.write(header); f.write(img.astype('<f4').tobytes())``: rows bottom to top, unless ``top_down``."""
    rows = image if top_down else image[::-1]
    h, w = image.shape[:2]
    path = folder / "render.pfm"
    path.write_bytes(f"PF\n{w} {h}\n-1.0\n".encode() + np.ascontiguousarray(rows, "<f4").tobytes())
    return path


def _write_png16(image: np.ndarray, folder: Path, *, srgb: bool) -> Path:
    """A 16-bit RGB PNG written with pypng, sRGB-encoded or holding linear codes."""
    import png

    h, w = image.shape[:2]
    codes = _codes(_srgb(image) if srgb else image, 16)
    path = folder / "render.png"
    with open(path, "wb") as f:
        png.Writer(w, h, bitdepth=16, greyscale=False).write(f, codes.reshape(h, w * 3).tolist())
    return path


def _write_png8(image: np.ndarray, folder: Path, *, times: int = 1, grey: bool = False) -> Path:
    """An 8-bit PNG written with Pillow after ``times`` sRGB encodings; ``grey``: one luminance channel (mode L)."""
    from PIL import Image

    v = image @ _LUMA if grey else image
    for _ in range(times):
        v = _srgb(v)
    path = folder / "render.png"
    Image.fromarray(_codes(v, 8), "L" if grey else "RGB").save(path, format="PNG")
    return path


# --------------------------------------------------------------------------
# Post-processes (linear render in, what the program holds before writing)
# --------------------------------------------------------------------------


def _mirror_x(x):
    return x[:, ::-1]


def _transpose(x):
    return np.swapaxes(x, 0, 1)


def _zero_channel(x, c: int):
    x = x.copy()
    x[..., c] = 0.0
    return x


def _scaled(x, f: float):
    return x * f


def _nan_as_zero(x, fraction: float, seed: int):
    """A fraction of pixels whose value was NaN (a 0/0 in a pdf), written as 0 (``np.nan_to_num``)."""
    x = x.copy()
    x[np.random.default_rng(seed).random(x.shape[:2]) < fraction] = np.nan
    return np.nan_to_num(x)


def _tile_black(x, row: int, col: int):
    """One of the 4 x 4 tiles (row, col) never written: a worker thread's tile lost."""
    x = x.copy()
    th, tw = x.shape[0] // 4, x.shape[1] // 4
    x[row * th:(row + 1) * th, col * tw:(col + 1) * tw] = 0.0
    return x


def _render(shape, integrator: dict, spp: int, seed: int, *, supersample: int = 1):
    """A Mitsuba render of the canonical scene at ``shape`` (times ``supersample``): the mean, linear RGB."""
    from mcrt.mitsuba_scene import render_with_variance, scene_dict
    from mcrt.scene import load_scene

    h, w = shape[0] * supersample, shape[1] * supersample
    d = scene_dict(load_scene(), "near", w, h, 8, spp=spp)
    d["integrator"] = dict(integrator)
    return np.asarray(render_with_variance(d, spp=spp, seed=seed).mean, np.float64)


def _with_render(x, *, factor: float, weight: float, integrator: dict, spp: int, seed: int):
    """``factor`` times the render plus ``weight`` times another Mitsuba render (``integrator``) of the same scene."""
    return factor * x + weight * _render(x.shape, integrator, spp, seed)


def _clamped_samples(x, *, limit: float, k: int, seed: int):
    """Each sample clamped to ``limit`` before averaging, ``k * k`` samples a pixel (the render ``x`` gives the size).

    One Mitsuba sample in each of ``k x k`` sub-pixels (a box filter: the
    sub-pixel's value is that sample), clamped, then averaged per pixel.
    """
    s = np.minimum(_render(x.shape, {"type": "path", "max_depth": 8}, 1, seed, supersample=k), limit)
    h, w = x.shape[:2]
    return s.reshape(h, k, w, k, 3).mean(axis=(1, 3))


def _crc(name: str) -> int:
    return 7000 + zlib.crc32(name.encode()) % 100000


#: Post-processes by name (the report shows the name): linear render in, what the program writes out.
POSTS = {
    "mirror_x": _mirror_x,
    "transpose": _transpose,
    "zero_blue": partial(_zero_channel, c=2),
    "times_2": partial(_scaled, f=2.0),
    "halved": partial(_scaled, f=0.5),
    "plus_direct": partial(_with_render, factor=1.0, weight=1.0, integrator={"type": "direct", "hide_emitters": True},
                           spp=256, seed=_crc("plus_direct")),
    "nee_and_hits": partial(_with_render, factor=2.0, weight=-1.0, integrator={"type": "path", "max_depth": 1},
                            spp=64, seed=_crc("nee_and_hits")),
    "nan_as_zero": partial(_nan_as_zero, fraction=0.005, seed=_crc("nan_as_zero")),
    "tile_black": partial(_tile_black, row=1, col=2),
    "clamp_1": partial(_clamped_samples, limit=1.0, k=8, seed=_crc("clamp_1")),
    "clamp_4": partial(_clamped_samples, limit=4.0, k=8, seed=_crc("clamp_4")),
}


def _posted(name: str) -> dict:
    return {"post": name, "post_fn": POSTS[name]}


# --------------------------------------------------------------------------
# Scene edits
# --------------------------------------------------------------------------


def _walls_shifted(s: Scene) -> Scene:
    """Each wall given the previous wall's colour (the colours' list read one place off)."""
    walls = s.room.walls
    shifted = tuple(replace(w, albedo=walls[k - 1].albedo) for k, w in enumerate(walls))
    return replace(s, room=replace(s.room, walls=shifted))


def _floor_ceiling_swapped(s: Scene) -> Scene:
    return replace(s, room=replace(s.room, floor_albedo=s.room.ceiling_albedo, ceiling_albedo=s.room.floor_albedo))


def _without_surface(d: dict, name: str) -> dict:
    return {k: v for k, v in d.items() if k != name}


def _roulette_from(d: dict, depth: int) -> dict:
    return dict(d, integrator=dict(d["integrator"], rr_depth=depth))


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

_SIDE2 = 2.0 * math.sqrt(2.0)  # a 2 x 2 light twice as large in area

#: Wrong hand-ins, grouped by cause in the order the held-out rule reads them.
MISTAKES: tuple[Spec, ...] = (
    # Orientation
    Spec("pfm_top_down", "orientation", True, writer=partial(_write_pfm, top_down=True), file="pfm-rows-top-down",
         truth="a PFM written top row first (PFM stores the bottom row first): the image upside down"),
    Spec("mirrored_x", "orientation", True, held_out=True, **_posted("mirror_x"),
         truth="columns written right to left (x index reversed): the image mirrored"),
    Spec("transposed", "orientation", True, **_posted("transpose"), file="png-srgb",
         truth="the array indexed [x, y] and saved as an sRGB PNG: the image transposed"),
    # Encoding
    Spec("exr_gamma22", "encoding", file="exr-gamma2.2", truth="gamma 1/2.2 applied, then saved as EXR"),
    Spec("png16_linear", "encoding", held_out=True, writer=partial(_write_png16, srgb=False), file="png16-linear",
         truth="linear values written to a 16-bit PNG with no sRGB encoding"),
    Spec("png_srgb_twice", "encoding", writer=partial(_write_png8, times=2), file="png-srgb-twice",
         truth="the sRGB curve applied twice before an 8-bit PNG"),
    # Colour lost
    Spec("grey_luminance", "colour_lost", True, writer=partial(_write_png8, grey=True), file="png-grey",
         truth="luminance written as a greyscale 8-bit PNG"),
    Spec("blue_zeroed", "colour_lost", True, held_out=True, **_posted("zero_blue"),
         truth="the blue channel written as 0"),
    # A constant factor
    Spec("exposure_2", "light_radiance", True, **_posted("times_2"),
         truth="the image multiplied by 2 for display, saved as EXR"),
    Spec("halved_pfm", "light_radiance", True, held_out=True, **_posted("halved"), writer=_write_pfm, file="pfm",
         truth="the sum divided by 2 x spp (two passes counted twice), saved as PFM"),
    # Direct light counted twice
    Spec("plus_direct", "direct_twice", True, **_posted("plus_direct"),
         truth="a direct-lighting pass (Mitsuba direct, light itself hidden) added to the path-traced image"),
    Spec("nee_and_hits", "direct_twice", True, held_out=True, **_posted("nee_and_hits"),
         truth="emission counted both by light sampling and on BSDF hits at every bounce (2 x path - emitters seen)"),
    # Path depth
    Spec("depth_7", "depth", max_depth=7, truth="max depth 7 instead of 8 (off by one)"),
    Spec("depth_2", "depth", True, held_out=True, max_depth=2, truth="direct light only (max depth 2)"),
    # Surface colours
    Spec("walls_shifted", "albedo", True, edit=_walls_shifted,
         truth="each wall given the previous wall's colour (the list read one place off)"),
    Spec("floor_ceiling_swapped", "albedo", True, held_out=True, edit=_floor_ceiling_swapped,
         truth="floor albedo 0.8 and ceiling 0.6 (swapped)"),
    # Pixels not computed
    Spec("nan_zero", "bad_pixels", **_posted("nan_as_zero"), truth="0.5 % of pixels NaN, written as 0"),
    Spec("tile_black", "bad_pixels", True, held_out=True, **_posted("tile_black"),
         truth="one 16 x 16 tile (a sixteenth of the image) never rendered, left black"),
    # Per-sample clamp
    Spec("clamp_1", "sample_clamp", True, spp=1, declared_spp=64, **_posted("clamp_1"),
         truth="each sample clamped to 1 (64 spp, the light itself clamped too)"),
    Spec("clamp_4", "sample_clamp", held_out=True, spp=1, declared_spp=64, **_posted("clamp_4"),
         truth="each sample clamped to 4 (64 spp)"),
    # Claimed samples per pixel
    Spec("claims_512", "spp_claim", spp=32, declared_spp=512, truth="32 spp rendered, 512 declared"),
    Spec("claims_64", "spp_claim", held_out=True, spp=16, declared_spp=64, truth="16 spp rendered, 64 declared"),
    # Causes with one case each
    Spec("no_ceiling", "object_missing", True, mitsuba_edit=partial(_without_surface, name="ceiling"),
         truth="the ceiling missing (only floor and walls built)"),
    Spec("sphere_raised", "object_moved", True, held_out=True, edit=moved("sphere", (0.0, 0.0, 1.5)),
         truth="the sphere raised by its radius (its lowest point taken for its centre)"),
    Spec("light_area_2x", "light_size", True, edit=light(size=(_SIDE2, _SIDE2)),
         truth="the light twice as large in area (2.83 x 2.83), same radiance"),
    Spec("light_lowered", "light_position", True, held_out=True, edit=light(move=(0.0, 0.0, -1.0)),
         truth="the light 1 below the ceiling"),
    Spec("light_facing_up", "light_facing", True, edit=light(normal=(0.0, 0.0, 1.0)),
         truth="the light's normal pointing up: it emits into the ceiling"),
    Spec("pixel_offset_x", "pixel_offset", True, held_out=True, sensor={"principal_point_offset_x": 0.5 / 64},
         truth="pixel centres at integer x (i/W, half a pixel off) and at (j+0.5)/H in y"),
)

#: Correct hand-ins, alternating held out in the order written. A sampler other than independent renders in two
#: passes (mcrt.mitsuba_scene: its variance from batches), so that its hand-in holds, and declares, twice its spp.
CORRECT: tuple[Spec, ...] = (
    Spec("ok_ld_pfm", None, spp=256, sampler="ldsampler", writer=_write_pfm, file="pfm",
         truth="Mitsuba path, low-discrepancy sampler, two passes of 256 spp, PFM written bottom row first"),
    Spec("ok_mj_png16", None, spp=144, sampler="multijitter", held_out=True, writer=partial(_write_png16, srgb=True),
         file="png16-srgb", truth="Mitsuba path, multi-jittered sampler, two passes of 144 spp (a square), 16-bit sRGB PNG"),
    Spec("ok_strat_64", None, spp=64, sampler="stratified", truth="Mitsuba path, stratified sampler, two passes of 64 spp, EXR"),
    Spec("ok_rr1_256", None, spp=256, held_out=True, mitsuba_edit=partial(_roulette_from, depth=1),
         truth="Mitsuba path, Russian roulette from the first bounce, 256 spp"),
    Spec("ok_mcrt_pfm", None, spp=256, renderer="mcrt", writer=_write_pfm, file="pfm", truth="mcrt, 256 spp, PFM"),
    Spec("ok_mcrt_png8", None, spp=32, renderer="mcrt", held_out=True, writer=_write_png8, file="png-srgb",
         truth="mcrt, 32 spp, 8-bit sRGB PNG written with Pillow"),
)

SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

_WORDS = {**cases.CAUSES, **outside.CAUSES, **NEW_CAUSES}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = {c: _WORDS[c] for c in dict.fromkeys(s.cause for s in MISTAKES)}


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out, by name."""
    groups: dict[str | None, list[str]] = {}
    for s in specs:
        groups.setdefault(s.cause, []).append(s.name)
    single = [names[0] for c, names in groups.items() if c is not None and len(names) == 1]
    out = {}
    for c, names in groups.items():
        if c is not None and len(names) == 1:
            continue
        out.update({n: k % 2 == 1 for k, n in enumerate(names)})
    out.update({n: k % 2 == 1 for k, n in enumerate(single)})
    return out
