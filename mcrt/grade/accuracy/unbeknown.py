r"""A twentieth class of hand-ins: mistakes of students' tracers, scene input and output no class tried, blind.

How it was written: from what goes wrong in students' programs (the denoisers,
looks and filters run after rendering, the library calls and encoders that
save the image, the BRDF's terms and the mirror's placeholder, the
intersection loop, the room's orientation test and the polygon helper, the
camera's angles, projection and film splats, the light sample's cosine, the
emission counted and the shadow loop, the roulette's random number, the path
loop's exits, the bounce's frame and the path's albedo, the passes' weights
and the buffer written), not from the grader. Its author read the other
classes' specs and cause words, the catalogue (:mod:`mcrt.mutants`), the scene files and
design notes, mcrt's scene, camera and image code,
:data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to
stay clear of their mistakes; never the grader's rules (what decides a
cause) nor its reports, and graded none of it, not one case. Each cause and
``major`` flag was set from the mistake alone; every mistake is worded by a
cause the other classes already have (:data:`NEW_CAUSES` is empty), so
``SAME_MISTAKE`` needed no new entry. The mistakes differ from those of the
nineteen other classes (:mod:`~mcrt.grade.accuracy.cases`,
:mod:`~mcrt.grade.accuracy.outside` and the modules of :data:`_EARLIER`, from
:mod:`~mcrt.grade.accuracy.programs` to :mod:`~mcrt.grade.accuracy.unheralded`)
and from the catalogue's bugs:

* **post-processing**: Intel Open Image Denoise on the colour alone
  (``pyoidn.denoise``); a "teal and orange" split toning for the look; an
  unsharp mask misremembered as the image less half its blur; each pixel
  clamped to its neighbours' range (a real-time renderer's firefly clamp);
* **writing the file**: ``cv2.imwrite`` of sRGB values in [0, 1] (OpenCV's
  unscaled float-to-byte conversion); a hand-written PNG whose Sub filter
  takes the byte before, not the pixel before; a Radiance HDR whose mantissas
  are scaled by 255 for 256; 8-bit codes cast to a signed byte;
* **materials**: the mirror's ``reflect`` left as its placeholder ``-d``;
  every Lambertian shaded with the cosine to the viewer multiplied in; the
  light sample's BRDF without the albedo;
* **geometry**: the intersection loop returning the first shape in the list
  that a ray meets, not the nearest; the room's corners "reoriented" by a
  clockwise test of the wrong sign (every room face wound outwards); the
  tetrahedron's vertices fanned as a polygon;
* **camera**: the forward vector rebuilt from a yaw of ``atan2`` with its
  arguments swapped; the ray's forward component solved for unit length (an
  orthographic fisheye); each sample splatted bilinearly about its pixel's
  corner;
* **light model**: the light sample's cosine at the light taken with the
  surface's normal; the emission a camera ray meets counted twice; the
  course's 30 shadow rays a vertex with ``break`` at the first blocked one;
* **integrator**: Russian roulette with one random number for every test of
  a path; ``break`` out of the path loop where a shadow ray is blocked; the
  bounce's tangent frame ``cross(n, z)`` (NaN on the floor and the ceiling);
  the first hit's albedo kept for every bounce;
* **samples and passes**: passes blended by an exponential moving average;
  passes weighted by their own inverse variance; each pixel's samples
  averaged in log space; the normal AOV's debug view written for the beauty.

The correct hand-ins come in ways no class used: Mitsuba with sub-pixel
offsets from the Hammersley points digitally shifted in each pixel, Mitsuba at
twice the resolution and field of view with its centre cut out, an 8-bit PNG
written by hand with each row's filter chosen by libpng's heuristic, Mitsuba
with a ``thinlens`` sensor of a negligible aperture, four Mitsuba renders of
four samplers averaged, mcrt with the camera rolled half a turn and the image
turned back, Mitsuba with the floor and the ceiling triangulated by
``scipy.spatial.Delaunay``, and an 8-bit PNG encoded through a 12-bit table.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s
``edit`` and ``mitsuba_edit``), Mitsuba renders combined where light
transport or pixel integrals are linear in what is combined (paths of each
length, passes), Mitsuba's path integrator sampling the rays a student's
camera or mirror makes (the helpers of :mod:`~mcrt.grade.accuracy.unsaid`),
its first vertex's direct light redone as a student's light sample makes it
(:func:`mcrt.grade.accuracy.unheralded._first_vertex`), its samples, one by
one, cut after the first vertex's light sample, scaled or traced in another
scene where a student's path changes there (same-seed samples of max depth 1,
2 and 8), added up as a student's loop or film adds them
(:func:`mcrt.grade.accuracy.unbidden._all_samples`,
:func:`mcrt.grade.accuracy.unsought._film_samples`), its ``aov`` integrator,
or correct renders post-processed and written with NumPy, SciPy, Open Image
Denoise, Pillow and the standard library as students' programs do. mcrt
renders only a correct hand-in.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over
:data:`CATEGORIES`: the 2nd, 4th, ... of each category and of the correct
hand-ins) are as in :mod:`~mcrt.grade.accuracy.unheralded`, fixed before any
case was graded.
"""

from __future__ import annotations

import math
import zlib
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unbidden, unforeseen,
                                 unguessed, unheard, unheralded, unmet, unprompted, unsaid, unseen, unsought, untold,
                                 untried)
from mcrt.grade.accuracy.cases import Spec
from mcrt.image_files import srgb_oetf

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


#: The classes after the first two, in the order they were written (their causes' words are this class's too).
_EARLIER = (programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked, unsought,
            unguessed, unforeseen, unprompted, unbidden, unheralded)


def _crc(name: str) -> int:
    return 701000 + zlib.crc32(name.encode()) % 100000


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


def _oidn(x):
    """Intel Open Image Denoise on the colour alone, ``pyoidn.denoise(img.astype(np.float32), hdr=True)`` (its RT
    filter, no albedo or normal guides)."""
    import pyoidn

    return np.asarray(pyoidn.denoise(np.ascontiguousarray(x, np.float32), hdr=True), np.float64)


#: The teal-and-orange look's tints: the shadows', the highlights'.
_TEAL, _ORANGE = (0.9, 1.0, 1.1), (1.1, 1.0, 0.9)


def _teal_orange(x):
    """A "teal and orange" split toning for the look, ``t = np.clip(lum, 0, 1)[..., None]; img * ((1 - t) * (0.9,
    1.0, 1.1) + t * (1.1, 1.0, 0.9))``, lum the Rec. 709 luminance: the shadows bluer, the highlights warmer, the
    mid-greys kept."""
    x = np.asarray(x, np.float64)
    t = np.clip(unseen._luma(x), 0.0, 1.0)[..., None]
    return x * ((1.0 - t) * np.asarray(_TEAL) + t * np.asarray(_ORANGE))


def _unsharp_without_image(x, *, sigma: float = 1.0, amount: float = 0.5):
    """An unsharp mask misremembered, ``img - 0.5 * ndimage.gaussian_filter(img, (1, 1, 0))`` for ``img + 0.5 * (img
    - blurred)``, negatives clipped to 0: a flat area half as bright, edges sharpened."""
    from scipy.ndimage import gaussian_filter

    x = np.asarray(x, np.float64)
    return np.maximum(x - amount * gaussian_filter(x, (sigma, sigma, 0.0)), 0.0)


