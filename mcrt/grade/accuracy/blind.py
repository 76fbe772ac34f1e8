r"""A fifth class of hand-ins: mistakes made outside the scene file, written blind to the grader.

How it was written: from what goes wrong in students' programs around a
correct scene, not from the grader. Its author read the other classes' specs
and cause words, :data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE` (with the scoring equivalences
beside them), to reuse their words; never the grader's rules (what decides a
cause), and graded none of it, not one case. Each cause and ``major`` flag
was set from the mistake alone, and the equivalences of the new causes were
added to ``SAME_MISTAKE`` before any grading. The mistakes differ from those
of the four other classes (:mod:`~mcrt.grade.accuracy.cases`,
:mod:`~mcrt.grade.accuracy.outside`, :mod:`~mcrt.grade.accuracy.programs`,
:mod:`~mcrt.grade.accuracy.fresh`):

* **post-processing**: Hable's filmic curve; the image divided by 4 for
  display, the factor written in a sidecar file and not applied; an unsharp
  mask; the saturation raised;
* **writing the file**: a planar buffer (all R, then all G, then all B)
  written as interleaved; 12-bit codes in a 16-bit PNG; a row stride of
  ``W - 1``; a hand-written BMP declaring bottom-up rows and given them top
  first;
* **materials**: every Lambertian divided by pi twice; every albedo squared;
  the mirror a silver conductor (Fresnel); the mirror weighted by a glass's
  Fresnel reflectance; the floor given the mirror's material;
* **camera model**: a thin lens with a small aperture; the field of view
  taken as the diagonal's; a 4:3 aspect ratio hard-coded into a square
  image; pixel jitter twice the pixel's width;
* **light model**: the radiance times the light's area; the light's pdf
  without its area; a disk inscribed in the square; the light sampled on
  one of its two triangles with the square's pdf;
* **resolution**: rendered at 63 x 63 and padded; rendered at 65 x 65 and
  cropped; rendered at 32 x 32 and enlarged with Pillow's default (bicubic)
  on 8-bit codes;
* **samples per pixel**: each colour channel from its own samples, their sum
  declared; adaptive sampling stopped per pixel, the most declared; a render
  interrupted with tiles at different spp, the target declared.

The correct hand-ins come in ways no class used: a BMP, a big-endian PFM
declared so, an EXR with a luminance channel beside R, G, B, a PNG with a
gAMA chunk, a 2x render reduced by 2 x 2 means, a Radiance HDR stored bottom
row first (``+Y``), mcrt as an 8-bit PPM, and a tiled EXR.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s
``edit``, ``sensor`` and ``mitsuba_edit``), Mitsuba renders combined where
light transport or pixel integrals are linear in what is combined (paths
seen directly or not, sub-pixel means, tiles, channels), or correct renders
post-processed and written with NumPy, SciPy, Pillow, pypng and OpenEXR as
students' programs do. mcrt renders only a correct hand-in.

Causes use the words of the other classes where the mistake really is that
cause (reworded for this class where the old words name only another
instance: :data:`_REWORDED`); the keys new here (:data:`NEW_CAUSES`) describe
mistakes no existing cause does.

**Held out**, fixed when the class was written, before any case was graded:
within each category above, in the order written, the 1st, 3rd, ... mistake
is tuned on and the 2nd, 4th, ... held out; the correct hand-ins alternate
the same way, the first tuned on. :func:`held_out_rule` states the rule as
code (the categories are :data:`CATEGORIES`) and the tests check the specs
against it.
"""

from __future__ import annotations

import math
import struct
import zlib
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import cases, fresh, outside, programs
from mcrt.grade.accuracy.cases import Spec
from mcrt.image_files import srgb_oetf

#: The causes new in this class, as the report words them.
NEW_CAUSES: dict[str, str] = {
    "sharpen": "a sharpening filter after rendering (an unsharp mask)",
    "colour_grade": "the colours graded after rendering (the saturation changed)",
    "code_range": "codes of another bit depth in the file (12-bit codes in a 16-bit PNG)",
    "row_stride": "pixels written at the wrong addresses (a row stride off by one)",
    "brdf_norm": "a BRDF's normalisation (a Lambertian divided by pi twice)",
    "light_pdf": "the light sampled wrongly (a wrong pdf, or part of it only): the light seen right, its light on "
                 "surfaces not",
    "light_shape": "the light's shape (a disk for a square)",
    "resolution_crop": "rendered at another resolution, then padded or cropped to the assignment's",
}


