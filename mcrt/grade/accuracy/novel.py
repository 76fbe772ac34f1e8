r"""An eighth class of hand-ins: mistakes in students' tracers, scene input and output that no class tried, written blind.

How it was written: from what goes wrong in students' own programs late at
night (post-processing, the code that saves the image, the scene typed in,
the camera, the light, the pixel loop, the sample count), not from the
grader. Its author read the other classes' specs and cause words, the
catalogue (:mod:`mcrt.mutants`), :data:`~mcrt.grade.accuracy.run.CAUSE_OF`
and :data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and
to stay clear of their mistakes; never the grader's rules (what decides a
cause) nor its reports, and graded none of it, not one case. Each cause and
``major`` flag was set from the mistake alone, and the equivalences of the
new causes were added to ``SAME_MISTAKE`` before any grading. The mistakes
differ from those of the seven other classes
(:mod:`~mcrt.grade.accuracy.cases`, :mod:`~mcrt.grade.accuracy.outside`,
:mod:`~mcrt.grade.accuracy.programs`, :mod:`~mcrt.grade.accuracy.fresh`,
:mod:`~mcrt.grade.accuracy.blind`, :mod:`~mcrt.grade.accuracy.unseen`,
:mod:`~mcrt.grade.accuracy.untried`) and from the catalogue's bugs:

* **post-processing**: an automatic exposure (the log-average luminance
  scaled to 0.18, middle grey); ``log1p`` of the values (to see the dark
  parts); a chromatic-aberration effect (red magnified 2 %, blue shrunk 2 %
  about the centre); a Bradford adaptation from D65 to D50 (a print
  profile's white);
* **writing the file**: saved as a JPEG of quality 75 on the way and
  converted to PNG; a PFM whose data are float64 (``tobytes`` of a float64
  array); 8-bit codes through an RGB565 framebuffer (shifted back, not
  rescaled); an EXR of unsigned-integer channels (the values cast to
  ``uint32``);
* **materials**: wall BC's colour channels rotated (G, B, R); every albedo
  read as a float (its red channel for all three); the mirror sphere given
  a Phong model with kd = ks = 0.5;
* **geometry**: corner D typed (12, 0) for (13, 0); the sphere's y negated;
  the sphere an ellipsoid (its z scaled by 0.8); the tetrahedron scaled by
  0.9 about the origin, not about itself;
* **camera model**: 90 degrees given in radians to a function that takes
  degrees (a field of view of 1.57 degrees); the camera looking at the
  sphere (a look-at helper given the sphere's centre); an equidistant
  fisheye;
* **light model**: a spherical light of radius 0.5 and the square's power;
  the light sampled on a parallelogram (the opposite corner taken for the
  second edge's end); the light seen directly at half its radiance (an MIS
  weight of 1/2 where no light sample competes); the light's centre taken
  for its corner;
* **pixel sampling**: sub-pixel offsets as the sum of two uniform numbers (a
  tent filter of radius 1 pixel); offsets drawn from a normal distribution
  (a Gaussian filter, sigma 0.5 pixel); a constant offset (0.2, 0.2) left
  from debugging;
* **samples per pixel**: one loop of sqrt(spp) strata (16 samples, 256
  declared); spp and max depth swapped in the call (8 spp at depth 256, 256
  declared); 4 passes of 64 spp declared as 64.

The correct hand-ins come in ways no class used: Mitsuba's ``prbvolpath``
and ``prb_basic`` (no light sampling) integrators, mcrt as a PPM of maxval
1023 (10-bit samples), a 16-bit PNG written by hand (big-endian, as PNG
stores), a render made of four tiles rendered as windows of the camera, a half-float EXR
ZIPS-compressed, an EXR written by Mitsuba's ``Bitmap``, and a 4x render
reduced by 4 x 4 means.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s
``edit``, ``sensor`` and ``mitsuba_edit``, the film's reconstruction filter
among them), Mitsuba renders combined where light transport or pixel
integrals are linear in what is combined (paths seen directly or not,
sub-pixel cells), a wide Mitsuba render resampled into the fisheye's pixels,
or correct renders post-processed and written with NumPy, SciPy and Pillow
as students' programs do. mcrt renders only a correct hand-in.

Causes (:data:`_REWORDED`, :data:`NEW_CAUSES`) and the held-out rule
(:func:`held_out_rule` over :data:`CATEGORIES`) are as in
:mod:`~mcrt.grade.accuracy.untried`, fixed before any case was graded.
"""

