r"""A nineteenth class of hand-ins: mistakes of students' tracers, scene input and output no class tried, blind.

How it was written: from what goes wrong in students' programs (the filters
and tricks run after rendering, the curves and writers that save the image,
the colours as a loader builds them, the objects' vertices and winding, the
camera's basis, field of view and sub-pixel offsets, the light's area and
radiance and what the camera sees of it, the integrator's shadow rays, the
order of its steps and its bounce's weight, the buffers and loops that add up
the samples and the passes), not from the grader. Its author read the other classes'
specs and cause words, the catalogue (:mod:`mcrt.mutants`), the scene files
and design notes, mcrt's scene, camera and image code,
:data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to
stay clear of their mistakes; never the grader's rules (what decides a
cause) nor its reports, and graded none of it, not one case. Each cause and
``major`` flag was set from the mistake alone; every mistake is worded by a
cause the other classes already have (:data:`NEW_CAUSES` is empty), so
``SAME_MISTAKE`` needed no new entry. The mistakes differ from those of the
eighteen other classes (:mod:`~mcrt.grade.accuracy.cases`,
:mod:`~mcrt.grade.accuracy.outside` and the modules of :data:`_EARLIER`, from
:mod:`~mcrt.grade.accuracy.programs` to :mod:`~mcrt.grade.accuracy.unbidden`)
and from the catalogue's bugs:

* **post-processing**: scikit-image's Butterworth low-pass
  (``filters.butterworth``) against the noise; ``exposure.adjust_gamma`` of
  0.8 to brighten the dark corners; a crosshair through the image's centre
  left from checking the camera's aim; the image halved with
  ``transform.rescale`` and scaled back with ``resize`` to smooth it;
* **writing the file**: a 16-bit PNG encoded with the PQ curve of HDR video
  (SMPTE ST 2084); a binary PPM built as a ``str`` of ``chr`` codes and
  written as text (UTF-8); a half-float EXR with DWAA compression; 8-bit
  codes written unscaled into a 16-bit PNG;
* **materials**: every albedo divided by 255 (a loader for 8-bit colours);
  every Lambertian sharing one colour list (Python's mutable default); the
  mirror a fuzzy metal of *Ray Tracing in One Weekend* (fuzz 0.3);
* **geometry**: the ceiling wound as the floor is, shaded one-sided; the
  tetrahedron's vertices sorted coordinate by coordinate
  (``np.sort(axis=0)``); its apex left at the origin;
* **camera**: the right vector ``cross(up, forward)``; sub-pixel offsets
  from ``random.randint(0, 1)``; ``atan`` typed for ``tan`` in the image
  plane's width;
* **light model**: the light's area from a triangle's formula (half the
  square's, in its samples' pdf); the light's radiance split between its two
  triangles; the emission the camera sees divided by pi;
* **integrator**: cosine-weighted bounces weighted with the uniform pdf;
  the Lambertian's 1/pi left out of the light sample's BRDF; shadow rays
  bounded by t < 1 with a unit direction; the throughput multiplied by the
  albedo before the light sample;
* **samples and passes**: an integer film (every add truncated); the image
  as ``[[0] * W] * H`` (one row list, every row the last); passes averaged
  with the empty image that started the list; each pixel the 5 % trimmed mean
  of its samples.

The correct hand-ins come in ways no class used: Mitsuba with sub-pixel
offsets from the R2 sequence shifted at random in each pixel, Mitsuba with
the camera's field of view given along the diagonal, a Radiance HDR written
by hand with old-style run-length encoding, a PFM written by Mitsuba's
``mi.Bitmap``, mcrt at twice the resolution reduced by 2 x 2 means, Mitsuba
with every wall a ``rectangle`` shape, Mitsuba's ``mi.render`` of four film
crop windows stitched, and a float EXR with a channel of per-pixel sample
counts.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s
``edit`` and ``mitsuba_edit``), Mitsuba renders combined where light
transport or pixel integrals are linear in what is combined (the light seen
apart from its light on surfaces, passes), Mitsuba's path integrator
sampling the rays a student's camera, mirror or bounce makes (the helpers of
:mod:`~mcrt.grade.accuracy.unsaid`), its first vertex's direct light
redone as a student's shadow ray or throughput makes it, or its samples, one
by one, added up as a student's loop adds them
(:func:`mcrt.grade.accuracy.unasked._samples`,
:func:`mcrt.grade.accuracy.unsought._film_samples`), or correct renders
post-processed and written with NumPy, SciPy, scikit-image, pypng, OpenEXR
and the standard library as students' programs do. mcrt renders only a
correct hand-in.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over
:data:`CATEGORIES`: the 2nd, 4th, ... of each category and of the correct
hand-ins) are as in :mod:`~mcrt.grade.accuracy.unbidden`, fixed before any
case was graded.
"""

from __future__ import annotations

import math
import zlib
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unbidden, unforeseen,
                                 unguessed, unheard, unmet, unprompted, unsaid, unseen, unsought, untold, untried)
from mcrt.grade.accuracy.cases import Spec

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


#: The classes after the first two, in the order they were written (their causes' words are this class's too).
_EARLIER = (programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked, unsought,
            unguessed, unforeseen, unprompted, unbidden)


def _crc(name: str) -> int:
    return 601000 + zlib.crc32(name.encode()) % 100000


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