def _crc(name: str) -> int:
    return 11000 + zlib.crc32(name.encode()) % 100000


# --------------------------------------------------------------------------
# Mitsuba renders inside post-processes
# --------------------------------------------------------------------------


def _render(width: int, height: int, spp: int, seed: int, *, fov: float | None = None, max_depth: int = 8,
            dict_edit=None) -> np.ndarray:
    """A Mitsuba path render of the canonical scene at ``width`` x ``height`` (field of view ``fov`` if given,
    ``dict_edit`` applied to the scene dict): the mean, linear RGB."""
    from mcrt.mitsuba_scene import render_with_variance, scene_dict
    from mcrt.scene import load_scene

    d = scene_dict(load_scene(), "near", width, height, max_depth, spp=spp)
    if fov is not None:
        d["sensor"] = dict(d["sensor"], fov=float(fov))
    if dict_edit is not None:
        d = dict_edit(d)
    return np.asarray(render_with_variance(d, spp=spp, seed=seed).mean, np.float64)


def _fov_for(pixels: float, of: int = 64, base: float = 90.0) -> float:
    """The field of view whose image plane is ``pixels / of`` times as wide as that of ``base`` (square pixels kept)."""
    return math.degrees(2.0 * math.atan(pixels / of * math.tan(math.radians(base) / 2.0)))


def _block_mean(x: np.ndarray, ky: int, kx: int) -> np.ndarray:
    h, w = x.shape[0] // ky, x.shape[1] // kx
    return x.reshape(h, ky, w, kx, 3).mean(axis=(1, 3))


# --------------------------------------------------------------------------
# Post-processing (linear render in, what the program writes out)
# --------------------------------------------------------------------------


def _hable(x, *, exposure: float = 2.0, white: float = 11.2):
    """Hable's Uncharted 2 filmic curve after an exposure bias, normalised by its value at ``white``."""
    def f(v):
        a, b, c, d, e, g = 0.15, 0.50, 0.10, 0.20, 0.02, 0.30
        return (v * (a * v + c * b) + d * e) / (v * (a * v + b) + d * g) - e / g

    return f(exposure * np.maximum(x, 0.0)) / f(white)


def _scaled(x, f: float):
    return x * f


def _unsharp(x, *, sigma: float = 1.0, amount: float = 0.6):
    """``x + amount (x - blur(x))``, negatives clipped to 0 (the program keeps radiance non-negative)."""
    from scipy.ndimage import gaussian_filter

    return np.maximum(x + amount * (x - gaussian_filter(x, sigma=(sigma, sigma, 0), mode="nearest")), 0.0)


def _saturated(x, *, s: float = 1.3):
    """Each pixel moved away from its luminance (Rec. 709) by ``s``, negatives clipped to 0: a "vibrance" slider."""
    y = (x @ programs._LUMA)[..., None]
    return np.maximum(y + s * (x - y), 0.0)


def _planar_as_interleaved(x):
    """A planar buffer (R plane, G plane, B plane) handed to a writer that reads pixels as RGB triples."""
    h, w = x.shape[:2]
    return np.ascontiguousarray(np.transpose(x, (2, 0, 1))).reshape(h, w, 3)


def _row_stride_slip(x):
    """Pixel (x, y) stored at ``y * (W - 1) + x``: each row's last pixel overwritten by the next row's first, the
    image sheared by one pixel a row, the buffer's last ``H - 1`` pixels never written (0)."""
    h, w = x.shape[:2]
    flat = np.zeros((h * w, 3), x.dtype)
    for y in range(h):  # in order: a later row overwrites where it overlaps
        flat[y * (w - 1): y * (w - 1) + w] = x[y]
    return flat.reshape(h, w, 3)


def _aspect_4_3(x, *, spp: int, seed: int):
    """Rays' y scaled by 3/4 (an aspect ratio of 4:3 hard-coded): the image's rows span 3/4 of the height the field
    of view gives. A 256 x 192 render at the same horizontal field of view covers that window; its 4 x 3 block means
    are the 64 x 64 pixels' integrals (box filter)."""
    h, w = x.shape[:2]
    return _block_mean(_render(4 * w, 3 * h, spp, seed), 3, 4)


