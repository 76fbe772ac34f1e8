r"""A twelfth class of hand-ins: mistakes in students' tracers, scene input and output no class tried, written blind.

How it was written: from what goes wrong in students' programs (the steps
after rendering, the code that saves the image, the scene typed in or built
into meshes, the camera's rays, the light's samples, the integrator's loop,
the loops that add up the samples), not from the grader. Its author read the
other classes' specs and cause words, the catalogue (:mod:`mcrt.mutants`),
:data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to
stay clear of their mistakes; never the grader's rules (what decides a
cause) nor its reports, and graded none of it, not one case. Each cause and
``major`` flag was set from the mistake alone; every mistake is worded by a
cause the other classes already have (:data:`NEW_CAUSES` is empty), so
``SAME_MISTAKE`` needed no new entry. The mistakes differ from those of the
eleven other classes (:mod:`~mcrt.grade.accuracy.cases`,
:mod:`~mcrt.grade.accuracy.outside`, :mod:`~mcrt.grade.accuracy.programs`,
:mod:`~mcrt.grade.accuracy.fresh`, :mod:`~mcrt.grade.accuracy.blind`,
:mod:`~mcrt.grade.accuracy.unseen`, :mod:`~mcrt.grade.accuracy.untried`,
:mod:`~mcrt.grade.accuracy.novel`, :mod:`~mcrt.grade.accuracy.untold`,
:mod:`~mcrt.grade.accuracy.unmet`, :mod:`~mcrt.grade.accuracy.unheard`) and
from the catalogue's bugs:

* **post-processing**: a 3 x 3 binomial blur written by hand, its weights
  (1, 2, 1 by 1, 2, 1) divided by 9, a box filter's count, not by their sum
  16; an exponential tone curve ``1 - exp(-x)``; a caption ("256 spp") drawn
  on the image with Pillow before the PNG is saved; a 3 x 3 maximum filter
  (SciPy's ``maximum_filter``, to fill dark speckles);
* **writing the file**: the channels' mean saved with Matplotlib's
  ``imsave`` (false colour: the viridis map over the values' range); a
  binary PPM's header (``P6``) over samples written as text; a hand-written
  PPM whose loops run channel before column (each row's reds, then its
  greens, then its blues); an 8-bit PNG encoded by the BT.709 camera curve
  (4.5 v below 0.018, 1.099 v^0.45 - 0.099 above) for sRGB's;
* **materials**: every albedo rounded to one decimal (the parser's
  ``round(a, 1)``); the mirror's reflected direction computed and never used
  (the ray goes on as it came: the sphere seen through, its shadow kept); the
  ceiling given the light's material (a material index off: the whole
  ceiling emits 20, black, its triangles among the lights); wall FA given
  wall EF's colour (a copied line);
* **geometry**: the sphere's normal ``p - c`` never divided by the radius
  (a normal 1.5 long in the reflection formula); the walls' top corners at
  z = 0 (built from ``(x, y)`` with z defaulting to 0): the upper half of the
  room open; the tetrahedron's bounding box taken as its hit (the box test's
  hit returned, the triangles never tested);
* **camera model**: the ray's direction the image-plane point itself (the
  eye never subtracted: right for an eye at the origin); the ``- 1`` of the
  pixel-to-plane mapping forgotten in x (an off-axis view from the centre
  rightwards); the camera's rotation matrix applied transposed (rows for
  columns);
* **light model**: the light seen only on the first of its two triangles (the
  emitter's lookup by primitive index, the light sampled right); 30 shadow
  rays a vertex (the course report's) summed, not averaged; the light's
  intersection taking its size for its half-size (a 4 x 4 square seen, the
  2 x 2 one sampled);
* **integrator**: the mirror handled only for camera rays (a path that meets
  it after a bounce ends there); the first surface's albedo left out of the
  throughput (its light sample right, the light after it not coloured by it);
  the sphere left out of the shadow rays' test (analytic shapes in another
  list than the triangles the test loops over);
* **samples and passes**: adaptive sampling whose pixels, stopped early, are
  divided by the full spp; ``n = isqrt(500)`` strata a side (484 samples)
  divided by the 500 asked for; a pass buffer never cleared, added to the
  total after each of 4 passes (the passes weighted 4, 3, 2, 1: 2.5 times too
  bright); rows rendered by a pool's ``imap_unordered`` and stored in the
  order they finished.

The correct hand-ins come in ways no class used: mcrt of the scene mirrored
(y negated, a left-handed habit) with the image flipped back, Mitsuba with
the light's three channels lit apart and summed, mcrt and Mitsuba averaged,
Mitsuba in CIE XYZ converted to RGB by the student (Mitsuba's own
``xyz_to_srgb``), Mitsuba with the light in other units (times 100) and the
image divided back, a TGA written by hand top row first (origin bit set), a
16-bit PNG with an alpha channel, and mcrt without Russian roulette.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s
``edit`` and ``mitsuba_edit``), Mitsuba renders combined where light
transport or pixel integrals are linear in what is combined (the light seen
apart, sub-pixel cells, passes, batches), Mitsuba's path integrator sampling
the rays a student's camera or mirror makes (:func:`_traced`: the rays made
with NumPy, each traced by the integrator's own ``sample``), or correct
renders post-processed and written with NumPy, SciPy, Pillow and Matplotlib
as students' programs do. mcrt renders only correct hand-ins.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over
:data:`CATEGORIES`: the 2nd, 4th, ... of each category and of the correct
hand-ins) are as in :mod:`~mcrt.grade.accuracy.unheard`, fixed before any
case was graded.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unheard, unmet, unseen, untold,
                                 untried)
from mcrt.grade.accuracy.cases import Spec

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


def _crc(name: str) -> int:
    return 81000 + zlib.crc32(name.encode()) % 100000


_render = unseen._render
_posted = unseen._posted
_scaled = unheard._scaled

#: A black, non-reflecting surface (the light's).
_BLACK = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0] * 3}}


# --------------------------------------------------------------------------
# Post-processing (linear render in, what the program writes out)
# --------------------------------------------------------------------------

#: A binomial blur's weights (1, 2, 1 by 1, 2, 1) over a box filter's count, 9: their sum is 16/9.
_BINOMIAL_OVER_9 = np.outer([1.0, 2.0, 1.0], [1.0, 2.0, 1.0]) / 9.0


def _binomial_over_9(x):
    """A 3 x 3 binomial blur written by hand, its weights divided by 9 (not 16): blurred and 16/9 too bright."""
    from scipy.ndimage import convolve

    x = np.asarray(x, np.float64)
    return np.stack([convolve(x[..., c], _BINOMIAL_OVER_9, mode="nearest") for c in range(3)], axis=-1)


def _exponential(x):
    """An exponential tone curve, ``1 - exp(-x)`` (values in [0, 1))."""
    return -np.expm1(-np.maximum(np.asarray(x, np.float64), 0.0))


def _max_filter(x):
    """SciPy's ``maximum_filter`` over 3 x 3 pixels on each channel (to fill dark speckles): bright areas grow a
    pixel."""
    from scipy.ndimage import maximum_filter

    return maximum_filter(np.asarray(x, np.float64), size=(3, 3, 1), mode="nearest")


def _captioned(codes: np.ndarray, text: str = "256 spp") -> np.ndarray:
    """8-bit codes with ``text`` drawn at (2, 2) in white by Pillow's ``ImageDraw`` (its default font)."""
    from PIL import Image, ImageDraw, ImageFont

    img = Image.fromarray(codes, "RGB")
    ImageDraw.Draw(img).text((2, 2), text, fill=(255, 255, 255), font=ImageFont.load_default())
    return np.asarray(img)