from __future__ import annotations

import io
import math
import struct
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import blind, cases, fresh, outside, programs, unseen, untried
from mcrt.grade.accuracy.cases import Spec
from mcrt.image_files import srgb_oetf

#: The causes new in this class, as the report words them.
NEW_CAUSES: dict[str, str] = {
    "channel_misaligned": "the colour channels out of register (each magnified a little differently after "
                          "rendering, a chromatic-aberration effect)",
    "lossy_compression": "the image saved with lossy compression on the way (JPEG): blocks, and colours smeared",
    "light_seen": "the light's own pixels (where the camera sees it) at the wrong brightness, its light on surfaces "
                  "right",
}


def _crc(name: str) -> int:
    return 41000 + zlib.crc32(name.encode()) % 100000


_render = unseen._render


# --------------------------------------------------------------------------
# Post-processing (linear render in, what the program writes out)
# --------------------------------------------------------------------------


def _auto_exposure(x, *, key: float = 0.18):
    """Reinhard's automatic exposure: the image scaled so that its log-average luminance is ``key``."""
    lum = np.maximum(x @ programs._LUMA, 0.0)
    return x * (key / math.exp(float(np.mean(np.log(1e-4 + lum)))))


def _log1p(x):
    """``np.log1p`` of the values (to see the dark parts of the room), written as they are."""
    return np.log1p(np.maximum(x, 0.0))


def _magnified(channel: np.ndarray, s: float) -> np.ndarray:
    """One channel magnified by ``s`` about the image's centre (bilinear, edges repeated)."""
    from scipy.ndimage import map_coordinates

    h, w = channel.shape
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    cy, cx = (h - 1) / 2.0, (w - 1) / 2.0
    return map_coordinates(channel, [cy + (yy - cy) / s, cx + (xx - cx) / s], order=1, mode="nearest")


def _chromatic_aberration(x, *, red: float = 1.02, blue: float = 0.98):
    """A lateral chromatic aberration for the look: red magnified by ``red``, blue by ``blue``, green kept."""
    return np.stack([_magnified(x[..., 0], red), x[..., 1], _magnified(x[..., 2], blue)], axis=-1)


#: The Bradford cone response matrix (XYZ to "sharpened" LMS).
_BRADFORD = np.array([[0.8951, 0.2664, -0.1614], [-0.7502, 1.7135, 0.0367], [0.0389, -0.0685, 1.0296]])


def _adapt_matrix(src_white, dst_white) -> np.ndarray:
    """Linear sRGB to linear sRGB with the white moved from ``src_white`` to ``dst_white`` (XYZ), Bradford's way."""
    srgb_to_xyz = untried._rgb_to_xyz(((0.640, 0.330), (0.300, 0.600), (0.150, 0.060)))
    gain = (_BRADFORD @ np.asarray(dst_white)) / (_BRADFORD @ np.asarray(src_white))
    cat = np.linalg.solve(_BRADFORD, np.diag(gain) @ _BRADFORD)
    return np.linalg.solve(srgb_to_xyz, cat @ srgb_to_xyz)


#: D65 to D50 on linear sRGB (a print profile's white point applied to the render).
D65_TO_D50 = _adapt_matrix((0.95047, 1.0, 1.08883), (0.96422, 1.0, 0.82521))


def _to_d50(x):
    return x @ D65_TO_D50.T


_posted = unseen._posted


# --------------------------------------------------------------------------
# Renderer mistakes realised with Mitsuba (the render's shape in, the image out)
# --------------------------------------------------------------------------