def _jitter_two_pixels(x, *, spp: int, seed: int):
    """Sub-pixel jitter drawn in [-1, 1) instead of [-0.5, 0.5): each pixel the mean over a 2 x 2-pixel box. A render
    one pixel wider on each side (66 x 66 at the matching field of view), 4 x 4 sub-pixels a pixel, gives each pixel's
    window as 8 x 8 sub-pixels; ``spp`` over 64 sub-pixels a sub-pixel keeps the samples a pixel at ``spp``."""
    k, n = 4, x.shape[0]
    fine = _render((n + 2) * k, (n + 2) * k, max(1, spp // 64), seed, fov=_fov_for(n + 2, n))
    c = np.cumsum(np.cumsum(np.pad(fine, ((1, 0), (1, 0), (0, 0))), axis=0), axis=1)  # summed-area table
    idx = np.arange(n) * k
    a, b = idx[:, None], idx[None, :]
    s = c[a + 2 * k, b + 2 * k] - c[a, b + 2 * k] - c[a + 2 * k, b] + c[a, b]
    return s / (2 * k) ** 2


def _light_pdf_without_area(x, *, f: float, spp: int, seed: int):
    """Light reaching surfaces weighted by ``f`` (the light's pdf taken as 1, not 1/area: f = 1/4), the light seen
    directly kept. Same-seed renders at max depth 1 (only the light seen) and 8 share their first segments, so the
    second minus the first is everything else; light seen in the mirror is scaled with it."""
    h, w = x.shape[:2]
    seen = _render(w, h, spp, seed, max_depth=1)
    full = _render(w, h, spp, seed)
    return seen + f * (full - seen)


def _light_one_triangle(x, *, spp: int, seed: int):
    """NEE on the light's first triangle only, with the whole square's pdf (1/4): that triangle lights the room at
    twice its radiance, the other not at all; the light seen directly is the square. Same-seed renders: the light
    seen (max depth 1) of the scene, plus everything else (full minus max depth 1) of the scene whose light is
    :func:`_first_triangle_light`; light seen in the mirror is the latter's."""
    h, w = x.shape[:2]
    seen = _render(w, h, spp, seed, max_depth=1)
    edit = _first_triangle_light
    return seen + _render(w, h, spp, seed, dict_edit=edit) - _render(w, h, spp, seed, max_depth=1, dict_edit=edit)


def _padded(x, *, spp: int, seed: int):
    """Rendered one pixel short (63 x 63 for 64 x 64; the field of view over those pixels), padded with zeros on the
    bottom and right (np.pad)."""
    n = x.shape[0]
    return np.pad(_render(n - 1, n - 1, spp, seed), ((0, 1), (0, 1), (0, 0)))


def _cropped(x, *, spp: int, seed: int):
    """Rendered one pixel over (65 x 65 for 64 x 64; the field of view over those pixels), its first rows and
    columns kept."""
    n = x.shape[0]
    return _render(n + 1, n + 1, spp, seed)[:n, :n]


def _pillow_enlarged(x, *, spp: int, seed: int):
    """Rendered at 32 x 32, saved as 8-bit sRGB codes, enlarged with ``Image.resize((64, 64))`` (Pillow's default
    resampling, bicubic, on the codes): display values out, as the PNG holds them."""
    from PIL import Image

    h, w = x.shape[:2]
    codes = _srgb8(_render(w // 2, h // 2, spp, seed))
    return np.asarray(Image.fromarray(codes, "RGB").resize((w, h)), np.float64) / 255.0


def _channels_apart(x, *, spp: int, seed: int):
    """R, G and B each from a render of its own (three seeds): a program that traces one channel at a time."""
    h, w = x.shape[:2]
    return np.stack([_render(w, h, spp, seed + c)[..., c] for c in range(3)], axis=-1)


def _adaptive(x, *, batch: int, batches: int, rel: float, seed: int):
    """Adaptive sampling: batches of ``batch`` spp (a seed each) added per pixel until the standard error of the
    pixel's mean (from its batch means) falls below ``rel`` of its luminance, after two batches at least; each pixel
    the mean of the batches it took. The stopping rule depends on the values: not an unbiased mean."""
    h, w = x.shape[:2]
    means = np.stack([_render(w, h, batch, seed + k) for k in range(batches)])
    lum = means @ programs._LUMA
    out = np.empty_like(means[0])  # every pixel is set: where it stopped, or the mean of all batches
    done = np.zeros(lum.shape[1:], bool)
    for n in range(2, batches + 1):
        m = means[:n].mean(axis=0)
        se = lum[:n].std(axis=0, ddof=1) / math.sqrt(n)
        stop = ~done & (se < rel * np.maximum(lum[:n].mean(axis=0), 1e-6))
        out[stop] = m[stop]
        done |= stop
    out[~done] = means.mean(axis=0)[~done]
    return out


def _tiles_interrupted(x, *, full: int, low: int, done: int, seed: int):
    """4 x 4 tiles (16 x 16 pixels at 64 x 64) in row order: the first ``done`` at ``full`` spp, the rest at
    ``low`` (the time limit hit while the render went round again)."""
    h, w = x.shape[:2]
    hi, lo = _render(w, h, full, seed), _render(w, h, low, seed + 1)
    out, th, tw = lo.copy(), h // 4, w // 4
    for t in range(done):
        r, c = divmod(t, 4)
        out[th * r:th * (r + 1), tw * c:tw * (c + 1)] = hi[th * r:th * (r + 1), tw * c:tw * (c + 1)]
    return out


def _posted(name: str, fn) -> dict:
    return {"post": name, "post_fn": fn}


# --------------------------------------------------------------------------
# Files as students' programs write them (the program's buffer in, file out)
# --------------------------------------------------------------------------


def _srgb8(x) -> np.ndarray:
    return np.floor(srgb_oetf(np.clip(np.nan_to_num(x), 0.0, 1.0)) * 255.0 + 0.5).astype(np.uint8)


def _write_exr_sidecar(image: np.ndarray, folder: Path, *, ev: int) -> Path:
    """A float EXR and ``exposure.txt`` saying to multiply by 2^ev (the viewer the program wrote it for would)."""
    fresh._write_exr(image, folder)
    (folder / "exposure.txt").write_text(f"exposure = {ev:+d} EV  # multiply by {2 ** ev} to get radiance\n")
    return folder / "render.exr"


def _write_png16_codes(image: np.ndarray, folder: Path, *, bits: int) -> Path:
    """A 16-bit PNG (pypng) holding sRGB codes of ``bits`` bits, not scaled to 16 (a camera pipeline's raw range)."""
    import png

    h, w = image.shape[:2]
    codes = np.floor(srgb_oetf(np.clip(np.nan_to_num(image), 0.0, 1.0)) * ((1 << bits) - 1) + 0.5).astype(np.uint16)
    path = folder / "render.png"
    with open(path, "wb") as fh:
        png.Writer(w, h, bitdepth=16, greyscale=False).write(fh, codes.reshape(h, w * 3).tolist())
    return path


def _bmp_bytes(codes: np.ndarray, *, rows_top_first: bool) -> bytes:
    """A 24-bit BMP by hand: BITMAPFILEHEADER, BITMAPINFOHEADER with a positive height (rows stored bottom-up), BGR
    pixels, rows padded to 4 bytes; the rows given top first when ``rows_top_first``."""
    h, w = codes.shape[:2]
    pad = (-3 * w) % 4
    rows = codes if rows_top_first else codes[::-1]
    body = b"".join(r[:, ::-1].tobytes() + b"\0" * pad for r in rows)
    info = struct.pack("<IiiHHIIiiII", 40, w, h, 1, 24, 0, len(body), 2835, 2835, 0, 0)
    return b"BM" + struct.pack("<IHHI", 14 + 40 + len(body), 0, 0, 54) + info + body


def _write_bmp_by_hand(image: np.ndarray, folder: Path) -> Path:
    path = folder / "render.bmp"
    path.write_bytes(_bmp_bytes(_srgb8(image), rows_top_first=True))
    return path


def _write_bmp_pillow(image: np.ndarray, folder: Path) -> Path:
    from PIL import Image

    path = folder / "render.bmp"
    Image.fromarray(_srgb8(image), "RGB").save(path, format="BMP")
    return path


def _write_pfm_big_endian(image: np.ndarray, folder: Path) -> Path:
    """A PFM declared big-endian (scale +1.0) and written big-endian (``>f4``), bottom row first."""
    h, w = image.shape[:2]
    path = folder / "render.pfm"
    path.write_bytes(f"PF\n{w} {h}\n1.0\n".encode() + np.ascontiguousarray(image[::-1], ">f4").tobytes())
    return path


def _write_exr_with_luma(image: np.ndarray, folder: Path) -> Path:
    """A float EXR with R, G, B and Y (their Rec. 709 luminance, for a viewer's grey preview)."""
    chans = {c: np.ascontiguousarray(image[..., i], np.float32) for i, c in enumerate("RGB")}
    chans["Y"] = np.ascontiguousarray(image @ programs._LUMA, np.float32)
    path = folder / "render.exr"
    fresh._exr_file(path, chans)
    return path


def _write_png_gama(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB PNG (pypng) with a gAMA chunk of 1/2.2, as libpng writes beside sRGB."""
    import png

    h, w = image.shape[:2]
    path = folder / "render.png"
    with open(path, "wb") as fh:
        png.Writer(w, h, bitdepth=8, greyscale=False, gamma=1 / 2.2).write(fh, _srgb8(image).reshape(h, w * 3).tolist())
    return path


def _write_hdr_bottom_up(image: np.ndarray, folder: Path) -> Path:
    """A Radiance RGBE picture with resolution string ``+Y H +X W``: rows stored bottom first (RGBE as in fresh)."""
    tmp = fresh._write_hdr(image[::-1], folder)  # the bottom row first in the data
    data = tmp.read_bytes()
    h, w = image.shape[:2]
    tmp.write_bytes(data.replace(f"-Y {h} +X {w}\n".encode(), f"+Y {h} +X {w}\n".encode(), 1))
    return tmp


def _write_ppm8(image: np.ndarray, folder: Path) -> Path:
    h, w = image.shape[:2]
    path = folder / "render.ppm"
    path.write_bytes(f"P6\n{w} {h}\n255\n".encode() + _srgb8(image).tobytes())
    return path


def _write_exr_tiled(image: np.ndarray, folder: Path) -> Path:
    """A float EXR stored in 16 x 16 tiles, PIZ-compressed (OpenEXR bindings)."""
    import OpenEXR

    tiles = OpenEXR.TileDescription()  # one level (no mipmaps)
    tiles.xSize = tiles.ySize = 16
    header = {"compression": OpenEXR.PIZ_COMPRESSION, "type": OpenEXR.tiledimage, "tiles": tiles}
    path = folder / "render.exr"
    OpenEXR.File(header, {c: np.ascontiguousarray(image[..., i], np.float32) for i, c in enumerate("RGB")}).write(
        str(path))
    return path


def _box_reduced(x, *, spp: int, seed: int):
    """A render at twice the resolution reduced by 2 x 2 means: each pixel's integral (box filter) from four times
    the samples."""
    h, w = x.shape[:2]
    return _block_mean(_render(2 * w, 2 * h, spp, seed), 2, 2)


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _diffuse_remapped(d: dict, *, power: float = 1.0, factor: float = 1.0) -> dict:
    """Every diffuse surface's reflectance ``factor * albedo ** power`` (as the program computes it)."""
    from mcrt.scene import Lambertian, load_scene

    for sf in load_scene().surfaces():
        if isinstance(sf.material, Lambertian):
            rho = [factor * a ** power for a in sf.material.albedo]
            bsdf = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": rho}}}
            d = fresh._rebuilt(d, sf.name, sf.triangles, bsdf)
    return d


def _sphere_bsdf(d: dict, bsdf: dict) -> dict:
    return dict(d, sphere=dict(d["sphere"], bsdf=bsdf))


def _floor_mirror(d: dict) -> dict:
    """The floor given the sphere's material (a perfect mirror): material indices read one place off."""
    bsdf = {"type": "conductor", "material": "none"}
    return fresh._rebuilt(d, "floor", fresh._surface("floor").triangles, bsdf)


def _light_disk(d: dict) -> dict:
    """The light built as a disk of diameter 2 (the square's side) at its centre, facing down, same radiance."""
    import mitsuba as mi

    from mcrt.scene import load_scene

    lt = load_scene().light
    to_world = mi.ScalarTransform4f().translate([float(c) for c in lt.center]) @ \
        mi.ScalarTransform4f().rotate([1.0, 0.0, 0.0], 180.0) @ mi.ScalarTransform4f().scale(0.5 * float(lt.size[0]))
    black = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0] * 3}}
    disk = {"type": "disk", "to_world": to_world, "bsdf": black,
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [float(c) for c in lt.radiance]}}}
    return dict(fresh._without_mesh(d, "light"), light=disk)


