r"""A twenty-second class of hand-ins: mistakes of students' tracers, scene input and output no class tried, blind.

How it was written: from what goes wrong in students' programs (a SciPy filter's
default footprint, a quick tone curve, Pillow's sharpness slider and a colour
profile assumed, a hand-written PNG filter's byte arithmetic, the sRGB curve's
formulas and tables, a rounded RGBE mantissa, the 1/pi typed with ``//``, a game's
half-Lambert, an energy check on the albedo, a polygon's corners sorted, a sphere
mesh's loop bound, a normals list read one place off, the image plane in pixels,
degrees over 57 and a stratum's jitter centred twice, a spotlight's cone, the
light's cosine twice and clamped, roulette tested on the radiance, the light
sample from the ray's origin, a disk sampler skipped, the throughput's albedo
multiplied once, NumPy's default axis, a root mean square, a fancy-index add and a
counter that is not reset), not from the grader. Its author read the other
classes' specs and cause words, the catalogue (:mod:`mcrt.mutants`), the scene
files and design notes, mcrt's scene, camera and image code,
:data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to stay
clear of their mistakes; never the grader's rules (what decides a cause) nor its
reports, and graded none of it, not one case. Each cause and ``major`` flag was set
from the mistake alone; every mistake is worded by a cause the other classes
already have (:data:`NEW_CAUSES` is empty), so ``SAME_MISTAKE`` needed no new
entry. The mistakes differ from those of the twenty-one other classes
(:mod:`~mcrt.grade.accuracy.cases`, :mod:`~mcrt.grade.accuracy.outside` and the
modules of :data:`_EARLIER`, from :mod:`~mcrt.grade.accuracy.programs` to
:mod:`~mcrt.grade.accuracy.unvisited`) and from the catalogue's bugs:

* **post-processing**: ``scipy.ndimage.median_filter(img, size=3)`` on the (H, W,
  3) render (the median over the channels too); ``np.tanh`` as a quick tone curve;
  Pillow's ``ImageEnhance.Sharpness(2.0)`` on the 8-bit image; the linear render
  taken for Adobe RGB (1998) and converted to sRGB;
* **writing the file**: a hand-written PNG whose Average filter adds its two
  neighbours in ``uint8`` (the sum wraps); the sRGB encoding written as the
  decoding's ``((v + 0.055) / 1.055) ** (1 / 2.4)``; the sRGB curve looked up with
  ``np.interp`` in a table of 17 entries; a Radiance HDR whose rounded mantissas
  are cast to bytes unclipped (256 wraps to 0);
* **materials**: ``INV_PI = 1 // math.pi`` (0: every Lambertian black); a game's
  half-Lambert ``(0.5 cos + 0.5)^2`` in the light sample; an energy check that
  divides an albedo by its channels' sum where that sum exceeds 1;
* **geometry**: the floor's and the ceiling's corners sorted by x before they are
  fanned (two holes); the sphere meshed with its rings' loop bound halved (its
  upper half only); the walls' normals list read one place off in the light
  sample;
* **camera**: the image plane in pixel units (the division by W / 2 left out);
  the field of view turned into radians by ``/ 57``; 4 x 4 strata whose jitter
  is centred a second time (``(s + u - 0.5) / 4``);
* **light model**: a spotlight's 60-degree cone left on the area light; the
  light's cosine in its sample twice (in the geometry term and the pdf's
  conversion); the pdf's cosine at the light clamped to 0.1;
* **integrator**: Russian roulette tested on the path's radiance, not its
  throughput; the light sample taken from the ray's origin (the eye), not the
  hit point; the bounce's disk sample drawn in the square; the albedo multiplied
  into the throughput at the first bounce only;
* **samples and passes**: each pixel's mean taken with ``np.mean`` over all axes
  (one grey value); a root mean square for the mean; samples added with a NumPy
  fancy index (one of each pixel's 64 a batch kept); the sample counter reset
  per row, not per pixel.

The correct hand-ins come in ways no class used: Mitsuba with the sensor's near
clip on the image plane, mcrt written as a TGA by hand bottom row first, Mitsuba's
``aov`` integrator around the path tracer (its colour kept), a 32-bit BMP by hand,
Mitsuba with sub-pixel offsets from a SciPy Poisson-disk set shifted in each
pixel, an EXR of float red and green and a half-float blue, Mitsuba with every
Lambertian's colour a 1 x 1 bitmap texture, and Mitsuba with a half-float film.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s ``edit``
and ``mitsuba_edit``), Mitsuba renders at another field of view, Mitsuba's path
integrator on sub-pixel offsets a student's loop makes
(:func:`mcrt.grade.accuracy.unforeseen._mean_through`), its first vertex's direct
light redone as a student's light sample makes it
(:func:`mcrt.grade.accuracy.unheralded._first_vertex`), its first bounce redrawn
(:func:`mcrt.grade.accuracy.unprompted._first_bounce`), its samples, one by one,
cut or traced in another scene where a student's path changes (same-seed samples
of max depth 2 and 8, :func:`mcrt.grade.accuracy.unbeknown._camera_samples`) or
combined as a student's loop combines them
(:func:`mcrt.grade.accuracy.unbidden._all_samples`), or correct renders
post-processed and written with NumPy, SciPy, Pillow and the standard library as
students' programs do. mcrt renders only a correct hand-in.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over
:data:`CATEGORIES`: the 2nd, 4th, ... of each category and of the correct
hand-ins) are as in :mod:`~mcrt.grade.accuracy.unvisited`, fixed before any case
was graded.
"""

from __future__ import annotations

