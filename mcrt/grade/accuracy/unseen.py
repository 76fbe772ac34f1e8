r"""A sixth class of hand-ins: mistakes in students' tracers and their output, unseen by every class, written blind.

How it was written: from what goes wrong in students' programs and in the
code that saves their images, not from the grader. Its author read the other
classes' specs and cause words, :data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words; never
the grader's rules (what decides a cause) nor its reports, and graded none of
it, not one case. Each cause and ``major`` flag was set from the mistake
alone, and the equivalences of the new causes were added to ``SAME_MISTAKE``
before any grading. The mistakes differ from those of the five other classes
(:mod:`~mcrt.grade.accuracy.cases`, :mod:`~mcrt.grade.accuracy.outside`,
:mod:`~mcrt.grade.accuracy.programs`, :mod:`~mcrt.grade.accuracy.fresh`,
:mod:`~mcrt.grade.accuracy.blind`):

* **post-processing**: Reinhard's extended curve on the luminance (white
  point 20); a vignette; a bloom (a glow from the pixels above 1); a
  grey-world white balance;
* **writing the file**: a 16-bit PNG written by hand with little-endian
  samples; a PPM with a newline too many after its header (the data one byte
  late); a PFM headed ``Pf`` (grey) holding RGB data; a Radiance HDR whose
  exponents are biased by 127 (IEEE's bias) instead of 128;
* **materials**: the mirror sphere made of glass (refracting); the
  tetrahedron shaded with smoothed vertex normals; an ambient term on every
  diffuse surface; the tetrahedron's colour taken as sRGB and decoded;
* **camera model**: the assignment's other camera (the far one); the up
  vector +y (a y-up habit); sub-pixel jitter in x only;
* **light model**: the light's samples in one quadrant of it (``2u - 1``
  written ``u``); every shadow ray blocked by the light's own surface; the
  light sampled with one random number for both coordinates (on its
  diagonal);
* **resolution**: a 2x render reduced in 8-bit display codes; rows stored
  one place up (the first at the bottom); a 2x render reduced by 2 x 2 sums;
  the course's 100 x 100 render resized to 64 x 64 by nearest pixels;
* **samples per pixel**: every row rendered with the same random numbers;
  the median of 8 batch means; a 64 and a 192 spp render averaged with equal
  weights; a running mean updated as ``(mean + sample) / 2``.

The correct hand-ins come in ways no class used: Mitsuba's ``prb``
integrator, an 8-bit PNG with an alpha channel, a plain (ASCII) PPM, a 64
and a 192 spp render averaged with weights 1 : 3, mcrt as a run-length
encoded Radiance HDR, an interlaced 16-bit PNG, paths without Russian
roulette, and a run-length encoded TGA.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s
``edit``, ``sensor`` and ``mitsuba_edit``), Mitsuba renders combined where
light transport or pixel integrals are linear in what is combined (paths seen
directly or not, rows, thin bands of rows, runs), Mitsuba renders combined
as the student's estimator combines its samples (a median of batches, a
running mean halved), or correct renders post-processed and written with
NumPy, SciPy, Pillow and pypng as students' programs do. mcrt renders only a correct hand-in.

Causes and the held-out rule follow the blind class
(:mod:`~mcrt.grade.accuracy.blind`): the other classes' words where the
mistake is that cause (:data:`_REWORDED` where they name another instance),
:data:`NEW_CAUSES` for the rest; and, fixed before any case was graded, the
2nd, 4th, ... mistake of each of :data:`CATEGORIES` and correct hand-in
held out (:func:`held_out_rule`, checked against the specs by the tests).
"""

from __future__ import annotations

import math
import struct
import zlib
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import blind, cases, fresh, outside, programs
from mcrt.grade.accuracy.cases import Spec
from mcrt.image_files import srgb_eotf, srgb_oetf