#: A 3 x 3 footprint without its centre (the 8 neighbours), one channel deep.
_RING = np.pad(np.zeros((1, 1, 1), bool), ((1, 1), (1, 1), (0, 0)), constant_values=True)


def _neighbour_clamped(x):
    """Each pixel clamped, channel by channel, to the range of its 8 neighbours (a real-time renderer's neighbourhood
    clamp, against fireflies): ``np.clip(img, minimum_filter(img, footprint=ring), maximum_filter(img,
    footprint=ring))``, ``ring`` the 3 x 3 footprint without its centre (SciPy, the edges mirrored)."""
    from scipy.ndimage import maximum_filter, minimum_filter

    x = np.asarray(x, np.float64)
    return np.clip(x, minimum_filter(x, footprint=_RING), maximum_filter(x, footprint=_RING))


# --------------------------------------------------------------------------
# Writers (the render in, the file a program writes)
# --------------------------------------------------------------------------


def _srgb(image: np.ndarray) -> np.ndarray:
    return srgb_oetf(np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 1.0))


def _cv2_float_codes(values: np.ndarray) -> np.ndarray:
    """What ``cv2.imwrite`` makes of a float image: each value rounded to an integer and saturated to 0-255
    (``cv::saturate_cast<uchar>``), not scaled."""
    return np.clip(np.rint(values), 0, 255).astype(np.uint8)


def _write_png_cv2_float(image: np.ndarray, folder: Path) -> Path:
    """``cv2.imwrite("render.png", cv2.cvtColor(srgb.astype(np.float32), cv2.COLOR_RGB2BGR))``, ``srgb`` the
    sRGB-encoded values in [0, 1] (the ``* 255`` left out): every code 0 or 1, the channels in their order."""
    return novel._write_png(_cv2_float_codes(_srgb(image)), folder)


def _png(w: int, h: int, scanlines: bytes) -> bytes:
    """An 8-bit RGB PNG file: its signature, IHDR, one IDAT (the zlib stream of ``scanlines``, each row its filter
    byte and its bytes), IEND."""
    import struct

    return (b"\x89PNG\r\n\x1a\n" + unseen._png_chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
            + unseen._png_chunk(b"IDAT", zlib.compress(scanlines, 9)) + unseen._png_chunk(b"IEND", b""))


def _write_png_scanlines(image: np.ndarray, folder: Path, filtered) -> Path:
    """The 8-bit sRGB codes of ``image`` written by hand as a PNG of the scanlines ``filtered(codes)`` makes."""
    h, w = image.shape[:2]
    path = folder / "render.png"
    path.write_bytes(_png(w, h, filtered(blind._srgb8(image))))
    return path


def _sub_one_byte(codes: np.ndarray) -> bytes:
    """The PNG scanlines of (H, W, 3) 8-bit codes with filter type 1 (Sub) taken one byte back, ``row[k] - row[k -
    1]``, where PNG's Sub takes the byte one pixel back (``row[k - 3]`` for RGB, the 'bpp' of the specification)."""
    rows = codes.astype(np.int16).reshape(codes.shape[0], -1)
    left = np.pad(rows[:, :-1], ((0, 0), (1, 0)))
    return b"".join(b"\x01" + r.astype(np.uint8).tobytes() for r in (rows - left) % 256)


_write_png_sub_one_byte = partial(_write_png_scanlines, filtered=_sub_one_byte)


def _rgbe_255(image: np.ndarray) -> np.ndarray:
    """(H, W, 4) RGBE bytes from Ward's formula with its 256 written 255 (the 8-bit habit): ``f, e =
    np.frexp(largest); m = np.round(v * f * 255 / largest)``, the exponent byte e + 128: every value read back 255 /
    256 of itself."""
    a = np.maximum(np.nan_to_num(np.asarray(image, np.float64)), 0.0)
    mx = a.max(axis=2)
    f, e = np.frexp(mx)
    lit = mx > 1e-30
    scale = np.where(lit, f * 255.0 / np.where(lit, mx, 1.0), 0.0)
    out = np.zeros(a.shape[:2] + (4,), np.uint8)
    out[..., :3] = np.floor(a * scale[..., None] + 0.5)
    out[..., 3] = np.where(lit, e + 128, 0)
    return out


def _write_hdr_mantissa_255(image: np.ndarray, folder: Path) -> Path:
    return unprompted._write_hdr_flat(_rgbe_255(image), folder)


def _signed_byte_codes(image: np.ndarray) -> np.ndarray:
    """What ``np.maximum((srgb * 255).round().astype(np.int8), 0).astype(np.uint8)`` gives: the codes cast to a
    signed byte (NumPy wraps 128 to 255 round to -128 to -1), the negatives then clipped to 0 as a guard: every code
    of 128 or more 0."""
    return np.maximum(blind._srgb8(image).view(np.int8), 0).astype(np.uint8)


def _write_png_signed_bytes(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_signed_byte_codes(image), folder)


# --------------------------------------------------------------------------
# Scene edits
# --------------------------------------------------------------------------


def _objects_never_found(d: dict) -> dict:
    """The tetrahedron and the sphere gone: an intersection loop that returns the first shape of its list a ray meets
    (``for shape in [light] + room + objects: if shape.hit(ray): return``), not the nearest: every ray meets the
    light or one of the room's faces first in the list, never an object (the shadow rays too)."""
    return fresh._without_mesh(fresh._without_mesh(d, "tetrahedron"), "sphere")


def _room_names() -> tuple[str, ...]:
    """The room's faces' mesh names: its walls, the floor and the ceiling."""
    return tuple(sf.name for sf in _scene().surfaces() if sf.name.startswith("wall_")) + ("floor", "ceiling")


def _room_outwards(d: dict) -> dict:
    """Every wall, the floor and the ceiling wound outwards with a one-sided Lambertian: the room's corners reversed
    by a clockwise test of the wrong sign (``if shoelace_area(corners) > 0: corners.reverse()``, a counter-clockwise
    room 'reoriented'), its faces built from them."""
    for name in _room_names():
        d = fresh._one_sided_flipped(d, name)
    return d


def _polygon_fan(vertices) -> np.ndarray:
    """(n - 2, 3, 3): the fan of triangles (v0, v[k], v[k + 1]) a polygon helper makes of its vertices."""
    v = np.asarray(vertices, np.float64)
    return np.array([[v[0], v[k], v[k + 1]] for k in range(1, len(v) - 1)])


def _tetra_fanned(d: dict) -> dict:
    """The tetrahedron's four vertices given to the room's polygon helper: the fan (v0, v1, v2), (v0, v2, v3), two of
    its four faces (the base and one side), two-sided."""
    from mcrt.mitsuba_scene import _bsdf_dict

    tetra = next(o for o in _scene().objects if o.name == "tetrahedron")
    return fresh._rebuilt(d, "tetrahedron", _polygon_fan(tetra.vertices), _bsdf_dict(tetra.material))