def _write_png_captioned(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB PNG with a caption drawn on it (:func:`_captioned`)."""
    return novel._write_png(_captioned(blind._srgb8(image)), folder)


# --------------------------------------------------------------------------
# Files as students' programs write them (the program's buffer in, file out)
# --------------------------------------------------------------------------


def _write_png_viridis(image: np.ndarray, folder: Path) -> Path:
    """``matplotlib.image.imsave`` of the channels' mean (clipped to [0, 1]): a single channel gets the default colour
    map (viridis) over the values' range, written as an RGBA PNG."""
    from matplotlib.image import imsave

    path = folder / "render.png"
    imsave(path, np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 1.0).mean(axis=2), format="png")
    return path


def _ascii_rows(codes: np.ndarray) -> bytes:
    """The codes as text, a row a line, samples separated by spaces (what a plain PPM holds)."""
    return b"".join((" ".join(str(int(v)) for v in row.reshape(-1)) + "\n").encode() for row in codes)


def _write_ppm_p6_ascii(image: np.ndarray, folder: Path) -> Path:
    """A binary PPM's header (``P6``, maxval 255) over 8-bit sRGB samples written as text (a plain PPM's data)."""
    h, w = image.shape[:2]
    path = folder / "render.ppm"
    path.write_bytes(unheard._ppm_header(w, h) + _ascii_rows(blind._srgb8(image)))
    return path


def _rows_planar(codes: np.ndarray) -> bytes:
    """Each row's samples with the channel loop outside the column loop: the row's reds, then greens, then blues."""
    return b"".join(np.ascontiguousarray(row.T).tobytes() for row in codes)


def _write_ppm_rows_planar(image: np.ndarray, folder: Path) -> Path:
    """A binary PPM (P6, maxval 255) written by hand, ``for c in range(3): for i in range(w)`` inside the row loop."""
    h, w = image.shape[:2]
    path = folder / "render.ppm"
    path.write_bytes(unheard._ppm_header(w, h) + _rows_planar(blind._srgb8(image)))
    return path


def _bt709(v) -> np.ndarray:
    """The BT.709 camera curve (OETF): 4.5 v below 0.018, 1.099 v^0.45 - 0.099 above."""
    v = np.clip(np.nan_to_num(np.asarray(v, np.float64)), 0.0, 1.0)
    return np.where(v < 0.018, 4.5 * v, 1.099 * np.power(v, 0.45) - 0.099)


