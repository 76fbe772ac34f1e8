r"""A ninth class of hand-ins: mistakes in students' tracers, scene input and output that no class tried, written blind.

How it was written: from what goes wrong in students' programs (the lines
after rendering, the code that saves the image, the scene typed in, the
camera, the light, the integrator's loop, the passes that add up the
samples), not from the grader. Its author read the other classes' specs and
cause words, the catalogue (:mod:`mcrt.mutants`),
:data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to
stay clear of their mistakes; never the grader's rules (what decides a
cause) nor its reports, and graded none of it, not one case. Each cause and
``major`` flag was set from the mistake alone, and the equivalences of the
new causes were added to ``SAME_MISTAKE`` before any grading. The mistakes
differ from those of the eight other classes
(:mod:`~mcrt.grade.accuracy.cases`, :mod:`~mcrt.grade.accuracy.outside`,
:mod:`~mcrt.grade.accuracy.programs`, :mod:`~mcrt.grade.accuracy.fresh`,
:mod:`~mcrt.grade.accuracy.blind`, :mod:`~mcrt.grade.accuracy.unseen`,
:mod:`~mcrt.grade.accuracy.untried`, :mod:`~mcrt.grade.accuracy.novel`) and
from the catalogue's bugs:

* **post-processing**: a black level of 0.01 subtracted (clipped at 0);
  outlier pixels (3 times their 3 x 3 median's luminance) replaced by that
  median; the hue turned 10 degrees about the grey axis; a barrel lens
  distortion for the look;
* **writing the file**: the sRGB curve's linear segment taken up to the
  decoding's threshold 0.04045; the sRGB values cast to ``uint8`` before
  they are scaled by 255; linear values quantised to 8 bits, then put
  through a 256-entry sRGB table; a PPM headed maxval 256 over 8-bit data;
* **materials**: the floor a polished plastic; the tetrahedron's blue typed
  0.01 for 0.10; the tetrahedron emitting its colour (its material read as
  an emitter); the ceiling given the floor's albedo (a copied line);
* **geometry**: the sphere test given r where it needs r squared (radius
  sqrt(1.5)); the floor typed at z = -4; the tetrahedron's vertices read
  (x, z, y);
* **camera model**: the eye put at the image plane's centre; sub-pixel
  offsets scaled by 1/W for a plane 2 wide (the top-left quarter of each
  pixel); a cylindrical panorama (the horizontal angle linear in the
  column);
* **light model**: the light's corners in Z order (two triangles, a bow
  tie); the light seen by the camera clamped to 1; the light sampled about
  its corner; its height typed 4.9 for 4.99;
* **integrator**: emission not counted after a mirror bounce (the light's
  reflection in the sphere black); the maximum depth ignored once Russian
  roulette runs; a light tracer handed in (no path through the mirror);
* **samples and passes**: the passes counted from 0 in the mean's divisor;
  the far camera's samples left in the buffer; every pass seeded alike.

The correct hand-ins come in ways no class used: Mitsuba's ``direct``
integrator for direct light plus the longer paths of a separate pass, a
``path`` and a ``volpath`` render of equal spp averaged, mcrt with MIS and 4
light samples a vertex, mcrt sampling the light by solid angle, a PXR24
float EXR, an 8-bit PNG with an sRGB ICC profile, a 16-bit binary netpbm
named ``.pnm``, and a Radiance HDR written by Mitsuba's ``Bitmap``.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s
``edit``, ``sensor``, ``integrator``, ``max_depth`` and ``mitsuba_edit``),
Mitsuba renders combined where light transport or pixel integrals are linear
in what is combined (paths seen directly or not, paths after a mirror,
sub-pixel cells, two cameras' buffers), a wide Mitsuba render resampled into
a panorama's pixels, or correct renders post-processed and written with
NumPy, SciPy and Pillow as students' programs do. mcrt renders only correct
hand-ins.

Causes (:data:`_REWORDED`, :data:`NEW_CAUSES`) and the held-out rule
(:func:`held_out_rule` over :data:`CATEGORIES`: the 2nd, 4th, ... of each
category and of the correct hand-ins) are as in
:mod:`~mcrt.grade.accuracy.untried`, fixed before any case was graded.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import blind, cases, fresh, novel, outside, programs, unseen, untried
from mcrt.grade.accuracy.cases import Spec
from mcrt.image_files import srgb_oetf

#: The causes new in this class, as the report words them.
NEW_CAUSES: dict[str, str] = {
    "object_emits": "a surface emitting light that should not (its material read as an emitter)",
    "specular_unseen": "nothing seen in the mirror (paths through a perfect mirror never reach the camera, as in a "
                       "light tracer)",
    "buffer_reused": "another render's samples left in the accumulation buffer (not cleared between renders)",
}


def _crc(name: str) -> int:
    return 51000 + zlib.crc32(name.encode()) % 100000


_render = unseen._render
_posted = unseen._posted


# --------------------------------------------------------------------------
# Post-processing (linear render in, what the program writes out)
# --------------------------------------------------------------------------


def _black_level(x, *, level: float = 0.01):
    """A black level subtracted for deeper shadows: ``max(x - level, 0)``."""
    return np.maximum(x - level, 0.0)


def _outliers_replaced(x, *, factor: float = 3.0):
    """A firefly filter: each pixel whose luminance exceeds ``factor`` times the median luminance of its 3 x 3
    neighbourhood replaced by its neighbourhood's per-channel median."""
    from scipy.ndimage import median_filter

    lum = x @ programs._LUMA
    med = median_filter(x, size=(3, 3, 1), mode="nearest")
    hot = lum > factor * median_filter(lum, size=3, mode="nearest") + 1e-6
    return np.where(hot[..., None], med, x)