def _yaw_pitch_forward(forward, *, swapped: bool = True) -> tuple[float, float, float]:
    """The forward vector rebuilt from its yaw and pitch as a first-person camera's code keeps them: pitch asin(f.z),
    yaw ``atan2(f.x, f.y)`` with ``swapped`` (for ``atan2(f.y, f.x)``), then (cos p cos y, cos p sin y, sin p)."""
    f = np.asarray(forward, np.float64) / np.linalg.norm(forward)
    pitch = math.asin(f[2])
    yaw = math.atan2(f[0], f[1]) if swapped else math.atan2(f[1], f[0])
    return (math.cos(pitch) * math.cos(yaw), math.cos(pitch) * math.sin(yaw), math.sin(pitch))


def _yaw_atan2_swapped(s):
    """The near camera's forward vector from its yaw with ``atan2``'s arguments swapped: 90 degrees for 0, the camera
    looking along +y (its up the scene's)."""
    return cases._camera(s, forward=_yaw_pitch_forward(s.cameras["near"].forward))


def _thinlens(d: dict, *, radius: float = 1e-5, focus: float = 10.0) -> dict:
    """Mitsuba's ``thinlens`` sensor for the perspective one, same frame and field of view, an aperture of radius
    ``radius`` focused at ``focus``."""
    return dict(d, sensor=dict(d["sensor"], type="thinlens", aperture_radius=radius, focus_distance=focus))


def _delaunay_faces(name: str) -> np.ndarray:
    """(n, 3, 3): the room's floor or ceiling as ``scipy.spatial.Delaunay`` triangulates its corners, each triangle
    wound as the face's own (the floor's normals up, the ceiling's down)."""
    from scipy.spatial import Delaunay

    room = _scene().room
    poly = room.polygon()
    z = room.floor_z if name == "floor" else room.ceiling_z
    tris = np.array([[[*poly[i], z] for i in t] for t in Delaunay(poly).simplices])
    up = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])[:, 2] > 0
    return np.where((up != (name == "floor"))[:, None, None], tris[:, [0, 2, 1]], tris)


def _floor_ceiling_delaunay(d: dict) -> dict:
    from mcrt.mitsuba_scene import _bsdf_dict

    for name in ("floor", "ceiling"):
        d = fresh._rebuilt(d, name, _delaunay_faces(name), _bsdf_dict(fresh._surface(name).material))
    return d


# --------------------------------------------------------------------------
# The camera's and the mirror's rays
# --------------------------------------------------------------------------


def _direction_z_solved(fx, fy):
    """The camera ray's direction (s, t, sqrt(max(0, 1 - s^2 - t^2))) in the camera's frame (right, up, forward):
    its forward component solved for unit length, the image-plane point (s, t, 1) never normalised: an orthographic
    fisheye, 90 degrees from the view's axis at the image's edges (s = +-1), the corners looking sideways."""
    eye, r, u, f, k = unsaid._frame()
    s, t = k * (2.0 * fx - 1.0), k * (1.0 - 2.0 * fy)
    z = np.sqrt(np.maximum(1.0 - s * s - t * t, 0.0))
    return np.broadcast_to(eye, (len(fx), 3)), unsaid._unit(z[:, None] * f + s[:, None] * r + t[:, None] * u)


def _retroreflected(o, d):
    """Camera rays that meet the sphere sent back the way they came from the hit point (the mirror's ``reflect``
    left as its placeholder ``return -d``): (origins, directions, segments used)."""
    p, _, hit = unsaid._reflected(o, d)
    return p, np.where(hit[:, None] == 1, -d, d), hit


def _splat_about_corner(x, *, spp: int, seed: int):
    """Each sample splatted bilinearly to the four pixels about its film position (x, y) = (i + u, j + v): pixel
    (floor x, floor y) taking (1 - fx)(1 - fy) of it, (floor x + 1, floor y) fx (1 - fy), ..., ``fx = x -
    floor(x)`` (the pixel's corner taken for its centre, no ``- 0.5``), each pixel's sum divided by its weights: a
    tent of radius one pixel about each pixel's top-left corner."""
    h, w = x.shape[:2]
    jj, ii = np.divmod(np.arange(w * h), w)
    sums, weights = np.zeros((h + 1, w + 1, 3)), np.zeros((h + 1, w + 1))
    for L, u, v in unsought._film_samples(w, h, spp, seed, partial(unsought._independent, pixels=w * h)):
        for dy, wy in ((0, 1.0 - v), (1, v)):
            for dx, wx in ((0, 1.0 - u), (1, u)):
                at = (np.repeat(jj + dy, u.shape[1]), np.repeat(ii + dx, u.shape[1]))
                np.add.at(sums, at, L.reshape(-1, 3) * (wy * wx).reshape(-1, 1))
                np.add.at(weights, at, (wy * wx).reshape(-1))
    return sums[:h, :w] / weights[:h, :w, None]


# --------------------------------------------------------------------------
# Renderer mistakes realised on rays, sample by sample, or with Mitsuba renders combined
# --------------------------------------------------------------------------


def _camera_samples(x, *, spp: int, seed: int, sample):
    """Each pixel the mean of ``sample(o, d, chunk seed)`` -> (N, 3) on the pinhole's rays, jittered over the pixels
    (N = W H n a chunk, a pixel's n samples together, pixels in row order)."""
    h, w = x.shape[:2]
    total = np.zeros((h * w, 3))
    for cseed, n, fx, fy in unsaid._lanes(w, h, spp, seed):
        o, d = (np.array(a, np.float64) for a in unsaid._pinhole(fx, fy))
        total += sample(o, d, cseed).reshape(h * w, n, 3).sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _diffuse_first(mscene, o, d) -> np.ndarray:
    """Whether each ray's first hit is a Lambertian's (not the mirror's or the light's black surface)."""
    return unsaid._first_albedo(mscene, o, d).max(axis=1) > 0.0


def _view_cosine_sample(o, d, seed, *, full, seen):
    """A sample whose first diffuse hit's light (the sample less the emission the ray sees, same seed) is times the
    cosine between its normal and the way back to the eye."""
    L, le = unsaid._sampled(full, o, d, seed), unsaid._sampled(seen, o, d, seed)
    cos = np.ones(len(o))
    sel = _diffuse_first(full, o, d)
    if sel.any():
        cos[sel] = -np.einsum("ij,ij->i", unforeseen._first_normal(full, o[sel], d[sel]), d[sel])
    return le + cos[:, None] * (L - le)


def _view_cosine(x, *, spp: int, seed: int):
    """Every Lambertian's BRDF ``albedo / pi * dot(n, wo)`` (Lambert's cosine taken for the way to the viewer too),
    where a camera ray meets a Lambertian first: the light it reflects there times that cosine (Mitsuba's path after
    it; the mirror and the light, Mitsuba's)."""
    return _camera_samples(x, spp=spp, seed=seed, sample=partial(
        _view_cosine_sample, full=unsaid._loaded(_DEPTH), seen=unsaid._loaded(1)))


