r"""A seventh class of hand-ins: mistakes in students' tracers and their output, untried by every class, written blind.

How it was written: from what goes wrong in students' programs, their scene
input and the code that saves their images, not from the grader. Its author
read the other classes' specs and cause words, the catalogue
(:mod:`mcrt.mutants`), :data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to
stay clear of their mistakes; never the grader's rules (what decides a cause)
nor its reports, and graded none of it, not one case. Each cause and
``major`` flag was set from the mistake alone, and the equivalences of the new
causes were added to ``SAME_MISTAKE`` before any grading. The mistakes differ
from those of the six other classes (:mod:`~mcrt.grade.accuracy.cases`,
:mod:`~mcrt.grade.accuracy.outside`, :mod:`~mcrt.grade.accuracy.programs`,
:mod:`~mcrt.grade.accuracy.fresh`, :mod:`~mcrt.grade.accuracy.blind`,
:mod:`~mcrt.grade.accuracy.unseen`) and from the catalogue's bugs:

* **post-processing**: a 3 x 3 median filter against fireflies; the linear
  render sRGB-decoded (taken for display values); the values stretched from
  their minimum and maximum to 0 and 1; the colours converted to Display P3
  for a wide-gamut screen;
* **writing the file**: 16-bit samples under a PPM header of maxval 255; 8-bit
  codes times 256 (not 257) in a 16-bit PNG; an 8-bit PNG converted to
  Pillow's web palette (dithered); 8-bit codes cast without a clip (past 255
  they wrap round);
* **materials**: every Lambertian as albedo / (2 pi); the mirror tinted with
  the tetrahedron's colour; the light's rectangle reflecting like the
  ceiling;
* **geometry**: the sphere's radius taken for its diameter; the
  tetrahedron's apex with two digits swapped (x 5.8 for 8.5); the sphere as
  a mesh of flat facets; the sphere's centre truncated to integers;
* **camera model**: pixel coordinates mapped to [-0.5, 0.5] (the image plane
  half as wide); pixel indices from 1 in both loops; the far camera's eye
  with the near camera's field of view; the sub-pixel jitter drawn once per
  pixel;
* **light model**: the light's 20 taken for its power; 29 of 30 shadow rays
  summed, divided by 30; the light at the ceiling's height (4.99 rounded to
  5, coplanar);
* **resolution and pixel sampling**: stratified samples with the row stratum
  equal to the column stratum (the pixel's diagonal); the centre 64 x 64 of
  the course's 100 x 100 render kept; every other row rendered and copied to
  the next;
* **samples per pixel**: a preview pass (direct light only) kept in the
  mean; batches written as 8-bit PNGs and their codes averaged; the sum
  divided by n + 1.

The correct hand-ins come in ways no class used: Mitsuba's ``volpathmis``
integrator, a PFM with a trailing newline, a plain (ASCII) 16-bit PPM, a
32-bit BMP with alpha, a Radiance HDR with an ``EXPOSURE=`` line (pixels
scaled by it), mcrt as an RLE-compressed EXR, a 3x render reduced by 3 x 3
means, and a binary PPM with comments in its header.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s
``edit``, ``sensor`` and ``mitsuba_edit``), Mitsuba renders combined where
light transport or pixel integrals are linear in what is combined (paths seen
directly or not, sub-pixel cells), Mitsuba renders combined as the student's
program combines its batches (8-bit codes averaged), or correct renders
post-processed and written with NumPy, SciPy, Pillow and pypng as students'
programs do. mcrt renders only a correct hand-in.

Causes and the held-out rule follow the blind class
(:mod:`~mcrt.grade.accuracy.blind`): the other classes' words where the
mistake is that cause (:data:`_REWORDED` where they name another instance),
:data:`NEW_CAUSES` for the rest; and, fixed before any case was graded, the
2nd, 4th, ... mistake of each of :data:`CATEGORIES` and correct hand-in
held out (:func:`held_out_rule`, checked against the specs by the tests).
"""