import math
import struct
import zlib
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unbeknown, unbidden,
                                 unforeseen, unguessed, unheard, unheralded, unmet, unprompted, unsaid, unseen,
                                 unsought, untold, untried, unvisited)
from mcrt.grade.accuracy.cases import Spec
from mcrt.image_files import srgb_oetf

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


#: The classes after the first two, in the order they were written (their causes' words are this class's too).
_EARLIER = (programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked, unsought,
            unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited)


def _crc(name: str) -> int:
    return 901000 + zlib.crc32(name.encode()) % 100000


_render = unseen._render
_posted = unseen._posted
_scene = unprompted._scene

#: The class's spp (the class is built at 64 x 64).
_S = 256
#: The assignment's maximum depth.
_DEPTH = 8


# --------------------------------------------------------------------------
# Post-processing (linear render in, what the program writes out)
# --------------------------------------------------------------------------


def _median_all_axes(x):
    """``scipy.ndimage.median_filter(img, size=3)`` on the (H, W, 3) render: ``size`` counts for every axis, so each
    value is the median of a 3 x 3 x 3 block, its neighbours' other channels among them (the ends reflected)."""
    from scipy.ndimage import median_filter

    return median_filter(np.asarray(x, np.float64), size=3)


def _tanh_curve(x):
    """``np.tanh(img)`` as a quick tone curve: nearly linear in the dark, 1 at the light."""
    return np.tanh(np.asarray(x, np.float64))


#: Linear Adobe RGB (1998) to CIE XYZ, and CIE XYZ to linear sRGB (both D65).
_ADOBE_TO_XYZ = np.array([[0.5767309, 0.1855540, 0.1881852], [0.2973769, 0.6273491, 0.0752741],
                          [0.0270343, 0.0706872, 0.9911085]])
_XYZ_TO_SRGB = np.array([[3.2404542, -1.5371385, -0.4985314], [-0.9692660, 1.8760108, 0.0415560],
                         [0.0556434, -0.2040259, 1.0572252]])


def _adobe_to_srgb(x):
    """The linear render taken for Adobe RGB (1998) (a colour-managed script's assumed profile) and converted to
    linear sRGB, the negatives (colours outside sRGB) clipped to 0: the colours more saturated."""
    return np.maximum(np.asarray(x, np.float64) @ (_XYZ_TO_SRGB @ _ADOBE_TO_XYZ).T, 0.0)