def _horizontal_unbounced_sample(o, d, seed, *, full, direct):
    """A sample whose first hit is on the floor or the ceiling (a normal along z) cut after its light sample (the
    same seed's max-depth-2 sample): no bounce from there."""
    L = unsaid._sampled(full, o, d, seed)
    sel = np.flatnonzero(_diffuse_first(full, o, d))
    flat = sel[np.abs(unforeseen._first_normal(full, o[sel], d[sel])[:, 2]) > 0.999] if len(sel) else sel
    if len(flat):
        L[flat] = unsaid._sampled(direct, o[flat], d[flat], seed)
    return L


def _frame_nan_horizontal(x, *, spp: int, seed: int):
    """The bounce's tangent frame ``t = normalize(cross(n, (0, 0, 1)))``: zero, so NaN, where the normal is along z
    (the floor, the ceiling), whose bounce rays then meet nothing and end the path, at the first surface a camera
    ray meets (Mitsuba's path elsewhere and after it)."""
    return _camera_samples(x, spp=spp, seed=seed, sample=partial(
        _horizontal_unbounced_sample, full=unsaid._loaded(_DEPTH), direct=unsaid._loaded(2)))


def _albedo_scene(albedo: tuple[float, ...], max_depth: int = _DEPTH):
    """The scene loaded in Mitsuba with every Lambertian of albedo ``albedo`` (the mirror and the light as they
    are)."""
    import mitsuba as mi

    from mcrt.mitsuba_scene import scene_dict

    s = unbidden._albedos_mapped(_scene(), lambda _: albedo)
    return mi.load_dict(scene_dict(s, "near", 4, 4, max_depth, spp=1))


def _first_albedo_kept_sample(o, d, seed, *, full, scenes):
    """A sample whose path meets a Lambertian first, traced in the scene where every Lambertian has that first one's
    albedo (the albedo read once, at the first hit, and used at every bounce after it)."""
    L = unsaid._sampled(full, o, d, seed)
    rho = np.round(unsaid._first_albedo(full, o, d), 4)
    for a in np.unique(rho[rho.max(axis=1) > 0.0], axis=0):
        sel = np.all(rho == a, axis=1)
        key = tuple(float(c) for c in a)
        if key not in scenes:
            scenes[key] = _albedo_scene(key)
        L[sel] = unsaid._sampled(scenes[key], o[sel], d[sel], seed)
    return L


def _first_albedo_kept(x, *, spp: int, seed: int):
    """The path's albedo read once, at the first hit, and used at every bounce (``albedo = hit.material.albedo``
    before the bounce loop, the loop's hits never read it again), where a camera ray meets a Lambertian first:
    Mitsuba's path in the scene with every Lambertian of that albedo (the mirror and the light, Mitsuba's)."""
    return _camera_samples(x, spp=spp, seed=seed, sample=partial(
        _first_albedo_kept_sample, full=unsaid._loaded(_DEPTH), scenes={}))


def _light_points(rng, n: int) -> np.ndarray:
    """(n, 3) points drawn uniformly on the light's square."""
    lt = _scene().light
    u, v = rng.random((2, n))
    return np.stack([lt.center[0] + (u - 0.5) * lt.size[0], lt.center[1] + (v - 0.5) * lt.size[1],
                     np.full(n, lt.center[2])], axis=1)


def _geometry(p, n, q) -> np.ndarray:
    """The light sample's geometry term max(0, n . wi) cos_light / |q - p|^2 (the light faces down: cos_light is
    wi's z)."""
    wi = unsaid._unit(q - p)
    return np.maximum(np.einsum("ij,ij->i", n, wi), 0.0) * np.maximum(wi[:, 2], 0.0) / np.sum((q - p) ** 2, axis=1)


def _cos_light_from_surface(p, n, q) -> np.ndarray:
    """The geometry term with the cosine at the light taken with the surface's normal, ``abs(dot(n, wi))`` for
    ``dot(light.normal, -wi)`` (one name for two normals): cos_surface^2 / d^2."""
    wi = unsaid._unit(q - p)
    cos = np.einsum("ij,ij->i", n, wi)
    return np.maximum(cos, 0.0) * np.abs(cos) / np.sum((q - p) ** 2, axis=1)


def _unblocked(mscene, p, q) -> np.ndarray:
    """Whether nothing lies between each p and q (the right shadow ray, stopping short of the light's point)."""
    return unheralded._visible_within(mscene, p, unsaid._unit(q - p), np.linalg.norm(q - p, axis=1), reach=np.inf)


def _light_sampled(mscene, rng, p, n, rho, mitsuba, *, geometry=_geometry):
    """A first vertex's light sample by hand: a point q uniform on the light's square, rho Le G A / pi where nothing
    lies between, G = ``geometry(p, n, q)`` (:func:`_geometry`: the right one)."""
    lt = _scene().light
    q = _light_points(rng, len(p))
    g = np.where(_unblocked(mscene, p, q), geometry(p, n, q), 0.0)
    return rho * (g * lt.area / math.pi)[:, None] * np.asarray(lt.radiance, np.float64)


def _light_until_blocked(mscene, rng, p, n, rho, mitsuba, *, rays: int = 30):
    """``rays`` light samples at a first vertex in a loop left (``break`` for ``continue``) at the first whose shadow
    ray is blocked, the sum of those before it divided by ``rays``."""
    lt = _scene().light
    total, going = np.zeros(len(p)), np.ones(len(p), bool)
    for _ in range(rays):
        q = _light_points(rng, len(p))
        going &= _unblocked(mscene, p, q)
        total += np.where(going, _geometry(p, n, q), 0.0)
    return rho * (total / rays * lt.area / math.pi)[:, None] * np.asarray(lt.radiance, np.float64)


def _without_albedo(mscene, rng, p, n, rho, mitsuba):
    """The first vertex's light sample with its BRDF 1 / pi (the albedo left out): Mitsuba's over the albedo."""
    return mitsuba / np.where(rho > 0.0, rho, 1.0)


def _path_break_sample(o, d, seed, *, full, direct, rng):
    """A sample whose path ends at its first diffuse vertex where that vertex's shadow ray (to a point drawn on the
    light, the surface facing it) is blocked: the same seed's max-depth-2 sample there (the light seen and the
    vertex's own light sample), Mitsuba's path on from it elsewhere."""
    L = unsaid._sampled(full, o, d, seed)
    t, valid = unguessed._first_hit(full, o, d)
    sel = np.flatnonzero(valid & _diffuse_first(full, o, d))
    if len(sel):
        n = unforeseen._first_normal(full, o[sel], d[sel])
        p = o[sel] + t[sel, None] * d[sel] + 1e-4 * n
        q = _light_points(rng, len(sel))
        facing = np.einsum("ij,ij->i", n, q - p) > 0.0
        stop = sel[facing & ~_unblocked(full, p, q)]
        if len(stop):
            L[stop] = unsaid._sampled(direct, o[stop], d[stop], seed)
    return L


def _path_break_on_shadow(x, *, spp: int, seed: int):
    """``break`` out of the bounce loop when a vertex's shadow ray is blocked (an early exit meant for the shadow
    test, placed in the path loop), at the first surface a camera ray meets (Mitsuba's path after it): no light
    bounced from a point whose light sample was blocked."""
    rng = np.random.default_rng(seed + 11)
    return _camera_samples(x, spp=spp, seed=seed, sample=partial(
        _path_break_sample, full=unsaid._loaded(_DEPTH), direct=unsaid._loaded(2), rng=rng))