def _hue_matrix(deg: float) -> np.ndarray:
    """The rotation of RGB by ``deg`` about the grey axis (greys kept, hues turned)."""
    return np.array([cases._rotate(e, (1.0, 1.0, 1.0), deg) for e in np.eye(3)]).T


def _hue_rotated(x, *, deg: float = 10.0):
    return x @ _hue_matrix(deg).T


def _remapped(x: np.ndarray, sy: np.ndarray, sx: np.ndarray) -> np.ndarray:
    """Each channel of ``x`` sampled bilinearly at pixel coordinates (``sy``, ``sx``), edges repeated."""
    from scipy.ndimage import map_coordinates

    return np.stack([map_coordinates(x[..., c], [sy, sx], order=1, mode="nearest") for c in range(3)], axis=-1)


def _barrel(x, *, k: float = 0.06):
    """A barrel lens distortion for the look: output pixel at radius r (1 at an edge's middle) from the input at
    r (1 + k r^2), about the centre."""
    h, w = x.shape[:2]
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    cy, cx = (h - 1) / 2.0, (w - 1) / 2.0
    ny, nx = (yy - cy) / (h / 2.0), (xx - cx) / (w / 2.0)
    f = 1.0 + k * (nx ** 2 + ny ** 2)
    return _remapped(x, cy + ny * f * h / 2.0, cx + nx * f * w / 2.0)


# --------------------------------------------------------------------------
# Renderer mistakes realised with Mitsuba (the render's shape in, the image out)
# --------------------------------------------------------------------------