def _write_png_sharpened(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB PNG through Pillow's ``ImageEnhance.Sharpness(img).enhance(2.0)``: the image plus its difference
    from Pillow's 3 x 3 SMOOTH filter (the border pixels kept)."""
    from PIL import Image, ImageEnhance

    path = folder / "render.png"
    ImageEnhance.Sharpness(Image.fromarray(blind._srgb8(image), "RGB")).enhance(2.0).save(path, format="PNG")
    return path


# --------------------------------------------------------------------------
# Writers (the render in, the file a program writes)
# --------------------------------------------------------------------------


def _average_uint8_sum(codes: np.ndarray) -> bytes:
    """The PNG scanlines of (H, W, 3) 8-bit codes with filter type 3 (Average) whose prediction ``(left + up) // 2``
    is taken on the ``uint8`` arrays: the sum wraps past 255, so a byte whose neighbours add up to 256 or more is
    predicted 128 too low, and a decoder (which adds without wrapping) puts its error into every byte after it."""
    rows = codes.reshape(codes.shape[0], -1)
    left = np.pad(rows[:, :-3], ((0, 0), (3, 0)))
    up = np.pad(rows[:-1], ((1, 0), (0, 0)))
    filtered = ((rows.astype(np.int16) - (left + up) // 2) % 256).astype(np.uint8)
    return b"".join(b"\x03" + r.tobytes() for r in filtered)


_write_png_average_uint8 = partial(unbeknown._write_png_scanlines, filtered=_average_uint8_sum)


def _codes(values: np.ndarray) -> np.ndarray:
    """8-bit codes of display values in [0, 1], rounded."""
    return np.floor(np.clip(values, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def _decode_inverted_codes(image: np.ndarray) -> np.ndarray:
    """8-bit codes of the sRGB encoding written from the decoding's formula, ``((v + 0.055) / 1.055) ** (1 / 2.4)``
    (its inner expression kept, the exponent inverted): black code 74, every dark value far too bright."""
    v = np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 1.0)
    return _codes(((v + 0.055) / 1.055) ** (1.0 / 2.4))


def _write_png_decode_inverted(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_decode_inverted_codes(image), folder)


#: The 17 linear values of the coarse sRGB table (a shader's lookup, 0 to 1 in sixteenths).
_COARSE = np.linspace(0.0, 1.0, 17)


def _coarse_table_codes(image: np.ndarray) -> np.ndarray:
    """8-bit codes of the sRGB curve looked up with ``np.interp(v, table_x, srgb(table_x))`` in a table of 17
    entries: the curve's chords for the curve, the shadows (under 1/16, where the curve is steepest) too dark."""
    v = np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 1.0)
    return _codes(np.interp(v, _COARSE, srgb_oetf(_COARSE)))


def _write_png_coarse_table(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_coarse_table_codes(image), folder)


def _rgbe_rounded_wrapping(image: np.ndarray) -> np.ndarray:
    """(H, W, 4) RGBE bytes with ``frexp(largest)``'s exponent and each mantissa ``np.round(v * 256 / 2^e)`` cast to a
    byte unclipped: a largest channel within half a step of 2^e rounds to 256, which the cast wraps to 0 (that pixel's
    brightest channel black)."""
    a = np.maximum(np.nan_to_num(np.asarray(image, np.float64)), 0.0)
    mx = a.max(axis=2)
    _, e = np.frexp(mx)
    lit = mx > 1e-30
    m = np.round(a * np.ldexp(1.0, 8 - e)[..., None]).astype(np.int64) % 256
    out = np.zeros(a.shape[:2] + (4,), np.uint8)
    out[..., :3] = np.where(lit[..., None], m, 0)
    out[..., 3] = np.where(lit, e + 128, 0)
    return out


def _write_hdr_rounded_wrapping(image: np.ndarray, folder: Path) -> Path:
    return unprompted._write_hdr_flat(_rgbe_rounded_wrapping(image), folder)


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _over_channel_sum(albedo) -> tuple[float, ...]:
    """An 'energy check': the albedo divided by its channels' sum where that sum exceeds 1."""
    total = sum(albedo)
    return tuple(float(a / total) for a in albedo) if total > 1.0 else tuple(albedo)


def _albedos_over_sum(s):
    """Every Lambertian albedo through :func:`_over_channel_sum`: the ceiling 0.33 for 0.8, the floor 0.33 for 0.6,
    the yellow wall (0.47, 0.44, 0.09), the red one (0.71, 0.14, 0.14)."""
    return unbidden._albedos_mapped(s, _over_channel_sum)


def _fan_sorted_by_x(name: str) -> np.ndarray:
    """(4, 3, 3): the floor or the ceiling fanned from the room's corners sorted by x (``sorted(corners.values(),
    key=lambda c: c[0])``: A, B, F, C, E, D), each triangle wound as the face's own (the floor's normals up)."""
    room = _scene().room
    z = room.floor_z if name == "floor" else room.ceiling_z
    tris = unbeknown._polygon_fan([(*c, z) for c in sorted(room.corners.values(), key=lambda c: c[0])])
    up = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])[:, 2] > 0
    return np.where((up != (name == "floor"))[:, None, None], tris[:, [0, 2, 1]], tris)


def _floor_ceiling_sorted(d: dict) -> dict:
    """The floor and the ceiling as :func:`_fan_sorted_by_x` makes them: the triangles B, C, (0, -1.38) and C, D, (10,
    0) of each missing, the void seen through them."""
    from mcrt.mitsuba_scene import _bsdf_dict

    for name in ("floor", "ceiling"):
        d = fresh._rebuilt(d, name, _fan_sorted_by_x(name), _bsdf_dict(fresh._surface(name).material))
    return d


def _sphere_upper_half(d: dict, *, segments: int = 96, rings: int = 48) -> dict:
    """The mirror sphere as a UV mesh whose rings' loop stops at ``rings // 2`` (a dome generator's bound): its upper
    half only, open below the equator."""
    from mcrt.mitsuba_scene import _bsdf_dict

    sph = _scene().spheres()[0]
    tris = untried._sphere_mesh(sph.center, sph.radius, segments, rings)
    upper = tris.mean(axis=1)[:, 2] >= sph.center[2]
    return fresh._rebuilt(d, "sphere", tris[upper], _bsdf_dict(sph.material))


def _bitmap_albedos(d: dict) -> dict:
    """Every Lambertian's colour a 1 x 1 bitmap texture of its albedo (``raw``: no sRGB decoding, nearest lookup)."""
    import mitsuba as mi

    from mcrt.scene import Lambertian

    lambertians = [sf for sf in _scene().surfaces() if isinstance(sf.material, Lambertian)]
    for sf in lambertians:
        texel = mi.Bitmap(np.full((1, 1, 3), sf.material.albedo, np.float32))
        tex = {"type": "bitmap", "bitmap": texel, "raw": True, "filter_type": "nearest"}
        d = fresh._rebuilt(d, sf.name, sf.triangles, {"type": "twosided", "bsdf": {"type": "diffuse",
                                                                                  "reflectance": tex}})
    return d


def _film_half(d: dict) -> dict:
    """The film's components stored as half floats (``hdrfilm``'s ``component_format = 'float16'``)."""
    return dict(d, sensor=dict(d["sensor"], film=dict(d["sensor"]["film"], component_format="float16")))


def _aov_nested(d: dict) -> dict:
    """Mitsuba's ``aov`` integrator around the path tracer: the path tracer's R, G, B, then a depth AOV."""
    return dict(d, integrator={"type": "aov", "aovs": "dd.y:depth", "integrator": d["integrator"]})


# --------------------------------------------------------------------------
# The camera's field of view and sub-pixel offsets
# --------------------------------------------------------------------------


def _plane_in_pixels(x, *, spp: int, seed: int):
    """The image-plane point ``s = (i + u) - W / 2`` (pixel units, the division by W / 2 left out): a half-width of
    W / 2, a field of view of 2 atan(W / 2) (176.4 degrees at 64 pixels)."""
    h, w = x.shape[:2]
    return _render(w, h, spp, seed, sensor={"fov": math.degrees(2.0 * math.atan(w / 2.0))})


#: The field of view 90 turned into radians by ``/ 57`` (a rounded degrees-per-radian), in degrees: 90.47.
_FOV_OVER_57 = math.degrees(90.0 / 57.0)


def _strata_centred_twice(rng, n: int, *, w: int, pixels: int, side: int = 4):
    """Offsets over ``side`` x ``side`` strata, sample k in stratum k mod side^2, jittered ``(s + u - 0.5) / side``
    (the - 0.5 of a centred jitter kept): every offset half a stratum (1/8 pixel) up and left."""
    k = np.arange(n) % (side * side)
    u, v = rng.random((2, pixels, n))
    return (k % side + u - 0.5) / side, (k // side + v - 0.5) / side


def _poisson_disk_shifted(rng, n: int, *, w: int, pixels: int):
    """Offsets of ``n`` points drawn from a Poisson-disk set filling the pixel (``scipy.stats.qmc.PoissonDisk(2,
    radius=0.6 / sqrt(n)).fill_space()``, about 1.7 n points; its ``random(n)`` grows from one seed point, so its first
    n cluster), shifted at random in each pixel (Cranley-Patterson): every offset uniform on the pixel."""
    from scipy.stats import qmc

    pts = qmc.PoissonDisk(2, radius=0.6 / math.sqrt(n), rng=rng).fill_space()
    pts = pts[rng.choice(len(pts), n, replace=False)]
    shift = rng.random((2, pixels, 1))
    return np.mod(pts[:, 0] + shift[0], 1.0), np.mod(pts[:, 1] + shift[1], 1.0)


# --------------------------------------------------------------------------
# Light samples at the first vertex (unheralded._first_vertex's ``direct``)
# --------------------------------------------------------------------------


def _cosines(p, n, q):
    """(cos at the surface, signed; cos at the light, wi's z; squared distance)."""
    wi = unsaid._unit(q - p)
    return np.einsum("ij,ij->i", n, wi), wi[:, 2], np.sum((q - p) ** 2, axis=1)


def _half_lambert(p, n, q) -> np.ndarray:
    """The geometry term with Valve's half-Lambert ``(0.5 cos + 0.5)^2`` for ``max(0, cos)`` at the surface."""
    cs, cl, d2 = _cosines(p, n, q)
    return (0.5 * cs + 0.5) ** 2 * np.maximum(cl, 0.0) / d2


#: The cosine of the spotlight cone's half-angle (60 degrees) left on the area light.
_CONE = 0.5


def _spot_cone(p, n, q) -> np.ndarray:
    """The geometry term where the direction leaves the light within 60 degrees of its normal, 0 beyond."""
    return unbeknown._geometry(p, n, q) * (_cosines(p, n, q)[1] > _CONE)


def _light_cosine_twice(p, n, q) -> np.ndarray:
    """The geometry term times the cosine at the light again (in G and in the area-to-solid-angle pdf)."""
    return unbeknown._geometry(p, n, q) * np.maximum(_cosines(p, n, q)[1], 0.0)


def _light_cosine_clamped(p, n, q, *, floor: float = 0.1) -> np.ndarray:
    """The geometry term with the solid-angle pdf's cosine at the light ``max(cos, 0.1)`` (against a division by
    zero), the light's back (cos <= 0) still black."""
    cs, cl, d2 = _cosines(p, n, q)
    return np.maximum(cs, 0.0) * np.where(cl > 0.0, np.maximum(cl, floor), 0.0) / d2


def _previous_wall_normals(p, n) -> np.ndarray:
    """(N, 3): ``n``, but on wall k the inward normal of wall k - 1 (the walls' normals list read one place off;
    wall AB takes FA's)."""
    walls = len(_scene().room.walls)
    planes = _scene().room.planes()[:walls]
    out = np.array(n, np.float64)
    for k in range(walls):
        on = np.abs(p @ planes[k, :3] - planes[k, 3]) < 1e-3
        out[on] = -planes[k - 1, :3]
    return out


def _wall_normal_shifted(p, n, q) -> np.ndarray:
    return unbeknown._geometry(p, _previous_wall_normals(p, n), q)


def _from_ray_origin(mscene, rng, p, n, rho, mitsuba):
    """The light sample taken from the camera ray's origin (``ray.o`` for the hit point): the eye's distance,
    direction and shadow ray, with the surface's normal."""
    eye = np.broadcast_to(unsaid._frame()[0], p.shape)
    return unbeknown._light_sampled(mscene, rng, eye, n, rho, mitsuba)


def _light_sample(name: str, direct) -> dict:
    """A spec's post-process: Mitsuba's path with its first vertex's light sample made by ``direct``."""
    return _posted(name, partial(unheralded._first_vertex, spp=_S, seed=_crc(name), direct=direct))


def _geometry_sample(name: str, geometry) -> dict:
    """:func:`_light_sample` by :func:`mcrt.grade.accuracy.unbeknown._light_sampled` with ``geometry``."""
    return _light_sample(name, partial(unbeknown._light_sampled, geometry=geometry))


# --------------------------------------------------------------------------
# Bounces and samples of the path
# --------------------------------------------------------------------------


def _square_lifted(rng, n):
    """Cosine-weighted directions whose disk sample is drawn in the square [-1, 1]^2 (no rejection, no concentric
    map), lifted with z = sqrt(max(0, 1 - x^2 - y^2)): a fifth of them along the tangent plane, weighted by the
    albedo."""
    x, y = rng.random((2, len(n))) * 2.0 - 1.0
    z = np.sqrt(np.maximum(1.0 - x * x - y * y, 0.0))
    t, b = unforeseen._frame_of(n)
    return unsaid._unit(x[:, None] * t + y[:, None] * b + z[:, None] * n), np.ones(len(n))


def _roulette_on_radiance_sample(o, d, seed, *, full, direct):
    """A sample whose Russian roulette after the first vertex's light sample survives with ``min(1, max(L))``, L the
    path's radiance so far (the same seed's max-depth-2 sample), the survivors divided by it: a path with nothing yet
    stops there; the others, unbiased, Mitsuba's."""
    L, near = unsaid._sampled(full, o, d, seed), unsaid._sampled(direct, o, d, seed)
    return np.where((near.max(axis=1) > 0.0)[:, None], L, near)


def _roulette_on_radiance(x, *, spp: int, seed: int):
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(
        _roulette_on_radiance_sample, full=unsaid._loaded(_DEPTH), direct=unsaid._loaded(2)))


def _first_albedo_only_sample(o, d, seed, *, full, white):
    """A sample whose path meets a Lambertian first traced in the scene where every Lambertian is white, times that
    first one's albedo (``if depth == 0: beta *= albedo``: the later albedos never multiplied)."""
    L = unsaid._sampled(full, o, d, seed)
    rho = unsaid._first_albedo(full, o, d)
    sel = rho.max(axis=1) > 0.0
    if sel.any():
        L[sel] = rho[sel] * unsaid._sampled(white, o[sel], d[sel], seed)
    return L


def _first_albedo_only(x, *, spp: int, seed: int):
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(
        _first_albedo_only_sample, full=unsaid._loaded(_DEPTH), white=unbeknown._albedo_scene((1.0, 1.0, 1.0))))