def _light_seen_twice(x, *, spp: int, seed: int):
    """The emission a camera ray meets counted twice (``if depth == 0: L += Le`` and the emitter branch's ``L +=
    beta * Le`` both): a render plus its max-depth-1 render, same seed (the same camera rays)."""
    h, w = x.shape[:2]
    return _render(w, h, spp, seed) + _render(w, h, spp, seed, max_depth=1)


def _roulette_one_number(x, *, spp: int, seed: int, survival: float = 0.5, first: int = 3):
    """Russian roulette from vertex ``first`` with survival ``survival``, its random number drawn once per path
    (before the bounce loop) and tested after each vertex's light sample, the survivors divided by ``survival`` each
    time: a path that passes the first test passes them all, so the light sampled after m tests weighs survival^(1
    - m) for 1. Renders at max depth first + 1 to 8 (same seed, Mitsuba's own roulette off): the paths of k segments
    (k > first + 1) have passed k - first - 1 tests."""
    renders = {k: fresh._mitsuba(x.shape, spp, seed, max_depth=k, rr_depth=100) for k in range(first + 1, _DEPTH + 1)}
    out = renders[first + 1]
    for k in range(first + 2, _DEPTH + 1):
        out = out + survival ** (first + 2 - k) * (renders[k] - renders[k - 1])
    return out


def _passes_moving_average(x, *, passes: int, spp: int, seed: int, alpha: float = 0.1):
    """``passes`` Mitsuba renders of ``spp`` (a seed each) blended as a viewer accumulates frames, ``img = (1 - alpha)
    * img + alpha * frame`` from the first (an exponential moving average)."""
    h, w = x.shape[:2]
    img = _render(w, h, spp, seed)
    for k in range(1, passes):
        img = (1.0 - alpha) * img + alpha * _render(w, h, spp, seed + k)
    return img