from __future__ import annotations

import math
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import blind, cases, fresh, outside, programs, unseen
from mcrt.grade.accuracy.cases import Spec
from mcrt.image_files import srgb_eotf, srgb_oetf

#: The causes new in this class, as the report words them.
NEW_CAUSES: dict[str, str] = {
    "normalised": "the values normalised after rendering (stretched so that the darkest pixel is 0 and the "
                  "brightest 1)",
    "code_overflow": "values past the top 8-bit code wrapped round (cast without a clip): the brightest pixels "
                     "dark",
    "object_shape": "an object's shape (a vertex in the wrong place, a sphere made of flat facets)",
    "preview_kept": "a preview pass's samples (direct light only) kept in each pixel's mean",
}


def _crc(name: str) -> int:
    return 31000 + zlib.crc32(name.encode()) % 100000


_render = unseen._render


# --------------------------------------------------------------------------
# Post-processing (linear render in, what the program writes out)
# --------------------------------------------------------------------------


def _median3(x):
    """A 3 x 3 median filter on each channel (``scipy.ndimage.median_filter``), to remove fireflies."""
    from scipy.ndimage import median_filter

    return median_filter(x, size=(3, 3, 1), mode="nearest")


def _srgb_decoded(x):
    """The linear render passed through the sRGB decoding (taken for display values and "linearised")."""
    return srgb_eotf(np.maximum(x, 0.0))


def _stretched(x):
    """``(x - x.min()) / (x.max() - x.min())``: the values stretched to fill [0, 1] (an "auto levels")."""
    lo, hi = float(np.min(x)), float(np.max(x))
    return (x - lo) / (hi - lo)


def _rgb_to_xyz(primaries, white=(0.3127, 0.3290)) -> np.ndarray:
    """The RGB-to-XYZ matrix of ``primaries`` ((x, y) of R, G, B) and the ``white`` point (both D65 here)."""
    xyz = np.array([[x / y, 1.0, (1.0 - x - y) / y] for x, y in primaries]).T
    w = np.array([white[0] / white[1], 1.0, (1.0 - white[0] - white[1]) / white[1]])
    return xyz * np.linalg.solve(xyz, w)


#: Linear sRGB (Rec. 709 primaries) to linear Display P3, both D65.
SRGB_TO_P3 = np.linalg.solve(_rgb_to_xyz(((0.680, 0.320), (0.265, 0.690), (0.150, 0.060))),
                             _rgb_to_xyz(((0.640, 0.330), (0.300, 0.600), (0.150, 0.060))))


def _to_display_p3(x):
    """The colours converted from linear sRGB to linear Display P3 (for a wide-gamut screen), written as RGB."""
    return x @ SRGB_TO_P3.T


# --------------------------------------------------------------------------
# Renderer mistakes realised with Mitsuba (the render's shape in, the image out)
# --------------------------------------------------------------------------


def _cells(w: int, h: int, k: int, spp: int, seed: int) -> np.ndarray:
    """A render ``k`` times the resolution as (H, k, W, k, 3): each pixel's k x k cells, ``spp`` samples each."""
    return _render(k * w, k * h, spp, seed).reshape(h, k, w, k, 3)


def _strata_diagonal(x, *, k: int, spp: int, seed: int):
    """Stratified k x k jitter whose row stratum is the column stratum (one loop index for both): a pixel's samples
    only in its k diagonal cells, ``spp`` each (``k spp`` a pixel)."""
    h, w = x.shape[:2]
    c = _cells(w, h, k, spp, seed)
    d = np.arange(k)
    return c[:, d, :, d].mean(axis=0)  # (k, H, W, 3): the diagonal cells


def _jitter_once(x, *, k: int, spp: int, seed: int):
    """The sub-pixel jitter drawn once per pixel, outside the sample loop: all of a pixel's ``spp`` samples through
    one random point, here one random cell of its k x k cells."""
    h, w = x.shape[:2]
    c = _cells(w, h, k, spp, seed)
    rng = np.random.default_rng(seed)
    a, b = rng.integers(0, k, (h, w)), rng.integers(0, k, (h, w))
    iy, ix = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    return c[iy, a, ix, b]


