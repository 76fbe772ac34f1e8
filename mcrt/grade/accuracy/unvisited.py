r"""A twenty-first class of hand-ins: mistakes of students' tracers, scene input and output no class tried, blind.

How it was written: from what goes wrong in students' programs (the denoisers,
library tone maps, edge filters and grades run after rendering, the header
fields, shared exponents, dithers and 8-bit arithmetic of the files they
save, the BRDF's cosine and a PBR tutorial's diffuse factor, a typo in a
colour, the triangle normal, the objects' placement and a radius parsed as an
integer, a focal length's sensor, the camera basis's cross product and the
jitter's origin, a real-time light's attenuation, the light sample's variables
and the emission seen, the bounce's weight and random numbers, the roulette's
test, a clamp of the indirect light, the sample counter's dtype, an operator
typed for another, a weighted mean and a loop bound), not from the grader. Its
author read the other classes' specs and cause words, the catalogue
(:mod:`mcrt.mutants`), the scene files and design notes, mcrt's scene, camera
and image code, :data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to
stay clear of their mistakes; never the grader's rules (what decides a cause)
nor its reports, and graded none of it, not one case. Each cause and ``major``
flag was set from the mistake alone; every mistake is worded by a cause the
other classes already have (:data:`NEW_CAUSES` is empty), so ``SAME_MISTAKE``
needed no new entry. The mistakes differ from those of the twenty other
classes (:mod:`~mcrt.grade.accuracy.cases`, :mod:`~mcrt.grade.accuracy.outside`
and the modules of :data:`_EARLIER`, from :mod:`~mcrt.grade.accuracy.programs`
to :mod:`~mcrt.grade.accuracy.unbeknown`) and from the catalogue's bugs:

* **post-processing**: a Perona-Malik anisotropic diffusion written from a
  tutorial, against the noise; OpenCV's ``cv2.createTonemap(gamma=2.2)`` run
  on the render (the values stretched by their minimum and maximum, then
  gamma-encoded) and written as EXR; the Sobel gradient's magnitude added for
  crisper edges; an ASC CDL grade with a warm slope and a cool power;
* **writing the file**: a PFM whose header's scale is given the image's
  maximum (thought to record its range); a Radiance HDR with one exponent
  for the whole image (the "shared exponent" taken for the picture's); a
  dither of ``floor(v + u - 0.5)`` that leaves each code half a step low; two
  passes' 8-bit codes averaged as ``(a + b) // 2`` in ``uint8``;
* **materials**: the floor's albedo typed 0.06; Lambert's cosine folded into
  the BRDF and kept in the light sample's geometry term; every Lambertian
  weighted by one minus Schlick's Fresnel of the view (a PBR tutorial's
  ``kD``, its specular never added);
* **geometry**: the triangle normal ``cross(e1, e2)`` never normalised in the
  light sample's cosine; every object snapped onto the floor by a placement
  helper; the sphere's radius parsed with ``int()``;
* **camera**: the 90 degrees turned into a focal length with the sensor's
  height and back with its width; the camera's up re-derived as
  ``cross(forward, right)``; the jitter added to the pixel's centre;
* **light model**: an OpenGL tutorial's attenuation ``1 / (1 + 0.09 d +
  0.032 d^2)`` in the light sample; the light sample's geometry term taken at
  the light's centre (its shadow ray at the point drawn); the emission a
  camera ray sees added for a pixel's first sample only;
* **integrator**: the bounce's throughput multiplied by the pdf, not divided;
  Russian roulette's comparison flipped; one random number for both of the
  bounce's coordinates; each sample's indirect light clamped to 1;
* **samples and passes**: the sample counter a ``uint8`` (320 samples counted
  64); the spp typed ``2 ^ 8`` (XOR: 10); each pixel's samples averaged with
  ``np.average`` weighted by their luminance; 16 x 16 strata with the inner
  loop one short.

The correct hand-ins come in ways no class used: Mitsuba with the
tetrahedron meshed from ``itertools.permutations`` of its vertices (every face
six times), Mitsuba's ``moment`` integrator around the path tracer (its mean
channels kept), mcrt's render and a second seed's interleaved in a
checkerboard, a Radiance HDR stored bottom row first and right to left, a BMP
written by hand bottom-up, a PNG saved by Pillow without compression, Mitsuba
with sub-pixel offsets from SciPy's scrambled Sobol points (a scramble a
pixel), and Mitsuba with an RGBA film whose alpha is dropped.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s
``edit``), Mitsuba renders combined where light transport or pixel integrals
are linear in what is combined (paths of each length, the light seen),
Mitsuba's path integrator on sub-pixel offsets a student's loop makes
(:func:`mcrt.grade.accuracy.unforeseen._mean_through`), its first vertex's
direct light redone as a student's light sample makes it
(:func:`mcrt.grade.accuracy.unheralded._first_vertex`), its first bounce
redrawn (:func:`mcrt.grade.accuracy.unprompted._first_bounce`), its samples,
one by one, cut where a student's path changes (same-seed samples of max
depth 2 and 8, :func:`mcrt.grade.accuracy.unbeknown._camera_samples`) or
combined as a student's loop combines them
(:func:`mcrt.grade.accuracy.unbidden._all_samples`), or correct renders
post-processed and written with NumPy, SciPy, Pillow and the standard library
as students' programs do. mcrt renders only a correct hand-in.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over
:data:`CATEGORIES`: the 2nd, 4th, ... of each category and of the correct
hand-ins) are as in :mod:`~mcrt.grade.accuracy.unbeknown`, fixed before any
case was graded.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unbeknown, unbidden,
                                 unforeseen, unguessed, unheard, unheralded, unmet, unprompted, unsaid, unseen,
                                 unsought, untold, untried)
from mcrt.grade.accuracy.cases import Spec
from mcrt.image_files import srgb_eotf

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


#: The classes after the first two, in the order they were written (their causes' words are this class's too).
_EARLIER = (programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked, unsought,
            unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown)


def _crc(name: str) -> int:
    return 801000 + zlib.crc32(name.encode()) % 100000


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

#: The four neighbours a diffusion step looks at (row, column offsets).
_NEIGHBOURS = ((-1, 0), (1, 0), (0, -1), (0, 1))


def _perona_malik(x, *, iterations: int = 10, kappa: float = 0.1, step: float = 0.2):
    """Perona-Malik anisotropic diffusion by hand, each channel: ``iterations`` steps of ``img += step * sum(g(diff)
    * diff)`` over the 4 neighbours' differences, ``g(d) = exp(-(d / kappa)^2)`` (edges over kappa kept), the border
    replicated (``np.pad(mode='edge')``)."""
    u = np.asarray(x, np.float64).copy()
    h, w = u.shape[:2]
    for _ in range(iterations):
        p = np.pad(u, ((1, 1), (1, 1), (0, 0)), mode="edge")
        flux = np.zeros_like(u)
        for dy, dx in _NEIGHBOURS:
            diff = p[1 + dy:1 + dy + h, 1 + dx:1 + dx + w] - u
            flux += np.exp(-(diff / kappa) ** 2) * diff
        u += step * flux
    return u


def _opencv_tonemap(x, *, gamma: float = 2.2):
    """What ``cv2.createTonemap(gamma=2.2).process(img)`` does: the values mapped linearly from the image's minimum
    and maximum (over all channels) to [0, 1], then raised to 1 / gamma."""
    x = np.asarray(x, np.float64)
    lo, hi = x.min(), x.max()
    return ((x - lo) / (hi - lo)) ** (1.0 / gamma)


def _sobel_added(x, *, amount: float = 0.1):
    """The Sobel gradient's magnitude of each channel, ``np.hypot(sobel(c, 0), sobel(c, 1))`` (SciPy, edges
    reflected), added times ``amount`` for crisper edges."""
    from scipy.ndimage import sobel

    x = np.asarray(x, np.float64)
    mag = np.stack([np.hypot(sobel(x[..., c], 0), sobel(x[..., c], 1)) for c in range(3)], axis=-1)
    return x + amount * mag


#: The CDL grade's slope and power, (R, G, B): warmer highlights, a cooler fall-off.
_CDL_SLOPE, _CDL_POWER = (1.05, 1.0, 0.95), (1.0, 1.0, 1.1)


def _asc_cdl(x):
    """An ASC CDL grade, ``np.maximum(img * slope, 0) ** power`` (no offset), per channel."""
    return np.maximum(np.asarray(x, np.float64) * _CDL_SLOPE, 0.0) ** _CDL_POWER


# --------------------------------------------------------------------------
# Writers (the render in, the file a program writes)
# --------------------------------------------------------------------------


def _write_pfm_scale_max(image: np.ndarray, folder: Path) -> Path:
    """A little-endian PFM of the render as it is, its header's scale given minus the image's maximum (the field
    thought to record the range): a reader multiplies the data by that magnitude."""
    return fresh._write_pfm(image, folder, scale=f"{-float(np.max(image)):.6f}")


def _rgbe_one_exponent(image: np.ndarray) -> np.ndarray:
    """(H, W, 4) RGBE bytes with one exponent for the whole picture, ``frexp(img.max())``'s, every mantissa
    ``round(v * 256 / 2^e)`` clipped to 255: steps of 2^e / 256 (0.125 under a light of 20), values under half a step
    written 0."""
    a = np.maximum(np.nan_to_num(np.asarray(image, np.float64)), 0.0)
    _, e = np.frexp(a.max())
    out = np.zeros(a.shape[:2] + (4,), np.uint8)
    out[..., :3] = np.minimum(np.floor(a * 2.0 ** (8 - e) + 0.5), 255)
    out[..., 3] = e + 128
    return out


def _write_hdr_rle(rgbe: np.ndarray, folder: Path) -> Path:
    """A Radiance HDR of the (H, W, 4) RGBE bytes ``rgbe``, each scanline new-style run-length encoded (mcrt's
    encoder; flat, a pixel whose mantissas are (1, 1, 1) or (2, 2, b) would read as a run's marker), top row first."""
    from mcrt.image_files import _rle_channel

    h, w = rgbe.shape[:2]
    marker = bytes((2, 2, w >> 8, w & 255))
    body = b"".join(marker + b"".join(_rle_channel(rgbe[y, :, c]) for c in range(4)) for y in range(h))
    path = folder / "render.hdr"
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"-Y {h} +X {w}\n".encode() + body)
    return path