def _passes_inverse_variance(x, *, passes: int, spp: int, seed: int):
    """``spp`` samples a pixel in ``passes`` passes, combined with each pass's weight the inverse of its own mean's
    variance, ``w = 1 / (var(lum) / n + 1e-8)`` (n a pass's samples, lum their Rec. 709 luminance)."""
    h, w = x.shape[:2]
    L = unbidden._all_samples(w, h, spp, seed).reshape(h * w, passes, spp // passes, 3)
    weight = 1.0 / ((L @ programs._LUMA).var(axis=2, ddof=1) / (spp // passes) + 1e-8)
    out = np.einsum("ip,ipc->ic", weight, L.mean(axis=2)) / weight.sum(axis=1)[:, None]
    return out.reshape(h, w, 3)


def _log_mean(x, *, spp: int, seed: int, eps: float = 1e-3):
    """Each pixel's samples averaged in log space, ``np.exp(np.mean(np.log(samples + 1e-3), axis=0)) - 1e-3``,
    channel by channel (a geometric mean, against fireflies)."""
    h, w = x.shape[:2]
    L = unbidden._all_samples(w, h, spp, seed)
    return (np.exp(np.log(L + eps).mean(axis=1)) - eps).reshape(h, w, 3)


def _normal_view(x, *, spp: int, seed: int):
    """The film's normal AOV in its debug view, (n + 1) / 2 (Mitsuba's ``aov`` integrator, ``nn:sh_normal``, its
    pixels the mean of their samples' shading normals)."""
    import mitsuba as mi

    from mcrt.mitsuba_scene import scene_dict

    h, w = x.shape[:2]
    d = scene_dict(_scene(), "near", w, h, _DEPTH, spp=spp)
    d["integrator"] = {"type": "aov", "aovs": "nn:sh_normal"}
    return (np.asarray(mi.render(mi.load_dict(d), spp=spp, seed=seed), np.float64) + 1.0) / 2.0


# --------------------------------------------------------------------------
# Correct renders made in other ways
# --------------------------------------------------------------------------


def _hammersley_shifted(rng, n: int, *, w: int, pixels: int):
    """Sub-pixel offsets of the Hammersley points (i / n, the radical inverse of i in base 2), digitally shifted at
    random in each pixel (each coordinate's 32 bits XORed with a random word of the pixel's): every offset uniform on
    the pixel."""
    i = np.arange(n)
    bits = np.floor(np.stack([i / n, unprompted._radical_inverse(i, 2)]) * 2.0 ** 32).astype(np.uint64)
    shift = rng.integers(0, 2 ** 32, (2, pixels, 1), dtype=np.uint64)
    u, v = ((bits[:, None, :] ^ shift) + 0.5) / 2.0 ** 32
    return u, v


def _wide_centre(x, *, spp: int, seed: int):
    """Mitsuba at twice the resolution with the image plane twice as wide (a field of view of 2 atan(2 tan(fov / 2))),
    its centre kept: the assignment's view, pixel for pixel."""
    h, w = x.shape[:2]
    half = math.tan(math.radians(_scene().cameras["near"].fov_x_deg) / 2.0)
    wide = _render(2 * w, 2 * h, spp, seed, sensor={"fov": math.degrees(2.0 * math.atan(2.0 * half))})
    return wide[h // 2:h // 2 + h, w // 2:w // 2 + w]


#: The samplers of :func:`_samplers_averaged` (64 spp suits each).
_SAMPLERS = ("independent", "stratified", "multijitter", "ldsampler")


def _samplers_averaged(x, *, spp: int, seed: int):
    """Four Mitsuba renders of ``spp`` with the independent, stratified, multi-jittered and low-discrepancy samplers
    (a seed each), averaged."""
    from mcrt.mitsuba_scene import render_with_variance, scene_dict

    h, w = x.shape[:2]
    out = []
    for k, sampler in enumerate(_SAMPLERS):
        d = scene_dict(_scene(), "near", w, h, _DEPTH, spp=spp)
        d["sensor"] = dict(d["sensor"], sampler={"type": sampler, "sample_count": spp})
        out.append(np.asarray(render_with_variance(d, spp=spp, seed=seed + k, spp_per_pass=spp).mean, np.float64))
    return np.mean(out, axis=0)


def _mcrt_half_turn(x, *, spp: int, seed: int):
    """mcrt with the camera's up vector negated (rolled half a turn), the image turned back (``np.rot90(img, 2)``)."""
    return np.rot90(unsaid._mcrt_scene(x, spp=spp, seed=seed, scene_edit=fresh._up_negated), 2)


def _adaptive_filtered(codes: np.ndarray) -> bytes:
    """The PNG scanlines of (H, W, 3) 8-bit codes, each row with the filter (None, Sub, Up, Average or Paeth) whose
    bytes, read as signed, have the least sum of absolute values (libpng's heuristic)."""
    h = codes.shape[0]
    none = b"".join(b"\0" + r.tobytes() for r in codes.reshape(h, -1))
    streams = (none, unguessed._sub_filtered(codes), unforeseen._up_filtered(codes),
               unbidden._average_filtered(codes), unprompted._paeth_filtered(codes))
    rows = np.stack([np.frombuffer(s, np.uint8).reshape(h, -1) for s in streams])
    cost = np.abs(rows[:, :, 1:].view(np.int8).astype(np.int64)).sum(axis=2)
    return rows[cost.argmin(axis=0), np.arange(h)].tobytes()


_write_png_adaptive = partial(_write_png_scanlines, filtered=_adaptive_filtered)


def _lut12_codes(image: np.ndarray) -> np.ndarray:
    """8-bit sRGB codes through a table of 4096 entries (a game engine's encoder): the linear value rounded to 12 bits,
    its code ``lut[k] = round(255 srgb(k / 4095))``."""
    lut = np.floor(srgb_oetf(np.arange(4096) / 4095.0) * 255.0 + 0.5).astype(np.uint8)
    return lut[np.floor(np.clip(np.nan_to_num(image), 0.0, 1.0) * 4095.0 + 0.5).astype(np.int64)]


def _write_png_lut12(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_lut12_codes(image), folder)


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_oidn_colour_only", "pp_teal_orange_split_tone", "pp_unsharp_without_image",
                        "pp_neighbourhood_clamp"),
    "file": ("file_png_cv2_float_unscaled", "file_png_sub_filter_one_byte", "file_hdr_mantissa_255",
             "file_png_signed_byte_codes"),
    "materials": ("mirror_reflect_placeholder", "lambert_view_cosine", "light_sample_without_albedo"),
    "geometry": ("first_hit_in_list", "room_reoriented_outwards", "tetra_fanned_as_polygon"),
    "camera": ("yaw_atan2_swapped", "direction_z_solved", "splat_about_corner"),
    "light": ("cos_light_from_surface_normal", "light_seen_counted_twice", "shadow_rays_break_at_blocked"),
    "integrator": ("roulette_one_number", "path_break_on_blocked_shadow", "frame_nan_on_floor_ceiling",
                   "albedo_of_first_hit_kept"),
    "samples": ("passes_moving_average", "passes_inverse_variance", "samples_log_mean", "normal_aov_written"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_oidn_colour_only", "blur", **_posted("oidn", _oidn),
             truth="Intel Open Image Denoise run on the render, pyoidn.denoise(img, hdr=True), its RT filter on the "
             "colour alone (no albedo or normal guides), as EXR: the noise gone, the detail it hid smoothed with it, "
             "the shadows' edges and the mirror's room soft"),
        Spec("pp_teal_orange_split_tone", "colour_grade", held_out=True, **_posted("teal_orange", _teal_orange),
             truth="a 'teal and orange' split toning for the look, img * ((1 - t) (0.9, 1.0, 1.1) + t (1.1, 1.0, "
             "0.9)) with t the luminance clipped to [0, 1], as EXR: the dark parts bluer, the bright parts and the "
             "light warmer (22, 20, 18 for 20), the mid-greys kept"),
        Spec("pp_unsharp_without_image", "sharpen", True, **_posted("unsharp_minus_blur", _unsharp_without_image),
             truth="an unsharp mask misremembered, img - 0.5 * gaussian_filter(img, (1, 1, 0)) for img + 0.5 * (img "
             "- blurred), negatives clipped to 0, as EXR: every flat area half as bright, the edges sharpened, dark "
             "rims round the light"),
        Spec("pp_neighbourhood_clamp", "blur", held_out=True, **_posted("neighbourhood_clamp", _neighbour_clamped),
             truth="each pixel clamped channel by channel to the range of its 8 neighbours (a real-time renderer's "
             "neighbourhood clamp, against fireflies): np.clip(img, minimum_filter(img, footprint=ring), "
             "maximum_filter(img, footprint=ring)), as EXR: the noise's lone peaks and dips cut to their "
             "neighbours', the edges and the rest right"),
        # Writing the file
        Spec("file_png_cv2_float_unscaled", "code_range", True, writer=_write_png_cv2_float, file="png-cv2-float",
             truth="cv2.imwrite of the sRGB values in [0, 1] as float32 (the * 255 left out, the channels turned to "
             "BGR as OpenCV wants): OpenCV rounds a float image's values to 8-bit codes unscaled, every code 0 or 1 "
             "(1 over the sRGB value 0.5, linear 0.214), the 8-bit PNG nearly black"),
        Spec("file_png_sub_filter_one_byte", "file_format", True, held_out=True, writer=_write_png_sub_one_byte,
             file="png-sub-one-byte",
             truth="an 8-bit sRGB PNG written by hand with the Sub filter on every row, each byte less the byte "
             "before it (row[k] - row[k - 1]) where PNG's Sub subtracts the byte one pixel before (3 bytes for RGB): "
             "decoded, each sample the running sum of differences of its channel's neighbours, the colours and "
             "brightness drifting along every row"),
        Spec("file_hdr_mantissa_255", "light_radiance", writer=_write_hdr_mantissa_255, file="hdr-mantissa-255",
             truth="a Radiance HDR written by hand with Ward's RGBE formula's 256 typed 255 (the 8-bit habit): "
             "mantissas v * f * 255 / max for v * f * 256 / max, every value read back about 255 / 256 of itself "
             "(0.4 % dark), the light 19.875 for 20"),
        Spec("file_png_signed_byte_codes", "code_overflow", True, held_out=True, writer=_write_png_signed_bytes,
             file="png-int8",
             truth="8-bit sRGB codes cast with .astype(np.int8) for np.uint8 (a signed byte: 128 to 255 wrap to "
             "-128 to -1), the negatives then clipped to 0 as a guard: every code of 128 or more (linear 0.214 and "
             "over) written 0, the light, its reflection and the brightest noise black, the rest right"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    c = _crc
    return (
        # Materials
        Spec("mirror_reflect_placeholder", "material", True, **_posted("reflect_placeholder", partial(
            unsaid._traced, spp=_S, seed=c("mirror_reflect_placeholder"), after=_retroreflected)),
             truth="the mirror's reflect() left as its placeholder return -d, for the camera's rays (Mitsuba's path "
             "on from the sphere): every ray that meets the sphere sent back the way it came, past the eye, the "
             "sphere filled with the patch of red wall AB behind the camera"),
        Spec("lambert_view_cosine", "material", True, held_out=True, **_posted("view_cosine", partial(
            _view_cosine, spp=_S, seed=c("lambert_view_cosine"))),
             truth="every Lambertian's BRDF albedo / pi * dot(n, wo), Lambert's cosine taken for the way to the eye "
             "too, where a camera ray meets a Lambertian first (Mitsuba's path after it): each surface darker the "
             "more obliquely it is seen, the floor about half as bright, the ceiling and the side walls a quarter "
             "darker, the far walls nearly right"),
        Spec("light_sample_without_albedo", "albedo", True, **_posted("light_sample_white", partial(
            unheralded._first_vertex, spp=_S, seed=c("light_sample_without_albedo"), direct=_without_albedo)),
             truth="the Lambertian's BRDF in the light sample written 1 / pi (the albedo left out; the bounce's "
             "weight, the albedo, right), at the first surface a camera ray meets (Mitsuba's path after it): the "
             "direct light white on every surface, the coloured walls pale and the lit surfaces half again as bright"),
        # Geometry
        Spec("first_hit_in_list", "object_missing", True, mitsuba_edit=_objects_never_found,
             truth="the intersection loop returning the first shape of its list that a ray meets (for shape in "
             "[light] + room + objects: if shape.hit(ray): return), not the nearest: every ray meets the light or "
             "one of the room's faces before the objects in the list, the tetrahedron and the sphere never found, "
             "by camera rays, bounces or shadow rays: both gone with their shadows"),
        Spec("room_reoriented_outwards", "normals", True, held_out=True, mitsuba_edit=_room_outwards,
             truth="the room's corners 'reoriented' by a clockwise test of the wrong sign (if shoelace_area(corners) "
             "> 0: corners.reverse(), for a counter-clockwise room), every wall, the floor and the ceiling wound "
             "outwards, shaded one-sided (max(0, n . l)): the whole room black and reflecting nothing, the "
             "tetrahedron lit by the light alone, the light and its reflection right"),
        Spec("tetra_fanned_as_polygon", "mesh_face", True, mitsuba_edit=_tetra_fanned,
             truth="the tetrahedron's four vertices handed to the room's polygon helper, which fans them: triangles "
             "(v0, v1, v2) and (v0, v2, v3), its base and one side, two of its four faces: the side the camera sees "
             "towards the room's middle and the far side missing, the floor and the kept faces' insides seen "
             "through them"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera
        Spec("yaw_atan2_swapped", "camera_rotation", True, edit=_yaw_atan2_swapped,
             truth="the camera's forward vector rebuilt from its yaw and pitch (a first-person camera's code), the yaw "
             "atan2(f.x, f.y) for atan2(f.y, f.x) (the arguments swapped): 90 degrees for 0, the camera turned to "
             "look along +y, at the green wall EF and the cyan wall FA, the light and the objects out of view"),
        Spec("direction_z_solved", "camera_model", True, held_out=True, **_posted("z_solved", partial(
            unsaid._traced, spp=_S, seed=c("direction_z_solved"), camera=_direction_z_solved)),
             truth="the camera ray's direction (s, t, sqrt(max(0, 1 - s^2 - t^2))) in the camera's frame, its forward "
             "component solved for unit length (the image-plane point (s, t, 1) never normalised): an orthographic "
             "fisheye, 90 degrees off the axis at the image's edges: the assignment's view shrunk into the middle 71 "
             "% of the width, the room's sides round it, the corners looking sideways"),
        Spec("splat_about_corner", "pixel_footprint", **_posted("splat_about_corner", partial(
            _splat_about_corner, spp=_S, seed=c("splat_about_corner"))),
             truth="each sample splatted bilinearly to the four pixels about its film position with i = floor(x) "
             "and weights 1 - (x - i), x - i (the pixel's corner taken for its centre, no - 0.5), each pixel's sum "
             "divided by its weights: a tent of radius one pixel about each pixel's top-left corner, the image "
             "blurred and half a pixel off to the lower right"),
        # Light model
        Spec("cos_light_from_surface_normal", "light_pdf", True, **_posted("cos_light_surface", partial(
            unheralded._first_vertex, spp=_S, seed=c("cos_light_from_surface_normal"),
            direct=partial(_light_sampled, geometry=_cos_light_from_surface))),
             truth="the cosine at the light taken with the surface's normal, abs(dot(n, wi)) for dot(light.normal, "
             "-wi) (one variable for two normals): cos_surface^2 / d^2 in the light sample, at the first surface a "
             "camera ray meets (Mitsuba's path after it): the floor right, the walls brighter the nearer the light's "
             "height, the light on surfaces a quarter too bright, the light seen right"),
        Spec("light_seen_counted_twice", "light_seen", held_out=True, **_posted("seen_twice", partial(
            _light_seen_twice, spp=_S, seed=c("light_seen_counted_twice"))),
             truth="the emission a camera ray meets counted twice (the first hit's if depth == 0: L += Le and the "
             "emitter branch's L += beta * Le both run): the light's own pixels 40 for 20, its reflection in the "
             "mirror and its light on surfaces right"),
        Spec("shadow_rays_break_at_blocked", "light_pdf", spp=64, **_posted("shadow_loop_break", partial(
            unheralded._first_vertex, spp=64, seed=c("shadow_rays_break_at_blocked"), direct=_light_until_blocked)),
             truth="30 shadow rays a vertex (the course report's), their loop left (break for continue) at the first "
             "blocked one, the sum of those before it divided by 30, at the first surface a camera ray meets "
             "(Mitsuba's path after it), 64 spp: the penumbrae of the sphere's and the tetrahedron's shadows nearly "
             "as dark as their umbrae, the shadows a little larger and harder, the rest right"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples, passes and buffers."""
    c = _crc
    return (
        # Integrator
        Spec("roulette_one_number", "roulette", True, **_posted("roulette_one_number", partial(
            _roulette_one_number, spp=_S, seed=c("roulette_one_number"))),
             truth="Russian roulette from the 3rd vertex with survival 0.5, its random number drawn once per path "
             "before the bounce loop and tested at every vertex, the survivors divided by 0.5 each time: a path "
             "that passes the first test passes them all, the light of paths of 6, 7 and 8 segments counted 2, 4 "
             "and 8 times: the lit surfaces about a sixth too bright, the light seen right"),
        Spec("path_break_on_blocked_shadow", "indirect_scale", True, held_out=True, **_posted(
            "path_break_on_shadow", partial(_path_break_on_shadow, spp=_S, seed=c("path_break_on_blocked_shadow"))),
             truth="break out of the bounce loop when a vertex's shadow ray is blocked (an early exit meant for the "
             "shadow test, placed in the path loop), at the first surface a camera ray meets (Mitsuba's path after "
             "it): no light bounced from where the light sample was blocked, the shadows of the sphere and the "
             "tetrahedron nearly black, the lit surfaces right"),
        Spec("frame_nan_on_floor_ceiling", "indirect_scale", True, **_posted("frame_nan_horizontal", partial(
            _frame_nan_horizontal, spp=_S, seed=c("frame_nan_on_floor_ceiling"))),
             truth="the bounce's tangent frame normalize(cross(n, (0, 0, 1))): zero, so NaN, for the floor's and the "
             "ceiling's normals, their bounce rays meeting nothing and ending the path, where a camera ray meets "
             "them first (Mitsuba's path elsewhere and after): the floor without its indirect light, the ceiling "
             "(lit by nothing else) black, the walls right"),
        Spec("albedo_of_first_hit_kept", "albedo", True, held_out=True, **_posted("first_albedo_kept", partial(
            _first_albedo_kept, spp=_S, seed=c("albedo_of_first_hit_kept"))),
             truth="the path's albedo read once, at the first hit (albedo = hit.material.albedo before the bounce "
             "loop), and used at every bounce, where a camera ray meets a Lambertian first (Mitsuba's path in the "
             "scene with every Lambertian of that albedo): each surface's indirect light in its own colour again and "
             "again, the walls deeper in colour, the ceiling about twice as bright, the light on surfaces half "
             "again as bright"),
        # Samples, passes and buffers
        Spec("passes_moving_average", "spp_claim", **_posted("moving_average", partial(
            _passes_moving_average, passes=16, spp=16, seed=c("passes_moving_average"))),
             truth="16 passes of 16 spp blended as a real-time viewer accumulates frames, img = 0.9 img + 0.1 pass, "
             "from the first pass (an exponential moving average): unbiased, but the last passes weigh most, the "
             "noise of about 170 spp (11 passes' worth) for the 256 declared"),
        Spec("passes_inverse_variance", "biased_estimator", held_out=True, **_posted("inverse_variance", partial(
            _passes_inverse_variance, passes=8, spp=_S, seed=c("passes_inverse_variance"))),
             truth="8 passes of 32 spp combined with inverse-variance weights, each pass's weight 1 / (the variance "
             "of its pixel's luminance samples / 32 + 1e-8), from its own samples: a pass that caught a bright path "
             "weighs little, the indirect light's rare bright samples discounted: the walls and the floor a few per "
             "cent too dark, the ceiling (lit by bounces alone) about a tenth"),
        Spec("samples_log_mean", "biased_estimator", True, **_posted("log_mean", partial(
            _log_mean, spp=_S, seed=c("samples_log_mean"))),
             truth="each pixel's samples averaged in log space, np.exp(np.mean(np.log(samples + 1e-3), axis=0)) - "
             "1e-3 (a geometric mean, against fireflies): every pixel whose samples vary darker, the walls and the "
             "floor about a tenth too dark, the ceiling (lit by bounces alone) half as bright, the light's edges "
             "much darker, its middle right"),
        Spec("normal_aov_written", "wrong_buffer", True, held_out=True, **_posted("normal_view", partial(
            _normal_view, spp=_S, seed=c("normal_aov_written"))),
             truth="the film's normal AOV in its debug view, (n + 1) / 2, written for the beauty (a debug switch "
             "left on): each surface a flat colour of its facing (the floor (0.5, 0.5, 1), the ceiling (0.5, 0.5, "
             "0), the walls by their direction), the sphere a normal map, no light anywhere"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_hammersley_digital_shift", None, spp=192, **_posted("hammersley_shifted", partial(
            unforeseen._mean_through, spp=192, seed=c("ok_hammersley_digital_shift"), jitter=_hammersley_shifted)),
             truth="Mitsuba path 192 spp, sub-pixel offsets from the Hammersley points (i / n, the base-2 radical "
             "inverse of i) digitally shifted at random in each pixel (their bits XORed with a random word), EXR"),
        Spec("ok_wide_render_centre", None, held_out=True, spp=140, **_posted("wide_centre", partial(
            _wide_centre, spp=140, seed=c("ok_wide_render_centre"))),
             truth="Mitsuba path 140 spp at 128 x 128 with the field of view 2 atan(2) (the image plane twice as "
             "wide), its centre 64 x 64 kept: the assignment's view pixel for pixel, EXR"),
        Spec("ok_png_adaptive_filters", None, spp=212, writer=_write_png_adaptive, file="png-adaptive",
             truth="Mitsuba path 212 spp, an 8-bit sRGB PNG written by hand, each row's filter (None, Sub, Up, "
             "Average or Paeth) the one whose bytes' signed sum of magnitudes is least (libpng's heuristic)"),
        Spec("ok_thinlens_pinhole", None, held_out=True, spp=176, mitsuba_edit=_thinlens,
             truth="Mitsuba path 176 spp with the thinlens sensor, an aperture of radius 1e-5 focused at 10 (a "
             "pinhole in effect), EXR"),
        Spec("ok_four_samplers_averaged", None, **_posted("four_samplers", partial(
            _samplers_averaged, spp=64, seed=c("ok_four_samplers_averaged"))),
             truth="four Mitsuba path renders of 64 spp, with the independent, stratified, multi-jittered and "
             "low-discrepancy samplers (a seed each), averaged: 256 spp, EXR"),
        Spec("ok_mcrt_half_turn", None, held_out=True, spp=96, renderer="mcrt", **_posted("mcrt_half_turn", partial(
            _mcrt_half_turn, spp=96, seed=c("ok_mcrt_half_turn"))),
             truth="mcrt 96 spp with the camera's up vector negated (rolled half a turn), the image turned back with "
             "np.rot90(img, 2), EXR"),
        Spec("ok_delaunay_floor_ceiling", None, spp=228, mitsuba_edit=_floor_ceiling_delaunay,
             truth="Mitsuba path 228 spp with the floor and the ceiling triangulated by scipy.spatial.Delaunay of the "
             "room's six corners, EXR"),
        Spec("ok_png_12bit_table", None, held_out=True, spp=148, writer=_write_png_lut12, file="png-lut12",
             truth="Mitsuba path 148 spp, an 8-bit sRGB PNG encoded through a table of 4096 entries (the linear "
             "value rounded to 12 bits, then looked up), as game engines encode"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "blur": "a filter after rendering (a denoiser on the colour alone, a neighbourhood clamp)",
    "colour_grade": "the colours graded after rendering (a split toning)",
    "sharpen": "a sharpening filter after rendering (an unsharp mask without the image)",
    "code_range": "codes of another range in the file (values in [0, 1] written as 8-bit codes unscaled)",
    "file_format": "the file's bytes and its header disagree (a PNG's Sub filter one byte back, not one pixel)",
    "light_radiance": "the light's radiance or a constant factor (RGBE mantissas scaled by 255 for 256)",
    "code_overflow": "codes past a signed byte's top wrapped round (every code of 128 or more black)",
    "material": "an object rendered with another material (the mirror sending rays back, the Lambertians shaded by "
                "the view's cosine)",
    "albedo": "a surface's colour (the light sample's BRDF without the albedo, the first hit's albedo at every "
              "bounce)",
    "object_missing": "objects missing (the nearest hit never looked for: the tetrahedron and the sphere never found)",
    "normals": "surface normals facing the wrong way (the whole room's, shaded one-sided)",
    "mesh_face": "faces of a mesh missing (the tetrahedron fanned as a polygon, two of its faces)",
    "camera_rotation": "the camera's rotation (a yaw of 90 degrees, atan2's arguments swapped)",
    "camera_model": "another camera model (an orthographic fisheye)",
    "pixel_footprint": "each pixel's samples not spread over its square (splatted about its corner)",
    "light_pdf": "the light sampled wrongly (the cosine at the light, shadow rays stopped at the first blocked one): "
                 "the light seen right, its light on surfaces not",
    "light_seen": "the light's own pixels (where the camera sees it) at the wrong brightness (counted twice), its "
                  "light on surfaces right",
    "roulette": "Russian roulette wrong (one random number for every test of a path)",
    "indirect_scale": "the indirect light wrong (the paths ended at a blocked light sample, no bounce off the floor "
                      "and the ceiling), the direct light right",
    "spp_claim": "fewer samples per pixel than declared (passes blended by a moving average)",
    "biased_estimator": "a biased estimate of each pixel's mean (passes weighted by their own variance, a mean in "
                        "log space)",
    "wrong_buffer": "another buffer written in place of the mean (the normal AOV's debug view)",
}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = blind.class_causes(MISTAKES, _EARLIER, NEW_CAUSES, _REWORDED)


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