def _fisheye(x, *, spp: int, seed: int, k: int = 4, s: int = 4):
    """An equidistant fisheye of 90 degrees across the width: a ray at image radius r (1 at the middle of an edge)
    leaves at r * 45 degrees from the view axis. A perspective render wide enough for the corners (63.6 degrees
    off axis), ``k`` times finer, is sampled bilinearly at ``s`` x ``s`` points in each pixel, which are averaged."""
    from scipy.ndimage import map_coordinates

    h, w = x.shape[:2]
    t = math.tan(math.sqrt(2.0) * math.pi / 4.0) * 1.02  # the plane's half-width that holds the corners' rays
    m = k * w
    wide = _render(m, m, spp, seed, sensor={"fov": math.degrees(2.0 * math.atan(t))})
    sub = (np.arange(s) + 0.5) / s
    py = 2.0 * (np.arange(h)[:, None] + sub[None, :]).reshape(-1) / h - 1.0  # down
    px = 2.0 * (np.arange(w)[:, None] + sub[None, :]).reshape(-1) / w - 1.0  # right
    yy, xx = np.meshgrid(py, px, indexing="ij")
    r = np.hypot(xx, yy)
    f = np.where(r > 0, np.tan(r * math.pi / 4.0) / np.where(r > 0, r, 1.0), math.pi / 4.0)
    cy, cx = (yy * f + t) / (2.0 * t) * m - 0.5, (xx * f + t) / (2.0 * t) * m - 0.5
    out = np.stack([map_coordinates(wide[..., c], [cy, cx], order=1, mode="nearest") for c in range(3)], axis=-1)
    return out.reshape(h, s, w, s, 3).mean(axis=(1, 3))


def _jitter_constant(x, *, k: int, cell: int, spp: int, seed: int):
    """The jitter's random numbers replaced by a constant (left from debugging): every sample of a pixel through one
    point, here cell (``cell``, ``cell``) of its k x k cells."""
    h, w = x.shape[:2]
    return untried._cells(w, h, k, spp, seed)[:, cell, :, cell]


def _seen_scaled(x, *, f: float, spp: int, seed: int):
    """The light seen directly (a max-depth-1 render of the same seed: the same camera rays) scaled by ``f``,
    everything else kept."""
    h, w = x.shape[:2]
    return _render(w, h, spp, seed) + (f - 1.0) * _render(w, h, spp, seed, max_depth=1)


def _light_sampled_elsewhere(x, *, spp: int, seed: int, dict_edit):
    """The light seen directly as the scene has it, its light on surfaces from the light of ``dict_edit``: same-seed
    renders, the scene's max-depth-1 plus the edited scene's full minus its max-depth-1."""
    h, w = x.shape[:2]
    seen = _render(w, h, spp, seed, max_depth=1)
    return seen + _render(w, h, spp, seed, dict_edit=dict_edit) - _render(w, h, spp, seed, max_depth=1,
                                                                           dict_edit=dict_edit)


def _box_reduced_4x(x, *, spp: int, seed: int):
    """A render at four times the resolution reduced by 4 x 4 means."""
    h, w = x.shape[:2]
    return blind._block_mean(_render(4 * w, 4 * h, spp, seed), 4, 4)