def _centre_of_100(x, *, spp: int, seed: int):
    """The course's 100 x 100 render (for 64 x 64; in proportion at other sizes), its centre 64 x 64 kept."""
    n = x.shape[0]
    big = int(round(100 * n / 64))
    o = (big - n) // 2
    return _render(big, big, spp, seed)[o:o + n, o:o + n]


def _odd_rows_copied(x):
    """Only the even rows rendered (half the time), each copied to the row below it."""
    out = x.copy()
    out[1::2] = x[0::2][: out[1::2].shape[0]]
    return out


def _preview_kept(x, *, preview: int, full: int, seed: int):
    """A preview pass of ``preview`` spp at max depth 2 (direct light only) left in the buffer that ``full`` spp at
    the assignment's depth are added to, all divided by ``preview + full`` (two seeds)."""
    h, w = x.shape[:2]
    return (preview * _render(w, h, preview, seed, max_depth=2) + full * _render(w, h, full, seed + 1)) / (
        preview + full)


def _png_batches(x, *, batches: int, spp: int, seed: int):
    """``batches`` renders of ``spp`` (a seed each) saved as 8-bit sRGB PNGs, their codes averaged: display values
    out, as the PNG written from them holds them."""
    h, w = x.shape[:2]
    codes = np.mean([blind._srgb8(_render(w, h, spp, seed + k)).astype(np.float64) for k in range(batches)], axis=0)
    return codes / 255.0


_posted = unseen._posted


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _tetra_vertex(s, index: int, vertex):
    """The tetrahedron with vertex ``index`` replaced (its faces rewound by the scene)."""
    objs = tuple(replace(o, vertices=tuple(tuple(vertex) if k == index else v for k, v in enumerate(o.vertices)))
                 if o.name == "tetrahedron" else o for o in s.objects)
    return replace(s, objects=objs)


def _sphere_mesh(center, radius: float, segments: int, rings: int) -> np.ndarray:
    """A UV sphere of ``segments`` x ``rings`` flat triangles (vertices on the sphere), wound outwards."""
    c = np.asarray(center, np.float64)
    th = np.linspace(0.0, math.pi, rings + 1)
    ph = np.linspace(0.0, 2.0 * math.pi, segments + 1)
    p = c + radius * np.stack([np.sin(th)[:, None] * np.cos(ph), np.sin(th)[:, None] * np.sin(ph),
                               np.cos(th)[:, None] * np.ones_like(ph)], axis=-1)
    tris = []
    for i in range(rings):
        for j in range(segments):
            a, b, cc, d = p[i, j], p[i, j + 1], p[i + 1, j + 1], p[i + 1, j]
            if i > 0:
                tris.append([a, b, cc])
            if i < rings - 1:
                tris.append([a, cc, d])
    t = np.array(tris)
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    inward = np.einsum("ij,ij->i", n, t.mean(axis=1) - c) < 0
    return np.where(inward[:, None, None], t[:, [0, 2, 1]], t)


def _sphere_faceted(d: dict, *, segments: int = 24, rings: int = 12) -> dict:
    """The mirror sphere built as a mesh of flat facets (a UV sphere from a modelling tool), same mirror."""
    from mcrt.mitsuba_scene import _bsdf_dict
    from mcrt.scene import load_scene

    sph = load_scene().spheres()[0]
    return fresh._rebuilt(d, "sphere", _sphere_mesh(sph.center, sph.radius, segments, rings), _bsdf_dict(sph.material))


def _mirror_tinted_tetra(d: dict) -> dict:
    """The mirror's reflectance the tetrahedron's albedo (the last Lambertian's colour left in the material)."""
    albedo = [float(a) for a in fresh._surface("tetrahedron").material.albedo]
    return blind._sphere_bsdf(d, {"type": "conductor", "material": "none",
                                  "specular_reflectance": {"type": "rgb", "value": albedo}})