#: The causes new in this class, as the report words them.
NEW_CAUSES: dict[str, str] = {
    "bloom": "a glow added around bright pixels after rendering (a bloom)",
    "white_balance": "each colour channel scaled after rendering (an automatic white balance)",
    "ambient": "an ambient term added to every diffuse surface (light from nowhere)",
    "pixel_footprint": "each pixel's samples not spread over its square (jitter in one direction only)",
    "shadow_self": "every shadow ray blocked by the light's own surface: no light on any surface, only the light "
                   "seen (directly or in the mirror)",
    "biased_estimator": "a biased estimate of each pixel's mean (the median of batch means)",
}


def _crc(name: str) -> int:
    return 21000 + zlib.crc32(name.encode()) % 100000


# --------------------------------------------------------------------------
# Mitsuba renders inside post-processes
# --------------------------------------------------------------------------


def _render(width: int, height: int, spp: int, seed: int, *, max_depth: int = 8, scene_edit=None, dict_edit=None,
            sensor: dict | None = None) -> np.ndarray:
    """A Mitsuba path render of the canonical scene at ``width`` x ``height`` (``scene_edit`` applied to the scene,
    ``sensor`` entries and ``dict_edit`` to its dict): the mean, linear RGB."""
    from mcrt.mitsuba_scene import render_with_variance, scene_dict
    from mcrt.scene import load_scene

    s = load_scene()
    d = scene_dict(scene_edit(s) if scene_edit else s, "near", width, height, max_depth, spp=spp)
    if sensor:
        d["sensor"] = dict(d["sensor"], **sensor)
    if dict_edit is not None:
        d = dict_edit(d)
    return np.asarray(render_with_variance(d, spp=spp, seed=seed).mean, np.float64)


def _window(n: int, of: int, offset_x: float, offset_y: float) -> dict:
    """Sensor entries that render the window ``n`` pixels wide of an ``of``-pixel image (90 degrees) whose centre
    lies ``offset_x``, ``offset_y`` windows right of and below the image's centre (a row, or a band of one)."""
    fov = math.degrees(2.0 * math.atan(n / of))
    return {"fov": fov, "principal_point_offset_x": float(offset_x), "principal_point_offset_y": float(offset_y)}


# --------------------------------------------------------------------------
# Post-processing (linear render in, what the program writes out)
# --------------------------------------------------------------------------


def _luma(x):
    return x @ programs._LUMA


def _reinhard_luminance(x, *, white: float = 20.0):
    """Reinhard's extended operator on the luminance, L (1 + L / white^2) / (1 + L), the colour scaled with it."""
    lum = _luma(x)
    out = lum * (1.0 + lum / white ** 2) / (1.0 + lum)
    return x * np.where(lum > 0, out / np.where(lum > 0, lum, 1.0), 0.0)[..., None]


def _vignette(x, *, strength: float = 0.3):
    """A vignette for the look: each pixel times ``1 - strength r^2``, r the distance from the centre (1 at the
    corners)."""
    h, w = x.shape[:2]
    yy, xx = np.meshgrid((np.arange(h) + 0.5) / h - 0.5, (np.arange(w) + 0.5) / w - 0.5, indexing="ij")
    return x * (1.0 - strength * (xx ** 2 + yy ** 2) / 0.5)[..., None]


def _bloom(x, *, threshold: float = 1.0, sigma: float = 4.0, strength: float = 0.05):
    """A bloom: what exceeds ``threshold``, blurred (sigma in pixels) and added back times ``strength``."""
    from scipy.ndimage import gaussian_filter

    glow = gaussian_filter(np.maximum(x - threshold, 0.0), sigma=(sigma, sigma, 0), mode="constant")
    return x + strength * glow


def _grey_world(x):
    """A grey-world white balance: each channel scaled so that the three channels' means are equal (their mean)."""
    m = x.reshape(-1, 3).mean(axis=0)
    return x * (m.mean() / m)


# --------------------------------------------------------------------------
# Renderer mistakes realised with Mitsuba (the render's shape in, the image out)
# --------------------------------------------------------------------------