def _cylindrical(x, *, spp: int, seed: int, k: int = 4, s: int = 4):
    """A cylindrical panorama of 90 degrees across the width: the ray of image point (px, py) (-1 to 1, right and
    down) turned px * 45 degrees about the vertical, rising -py over a unit of horizontal distance. A perspective
    render ``k`` times finer, wide enough for its corners (a plane point (tan a, py / cos a)), is sampled
    bilinearly at ``s`` x ``s`` points in each pixel, which are averaged."""
    h, w = x.shape[:2]
    t = math.sqrt(2.0) * 1.02  # the plane's half-width that holds the corners' rays
    m = k * w
    wide = _render(m, m, spp, seed, sensor={"fov": math.degrees(2.0 * math.atan(t))})
    sub = (np.arange(s) + 0.5) / s
    py = 2.0 * (np.arange(h)[:, None] + sub[None, :]).reshape(-1) / h - 1.0
    px = 2.0 * (np.arange(w)[:, None] + sub[None, :]).reshape(-1) / w - 1.0
    yy, xx = np.meshgrid(py, px, indexing="ij")
    a = xx * math.pi / 4.0
    out = _remapped(wide, (yy / np.cos(a) + t) / (2.0 * t) * m - 0.5, (np.tan(a) + t) / (2.0 * t) * m - 0.5)
    return out.reshape(h, s, w, s, 3).mean(axis=(1, 3))


def _jitter_quarter(x, *, spp: int, seed: int):
    """Sub-pixel offsets scaled by 1/W on a plane 2 wide: every sample in the top-left quarter of its pixel (a render
    at twice the resolution, each pixel's top-left cell)."""
    h, w = x.shape[:2]
    return untried._cells(w, h, 2, spp, seed)[:, 0, :, 0]


def _black_diffuse(d: dict) -> dict:
    return blind._diffuse_remapped(d, factor=0.0)


def _mirror_light_uncounted(x, *, spp: int, seed: int):
    """Emission never counted after a mirror bounce: the light's reflection in the sphere removed. Same-seed renders
    share their camera rays and mirror bounces; with every diffuse surface black, max depth 2 minus max depth 1 is
    exactly the light seen in the mirror. (Light reaching a diffuse surface by way of the mirror, which the mistake
    also loses, is kept.)"""
    h, w = x.shape[:2]
    in_mirror = (_render(w, h, spp, seed, max_depth=2, dict_edit=_black_diffuse)
                 - _render(w, h, spp, seed, max_depth=1, dict_edit=_black_diffuse))
    return _render(w, h, spp, seed) - in_mirror


def _other_camera_kept(x, *, spp: int, seed: int):
    """The far camera rendered first into the same buffer, not cleared: the near camera's image is the mean over
    both cameras' samples (``spp`` each)."""
    h, w = x.shape[:2]
    return 0.5 * (x + _render(w, h, spp, seed, scene_edit=unseen._other_camera))


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _floor_polished(d: dict) -> dict:
    """The floor a smooth plastic (its albedo under a dielectric coat of index 1.5): a polished floor."""
    sf = fresh._surface("floor")
    bsdf = {"type": "twosided", "bsdf": {"type": "plastic", "int_ior": 1.5, "diffuse_reflectance": {
        "type": "rgb", "value": [float(a) for a in sf.material.albedo]}}}
    return fresh._rebuilt(d, "floor", sf.triangles, bsdf)


def _tetra_emitting(d: dict) -> dict:
    """The tetrahedron's material read as an emitter too: its faces emit radiance equal to its albedo."""
    from mcrt.mitsuba_scene import _bsdf_dict, _mesh

    sf = fresh._surface("tetrahedron")
    emitter = {"type": "area", "radiance": {"type": "rgb", "value": [float(a) for a in sf.material.albedo]}}
    return dict(d, tetrahedron=_mesh(sf, _bsdf_dict(sf.material), emitter))


def _ceiling_albedo(s, albedo):
    return replace(s, room=replace(s.room, ceiling_albedo=tuple(albedo)))


def _floor_z(s, z: float):
    return replace(s, room=replace(s.room, floor_z=float(z)))


def _tetra_yz_swapped(s):
    """The tetrahedron's vertices read as (x, z, y) (a y-up mesh convention)."""
    objs = tuple(replace(o, vertices=tuple((float(v[0]), float(v[2]), float(v[1])) for v in o.vertices))
                 if o.name == "tetrahedron" else o for o in s.objects)
    return replace(s, objects=objs)