def _write_hdr_one_exponent(image: np.ndarray, folder: Path) -> Path:
    return _write_hdr_rle(_rgbe_one_exponent(image), folder)


def _dither_half_low(image: np.ndarray, *, seed: int = 0) -> np.ndarray:
    """8-bit sRGB codes dithered as ``np.floor(v * 255 + u - 0.5)``, u uniform (the - 0.5 of ``round(v + u - 0.5)``
    kept with ``floor``): each code half a step low on average."""
    u = np.random.default_rng(seed).random(image.shape)
    return np.clip(np.floor(unbeknown._srgb(image) * 255.0 + u - 0.5), 0, 255).astype(np.uint8)


def _write_png_dither_half_low(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_dither_half_low(image), folder)


def _passes_uint8_mean(x, *, spp: int, seed: int):
    """Two passes of ``spp / 2`` (a seed each) saved as 8-bit sRGB codes, then averaged as ``(a + b) // 2`` on the
    ``uint8`` arrays (NumPy keeps the dtype: a sum past 255 wraps): the linear values of those codes, which the
    case's sRGB PNG writes back exactly."""
    h, w = x.shape[:2]
    a, b = (blind._srgb8(_render(w, h, spp // 2, seed + k)) for k in range(2))
    return srgb_eotf((a + b) // 2 / 255.0)


# --------------------------------------------------------------------------
# Scene edits
# --------------------------------------------------------------------------


def _lowest_z(obj) -> float:
    return obj.center[2] - obj.radius if hasattr(obj, "radius") else min(v[2] for v in obj.vertices)


def _snapped_to_floor(s):
    """Every object moved down until its lowest point is on the floor (a placement helper's "rest on the ground"):
    the sphere 0.2, the tetrahedron 0.1."""
    for obj in s.objects:
        s = cases._moved(s, obj.name, (0.0, 0.0, s.room.floor_z - _lowest_z(obj)))
    return s


def _sphere_radius_int(s):
    """The sphere's radius parsed with ``int()`` (as the integer fields are): 1 for 1.5."""
    return replace(s, objects=tuple(replace(o, radius=float(int(o.radius))) if o.name == "sphere" else o
                                    for o in s.objects))


#: A full-frame sensor's width and height (mm).
_SENSOR = (36.0, 24.0)


def _fov_height_then_width(s):
    """The field of view turned into a focal length with the sensor's height (12 / tan 45 degrees: 12 mm) and back
    with its width (2 atan(18 / 12)): 112.6 degrees for 90."""
    focal = _SENSOR[1] / 2.0 / math.tan(math.radians(s.cameras["near"].fov_x_deg) / 2.0)
    return cases._camera(s, fov_x_deg=math.degrees(2.0 * math.atan(_SENSOR[0] / 2.0 / focal)))


def _rows_flipped(x):
    """The camera's up re-derived as ``cross(forward, right)`` for ``cross(right, forward)`` (right kept): the up
    negated alone, each row's rays through the mirror row's place, the image upside down."""
    return np.asarray(x)[::-1]


def _tetra_permutations(d: dict) -> dict:
    """The tetrahedron meshed from ``itertools.permutations(vertices, 3)``: each of its faces six times, in both
    windings (two-sided)."""
    from itertools import permutations

    from mcrt.mitsuba_scene import _bsdf_dict

    tetra = next(o for o in _scene().objects if o.name == "tetrahedron")
    tris = np.array([[tetra.vertices[i] for i in p] for p in permutations(range(4), 3)], np.float64)
    return fresh._rebuilt(d, "tetrahedron", tris, _bsdf_dict(tetra.material))


# --------------------------------------------------------------------------
# Sub-pixel offsets (rng, samples a pixel n) -> (u, v), each (pixels, n)
# --------------------------------------------------------------------------


def _centre_plus_jitter(rng, n: int, *, w: int, pixels: int):
    """The jitter added to the pixel's centre, ``i + 0.5 + u``: offsets in [0.5, 1.5) of the pixel."""
    u, v = rng.random((2, pixels, n))
    return u + 0.5, v + 0.5


def _rows_short(rng, n: int, *, w: int, pixels: int, of: int = 16):
    """Offsets over the strata ``range(16)`` x ``range(15)`` (the inner loop one short): v in [0, 15/16), uniform
    there (the mean the jittered strata give)."""
    u, v = rng.random((2, pixels, n))
    return u, v * (of - 1) / of


def _scipy_sobol(rng, n: int, *, w: int, pixels: int):
    """Offsets from ``scipy.stats.qmc.Sobol(2, scramble=True)``, a new scramble each pixel (and chunk)."""
    from scipy.stats import qmc

    pts = np.stack([qmc.Sobol(2, scramble=True, rng=rng).random(n) for _ in range(pixels)])
    return pts[..., 0], pts[..., 1]


def _strata_short(x, *, spp: int, seed: int, of: int = 16):
    """``of`` x ``of`` strata a pixel with the inner loop ``range(of - 1)``: ``spp (of - 1) / of`` samples, their
    sum divided by ``spp``."""
    kept = spp * (of - 1) // of
    return unforeseen._mean_through(x, spp=kept, seed=seed, jitter=partial(_rows_short, of=of)) * kept / spp


# --------------------------------------------------------------------------
# Light samples at the first vertex (unheralded._first_vertex's ``direct``)
# --------------------------------------------------------------------------


def _cos_twice(p, n, q) -> np.ndarray:
    """The geometry term times the BRDF's own cosine (f = albedo cos / pi): cos_s^2 cos_l / d^2."""
    return unbeknown._geometry(p, n, q) * np.maximum(np.einsum("ij,ij->i", n, unsaid._unit(q - p)), 0.0)


#: OpenGL tutorials' constant, linear and quadratic attenuation for a range of 50.
_ATTENUATION = (1.0, 0.09, 0.032)


def _attenuated(p, n, q) -> np.ndarray:
    """The geometry term divided by ``1 + 0.09 d + 0.032 d^2`` (a point light's attenuation kept on the area light)."""
    d = np.linalg.norm(q - p, axis=1)
    k0, k1, k2 = _ATTENUATION
    return unbeknown._geometry(p, n, q) / (k0 + k1 * d + k2 * d * d)


def _from_centre(p, n, q) -> np.ndarray:
    """The geometry term with the light's centre for the point drawn (``to_light`` computed once from the centre;
    the shadow ray, :func:`mcrt.grade.accuracy.unbeknown._light_sampled`'s, still goes to the point drawn)."""
    return unbeknown._geometry(p, n, np.broadcast_to(np.asarray(_scene().light.center, np.float64), q.shape))


def _doubled_areas(p: np.ndarray) -> np.ndarray:
    """(N,): ``|cross(e1, e2)|`` (twice the area) of the Lambertian triangle each point lies on or within 1e-3 of (the
    room's and the tetrahedron's faces as mcrt's scene triangulates them); 1 where none."""
    from mcrt.scene import Lambertian

    out = np.ones(len(p))
    for sf in _scene().surfaces():
        if not isinstance(sf.material, Lambertian):
            continue
        for a, b, c in np.asarray(sf.triangles, np.float64):
            e1, e2, rel = b - a, c - a, p - a
            cr = np.cross(e1, e2)
            d00, d01, d11 = e1 @ e1, e1 @ e2, e2 @ e2
            s, t = rel @ e1, rel @ e2
            den = d00 * d11 - d01 * d01
            v, w = (d11 * s - d01 * t) / den, (d00 * t - d01 * s) / den
            on = (np.abs(rel @ cr) < 1e-3 * np.linalg.norm(cr)) & (v >= -1e-6) & (w >= -1e-6) & (v + w <= 1 + 1e-6)
            out[on] = np.linalg.norm(cr)
    return out


def _normal_unnormalised(mscene, rng, p, n, rho, mitsuba):
    """The light sample with the triangle's normal ``cross(e1, e2)`` never normalised in its cosine: Mitsuba's direct
    light times twice the triangle's area."""
    return mitsuba * _doubled_areas(p)[:, None]


# --------------------------------------------------------------------------
# Bounces at the first vertex (unprompted._first_bounce's ``draw``)
# --------------------------------------------------------------------------


def _times_pdf(rng, n):
    """Cosine-weighted directions whose weight is ``f cos * pdf`` for ``f cos / pdf``: (albedo / pi) cos (cos / pi),
    the albedo times cos^2 / pi^2."""
    d, cos = unprompted._cosine_directions(rng, n)
    return d, (cos / math.pi) ** 2


def _one_number(rng, n):
    """Cosine-weighted directions from one random number for both coordinates, r = sqrt(u), phi = 2 pi u (u1 reused
    for u2): a spiral of directions, weighted by the albedo."""
    u = rng.random(len(n))
    r, phi = np.sqrt(u), 2.0 * math.pi * u
    t, b = unforeseen._frame_of(n)
    d = (r * np.cos(phi))[:, None] * t + (r * np.sin(phi))[:, None] * b + np.sqrt(1.0 - u)[:, None] * n
    return d, np.ones(len(n))


# --------------------------------------------------------------------------
# Samples cut, weighted or counted as a student's loop does
# --------------------------------------------------------------------------


def _schlick(cos: np.ndarray, f0: float = 0.04) -> np.ndarray:
    return f0 + (1.0 - f0) * (1.0 - cos) ** 5


def _fresnel_kd_sample(o, d, seed, *, full, seen):
    """A sample whose first diffuse hit's light (the sample less the emission the ray sees, same seed) is times ``1 -
    F(cos)``, Schlick's Fresnel (F0 0.04) of the angle to the eye."""
    L, le = unsaid._sampled(full, o, d, seed), unsaid._sampled(seen, o, d, seed)
    kd = np.ones(len(o))
    sel = unbeknown._diffuse_first(full, o, d)
    if sel.any():
        kd[sel] = 1.0 - _schlick(-np.einsum("ij,ij->i", unforeseen._first_normal(full, o[sel], d[sel]), d[sel]))
    return le + kd[:, None] * (L - le)


def _fresnel_kd(x, *, spp: int, seed: int):
    """Every Lambertian weighted by ``kD = 1 - F`` (a PBR tutorial's energy split, its specular never added), where a
    camera ray meets a Lambertian first (Mitsuba's path after it)."""
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(
        _fresnel_kd_sample, full=unsaid._loaded(_DEPTH), seen=unsaid._loaded(1)))


def _indirect_clamped_sample(o, d, seed, *, full, direct, limit: float = 1.0):
    """A sample whose light of 3 or more segments (the sample less the same seed's max-depth-2 sample) is clamped
    to ``limit``, channel by channel."""
    near = unsaid._sampled(direct, o, d, seed)
    return near + np.minimum(unsaid._sampled(full, o, d, seed) - near, limit)


def _indirect_clamped(x, *, spp: int, seed: int):
    """Each sample's indirect light clamped to 1 (a production renderer's indirect clamp against fireflies), its
    direct light and the light seen kept."""
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(
        _indirect_clamped_sample, full=unsaid._loaded(_DEPTH), direct=unsaid._loaded(2)))


def _light_seen_once(x, *, spp: int, seed: int):
    """The emission a camera ray meets added for a pixel's first sample only (``if depth == 0 and s == 0``, the sum
    divided by the spp): a render less all but 1 / spp of its max-depth-1 render, same seed (the same camera
    rays)."""
    h, w = x.shape[:2]
    return _render(w, h, spp, seed) - (1.0 - 1.0 / spp) * _render(w, h, spp, seed, max_depth=1)


def _roulette_flipped(x, *, spp: int, seed: int, survival: float = 0.8):
    """Russian roulette from the 3rd vertex with survival 0.8 whose test is flipped (the path goes on when ``u >
    0.8``), the survivors divided by 0.8: each test weighs what follows q = 0.2 / 0.8 = 1 / 4. The paths of k
    segments weigh q^(k - 4): :func:`mcrt.grade.accuracy.unbeknown._roulette_one_number`'s weights
    ``s^(first + 2 - k)`` with s = 1 / q from ``first`` 2 (the same renders, Mitsuba's roulette off)."""
    return unbeknown._roulette_one_number(x, spp=spp, seed=seed, survival=survival / (1.0 - survival), first=2)


def _count_wrapped(x, *, spp: int):
    """Each pixel's sum divided by its sample count kept in a ``uint8`` (``np.zeros((H, W), np.uint8)``, ``+= 1``
    a sample): ``spp mod 256`` for ``spp``."""
    return np.asarray(x, np.float64) * spp / (spp % 256)


def _luminance_weighted(x, *, spp: int, seed: int):
    """Each pixel ``np.average(samples, axis=0, weights=luminance)`` (Rec. 709 luminance of each sample; a pixel
    whose samples are all black 0): the bright samples weigh more."""
    h, w = x.shape[:2]
    L = unbidden._all_samples(w, h, spp, seed)
    wt = L @ programs._LUMA
    total = wt.sum(axis=1)
    return (np.einsum("ij,ijc->ic", wt, L) / np.where(total > 0.0, total, 1.0)[:, None]).reshape(h, w, 3)


# --------------------------------------------------------------------------
# Correct renders made in other ways
# --------------------------------------------------------------------------


def _mitsuba_edited(x, *, spp: int, seed: int, edit):
    """Mitsuba's own ``mi.render`` of the scene's dict as ``edit`` changes it, its first three channels."""
    import mitsuba as mi

    from mcrt.mitsuba_scene import scene_dict

    h, w = x.shape[:2]
    d = edit(scene_dict(_scene(), "near", w, h, _DEPTH, spp=spp))
    return np.asarray(mi.render(mi.load_dict(d), spp=spp, seed=seed), np.float64)[..., :3]


def _moment(d: dict) -> dict:
    """Mitsuba's ``moment`` integrator around the path tracer (channels R, G, B, then its moments in XYZ)."""
    return dict(d, integrator={"type": "moment", "nested": d["integrator"]})


def _rgba_film(d: dict) -> dict:
    """The film's pixel format RGBA (an alpha of 1 everywhere after R, G, B)."""
    return dict(d, sensor=dict(d["sensor"], film=dict(d["sensor"]["film"], pixel_format="rgba")))


def _mcrt_checkerboard(x, *, spp: int, seed: int):
    """mcrt's render (``x``) and a second seed's interleaved in a checkerboard (two machines, alternate pixels)."""
    other = unsaid._mcrt_scene(x, spp=spp, seed=seed + 1)
    jj, ii = np.indices(x.shape[:2])
    return np.where(((ii + jj) % 2 == 0)[..., None], np.asarray(x, np.float64), other)


def _write_hdr_turned(image: np.ndarray, folder: Path) -> Path:
    """A Radiance HDR written by hand, flat, with the resolution line ``+Y H -X W``: the bottom row first, each row
    right to left (mcrt's RGBE encoding, a SOFTWARE line in the header)."""
    from mcrt.image_files import _rgbe_encode

    h, w = image.shape[:2]
    path = folder / "render.hdr"
    rgbe = _rgbe_encode(path, np.nan_to_num(np.asarray(image, np.float64))[::-1, ::-1])
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nSOFTWARE=student tracer\n\n"
                     + f"+Y {h} -X {w}\n".encode() + rgbe.tobytes())
    return path


def _write_bmp_bottom_up(image: np.ndarray, folder: Path) -> Path:
    """A 24-bit BMP written by hand as the format stores it: bottom row first, BGR, rows padded to 4 bytes."""
    path = folder / "render.bmp"
    path.write_bytes(blind._bmp_bytes(blind._srgb8(image), rows_top_first=False))
    return path


def _write_png_stored(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB PNG saved by Pillow with ``compress_level=0`` (deflate's stored blocks, no compression)."""
    from PIL import Image

    path = folder / "render.png"
    Image.fromarray(blind._srgb8(image), "RGB").save(path, format="PNG", compress_level=0)
    return path


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_perona_malik_diffusion", "pp_opencv_tonemap_gamma", "pp_sobel_edges_added",
                        "pp_asc_cdl_grade"),
    "file": ("file_pfm_scale_as_maximum", "file_hdr_one_exponent_for_image", "file_png_dither_half_code_low",
             "file_png_passes_uint8_mean"),
    "materials": ("floor_albedo_typed_0_06", "light_sample_cosine_squared", "lambert_fresnel_kd"),
    "geometry": ("triangle_normal_unnormalised", "objects_snapped_to_floor", "sphere_radius_int"),
    "camera": ("fov_focal_from_height", "camera_up_cross_reversed", "jitter_added_to_centre"),
    "light": ("light_opengl_attenuation", "light_geometry_from_centre", "light_seen_once_per_pixel"),
    "integrator": ("bounce_times_pdf", "roulette_comparison_flipped", "bounce_one_number",
                   "indirect_clamped_per_sample"),
    "samples": ("sample_count_uint8", "spp_xor_typed", "pixel_luminance_weighted_mean", "strata_inner_loop_short"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    c = _crc
    return (
        # Post-processing
        Spec("pp_perona_malik_diffusion", "blur", **_posted("perona_malik", _perona_malik),
             truth="Perona-Malik anisotropic diffusion written from a tutorial against the noise, 10 steps of 0.2 "
             "with the conductance exp(-(d / 0.1)^2) on each channel, as EXR: the noise of the dim surfaces "
             "smoothed away, the edges over 0.1 kept, the bright surfaces' noise mostly kept"),
        Spec("pp_opencv_tonemap_gamma", "tone_map", True, held_out=True, **_posted("opencv_tonemap", _opencv_tonemap),
             truth="cv2.createTonemap(gamma=2.2).process(img) run on the render before the EXR (taken for the "
             "display conversion): the values mapped linearly from the image's minimum and maximum (the light) to "
             "[0, 1], then raised to 1 / 2.2: the light 1, a wall of 0.3 about 0.17, the room far darker"),
        Spec("pp_sobel_edges_added", "sharpen", **_posted("sobel_added", _sobel_added),
             truth="the Sobel gradient's magnitude of each channel (scipy.ndimage.sobel along the rows and the "
             "columns, np.hypot) added times 0.1 for crisper edges, as EXR: bright rims on both sides of every edge, "
             "about the light several times its own brightness, the noisy surfaces a little brighter"),
        Spec("pp_asc_cdl_grade", "colour_grade", held_out=True, **_posted("asc_cdl", _asc_cdl),
             truth="an ASC CDL grade for the look, np.maximum(img * (1.05, 1.0, 0.95), 0) ** (1.0, 1.0, 1.1), as "
             "EXR: red 5 % up, blue 5 % down and raised to 1.1 (the dark blues darker still, the light's blue 25 "
             "for 20)"),
        # Writing the file
        Spec("file_pfm_scale_as_maximum", "light_radiance", True, writer=_write_pfm_scale_max, file="pfm-scale-max",
             truth="a little-endian PFM of the render as rendered, its header's scale written as minus the image's "
             "maximum (about -20, the field thought to record the values' range): a reader multiplies the data by "
             "the scale's magnitude, every value about 20 times too bright"),
        Spec("file_hdr_one_exponent_for_image", "quantisation", True, held_out=True, writer=_write_hdr_one_exponent,
             file="hdr-one-exponent",
             truth="a run-length encoded Radiance HDR written by hand with one exponent for the whole picture, "
             "frexp(img.max())'s (the 'shared exponent' taken for the image's), every mantissa round(v * 256 / "
             "2^e): values in steps of 0.125 (the light near 20), everything under 0.0625 black, the room in a few "
             "bands"),
        Spec("file_png_dither_half_code_low", "quantisation", writer=_write_png_dither_half_low, file="png-dither-low",
             truth="an 8-bit sRGB PNG dithered with np.floor(v * 255 + u - 0.5), u uniform (round's - 0.5 kept with "
             "floor): each code half a step low on average, the dark parts a few per cent too dark, the mid-tones "
             "about 1 %"),
        Spec("file_png_passes_uint8_mean", "code_overflow", True, held_out=True, file="png-srgb", **_posted(
            "passes_uint8", partial(_passes_uint8_mean, spp=_S, seed=c("file_png_passes_uint8_mean"))),
             truth="two passes of 128 spp saved as 8-bit sRGB codes, averaged as (a + b) // 2 on the uint8 arrays, "
             "an 8-bit PNG: a sum past 255 wraps, every pixel whose codes add up to 256 or more (linear about 0.2 "
             "and over) dark, the light and the lit surfaces' brightest parts nearly black"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    c = _crc
    return (
        # Materials
        Spec("floor_albedo_typed_0_06", "albedo", True, edit=cases.floor_albedo((0.06, 0.06, 0.06)),
             truth="the floor's albedo typed 0.06 for 0.6 (a zero slipped in): the floor nearly black, the walls' "
             "lower parts and the ceiling a little darker without its light"),
        Spec("light_sample_cosine_squared", "material", True, held_out=True, **_posted("cosine_squared", partial(
            unheralded._first_vertex, spp=_S, seed=c("light_sample_cosine_squared"),
            direct=partial(unbeknown._light_sampled, geometry=_cos_twice))),
             truth="Lambert's cosine folded into the BRDF (f = albedo cos / pi) and the light sample's geometry term "
             "keeping its own: cos^2 at the surface in the light sample (the bounce's weight, the albedo, right), "
             "at the first surface a camera ray meets (Mitsuba's path after it): the direct light darker the more "
             "obliquely it arrives (the walls' most), the floor under the light nearly right"),
        Spec("lambert_fresnel_kd", "material", **_posted("fresnel_kd", partial(
            _fresnel_kd, spp=_S, seed=c("lambert_fresnel_kd"))),
             truth="every Lambertian weighted by kD = 1 - F, Schlick's Fresnel of the angle to the eye (F0 0.04, a "
             "PBR tutorial's energy split whose specular term was never added), where a camera ray meets a "
             "Lambertian first (Mitsuba's path after it): surfaces seen head-on 4 % dark, the floor seen obliquely "
             "about a fifth darker at the image's bottom edge"),
        # Geometry
        Spec("triangle_normal_unnormalised", "normals", True, **_posted("normal_unnormalised", partial(
            unheralded._first_vertex, spp=_S, seed=c("triangle_normal_unnormalised"), direct=_normal_unnormalised)),
             truth="the triangle's normal cross(e1, e2) never normalised where the light sample takes its cosine "
             "(the bounce's frame normalises its own), at the first surface a camera ray meets (Mitsuba's path "
             "after it): each face's direct light times twice its triangle's area, the walls and the floor tens "
             "of times too bright triangle by triangle, the light seen right"),
        Spec("objects_snapped_to_floor", "object_moved", held_out=True, edit=_snapped_to_floor,
             truth="every object moved down until its lowest point is on the floor (a placement helper's 'rest on "
             "the ground', left on): the sphere 0.2 lower, touching the floor, the tetrahedron 0.1 lower, its base "
             "on the floor, their shadows' contact regions darker"),
        Spec("sphere_radius_int", "object_size", True, edit=_sphere_radius_int,
             truth="the sphere's radius parsed with int() as the scene's integer fields are: 1 for 1.5, the mirror "
             "ball two thirds its size, its centre where it was, 0.7 above the floor"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera
        Spec("fov_focal_from_height", "camera_fov", True, edit=_fov_height_then_width,
             truth="the field of view turned into a 35 mm focal length with the sensor's height 24 mm (12 / tan 45 "
             "degrees: 12 mm) and back into a field of view with its width 36 mm: 2 atan(18 / 12) = 112.6 degrees "
             "for 90, the room seen wide, its middle smaller"),
        Spec("camera_up_cross_reversed", "camera_rotation", True, held_out=True, **_posted("up_reversed",
                                                                                       _rows_flipped),
             truth="the camera's up re-derived as cross(forward, right) for cross(right, forward), the right kept: "
             "the up vector negated alone, the image upside down (not turned), the floor at the top"),
        Spec("jitter_added_to_centre", "pixel_offset", **_posted("jitter_from_centre", partial(
            unforeseen._mean_through, spp=_S, seed=c("jitter_added_to_centre"), jitter=_centre_plus_jitter)),
             truth="the jitter added to the pixel's centre, (i + 0.5 + u) / W with u in [0, 1): each pixel's samples "
             "over the square half a pixel right of and below it, the image half a pixel up and left"),
        # Light model
        Spec("light_opengl_attenuation", "light_model", True, **_posted("opengl_attenuation", partial(
            unheralded._first_vertex, spp=_S, seed=c("light_opengl_attenuation"),
            direct=partial(unbeknown._light_sampled, geometry=_attenuated))),
             truth="an OpenGL tutorial's point-light attenuation 1 / (1 + 0.09 d + 0.032 d^2) kept in the area "
             "light's sample, at the first surface a camera ray meets (Mitsuba's path after it): the direct light on "
             "surfaces 2 to 5 times too dark, the more the farther from the light, the light seen right"),
        Spec("light_geometry_from_centre", "light_pdf", held_out=True, **_posted("geometry_from_centre", partial(
            unheralded._first_vertex, spp=_S, seed=c("light_geometry_from_centre"),
            direct=partial(unbeknown._light_sampled, geometry=_from_centre))),
             truth="the light sample's cosines and distance computed once from the light's centre (to_light = "
             "light.center - p), the shadow ray to the point drawn on the light, at the first surface a camera ray "
             "meets (Mitsuba's path after it): the soft shadows kept, the light on surfaces a few per cent off near "
             "the light, the light seen right"),
        Spec("light_seen_once_per_pixel", "light_seen", **_posted("seen_once", partial(
            _light_seen_once, spp=_S, seed=c("light_seen_once_per_pixel"))),
             truth="the emission a camera ray meets added for a pixel's first sample only (if depth == 0 and s == "
             "0, meant to add a constant once), the sum divided by 256: the light's own pixels 0.08 for 20, its "
             "reflection in the mirror and its light on surfaces right"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples, passes and counters."""
    c = _crc
    return (
        # Integrator
        Spec("bounce_times_pdf", "indirect_scale", True, **_posted("bounce_times_pdf", partial(
            unprompted._first_bounce, spp=_S, seed=c("bounce_times_pdf"), draw=_times_pdf)),
             truth="the diffuse bounce's throughput multiplied by the pdf, beta *= f * cos * pdf for f * cos / "
             "pdf, at the first surface a camera ray meets (Mitsuba's path after it): each bounce weighs albedo "
             "cos^2 / pi^2 for albedo, the indirect light nearly gone, the ceiling black, the direct light right"),
        Spec("roulette_comparison_flipped", "roulette", True, held_out=True, **_posted("roulette_flipped", partial(
            _roulette_flipped, spp=_S, seed=c("roulette_comparison_flipped"))),
             truth="Russian roulette from the 3rd vertex with survival 0.8 whose test is flipped (the path goes on "
             "when u > 0.8), the survivors divided by 0.8: each test keeps a quarter of what follows, the light of "
             "paths of 5 or more segments a quarter, a sixteenth, ...: the indirect light too dark, the ceiling "
             "most"),
        Spec("bounce_one_number", "indirect_scale", **_posted("bounce_one_number", partial(
            unprompted._first_bounce, spp=_S, seed=c("bounce_one_number"), draw=_one_number)),
             truth="the cosine-weighted bounce drawn from one random number for both coordinates (r = sqrt(u), phi = "
             "2 pi u, u1 reused for u2), at the first surface a camera ray meets (Mitsuba's path after it): the "
             "directions on one spiral about the normal, the indirect light biased by where the spiral looks"),
        Spec("indirect_clamped_per_sample", "sample_clamp", held_out=True, **_posted("indirect_clamped", partial(
            _indirect_clamped, spp=_S, seed=c("indirect_clamped_per_sample"))),
             truth="each sample's indirect light (paths of 3 or more segments) clamped to 1, channel by channel, "
             "against fireflies (a production renderer's indirect clamp): the light seen and the direct light "
             "right, the indirect light's bright samples cut, the ceiling and the shadows a little dark"),
        # Samples, passes and counters
        Spec("sample_count_uint8", "light_radiance", True, spp=320, **_posted("count_uint8", partial(
            _count_wrapped, spp=320)),
             truth="320 spp with each pixel's sample count kept in a uint8 array (count += 1 a sample wraps at "
             "256): the sum divided by 64 for 320, every pixel 5 times too bright"),
        Spec("spp_xor_typed", "spp_claim", True, held_out=True, spp=2 ^ 8, declared_spp=256,
             truth="the spp typed SPP = 2 ^ 8 (Python's XOR: 10) for 2 ** 8, the manifest's 256 typed by hand: 10 "
             "spp rendered, 256 declared, the image right but for its noise"),
        Spec("pixel_luminance_weighted_mean", "biased_estimator", True, **_posted("luminance_weighted", partial(
            _luminance_weighted, spp=_S, seed=c("pixel_luminance_weighted_mean"))),
             truth="each pixel np.average(samples, axis=0, weights=luminance) (the weights taken for importance): a "
             "sample's weight its own brightness, the mean of L^2 over the mean of L: every pixel whose samples "
             "vary too bright, the ceiling (lit by bounces alone) several times, the light's edges too bright"),
        Spec("strata_inner_loop_short", "light_radiance", held_out=True, **_posted("strata_short", partial(
            _strata_short, spp=_S, seed=c("strata_inner_loop_short"))),
             truth="16 x 16 strata a pixel with the inner loop range(15) for range(16): 240 samples, the bottom "
             "sixteenth of each pixel never sampled, the sum divided by 256: 6 % dark everywhere, the light 18.75"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_tetra_permutations", None, spp=216, mitsuba_edit=_tetra_permutations,
             truth="Mitsuba path 216 spp with the tetrahedron meshed from itertools.permutations of its vertices "
             "(24 triangles: each face six times, in both windings), EXR"),
        Spec("ok_moment_integrator", None, held_out=True, spp=184, **_posted("moment", partial(
            _mitsuba_edited, spp=184, seed=c("ok_moment_integrator"), edit=_moment)),
             truth="Mitsuba's moment integrator around the path tracer, 184 spp, its R, G, B channels kept (the "
             "moments dropped), EXR"),
        Spec("ok_mcrt_checkerboard_seeds", None, spp=88, renderer="mcrt", **_posted("checkerboard", partial(
            _mcrt_checkerboard, spp=88, seed=c("ok_mcrt_checkerboard_seeds"))),
             truth="mcrt 88 spp rendered twice with two seeds (two machines), the pixels taken alternately in a "
             "checkerboard, EXR"),
        Spec("ok_hdr_turned_storage", None, held_out=True, spp=164, writer=_write_hdr_turned, file="hdr-turned",
             truth="Mitsuba path 164 spp, a Radiance HDR written by hand with the resolution line +Y H -X W (the "
             "bottom row first, each row right to left) and a SOFTWARE line"),
        Spec("ok_bmp_bottom_up_by_hand", None, spp=196, writer=_write_bmp_bottom_up, file="bmp-bottom-up",
             truth="Mitsuba path 196 spp, a 24-bit sRGB BMP written by hand as the format stores it: bottom row "
             "first, BGR, rows padded to 4 bytes"),
        Spec("ok_png_stored_deflate", None, held_out=True, spp=244, writer=_write_png_stored, file="png-stored",
             truth="Mitsuba path 244 spp, an 8-bit sRGB PNG saved by Pillow with compress_level=0 (deflate's stored "
             "blocks)"),
        Spec("ok_scipy_sobol_offsets", None, **_posted("scipy_sobol", partial(
            unforeseen._mean_through, spp=_S, seed=c("ok_scipy_sobol_offsets"), jitter=_scipy_sobol)),
             truth="Mitsuba path 256 spp, sub-pixel offsets from scipy.stats.qmc.Sobol(2, scramble=True), a new "
             "scramble each pixel, EXR"),
        Spec("ok_rgba_film", None, held_out=True, spp=172, **_posted("rgba_film", partial(
            _mitsuba_edited, spp=172, seed=c("ok_rgba_film"), edit=_rgba_film)),
             truth="Mitsuba's mi.render 172 spp with the film's pixel format RGBA, the alpha channel dropped, EXR"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "blur": "a filter after rendering (an anisotropic diffusion against the noise)",
    "tone_map": "a tone map applied before saving (OpenCV's tone map: the values stretched, then gamma-encoded)",
    "sharpen": "a sharpening filter after rendering (the gradient's magnitude added)",
    "colour_grade": "the colours graded after rendering (an ASC CDL grade)",
    "light_radiance": "the light's radiance or a constant factor (a PFM's scale, a sample counter wrapped, a loop "
                      "one short)",
    "quantisation": "values quantised wrongly (one RGBE exponent for the whole image, a dither half a code low)",
    "code_overflow": "codes past 255 wrapped round (two passes' 8-bit codes added in uint8)",
    "albedo": "a surface's colour (the floor's albedo typed 0.06)",
    "material": "an object rendered with another material (Lambert's cosine twice in the light sample, the "
                "Lambertians weighted by one minus a Fresnel term)",
    "normals": "surface normals wrong (a triangle's normal never normalised)",
    "object_moved": "objects moved (snapped onto the floor)",
    "object_size": "an object's size (the sphere's radius parsed as an integer)",
    "camera_fov": "the camera's field of view (a focal length converted with the sensor's height, then its width)",
    "camera_rotation": "the camera's rotation (its up vector re-derived with the cross product reversed)",
    "pixel_offset": "the pixel centres (the jitter added to the pixel's centre: the image shifted half a pixel)",
    "light_model": "another light model (a point light's attenuation on the area light)",
    "light_pdf": "the light sampled wrongly (its geometry term taken at the light's centre): the light seen right, "
                 "its light on surfaces not",
    "light_seen": "the light's own pixels (where the camera sees it) at the wrong brightness (its emission added for "
                  "one sample a pixel), its light on surfaces right",
    "indirect_scale": "the indirect light wrong (a bounce's weight times its pdf, one random number for its "
                      "direction), the direct light right",
    "roulette": "Russian roulette wrong (its test flipped)",
    "sample_clamp": "samples clamped (each sample's indirect light)",
    "spp_claim": "fewer samples per pixel than declared (the spp typed with XOR)",
    "biased_estimator": "a biased estimate of each pixel's mean (its samples weighted by their luminance)",
}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = blind.class_causes(MISTAKES, _EARLIER, NEW_CAUSES, _REWORDED)


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