def _jitter_x_only(x, *, spp: int, seed: int, k: int = 9):
    """Jitter in x only (v = 0.5): each pixel the mean over the line through its centre. Each row is a band 1/k of
    a pixel high about that line: a film of ``k W`` x 1 square sub-pixels, ``spp`` each, a sub-pixel of ``k`` a
    pixel in x (so ``k spp`` samples a pixel)."""
    h, w = x.shape[:2]
    rows = [_render(k * w, 1, spp, seed + j, sensor=_window(k * w, k * w, 0.0, k * (j + 0.5 - h / 2)))
            for j in range(h)]
    return np.concatenate(rows).reshape(h, w, k, 3).mean(axis=2)


def _light_elsewhere(x, *, spp: int, seed: int, scene_edit=None, dict_edit=None):
    """The light seen directly where it is; everything else from the scene edited (its light shrunk or reshaped
    inside the square). Same-seed renders at max depth 1 (only the light seen) and 8 share their first segments: full
    minus depth 1 is all but the light seen; light seen in the mirror is the edited light's. Where the square is seen
    and the edited light is not, the ceiling's faint light behind it is added (under 1 % of the light's radiance)."""
    h, w = x.shape[:2]
    e = {"scene_edit": scene_edit, "dict_edit": dict_edit}
    seen = _render(w, h, spp, seed, max_depth=1)
    return seen + _render(w, h, spp, seed, **e) - _render(w, h, spp, seed, max_depth=1, **e)