def _light_bow_tie(d: dict) -> dict:
    """The light's corners taken in Z order (c0 (4, -1), c1 (6, -1), c2 (4, 1), c3 (6, 1)) and split as a
    quad's (c0, c1, c2), (c0, c2, c3): two triangles that overlap over a quarter and leave a quarter out; both
    face down, same radiance."""
    from mcrt.mitsuba_scene import _light_surface, _mesh
    from mcrt.scene import Surface, load_scene

    lt = load_scene().light
    (x, y, z), (a, b) = lt.center, (0.5 * lt.size[0], 0.5 * lt.size[1])
    c0, c1, c2, c3 = ((x - a, y - b, z), (x + a, y - b, z), (x - a, y + b, z), (x + a, y + b, z))
    tris = np.array([[c0, c1, c2], [c0, c2, c3]], np.float64)
    black = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0] * 3}}
    emitter = {"type": "area", "radiance": {"type": "rgb", "value": [float(v) for v in lt.radiance]}}
    return dict(d, light=_mesh(_light_surface(Surface("light", tris, None), lt.normal), black, emitter))


# --------------------------------------------------------------------------
# Files as students' programs write them (the program's buffer in, file out)
# --------------------------------------------------------------------------


def _srgb_threshold_mixed(x) -> np.ndarray:
    """The sRGB encoding with its linear segment up to 0.04045 (the decoding's threshold) instead of 0.0031308."""
    v = np.clip(np.nan_to_num(x), 0.0, 1.0)
    return np.where(v <= 0.04045, 12.92 * v, 1.055 * np.power(v, 1.0 / 2.4) - 0.055)