def _window_tiles(x, *, spp: int, seed: int):
    """Four tiles (quarters) of the image rendered apart as windows of the camera (a narrower field of view, the
    principal point moved to the tile's centre), a seed each, put together."""
    h, w = x.shape[:2]
    out = np.zeros((h, w, 3))
    for k, (ty, tx) in enumerate(((0, 0), (0, 1), (1, 0), (1, 1))):
        window = unseen._window(w // 2, w, tx - 0.5, ty - 0.5)
        tile = _render(w // 2, h // 2, spp, seed + k, sensor=window)
        out[ty * (h // 2):(ty + 1) * (h // 2), tx * (w // 2):(tx + 1) * (w // 2)] = tile
    return out


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _corner(s, name: str, xy):
    """Room corner ``name`` at ``xy`` (both walls meeting there move)."""
    return replace(s, room=replace(s.room, corners={**s.room.corners, name: tuple(float(v) for v in xy)}))


def _tetra_scaled_about_origin(s, f: float):
    """The tetrahedron's vertices multiplied by ``f`` (scaled about the origin, not its centroid)."""
    objs = tuple(replace(o, vertices=tuple(tuple(float(f * c) for c in v) for v in o.vertices))
                 if o.name == "tetrahedron" else o for o in s.objects)
    return replace(s, objects=objs)


def _look_at_sphere(s):
    """The near camera's forward pointed at the sphere's centre (a look-at helper given the wrong target)."""
    c = s.cameras["near"]
    sph = next(o for o in s.objects if o.name == "sphere")
    f = np.asarray(sph.center, np.float64) - np.asarray(c.eye, np.float64)
    return cases._camera(s, forward=tuple(float(v) for v in f / np.linalg.norm(f)))


def _wall_channels_rotated(s, corners: str):
    """Wall ``corners``'s albedo (R, G, B) stored as (G, B, R)."""
    w = next(w for w in s.room.walls if "".join(w.corners) == corners)
    return cases._wall_albedo(s, corners, tuple(w.albedo[1:]) + (w.albedo[0],))


def _albedo_first_channel(d: dict) -> dict:
    """Every Lambertian's albedo read as one float, its red channel, for all three channels."""
    from mcrt.scene import Lambertian, load_scene

    for sf in load_scene().surfaces():
        if isinstance(sf.material, Lambertian):
            rho = [float(sf.material.albedo[0])] * 3
            bsdf = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": rho}}}
            d = fresh._rebuilt(d, sf.name, sf.triangles, bsdf)
    return d


def _sphere_phong(d: dict, *, kd: float = 0.5) -> dict:
    """The mirror sphere as a Phong-style mix: ``kd`` of a white Lambertian, ``1 - kd`` of the perfect mirror."""
    return blind._sphere_bsdf(d, {"type": "blendbsdf", "weight": 1.0 - kd,
                                  "bsdf_0": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [1.0] * 3}},
                                  "bsdf_1": {"type": "conductor", "material": "none"}})


def _sphere_ellipsoid(d: dict, *, z: float = 0.8, segments: int = 96, rings: int = 48) -> dict:
    """The mirror sphere as a fine mesh with its z scaled by ``z`` about its centre (a non-uniform scale in its
    transform): an ellipsoid."""
    from mcrt.mitsuba_scene import _bsdf_dict
    from mcrt.scene import load_scene

    sph = load_scene().spheres()[0]
    tris = untried._sphere_mesh(sph.center, sph.radius, segments, rings)
    tris[..., 2] = sph.center[2] + z * (tris[..., 2] - sph.center[2])
    return fresh._rebuilt(d, "sphere", tris, _bsdf_dict(sph.material))


def _light_sphere(d: dict, *, radius: float = 0.5) -> dict:
    """The square light replaced by a spherical one of ``radius`` just under the ceiling, emitting the square's
    power: pi L A = 4 pi^2 r^2 L_s, so L_s = L A / (4 pi r^2)."""
    from mcrt.scene import load_scene

    lt = load_scene().light
    area = float(lt.size[0] * lt.size[1])
    ls = [float(c) * area / (4.0 * math.pi * radius ** 2) for c in lt.radiance]
    centre = [float(lt.center[0]), float(lt.center[1]), float(lt.center[2]) - radius]
    black = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0] * 3}}
    sphere = {"type": "sphere", "center": centre, "radius": float(radius), "bsdf": black,
              "emitter": {"type": "area", "radiance": {"type": "rgb", "value": ls}}}
    return dict(fresh._without_mesh(d, "light"), light=sphere)


def _light_parallelogram(d: dict) -> dict:
    """The light's samples c0 + u (c1 - c0) + v (c2 - c0) with c2 the corner opposite c0: a parallelogram of the
    square's area (the same pdf) reaching 2 further along x on one side; same radiance, facing down."""
    from mcrt.mitsuba_scene import _light_surface, _mesh
    from mcrt.scene import Surface, load_scene

    lt = load_scene().light
    c = np.asarray(lt.corners(), np.float64)
    c0, e1, e2 = c[0], c[1] - c[0], c[2] - c[0]
    quad = np.array([c0, c0 + e1, c0 + e1 + e2, c0 + e2])
    tris = np.array([[quad[0], quad[1], quad[2]], [quad[0], quad[2], quad[3]]])
    black = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0] * 3}}
    emitter = {"type": "area", "radiance": {"type": "rgb", "value": [float(v) for v in lt.radiance]}}
    return dict(d, light=_mesh(_light_surface(Surface("light", tris, None), lt.normal), black, emitter))