def _grey_mean(x):
    """Each pixel ``np.mean(samples)`` with no axis: the mean over the samples and the channels, one grey value."""
    x = np.asarray(x, np.float64)
    return np.repeat(x.mean(axis=2, keepdims=True), 3, axis=2)


def _root_mean_square(x, *, spp: int, seed: int):
    """Each pixel ``np.sqrt(np.mean(samples ** 2, axis=0))``, channel by channel (a magnitude for the mean)."""
    h, w = x.shape[:2]
    return np.sqrt((unbidden._all_samples(w, h, spp, seed) ** 2).mean(axis=1)).reshape(h, w, 3)


def _fancy_index_added(x, *, spp: int, seed: int, batch: int = 64):
    """Batches of ``batch`` samples a pixel added with ``film[ys, xs] += L`` (each pixel's index repeated ``batch``
    times): NumPy's fancy-index add is buffered, so of each pixel's repeated entries one (the last) is added; the sum
    of those divided by the spp."""
    h, w = x.shape[:2]
    L = unbidden._all_samples(w, h, spp, seed)
    return (L[:, batch - 1::batch].sum(axis=1) / spp).reshape(h, w, 3)


def _count_per_row(x):
    """The sample counter reset before each row, not each pixel: pixel i of a row divided by the (i + 1) spp samples
    of the row so far."""
    x = np.asarray(x, np.float64)
    return x / (np.arange(x.shape[1]) + 1.0)[None, :, None]