def _write_png_threshold_mixed(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(np.floor(np.clip(_srgb_threshold_mixed(image), 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8),
                            folder)


def _cast_before_scale(image: np.ndarray) -> np.ndarray:
    """``srgb.astype(np.uint8) * 255``: the cast first, so every value under 1 is 0 and only 1 is 255."""
    return np.clip(srgb_oetf(np.maximum(np.nan_to_num(image), 0.0)), 0.0, 1.0).astype(np.uint8) * np.uint8(255)


def _write_png_cast_before_scale(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_cast_before_scale(image), folder)


def _linear_quantised_first(image: np.ndarray) -> np.ndarray:
    """Linear values quantised to 8 bits, then encoded through a 256-entry sRGB table: the shadows in a few steps."""
    lut = np.floor(srgb_oetf(np.arange(256) / 255.0) * 255.0 + 0.5).astype(np.uint8)
    return lut[np.floor(np.clip(np.nan_to_num(image), 0.0, 1.0) * 255.0 + 0.5).astype(np.int64)]


def _write_png_linear_quantised_first(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_linear_quantised_first(image), folder)


def _write_ppm_maxval_256(image: np.ndarray, folder: Path) -> Path:
    """A binary PPM headed maxval 256 (the number of levels) over one byte a sample: netpbm reads two bytes a sample
    past 255, so the file holds half the data its header declares."""
    h, w = image.shape[:2]
    path = folder / "render.ppm"
    path.write_bytes(f"P6\n{w} {h}\n256\n".encode() + blind._srgb8(image).tobytes())
    return path


def _write_exr_pxr24(image: np.ndarray, folder: Path) -> Path:
    """A float EXR (R, G, B), PXR24-compressed (floats rounded to 24 bits)."""
    import OpenEXR

    path = folder / "render.exr"
    OpenEXR.File({"compression": OpenEXR.PXR24_COMPRESSION, "type": OpenEXR.scanlineimage},
                 {c: np.ascontiguousarray(image[..., i], np.float32) for i, c in enumerate("RGB")}).write(str(path))
    return path


def _write_png_icc(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB PNG with an sRGB ICC profile embedded (Pillow's ImageCms)."""
    from PIL import Image, ImageCms

    path = folder / "render.png"
    icc = ImageCms.ImageCmsProfile(ImageCms.createProfile("sRGB")).tobytes()
    Image.fromarray(blind._srgb8(image), "RGB").save(path, format="PNG", icc_profile=icc)
    return path


def _write_pnm16(image: np.ndarray, folder: Path) -> Path:
    """A binary netpbm (P6) of maxval 65535, sRGB-encoded, big-endian, saved as ``.pnm``."""
    h, w = image.shape[:2]
    path = folder / "render.pnm"
    path.write_bytes(f"P6\n{w} {h}\n65535\n".encode() + untried._codes16(image).astype(">u2").tobytes())
    return path


def _write_mitsuba_hdr(image: np.ndarray, folder: Path) -> Path:
    """A Radiance HDR (RGBE) written by Mitsuba's own ``mi.Bitmap(...).write``."""
    import mitsuba as mi

    path = folder / "render.hdr"
    mi.Bitmap(np.ascontiguousarray(image, np.float32)).write(str(path))
    return path


# --------------------------------------------------------------------------
# Correct renders made in other ways
# --------------------------------------------------------------------------


def _with_integrator(integrator: dict):
    return partial(_integrator_dict, integrator=integrator)


def _integrator_dict(d: dict, integrator: dict) -> dict:
    return dict(d, integrator=dict(integrator))


def _direct_plus_indirect(x, *, spp: int, seed: int):
    """Direct light from Mitsuba's ``direct`` integrator (light and BSDF samples, MIS), plus the paths of 3 to 8
    segments from another pass (a path render minus its same-seed max-depth-2 render)."""
    h, w = x.shape[:2]
    direct = _render(w, h, spp, seed, dict_edit=_with_integrator({"type": "direct"}))
    return direct + _render(w, h, spp, seed + 1) - _render(w, h, spp, seed + 1, max_depth=2)


def _path_and_volpath(x, *, spp: int, seed: int):
    """A ``path`` and a ``volpath`` render of ``spp`` each, averaged."""
    h, w = x.shape[:2]
    vol = _with_integrator({"type": "volpath", "max_depth": 8, "rr_depth": 5})
    return 0.5 * (_render(w, h, spp, seed) + _render(w, h, spp, seed + 1, dict_edit=vol))


def _mcrt(x, *, spp: int, seed: int, light_samples: int = 1, **options):
    """mcrt at the image's size with estimator ``options`` (and ``light_samples`` a vertex)."""
    from mcrt.render import render
    from mcrt.scene import load_scene

    h, w = x.shape[:2]
    s = load_scene()
    settings = s.settings(camera="near", width=w, height=h, spp=spp, max_depth=8, light_samples=light_samples)
    return np.asarray(render(s, settings, seed=seed, progress=False, **options).mean, np.float64)


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_black_level", "pp_outliers_replaced", "pp_hue_turned", "pp_barrel_distortion"),
    "file": ("file_srgb_threshold_mixed", "file_cast_before_scale", "file_linear_quantised_first",
             "file_ppm_maxval_256"),
    "materials": ("floor_polished", "tetra_blue_typo", "tetra_emitting", "ceiling_floor_albedo"),
    "geometry": ("sphere_r_for_r_squared", "floor_typed_minus_4", "tetra_yz_swapped"),
    "camera": ("eye_at_image_plane", "jitter_quarter_pixel", "cylindrical_panorama"),
    "light": ("light_bow_tie", "light_seen_clamped", "light_sampled_about_corner", "light_height_4_9"),
    "integrator": ("mirror_light_uncounted", "depth_unbounded", "light_tracer"),
    "samples": ("passes_counted_from_0", "far_camera_in_buffer", "passes_one_seed"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_black_level", "tone_map", **_posted("black_level_0.01", _black_level),
             truth="a black level of 0.01 subtracted (for deeper shadows), clipped at 0, as EXR"),
        Spec("pp_outliers_replaced", "blur", held_out=True, **_posted("outliers_replaced", _outliers_replaced),
             truth="a firefly filter: pixels over 3 times their 3 x 3 median's luminance replaced by that median (the "
             "light's corners and its reflection too), as EXR"),
        Spec("pp_hue_turned", "colour_grade", **_posted("hue_10", _hue_rotated),
             truth="the hue turned 10 degrees about the grey axis (a colour-grading step), as EXR"),
        Spec("pp_barrel_distortion", "camera_model", held_out=True, **_posted("barrel_0.06", _barrel),
             truth="a barrel lens distortion for the look (each pixel from radius r (1 + 0.06 r^2)), as EXR"),
        # Writing the file
        Spec("file_srgb_threshold_mixed", "encoding", writer=_write_png_threshold_mixed,
             file="png-srgb-threshold-0.04045",
             truth="the sRGB encoding's linear segment 12.92 x taken up to 0.04045 (the decoding's threshold), 8-bit "
             "PNG: dark values too bright, a step at 0.04"),
        Spec("file_cast_before_scale", "quantisation", True, held_out=True, writer=_write_png_cast_before_scale,
             file="png-srgb-cast-first",
             truth="srgb.astype(np.uint8) * 255: cast before scaling, every value under 1 written 0, the light 255"),
        Spec("file_linear_quantised_first", "quantisation", writer=_write_png_linear_quantised_first,
             file="png-srgb-from-linear8",
             truth="linear values rounded to 8 bits, then through a 256-entry sRGB table: the shadows in a few bands"),
        Spec("file_ppm_maxval_256", "file_format", True, held_out=True, writer=_write_ppm_maxval_256,
             file="ppm-maxval256-8bit-data",
             truth="a PPM headed maxval 256 (the number of levels) over 8-bit samples: two bytes a sample by "
             "netpbm's rule, half the data there"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    from mcrt.scene import Lambertian

    return (
        # Materials
        Spec("floor_polished", "material", True, mitsuba_edit=_floor_polished,
             truth="the floor a smooth plastic (albedo 0.6 under a dielectric coat, index 1.5): the light and the "
             "walls reflected in it"),
        Spec("tetra_blue_typo", "albedo", held_out=True,
             edit=partial(fresh._object_material, name="tetrahedron", material=Lambertian((0.80, 0.45, 0.01))),
             truth="the tetrahedron's albedo typed (0.80, 0.45, 0.01) for (0.80, 0.45, 0.10): its blue a tenth"),
        Spec("tetra_emitting", "object_emits", True, mitsuba_edit=_tetra_emitting,
             truth="the tetrahedron's material read as an emitter too: its faces emit radiance (0.8, 0.45, 0.1)"),
        Spec("ceiling_floor_albedo", "albedo", True, held_out=True, edit=partial(_ceiling_albedo, albedo=(0.6,) * 3),
             truth="the ceiling given the floor's albedo 0.6 (its line copied) for 0.8: the room darker"),
        # Geometry
        Spec("sphere_r_for_r_squared", "object_size", True,
             edit=partial(outside._scaled_object, name="sphere", f=math.sqrt(1.5) / 1.5),
             truth="the ray-sphere test given r = 1.5 where it needs r^2: a sphere of radius sqrt(1.5) = 1.22"),
        Spec("floor_typed_minus_4", "object_moved", True, held_out=True, edit=partial(_floor_z, z=-4.0),
             truth="the floor typed at z = -4 for -5: the tetrahedron under it but for its tip, the sphere cut"),
        Spec("tetra_yz_swapped", "object_moved", True, edit=_tetra_yz_swapped,
             truth="the tetrahedron's vertices read (x, z, y) (a y-up mesh habit): hanging by the wall BC, "
             "turned"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera model
        Spec("eye_at_image_plane", "camera_eye", True, edit=cases.eye(dx=1.0),
             truth="the eye put at the image plane's centre (0, 0, 0) for (-1, 0, 0), same field of view"),
        Spec("jitter_quarter_pixel", "pixel_footprint", held_out=True, **_posted("jitter_quarter", partial(
            _jitter_quarter, spp=256, seed=c("jitter_quarter_pixel"))),
             truth="sub-pixel offsets u / W on a plane 2 wide (for 2 u / W): every sample in the top-left quarter "
             "of its pixel"),
        Spec("cylindrical_panorama", "camera_model", True, **_posted("cylindrical", partial(
            _cylindrical, spp=16, seed=c("cylindrical_panorama"))),
             truth="a cylindrical panorama (the horizontal angle linear in the column, 90 degrees across, heights "
             "perspective)"),
        # Light model
        Spec("light_bow_tie", "light_shape", True, mitsuba_edit=_light_bow_tie,
             truth="the light's corners in Z order split as a quad's: two triangles overlapping over a quarter, a "
             "quarter of the square missing"),
        Spec("light_seen_clamped", "light_seen", held_out=True, **_posted("light_seen_clamped", partial(
            novel._seen_scaled, f=1.0 / 20.0, spp=256, seed=c("light_seen_clamped"))),
             truth="emission seen from the camera clamped to 1 (so the light does not blow out): the light's pixels "
             "1, its light on surfaces right"),
        Spec("light_sampled_about_corner", "light_pdf", True, **_posted("light_about_corner", partial(
            unseen._light_elsewhere, spp=256, seed=c("light_sampled_about_corner"),
            scene_edit=cases.light(move=(-1.0, -1.0, 0.0)))),
             truth="the light sampled at corner + (u - 0.5) * size: a 2 x 2 square about (4, -1), the light seen "
             "right"),
        Spec("light_height_4_9", "light_position", True, held_out=True, edit=cases.light(move=(0.0, 0.0, -0.09)),
             truth="the light's height typed 4.9 for 4.99: 0.09 lower"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples and passes."""
    c = _crc
    return (
        # Integrator
        Spec("mirror_light_uncounted", "light_seen", **_posted("mirror_light_uncounted", partial(
            _mirror_light_uncounted, spp=256, seed=c("mirror_light_uncounted"))),
             truth="emission counted only for camera rays and light samples, never after a mirror bounce: the "
             "light's reflection in the sphere black"),
        Spec("depth_unbounded", "depth", held_out=True, max_depth=-1,
             truth="the maximum depth ignored once Russian roulette runs (a while-True loop): paths of any length"),
        Spec("light_tracer", "specular_unseen", True, integrator="ptracer",
             truth="a light tracer handed in (Mitsuba ptracer): no path reaches the camera through the mirror, the "
             "sphere black"),
        # Samples and passes
        Spec("passes_counted_from_0", "light_radiance", True, **_posted("times_4_3", partial(blind._scaled, f=4 / 3)),
             truth="4 passes of 64 spp, the sum divided by pass * 64 with the pass counted from 0 (3 * 64): 4/3 too "
             "bright"),
        Spec("far_camera_in_buffer", "buffer_reused", True, held_out=True, **_posted("far_camera_kept", partial(
            _other_camera_kept, spp=256, seed=c("far_camera_in_buffer"))),
             truth="the far camera rendered first into the same buffer, not cleared: the mean of both cameras' "
             "images"),
        Spec("passes_one_seed", "same_seed", spp=64, declared_spp=256,
             truth="4 passes of 64 spp all seeded alike: the same 64 samples 4 times, 256 declared"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_direct_plus_indirect", None, spp=256, **_posted("direct_plus_indirect", partial(
            _direct_plus_indirect, spp=256, seed=c("ok_direct_plus_indirect"))),
             truth="Mitsuba direct (light and BSDF samples) 256 spp plus the paths of 3 to 8 segments of a path "
             "pass, EXR"),
        Spec("ok_path_volpath_halves", None, held_out=True, spp=256, **_posted("path_and_volpath", partial(
            _path_and_volpath, spp=128, seed=c("ok_path_volpath_halves"))),
             truth="Mitsuba path 128 spp and volpath 128 spp averaged: 256 declared, EXR"),
        Spec("ok_mcrt_mis_k4", None, spp=64, renderer="mcrt", **_posted("mcrt_mis_k4", partial(
            _mcrt, spp=64, seed=c("ok_mcrt_mis_k4"), light_samples=4, mis=True)),
             truth="mcrt 64 spp with MIS and 4 light samples a vertex, EXR"),
        Spec("ok_mcrt_solid_angle", None, held_out=True, spp=128, renderer="mcrt", **_posted("mcrt_solid_angle", partial(
            _mcrt, spp=128, seed=c("ok_mcrt_solid_angle"), light_sampling="solid_angle")),
             truth="mcrt 128 spp sampling the light uniformly in its solid angle, EXR"),
        Spec("ok_exr_pxr24", None, spp=208, writer=_write_exr_pxr24, file="exr-pxr24",
             truth="Mitsuba path 208 spp, a float EXR, PXR24-compressed"),
        Spec("ok_png_icc_srgb", None, held_out=True, spp=288, writer=_write_png_icc, file="png-srgb-icc",
             truth="Mitsuba path 288 spp, an 8-bit sRGB PNG with an sRGB ICC profile"),
        Spec("ok_pnm16", None, spp=112, writer=_write_pnm16, file="pnm16-srgb",
             truth="Mitsuba path 112 spp, a 16-bit binary netpbm (P6, maxval 65535) named .pnm"),
        Spec("ok_mitsuba_bitmap_hdr", None, held_out=True, spp=192, writer=_write_mitsuba_hdr, file="hdr-mitsuba-bitmap",
             truth="Mitsuba path 192 spp, a Radiance HDR written by Mitsuba's mi.Bitmap"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "tone_map": "a curve on the values after rendering (a black level subtracted)",
    "blur": "a filter after rendering (outlier pixels replaced by their neighbours' median)",
    "colour_grade": "the colours graded after rendering (the hue turned)",
    "camera_model": "another camera model (a lens distortion, a cylindrical panorama)",
    "encoding": "the values' encoding (the sRGB curve's linear segment to the wrong threshold)",
    "quantisation": "values quantised wrongly (cast before scaling, or linear values quantised to 8 bits)",
    "file_format": "the file's header and data disagree (a maxval that asks for two bytes a sample over one)",
    "material": "a surface rendered with another material (a polished floor)",
    "albedo": "a surface's colour (a channel mistyped, another surface's albedo copied)",
    "object_size": "an object's size (a sphere's radius where its square belongs)",
    "object_moved": "an object moved (the floor's height mistyped, a mesh's axes swapped)",
    "camera_eye": "the camera's eye position (put at the image plane)",
    "pixel_footprint": "each pixel's samples not spread over its square (only its top-left quarter)",
    "light_shape": "the light's shape (its corners in the wrong order: two overlapping triangles)",
    "light_seen": "the light as the camera sees it (directly or in the mirror) at the wrong brightness, its light on "
                  "surfaces right",
    "light_pdf": "the light sampled wrongly (about its corner): the light seen right, its light on surfaces not",
    "light_position": "the light's position (its height mistyped)",
    "depth": "the path depth (unbounded)",
    "light_radiance": "the light's radiance (or a constant factor: the mean's divisor one pass short)",
    "same_seed": "what should be independent rendered with the same seed (every pass)",
}
_WORDS = {**cases.CAUSES, **outside.CAUSES, **programs.NEW_CAUSES, **fresh.NEW_CAUSES, **blind.NEW_CAUSES,
          **unseen.NEW_CAUSES, **untried.NEW_CAUSES, **novel.NEW_CAUSES, **NEW_CAUSES, **_REWORDED}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = {c: _WORDS[c] for c in dict.fromkeys(s.cause for s in MISTAKES)}


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