def _light_mesh(d: dict, *, bsdf: dict | None = None, z: float | None = None) -> dict:
    """The light's rectangle rebuilt: with ``bsdf`` instead of black, and/or at height ``z``; same emitter."""
    from mcrt.mitsuba_scene import _light_surface, _mesh
    from mcrt.scene import Surface, load_scene

    s = load_scene()
    tris = np.array(_light_surface(fresh._surface("light"), s.light.normal).triangles, np.float64)
    if z is not None:
        tris[..., 2] = z
    black = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0] * 3}}
    emitter = {"type": "area", "radiance": {"type": "rgb", "value": [float(c) for c in s.light.radiance]}}
    return dict(d, light=_mesh(Surface("light", tris, None), bsdf or black, emitter))


def _light_reflecting(d: dict) -> dict:
    """The light's rectangle given the ceiling's material (a default material, not black): it reflects."""
    from mcrt.scene import load_scene

    rho = [float(a) for a in load_scene().room.ceiling_albedo]
    return _light_mesh(d, bsdf={"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {
        "type": "rgb", "value": rho}}})


def _light_at_ceiling(d: dict) -> dict:
    """The light at the ceiling's height (4.99 rounded to 5), the ceiling whole: two coplanar surfaces."""
    from mcrt.scene import load_scene

    return _light_mesh(d, z=float(load_scene().room.ceiling_z))


def _radiance_as_power(s):
    """The light's 20 taken for its power: radiance 20 / (pi A)."""
    lt = s.light
    return cases._light(s, radiance=tuple(float(c) / (math.pi * lt.area) for c in lt.radiance))


# --------------------------------------------------------------------------
# Files as students' programs write them (the program's buffer in, file out)
# --------------------------------------------------------------------------


def _codes16(image: np.ndarray) -> np.ndarray:
    return np.floor(srgb_oetf(np.clip(np.nan_to_num(image), 0.0, 1.0)) * 65535.0 + 0.5).astype(np.uint16)


def _write_png16(codes: np.ndarray, folder: Path, **kw) -> Path:
    import png

    h, w = codes.shape[:2]
    path = folder / "render.png"
    with open(path, "wb") as fh:
        png.Writer(w, h, bitdepth=16, greyscale=False, **kw).write(fh, codes.reshape(h, w * 3).tolist())
    return path


def _write_ppm_16bit_data(image: np.ndarray, folder: Path) -> Path:
    """16-bit sRGB samples (big-endian) under a binary PPM header of maxval 255 (the header not changed when the
    program moved to 16 bits): a reader takes each sample's two bytes for two samples, and reads the first half."""
    h, w = image.shape[:2]
    path = folder / "render.ppm"
    path.write_bytes(f"P6\n{w} {h}\n255\n".encode() + _codes16(image).astype(">u2").tobytes())
    return path


def _write_png16_times_256(image: np.ndarray, folder: Path) -> Path:
    """A 16-bit PNG (pypng) of 8-bit sRGB codes times 256 (``codes8 << 8``, not times 257): white is 65280."""
    return _write_png16(blind._srgb8(image).astype(np.uint16) * 256, folder)