def _butterworth(x, *, cutoff: float = 0.25):
    """scikit-image's Butterworth low-pass, ``filters.butterworth(img, 0.25, high_pass=False, channel_axis=-1)``
    (order 2, no padding: the image taken as periodic), its ringing's negatives clipped to 0."""
    from skimage import filters

    out = filters.butterworth(np.asarray(x, np.float64), cutoff_frequency_ratio=cutoff, high_pass=False,
                              channel_axis=-1)
    return np.maximum(out, 0.0)


def _gamma_brightened(x, *, gamma: float = 0.8):
    """``skimage.exposure.adjust_gamma(img, 0.8)``: every value v ** 0.8."""
    from skimage import exposure

    return exposure.adjust_gamma(np.asarray(x, np.float64), gamma)


def _crosshair(x, *, colour=(1.0, 0.0, 0.0)):
    """A one-pixel red crosshair through the image's centre (row H // 2 and column W // 2), drawn to check where the
    camera points and never taken out."""
    out = np.array(x, np.float64, copy=True)
    h, w = out.shape[:2]
    out[h // 2, :] = colour
    out[:, w // 2] = colour
    return out


def _halved_and_back(x):
    """``transform.rescale(img, 0.5, anti_aliasing=True)`` then ``transform.resize`` back to the image's size
    (bilinear): a denoising trick, each pixel from a half-resolution image."""
    from skimage import transform

    x = np.asarray(x, np.float64)
    small = transform.rescale(x, 0.5, anti_aliasing=True, channel_axis=-1)
    return transform.resize(small, x.shape, order=1)


# --------------------------------------------------------------------------
# Writers (the render in, the file a program writes)
# --------------------------------------------------------------------------

#: SMPTE ST 2084 (PQ): m1, m2, c1, c2, c3.
_PQ = (2610.0 / 16384.0, 2523.0 / 4096.0 * 128.0, 3424.0 / 4096.0, 2413.0 / 4096.0 * 32.0, 2392.0 / 4096.0 * 32.0)


def _pq(y) -> np.ndarray:
    """The PQ inverse EOTF of luminances ``y`` as fractions of 10000 cd/m^2 (clipped to [0, 1])."""
    m1, m2, c1, c2, c3 = _PQ
    p = np.power(np.clip(y, 0.0, 1.0), m1)
    return np.power((c1 + c2 * p) / (1.0 + c3 * p), m2)


def _pq_codes(image: np.ndarray, *, white: float = 100.0) -> np.ndarray:
    """16-bit codes of the PQ curve, a value of 1 taken as ``white`` cd/m^2 (SDR's reference white)."""
    return np.floor(_pq(np.nan_to_num(image) * white / 10000.0) * 65535.0 + 0.5).astype(np.uint16)


def _write_png16_pq(image: np.ndarray, folder: Path) -> Path:
    return untried._write_png16(_pq_codes(image), folder)


def _utf8_ppm(codes: np.ndarray) -> bytes:
    """What ``open(path, "w").write(header + "".join(map(chr, codes.flat)))`` writes on Linux: the 8-bit samples as
    characters, encoded UTF-8 (every code of 128 or more two bytes)."""
    h, w = codes.shape[:2]
    return (f"P6\n{w} {h}\n255\n" + "".join(map(chr, codes.reshape(-1).tolist()))).encode("utf-8")


def _write_ppm_utf8(image: np.ndarray, folder: Path) -> Path:
    path = folder / "render.ppm"
    path.write_bytes(_utf8_ppm(blind._srgb8(image)))
    return path


def _write_exr_dwaa(image: np.ndarray, folder: Path) -> Path:
    """A half-float EXR (R, G, B) with DWAA compression (lossy: a DCT of 8 x 8 blocks, OpenEXR's default level 45)."""
    import OpenEXR

    path = folder / "render.exr"
    chans = {c: np.ascontiguousarray(image[..., i], np.float16) for i, c in enumerate("RGB")}
    OpenEXR.File({"compression": OpenEXR.DWAA_COMPRESSION, "type": OpenEXR.scanlineimage}, chans).write(str(path))
    return path


def _write_png16_8bit_codes(image: np.ndarray, folder: Path) -> Path:
    """8-bit sRGB codes (0-255) written unscaled into a 16-bit PNG (pypng's ``bitdepth=16``)."""
    return untried._write_png16(blind._srgb8(image).astype(np.uint16), folder)


# --------------------------------------------------------------------------
# Scene edits
# --------------------------------------------------------------------------


def _over_255(a) -> tuple[float, ...]:
    return tuple(float(c) / 255.0 for c in a)


def _albedos_over_255(s):
    """Every Lambertian albedo divided by 255 (the loader's colour parser written for 8-bit colours)."""
    return unbidden._albedos_mapped(s, _over_255)


def _albedos_shared(s):
    """Every Lambertian given one colour: the last one loaded (the tetrahedron's), as when the material class's
    default albedo is a list shared by every instance and the loader writes into it (``albedo[:] = ...``)."""
    last = unbidden._colour_table(s)[-1]
    return unbidden._albedos_mapped(s, lambda _: last)


def _ceiling_as_floor(d: dict) -> dict:
    """The ceiling's fan wound as the floor's (its normal up, out of the room), a one-sided Lambertian."""
    return fresh._one_sided_flipped(d, "ceiling")


def _sorted_per_axis(vertices):
    return tuple(tuple(float(c) for c in v) for v in np.sort(np.asarray(vertices, np.float64), axis=0))


def _tetra_sorted_per_axis(s):
    """The tetrahedron's vertices put in order with ``np.sort(vertices, axis=0)``: each coordinate's column sorted on
    its own, the points taken apart."""
    return unguessed._tetra_vertices(s, _sorted_per_axis)


def _apex_at_origin(vertices):
    return tuple(vertices[:3]) + ((0.0, 0.0, 0.0),)


def _tetra_apex_at_origin(s):
    """The tetrahedron's vertices copied into ``np.zeros((4, 3))`` with a triangle's slice (``[:3]``): the apex
    left at the origin."""
    return unguessed._tetra_vertices(s, _apex_at_origin)


def _fov_atan(s):
    """The image plane's half-width atan(fov / 2) for tan(fov / 2): 0.666 for 1, a field of view of 67.3 degrees for
    90."""
    half = math.atan(math.radians(s.cameras["near"].fov_x_deg) / 2.0)
    return cases._camera(s, fov_x_deg=math.degrees(2.0 * math.atan(half)))


def _light_over_pi(d: dict) -> dict:
    """The light, emitting its radiance divided by pi (what the camera sees of it)."""
    le = _scene().light.radiance
    return unsaid._meshes(d, light=(unsaid._light_tris(), tuple(r / math.pi for r in le)))


# --------------------------------------------------------------------------
# The camera's rays and sub-pixel offsets
# --------------------------------------------------------------------------


def _right_reversed(fx, fy):
    """The camera's right vector ``cross(up, forward)`` for ``cross(forward, up)`` (the up vector the scene's): the
    image plane's s axis pointing left."""
    eye, r, u, f, k = unsaid._frame()
    s, t = k * (2.0 * fx - 1.0), k * (1.0 - 2.0 * fy)
    return np.broadcast_to(eye, (len(fx), 3)), unsaid._unit(f - s[:, None] * r + t[:, None] * u)


def _corner_offsets(rng, n: int, *, w: int, pixels: int):
    """Sub-pixel offsets from ``random.randint(0, 1)`` (an integer, 0 or 1, both ends included): every sample
    through one of the pixel's four corners."""
    u, v = rng.integers(0, 2, (2, pixels, n))
    return u.astype(np.float64), v.astype(np.float64)


#: The plastic number, the R2 sequence's base.
_PLASTIC = 1.324717957244746


def _r2(rng, n: int, *, w: int, pixels: int):
    """Sub-pixel offsets from the R2 sequence (i / p, i / p^2 modulo 1, p the plastic number), shifted at random in
    each pixel (Cranley-Patterson): every offset uniform on the pixel."""
    i = np.arange(1, n + 1)
    shift = rng.random((2, pixels, 1))
    return np.mod(i / _PLASTIC + shift[0], 1.0), np.mod(i / _PLASTIC ** 2 + shift[1], 1.0)


# --------------------------------------------------------------------------
# Renderer mistakes realised on rays, sample by sample, or with Mitsuba renders combined
# --------------------------------------------------------------------------


def _in_ball(rng, n: int) -> np.ndarray:
    """(n, 3) points uniform in the unit ball."""
    d = unsaid._unit(rng.normal(size=(n, 3)))
    return d * np.cbrt(rng.random(n))[:, None]


def _fuzzy_mirror(x, *, spp: int, seed: int, fuzz: float = 0.3):
    """The mirror as *Ray Tracing in One Weekend*'s metal: the reflection plus ``fuzz`` times a point in the unit
    ball, the ray absorbed (black) when that falls below the surface, for the camera's rays (Mitsuba's path on from
    the sphere, and on the rest)."""
    h, w = x.shape[:2]
    full, rest = unsaid._loaded(_DEPTH), unsaid._loaded(_DEPTH - 1)
    c, _ = unsaid._sphere()
    rng = np.random.default_rng(seed + 29)
    total = np.zeros((h * w, 3))
    for cseed, n, fx, fy in unsaid._lanes(w, h, spp, seed):
        o, d = (np.asarray(a, np.float64) for a in unsaid._pinhole(fx, fy))
        ro, rd, hit = unsaid._reflected(o, d)
        L, on = np.zeros((len(o), 3)), hit == 1
        L[~on] = unsaid._sampled(full, o[~on], d[~on], cseed)
        scattered = rd[on] + fuzz * _in_ball(rng, int(on.sum()))
        out = np.einsum("ij,ij->i", scattered, unsaid._unit(ro[on] - c)) > 0.0
        kept = np.flatnonzero(on)[out]
        if len(kept):
            L[kept] = unsaid._sampled(rest, ro[kept], unsaid._unit(scattered[out]), cseed + 7919)
        total += L.reshape(h * w, n, 3).sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _occluded(mscene, o: np.ndarray, d: np.ndarray, maxt: np.ndarray) -> np.ndarray:
    """Whether something lies on each ray from ``o`` along the unit ``d`` nearer than ``maxt``."""
    import mitsuba as mi

    ray = unsaid._rays(o, d)
    ray.maxt = mi.Float(np.asarray(maxt, np.float32))
    return np.array(mscene.ray_test(ray), bool)


def _visible_within(mscene, p, wi, dist, *, reach: float = 1.0):
    """The shadow ray's hits tested as t < ``reach``: t < 1, the parameter of the unnormalised segment to the light,
    on a ray whose direction was normalised, finds no occluder more than 1 away (``reach = inf``: the right shadow
    ray, stopping short of the light's sample point)."""
    return ~_occluded(mscene, p, wi, np.minimum(reach, dist * (1.0 - 1e-4)))


def _light_sample(mscene, rng, p: np.ndarray, n: np.ndarray, visible) -> np.ndarray:
    """(N, 3): one light sample at each point ``p`` (normal ``n``) of a white Lambertian: a point drawn uniformly
    on the light's square (pdf 1 / A), Le cos_p cos_l / (pi d^2) A, where ``visible`` (scene, p, wi, d) says so."""
    lt = _scene().light
    u, v = rng.random((2, len(p)))
    q = np.stack([lt.center[0] + (u - 0.5) * lt.size[0], lt.center[1] + (v - 0.5) * lt.size[1],
                  np.full(len(p), lt.center[2])], axis=1)
    dist = np.linalg.norm(q - p, axis=1)
    wi = (q - p) / dist[:, None]
    # The light faces down: the cosine at it is wi's z.
    g = np.maximum(np.einsum("ij,ij->i", n, wi), 0.0) * np.maximum(wi[:, 2], 0.0) / dist ** 2
    g = np.where(visible(mscene, p, wi, dist), g, 0.0)
    return (g * lt.area / math.pi)[:, None] * np.asarray(lt.radiance, np.float64)


def _first_vertex(x, *, spp: int, seed: int, direct):
    """Mitsuba's path on the pinhole's rays with its first diffuse vertex's direct light (its max-depth-2 sample
    minus max-depth-1, same seed) replaced by ``direct`` (scene, rng, hit points, normals, albedos, Mitsuba's direct
    light) -> (N, 3). Mirror and light hits, Mitsuba's."""
    h, w = x.shape[:2]
    full, two, one = (unsaid._loaded(k) for k in (_DEPTH, 2, 1))
    rng = np.random.default_rng(seed + 17)
    total = np.zeros((h * w, 3))
    for cseed, n, fx, fy in unsaid._lanes(w, h, spp, seed):
        o, d = (np.array(a, np.float64) for a in unsaid._pinhole(fx, fy))
        L = unsaid._sampled(full, o, d, cseed)
        rho = unsaid._first_albedo(full, o, d)
        t, valid = unguessed._first_hit(full, o, d)
        sel = valid & (rho.max(axis=1) > 0.0)
        if sel.any():
            od, dd = o[sel], d[sel]
            theirs = unsaid._sampled(two, od, dd, cseed) - unsaid._sampled(one, od, dd, cseed)
            nrm = unforeseen._first_normal(full, od, dd)
            p = od + t[sel, None] * dd + 1e-4 * nrm
            L[sel] += direct(full, rng, p, nrm, rho[sel], theirs) - theirs
        total += L.reshape(h * w, n, 3).sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _shadowed_within(mscene, rng, p, n, rho, mitsuba, *, reach: float = 1.0):
    """A first vertex's direct light from :func:`_light_sample` with the shadow ray of :func:`_visible_within`."""
    return rho * _light_sample(mscene, rng, p, n, partial(_visible_within, reach=reach))


def _albedo_twice(mscene, rng, p, n, rho, mitsuba):
    """The throughput multiplied by the albedo before the light sample, whose BRDF holds it again."""
    return rho * mitsuba


def _cosine_as_uniform(rng, n):
    """Cosine-weighted directions weighted with the uniform hemisphere's pdf: f cos / (1 / 2 pi) = 2 albedo cos."""
    d, cos = unprompted._cosine_directions(rng, n)
    return d, 2.0 * cos


def _integer_film(x, *, spp: int, seed: int):
    """The film ``np.zeros((H, W, 3), dtype=int)``, each sample added as ``film[j, i] = film[j, i] + L`` (the float
    sum cast back to an integer, truncated), the sum divided by the spp."""
    h, w = x.shape[:2]
    film = np.zeros((h * w, 3), np.int64)
    for L, _, _ in unasked._samples(w, h, spp, seed):
        for k in range(L.shape[1]):
            film = (film + L[:, k]).astype(np.int64)
    return (film / spp).reshape(h, w, 3)


def _rows_aliased(x):
    """The image held as ``[[0.0] * W] * H`` (H references to one row), each pixel assigned its mean: every row the
    last row written."""
    x = np.asarray(x, np.float64)
    return np.broadcast_to(x[-1:], x.shape).copy()


def _passes_with_empty(x, *, passes: int, spp: int, seed: int):
    """``passes`` Mitsuba renders of ``spp`` (a seed each) appended to a list started with an empty (zero) image,
    the list averaged with ``np.mean(images, axis=0)``."""
    h, w = x.shape[:2]
    images = [np.zeros((h, w, 3))] + [_render(w, h, spp, seed + k) for k in range(passes)]
    return np.mean(images, axis=0)


def _trimmed(x, *, spp: int, seed: int, cut: float = 0.05):
    """Each pixel ``scipy.stats.trim_mean(samples, 0.05)`` of its samples, channel by channel: the lowest and the
    highest 5 % dropped."""
    from scipy.stats import trim_mean

    h, w = x.shape[:2]
    return trim_mean(unbidden._all_samples(w, h, spp, seed), cut, axis=1).reshape(h, w, 3)


# --------------------------------------------------------------------------
# Correct renders made in other ways
# --------------------------------------------------------------------------


def _fov_diagonal(d: dict) -> dict:
    """The camera's field of view given along the image's diagonal (Mitsuba's ``fov_axis = "diagonal"``): 2
    atan(sqrt(2) tan(fov / 2)), 109.47 degrees for 90 across a square image."""
    half = math.tan(math.radians(_scene().cameras["near"].fov_x_deg) / 2.0)
    fov = math.degrees(2.0 * math.atan(math.sqrt(2.0) * half))
    return dict(d, sensor=dict(d["sensor"], fov_axis="diagonal", fov=fov))


def _wall_rectangle(s, wall) -> dict:
    """A wall as Mitsuba's ``rectangle`` ([-1, 1]^2 in its plane z = 0) placed by a matrix: its columns half the
    wall's width along it, half its height up, its normal, its centre."""
    import mitsuba as mi

    from mcrt.mitsuba_scene import _bsdf_dict
    from mcrt.scene import Lambertian

    a, b = (np.asarray(s.room.corners[k], np.float64) for k in wall.corners)
    z0, z1 = s.room.floor_z, s.room.ceiling_z
    m = np.eye(4)
    m[:3, 0] = [(b[0] - a[0]) / 2.0, (b[1] - a[1]) / 2.0, 0.0]
    m[:3, 1] = [0.0, 0.0, (z1 - z0) / 2.0]
    m[:3, 2] = unsaid._unit(np.cross(m[:3, 0], m[:3, 1]))
    m[:3, 3] = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0, (z0 + z1) / 2.0]
    return {"type": "rectangle", "to_world": mi.ScalarTransform4f(m.tolist()),
            "bsdf": _bsdf_dict(Lambertian(wall.albedo))}


def _walls_as_rectangles(d: dict) -> dict:
    s = _scene()
    return dict(d, **{f"wall_{w.corners[0]}{w.corners[1]}": _wall_rectangle(s, w) for w in s.room.walls})


def _crop_quarters(x, *, spp: int, seed: int):
    """Mitsuba's ``mi.render`` of the film's four quarter crop windows (``crop_offset_x``, ``crop_width``, ...), a
    seed each, put together."""
    import mitsuba as mi

    from mcrt.mitsuba_scene import scene_dict

    h, w = x.shape[:2]
    out = np.zeros((h, w, 3))
    for k, (y0, x0) in enumerate(((0, 0), (0, w // 2), (h // 2, 0), (h // 2, w // 2))):
        ch, cw = (h // 2 if y0 == 0 else h - h // 2), (w // 2 if x0 == 0 else w - w // 2)
        d = scene_dict(_scene(), "near", w, h, _DEPTH, spp=spp)
        film = dict(d["sensor"]["film"], crop_offset_x=x0, crop_offset_y=y0, crop_width=cw, crop_height=ch)
        scene = mi.load_dict(dict(d, sensor=dict(d["sensor"], film=film)))
        out[y0:y0 + ch, x0:x0 + cw] = np.asarray(mi.render(scene, spp=spp, seed=seed + k), np.float64)
    return out


def _mcrt_box_reduced(x, *, spp: int, seed: int):
    """mcrt at twice the resolution reduced by 2 x 2 means: each pixel's integral (box filter) from four times the
    samples."""
    h, w = x.shape[:2]
    return blind._block_mean(unsaid._mcrt_scene(np.zeros((2 * h, 2 * w, 3)), spp=spp, seed=seed), 2, 2)


def _old_rle_row(rgbe: np.ndarray) -> bytes:
    """One scanline of RGBE pixels in old-style run-length encoding: a pixel equal to the one before starts a run,
    written as (1, 1, 1, count) (up to 255 a marker; a longer run starts again with the pixel itself)."""
    out, k, width = bytearray(), 0, len(rgbe)
    while k < width:
        out += rgbe[k].tobytes()
        run = 0
        while k + 1 + run < width and run < 255 and np.array_equal(rgbe[k + 1 + run], rgbe[k]):
            run += 1
        if run:
            out += bytes((1, 1, 1, run))
        k += 1 + run
    return bytes(out)


def _write_hdr_old_rle(image: np.ndarray, folder: Path) -> Path:
    """A Radiance HDR written by hand: RGBE pixels (frexp of the largest channel, rounded), each scanline in old-style
    run-length encoding."""
    from mcrt.image_files import _rgbe_encode

    h, w = image.shape[:2]
    path = folder / "render.hdr"
    rgbe = _rgbe_encode(path, np.nan_to_num(image))
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"-Y {h} +X {w}\n".encode()
                     + b"".join(_old_rle_row(row) for row in rgbe))
    return path


def _write_pfm_mitsuba_bitmap(image: np.ndarray, folder: Path) -> Path:
    """A PFM written by Mitsuba's ``mi.Bitmap`` (float32 RGB)."""
    import mitsuba as mi

    path = folder / "render.pfm"
    mi.Bitmap(np.ascontiguousarray(np.nan_to_num(image), np.float32)).write(str(path))
    return path


def _write_exr_counts(image: np.ndarray, folder: Path, *, spp: int) -> Path:
    """A float EXR (R, G, B, ZIP) with a fourth channel, N, of unsigned integers: each pixel's sample count."""
    import OpenEXR

    path = folder / "render.exr"
    h, w = image.shape[:2]
    chans = {c: np.ascontiguousarray(image[..., i], np.float32) for i, c in enumerate("RGB")}
    chans["N"] = np.full((h, w), spp, np.uint32)
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}, chans).write(str(path))
    return path


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_butterworth_lowpass", "pp_adjust_gamma_brighten", "pp_aim_crosshair_left",
                        "pp_rescaled_half_and_back"),
    "file": ("file_png16_pq_curve", "file_ppm_chr_text_utf8", "file_exr_half_dwaa", "file_png16_8bit_codes"),
    "materials": ("albedos_read_as_8bit", "albedos_shared_default_list", "mirror_fuzzy_metal"),
    "geometry": ("ceiling_wound_as_floor", "tetra_vertices_sorted_per_axis", "tetra_apex_at_origin"),
    "camera": ("camera_right_up_cross_forward", "jitter_randint_corners", "plane_atan_for_tan"),
    "light": ("light_area_triangle_formula", "light_radiance_split_in_two", "light_seen_over_pi"),
    "integrator": ("bounce_cosine_as_uniform", "light_sample_brdf_without_inv_pi", "shadow_ray_t_below_one",
                   "throughput_before_light_sample"),
    "samples": ("film_integer_buffer", "image_rows_aliased", "passes_mean_with_empty_image", "pixel_trimmed_mean"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_butterworth_lowpass", "blur", **_posted("butterworth", _butterworth),
             truth="skimage.filters.butterworth(img, 0.25, high_pass=False, channel_axis=-1) against the noise (a "
             "low-pass of order 2 in the frequency domain, the image taken as periodic), negatives clipped to 0, "
             "as EXR: blurred, ringing round the light, the opposite edges bleeding into each other"),
        Spec("pp_adjust_gamma_brighten", "tone_map", True, held_out=True,
             **_posted("adjust_gamma_08", _gamma_brightened),
             truth="skimage.exposure.adjust_gamma(img, 0.8) to brighten the dark corners, as EXR: every value v ** "
             "0.8, the dark values lifted (0.01 to 0.025), the light 11 for 20"),
        Spec("pp_aim_crosshair_left", "bad_pixels", **_posted("crosshair", _crosshair),
             truth="a one-pixel red crosshair (1, 0, 0) through the image's centre (row H // 2 and column W // 2), "
             "drawn to check where the camera points and left in, as EXR: the rest right"),
        Spec("pp_rescaled_half_and_back", "resampling", held_out=True, **_posted("rescaled_half", _halved_and_back),
             truth="skimage.transform.rescale(img, 0.5, anti_aliasing=True) then transform.resize back to 64 x 64 "
             "(bilinear), to smooth the noise, as EXR: the image at half its resolution, blurred"),
        # Writing the file
        Spec("file_png16_pq_curve", "encoding", True, writer=_write_png16_pq, file="png16-pq",
             truth="a 16-bit PNG encoded with HDR video's PQ curve (SMPTE ST 2084), a value of 1 taken as 100 "
             "cd/m^2, to keep the highlights: read as sRGB, 0.01 read as 0.02, 0.1 as 0.07, 1 as 0.22 and the light "
             "as 0.65, the contrast flattened"),
        Spec("file_ppm_chr_text_utf8", "file_format", True, held_out=True, writer=_write_ppm_utf8, file="ppm-utf8",
             truth="a binary PPM built as a str, header + ''.join(map(chr, codes)), written through a text file "
             "(UTF-8): every sample of 128 or more written as two bytes, the samples after the first of them "
             "read one byte later for each, the image's colours and pixels slipping further down the image"),
        Spec("file_exr_half_dwaa", "lossy_compression", writer=_write_exr_dwaa, file="exr-half-dwaa",
             truth="a half-float EXR saved with DWAA compression (lossy: a DCT of 8 x 8 blocks, the default level "
             "45), to make it small: small errors everywhere, larger about the light's edges"),
        Spec("file_png16_8bit_codes", "code_range", True, held_out=True, writer=_write_png16_8bit_codes,
             file="png16-8bit-codes",
             truth="8-bit sRGB codes (0-255) written unscaled into a 16-bit PNG (pypng, bitdepth=16): every code "
             "1/257 of what it should be, the image nearly black (the light 0.0003)"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    c = _crc
    return (
        # Materials
        Spec("albedos_read_as_8bit", "albedo", True, edit=_albedos_over_255,
             truth="every Lambertian albedo divided by 255 by a colour parser written for 8-bit colours: the floor "
             "0.0024, the red wall (0.0029, 0.0006, 0.0006), the room nearly black, the light and its reflection "
             "right"),
        Spec("albedos_shared_default_list", "albedo", True, held_out=True, edit=_albedos_shared,
             truth="the material class's default albedo a list shared by every instance (a mutable default "
             "argument), the loader writing into it: every Lambertian the last colour loaded, the tetrahedron's "
             "(0.8, 0.45, 0.1): the floor, the ceiling and every wall orange"),
        Spec("mirror_fuzzy_metal", "material", True, **_posted("fuzzy_metal", partial(
            _fuzzy_mirror, spp=_S, seed=c("mirror_fuzzy_metal"))),
             truth="the mirror as Ray Tracing in One Weekend's metal with the book's fuzz 0.3: the reflected "
             "direction plus 0.3 times a random point in the unit ball, absorbed when that points into the "
             "sphere, for the camera's rays (Mitsuba's path on from the sphere): the room in the sphere blurred, "
             "its rim darker"),
        # Geometry
        Spec("ceiling_wound_as_floor", "normals", True, mitsuba_edit=_ceiling_as_floor,
             truth="the ceiling's fan wound as the floor's (its code copied), its normal up, out of the room, "
             "shaded one-sided (max(0, n . l)): the ceiling black where seen, and reflecting nothing"),
        Spec("tetra_vertices_sorted_per_axis", "object_shape", True, held_out=True, edit=_tetra_sorted_per_axis,
             truth="the tetrahedron's vertices put in order with np.sort(vertices, axis=0), each coordinate's "
             "column sorted on its own: (7.5, -3.8, -4.9), (8.5, -2.3, -4.9), (8.5, -2.0, -4.9), (9.5, -1.0, "
             "-2.0): a thin base, the apex over the base's far corner"),
        Spec("tetra_apex_at_origin", "object_shape", True, edit=_tetra_apex_at_origin,
             truth="the tetrahedron's vertices copied into np.zeros((4, 3)) with a triangle's slice [:3]: the apex "
             "left at the origin (0, 0, 0), one unit in front of the eye: a long orange spike from the base to the "
             "image's centre"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera
        Spec("camera_right_up_cross_forward", "camera_rotation", True, **_posted("right_reversed", partial(
            unsaid._traced, spp=_S, seed=c("camera_right_up_cross_forward"), camera=_right_reversed)),
             truth="the camera's right vector cross(up, forward) for cross(forward, up) (the cross product's "
             "handedness), its up the scene's: the image plane's horizontal axis pointing left, the image mirrored "
             "left to right"),
        Spec("jitter_randint_corners", "pixel_footprint", held_out=True,
             **_posted("randint_corners", partial(unforeseen._mean_through, spp=_S, seed=c("jitter_randint_corners"),
                                                  jitter=_corner_offsets)),
             truth="the sub-pixel offsets from random.randint(0, 1) for random.random() (integers, 0 or 1): every "
             "sample through one of the pixel's four corners, each pixel the mean of the radiance at its corners "
             "(each corner shared with three neighbours): slightly blurred, edges aliased"),
        Spec("plane_atan_for_tan", "camera_fov", True, edit=_fov_atan,
             truth="the image plane's half-width atan(fov / 2) for tan(fov / 2) (the function's name mistyped): "
             "0.666 for 1, a field of view of 67.3 degrees for 90, the middle of the view magnified"),
        # Light model
        Spec("light_area_triangle_formula", "light_pdf", True, **_posted("light_area_halved", partial(
            unheard._light_direct_scaled, f=0.5, spp=_S, seed=c("light_area_triangle_formula"))),
             truth="the light's area from a triangle's formula, |e1 x e2| / 2 of two of its edges (the mesh code's "
             "area function reused): 2 for 4, its samples' pdf 1/2 for 1/4: every light sample half as bright, "
             "the light on surfaces half the truth, the light seen right"),
        Spec("light_radiance_split_in_two", "light_radiance", True, held_out=True,
             edit=cases.light(radiance=(10.0, 10.0, 10.0)),
             truth="the light's radiance divided between its two triangles (as a power would be): each emitting 10, "
             "the light and every surface half as bright"),
        Spec("light_seen_over_pi", "light_seen", **_posted("seen_over_pi", partial(
            unsaid._light_seen_from, spp=_S, seed=c("light_seen_over_pi"), seen_edit=_light_over_pi)),
             truth="the emission a camera ray meets divided by pi (the emitter's radiance passed through a "
             "Lambertian's 1 / pi), directly and in the mirror: the light's own pixels 6.4 for 20, its light on "
             "surfaces right"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples, passes and buffers."""
    c = _crc
    return (
        # Integrator
        Spec("bounce_cosine_as_uniform", "indirect_scale", True, **_posted("cosine_as_uniform", partial(
            unprompted._first_bounce, spp=_S, seed=c("bounce_cosine_as_uniform"), draw=_cosine_as_uniform)),
             truth="the diffuse bounce drawn cosine-weighted and weighted with the uniform hemisphere's pdf 1 / (2 "
             "pi) (f cos / pdf = 2 albedo cos), at the first surface a camera ray meets (Mitsuba's path after "
             "it): the indirect light there a third too bright on average, most from near the normal, the direct "
             "right"),
        Spec("light_sample_brdf_without_inv_pi", "brdf_norm", True, held_out=True, **_posted(
            "light_sample_times_pi", partial(unheard._light_direct_scaled, f=math.pi, spp=_S,
                                             seed=c("light_sample_brdf_without_inv_pi"))),
             truth="the Lambertian's BRDF written albedo (its 1 / pi left out) in the light sample, the bounce's "
             "weight (albedo) right: every light sample pi times too bright, the light on surfaces pi times the "
             "truth, the light seen right"),
        Spec("shadow_ray_t_below_one", "light_pdf", True, **_posted("shadow_within_one", partial(
            _first_vertex, spp=_S, seed=c("shadow_ray_t_below_one"), direct=_shadowed_within)),
             truth="the shadow ray's hits tested as t < 1 (the parameter of the segment to the light) on a ray "
             "whose direction was normalised, at the first surface a camera ray meets (Mitsuba's path after it): "
             "occluders over 1 away never found, the shadows of the sphere and the tetrahedron gone but right "
             "by them, the light seen right"),
        Spec("throughput_before_light_sample", "albedo", True, held_out=True, **_posted(
            "albedo_in_light_sample_twice", partial(_first_vertex, spp=_S, seed=c("throughput_before_light_sample"),
                                                    direct=_albedo_twice)),
             truth="the throughput multiplied by the albedo before the light sample (beta *= albedo; then L += beta "
             "f Le G / pdf, f holding the albedo again), at the first surface a camera ray meets (Mitsuba's path "
             "after it): its direct light times its albedo, the coloured walls deeper in colour, everything "
             "darker, the light seen right"),
        # Samples, passes and buffers
        Spec("film_integer_buffer", "quantisation", True, **_posted("integer_film", partial(
            _integer_film, spp=_S, seed=c("film_integer_buffer"))),
             truth="the film allocated np.zeros((H, W, 3), dtype=int), each sample added as film[j, i] = film[j, "
             "i] + L (the sum cast back to an integer, truncated), divided by 256: a sample under 1 never counts, "
             "the room nearly black, the light right"),
        Spec("image_rows_aliased", "row_stride", True, held_out=True, **_posted("rows_aliased", _rows_aliased),
             truth="the image held as [[0.0] * W] * H (H references to one row list), each pixel assigned its "
             "mean: every row the last one written, the bottom row repeated down the whole image"),
        Spec("passes_mean_with_empty_image", "light_radiance", True, **_posted("passes_with_empty", partial(
            _passes_with_empty, passes=4, spp=64, seed=c("passes_mean_with_empty_image"))),
             truth="4 passes of 64 spp appended to a list started with an empty (zero) image, np.mean(images, "
             "axis=0) over the 5: every pixel 4/5 of the truth"),
        Spec("pixel_trimmed_mean", "biased_estimator", held_out=True, **_posted("trimmed_mean", partial(
            _trimmed, spp=_S, seed=c("pixel_trimmed_mean"))),
             truth="each pixel scipy.stats.trim_mean(samples, 0.05) of its 256 samples, channel by channel (the "
             "lowest and the highest 12 dropped, against fireflies): the indirect light's rare bright samples "
             "lost, the lit surfaces too dark, the light right"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_r2_offsets", None, spp=188, **_posted("r2_offsets", partial(
            unforeseen._mean_through, spp=188, seed=c("ok_r2_offsets"), jitter=_r2)),
             truth="Mitsuba path 188 spp, sub-pixel offsets from the R2 sequence (the plastic number's additive "
             "recurrence) shifted at random in each pixel (Cranley-Patterson), EXR"),
        Spec("ok_fov_diagonal_axis", None, held_out=True, spp=196, mitsuba_edit=_fov_diagonal,
             truth="Mitsuba path 196 spp with the camera's field of view given along the diagonal (fov_axis = "
             "diagonal, 109.47 degrees: 90 across the square image), EXR"),
        Spec("ok_hdr_old_rle", None, spp=156, writer=_write_hdr_old_rle, file="hdr-old-rle",
             truth="Mitsuba path 156 spp, a Radiance HDR written by hand with old-style run-length encoding"),
        Spec("ok_pfm_mitsuba_bitmap", None, held_out=True, spp=268, writer=_write_pfm_mitsuba_bitmap,
             file="pfm-mi-bitmap", truth="Mitsuba path 268 spp, a PFM written by Mitsuba's mi.Bitmap"),
        Spec("ok_mcrt_2x_box_reduced", None, spp=80, renderer="mcrt", **_posted("mcrt_2x_box", partial(
            _mcrt_box_reduced, spp=20, seed=c("ok_mcrt_2x_box_reduced"))),
             truth="mcrt at 128 x 128, 20 spp, reduced by 2 x 2 means: 80 samples a pixel, 80 declared, EXR"),
        Spec("ok_walls_as_rectangles", None, held_out=True, spp=172, mitsuba_edit=_walls_as_rectangles,
             truth="Mitsuba path 172 spp with every wall a rectangle shape placed by a matrix, EXR"),
        Spec("ok_film_crop_quarters", None, spp=236, **_posted("crop_quarters", partial(
            _crop_quarters, spp=236, seed=c("ok_film_crop_quarters"))),
             truth="Mitsuba's mi.render 236 spp of the film's four quarter crop windows, a seed each, put together, "
             "EXR"),
        Spec("ok_exr_sample_counts", None, held_out=True, spp=124, writer=partial(_write_exr_counts, spp=124),
             file="exr-counts",
             truth="Mitsuba path 124 spp, a float EXR with a fourth channel N of each pixel's sample count "
             "(unsigned integers)"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "blur": "a filter after rendering (a Butterworth low-pass)",
    "tone_map": "a curve applied before saving (a gamma of 0.8 to brighten)",
    "bad_pixels": "pixels overwritten after rendering (a crosshair left in)",
    "resampling": "resampled after rendering (halved and enlarged again to smooth the noise)",
    "encoding": "the values' encoding (HDR video's PQ curve for sRGB's)",
    "file_format": "the file's bytes and its header disagree (a binary PPM written as UTF-8 text)",
    "lossy_compression": "the image saved with lossy compression (an EXR's DWAA)",
    "code_range": "codes of another bit depth in the file (8-bit codes in a 16-bit PNG)",
    "albedo": "a surface's colour (every colour divided by 255, one colour shared by all, the albedo applied twice "
              "in the light sample)",
    "material": "the mirror rendered with another material (a fuzzy metal)",
    "normals": "surface normals facing the wrong way (the ceiling's, shaded one-sided)",
    "object_shape": "an object's shape (the tetrahedron's vertices sorted per axis, its apex at the origin)",
    "camera_rotation": "the camera's basis (its right vector's cross product the wrong way round)",
    "pixel_footprint": "each pixel's samples not spread over its square (at its corners)",
    "camera_fov": "the camera's field of view (atan for tan)",
    "light_pdf": "the light sampled wrongly (its area, shadow rays bounded too short): the light seen right, its "
                 "light on surfaces not",
    "light_radiance": "the light's radiance or a constant factor (the radiance split in two, an empty pass averaged "
                      "in)",
    "light_seen": "the light's own pixels (where the camera sees it) at the wrong brightness (divided by pi), its "
                  "light on surfaces right",
    "indirect_scale": "the indirect light wrong (the diffuse bounce weighted with another pdf), the direct light right",
    "brdf_norm": "a BRDF's normalisation (the Lambertian's 1 / pi left out of the light sample)",
    "quantisation": "values quantised wrongly (an integer film)",
    "row_stride": "pixels written at the wrong addresses (every row one list)",
    "biased_estimator": "a biased estimate of each pixel's mean (a trimmed mean of its samples)",
}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = blind.class_causes(MISTAKES, _EARLIER, NEW_CAUSES, _REWORDED)


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