def _diagonal_light(d: dict, *, width: float = 0.02) -> dict:
    """The light replaced by a strip ``width`` wide along its diagonal from corner (4, -1) to (6, 1), facing down,
    emitting the square's power: where samples (u, u) put it."""
    import mitsuba as mi

    from mcrt.scene import load_scene

    lt = load_scene().light
    half = 0.5 * math.sqrt(2.0) * float(lt.size[0])
    to_world = mi.ScalarTransform4f().translate([float(c) for c in lt.center]) @ \
        mi.ScalarTransform4f().rotate([0.0, 0.0, 1.0], 45.0) @ mi.ScalarTransform4f().rotate([1.0, 0.0, 0.0], 180.0) @ \
        mi.ScalarTransform4f().scale([half, 0.5 * width, 1.0])
    gain = float(lt.size[0] * lt.size[1]) / (2.0 * half * width)
    black = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0] * 3}}
    strip = {"type": "rectangle", "to_world": to_world, "bsdf": black,
             "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [gain * float(c) for c in lt.radiance]}}}
    return dict(fresh._without_mesh(d, "light"), light=strip)


def _reduced_in_display_codes(x, *, spp: int, seed: int):
    """Rendered at twice the resolution, saved as 8-bit sRGB codes, reduced with Pillow's ``Image.reduce(2)`` (2 x 2
    means of the codes): display values out, as the PNG holds them."""
    from PIL import Image

    h, w = x.shape[:2]
    codes = blind._srgb8(_render(2 * w, 2 * h, spp, seed))
    return np.asarray(Image.fromarray(codes, "RGB").reduce(2), np.float64) / 255.0


def _rows_up_one(x):
    """Row j written to row j - 1 (``img[j - 1] = row``): every row one place up, the first row at the bottom."""
    return np.roll(x, -1, axis=0)


def _summed_2x(x, *, spp: int, seed: int):
    """Rendered at twice the resolution, reduced by 2 x 2 sums (``.sum`` for ``.mean``)."""
    h, w = x.shape[:2]
    return 4.0 * blind._block_mean(_render(2 * w, 2 * h, spp, seed), 2, 2)


def _nearest_from_100(x, *, spp: int, seed: int):
    """The course's 100 x 100 render, each channel resized to the assignment's size with Pillow's NEAREST (float)."""
    from PIL import Image

    h, w = x.shape[:2]
    big = _render(100, 100, spp, seed).astype(np.float32)
    return np.stack([np.asarray(Image.fromarray(big[..., c], "F").resize((w, h), Image.NEAREST)) for c in range(3)],
                    axis=-1).astype(np.float64)


def _rows_one_seed(x, *, spp: int, seed: int):
    """Each row rendered by its own task, every task's generator in the same state (workers forked with one seed):
    a film one row high (the same random streams) whose window is the row's. Rows next to each other see nearly the
    same scene with the same random numbers: the noise runs in vertical streaks."""
    h, w = x.shape[:2]
    return np.concatenate([_render(w, 1, spp, seed, sensor=_window(w, w, 0.0, j + 0.5 - h / 2)) for j in range(h)])


def _median_of_batches(x, *, batches: int, spp: int, seed: int):
    """Each pixel the median of ``batches`` renders of ``spp`` (a seed each): robust to fireflies, biased."""
    h, w = x.shape[:2]
    return np.median(np.stack([_render(w, h, spp, seed + k) for k in range(batches)]), axis=0)


def _two_runs(x, *, spp: tuple[int, int], weights: tuple[float, float], seed: int):
    """Two runs of ``spp[0]`` and ``spp[1]`` (two seeds) averaged with ``weights``."""
    h, w = x.shape[:2]
    return sum(wt * _render(w, h, n, seed + k) for k, (n, wt) in enumerate(zip(spp, weights)))


def _halving_mean(x, *, n: int, seed: int):
    """A running mean updated as ``(mean + sample) / 2`` over ``n`` one-spp renders (a seed each): the last sample
    weighs 1/2, the one before 1/4, ..."""
    h, w = x.shape[:2]
    mean = _render(w, h, 1, seed)
    for k in range(1, n):
        mean = 0.5 * (mean + _render(w, h, 1, seed + k))
    return mean


#: The light's samples at ``centre + u * half-size``: the quadrant (5..6, 0..1) at 4 times the radiance (the square's
#: pdf, a quarter of its area).
_QUADRANT = cases.light(move=(0.5, 0.5, 0.0), size=(1.0, 1.0), radiance=(80.0, 80.0, 80.0))


def _posted(name: str, fn) -> dict:
    return {"post": name, "post_fn": fn}


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _other_camera(s, name: str = "far"):
    """The scene's camera ``name`` rendered in place of the near one."""
    from dataclasses import replace

    return replace(s, cameras=dict(s.cameras, near=s.cameras[name]))


def _up_y(s):
    return cases._camera(s, up=(0.0, 1.0, 0.0))


def _tetra_srgb_decoded(s):
    """The tetrahedron's albedo passed through the sRGB decoding (taken for a display colour)."""
    from mcrt.scene import Lambertian

    tetra = next(o for o in s.objects if o.name == "tetrahedron")
    albedo = tuple(float(a) for a in srgb_eotf(np.asarray(tetra.material.albedo, np.float64)))
    return fresh._object_material(s, "tetrahedron", Lambertian(albedo))


def _sphere_glass(d: dict) -> dict:
    return dict(d, sphere=dict(d["sphere"], bsdf={"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0}))


def _smooth_normals(triangles: np.ndarray) -> np.ndarray:
    """Each corner's normal the normalised sum of the face normals (area-weighted) of the faces meeting at its
    position: what a mesh loader computes for a smooth surface."""
    n = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    corners = triangles.reshape(-1, 3)
    keys = [tuple(np.round(p, 9)) for p in corners]
    acc: dict = {}
    for k, face in zip(keys, np.repeat(n, 3, axis=0)):
        acc[k] = acc.get(k, 0.0) + face
    out = np.array([acc[k] for k in keys])
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def _tetra_smooth(d: dict) -> dict:
    """The tetrahedron with shading normals interpolated from smoothed vertex normals (its faces look rounded)."""
    import mitsuba as mi

    sf = fresh._surface("tetrahedron")
    tris = np.asarray(sf.triangles, np.float64)
    props = mi.Properties()
    props["bsdf"] = mi.load_dict({"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {
        "type": "rgb", "value": [float(a) for a in sf.material.albedo]}}})
    mesh = mi.Mesh("tetrahedron", 3 * len(tris), len(tris), props, has_vertex_normals=True)
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(tris.reshape(-1).astype(np.float32))
    params["vertex_normals"] = mi.Float(_smooth_normals(tris).reshape(-1).astype(np.float32))
    params["faces"] = mi.UInt32(np.arange(3 * len(tris), dtype=np.uint32))
    params.update()
    return dict(d, tetrahedron=mesh)


def _ambient(d: dict, *, k: float = 0.02) -> dict:
    """Every diffuse surface emitting ``k`` times its albedo from its front (into the room; outwards for the
    tetrahedron): the ambient term of a Phong shader kept in a path tracer."""
    from mcrt.mitsuba_scene import _mesh
    from mcrt.scene import Lambertian, load_scene

    for sf in load_scene().surfaces():
        if isinstance(sf.material, Lambertian):
            rho = [float(a) for a in sf.material.albedo]
            bsdf = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": rho}}}
            d = dict(d, **{sf.name: _mesh(sf, bsdf, {"type": "area", "radiance": {
                "type": "rgb", "value": [k * a for a in rho]}})})
    return d


def _no_roulette(d: dict) -> dict:
    return dict(d, integrator=dict(d["integrator"], rr_depth=1000))


# --------------------------------------------------------------------------
# Files as students' programs write them (the program's buffer in, file out)
# --------------------------------------------------------------------------


def _png_chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def _write_png16_little_endian(image: np.ndarray, folder: Path) -> Path:
    """A 16-bit sRGB PNG written by hand (IHDR, one zlib IDAT, filter 0) with each row's samples from
    ``row.astype(np.uint16).tobytes()`` on x86: little-endian, where PNG stores big-endian."""
    h, w = image.shape[:2]
    codes = np.floor(srgb_oetf(np.clip(np.nan_to_num(image), 0.0, 1.0)) * 65535.0 + 0.5).astype("<u2")
    raw = b"".join(b"\0" + row.tobytes() for row in codes)
    ihdr = struct.pack(">IIBBBBB", w, h, 16, 2, 0, 0, 0)
    path = folder / "render.png"
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + _png_chunk(b"IHDR", ihdr) + _png_chunk(b"IDAT", zlib.compress(raw))
                     + _png_chunk(b"IEND", b""))
    return path


def _write_ppm_extra_newline(image: np.ndarray, folder: Path) -> Path:
    """A binary PPM whose header ends ``255\\n\\n``: a reader takes the second newline for the first sample."""
    h, w = image.shape[:2]
    path = folder / "render.ppm"
    path.write_bytes(f"P6\n{w} {h}\n255\n\n".encode() + blind._srgb8(image).tobytes())
    return path


def _write_pfm_grey_header(image: np.ndarray, folder: Path) -> Path:
    """A PFM headed ``Pf`` (one channel) holding three floats a pixel, bottom row first, little-endian."""
    h, w = image.shape[:2]
    path = folder / "render.pfm"
    path.write_bytes(f"Pf\n{w} {h}\n-1.0\n".encode() + np.ascontiguousarray(image[::-1], "<f4").tobytes())
    return path


def _write_hdr_bias_127(image: np.ndarray, folder: Path) -> Path:
    """A Radiance RGBE picture as :func:`mcrt.grade.accuracy.fresh._write_hdr` writes it, but with each exponent
    stored as ``e + 127`` (IEEE's bias) instead of ``e + 128``: every value read half."""
    path = fresh._write_hdr(image, folder)
    data = path.read_bytes()
    h, w = image.shape[:2]
    start = len(data) - 4 * h * w
    rgbe = np.frombuffer(data[start:], np.uint8).reshape(-1, 4).copy()
    rgbe[:, 3] = np.where(rgbe[:, 3] > 0, rgbe[:, 3] - 1, 0)  # 0 stays the code of black
    path.write_bytes(data[:start] + rgbe.tobytes())
    return path


def _write_png_rgba(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB PNG with an opaque alpha channel (Pillow, mode RGBA)."""
    from PIL import Image

    codes = blind._srgb8(image)
    rgba = np.concatenate([codes, np.full(codes.shape[:2] + (1,), 255, np.uint8)], axis=-1)
    path = folder / "render.png"
    Image.fromarray(rgba, "RGBA").save(path, format="PNG")
    return path


def _write_ppm_plain(image: np.ndarray, folder: Path) -> Path:
    """A plain (ASCII, P3) 8-bit sRGB PPM, one image row a line."""
    h, w = image.shape[:2]
    lines = [" ".join(str(int(v)) for v in row.reshape(-1)) for row in blind._srgb8(image)]
    path = folder / "render.ppm"
    path.write_text(f"P3\n{w} {h}\n255\n" + "\n".join(lines) + "\n")
    return path


def _write_hdr_rle(image: np.ndarray, folder: Path) -> Path:
    from mcrt.image_files import write_hdr

    path = folder / "render.hdr"
    write_hdr(path, np.asarray(image, np.float32), rle=True)
    return path


def _write_png16_interlaced(image: np.ndarray, folder: Path) -> Path:
    """A 16-bit sRGB PNG, Adam7-interlaced (pypng)."""
    import png

    h, w = image.shape[:2]
    codes = np.floor(srgb_oetf(np.clip(np.nan_to_num(image), 0.0, 1.0)) * 65535.0 + 0.5).astype(np.uint16)
    path = folder / "render.png"
    with open(path, "wb") as fh:
        png.Writer(w, h, bitdepth=16, greyscale=False, interlace=True).write(fh, codes.reshape(h, w * 3).tolist())
    return path


def _write_tga_rle(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB TGA, run-length encoded (Pillow)."""
    from PIL import Image

    path = folder / "render.tga"
    Image.fromarray(blind._srgb8(image), "RGB").save(path, format="TGA", compression="tga_rle")
    return path


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_reinhard_luminance", "pp_vignette", "pp_bloom", "pp_grey_world"),
    "file": ("file_png16_little_endian", "file_ppm_extra_newline", "file_pfm_grey_header", "file_hdr_bias_127"),
    "materials": ("sphere_glass", "tetra_smooth_normals", "ambient_term", "tetra_albedo_srgb_decoded"),
    "camera": ("far_camera", "up_y", "jitter_x_only"),
    "light": ("light_samples_quadrant", "shadow_rays_hit_light", "light_samples_diagonal"),
    "resolution": ("reduced_in_srgb_codes", "rows_up_one", "summed_2x", "nearest_from_100"),
    "samples": ("rows_one_seed", "median_of_batches", "equal_weights_64_192", "halving_mean"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_renderer() + _pixels_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_reinhard_luminance", "tone_map", **_posted("reinhard_luminance", _reinhard_luminance),
             truth="Reinhard's extended curve on the luminance (white point 20), the colour scaled with it, as EXR"),
        Spec("pp_vignette", "falloff", held_out=True, **_posted("vignette_0.3", _vignette),
             truth="a vignette for the look: each pixel times 1 - 0.3 r^2 (r = 1 at the corners), as EXR"),
        Spec("pp_bloom", "bloom", **_posted("bloom", _bloom),
             truth="a bloom: what exceeds 1, blurred (sigma 4 pixels) and added back times 0.05, as EXR"),
        Spec("pp_grey_world", "white_balance", held_out=True, **_posted("grey_world", _grey_world),
             truth="a grey-world white balance: each channel scaled to make the channels' means equal, as EXR"),
        # Writing the file
        Spec("file_png16_little_endian", "file_format", True, writer=_write_png16_little_endian,
             file="png16-srgb-little-endian", truth="a 16-bit sRGB PNG written by hand with little-endian samples "
             "(PNG's are big-endian): each code's two bytes swapped"),
        Spec("file_ppm_extra_newline", "file_format", True, held_out=True, writer=_write_ppm_extra_newline,
             file="ppm8-srgb-extra-newline",
             truth="a binary PPM whose header ends with two newlines: every sample read one byte late (R from the "
             "previous B)"),
        Spec("file_pfm_grey_header", "file_format", True, writer=_write_pfm_grey_header, file="pfm-Pf-header",
             truth="a PFM headed 'Pf' (greyscale) holding RGB data: the first third of the floats read as grey "
             "pixels"),
        Spec("file_hdr_bias_127", "light_radiance", True, held_out=True, writer=_write_hdr_bias_127,
             file="hdr-exponent-bias-127",
             truth="a Radiance HDR written by hand with exponents biased by 127 instead of 128: every value half"),
    )


def _in_the_renderer() -> tuple[Spec, ...]:
    """Materials, camera and light models."""
    c = _crc
    return (
        # Materials
        Spec("sphere_glass", "material", True, mitsuba_edit=_sphere_glass,
             truth="the mirror sphere made of glass (a dielectric of ior 1.5): it refracts the room"),
        Spec("tetra_smooth_normals", "normals", held_out=True, mitsuba_edit=_tetra_smooth,
             truth="the tetrahedron shaded with vertex normals smoothed across its edges (a loader's default): its "
             "flat faces shaded as if rounded"),
        Spec("ambient_term", "ambient", True, mitsuba_edit=_ambient,
             truth="an ambient term: every diffuse surface emits 0.02 times its albedo"),
        Spec("tetra_albedo_srgb_decoded", "albedo", True, held_out=True, edit=_tetra_srgb_decoded,
             truth="the tetrahedron's albedo taken for an sRGB colour and decoded: (0.60, 0.17, 0.010) instead of "
             "(0.8, 0.45, 0.1)"),
        # Camera model
        Spec("far_camera", "camera_eye", True, edit=_other_camera,
             truth="the assignment's far camera (eye (-2, 0, 0), 53.13 degrees) rendered for the near one"),
        Spec("up_y", "camera_rotation", True, held_out=True, edit=_up_y,
             truth="the camera's up vector +y (a y-up habit) instead of +z: the image turned 90 degrees"),
        Spec("jitter_x_only", "pixel_footprint", spp=126,
             **_posted("jitter_x_only", partial(_jitter_x_only, spp=14, seed=c("jitter_x_only"))),
             truth="sub-pixel jitter in x only (v = 0.5): each pixel the mean over the line through its centre, "
             "126 spp"),
        # Light model
        Spec("light_samples_quadrant", "light_pdf", True, **_posted("light_samples_quadrant", partial(
            _light_elsewhere, spp=256, seed=c("light_samples_quadrant"), scene_edit=_QUADRANT)),
             truth="the light's samples at centre + u * half-size (2u - 1 written u): all in one quadrant, with the "
             "square's pdf: a 1 x 1 quarter at 4 times the radiance lights the room, the light seen right"),
        Spec("shadow_rays_hit_light", "shadow_self", True, held_out=True,
             mitsuba_edit=partial(blind._diffuse_remapped, factor=0.0),
             truth="shadow rays run to the light's surface and blocked by it: no direct light, so no light at all on "
             "any surface; only the light seen, directly or in the mirror"),
        Spec("light_samples_diagonal", "light_pdf", True, **_posted("light_samples_diagonal", partial(
            _light_elsewhere, spp=256, seed=c("light_samples_diagonal"), dict_edit=_diagonal_light)),
             truth="the light sampled at (u, u), one random number for both coordinates: its light on surfaces "
             "from its diagonal, the light seen right"),
    )


def _pixels_and_samples() -> tuple[Spec, ...]:
    """Resolution, samples per pixel."""
    c = _crc
    return (
        # Resolution
        Spec("reduced_in_srgb_codes", "resampling", writer=partial(fresh._write_png8, encode=False), file="png-srgb",
             **_posted("reduce_codes_2x", partial(_reduced_in_display_codes, spp=64, seed=c("reduced_in_srgb_codes"))),
             truth="rendered at 128 x 128 (64 spp), 8-bit sRGB codes reduced by Image.reduce(2) (means of codes)"),
        Spec("rows_up_one", "row_stride", True, held_out=True, **_posted("rows_up_one", _rows_up_one),
             truth="row j written to row j - 1: the image one row up, its first row at the bottom (wrapped)"),
        Spec("summed_2x", "light_radiance", True,
             **_posted("summed_2x", partial(_summed_2x, spp=64, seed=c("summed_2x"))),
             truth="rendered at 128 x 128 (64 spp), reduced by 2 x 2 sums instead of means: 4 times too bright"),
        Spec("nearest_from_100", "resampling", held_out=True,
             **_posted("nearest_from_100", partial(_nearest_from_100, spp=256, seed=c("nearest_from_100"))),
             truth="rendered at the course's 100 x 100, resized to 64 x 64 with Pillow's NEAREST"),
        # Samples per pixel
        Spec("rows_one_seed", "same_seed", spp=64,
             **_posted("rows_one_seed", partial(_rows_one_seed, spp=64, seed=c("rows_one_seed"))),
             truth="each row rendered by a forked worker whose generator has the same state: the same random numbers "
             "in every row, 64 spp"),
        Spec("median_of_batches", "biased_estimator", held_out=True, spp=256, **_posted("median_of_8", partial(
            _median_of_batches, batches=8, spp=32, seed=c("median_of_batches"))),
             truth="each pixel the median of 8 batch means of 32 spp (to remove fireflies), 256 declared"),
        Spec("equal_weights_64_192", "spp_claim", spp=256, **_posted("equal_weights", partial(
            _two_runs, spp=(64, 192), weights=(0.5, 0.5), seed=c("equal_weights_64_192"))),
             truth="a 64 spp run and a 192 spp run averaged with equal weights, 256 declared"),
        Spec("halving_mean", "spp_claim", held_out=True, spp=256,
             **_posted("halving_mean", partial(_halving_mean, n=16, seed=c("halving_mean"))),
             truth="each pixel's running mean updated as (mean + sample) / 2: the last sample weighs 1/2 (16 one-spp "
             "renders; earlier ones would weigh under 2^-15), 256 declared"),
    )


def _correct() -> tuple[Spec, ...]:
    return (
        Spec("ok_prb_200", None, spp=200, integrator="prb", truth="Mitsuba prb (path replay) integrator 200 spp, EXR"),
        Spec("ok_png_rgba", None, held_out=True, spp=96, writer=_write_png_rgba, file="png-srgb-rgba",
             truth="Mitsuba path 96 spp, an 8-bit sRGB PNG with an opaque alpha channel"),
        Spec("ok_ppm_plain", None, spp=144, writer=_write_ppm_plain, file="ppm8-srgb-plain",
             truth="Mitsuba path 144 spp, a plain (ASCII, P3) 8-bit sRGB PPM"),
        Spec("ok_weighted_64_192", None, held_out=True, spp=256, **_posted("weighted_1_3", partial(
            _two_runs, spp=(64, 192), weights=(0.25, 0.75), seed=_crc("ok_weighted_64_192"))),
             truth="a 64 spp run and a 192 spp run averaged with weights 1/4 and 3/4, 256 declared"),
        Spec("ok_mcrt_hdr_rle", None, spp=96, renderer="mcrt", writer=_write_hdr_rle, file="hdr-rle",
             truth="mcrt 96 spp, a run-length encoded Radiance HDR"),
        Spec("ok_png16_interlaced", None, held_out=True, spp=320, writer=_write_png16_interlaced,
             file="png16-srgb-interlaced", truth="Mitsuba path 320 spp, a 16-bit sRGB PNG, Adam7-interlaced"),
        Spec("ok_no_roulette_384", None, spp=384, mitsuba_edit=_no_roulette,
             truth="Mitsuba path without Russian roulette (rr_depth past max_depth), 384 spp, EXR"),
        Spec("ok_tga_rle_77", None, held_out=True, spp=77, writer=_write_tga_rle, file="tga-rle",
             truth="Mitsuba path 77 spp, a run-length encoded 8-bit sRGB TGA"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "falloff": "a fall-off across the image (rays weighted by the camera, or a vignette)",
    "file_format": "the file's header and data disagree (byte order, a byte too many, a grey header for colour)",
    "resampling": "rendered at another resolution and resized wrongly",
    "row_stride": "pixels written at the wrong addresses (rows one place off)",
    "same_seed": "what should be independent rendered with the same seed (rows, renders)",
    "light_pdf": "the light sampled wrongly (part of it only, with the whole light's pdf): the light seen right, its "
                 "light on surfaces not",
    "normals": "surface normals wrong (smoothed across an object's edges)",
}
_WORDS = {**cases.CAUSES, **outside.CAUSES, **programs.NEW_CAUSES, **fresh.NEW_CAUSES, **blind.NEW_CAUSES,
          **NEW_CAUSES, **_REWORDED}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = {c: _WORDS[c] for c in dict.fromkeys(s.cause for s in MISTAKES)}


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