def _first_triangle_light(d: dict) -> dict:
    """The light's first triangle emitting twice the radiance, its second black (a surface, emitting nothing)."""
    from mcrt.mitsuba_scene import _light_surface, _mesh
    from mcrt.scene import Surface, load_scene

    s = load_scene()
    lt = next(sf for sf in s.surfaces() if sf.name == "light")
    tris = np.asarray(_light_surface(lt, s.light.normal).triangles)
    black = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0] * 3}}
    emitter = {"type": "area", "radiance": {"type": "rgb", "value": [2.0 * float(c) for c in s.light.radiance]}}
    return dict(d, light=_mesh(Surface("light", tris[:1], None), black, emitter),
                light_rest=_mesh(Surface("light_rest", tris[1:], None), black))


#: The sphere's distance from the eye (-1, 0, 0): the thin lens's focus.
_SPHERE_DISTANCE = math.dist((-1.0, 0.0, 0.0), (9.5, 2.0, -3.3))


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: spp of the renders inside post-processes; a case whose post-process renders the image itself renders its own
#: (unused) image at the spp it declares.
_S = 256

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_hable", "pp_exposure_sidecar", "pp_unsharp", "pp_saturation"),
    "file": ("file_planar_as_rgb", "file_png16_12bit", "file_row_stride", "file_bmp_rows_top_first"),
    "materials": ("lambert_pi_twice", "albedo_squared", "mirror_silver", "mirror_glass_fresnel", "floor_mirror"),
    "camera": ("thin_lens", "fov_diagonal", "aspect_4_3", "jitter_two_pixels"),
    "light": ("light_times_area", "light_pdf_no_area", "light_disk", "light_one_triangle"),
    "resolution": ("render_63_padded", "render_65_cropped", "pillow_enlarged_32"),
    "samples": ("channels_apart", "adaptive_stop", "tiles_interrupted"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_renderer()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file, materials."""
    return (
        # Post-processing
        Spec("pp_hable", "tone_map", **_posted("hable", _hable),
             truth="Hable's filmic (Uncharted 2) curve after an exposure of 2, white point 11.2, written as EXR"),
        Spec("pp_exposure_sidecar", "light_radiance", True, held_out=True,
             **_posted("times_0.25", partial(_scaled, f=0.25)),
             writer=partial(_write_exr_sidecar, ev=2), file="exr+exposure.txt",
             truth="the image divided by 4 to fit a display, '+2 EV' written in exposure.txt and not applied"),
        Spec("pp_unsharp", "sharpen", **_posted("unsharp", _unsharp),
             truth="an unsharp mask (sigma 1 pixel, amount 0.6) after rendering, negatives clipped to 0"),
        Spec("pp_saturation", "colour_grade", held_out=True, **_posted("saturation_1.3", _saturated),
             truth="saturation raised 1.3x about each pixel's luminance (a vibrance slider), negatives clipped"),
        # Writing the file
        Spec("file_planar_as_rgb", "channels", True, **_posted("planar_as_interleaved", _planar_as_interleaved),
             truth="a planar buffer (all R, all G, all B) written as interleaved RGB: a 3 x 3 mosaic, one channel "
             "each"),
        Spec("file_png16_12bit", "code_range", True, held_out=True, writer=partial(_write_png16_codes, bits=12),
             file="png16-srgb-12bit-codes", truth="sRGB codes of 12 bits (0-4095) written into a 16-bit PNG unscaled"),
        Spec("file_row_stride", "row_stride", True, **_posted("row_stride_w_minus_1", _row_stride_slip),
             file="png-srgb",
             truth="pixel (x, y) stored at y * (W - 1) + x: the image sheared a pixel a row, an 8-bit sRGB PNG"),
        Spec("file_bmp_rows_top_first", "orientation", True, held_out=True, writer=_write_bmp_by_hand,
             file="bmp-by-hand",
             truth="a BMP written by hand: its header declares bottom-up rows, the top row went first"),
        # Materials
        Spec("lambert_pi_twice", "brdf_norm", True, mitsuba_edit=partial(_diffuse_remapped, factor=1.0 / math.pi),
             truth="every Lambertian's 1/pi applied twice (in the BRDF and again in its sample's weight): albedo / pi"),
        Spec("albedo_squared", "albedo", True, held_out=True, mitsuba_edit=partial(_diffuse_remapped, power=2.0),
             truth="the albedo multiplied in twice (in the BRDF and the sample's weight): every diffuse colour "
             "squared"),
        Spec("mirror_silver", "albedo",
             mitsuba_edit=partial(_sphere_bsdf, bsdf={"type": "conductor", "material": "Ag"}),
             truth="the mirror sphere a silver conductor (Fresnel of Ag) instead of a perfect mirror"),
        Spec("mirror_glass_fresnel", "material", True, held_out=True,
             mitsuba_edit=partial(_sphere_bsdf, bsdf={"type": "plastic", "int_ior": 1.5, "diffuse_reflectance": {
                 "type": "rgb", "value": [0.0, 0.0, 0.0]}}),
             truth="the mirror weighted by a glass's Fresnel reflectance (ior 1.5: 4 % head-on), nothing else "
             "reflected"),
        Spec("floor_mirror", "material", True, mitsuba_edit=_floor_mirror,
             truth="the floor given the sphere's material (a perfect mirror): material indices one off"),
    )


def _in_the_renderer() -> tuple[Spec, ...]:
    """Camera and light models, resolution, samples per pixel."""
    c = _crc
    return (
        # Camera model
        Spec("thin_lens", "camera_model", sensor={"type": "thinlens", "aperture_radius": 0.1,
                                                  "focus_distance": _SPHERE_DISTANCE},
             truth="a thin lens of aperture radius 0.1 focused on the sphere's centre (11.2): the rest slightly "
             "defocused"),
        Spec("fov_diagonal", "camera_fov", True, held_out=True, sensor={"fov_axis": "diagonal"},
             truth="the 90 degrees taken as the diagonal field of view: 70.5 degrees horizontally"),
        Spec("aspect_4_3", "camera_fov", True,
             **_posted("aspect_4_3", partial(_aspect_4_3, spp=_S, seed=c("aspect_4_3"))),
             truth="an aspect ratio of 4:3 hard-coded: rays' y scaled by 3/4, the image stretched vertically"),
        Spec("jitter_two_pixels", "blur", held_out=True,
             **_posted("jitter_2px", partial(_jitter_two_pixels, spp=_S, seed=c("jitter_two_pixels"))),
             truth="sub-pixel jitter in [-1, 1) instead of [-0.5, 0.5): each pixel a 2 x 2-pixel box"),
        # Light model
        Spec("light_times_area", "light_radiance", True, edit=cases.light(radiance=(80.0, 80.0, 80.0)),
             truth="the light's radiance multiplied by its area (4): 80 instead of 20"),
        Spec("light_pdf_no_area", "light_pdf", True, held_out=True,
             **_posted("light_pdf_1", partial(_light_pdf_without_area, f=0.25, spp=_S, seed=c("light_pdf_no_area"))),
             truth="the light's pdf taken as 1, not 1/area: light on surfaces 1/4 of the truth, the light seen right"),
        Spec("light_disk", "light_shape", True, mitsuba_edit=_light_disk,
             truth="the light a disk of diameter 2 inscribed in the 2 x 2 square, same radiance (pi/4 of the power)"),
        Spec("light_one_triangle", "light_pdf", True, held_out=True,
             **_posted("light_first_triangle", partial(_light_one_triangle, spp=_S, seed=c("light_one_triangle"))),
             truth="light sampled on the square's first triangle only, with the square's pdf: half the light at "
             "twice its radiance lights the room, the light seen right"),
        # Resolution
        Spec("render_63_padded", "resolution_crop", True,
             **_posted("63_padded", partial(_padded, spp=_S, seed=c("render_63_padded"))),
             truth="rendered at 63 x 63 (a loop bound off by one), padded with a black last row and column"),
        Spec("render_65_cropped", "resolution_crop", held_out=True,
             **_posted("65_cropped", partial(_cropped, spp=_S, seed=c("render_65_cropped"))),
             truth="rendered at 65 x 65 (<= in the loop bound), its first 64 rows and columns kept"),
        Spec("pillow_enlarged_32", "resampling", writer=partial(fresh._write_png8, encode=False), file="png-srgb",
             **_posted("pillow_bicubic_32", partial(_pillow_enlarged, spp=64, seed=c("pillow_enlarged_32"))), spp=64,
             truth="rendered at 32 x 32 (64 spp), 8-bit sRGB codes enlarged with Image.resize((64, 64)) (bicubic)"),
        # Samples per pixel
        Spec("channels_apart", "spp_claim", spp=192,
             **_posted("channels_apart", partial(_channels_apart, spp=64, seed=c("channels_apart"))),
             truth="R, G and B traced apart, 64 spp each (three seeds), 192 spp declared"),
        Spec("adaptive_stop", "spp_claim", held_out=True, spp=256,
             **_posted("adaptive", partial(_adaptive, batch=16, batches=16, rel=0.03, seed=c("adaptive_stop"))),
             truth="adaptive sampling: batches of 16 spp until the standard error < 3 % of the luminance (98 spp on "
             "average), 256 declared"),
        Spec("tiles_interrupted", "spp_claim", spp=256,
             **_posted("tiles", partial(_tiles_interrupted, full=256, low=32, done=9, seed=c("tiles_interrupted"))),
             truth="the render stopped at its time limit: 9 of 16 tiles at 256 spp, 7 at 32, 256 declared"),
    )


def _correct() -> tuple[Spec, ...]:
    return (
        Spec("ok_bmp_pillow", None, spp=300, writer=_write_bmp_pillow, file="bmp",
             truth="Mitsuba path 300 spp, an 8-bit sRGB BMP written with Pillow"),
        Spec("ok_pfm_big_endian", None, held_out=True, spp=128, writer=_write_pfm_big_endian, file="pfm-big-endian",
             truth="Mitsuba path 128 spp, a PFM declared big-endian (scale 1.0) and written big-endian"),
        Spec("ok_exr_with_luma", None, spp=160, writer=_write_exr_with_luma, file="exr-rgby",
             truth="Mitsuba path 160 spp, a float EXR with a luminance channel Y beside R, G, B"),
        Spec("ok_png_gama", None, held_out=True, spp=400, writer=_write_png_gama, file="png-srgb-gama",
             truth="Mitsuba path 400 spp, an 8-bit sRGB PNG with a gAMA chunk (1/2.2) written by pypng"),
        Spec("ok_2x_box_reduced", None, spp=256,
             **_posted("box_reduced", partial(_box_reduced, spp=64, seed=_crc("ok_2x_box_reduced"))),
             truth="Mitsuba path at 128 x 128, 64 spp, reduced by 2 x 2 means: 256 samples a pixel, 256 declared"),
        Spec("ok_hdr_bottom_up", None, held_out=True, spp=256, writer=_write_hdr_bottom_up, file="hdr+Y",
             truth="Mitsuba path 256 spp, a Radiance HDR with resolution string +Y (bottom row first)"),
        Spec("ok_mcrt_ppm8", None, spp=128, renderer="mcrt", writer=_write_ppm8, file="ppm8-srgb",
             truth="mcrt 128 spp, an 8-bit sRGB binary PPM"),
        Spec("ok_exr_tiled", None, held_out=True, spp=192, writer=_write_exr_tiled, file="exr-tiled-piz",
             truth="Mitsuba path 192 spp, a float EXR in 16 x 16 tiles, PIZ-compressed"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "camera_model": "another camera model (a thin lens with an aperture)",
    "blur": "a blur (a filter after rendering, or pixels' samples spread over twice a pixel)",
}
_WORDS = {**cases.CAUSES, **outside.CAUSES, **programs.NEW_CAUSES, **fresh.NEW_CAUSES, **NEW_CAUSES, **_REWORDED}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = {c: _WORDS[c] for c in dict.fromkeys(s.cause for s in MISTAKES)}


def alternating(categories: dict[str, tuple[str, ...]], specs: tuple[Spec, ...]) -> dict[str, bool]:
    """Which cases are held out, by name: the 2nd, 4th, ... of each category and of the correct hand-ins (cause
    None) of ``specs``, in the order written."""
    out = {n: k % 2 == 1 for names in categories.values() for k, n in enumerate(names)}
    out.update({s.name: k % 2 == 1 for k, s in enumerate(x for x in specs if x.cause is None)})
    return out


def class_causes(mistakes: tuple[Spec, ...], earlier, new_causes: dict[str, str],
                 reworded: dict[str, str]) -> dict[str, str]:
    """The causes of a blind class's ``mistakes`` as its report words them: the words of the scene's and outside
    classes and the new causes of the ``earlier`` class modules, overridden by the class's ``new_causes`` and then
    by its ``reworded`` ones."""
    words = {**cases.CAUSES, **outside.CAUSES, **{c: w for m in earlier for c, w in m.NEW_CAUSES.items()},
             **new_causes, **reworded}
    return {c: words[c] for c in dict.fromkeys(s.cause for s in mistakes)}


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (:func:`alternating` over :data:`CATEGORIES`)."""
    return alternating(CATEGORIES, specs)