def _write_png_bt709(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit PNG of BT.709-encoded values (rounded codes), read as sRGB."""
    return novel._write_png(np.floor(_bt709(image) * 255.0 + 0.5).astype(np.uint8), folder)


# --------------------------------------------------------------------------
# Mitsuba's path integrator on the rays a student's program makes
# --------------------------------------------------------------------------


def _loaded(max_depth: int, dict_edit=None):
    """The canonical scene loaded in Mitsuba (``dict_edit`` applied to its dict), its path integrator of ``max_depth``
    (rr_depth 5, as the reference's); the sensor is never used."""
    import mitsuba as mi

    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    d = scene_dict(load_scene(), "near", 4, 4, max_depth, spp=1)
    return mi.load_dict(dict_edit(d) if dict_edit is not None else d)


def _rays(o: np.ndarray, d: np.ndarray):
    import mitsuba as mi

    def vec(kind, a):
        a = np.asarray(a, np.float32)
        return kind(mi.Float(a[:, 0]), mi.Float(a[:, 1]), mi.Float(a[:, 2]))

    return mi.Ray3f(vec(mi.Point3f, o), vec(mi.Vector3f, d))


def _sampled(mscene, o: np.ndarray, d: np.ndarray, seed: int) -> np.ndarray:
    """(N, 3): one radiance sample of each ray from ``o`` along ``d`` (N, 3), by the scene's integrator's own
    ``sample`` (Mitsuba's path tracer), its independent sampler seeded with ``seed`` (the same seed, the same random
    numbers lane by lane)."""
    import drjit as dr
    import mitsuba as mi

    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(dr.opaque(mi.UInt32, seed), len(o))
    L = mscene.integrator().sample(mscene, sampler, mi.RayDifferential3f(_rays(o, d)), None, True)[0]
    return np.stack([np.array(L[c], np.float64) for c in range(3)], axis=1)


def _lanes(w: int, h: int, spp: int, seed: int, *, lanes: int = 1 << 18):
    """The camera samples in chunks: (chunk seed, samples a pixel n, fx, fy), fx and fy (W H n,) the samples' film
    positions in [0, 1) (lane = pixel n + sample, pixels in row order), uniform in each pixel's square."""
    from mcrt.mitsuba_scene import pass_seed

    rng = np.random.default_rng(seed)
    n_chunk = max(1, lanes // (w * h))
    jj, ii = np.divmod(np.arange(w * h), w)
    done, k = 0, 0
    while done < spp:
        n = min(n_chunk, spp - done)
        u, v = rng.random((2, w * h * n))
        yield pass_seed(seed, k), n, (np.repeat(ii, n) + u) / w, (np.repeat(jj, n) + v) / h
        done, k = done + n, k + 1


def _frame():
    """The near camera: eye, right, up, forward (scene.md's frame) and tan(fov / 2)."""
    from mcrt.scene import load_scene

    cam = load_scene().cameras["near"]
    r, u, f = cam.frame()
    return np.asarray(cam.eye, np.float64), r, u, f, math.tan(math.radians(cam.fov_x_deg) / 2.0)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _pinhole(fx, fy):
    """The scene's camera: from the eye through the image-plane point (s, t) = (2 fx - 1, 1 - 2 fy) (times
    tan(fov / 2)) at distance 1 along the view."""
    eye, r, u, f, k = _frame()
    s, t = k * (2.0 * fx - 1.0), k * (1.0 - 2.0 * fy)
    return np.broadcast_to(eye, (len(fx), 3)), _unit(f + s[:, None] * r + t[:, None] * u)


def _eye_not_subtracted(fx, fy):
    """The ray's direction the image-plane point itself (``normalize(eye + forward + s right + t up)``), from the
    eye: with the eye at (-1, 0, 0) every ray runs in the plane x = 0's directions, across the view."""
    eye, r, u, f, k = _frame()
    s, t = k * (2.0 * fx - 1.0), k * (1.0 - 2.0 * fy)
    return np.broadcast_to(eye, (len(fx), 3)), _unit(eye + f + s[:, None] * r + t[:, None] * u)


def _plane_without_minus_one(fx, fy):
    """The pixel-to-plane mapping with its ``- 1`` forgotten in x: s = 2 fx in [0, 2], from the view's centre to
    63.4 degrees right."""
    eye, r, u, f, k = _frame()
    s, t = k * 2.0 * fx, k * (1.0 - 2.0 * fy)
    return np.broadcast_to(eye, (len(fx), 3)), _unit(f + s[:, None] * r + t[:, None] * u)


def _rotation_transposed(fx, fy):
    """The camera's rotation M (right, up and forward as its columns) applied transposed: direction M^T (s, t, 1),
    i.e. (r . v, u . v, f . v) for v = (s, t, 1) read as a world vector."""
    eye, r, u, f, k = _frame()
    v = np.stack([k * (2.0 * fx - 1.0), k * (1.0 - 2.0 * fy), np.ones_like(fx)], axis=1)
    return np.broadcast_to(eye, (len(fx), 3)), _unit(v @ np.stack([r, u, f], axis=1))


def _sphere():
    from mcrt.scene import load_scene

    sph = next(o for o in load_scene().objects if o.name == "sphere")
    return np.asarray(sph.center, np.float64), float(sph.radius)


def _reflected(o, d, *, unnormalised: bool = False):
    """Camera rays that meet the sphere (nothing lies in front of it) reflected there, the rest as they are:
    (origins, directions, segments used: 1 where reflected, else 0). The reflection ``d - 2 (d . n) n`` takes
    ``n = (p - c) / r``, or with ``unnormalised`` ``n = p - c`` (r long), the result normalised."""
    c, radius = _sphere()
    oc = o - c
    b = np.einsum("ij,ij->i", oc, d)
    disc = b * b - (np.einsum("ij,ij->i", oc, oc) - radius * radius)
    t = -b - np.sqrt(np.maximum(disc, 0.0))
    hit = (disc > 0.0) & (t > 0.0)
    p = o + t[:, None] * d
    n_hat = (p - c) / radius
    n = n_hat * (radius if unnormalised else 1.0)
    r = _unit(d - 2.0 * np.einsum("ij,ij->i", d, n)[:, None] * n)
    return (np.where(hit[:, None], p + 1e-4 * n_hat, o), np.where(hit[:, None], r, d), hit.astype(int))


def _traced(x, *, spp: int, seed: int, camera=_pinhole, after=None, dict_edit=None, max_depth: int = 8):
    """Each pixel the mean of ``spp`` samples of Mitsuba's path integrator on the rays ``camera`` (fx, fy) -> (o, d)
    makes (jittered over the pixel), first changed by ``after`` (o, d) -> (o, d, segments used) where the student's
    tracer does a first segment itself (a mirror bounce): those go on with a path of ``max_depth`` less those
    segments. ``dict_edit`` edits the scene the integrator sees."""
    h, w = x.shape[:2]
    scenes: dict = {}
    total = np.zeros((h * w, 3))
    for cseed, n, fx, fy in _lanes(w, h, spp, seed):
        o, d = camera(fx, fy)
        used = np.zeros(len(o), int)
        if after is not None:
            o, d, used = after(np.asarray(o, np.float64), np.asarray(d, np.float64))
        L = np.zeros((len(o), 3))
        for k in np.unique(used):
            if k not in scenes:
                scenes[k] = _loaded(max_depth - int(k), dict_edit)
            sel = used == k
            L[sel] = _sampled(scenes[k], o[sel], d[sel], cseed + 7919 * int(k))
        total += L.reshape(h * w, n, 3).sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _first_albedo_skipped(x, *, spp: int, seed: int):
    """The first surface's albedo left out of the path's throughput (``if depth > 0: beta *= albedo``): its light
    sample (with its BRDF) right, the light of every later vertex not multiplied by it. Per sample, with the same
    random numbers: L2 + (L8 - L2) / albedo, L2 and L8 the sample's radiance at max depth 2 and 8 (the seen light and
    the first hit's light sample, then the rest), the albedo that of the camera ray's first hit (the mirror and the
    light's black surface left as they are)."""
    h, w = x.shape[:2]
    full, two = _loaded(8), _loaded(2)
    total = np.zeros((h * w, 3))
    for cseed, n, fx, fy in _lanes(w, h, spp, seed):
        o, d = _pinhole(fx, fy)
        L8, L2 = _sampled(full, o, d, cseed), _sampled(two, o, d, cseed)
        rho = _first_albedo(full, o, d)
        rest = np.where(rho > 0.0, (L8 - L2) / np.where(rho > 0.0, rho, 1.0), L8 - L2)
        total += (L2 + rest).reshape(h * w, n, 3).sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _first_albedo(mscene, o, d) -> np.ndarray:
    """(N, 3): the diffuse reflectance of each ray's first hit (0 for the mirror and the light's black surface)."""
    si = mscene.ray_intersect(_rays(o, d))
    rho = si.bsdf().eval_diffuse_reflectance(si, si.is_valid())
    return np.stack([np.array(rho[c], np.float64) for c in range(3)], axis=1)


# --------------------------------------------------------------------------
# Renderer mistakes realised with Mitsuba renders combined (the render's shape in, the image out)
# --------------------------------------------------------------------------


def _seen(w: int, h: int, spp: int, seed: int, dict_edit=None) -> np.ndarray:
    """The light seen, directly (a max-depth-1 render) and in the mirror (the paths eye, sphere, light: with every
    diffuse surface black, max depth 2 minus max depth 1), of the scene as ``dict_edit`` makes it."""
    def black(d):
        return untold._black_diffuse(dict_edit(d) if dict_edit is not None else d)

    return (_render(w, h, spp, seed, max_depth=1, dict_edit=dict_edit)
            + _render(w, h, spp, seed, max_depth=2, dict_edit=black)
            - _render(w, h, spp, seed, max_depth=1, dict_edit=black))


def _light_seen_from(x, *, spp: int, seed: int, seen_edit, rest_edit=None):
    """The light as the camera sees it (directly and in the mirror) from the scene ``seen_edit`` makes, everything
    else from the scene ``rest_edit`` makes (None: the canonical one): same-seed renders, which share their camera
    rays and mirror bounces."""
    h, w = x.shape[:2]
    return (_seen(w, h, spp, seed, seen_edit) + _render(w, h, spp, seed, dict_edit=rest_edit)
            - _seen(w, h, spp, seed, rest_edit))


def _sphere_unshadowing(x, *, spp: int, seed: int, k: int = 4):
    """The sphere left out of the shadow test: the plain render plus the direct light the sphere blocks at the
    surfaces the camera sees. In the cells of a render ``k`` times finer whose camera ray misses the sphere, that is a
    max-depth-2 render without the sphere minus its same-seed render with it (the same camera rays and light
    samples). (The sphere's shadows at deeper vertices, a few per cent of their light, are kept.)"""
    h, w = x.shape[:2]
    cells = max(1, spp // (k * k))
    cseed = seed + 1
    without = _render(k * w, k * h, cells, cseed, max_depth=2, dict_edit=partial(fresh._without_mesh, name="sphere"))
    gained = (without - _render(k * w, k * h, cells, cseed, max_depth=2)) * ~unheard._sphere_hit(w, h, k)[..., None]
    return _render(w, h, spp, seed) + gained.reshape(h, k, w, k, 3).mean(axis=(1, 3))


def _adaptive_fixed_divisor(x, *, batch: int, batches: int, rel: float, seed: int):
    """Adaptive sampling: batches of ``batch`` spp (a seed each) added to each pixel until the standard error of its
    mean (from its batch means) falls below ``rel`` of its luminance, after two batches at least; every pixel's sum
    then divided by the full ``batch * batches`` spp, those stopped early too (the light's own pixels, which never
    vary, stop after two)."""
    h, w = x.shape[:2]
    means = np.stack([_render(w, h, batch, seed + k) for k in range(batches)])
    lum = means @ programs._LUMA
    taken = np.full(lum.shape[1:], batches)
    done = np.zeros(lum.shape[1:], bool)
    for n in range(2, batches + 1):
        se = lum[:n].std(axis=0, ddof=1) / math.sqrt(n)
        stop = ~done & (se < rel * np.maximum(lum[:n].mean(axis=0), 1e-6))
        taken[stop] = n
        done |= stop
    kept = np.arange(batches)[:, None, None] < taken[None]
    return (means * kept[..., None]).sum(axis=0) / batches


def _passes_cumulative(x, *, passes: int, spp: int, seed: int):
    """``passes`` passes of ``spp`` (a seed each) into a pass buffer never cleared, the buffer added to the total
    after each pass, the total divided by the spp asked for: pass k counted ``passes - k`` times."""
    h, w = x.shape[:2]
    return sum((passes - k) * _render(w, h, spp, seed + k) for k in range(passes)) / passes


def _finish_order(rows: int, workers: int, seed: int) -> np.ndarray:
    """The order in which ``workers`` processes finish ``rows`` rows handed out in order (a pool's ``imap_unordered``,
    one row a task), each row's time 1 to 1.25 units (fixed by ``seed``)."""
    cost = 1.0 + 0.25 * np.random.default_rng(seed).random(rows)
    free = np.zeros(workers)
    finished = []
    for j in range(rows):
        k = int(np.argmin(free))
        free[k] += cost[j]
        finished.append((free[k], j))
    return np.array([j for _, j in sorted(finished)])


def _rows_unordered(x, *, workers: int, seed: int):
    """Row k of the image the k-th row to finish (``for k, row in enumerate(pool.imap_unordered(...))``)."""
    return np.asarray(x, np.float64)[_finish_order(x.shape[0], workers, seed)]


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _albedos_one_decimal(s):
    """Every Lambertian's albedo rounded to one decimal (Python's ``round(a, 1)``)."""
    from mcrt.scene import Lambertian

    def one(v):
        return tuple(round(float(a), 1) for a in v)

    room = replace(s.room, floor_albedo=one(s.room.floor_albedo), ceiling_albedo=one(s.room.ceiling_albedo),
                   walls=tuple(replace(w, albedo=one(w.albedo)) for w in s.room.walls))
    objs = tuple(replace(o, material=replace(o.material, albedo=one(o.material.albedo)))
                 if isinstance(o.material, Lambertian) else o for o in s.objects)
    return replace(s, room=room, objects=objs)


def _sphere_passes_rays(d: dict) -> dict:
    """The sphere as a dielectric of index 1 in a medium of index 1: every ray goes on as it came (two interactions,
    in and out, as the student's two mirror hits), shadow rays blocked by it."""
    return blind._sphere_bsdf(d, {"type": "dielectric", "int_ior": 1.0, "ext_ior": 1.0})


def _emitter(radiance) -> dict:
    return {"type": "area", "radiance": {"type": "rgb", "value": [float(a) for a in radiance]}}


def _ceiling_emits(d: dict) -> dict:
    """The ceiling given the light's material: black, emitting the light's radiance into the room."""
    from mcrt.mitsuba_scene import _mesh
    from mcrt.scene import load_scene

    return dict(d, ceiling=_mesh(fresh._surface("ceiling"), _BLACK, _emitter(load_scene().light.radiance)))


def _wall_fa_as_ef(s):
    """Wall FA given wall EF's albedo (the line above copied)."""
    ef = next(w.albedo for w in s.room.walls if "".join(w.corners) == "EF")
    return cases._wall_albedo(s, "FA", ef)


def _walls_top_at_zero(d: dict) -> dict:
    """Every wall's top corners at z = 0 (built from (x, y), z defaulting to 0), the ceiling where it was."""
    from mcrt.mitsuba_scene import _bsdf_dict
    from mcrt.scene import load_scene

    top = load_scene().room.ceiling_z
    for sf in load_scene().surfaces():
        if sf.name.startswith("wall_"):
            tris = np.array(sf.triangles, np.float64)
            tris[..., 2] = np.where(tris[..., 2] == top, 0.0, tris[..., 2])
            d = fresh._rebuilt(d, sf.name, tris, _bsdf_dict(sf.material))
    return d


def _box(lo, hi) -> np.ndarray:
    """(12, 3, 3): the axis-aligned box from ``lo`` to ``hi`` as triangles, two a face."""
    c = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    quads = ((0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3))
    return np.array([c[[q[0], q[1], q[2]]] for q in quads] + [c[[q[0], q[2], q[3]]] for q in quads])


def _tetra_bounding_box(d: dict) -> dict:
    """The tetrahedron replaced by its bounding box, of its material (the box test's hit taken for the object's)."""
    from mcrt.mitsuba_scene import _bsdf_dict

    sf = fresh._surface("tetrahedron")
    v = np.asarray(sf.triangles, np.float64).reshape(-1, 3)
    return fresh._rebuilt(d, "tetrahedron", _box(v.min(axis=0), v.max(axis=0)), _bsdf_dict(sf.material))


def _light_tris() -> np.ndarray:
    """(2, 3, 3): the light's two triangles as the scene builds them, wound to face down."""
    from mcrt.mitsuba_scene import _light_surface
    from mcrt.scene import load_scene

    return np.array(_light_surface(fresh._surface("light"), load_scene().light.normal).triangles, np.float64)


def _square(cx: float, cy: float, z: float, half: float) -> np.ndarray:
    """(2, 3, 3): a horizontal square about (cx, cy) at height z, wound to face down."""
    from mcrt.mitsuba_scene import _light_surface
    from mcrt.scene import Surface

    p = [(cx - half, cy - half, z), (cx + half, cy - half, z), (cx + half, cy + half, z), (cx - half, cy + half, z)]
    tris = np.array([[p[0], p[1], p[2]], [p[0], p[2], p[3]]], np.float64)
    return np.array(_light_surface(Surface("square", tris, None), (0.0, 0.0, -1.0)).triangles)


def _meshes(d: dict, **shapes) -> dict:
    """``d`` with meshes ``name=(triangles, emitted radiance or None)``, black, in place of or beside its own."""
    from mcrt.mitsuba_scene import _mesh
    from mcrt.scene import Surface

    return dict(d, **{name: _mesh(Surface(name, tris, None), _BLACK, None if le is None else _emitter(le))
                      for name, (tris, le) in shapes.items()})


def _light_first_triangle(d: dict) -> dict:
    """The light's first triangle emitting, its second black and dark (the emitter found by primitive index)."""
    from mcrt.scene import load_scene

    tris = _light_tris()
    return _meshes(d, light=(tris[:1], load_scene().light.radiance), light_second=(tris[1:], None))


def _light_seen_large(d: dict, *, f: float = 2.0) -> dict:
    """The light's square ``f`` times as wide (its size taken for its half-size), emitting: what the camera sees."""
    from mcrt.scene import load_scene

    lt = load_scene().light
    cx, cy, z = lt.center
    return _meshes(d, light=(_square(cx, cy, z, f * lt.size[0] / 2.0), lt.radiance))


def _light_sampled_under_large(d: dict, *, f: float = 2.0) -> dict:
    """The light's square ``f`` times as wide, black and dark, with the true square emitting just below it: what
    the rays after a bounce meet and what the light samples come from."""
    from mcrt.scene import load_scene

    lt = load_scene().light
    cx, cy, z = lt.center
    return _meshes(d, light=(_square(cx, cy, z, f * lt.size[0] / 2.0), None),
                   light_sampled=(_square(cx, cy, z - 1e-3, lt.size[0] / 2.0), lt.radiance))


# --------------------------------------------------------------------------
# Correct renders made in other ways
# --------------------------------------------------------------------------


def _mirrored(s):
    """The scene with y negated (a student's left-handed habit), its walls listed the other way round so that the
    room stays counter-clockwise: the image comes out mirrored left to right."""
    def flip(p):
        return (float(p[0]), float(-p[1])) + tuple(float(a) for a in p[2:])

    room = replace(s.room, corners={k: flip(v) for k, v in s.room.corners.items()},
                   walls=tuple(replace(w, corners=w.corners[::-1]) for w in reversed(s.room.walls)))
    objs = tuple(replace(o, center=flip(o.center)) if hasattr(o, "center")
                 else replace(o, vertices=tuple(flip(v) for v in o.vertices)) for o in s.objects)
    cams = {k: replace(c, eye=flip(c.eye), forward=flip(c.forward), up=flip(c.up)) for k, c in s.cameras.items()}
    return replace(s, room=room, objects=objs, light=replace(s.light, center=flip(s.light.center)), cameras=cams)


def _mcrt_scene(x, *, spp: int, seed: int, scene_edit=None, rr_depth: int = 5):
    """mcrt at the image's size of the scene ``scene_edit`` makes (rr_depth from which Russian roulette runs)."""
    from mcrt.render import render
    from mcrt.scene import load_scene

    h, w = x.shape[:2]
    s = load_scene()
    s = scene_edit(s) if scene_edit is not None else s
    settings = s.settings(camera="near", width=w, height=h, spp=spp, max_depth=8, rr_depth=rr_depth)
    return np.asarray(render(s, settings, seed=seed, progress=False).mean, np.float64)


def _mcrt_mirrored(x, *, spp: int, seed: int):
    """mcrt of the mirrored scene (:func:`_mirrored`), the image's columns flipped back."""
    return _mcrt_scene(x, spp=spp, seed=seed, scene_edit=_mirrored)[:, ::-1]


def _channels_lit_apart(x, *, spp: int, seed: int):
    """Three Mitsuba renders, the light emitting red, green and blue alone (the other channels 0), summed: light
    transport in RGB is linear in the light, channel by channel."""
    h, w = x.shape[:2]
    return sum(_render(w, h, spp, seed + c, scene_edit=cases.light(radiance=tuple(20.0 * (k == c) for k in range(3))))
               for c in range(3))


def _mcrt_and_mitsuba(x, *, spp: int, seed: int):
    """mcrt and Mitsuba, ``spp`` each (seeds apart), averaged."""
    h, w = x.shape[:2]
    return 0.5 * (_mcrt_scene(x, spp=spp, seed=seed) + _render(w, h, spp, seed + 1))


def _xyz_converted(x, *, spp: int, seed: int):
    """A Mitsuba render in CIE XYZ (the film's X, Y, Z), converted to linear sRGB by the student with Mitsuba's own
    ``xyz_to_srgb``."""
    import mitsuba as mi

    from mcrt.mitsuba_scene import render_with_variance, scene_dict
    from mcrt.scene import load_scene

    h, w = x.shape[:2]
    d = scene_dict(load_scene(), "near", w, h, 8, spp=spp)
    xyz = np.asarray(render_with_variance(d, spp=spp, seed=seed, space="xyz").mean, np.float32).reshape(-1, 3)
    rgb = mi.xyz_to_srgb(mi.Color3f(*(mi.Float(np.ascontiguousarray(xyz[:, c])) for c in range(3))))
    return np.stack([np.array(rgb[c], np.float64) for c in range(3)], axis=1).reshape(h, w, 3)


def _light_in_other_units(x, *, f: float, spp: int, seed: int):
    """Mitsuba with the light's radiance times ``f`` (the student's own units), the image divided by ``f``."""
    h, w = x.shape[:2]
    return _render(w, h, spp, seed, scene_edit=cases.light(radiance=(20.0 * f,) * 3)) / f


def _tga_top_left(codes: np.ndarray) -> bytes:
    """An uncompressed 24-bit TGA of ``codes`` (H, W, 3), top row first as its descriptor's origin bit (0x20) says,
    BGR."""
    import struct

    h, w = codes.shape[:2]
    head = struct.pack("<BBBHHBHHHHBB", 0, 0, 2, 0, 0, 0, 0, 0, w, h, 24, 0x20)
    return head + np.ascontiguousarray(codes[..., ::-1]).tobytes()


def _write_tga_top_left(image: np.ndarray, folder: Path) -> Path:
    path = folder / "render.tga"
    path.write_bytes(_tga_top_left(blind._srgb8(image)))
    return path


def _write_png16_rgba(image: np.ndarray, folder: Path) -> Path:
    """A 16-bit sRGB PNG with an opaque alpha channel (pypng)."""
    import png

    h, w = image.shape[:2]
    rgba = np.concatenate([untried._codes16(image), np.full((h, w, 1), 65535, np.uint16)], axis=2)
    path = folder / "render.png"
    with open(path, "wb") as fh:
        png.Writer(w, h, bitdepth=16, greyscale=False, alpha=True).write(fh, rgba.reshape(h, w * 4).tolist())
    return path


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_binomial_over_9", "pp_exponential_curve", "pp_caption_drawn", "pp_maximum_filter"),
    "file": ("file_png_viridis_mean", "file_ppm_p6_text_samples", "file_ppm_rows_planar", "file_png_bt709"),
    "materials": ("albedos_one_decimal", "mirror_direction_unused", "ceiling_light_material", "wall_fa_as_ef"),
    "geometry": ("sphere_normal_unnormalised", "walls_top_at_zero", "tetra_bounding_box"),
    "camera": ("eye_not_subtracted", "plane_minus_one_forgotten", "camera_rotation_transposed"),
    "light": ("light_seen_first_triangle", "shadow_rays_summed", "light_seen_twice_as_wide"),
    "integrator": ("mirror_for_camera_rays_only", "first_albedo_skipped", "sphere_not_in_shadow_test"),
    "samples": ("adaptive_full_divisor", "strata_isqrt_divided_by_asked", "pass_buffer_uncleared", "rows_unordered"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_binomial_over_9", "blur", True, **_posted("binomial_over_9", _binomial_over_9),
             truth="a 3 x 3 binomial blur written by hand, weights (1, 2, 1) x (1, 2, 1) divided by 9 for 16: "
             "blurred and 16/9 too bright, as EXR"),
        Spec("pp_exponential_curve", "tone_map", True, held_out=True, **_posted("exponential", _exponential),
             truth="an exponential tone curve 1 - exp(-x) before the EXR"),
        Spec("pp_caption_drawn", "bad_pixels", writer=_write_png_captioned, file="png-srgb-caption",
             truth="a caption '256 spp' drawn in white at the top left with Pillow's ImageDraw, then the 8-bit "
             "sRGB PNG saved"),
        Spec("pp_maximum_filter", "blur", held_out=True, **_posted("maximum_3x3", _max_filter),
             truth="scipy.ndimage.maximum_filter over 3 x 3 pixels (to fill dark speckles): bright areas a pixel "
             "wider, as EXR"),
        # Writing the file
        Spec("file_png_viridis_mean", "colour_lost", True, writer=_write_png_viridis, file="png-viridis-rgba",
             truth="matplotlib's imsave of the channels' mean (clipped to 1): false colour, the viridis map over "
             "the values' range, an RGBA PNG"),
        Spec("file_ppm_p6_text_samples", "file_format", True, held_out=True, writer=_write_ppm_p6_ascii,
             file="ppm-P6-text-samples",
             truth="a binary PPM's header (P6) over 8-bit sRGB samples written as text, a plain PPM's data"),
        Spec("file_ppm_rows_planar", "channels", True, writer=_write_ppm_rows_planar, file="ppm-rows-planar",
             truth="a PPM written by hand, the channel loop outside the column loop: each row's reds, greens, then "
             "blues, read as pixels (three squeezed copies of the row, one channel each)"),
        Spec("file_png_bt709", "encoding", held_out=True, writer=_write_png_bt709, file="png-bt709",
             truth="an 8-bit PNG encoded by the BT.709 camera curve (4.5 v, 1.099 v^0.45 - 0.099) for sRGB's: "
             "mid-tones about a quarter too dark once decoded"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    c = _crc
    return (
        # Materials
        Spec("albedos_one_decimal", "albedo", edit=_albedos_one_decimal,
             truth="every albedo rounded to one decimal (round(a, 1)): 0.15 to 0.1, 0.75 to 0.8, 0.45 to 0.5, ..."),
        Spec("mirror_direction_unused", "material", True, held_out=True, mitsuba_edit=_sphere_passes_rays,
             truth="the mirror's reflected direction computed and never used: rays go through the sphere as they "
             "came, its shadow kept"),
        Spec("ceiling_light_material", "object_emits", True, mitsuba_edit=_ceiling_emits,
             truth="the ceiling given the light's material (a material index off), its triangles among the lights "
             "with it: the whole ceiling black, emitting radiance 20"),
        Spec("wall_fa_as_ef", "albedo", True, held_out=True, edit=_wall_fa_as_ef,
             truth="wall FA (behind the camera) given wall EF's albedo (0.15, 0.70, 0.15) for (0.15, 0.65, 0.70): a "
             "copied line, seen in the mirror and in the light it reflects"),
        # Geometry
        Spec("sphere_normal_unnormalised", "normals", True, **_posted("sphere_normal_p_minus_c", partial(
            _traced, spp=256, seed=c("sphere_normal_unnormalised"), after=partial(_reflected, unnormalised=True))),
             truth="the sphere's normal p - c never divided by the radius: reflect(d, n) with n 1.5 long, the "
             "reflection bent towards the normal (camera rays; the room's rays off the sphere kept right)"),
        Spec("walls_top_at_zero", "object_shape", True, held_out=True, mitsuba_edit=_walls_top_at_zero,
             truth="the walls' top corners at z = 0 (built from (x, y), z defaulting to 0): the upper half of every "
             "wall open onto the void"),
        Spec("tetra_bounding_box", "object_shape", True, mitsuba_edit=_tetra_bounding_box,
             truth="the tetrahedron's bounding-box test's hit taken for the object's: an orange box in its place"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera model
        Spec("eye_not_subtracted", "camera_model", True, **_posted("direction_is_plane_point", partial(
            _traced, spp=256, seed=c("eye_not_subtracted"), camera=_eye_not_subtracted)),
             truth="the ray's direction the image-plane point itself, the eye never subtracted: every ray "
             "perpendicular to the view, the room's cross-section at the eye spread radially"),
        Spec("plane_minus_one_forgotten", "camera_model", True, held_out=True, **_posted("plane_from_0_to_2", partial(
            _traced, spp=256, seed=c("plane_minus_one_forgotten"), camera=_plane_without_minus_one)),
             truth="the pixel-to-plane mapping's - 1 forgotten in x (2 (i + u) / W): an off-axis view from the "
             "view's centre to 63.4 degrees right"),
        Spec("camera_rotation_transposed", "camera_rotation", True, **_posted("rotation_transposed", partial(
            _traced, spp=256, seed=c("camera_rotation_transposed"), camera=_rotation_transposed)),
             truth="the camera's rotation matrix applied transposed (rows for columns): the view along +y, the "
             "image turned"),
        # Light model
        Spec("light_seen_first_triangle", "light_seen", **_posted("light_seen_half", partial(
            _light_seen_from, spp=256, seed=c("light_seen_first_triangle"), seen_edit=_light_first_triangle)),
             truth="the emitter found by primitive index, only the light's first triangle registered: half of the "
             "light black where seen (and in the mirror), its light on surfaces right"),
        Spec("shadow_rays_summed", "light_pdf", True, held_out=True, **_posted("shadow_rays_summed", partial(
            unheard._light_direct_scaled, f=30.0, spp=256, seed=c("shadow_rays_summed"))),
             truth="30 shadow rays a vertex (the course report's), their light samples summed, not averaged: light on "
             "surfaces 30 times the truth, the light seen right"),
        Spec("light_seen_twice_as_wide", "light_seen", **_posted("light_seen_4x4", partial(
            _light_seen_from, spp=256, seed=c("light_seen_twice_as_wide"), seen_edit=_light_seen_large,
            rest_edit=_light_sampled_under_large)),
             truth="the light's hit test taking its size for its half-size: a 4 x 4 square seen (and blocking rays "
             "after a bounce), the 2 x 2 one sampled"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples and passes."""
    c = _crc
    return (
        # Integrator
        Spec("mirror_for_camera_rays_only", "material", **_posted("mirror_camera_only", partial(
            _traced, spp=256, seed=c("mirror_for_camera_rays_only"), after=_reflected,
            dict_edit=unmet._sphere_black)),
             truth="the mirror handled only for camera rays: a path meeting it after a bounce ends there (the light "
             "the sphere reflects into the room missing)"),
        Spec("first_albedo_skipped", "indirect_scale", True, held_out=True, **_posted("first_albedo_skipped", partial(
            _first_albedo_skipped, spp=256, seed=c("first_albedo_skipped"))),
             truth="the first surface's albedo left out of the throughput (if depth > 0: beta *= albedo): its direct "
             "light right, the light after it not coloured by it"),
        Spec("sphere_not_in_shadow_test", "light_pdf", True, **_posted("sphere_unshadowing", partial(
            _sphere_unshadowing, spp=256, seed=c("sphere_not_in_shadow_test"))),
             truth="the sphere left out of the shadow rays' test (the triangles only): no shadow of the sphere, the "
             "sphere itself right"),
        # Samples and passes
        Spec("adaptive_full_divisor", "sample_count", True, **_posted("adaptive_full_divisor", partial(
            _adaptive_fixed_divisor, batch=16, batches=16, rel=0.03, seed=c("adaptive_full_divisor"))),
             truth="adaptive sampling in batches of 16 spp until the standard error < 3 % of the luminance, every "
             "sum divided by 256: pixels stopped early dark (the light's after 32 spp, 1/8)"),
        Spec("strata_isqrt_divided_by_asked", "light_radiance", held_out=True, spp=484, declared_spp=500,
             **_posted("times_484_over_500", partial(_scaled, f=484.0 / 500.0)),
             truth="isqrt(500) = 22 strata a side, 484 samples summed and divided by the 500 asked for: 3.2 % dark, "
             "500 declared"),
        Spec("pass_buffer_uncleared", "light_radiance", True, **_posted("passes_cumulative", partial(
            _passes_cumulative, passes=4, spp=64, seed=c("pass_buffer_uncleared"))),
             truth="4 passes of 64 spp into a pass buffer never cleared, added to the total after each: passes "
             "weighted 4, 3, 2, 1, 2.5 times too bright"),
        Spec("rows_unordered", "row_stride", True, held_out=True, **_posted("rows_unordered", partial(
            _rows_unordered, workers=4, seed=c("rows_unordered"))),
             truth="rows rendered by a pool of 4 with imap_unordered, stored in the order they finished: rows "
             "swapped with their neighbours"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_mcrt_mirrored_world", None, spp=128, renderer="mcrt", **_posted("mcrt_mirrored", partial(
            _mcrt_mirrored, spp=128, seed=c("ok_mcrt_mirrored_world"))),
             truth="mcrt 128 spp of the scene with y negated (walls listed the other way round), the image's columns "
             "flipped back, EXR"),
        Spec("ok_channels_lit_apart", None, held_out=True, spp=256, **_posted("channels_lit_apart", partial(
            _channels_lit_apart, spp=256, seed=c("ok_channels_lit_apart"))),
             truth="three Mitsuba renders of 256 spp, the light red, green and blue alone, summed, EXR"),
        Spec("ok_mcrt_and_mitsuba", None, spp=256, renderer="mcrt", **_posted("mcrt_and_mitsuba", partial(
            _mcrt_and_mitsuba, spp=128, seed=c("ok_mcrt_and_mitsuba"))),
             truth="mcrt 128 spp and Mitsuba path 128 spp averaged: 256 declared, EXR"),
        Spec("ok_xyz_converted", None, held_out=True, spp=192, **_posted("xyz_to_srgb", partial(
            _xyz_converted, spp=192, seed=c("ok_xyz_converted"))),
             truth="Mitsuba path 192 spp rendered in CIE XYZ, converted to linear sRGB with Mitsuba's xyz_to_srgb, "
             "EXR"),
        Spec("ok_light_in_other_units", None, spp=160, **_posted("light_times_100", partial(
            _light_in_other_units, f=100.0, spp=160, seed=c("ok_light_in_other_units"))),
             truth="Mitsuba path 160 spp with the light's radiance in other units (times 100), the image divided by "
             "100, EXR"),
        Spec("ok_tga_top_left", None, held_out=True, spp=208, writer=_write_tga_top_left, file="tga-top-left",
             truth="Mitsuba path 208 spp, an 8-bit sRGB TGA written by hand, top row first (origin bit set)"),
        Spec("ok_png16_rgba", None, spp=144, writer=_write_png16_rgba, file="png16-srgb-rgba",
             truth="Mitsuba path 144 spp, a 16-bit sRGB PNG with an opaque alpha channel (pypng)"),
        Spec("ok_mcrt_no_roulette", None, held_out=True, spp=96, renderer="mcrt", **_posted("mcrt_no_roulette",
             partial(_mcrt_scene, spp=96, seed=c("ok_mcrt_no_roulette"), rr_depth=100)),
             truth="mcrt 96 spp without Russian roulette (rr_depth past the maximum depth), EXR"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "blur": "a filter after rendering (a binomial blur over the wrong count, a maximum filter)",
    "tone_map": "a curve on the values after rendering (an exponential tone curve)",
    "bad_pixels": "pixels overwritten after rendering (a caption drawn on the image)",
    "colour_lost": "colour lost in the file (the channels' mean written through a colour map)",
    "file_format": "the file's bytes not what its format says (text samples under a binary header)",
    "channels": "colour channels written in the wrong order (each row's channels one after another)",
    "encoding": "the values' encoding (another standard's curve for sRGB's)",
    "albedo": "a surface's colour (albedos rounded, a wall given another's colour)",
    "material": "a surface rendered with another material (the mirror's reflection never used, or used only for "
                "camera rays)",
    "object_emits": "a surface emitting light that should not (the ceiling given the light's material)",
    "normals": "surface normals wrong (the sphere's not of unit length)",
    "object_shape": "an object's shape wrong (walls cut short, a bounding box for the object)",
    "camera_model": "each pixel's ray wrong (the eye not subtracted, the pixel-to-plane mapping off)",
    "camera_rotation": "the camera's rotation (its matrix applied transposed)",
    "light_seen": "the light's own pixels (where the camera sees it) wrong, its light on surfaces right",
    "light_pdf": "the light sampled wrongly (its samples summed, not averaged; the sphere left out of the shadow "
                 "test): the light seen right, its light on surfaces not",
    "indirect_scale": "the indirect light off by a factor (the first surface's albedo left out of it), the direct "
                      "light right",
    "sample_count": "some pixels' sums divided by the spp, not by the samples they got (adaptive sampling)",
    "light_radiance": "the light's radiance (or a constant factor: samples or passes counted wrongly)",
    "row_stride": "pixels stored at the wrong places (rows in the order they finished)",
}
_WORDS = {**cases.CAUSES, **outside.CAUSES, **programs.NEW_CAUSES, **fresh.NEW_CAUSES, **blind.NEW_CAUSES,
          **unseen.NEW_CAUSES, **untried.NEW_CAUSES, **novel.NEW_CAUSES, **untold.NEW_CAUSES, **unmet.NEW_CAUSES,
          **unheard.NEW_CAUSES, **NEW_CAUSES, **_REWORDED}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = {c: _WORDS[c] for c in dict.fromkeys(s.cause for s in MISTAKES)}


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