# --------------------------------------------------------------------------
# Correct files made in other ways
# --------------------------------------------------------------------------


def _tga_bottom_up(codes: np.ndarray) -> bytes:
    """An uncompressed 24-bit TGA of ``codes`` (H, W, 3) as the format stores it by default: its descriptor's origin
    bit clear, the bottom row first, BGR."""
    h, w = codes.shape[:2]
    head = struct.pack("<BBBHHBHHHHBB", 0, 0, 2, 0, 0, 0, 0, 0, w, h, 24, 0)
    return head + np.ascontiguousarray(codes[::-1, :, ::-1]).tobytes()


def _write_tga_bottom_up(image: np.ndarray, folder: Path) -> Path:
    path = folder / "render.tga"
    path.write_bytes(_tga_bottom_up(blind._srgb8(image)))
    return path


def _bmp32_bytes(codes: np.ndarray) -> bytes:
    """A 32-bit BMP by hand: BITMAPFILEHEADER, BITMAPINFOHEADER (BI_RGB), BGRX pixels (the fourth byte unused),
    bottom row first."""
    h, w = codes.shape[:2]
    bgrx = np.concatenate([codes[::-1, :, ::-1], np.zeros((h, w, 1), np.uint8)], axis=2)
    body = np.ascontiguousarray(bgrx).tobytes()
    info = struct.pack("<IiiHHIIiiII", 40, w, h, 1, 32, 0, len(body), 2835, 2835, 0, 0)
    return b"BM" + struct.pack("<IHHI", 54 + len(body), 0, 0, 54) + info + body


def _write_bmp32(image: np.ndarray, folder: Path) -> Path:
    path = folder / "render.bmp"
    path.write_bytes(_bmp32_bytes(blind._srgb8(image)))
    return path