def _film_filter(d: dict, rfilter: dict) -> dict:
    """The film's reconstruction filter ``rfilter`` (sub-pixel offsets drawn from its shape) instead of the box."""
    return dict(d, sensor=dict(d["sensor"], film=dict(d["sensor"]["film"], rfilter=rfilter)))


# --------------------------------------------------------------------------
# Files as students' programs write them (the program's buffer in, file out)
# --------------------------------------------------------------------------


def _write_png(codes: np.ndarray, folder: Path) -> Path:
    from PIL import Image

    path = folder / "render.png"
    Image.fromarray(codes, "RGB").save(path, format="PNG")
    return path


def _write_jpeg_then_png(image: np.ndarray, folder: Path, *, quality: int = 75) -> Path:
    """The 8-bit sRGB image saved as a JPEG (Pillow, quality 75, 4:2:0), read back and saved as the PNG handed in."""
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(blind._srgb8(image), "RGB").save(buf, format="JPEG", quality=quality)
    buf.seek(0)
    return _write_png(np.asarray(Image.open(buf).convert("RGB")), folder)


def _write_pfm_float64(image: np.ndarray, folder: Path) -> Path:
    """A PFM header (little-endian, bottom row first) over float64 data: the array was never cast to float32."""
    h, w = image.shape[:2]
    path = folder / "render.pfm"
    path.write_bytes(f"PF\n{w} {h}\n-1.0\n".encode() + np.ascontiguousarray(image[::-1], "<f8").tobytes())
    return path


def _rgb565(codes: np.ndarray) -> np.ndarray:
    """8-bit codes through an RGB565 framebuffer and back by shifting (not rescaling): 5, 6, 5 bits."""
    c = codes.astype(np.uint8)
    return np.stack([(c[..., 0] >> 3) << 3, (c[..., 1] >> 2) << 2, (c[..., 2] >> 3) << 3], axis=-1).astype(np.uint8)


def _write_png_rgb565(image: np.ndarray, folder: Path) -> Path:
    return _write_png(_rgb565(blind._srgb8(image)), folder)


def _write_exr_uint(image: np.ndarray, folder: Path) -> Path:
    """An EXR whose channels are ``image.astype(np.uint32)``: unsigned integers, every value truncated."""
    import OpenEXR

    path = folder / "render.exr"
    chans = {c: np.ascontiguousarray(np.maximum(image[..., i], 0.0).astype(np.uint32)) for i, c in enumerate("RGB")}
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}, chans).write(str(path))
    return path


def _write_ppm_maxval_1023(image: np.ndarray, folder: Path) -> Path:
    """A binary PPM of maxval 1023: 10-bit sRGB codes, two bytes a sample, big-endian (as netpbm says)."""
    h, w = image.shape[:2]
    codes = np.floor(srgb_oetf(np.clip(np.nan_to_num(image), 0.0, 1.0)) * 1023.0 + 0.5).astype(">u2")
    path = folder / "render.ppm"
    path.write_bytes(f"P6\n{w} {h}\n1023\n".encode() + codes.tobytes())
    return path


def _write_png16_by_hand(image: np.ndarray, folder: Path) -> Path:
    """A 16-bit sRGB PNG written by hand (IHDR, one zlib IDAT, filter 0), samples big-endian as PNG stores them."""
    h, w = image.shape[:2]
    codes = untried._codes16(image).astype(">u2")
    raw = b"".join(b"\0" + row.tobytes() for row in codes)
    ihdr = struct.pack(">IIBBBBB", w, h, 16, 2, 0, 0, 0)
    path = folder / "render.png"
    chunk = unseen._png_chunk
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw))
                     + chunk(b"IEND", b""))
    return path


def _write_exr_half_zips(image: np.ndarray, folder: Path) -> Path:
    """A half-float EXR with R, G, B, ZIPS-compressed (one scanline a block)."""
    import OpenEXR

    path = folder / "render.exr"
    OpenEXR.File({"compression": OpenEXR.ZIPS_COMPRESSION, "type": OpenEXR.scanlineimage},
                 {c: np.ascontiguousarray(image[..., i], np.float16) for i, c in enumerate("RGB")}).write(str(path))
    return path