def _write_png_web_palette(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB image converted with Pillow's ``convert("P")`` (the web palette, Floyd-Steinberg) and saved."""
    from PIL import Image

    path = folder / "render.png"
    Image.fromarray(blind._srgb8(image), "RGB").convert("P").save(path, format="PNG")
    return path


def _wrapped_codes(image: np.ndarray) -> np.ndarray:
    """``np.round(srgb * 255).astype(np.uint8)`` with no clip: codes past 255 wrap modulo 256 (x86's cast)."""
    v = srgb_oetf(np.maximum(np.nan_to_num(image), 0.0))
    return (np.round(v * 255.0).astype(np.int64) % 256).astype(np.uint8)


def _write_png_wrapped(image: np.ndarray, folder: Path) -> Path:
    from PIL import Image

    path = folder / "render.png"
    Image.fromarray(_wrapped_codes(image), "RGB").save(path, format="PNG")
    return path


def _write_pfm_newline(image: np.ndarray, folder: Path) -> Path:
    """A little-endian PFM, bottom row first, with a newline after the data (``print`` after the write)."""
    path = fresh._write_pfm(image, folder)
    path.write_bytes(path.read_bytes() + b"\n")
    return path


def _write_ppm16_plain(image: np.ndarray, folder: Path) -> Path:
    """A plain (ASCII, P3) PPM of maxval 65535, sRGB-encoded, one image row a line."""
    h, w = image.shape[:2]
    lines = [" ".join(str(int(v)) for v in row.reshape(-1)) for row in _codes16(image)]
    path = folder / "render.ppm"
    path.write_text(f"P3\n{w} {h}\n65535\n" + "\n".join(lines) + "\n")
    return path


def _write_bmp_rgba(image: np.ndarray, folder: Path) -> Path:
    """A 32-bit BMP with an opaque alpha channel (Pillow, mode RGBA), sRGB-encoded."""
    from PIL import Image

    codes = blind._srgb8(image)
    rgba = np.concatenate([codes, np.full(codes.shape[:2] + (1,), 255, np.uint8)], axis=-1)
    path = folder / "render.bmp"
    Image.fromarray(rgba, "RGBA").save(path, format="BMP")
    return path


def _write_hdr_exposure(image: np.ndarray, folder: Path, *, exposure: float = 2.0) -> Path:
    """A Radiance HDR of the pixels times ``exposure``, recorded in the header as ``EXPOSURE=`` (as the format says:
    a reader divides it out)."""
    path = fresh._write_hdr(exposure * np.asarray(image, np.float64), folder)
    data = path.read_bytes()
    head = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n"
    path.write_bytes(head + f"EXPOSURE={exposure:g}\n".encode() + data[len(head):])
    return path


def _write_exr_rle(image: np.ndarray, folder: Path) -> Path:
    """A float EXR with R, G, B, RLE-compressed (OpenEXR bindings)."""
    import OpenEXR

    path = folder / "render.exr"
    OpenEXR.File({"compression": OpenEXR.RLE_COMPRESSION, "type": OpenEXR.scanlineimage},
                 {c: np.ascontiguousarray(image[..., i], np.float32) for i, c in enumerate("RGB")}).write(str(path))
    return path


def _write_ppm_comments(image: np.ndarray, folder: Path) -> Path:
    """A binary 8-bit sRGB PPM with comment lines in its header."""
    h, w = image.shape[:2]
    path = folder / "render.ppm"
    head = f"P6\n# rendered by tracer.py\n{w} {h}\n# sRGB, 8 bits\n255\n"
    path.write_bytes(head.encode() + blind._srgb8(image).tobytes())
    return path


def _box_reduced_3x(x, *, spp: int, seed: int):
    """A render at three times the resolution reduced by 3 x 3 means: each pixel's integral from 9 cells."""
    h, w = x.shape[:2]
    return blind._block_mean(_render(3 * w, 3 * h, spp, seed), 3, 3)


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_median3", "pp_srgb_decoded", "pp_stretch_min_max", "pp_display_p3"),
    "file": ("file_ppm_16bit_under_8bit_header", "file_png16_codes_times_256", "file_png_web_palette",
             "file_png_codes_wrapped"),
    "materials": ("lambert_two_pi", "mirror_tetra_colour", "light_reflects"),
    "geometry": ("sphere_radius_as_diameter", "tetra_apex_digits_swapped", "sphere_faceted",
                 "sphere_centre_truncated"),
    "camera": ("plane_half_width", "pixel_indices_from_1", "far_eye_near_fov", "jitter_once_per_pixel"),
    "light": ("light_radiance_as_power", "shadow_rays_29_of_30", "light_at_ceiling"),
    "resolution": ("strata_diagonal", "centre_of_100", "odd_rows_copied"),
    "samples": ("preview_pass_kept", "batches_as_png", "mean_over_n_plus_1"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _pixels_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_median3", "blur", **_posted("median_3x3", _median3),
             truth="a 3 x 3 median filter on each channel (to remove fireflies) after rendering, as EXR"),
        Spec("pp_srgb_decoded", "encoding", held_out=True, **_posted("srgb_decoded", _srgb_decoded),
             truth="the linear render passed through the sRGB decoding (taken for display values), as EXR"),
        Spec("pp_stretch_min_max", "normalised", True, **_posted("stretch_min_max", _stretched),
             truth="(x - min) / (max - min): the values stretched to [0, 1] (the light 1), as EXR"),
        Spec("pp_display_p3", "colour_space", held_out=True, **_posted("display_p3", _to_display_p3),
             truth="the colours converted from linear sRGB to linear Display P3 (a wide-gamut screen), as EXR"),
        # Writing the file
        Spec("file_ppm_16bit_under_8bit_header", "file_format", True, writer=_write_ppm_16bit_data,
             file="ppm-maxval255-16bit-data",
             truth="16-bit sRGB samples under a PPM header of maxval 255: each sample's bytes read as two 8-bit "
             "samples, the first half of the data read"),
        Spec("file_png16_codes_times_256", "code_range", held_out=True, writer=_write_png16_times_256,
             file="png16-srgb-codes-x256",
             truth="a 16-bit PNG of 8-bit sRGB codes times 256 (not 257): every code 0.4 % low, white 65280"),
        Spec("file_png_web_palette", "quantisation", True, writer=_write_png_web_palette, file="png-web-palette",
             truth="an 8-bit sRGB image converted with Pillow's convert('P') before saving: 216 web colours, "
             "dithered"),
        Spec("file_png_codes_wrapped", "code_overflow", held_out=True, writer=_write_png_wrapped,
             file="png-srgb-wrapped",
             truth="8-bit sRGB codes cast with np.round(v * 255).astype(uint8), no clip: past 255 they wrap (the "
             "light and its reflection dark)"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("lambert_two_pi", "brdf_norm", True, mitsuba_edit=partial(blind._diffuse_remapped, factor=0.5),
             truth="every Lambertian's BRDF albedo / (2 pi) (the hemisphere's solid angle) for albedo / pi: every "
             "diffuse reflectance halved"),
        Spec("mirror_tetra_colour", "albedo", True, held_out=True, mitsuba_edit=_mirror_tinted_tetra,
             truth="the mirror's reflectance the tetrahedron's colour (0.8, 0.45, 0.1), left from the last "
             "Lambertian"),
        Spec("light_reflects", "material", mitsuba_edit=_light_reflecting,
             truth="the light's rectangle given the ceiling's diffuse material (0.8) instead of black: it reflects "
             "light besides emitting"),
        # Geometry
        Spec("sphere_radius_as_diameter", "object_size", True,
             edit=partial(outside._scaled_object, name="sphere", f=0.5),
             truth="the sphere's 1.5 taken for its diameter: radius 0.75"),
        Spec("tetra_apex_digits_swapped", "object_shape", True, held_out=True,
             edit=partial(_tetra_vertex, index=3, vertex=(5.8, -2.3, -2.0)),
             truth="the tetrahedron's apex typed (5.8, -2.3, -2.0) for (8.5, -2.3, -2.0): it leans towards the "
             "camera"),
        Spec("sphere_faceted", "object_shape", mitsuba_edit=_sphere_faceted,
             truth="the mirror sphere a mesh of 24 x 12 flat facets (a UV sphere from a modelling tool)"),
        Spec("sphere_centre_truncated", "object_moved", True, held_out=True,
             edit=cases.moved("sphere", (-0.5, 0.0, 0.3)),
             truth="the sphere's centre read with int(): (9, 2, -3) for (9.5, 2, -3.3)"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera model
        Spec("plane_half_width", "camera_fov", True, edit=cases.fov(math.degrees(2.0 * math.atan(0.5))),
             truth="pixel coordinates mapped to [-0.5, 0.5] ((i + 0.5) / W - 0.5) on the plane at distance 1: field "
             "of view 53.13 degrees"),
        Spec("pixel_indices_from_1", "pixel_offset", True, held_out=True,
             sensor={"principal_point_offset_x": 1 / 64, "principal_point_offset_y": 1 / 64},
             truth="pixel indices from 1 in both loops (a MATLAB habit) in the ray's (i + u) / W, stored from 0: "
             "the view one pixel right and down"),
        Spec("far_eye_near_fov", "camera_eye", True, edit=cases.eye(dx=-1.0),
             truth="the far camera's eye (-2, 0, 0) with the near camera's 90 degrees (the cameras' fields read "
             "into one)"),
        Spec("jitter_once_per_pixel", "pixel_footprint", held_out=True, spp=16, **_posted("jitter_once", partial(
            _jitter_once, k=8, spp=16, seed=c("jitter_once_per_pixel"))),
             truth="the sub-pixel jitter drawn once per pixel (outside the sample loop): all 16 samples through "
             "one random point (a cell 1/8 of a pixel)"),
        # Light model
        Spec("light_radiance_as_power", "light_radiance", True, edit=_radiance_as_power,
             truth="the light's 20 taken for its power: radiance 20 / (4 pi) = 1.59"),
        Spec("shadow_rays_29_of_30", "light_pdf", held_out=True, **_posted("shadow_rays_29_of_30", partial(
            blind._light_pdf_without_area, f=29.0 / 30.0, spp=256, seed=c("shadow_rays_29_of_30"))),
             truth="30 shadow rays a vertex, the loop range(1, 30) summing 29, divided by 30: light on surfaces "
             "3.3 % low, the light seen right"),
        Spec("light_at_ceiling", "light_position", True, mitsuba_edit=_light_at_ceiling,
             truth="the light at z = 5 (4.99 rounded), coplanar with the whole ceiling: the two surfaces fight "
             "where the light is"),
    )


def _pixels_and_samples() -> tuple[Spec, ...]:
    """Resolution and pixel sampling, samples per pixel."""
    c = _crc
    return (
        # Resolution and pixel sampling
        Spec("strata_diagonal", "pixel_footprint", spp=128, **_posted("strata_diagonal", partial(
            _strata_diagonal, k=8, spp=16, seed=c("strata_diagonal"))),
             truth="8 x 8 stratified jitter with one loop index for both strata: samples in the 8 diagonal cells "
             "only, 128 spp"),
        Spec("centre_of_100", "resolution_crop", True, held_out=True, **_posted("centre_of_100", partial(
            _centre_of_100, spp=256, seed=c("centre_of_100"))),
             truth="the course's 100 x 100 render, its centre 64 x 64 kept (img[18:82, 18:82]): a narrower view"),
        Spec("odd_rows_copied", "resampling", **_posted("odd_rows_copied", _odd_rows_copied),
             truth="only even rows rendered, each copied to the odd row below it (half the time)"),
        # Samples per pixel
        Spec("preview_pass_kept", "preview_kept", spp=256, **_posted("preview_kept", partial(
            _preview_kept, preview=32, full=224, seed=c("preview_pass_kept"))),
             truth="a 32 spp preview pass at max depth 2 (direct light only) kept in the buffer, 224 spp at depth 8 "
             "added, divided by 256: indirect light 1/8 low"),
        Spec("batches_as_png", "sample_curve", held_out=True, writer=partial(fresh._write_png8, encode=False),
             file="png-srgb", **_posted("png_batches", partial(_png_batches, batches=8, spp=32,
                                                               seed=c("batches_as_png"))),
             truth="8 batches of 32 spp each saved as an 8-bit sRGB PNG, the PNGs' codes averaged: 256 spp"),
        Spec("mean_over_n_plus_1", "light_radiance", **_posted("times_256_257", partial(blind._scaled, f=256 / 257)),
             truth="each pixel's sum divided by n + 1 (257 for 256 samples): 0.4 % dark"),
    )


def _correct() -> tuple[Spec, ...]:
    return (
        Spec("ok_volpathmis_128", None, spp=128, integrator="volpathmis",
             truth="Mitsuba volpathmis (volumetric path tracer with spectral MIS) 128 spp, EXR"),
        Spec("ok_pfm_trailing_newline", None, held_out=True, spp=144, writer=_write_pfm_newline, file="pfm+newline",
             truth="Mitsuba path 144 spp, a little-endian PFM with a newline after its data"),
        Spec("ok_ppm16_plain", None, spp=200, writer=_write_ppm16_plain, file="ppm16-srgb-plain",
             truth="Mitsuba path 200 spp, a plain (ASCII, P3) 16-bit sRGB PPM"),
        Spec("ok_bmp_rgba", None, held_out=True, spp=96, writer=_write_bmp_rgba, file="bmp32-rgba",
             truth="Mitsuba path 96 spp, a 32-bit sRGB BMP with an opaque alpha channel (Pillow)"),
        Spec("ok_hdr_exposure", None, spp=256, writer=_write_hdr_exposure, file="hdr-exposure",
             truth="Mitsuba path 256 spp, a Radiance HDR of the pixels times 2 with EXPOSURE=2 in its header"),
        Spec("ok_mcrt_exr_rle", None, held_out=True, spp=80, renderer="mcrt", writer=_write_exr_rle, file="exr-rle",
             truth="mcrt 80 spp, a float EXR, RLE-compressed (OpenEXR bindings)"),
        Spec("ok_3x_box_reduced", None, spp=288, **_posted("box_reduced_3x", partial(
            _box_reduced_3x, spp=32, seed=_crc("ok_3x_box_reduced"))),
             truth="Mitsuba path at 192 x 192, 32 spp, reduced by 3 x 3 means: 288 samples a pixel, 288 declared"),
        Spec("ok_ppm8_comments", None, held_out=True, spp=160, writer=_write_ppm_comments, file="ppm8-srgb-comments",
             truth="Mitsuba path 160 spp, a binary 8-bit sRGB PPM with comment lines in its header"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "blur": "a blur or denoiser after rendering (a median filter)",
    "encoding": "the values' encoding (a display curve, or its inverse, applied to linear values)",
    "colour_space": "values in another colour space (linear Display P3 written as sRGB)",
    "file_format": "the file's header and data disagree (16-bit samples under an 8-bit header)",
    "code_range": "codes of another bit depth in the file (8-bit codes times 256 in a 16-bit PNG)",
    "quantisation": "values quantised wrongly (to a palette of 216 colours, dithered)",
    "brdf_norm": "a BRDF's normalisation (a Lambertian divided by 2 pi)",
    "pixel_footprint": "each pixel's samples not spread over its square (one point, or its diagonal only)",
    "light_pdf": "the light's samples weighted wrongly (a shadow ray lost from their sum): the light seen right, its "
                 "light on surfaces not",
    "light_position": "the light's position (coplanar with the ceiling)",
    "resolution_crop": "rendered at another resolution, then cropped to the assignment's",
    "sample_curve": "the display curve applied before averaging (to each batch)",
    "resampling": "rows not rendered, filled from their neighbours",
}
_WORDS = {**cases.CAUSES, **outside.CAUSES, **programs.NEW_CAUSES, **fresh.NEW_CAUSES, **blind.NEW_CAUSES,
          **unseen.NEW_CAUSES, **NEW_CAUSES, **_REWORDED}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = {c: _WORDS[c] for c in dict.fromkeys(s.cause for s in MISTAKES)}


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