def _write_exr_mixed_types(image: np.ndarray, folder: Path) -> Path:
    """An EXR whose R and G are float and B half-float (the program's blue buffer a half array)."""
    path = folder / "render.exr"
    chans = {c: np.ascontiguousarray(image[..., i], np.float32) for i, c in enumerate("RG")}
    chans["B"] = np.ascontiguousarray(image[..., 2], np.float16)
    fresh._exr_file(path, chans)
    return path


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_median_filter_all_axes", "pp_tanh_tone_curve", "pp_pillow_sharpness_2",
                        "pp_adobe_rgb_assumed"),
    "file": ("file_png_average_filter_uint8", "file_png_srgb_from_decoding", "file_png_srgb_coarse_table",
             "file_hdr_mantissa_rounds_to_256"),
    "materials": ("lambert_inv_pi_floor_division", "light_sample_half_lambert", "albedo_energy_check_sum"),
    "geometry": ("floor_ceiling_corners_sorted_x", "sphere_upper_half_mesh", "wall_normals_one_off"),
    "camera": ("plane_in_pixel_units", "fov_radians_over_57", "strata_jitter_centred_twice"),
    "light": ("light_spot_cone_left_on", "light_cosine_twice", "light_pdf_cosine_clamped"),
    "integrator": ("roulette_on_radiance", "light_sample_from_ray_origin", "bounce_disk_in_square",
                   "albedo_first_bounce_only"),
    "samples": ("pixel_mean_no_axis", "pixel_root_mean_square", "fancy_index_add_batches", "sample_counter_per_row"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_median_filter_all_axes", "blur", True, **_posted("median_all_axes", _median_all_axes),
             truth="scipy.ndimage.median_filter(img, size=3) on the (H, W, 3) render against fireflies, as EXR: size "
             "3 along the channel axis too, each value the median of a 3 x 3 x 3 block (its neighbours' other "
             "channels among them): the noise and the fine detail gone, the walls' colours pulled towards grey"),
        Spec("pp_tanh_tone_curve", "tone_map", held_out=True, **_posted("tanh_curve", _tanh_curve),
             truth="np.tanh(img) as a quick tone curve before the EXR: the dark values nearly kept (0.1 to 0.0997), a "
             "wall of 0.5 at 0.46, 1 at 0.76, the light and its reflection at 1"),
        Spec("pp_pillow_sharpness_2", "sharpen", writer=_write_png_sharpened, file="png-sharpness",
             truth="Pillow's ImageEnhance.Sharpness(img).enhance(2.0) on the 8-bit sRGB image before the PNG: the "
             "codes plus their difference from Pillow's 3 x 3 SMOOTH filter, the edges and the noise crisper, the "
             "border pixels kept"),
        Spec("pp_adobe_rgb_assumed", "colour_space", held_out=True, **_posted("adobe_to_srgb", _adobe_to_srgb),
             truth="the linear render taken for Adobe RGB (1998) (a colour-managed script's assumed profile) and "
             "converted to linear sRGB before the EXR, negatives clipped to 0: the greens and the reds more "
             "saturated, the greys kept"),
        # Writing the file
        Spec("file_png_average_filter_uint8", "file_format", True, writer=_write_png_average_uint8,
             file="png-average-uint8",
             truth="an 8-bit sRGB PNG written by hand with the Average filter on every row, its prediction (left + up) "
             "// 2 taken on the uint8 arrays: the sum wraps past 255, the bytes whose neighbours add to 256 or more "
             "predicted 128 low, and the decoder carries each error into the bytes after it (streaks along the rows "
             "and down the image from the bright parts)"),
        Spec("file_png_srgb_from_decoding", "encoding", True, held_out=True, writer=_write_png_decode_inverted,
             file="png-srgb-from-decoding",
             truth="an 8-bit PNG encoded with ((v + 0.055) / 1.055) ** (1 / 2.4), the sRGB decoding's inner formula "
             "with the exponent inverted, for sRGB's encoding: black written as code 74, the dark parts far too "
             "bright once decoded, white right"),
        Spec("file_png_srgb_coarse_table", "encoding", writer=_write_png_coarse_table, file="png-coarse-table",
             truth="an 8-bit PNG whose sRGB curve is looked up with np.interp in a table of 17 entries (0 to 1 in "
             "sixteenths, a shader's lookup): the curve's chords, values under 1/16 half as bright or less, the "
             "mid-tones within a per cent"),
        Spec("file_hdr_mantissa_rounds_to_256", "code_overflow", held_out=True, writer=_write_hdr_rounded_wrapping,
             file="hdr-mantissa-wraps",
             truth="a Radiance HDR written by hand with frexp(largest)'s exponent and each mantissa np.round(v * 256 / "
             "2^e) cast to a byte without a clip: a pixel whose largest channel lies within half a step under a "
             "power of two rounds it to 256, written 0 (that channel black; a few pixels in a thousand)"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("lambert_inv_pi_floor_division", "brdf_norm", True, mitsuba_edit=untold._black_diffuse,
             truth="the Lambertian's constant typed INV_PI = 1 // math.pi (floor division: 0.0) for 1 / math.pi: "
             "every Lambertian's BRDF 0, in the light sample and the bounce alike: the room black, only the light "
             "and its reflection in the mirror seen"),
        Spec("light_sample_half_lambert", "material", True, held_out=True, **_geometry_sample(
            "light_sample_half_lambert", _half_lambert),
             truth="Valve's half-Lambert (0.5 cos + 0.5)^2 for max(0, cos) in the light sample (a game shader's soft "
             "lighting), at the first surface a camera ray meets (Mitsuba's path after it): light arriving obliquely too "
             "bright (3 times at a cosine of 0.1, 12 % at 0.5), surfaces turned from the light lit a little, the floor "
             "under the light and the light seen right"),
        Spec("albedo_energy_check_sum", "albedo", True, edit=_albedos_over_sum,
             truth="an energy check on the scene's albedos dividing each by the sum of its channels where that sum "
             "exceeds 1 (the channels taken to share the energy): the ceiling and the floor 0.33, the yellow wall "
             "(0.47, 0.44, 0.09), the tetrahedron (0.59, 0.33, 0.07), the room darker"),
        # Geometry
        Spec("floor_ceiling_corners_sorted_x", "mesh_face", True, mitsuba_edit=_floor_ceiling_sorted,
             truth="the floor's and the ceiling's corners sorted by x before they are fanned (sorted(corners.values(), "
             "key=lambda c: c[0]): A, B, F, C, E, D): the fan's triangles overlap and miss two pieces, B, C, (0, "
             "-1.38) and C, D, (10, 0), two holes along the room's right side (walls BC and CD), the void seen "
             "through the floor's"),
        Spec("sphere_upper_half_mesh", "object_shape", True, held_out=True, mitsuba_edit=_sphere_upper_half,
             truth="the mirror sphere meshed as a UV sphere whose rings' loop stops at rings // 2 (a dome generator's "
             "bound): its upper half only, open below the equator, the floor seen under it and the hollow inside "
             "black"),
        Spec("wall_normals_one_off", "normals", True, **_geometry_sample("wall_normals_one_off",
                                                                          _wall_normal_shifted),
             truth="the walls' normals list read one place off in the light sample (normals[k - 1] for wall k, wall AB "
             "taking FA's), at the first surface a camera ray meets (Mitsuba's path after it): each wall lit as if "
             "turned 60 degrees, parts of it black, others brighter, the floor and the ceiling right"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera
        Spec("plane_in_pixel_units", "camera_fov", True, **_posted("plane_in_pixels", partial(
            _plane_in_pixels, spp=_S, seed=c("plane_in_pixel_units"))),
             truth="the image-plane point s = (i + u) - W / 2 in pixel units (the division by W / 2 left out): a "
             "half-width of W / 2, a field of view of 176.4 degrees at 64 pixels, the room a small spot in the "
             "middle of a view reaching sideways"),
        Spec("fov_radians_over_57", "camera_fov", held_out=True, edit=cases.fov(_FOV_OVER_57),
             truth="the field of view turned into radians as fov / 57 (a rounded degrees-per-radian): 1.579 for "
             "1.571, 90.47 degrees for 90, the view 0.8 % smaller, a quarter of a pixel at the image's edges"),
        Spec("strata_jitter_centred_twice", "pixel_offset", **_posted("strata_centred_twice", partial(
            unforeseen._mean_through, spp=_S, seed=c("strata_jitter_centred_twice"), jitter=_strata_centred_twice)),
             truth="4 x 4 strata a pixel with the jitter (s + u - 0.5) / 4, a centred jitter's - 0.5 kept with "
             "strata: every sample half a stratum up and left, each pixel's square an eighth of a pixel off, the "
             "image an eighth of a pixel down and right"),
        # Light model
        Spec("light_spot_cone_left_on", "light_model", True, **_geometry_sample("light_spot_cone_left_on",
                                                                                 _spot_cone),
             truth="a spotlight's cone of 60 degrees (a template's default) left on the area light's sample: no light "
             "leaving it more than 60 degrees from its normal, at the first surface a camera ray meets (Mitsuba's "
             "path after it): the walls' upper parts unlit, the floor and the light seen right"),
        Spec("light_cosine_twice", "light_pdf", True, held_out=True, **_geometry_sample("light_cosine_twice",
                                                                                         _light_cosine_twice),
             truth="the cosine at the light applied twice in its sample, in the geometry term and in the "
             "area-to-solid-angle pdf's conversion (cos_l^2 / d^2), at the first surface a camera ray meets "
             "(Mitsuba's path after it): the light on surfaces darker the more obliquely it leaves the light, the "
             "walls most, the light seen right"),
        Spec("light_pdf_cosine_clamped", "light_pdf", **_geometry_sample("light_pdf_cosine_clamped",
                                                                          _light_cosine_clamped),
             truth="the light sample's solid-angle pdf d^2 / (A max(cos_l, 0.1)) (its cosine clamped against a "
             "division by zero), at the first surface a camera ray meets (Mitsuba's path after it): light leaving "
             "the light within 6 degrees of its plane counted as at 6, a bright band along the walls' tops"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples, passes and counters."""
    c = _crc
    return (
        # Integrator
        Spec("roulette_on_radiance", "roulette", True, **_posted("roulette_on_radiance", partial(
            _roulette_on_radiance, spp=_S, seed=c("roulette_on_radiance"))),
             truth="Russian roulette from the first vertex with survival min(1, max(L)), L the path's radiance so far "
             "for its throughput, the survivors divided by it: a path with no light yet (its first light sample "
             "blocked or facing away) always stops: the ceiling black, the shadows without their indirect light"),
        Spec("light_sample_from_ray_origin", "light_pdf", True, held_out=True, **_light_sample(
            "light_sample_from_ray_origin", _from_ray_origin),
             truth="the light sample taken from the ray's origin (ray.o for the hit point: the eye for a camera ray) "
             "with the surface's normal, at the first surface a camera ray meets (Mitsuba's path after it): no "
             "shadows, every surface lit as if it stood at the eye, the far walls facing away unlit, the light seen "
             "right"),
        Spec("bounce_disk_in_square", "indirect_scale", **_posted("disk_in_square", partial(
            unprompted._first_bounce, spp=_S, seed=c("bounce_disk_in_square"), draw=_square_lifted)),
             truth="the cosine-weighted bounce's disk sample drawn in the square [-1, 1]^2 (the rejection left out) "
             "and lifted with sqrt(max(0, 1 - x^2 - y^2)), at the first surface a camera ray meets (Mitsuba's path "
             "after it): a fifth of the bounces along the tangent plane, weighted as cosine samples: the indirect "
             "light biased towards what lies at grazing angles"),
        Spec("albedo_first_bounce_only", "indirect_scale", True, held_out=True, **_posted("first_albedo_only", partial(
            _first_albedo_only, spp=_S, seed=c("albedo_first_bounce_only"))),
             truth="the albedo multiplied into the throughput at the first bounce only (if depth == 0: beta *= "
             "albedo), where a camera ray meets a Lambertian first: every later surface reflecting as if white, the "
             "indirect light several times too bright and uncoloured"),
        # Samples, passes and counters
        Spec("pixel_mean_no_axis", "colour_lost", True, **_posted("mean_no_axis", _grey_mean),
             truth="each pixel np.mean(samples) without axis=0 (NumPy's default: over every axis), the scalar "
             "broadcast into R, G and B: one grey value a pixel, the mean of its channels"),
        Spec("pixel_root_mean_square", "biased_estimator", True, held_out=True, **_posted("root_mean_square", partial(
            _root_mean_square, spp=_S, seed=c("pixel_root_mean_square"))),
             truth="each pixel np.sqrt(np.mean(samples ** 2, axis=0)), a root mean square for the mean: every pixel "
             "whose samples vary too bright (the root of its mean's square plus its variance), the room about 40 % "
             "brighter, the light's edges and the penumbrae more"),
        Spec("fancy_index_add_batches", "sample_count", True, **_posted("fancy_index_add", partial(
            _fancy_index_added, spp=_S, seed=c("fancy_index_add_batches"))),
             truth="batches of 64 samples a pixel added with film[ys, xs] += L, each pixel's index repeated 64 times: "
             "NumPy's buffered fancy-index add keeps one of them, 4 of 256 samples summed and divided by 256: every "
             "pixel 64 times too dark and as noisy as 4 spp"),
        Spec("sample_counter_per_row", "sample_count", True, held_out=True, **_posted("counter_per_row",
                                                                                       _count_per_row),
             truth="the sample counter set to 0 before each row, not each pixel, each pixel's sum divided by it: "
             "pixel i of a row divided by (i + 1) times the spp, the first column right, the image darker to the "
             "right (1/64 at the right edge)"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_near_clip_image_plane", None, spp=136, sensor={"near_clip": 1.0},
             truth="Mitsuba path 136 spp with the sensor's near clip 1 (the camera rays starting on the image plane), "
             "EXR"),
        Spec("ok_mcrt_tga_bottom_up", None, held_out=True, spp=60, renderer="mcrt", writer=_write_tga_bottom_up,
             file="tga-bottom-up",
             truth="mcrt 60 spp, a 24-bit sRGB TGA written by hand as the format stores it by default: origin bit "
             "clear, the bottom row first, BGR"),
        Spec("ok_aov_integrator_colour", None, spp=200, **_posted("aov_nested", partial(
            unvisited._mitsuba_edited, spp=200, seed=c("ok_aov_integrator_colour"), edit=_aov_nested)),
             truth="Mitsuba's aov integrator around the path tracer, 200 spp, its R, G, B kept (the depth AOV "
             "dropped), EXR"),
        Spec("ok_bmp32_by_hand", None, held_out=True, spp=180, writer=_write_bmp32, file="bmp32",
             truth="Mitsuba path 180 spp, a 32-bit sRGB BMP written by hand (BI_RGB, BGRX, the bottom row first)"),
        Spec("ok_poisson_disk_offsets", None, **_posted("poisson_disk", partial(
            unforeseen._mean_through, spp=_S, seed=c("ok_poisson_disk_offsets"), jitter=_poisson_disk_shifted)),
             truth="Mitsuba path 256 spp, sub-pixel offsets drawn from a scipy.stats.qmc.PoissonDisk set filling the "
             "pixel, shifted at random in each pixel (Cranley-Patterson), EXR"),
        Spec("ok_exr_mixed_pixel_types", None, held_out=True, spp=168, writer=_write_exr_mixed_types,
             file="exr-mixed-types",
             truth="Mitsuba path 168 spp, an EXR whose R and G are float and B half-float"),
        Spec("ok_bitmap_albedos", None, spp=152, mitsuba_edit=_bitmap_albedos,
             truth="Mitsuba path 152 spp with every Lambertian's colour a 1 x 1 bitmap texture (raw, nearest), EXR"),
        Spec("ok_film_half_float", None, held_out=True, spp=232, mitsuba_edit=_film_half,
             truth="Mitsuba path 232 spp with a half-float film (hdrfilm component_format float16), EXR"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "blur": "a filter after rendering (a median filter over the channels too)",
    "tone_map": "a tone map applied before saving (np.tanh as a tone curve)",
    "sharpen": "a sharpening filter after rendering (Pillow's sharpness enhancer)",
    "colour_space": "values in another colour space (the render taken for Adobe RGB and converted to sRGB)",
    "file_format": "the file's data not what its format says (a PNG filter's prediction computed in uint8)",
    "encoding": "the values' encoding (the sRGB curve written from its decoding, or looked up in a coarse table)",
    "code_overflow": "codes past 255 wrapped round (an RGBE mantissa rounded to 256)",
    "brdf_norm": "a BRDF's normalisation (1 // pi: every Lambertian black)",
    "material": "an object rendered with another material (a half-Lambert light sample)",
    "albedo": "a surface's colour (albedos divided by their channels' sum)",
    "mesh_face": "a face of a mesh missing (the floor and the ceiling fanned from corners sorted by x)",
    "object_shape": "an object's shape (the sphere meshed as its upper half)",
    "normals": "surface normals wrong (the walls' normals read one place off)",
    "camera_fov": "the camera's field of view (the image plane in pixel units, degrees over 57)",
    "pixel_offset": "the pixel centres (strata jittered about their corners: the image shifted an eighth of a pixel)",
    "light_model": "another light model (a spotlight's cone on the area light)",
    "light_pdf": "the light sampled wrongly (its cosine twice or clamped, the sample taken from the ray's origin): the "
                 "light seen right, its light on surfaces not",
    "roulette": "Russian roulette wrong (tested on the radiance, not the throughput)",
    "indirect_scale": "the indirect light wrong (a bounce drawn from a square, the albedo multiplied once), the direct "
                      "light right",
    "colour_lost": "colour lost (each pixel one grey value)",
    "biased_estimator": "a biased estimate of each pixel's mean (a root mean square)",
    "sample_count": "each pixel's sum divided by more samples than it got (a fancy-index add, a counter per row)",
}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = blind.class_causes(MISTAKES, _EARLIER, NEW_CAUSES, _REWORDED)


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