def _write_mitsuba_bitmap(image: np.ndarray, folder: Path) -> Path:
    """A float EXR written by Mitsuba's own ``mi.Bitmap(...).write``."""
    import mitsuba as mi

    path = folder / "render.exr"
    mi.Bitmap(np.ascontiguousarray(image, np.float32)).write(str(path))
    return path


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_auto_exposure", "pp_log1p", "pp_chromatic_aberration", "pp_d65_to_d50"),
    "file": ("file_jpeg_q75", "file_pfm_float64", "file_rgb565", "file_exr_uint"),
    "materials": ("wall_BC_channels_rotated", "albedo_red_for_all", "sphere_phong_half"),
    "geometry": ("corner_D_mistyped", "sphere_y_negated", "sphere_ellipsoid", "tetra_scaled_about_origin"),
    "camera": ("fov_radians_as_degrees", "look_at_sphere", "fisheye"),
    "light": ("light_sphere", "light_parallelogram", "light_seen_half", "light_centre_as_corner"),
    "pixel sampling": ("jitter_sum_of_two", "jitter_gaussian", "jitter_constant"),
    "samples": ("strata_sqrt_only", "spp_depth_swapped", "declared_per_pass"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _pixels_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_auto_exposure", "light_radiance", True, **_posted("auto_exposure_0.18", _auto_exposure),
             truth="an automatic exposure: the image scaled so that its log-average luminance is 0.18 (middle grey), "
             "as EXR"),
        Spec("pp_log1p", "tone_map", held_out=True, **_posted("log1p", _log1p),
             truth="np.log1p of the values (to see the dark corners), written as EXR"),
        Spec("pp_chromatic_aberration", "channel_misaligned", **_posted("chromatic_aberration", _chromatic_aberration),
             truth="a chromatic-aberration effect: red magnified 2 %, blue shrunk 2 % about the centre, as EXR"),
        Spec("pp_d65_to_d50", "white_balance", held_out=True, **_posted("bradford_d50", _to_d50),
             truth="a Bradford adaptation from D65 to D50 (a print profile's white) on the linear render: warmer, "
             "as EXR"),
        # Writing the file
        Spec("file_jpeg_q75", "lossy_compression", writer=_write_jpeg_then_png, file="jpeg75-then-png",
             truth="saved as a JPEG of quality 75 (Pillow, 4:2:0) on the way, converted to the PNG handed in"),
        Spec("file_pfm_float64", "file_format", True, held_out=True, writer=_write_pfm_float64, file="pfm-float64",
             truth="a PFM header over float64 data (the array never cast to float32): twice the bytes the header "
             "declares"),
        Spec("file_rgb565", "quantisation", writer=_write_png_rgb565, file="png-srgb-rgb565",
             truth="8-bit sRGB codes through an RGB565 framebuffer, shifted back (not rescaled): 32 and 64 levels, "
             "white (248, 252, 248)"),
        Spec("file_exr_uint", "quantisation", True, held_out=True, writer=_write_exr_uint, file="exr-uint32",
             truth="an EXR of unsigned-integer channels (image.astype(np.uint32)): every value truncated, nearly all "
             "0, the light 20"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("wall_BC_channels_rotated", "albedo", True, edit=partial(_wall_channels_rotated, corners="BC"),
             truth="wall BC's albedo stored (G, B, R): (0.15, 0.70, 0.55) for (0.55, 0.15, 0.70), green-cyan for "
             "purple"),
        Spec("albedo_red_for_all", "albedo", True, held_out=True, mitsuba_edit=_albedo_first_channel,
             truth="every Lambertian's albedo read as one float (its red channel) for all three channels: every "
             "diffuse surface grey"),
        Spec("sphere_phong_half", "material", True, mitsuba_edit=_sphere_phong,
             truth="the mirror sphere given a Phong-style model with kd = ks = 0.5: half white Lambertian, half "
             "mirror"),
        # Geometry
        Spec("corner_D_mistyped", "object_moved", True, edit=partial(_corner, name="D", xy=(12.0, 0.0)),
             truth="corner D typed (12, 0) for (13, 0): walls CD and DE moved, the far right corner nearer"),
        Spec("sphere_y_negated", "object_moved", True, held_out=True, edit=cases.moved("sphere", (0.0, -4.0, 0.0)),
             truth="the sphere's y negated: centre (9.5, -2, -3.3) for (9.5, 2, -3.3), through the tetrahedron"),
        Spec("sphere_ellipsoid", "object_shape", True, mitsuba_edit=_sphere_ellipsoid,
             truth="the mirror sphere squashed to an ellipsoid (z scaled by 0.8 about its centre, a non-uniform "
             "scale in its transform)"),
        Spec("tetra_scaled_about_origin", "object_moved", True, held_out=True,
             edit=partial(_tetra_scaled_about_origin, f=0.9),
             truth="the tetrahedron scaled by 0.9 about the origin (vertices times 0.9), not about itself: smaller, "
             "0.85 nearer the camera and 0.45 off the floor"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera model
        Spec("fov_radians_as_degrees", "camera_fov", True, edit=cases.fov(math.pi / 2.0),
             truth="the field of view given as math.radians(90) to a function that takes degrees: 1.57 degrees, a "
             "view of the far wall's middle"),
        Spec("look_at_sphere", "camera_rotation", True, held_out=True, edit=_look_at_sphere,
             truth="the camera looking at the sphere's centre (a look-at helper given the sphere as target): turned "
             "about 11 degrees left and 17 down"),
        Spec("fisheye", "camera_model", True, **_posted("fisheye", partial(_fisheye, spp=16, seed=c("fisheye"))),
             truth="an equidistant fisheye (angle from the axis proportional to the image radius), 90 degrees "
             "across the width"),
        # Light model
        Spec("light_sphere", "light_shape", True, mitsuba_edit=_light_sphere,
             truth="a spherical light of radius 0.5 centred 0.5 under the light's centre, of the square's power "
             "(radiance 25.5)"),
        Spec("light_parallelogram", "light_pdf", True, held_out=True, **_posted("light_parallelogram", partial(
            _light_sampled_elsewhere, spp=256, seed=c("light_parallelogram"), dict_edit=_light_parallelogram)),
             truth="the light sampled at c0 + u (c1 - c0) + v (c2 - c0), c2 the opposite corner: a parallelogram "
             "reaching x = 8, the light seen right"),
        Spec("light_seen_half", "light_seen", **_posted("light_seen_half", partial(
            _seen_scaled, f=0.5, spp=256, seed=c("light_seen_half"))),
             truth="an MIS weight of 1/2 applied to emission the camera sees directly (where no light sample "
             "competes): the light's own pixels 10, the rest right"),
        Spec("light_centre_as_corner", "light_position", True, held_out=True, edit=cases.light(move=(1.0, 1.0, 0.0)),
             truth="the light's centre (5, 0) taken for its corner: the square spans x 5 to 7, y 0 to 2"),
    )


def _pixels_and_samples() -> tuple[Spec, ...]:
    """Pixel sampling, samples per pixel."""
    c = _crc
    return (
        # Pixel sampling
        Spec("jitter_sum_of_two", "blur", mitsuba_edit=partial(_film_filter, rfilter={"type": "tent"}),
             truth="sub-pixel offsets u1 + u2 - 0.5 (two uniform numbers added): each pixel a tent of radius 1 "
             "pixel over its neighbours"),
        Spec("jitter_gaussian", "blur", held_out=True,
             mitsuba_edit=partial(_film_filter, rfilter={"type": "gaussian", "stddev": 0.5}),
             truth="sub-pixel offsets 0.5 + np.random.normal(0, 0.5), unclipped: each pixel a Gaussian of sigma 0.5 "
             "pixel"),
        Spec("jitter_constant", "pixel_offset", True, spp=16, **_posted("jitter_constant", partial(
            _jitter_constant, k=8, cell=1, spp=16, seed=c("jitter_constant"))),
             truth="the jitter's random numbers a constant 0.2 (left from debugging): every sample through "
             "(i + 0.2, j + 0.2), a point 0.3 pixel up and left of the centre"),
        # Samples per pixel
        Spec("strata_sqrt_only", "spp_claim", spp=16, sampler="stratified", declared_spp=256,
             truth="n = isqrt(256) strata a pixel in one loop, not n x n: 16 samples a pixel, 256 declared"),
        Spec("spp_depth_swapped", "spp_claim", held_out=True, spp=8, max_depth=256, declared_spp=256,
             truth="render(scene, 8, 256) for render(scene, spp, depth): 8 spp at max depth 256, 256 declared"),
        Spec("declared_per_pass", "spp_claim", spp=256, declared_spp=64,
             truth="4 passes of 64 spp rendered, the manifest given the pass's 64: fewer declared than rendered"),
    )


def _correct() -> tuple[Spec, ...]:
    return (
        Spec("ok_prbvolpath_128", None, spp=128, integrator="prbvolpath",
             truth="Mitsuba prbvolpath (volumetric path replay) 128 spp, EXR"),
        Spec("ok_prb_basic_512", None, held_out=True, spp=512, integrator="prb_basic",
             truth="Mitsuba prb_basic (no light sampling: the light found by BSDF sampling only) 512 spp, EXR"),
        Spec("ok_mcrt_ppm_1023", None, spp=96, renderer="mcrt", writer=_write_ppm_maxval_1023, file="ppm10-srgb",
             truth="mcrt 96 spp, a binary PPM of maxval 1023 (10-bit sRGB samples, two bytes each)"),
        Spec("ok_png16_by_hand", None, held_out=True, spp=224, writer=_write_png16_by_hand, file="png16-srgb-by-hand",
             truth="Mitsuba path 224 spp, a 16-bit sRGB PNG written by hand (zlib, big-endian samples)"),
        Spec("ok_window_tiles", None, spp=256, **_posted("window_tiles", partial(
            _window_tiles, spp=256, seed=_crc("ok_window_tiles"))),
             truth="Mitsuba path 256 spp in four quarter tiles rendered apart as windows of the camera (narrower "
             "field of view, principal point offset), a seed each, EXR"),
        Spec("ok_exr_half_zips", None, held_out=True, spp=176, writer=_write_exr_half_zips, file="exr-half-zips",
             truth="Mitsuba path 176 spp, a half-float EXR (R, G, B), ZIPS-compressed"),
        Spec("ok_mitsuba_bitmap_exr", None, spp=240, writer=_write_mitsuba_bitmap, file="exr-mitsuba-bitmap",
             truth="Mitsuba path 240 spp, an EXR written by Mitsuba's mi.Bitmap"),
        Spec("ok_4x_box_reduced", None, held_out=True, spp=256, **_posted("box_reduced_4x", partial(
            _box_reduced_4x, spp=16, seed=_crc("ok_4x_box_reduced"))),
             truth="Mitsuba path at 4x the resolution, 16 spp, reduced by 4 x 4 means: 256 samples a pixel, 256 "
             "declared"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "light_radiance": "the light's radiance (or a constant factor: an automatic exposure)",
    "tone_map": "a curve on the values after rendering (a logarithm)",
    "white_balance": "each colour's white moved after rendering (a chromatic adaptation to D50)",
    "file_format": "the file's header and data disagree (float64 data under a PFM header)",
    "quantisation": "values quantised wrongly (5 or 6 bits a channel, or cast to integers)",
    "object_shape": "an object's shape (a sphere squashed to an ellipsoid)",
    "camera_model": "another camera model (a fisheye)",
    "light_shape": "the light's shape (a sphere for a square)",
    "light_pdf": "the light sampled wrongly (on a parallelogram, not its square): the light seen right, its light on "
                 "surfaces not",
    "light_position": "the light's position (its centre taken for a corner)",
    "blur": "a blur: each pixel's samples spread over its neighbours (a tent or Gaussian filter)",
    "pixel_offset": "the pixel centres (every sample through one fixed point of its pixel)",
    "spp_claim": "samples per pixel other than declared (fewer, or more)",
}
_WORDS = {**cases.CAUSES, **outside.CAUSES, **programs.NEW_CAUSES, **fresh.NEW_CAUSES, **blind.NEW_CAUSES,
          **unseen.NEW_CAUSES, **untried.NEW_CAUSES, **NEW_CAUSES, **_REWORDED}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = {c: _WORDS[c] for c in dict.fromkeys(s.cause for s in MISTAKES)}


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
