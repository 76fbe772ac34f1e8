r"""A thirty-first class of hand-ins: mistakes of the mathematics students derive by hand and type in, blind.

How it was written: from what goes wrong where students derive a formula on paper and then type it in, not from the
grader: measure conversions (solid angle against area, the Jacobian of a mapping, where each cosine belongs), the
pdfs of hand-derived samplers (spherical coordinates without their ``sin(theta)``, an inverse CDF inverted wrongly,
a mapping's Jacobian taken as its scale), the rendering equation's constants (``1 / pi``, ``1 / (2 pi)``, the
sphere's ``4 pi`` steradians), estimator algebra (the ``1 / N`` at the wrong place, estimates of different variance
combined with weights the wrong way round, Russian roulette's ``1 / p`` applied twice, multiple importance sampling's
weights on one strategy only), conventions from a textbook (an angle measured from the horizon where the formula
wants it from the pole, a cross product's order, radians for degrees in a derivation), a pinhole's geometry drawn on
paper (the image plane's half-width a secant), colour and tone maths (an inverse of Reinhard's curve solved wrongly,
stops taken back with ``exp``, an XYZ round trip whose inverse is the transpose, sRGB's formula with the 2.2 of the
simple gamma) and the file formats' numeric definitions (RGBE's shared exponent, the Radiance header's ``EXPOSURE``
taken for stops). Its author read the other classes' specs and cause words, the catalogue (:mod:`mcrt.mutants`), the
scene files and design notes, mcrt's scene, camera and image code, :data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to stay clear of their mistakes; never the
grader's rules (what decides a cause) nor its reports, and graded none of it, not one case. Each cause and ``major``
flag was set from the mistake alone; every mistake is worded by a cause the other classes already have
(:data:`NEW_CAUSES` is empty), so ``SAME_MISTAKE`` needed no new entry. The mistakes differ from those of the thirty
other classes (:mod:`~mcrt.grade.accuracy.cases`, :mod:`~mcrt.grade.accuracy.outside` and the modules of
:data:`_EARLIER`, from :mod:`~mcrt.grade.accuracy.programs` to :mod:`~mcrt.grade.accuracy.unconsidered`) and from
the catalogue's bugs:

* **post-processing**: the EXR written from a buffer tone-mapped in place for the preview, y = x / (1 + x), "undone"
  with an inverse solved wrongly, x = y / (1 + y) (in all: x / (1 + 2 x)); the preview's sRGB-encoded buffer
  "linearised" back for the EXR with the simple gamma, ``v ** 2.2``; a firefly clip done in stops, ``np.log2`` and
  back with ``np.exp`` for ``np.exp2`` (every value to the power 1 / ln 2); the render taken to CIE XYZ for a
  luminance step and back with the matrix's transpose for its inverse (a rotation's rule);
* **writing the file**: an 8-bit PNG encoded by sRGB's piecewise formula with the exponent 1 / 2.2 for 1 / 2.4; a
  Radiance HDR whose mantissas are each normalised by their own channel's ``frexp``, the exponent the largest's;
  a Radiance HDR brightened by one stop for a viewer, the header's ``EXPOSURE=`` given the stops (1) where it takes
  the factor (2);
* **materials**: the mirror's reflection derived as ``-d`` turned half a turn about the normal by Rodrigues' formula,
  the half turn typed 180 for pi (radians: 233 degrees); Lambert's cosine in the light sample taken as the cosine of
  the elevation (the angle measured from the horizon): the sine of the angle from the normal; every albedo taken for
  a reflectance at normal incidence and replaced by Schlick's Fresnel averaged over the hemisphere, a + (1 - a) / 21;
* **geometry**: the tetrahedron's barycentric coordinates as sub-triangle areas with the 1/2 in the numerators only
  (every face doubled about its first vertex); the sphere meshed from its rings' and segments' angles in degrees
  handed to ``sin`` and ``cos`` (radians); the mirror's normal rebuilt from the hit point's spherical coordinates with
  the latitude for the polar angle; each wall's quad raised along a cross product taken in the wrong order (down:
  every wall below the floor);
* **camera**: the image plane's half-width ``1 / cos(fov / 2)`` (the distance to its edge, a secant, for the
  tangent: 109.5 degrees); a first-person camera's pitch ``acos(f.z)`` (the polar angle) where its formula wants the
  elevation ``asin(f.z)``: the camera looking straight up; Hammersley sub-pixel points shifted in each pixel
  (Cranley-Patterson) with the ``mod 1`` left out (offsets up to 2 pixels);
* **light model**: the light's pdf with the Jacobian of (u, v) -> the square taken as the side's scale 2, not the
  determinant 4 (the direct light halved); the light sample weighted by the balance heuristic, the BSDF sample's
  share never added; the light's rectangle turned to face down with ``rotate_x(180)`` in radians (tilted 53
  degrees); the direct light from 30 cosine-weighted rays that meet the light, each divided by the light's pdf 1 / A
  in area measure (a solid-angle sample);
* **integrator**: the bounce by spherical coordinates with theta uniform in [0, pi / 2] and the uniform hemisphere's
  pdf (no sin(theta) Jacobian); the cosine-weighted bounce's inverse CDF solved as cos(theta) = 1 - sqrt(u) (for
  sqrt(1 - u)); the uniform hemisphere's bounce weighted with the sphere's pdf 1 / (4 pi); Russian roulette's 1 / p
  applied to the survivors' throughput and again to the radiance they bring back;
* **samples and passes**: two passes (32 and 224 spp) combined with "inverse variance" weights derived as 1 / (sigma^2
  n) for n / sigma^2 (the noise of 42 spp, 256 declared); each pixel's radiance divided by the pixel's area on the
  image plane (a film of flux per area: 1024 times at 64 x 64); a splitting of 4 paths at the first hit with the
  pixel's sum divided by the paths (the emission seen and the first light sample divided by 4).

The correct hand-ins come in ways no class used: Mitsuba with the first bounce cosine-weighted by rejection (uniform
directions kept with probability cos(theta)), a 16-bit PNG of 8-bit codes widened by bit replication (``c << 8 |
c``), Mitsuba with the first vertex's light sample drawn from a linear density on the light by its inverse CDF and
divided by that pdf, Mitsuba with sub-pixel offsets uniform in one of the pixel's two triangles, Mitsuba with Russian
roulette at the first bounce of survival the albedo's luminance, an 8-bit PNG of the codes nearest in linear light,
Mitsuba with the first vertex's direct light by the balance heuristic (a light sample and a BSDF sample), and Mitsuba
with the first bounce by spherical coordinates with theta uniform and its pdf's sin(theta) kept.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s ``edit`` and ``mitsuba_edit``), Mitsuba
renders at other spp or depths (same-seed samples of max depth 1, 2 and 8 combined where a student's loop weighs
them), Mitsuba's path integrator on rays a student's camera or mirror makes (:func:`mcrt.grade.accuracy.unsaid._traced`
and the sub-pixel offsets of :func:`mcrt.grade.accuracy.unforeseen._mean_through`), its first vertex's direct light
redone as a student's light sample makes it (:func:`mcrt.grade.accuracy.unheralded._first_vertex`), its first bounce
redrawn (:func:`mcrt.grade.accuracy.unprompted._first_bounce`), or correct renders post-processed and written with
NumPy, Pillow, pypng and the standard library as the students' programs do. mcrt renders none of it.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over :data:`CATEGORIES`: the 2nd, 4th, ... of
each category and of the correct hand-ins) are as in :mod:`~mcrt.grade.accuracy.unconsidered`, fixed before any case
was graded.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, cases, fresh, novel, programs, unasked, unattended, unattested, unbeknown,
                                 unbidden, unconsidered, unforeseen, unguessed, unheard, unheralded, unlooked, unmet,
                                 unnoticed, unprompted, unrecorded, unremarked, unremembered, unsaid, unseen, unsought,
                                 untold, untried, unvisited, unwonted)
from mcrt.grade.accuracy.cases import Spec
from mcrt.image_files import RGB_TO_XYZ, srgb_eotf

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


#: The classes after the first two, in the order they were written (their causes' words are this class's too).
_EARLIER = (programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked, unsought,
            unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted,
            unremarked, unremembered, unnoticed, unrecorded, unattended, unattested, unconsidered)


def _crc(name: str) -> int:
    return 1801000 + zlib.crc32(name.encode()) % 100000


_render = unseen._render
_posted = unseen._posted
_scene = unprompted._scene
_bsdf = unremarked._bsdf

#: The class's spp (the class is built at 64 x 64).
_S = 256
#: The assignment's maximum depth.
_DEPTH = 8


# --------------------------------------------------------------------------
# Post-processing (the render in, what the program writes out)
# --------------------------------------------------------------------------


def _reinhard_inverse_slipped(x):
    """The preview's Reinhard curve y = x / (1 + x), applied in place, "undone" for the EXR with x = y / (1 + y): from
    y + y x = x a sign slipped, x (1 + y) = y for x (1 - y) = y. In all x / (1 + 2 x)."""
    x = np.maximum(np.asarray(x, np.float64), 0.0)
    y = x / (1.0 + x)
    return y / (1.0 + y)


def _srgb_unclipped(x):
    """sRGB's encoding (IEC 61966-2-1) of values >= 0, not clipped at 1 (the preview's buffer; its PNG writer clips)."""
    x = np.maximum(np.asarray(x, np.float64), 0.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def _srgb_linearised_gamma22(x):
    """The preview's sRGB-encoded buffer (:func:`_srgb_unclipped`) taken back to linear for the EXR by the simple gamma,
    ``v ** 2.2``, for sRGB's decoding: the darks darker (0.01 read 0.0063), the mid-tones about right (0.2 read 0.203),
    the light 16.96 for 20."""
    return np.power(_srgb_unclipped(x), 2.2)


#: The stops' clip: log2 values above it (256) are clipped; nothing in the render reaches it.
_STOPS_CLIP = 8.0


def _stops_back_with_exp(x):
    """A firefly clip done in stops, ``ev = np.log2(img + 1e-6); ev = np.minimum(ev, 8); img = np.exp(ev)`` (``exp``
    for ``exp2``): every value (v + 1e-6) ** (1 / ln 2) = v ** 1.4427 (0.2 to 0.098, 20 to 75.3)."""
    ev = np.minimum(np.log2(np.maximum(np.asarray(x, np.float64), 0.0) + 1e-6), _STOPS_CLIP)
    return np.exp(ev)


#: What the XYZ round trip applies: M^T M, M linear sRGB -> XYZ (the inverse taken as the transpose).
_XYZ_ROUND_TRIP = RGB_TO_XYZ.T @ RGB_TO_XYZ


def _xyz_round_trip_transposed(x):
    """The render taken to CIE XYZ, ``xyz = rgb @ M.T`` (M linear sRGB to XYZ), for a luminance step left at a factor
    1, and back with ``rgb = xyz @ M`` (M's transpose for its inverse, as for a rotation): each colour times M^T M,
    white (1, 1, 1) to (0.626, 1.185, 1.278)."""
    return np.asarray(x, np.float64) @ RGB_TO_XYZ.T @ RGB_TO_XYZ


# --------------------------------------------------------------------------
# Writers (the render in, the file a program writes)
# --------------------------------------------------------------------------


def _srgb_with_22(v) -> np.ndarray:
    """sRGB's piecewise formula with the exponent of the simple gamma: 12.92 v up to 0.0031308, 1.055 v^(1 / 2.2) -
    0.055 above (for v^(1 / 2.4)), of the values clipped to [0, 1]."""
    v = np.clip(np.nan_to_num(np.asarray(v, np.float64)), 0.0, 1.0)
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(v, 1.0 / 2.2) - 0.055)


def _srgb22_codes(image: np.ndarray) -> np.ndarray:
    return np.floor(np.clip(_srgb_with_22(image), 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def _write_png_srgb22(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_srgb22_codes(image), folder)


def _rgbe_own_frexp(image: np.ndarray) -> np.ndarray:
    """(H, W, 4) RGBE bytes whose exponent byte is the largest channel's ``frexp`` exponent plus 128 (Ward's) but whose
    mantissas are each ``int(m * 256)`` of their own channel's ``frexp`` mantissa m in [0.5, 1): a channel c read back
    as c 2^(e_max - e_c), lifted into the largest channel's octave."""
    a = np.maximum(np.nan_to_num(np.asarray(image, np.float64)), 0.0)
    mx = a.max(axis=2)
    ok = mx > 1e-32
    _, e_max = np.frexp(mx)
    m_c, _ = np.frexp(a)
    out = np.zeros(a.shape[:2] + (4,), np.uint8)
    out[..., :3] = np.where(ok[..., None], np.floor(m_c * 256.0), 0).astype(np.uint8)
    out[..., 3] = np.where(ok, e_max + 128, 0).astype(np.uint8)
    return out


def _write_hdr_own_frexp(image: np.ndarray, folder: Path) -> Path:
    return unprompted._write_hdr_flat(_rgbe_own_frexp(image), folder)


#: The viewer's exposure in stops, and the factor it means.
_EV = 1
_EV_FACTOR = 2.0 ** _EV


def _write_hdr_exposure_stops(image: np.ndarray, folder: Path) -> Path:
    """A Radiance HDR (flat scanlines, mcrt's RGBE encoding) of the pixels brightened by ``_EV`` stops (times 2) for a
    viewer, its header recording ``EXPOSURE=1``, the stops, where the format wants the factor applied (2): a reader
    divides by 1."""
    from mcrt.image_files import _rgbe_encode

    h, w = image.shape[:2]
    rgbe = _rgbe_encode("render.hdr", np.maximum(np.nan_to_num(np.asarray(image, np.float64)), 0.0) * _EV_FACTOR)
    path = folder / "render.hdr"
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n" + f"EXPOSURE={_EV}\n\n-Y {h} +X {w}\n".encode()
                     + np.ascontiguousarray(rgbe, np.uint8).tobytes())
    return path


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _schlick_average(a):
    """Schlick's Fresnel R0 + (1 - R0) (1 - cos)^5 averaged over the hemisphere with cos / pi: R0 + (1 - R0) / 21."""
    return tuple(float(c) + (1.0 - float(c)) / 21.0 for c in a)


def _albedos_schlick_averaged(s):
    """Every Lambertian's albedo a taken for a reflectance at normal incidence and replaced by its hemispherical
    average a + (1 - a) / 21."""
    walls = tuple(replace(w, albedo=_schlick_average(w.albedo)) for w in s.room.walls)
    room = replace(s.room, walls=walls, floor_albedo=_schlick_average(s.room.floor_albedo),
                   ceiling_albedo=_schlick_average(s.room.ceiling_albedo))
    objects = tuple(replace(o, material=replace(o.material, albedo=_schlick_average(o.material.albedo)))
                    if o.name == "tetrahedron" else o for o in s.objects)
    return replace(s, room=room, objects=objects)


def _doubled_about_first(triangles) -> np.ndarray:
    """(n, 3, 3): each triangle (p0, p1, p2) as the test with half-area barycentrics accepts it, (p0, p0 + 2 (p1 - p0),
    p0 + 2 (p2 - p0)): u and v half their value, u + v <= 1 passing points up to u + v <= 2."""
    t = np.asarray(triangles, np.float64)
    return np.stack([t[:, 0], t[:, 0] + 2.0 * (t[:, 1] - t[:, 0]), t[:, 0] + 2.0 * (t[:, 2] - t[:, 0])], axis=1)


def _half_area_barycentrics(p, tri):
    """The student's barycentrics of the points ``p`` (N, 3) in ``tri`` (3, 3): each a sub-triangle's signed area 1/2
    (p - p0) x e . n over the triangle's |e1 x e2| (the parallelogram's: the 1/2 in the numerators only)."""
    p0, e1, e2 = tri[0], tri[1] - tri[0], tri[2] - tri[0]
    n = np.cross(e1, e2)
    whole = np.linalg.norm(n)
    nh = n / whole
    u = 0.5 * np.einsum("ij,j->i", np.cross(p - p0, e2), nh) / whole
    v = 0.5 * np.einsum("ij,j->i", np.cross(e1, p - p0), nh) / whole
    return u, v


def _tetra_triangles() -> np.ndarray:
    return np.asarray(next(o for o in _scene().objects if o.name == "tetrahedron").triangles(), np.float64)


def _tetra_doubled(d: dict) -> dict:
    t = next(o for o in _scene().objects if o.name == "tetrahedron")
    return fresh._rebuilt(d, "tetrahedron", _doubled_about_first(_tetra_triangles()), _bsdf(t.material))


#: The sphere's mesh: rings i = 0..18 and segments j = 0..36 at 10 degrees a step, the angles 10 i and 10 j handed to
#: sin and cos as radians.
_RINGS, _SEGMENTS, _STEP = 18, 36, 10.0


def _sphere_degrees_vertices() -> np.ndarray:
    """(rings + 1, segments + 1, 3): c + r (sin t cos p, sin t sin p, cos t) with t = 10 i and p = 10 j in radians
    (meant as degrees): every vertex on the sphere, at angles all round it."""
    c, r = unsaid._sphere()
    t = _STEP * np.arange(_RINGS + 1)[:, None]
    p = _STEP * np.arange(_SEGMENTS + 1)[None, :]
    return c + r * np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t) * np.ones_like(p)], axis=-1)


def _sphere_degrees_triangles() -> np.ndarray:
    """(2 rings segments, 3, 3): each quad (i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1) of the grid as two
    triangles."""
    v = _sphere_degrees_vertices()
    a, b, c, d = v[:-1, :-1], v[1:, :-1], v[1:, 1:], v[:-1, 1:]
    return np.concatenate([np.stack([a, b, c], axis=-2).reshape(-1, 3, 3),
                           np.stack([a, c, d], axis=-2).reshape(-1, 3, 3)])


def _sphere_degrees_mesh(d: dict) -> dict:
    sph = next(o for o in _scene().objects if o.name == "sphere")
    return fresh._rebuilt(d, "sphere", _sphere_degrees_triangles(), _bsdf(sph.material))


def _walls_hanging(d: dict) -> dict:
    """Every wall's quad raised from its bottom edge along cross(n, t) (n the wall's inward normal, t along the wall)
    for cross(t, n): (0, 0, -10) for (0, 0, 10), the wall from z = -5 down to -15 (its triangles reflected in the
    floor's plane)."""
    s = _scene()
    z0 = s.room.floor_z
    for sf in s.surfaces():
        if sf.name.startswith("wall_"):
            tris = np.array(sf.triangles, np.float64)
            tris[..., 2] = 2.0 * z0 - tris[..., 2]
            d = fresh._rebuilt(d, sf.name, tris, _bsdf(sf.material))
    return d


def _wall_up(a, b, *, reversed_order: bool) -> np.ndarray:
    """The unit 'up' of the wall from corner a to corner b (seen from above, counter-clockwise), cross(t, n) (or, with
    ``reversed_order``, cross(n, t)), t along the wall and n its inward normal (t turned a quarter to the left)."""
    t = np.array([b[0] - a[0], b[1] - a[1], 0.0])
    t /= np.linalg.norm(t)
    n = np.array([-t[1], t[0], 0.0])
    return np.cross(n, t) if reversed_order else np.cross(t, n)


# --------------------------------------------------------------------------
# The camera
# --------------------------------------------------------------------------

#: The image plane's half-width 1 / cos(45 degrees) = sqrt(2) for tan(45 degrees) = 1: a field of view of 109.47.
_HALF_WIDTH_SECANT = 1.0 / math.cos(math.radians(45.0))
_FOV_SECANT = math.degrees(2.0 * math.atan(_HALF_WIDTH_SECANT))


def _first_person(yaw: float, pitch: float):
    """A first-person camera's frame from its yaw and pitch (radians): forward (cos p cos y, cos p sin y, sin p), right
    (sin y, -cos y, 0), up cross(right, forward)."""
    f = np.array([math.cos(pitch) * math.cos(yaw), math.cos(pitch) * math.sin(yaw), math.sin(pitch)])
    r = np.array([math.sin(yaw), -math.cos(yaw), 0.0])
    return f, r, np.cross(r, f)


def _pitch_polar(s):
    """The scene's forward (1, 0, 0) turned into the camera's yaw atan2(f.y, f.x) = 0 and pitch acos(f.z) = 90 degrees
    (the polar angle, for the elevation asin(f.z) = 0): forward (0, 0, 1), up (-1, 0, 0)."""
    f0 = np.asarray(s.cameras["near"].forward, np.float64)
    f0 = f0 / np.linalg.norm(f0)
    f, _, u = _first_person(math.atan2(f0[1], f0[0]), math.acos(f0[2]))
    return cases._camera(s, forward=tuple(float(round(c, 12)) + 0.0 for c in f),
                         up=tuple(float(round(c, 12)) + 0.0 for c in u))


def _hammersley_unwrapped(rng, n: int, *, w: int, pixels: int):
    """Sub-pixel offsets of the Hammersley points (i / n, radical inverse of i in base 2) shifted in each pixel by a
    random (sx, sy) without the ``mod 1``: offsets in [0, 2), each pixel's samples a pixel-sized square moved by up to a
    pixel right and down."""
    i = np.arange(n)
    shift = rng.random((2, pixels, 1))
    return i / n + shift[0], unprompted._radical_inverse(i, 2) + shift[1]


def _two_triangles(rng, n: int, *, w: int, pixels: int):
    """Sub-pixel offsets uniform in one of the pixel's two triangles (the lower-left or, with probability 1/2, the
    upper-right), each drawn as sqrt(u1) (1 - u2, u2) from the right angle's corner: uniform on the pixel."""
    u0, u1, u2 = rng.random((3, pixels, n))
    s = np.sqrt(u1)
    a, b = s * (1.0 - u2), s * u2
    upper = u0 >= 0.5
    return np.where(upper, 1.0 - a, a), np.where(upper, 1.0 - b, b)


# --------------------------------------------------------------------------
# The light: samples at the first vertex (unheralded._first_vertex's ``direct``) and the light's rectangle
# --------------------------------------------------------------------------


def _light_jacobian_scale(mscene, rng, p, n, rho, mitsuba):
    """A light sample with the pdf 1 / 2 of (u, v) -> (4 + 2 u, -1 + 2 v) taken as the side's scale, not 1 / 4 of its
    determinant: rho Le G 2 / pi, half the right estimate."""
    lt = _scene().light
    return unbeknown._light_sampled(mscene, rng, p, n, rho, mitsuba) * (lt.size[0] / lt.area)


def _mis_light_weight(p, n, q) -> np.ndarray:
    """The balance heuristic's weight of a light sample at q from p: p_light / (p_light + p_bsdf), p_light = d^2 / (A
    cos_light) and p_bsdf = cos_surface / pi in solid angle: 1 / (1 + A G / pi), G cos_surface cos_light / d^2."""
    lt = _scene().light
    return 1.0 / (1.0 + lt.area * unbeknown._geometry(p, n, q) / math.pi)


def _light_mis_half(mscene, rng, p, n, rho, mitsuba):
    """One light sample weighted by the balance heuristic, p_light / (p_light + p_bsdf); the BSDF sample that meets the
    light never added (the path counts no emission after a diffuse bounce): the direct light short of the BSDF's
    share."""
    lt = _scene().light
    q = unbeknown._light_points(rng, len(p))
    g = np.where(unbeknown._unblocked(mscene, p, q), unbeknown._geometry(p, n, q) * _mis_light_weight(p, n, q), 0.0)
    return rho * (g * lt.area / math.pi)[:, None] * np.asarray(lt.radiance, np.float64)


def _light_hit(mscene, p, d):
    """Whether the rays from ``p`` along the unit ``d`` meet the light's emitting (lower) side unblocked, and their
    points q on it and distances t."""
    lt = _scene().light
    cz = lt.center[2]
    dz = d[:, 2]
    up = (dz > 1e-9) & (p[:, 2] < cz)
    t = np.where(up, (cz - p[:, 2]) / np.where(up, dz, 1.0), 0.0)
    q = p + t[:, None] * d
    hit = up & (np.abs(q[:, 0] - lt.center[0]) <= 0.5 * lt.size[0]) & (np.abs(q[:, 1] - lt.center[1])
                                                                       <= 0.5 * lt.size[1])
    if hit.any():
        idx = np.flatnonzero(hit)
        hit[idx] = unbeknown._unblocked(mscene, p[idx], q[idx])
    return hit, q, t


#: The rays a vertex of the cosine-ray estimate (the course report's 30 shadow rays).
_RAYS = 30


def _light_by_cosine_rays(mscene, rng, p, n, rho, mitsuba, *, k: int = _RAYS):
    """The direct light from ``k`` cosine-weighted directions, each that meets the light counted Le (rho / pi) cos /
    (1 / A), the light's pdf in area measure for a direction drawn in solid angle (the right weight is Le rho): A cos /
    pi = 1.27 cos times the truth where the light lies, averaged."""
    lt = _scene().light
    total = np.zeros(len(p))
    for _ in range(k):
        d, cos = unprompted._cosine_directions(rng, n)
        hit, _, _ = _light_hit(mscene, p, d)
        total += np.where(hit, cos, 0.0)
    return rho * (total / k * lt.area / math.pi)[:, None] * np.asarray(lt.radiance, np.float64)


def _lambert_from_horizon(p, n, q) -> np.ndarray:
    """The light sample's geometry term with Lambert's cosine written cos(elev), elev = asin(n . wi) the direction's
    angle above the surface (from the horizon): sqrt(1 - (n . wi)^2) where n . wi > 0, times cos_light / d^2."""
    wi = unsaid._unit(q - p)
    c = np.einsum("ij,ij->i", n, wi)
    s = np.where(c > 0.0, np.sqrt(np.maximum(1.0 - c * c, 0.0)), 0.0)
    return s * np.maximum(wi[:, 2], 0.0) / np.sum((q - p) ** 2, axis=1)


def _light_sample(name: str, direct) -> dict:
    """A spec's post-process: Mitsuba's path with its first vertex's light sample made by ``direct``."""
    return _posted(name, partial(unheralded._first_vertex, spp=_S, seed=_crc(name), direct=direct))


#: rotate_x(180) in radians: 180 - 28 (2 pi) = 4.0708, 233.24 degrees.
_TURN = 180.0


def _rotate_x(v: np.ndarray, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    v = np.asarray(v, np.float64)
    return np.stack([v[..., 0], c * v[..., 1] - s * v[..., 2], s * v[..., 1] + c * v[..., 2]], axis=-1)


def _light_turned_triangles(angle: float = _TURN) -> np.ndarray:
    """(2, 3, 3): the light built as a rectangle [-1, 1]^2 facing +z, turned by ``rotate_x(angle)`` (radians) and
    moved to the light's centre (scaled to its size)."""
    lt = _scene().light
    hx, hy = 0.5 * lt.size[0], 0.5 * lt.size[1]
    p = np.array([(-hx, -hy, 0.0), (hx, -hy, 0.0), (hx, hy, 0.0), (-hx, hy, 0.0)])
    q = _rotate_x(p, angle) + np.asarray(lt.center, np.float64)
    return np.array([[q[0], q[1], q[2]], [q[0], q[2], q[3]]])


def _light_turned(d: dict) -> dict:
    return unsaid._meshes(d, light=(_light_turned_triangles(), _scene().light.radiance))


def _light_ramp_point(u: np.ndarray) -> np.ndarray:
    """The inverse CDF of the density 2 (1 + a) / 3 on [0, 1]: a = sqrt(1 + 3 u) - 1."""
    return np.sqrt(1.0 + 3.0 * np.asarray(u, np.float64)) - 1.0


def _light_ramp(mscene, rng, p, n, rho, mitsuba):
    """A light sample at a point of density 2 (1 + a) / 3 along x (a in [0, 1] across the light, by its inverse CDF),
    uniform along y, divided by that pdf: unbiased."""
    u, v = rng.random((2, len(p)))
    a = _light_ramp_point(u)
    return unnoticed._light_at(mscene, p, n, rho, unnoticed._light_points(a, v)) / (2.0 * (1.0 + a) / 3.0)[:, None]


def _light_mis_balance(mscene, rng, p, n, rho, mitsuba):
    """The direct light by the balance heuristic: a light sample times p_light / (p_light + p_bsdf) plus a
    cosine-weighted BSDF sample that meets the light, Le rho times p_bsdf / (p_bsdf + p_light): unbiased."""
    lt = _scene().light
    le = np.asarray(lt.radiance, np.float64)
    light = _light_mis_half(mscene, rng, p, n, rho, mitsuba)
    d, cos = unprompted._cosine_directions(rng, n)
    hit, _, t = _light_hit(mscene, p, d)
    cos_l = np.maximum(d[:, 2], 1e-12)
    p_bsdf, p_light = cos / math.pi, t * t / (lt.area * cos_l)
    w = np.where(hit, p_bsdf / np.maximum(p_bsdf + p_light, 1e-300), 0.0)
    return light + rho * w[:, None] * le


# --------------------------------------------------------------------------
# The mirror's reflection and normal (camera rays; Mitsuba's path after it)
# --------------------------------------------------------------------------


def _rodrigues(v, axis, angle: float):
    """v turned by ``angle`` (radians) about the unit ``axis``: v cos + (k x v) sin + k (k . v) (1 - cos)."""
    c, s = math.cos(angle), math.sin(angle)
    return v * c + np.cross(axis, v) * s + axis * (np.einsum("ij,ij->i", axis, v) * (1.0 - c))[:, None]


def _reflect_rodrigues(d, q):
    """The reflection derived as -d turned half a turn about the normal q, ``rodrigues(-d, n, 180)`` (radians: 233.24
    degrees): the part along the normal right, the tangential part turned 53.24 degrees too far."""
    return unsaid._unit(_rodrigues(-d, q, _TURN))


def _normal_from_latitude(q):
    """The sphere's normal rebuilt from the unit offset q's spherical coordinates, phi = atan2(q.y, q.x) and theta =
    asin(q.z) (the latitude, from the horizon) put in (sin theta cos phi, sin theta sin phi, cos theta) (the polar
    angle's formula): (q.z cos phi, q.z sin phi, sqrt(1 - q.z^2)): up at the equator, horizontal at the poles."""
    phi = np.arctan2(q[:, 1], q[:, 0])
    theta = np.arcsin(np.clip(q[:, 2], -1.0, 1.0))
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=1)


def _sphere_hits(o, d):
    """(hit, points, unit offsets (p - c) / r) of rays from ``o`` along ``d`` with the sphere (nothing lies in front
    of it)."""
    c, radius = unsaid._sphere()
    oc = o - c
    b = np.einsum("ij,ij->i", oc, d)
    disc = b * b - (np.einsum("ij,ij->i", oc, oc) - radius * radius)
    t = -b - np.sqrt(np.maximum(disc, 0.0))
    hit = (disc > 0.0) & (t > 0.0)
    p = o + t[:, None] * d
    return hit, p, (p - c) / radius


def _mirror_after(o, d, *, turn):
    """Camera rays that meet the sphere sent on along ``turn(d, q)`` (q the true unit normal) from the hit point, just
    outside the ball, or just inside it where the new direction points in (those end there: the conductor is black
    from inside): (origins, directions, segments used)."""
    hit, p, q = _sphere_hits(o, d)
    r = turn(d, q)
    side = np.where(np.einsum("ij,ij->i", r, q) >= 0.0, 1.0, -1.0)
    start = p + (1e-4 * side)[:, None] * q
    return np.where(hit[:, None], start, o), np.where(hit[:, None], r, d), hit.astype(int)


def _reflect_latitude_normal(d, q):
    n = _normal_from_latitude(q)
    return unsaid._unit(d - 2.0 * np.einsum("ij,ij->i", d, n)[:, None] * n)


def _traced(name: str, turn) -> dict:
    return _posted(name, partial(unsaid._traced, spp=_S, seed=_crc(name), after=partial(_mirror_after, turn=turn)))


# --------------------------------------------------------------------------
# Bounces at the first vertex (unprompted._first_bounce's ``draw``)
# --------------------------------------------------------------------------


def _about_normal(n, cos_t, phi) -> np.ndarray:
    """(N, 3) the directions of polar cosine ``cos_t`` and azimuth ``phi`` about the unit normals ``n``."""
    t, b = unforeseen._frame_of(n)
    sin_t = np.sqrt(np.maximum(1.0 - cos_t * cos_t, 0.0))
    return unsaid._unit((sin_t * np.cos(phi))[:, None] * t + (sin_t * np.sin(phi))[:, None] * b + cos_t[:, None] * n)


def _theta_uniform(rng, n):
    """theta = pi / 2 u1, phi = 2 pi u2 (taken for uniform on the hemisphere, the sin(theta) of dw = sin dtheta dphi
    left out: dense towards the normal), weighted with the uniform pdf 1 / (2 pi): f cos / pdf = 2 albedo cos."""
    u1, u2 = rng.random((2, len(n)))
    cos_t = np.cos(0.5 * math.pi * u1)
    return _about_normal(n, cos_t, 2.0 * math.pi * u2), 2.0 * cos_t


def _inverse_cdf_slipped(rng, n):
    """The cosine-weighted bounce's inverse CDF solved as cos(theta) = 1 - sqrt(u1) (for sqrt(1 - u1)): cos(theta)
    of density 2 (1 - c), crowded towards the horizon, weighted as a cosine-weighted sample (1)."""
    u1, u2 = rng.random((2, len(n)))
    return _about_normal(n, 1.0 - np.sqrt(u1), 2.0 * math.pi * u2), np.ones(len(n))


def _uniform_sphere_pdf(rng, n):
    """Uniform hemisphere directions (cos(theta) = u1) weighted with the sphere's pdf 1 / (4 pi): f cos / pdf = 4
    albedo cos, twice the right 2 albedo cos."""
    u1, u2 = rng.random((2, len(n)))
    return _about_normal(n, u1, 2.0 * math.pi * u2), 4.0 * u1


def _cosine_by_rejection(rng, n):
    """Uniform hemisphere directions kept with probability cos(theta) (drawn again until kept): cosine-weighted,
    weight 1."""
    m = len(n)
    cos_t = np.zeros(m)
    todo = np.ones(m, bool)
    while todo.any():
        k = int(todo.sum())
        c, keep = rng.random(k), rng.random(k)
        idx = np.flatnonzero(todo)
        ok = keep < c
        cos_t[idx[ok]] = c[ok]
        todo[idx[ok]] = False
    return _about_normal(n, cos_t, 2.0 * math.pi * rng.random(m)), np.ones(m)


def _theta_uniform_jacobian(rng, n):
    """theta = pi / 2 u1, phi = 2 pi u2 with its pdf in solid angle 1 / (pi^2 sin(theta)) kept: f cos / pdf = albedo pi
    cos(theta) sin(theta): unbiased."""
    u1, u2 = rng.random((2, len(n)))
    th = 0.5 * math.pi * u1
    return _about_normal(n, np.cos(th), 2.0 * math.pi * u2), math.pi * np.cos(th) * np.sin(th)


def _bounce(name: str, draw) -> dict:
    """A spec's post-process: Mitsuba's path with its first bounce drawn by ``draw``."""
    return _posted(name, partial(unprompted._first_bounce, spp=_S, seed=_crc(name), draw=draw))


# --------------------------------------------------------------------------
# Russian roulette at the first bounce and the paths' count (same-seed samples of max depth 1, 2 and 8)
# --------------------------------------------------------------------------


def _roulette_weights(p: np.ndarray, u: np.ndarray, power: int) -> np.ndarray:
    """The weight of the light after the first bounce under roulette of survival p: 1 / p^power where u < p, else 0
    (``power`` 1 is unbiased; 2 divides the survivors by p twice)."""
    p = np.asarray(p, np.float64)
    live = (p > 0.0) & (np.asarray(u) < p)
    return np.where(live, 1.0 / np.where(live, p, 1.0) ** power, 0.0)


#: Rec. 709's luminance weights (linear sRGB's Y).
_LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def _roulette_sample(o, d, seed, *, full, direct, survival, power: int):
    """A sample under Russian roulette at its first diffuse vertex, after the vertex's light sample: L2 + (L8 - L2) w,
    w from :func:`_roulette_weights` with p = ``survival(albedo)``, L2 and L8 the same seed's samples of max depth 2 and
    8 (the mirror and the light, Mitsuba's)."""
    L, near = unsaid._sampled(full, o, d, seed), unsaid._sampled(direct, o, d, seed)
    rho = unsaid._first_albedo(full, o, d)
    diffuse = rho.max(axis=1) > 0.0
    u = np.random.default_rng(seed + 43).random(len(o))
    w = _roulette_weights(survival(rho), u, power)
    return np.where(diffuse[:, None], near + (L - near) * w[:, None], L)


def _roulette(x, *, spp: int, seed: int, survival, power: int):
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(
        _roulette_sample, full=unsaid._loaded(_DEPTH), direct=unsaid._loaded(2), survival=survival, power=power))


def _max_channel(rho):
    return rho.max(axis=1)


def _luminance(rho):
    return rho @ _LUMINANCE


#: Paths a camera sample splits into at its first hit.
_SPLIT = 4


def _paths_counted(L8, L2, L1, diffuse, seen, *, k: int = _SPLIT) -> np.ndarray:
    """A camera sample's share of the pixel when its first hit splits into ``k`` paths and the pixel's sum is divided
    by the paths: the emission seen and the first vertex's light sample, added once, over k; the light after the
    first vertex, added k times, over k. At a diffuse hit (L2 - L1) / k + L1 / k + (L8 - L2); at the light L8 / k; at
    the mirror (no light sample there) L8."""
    return np.where(diffuse[:, None], L2 / k + (L8 - L2), np.where(seen[:, None], L8 / k, L8))


def _paths_counted_sample(o, d, seed, *, full, two, one):
    L8, L2, L1 = (unsaid._sampled(m, o, d, seed) for m in (full, two, one))
    diffuse = unsaid._first_albedo(full, o, d).max(axis=1) > 0.0
    return _paths_counted(L8, L2, L1, diffuse, L1.max(axis=1) > 0.0)


def _paths_count(x, *, spp: int, seed: int):
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(
        _paths_counted_sample, full=unsaid._loaded(_DEPTH), two=unsaid._loaded(2), one=unsaid._loaded(1)))


# --------------------------------------------------------------------------
# Samples and passes
# --------------------------------------------------------------------------

#: The two passes' spp (256 declared).
_PASSES = (32, 224)


def _inverse_spp_weights(spp=_PASSES) -> np.ndarray:
    """The passes' weights 1 / (sigma^2 n) (the variance of a pass's mean derived as sigma^2 n, for sigma^2 / n), one
    sigma^2 for both, normalised: (7/8, 1/8) for 32 and 224 spp."""
    w = 1.0 / np.asarray(spp, np.float64)
    return w / w.sum()


def _passes_inverse_spp(x, *, spp=_PASSES, seed: int):
    h, w = x.shape[:2]
    weights = _inverse_spp_weights(spp)
    return sum(wk * _render(w, h, n, seed + k) for k, (wk, n) in enumerate(zip(weights, spp)))


def _effective_spp(spp=_PASSES) -> float:
    """The spp whose noise the weighted passes have: 1 / sum(w_k^2 / n_k)."""
    w = _inverse_spp_weights(spp)
    return 1.0 / float(np.sum(w * w / np.asarray(spp, np.float64)))


def _pixel_area(w: int, h: int) -> float:
    """A pixel's area on the image plane (2 x 2 at distance 1 for 90 degrees)."""
    return (2.0 / w) * (2.0 / h)


def _over_pixel_area(x):
    """Each pixel's mean radiance divided by the pixel's area on the image plane (the film taken to record flux per
    unit area): times W H / 4."""
    h, w = x.shape[:2]
    return np.asarray(x, np.float64) / _pixel_area(w, h)


# --------------------------------------------------------------------------
# Correct files made in other ways
# --------------------------------------------------------------------------


def _bit_replicated(codes: np.ndarray) -> np.ndarray:
    """16-bit codes from 8-bit ones by left bit replication, ``c << 8 | c`` (= 257 c, exactly c / 255 of 65535)."""
    c = np.asarray(codes).astype(np.uint16)
    return (c << 8) | c


def _write_png16_replicated(image: np.ndarray, folder: Path) -> Path:
    import png

    h, w = image.shape[:2]
    codes = _bit_replicated(blind._srgb8(image))
    path = folder / "render.png"
    with open(path, "wb") as fh:
        png.Writer(w, h, bitdepth=16, greyscale=False).write(fh, codes.reshape(h, w * 3).tolist())
    return path


def _nearest_in_linear(image: np.ndarray) -> np.ndarray:
    """8-bit codes chosen as the code whose sRGB decoding lies nearest the linear value (a binary search on the 255
    midpoints of the decoded table), of the values clipped to [0, 1]."""
    table = srgb_eotf(np.arange(256) / 255.0)
    mids = 0.5 * (table[1:] + table[:-1])
    v = np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 1.0)
    return np.searchsorted(mids, v, side="left").astype(np.uint8)


def _write_png_nearest_in_linear(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_nearest_in_linear(image), folder)


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_reinhard_inverse_solved_wrongly", "pp_srgb_buffer_linearised_gamma_22",
                        "pp_stops_back_with_natural_exp", "pp_xyz_inverse_as_transpose"),
    "file": ("file_png_srgb_exponent_2_2", "file_hdr_mantissas_own_frexp", "file_hdr_exposure_in_stops"),
    "materials": ("mirror_rodrigues_half_turn_180_radians", "lambert_cosine_from_horizon",
                  "albedos_schlick_hemispherical_average"),
    "geometry": ("tetra_barycentric_half_areas", "sphere_mesh_degrees_as_radians", "sphere_normal_latitude_as_polar",
                 "walls_up_cross_reversed"),
    "camera": ("fov_half_width_secant", "camera_pitch_polar_angle", "jitter_cranley_patterson_unwrapped"),
    "light": ("light_jacobian_scale_not_determinant", "light_mis_bsdf_share_missing", "light_rotate_x_180_radians",
              "light_cosine_rays_area_pdf"),
    "integrator": ("bounce_theta_uniform_no_sine", "bounce_inverse_cdf_one_minus_sqrt", "bounce_uniform_sphere_pdf",
                   "roulette_divided_twice"),
    "samples": ("passes_weighted_inverse_spp", "film_over_pixel_area", "split_paths_counted"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_reinhard_inverse_solved_wrongly", "tone_map", True, **_posted(
            "reinhard_inverse_slipped", _reinhard_inverse_slipped),
             truth="the render tone-mapped in place for the preview with Reinhard's y = x / (1 + x), then undone for "
             "the EXR with an inverse solved by hand with a sign slipped, x = y / (1 + y) (from y + y x = x, x (1 + "
             "y) = y for x (1 - y) = y): every value x / (1 + 2 x), 0.2 written 0.143, 1 written 0.333, the light's "
             "20 written 0.488, as EXR"),
        Spec("pp_srgb_buffer_linearised_gamma_22", "encoding", held_out=True, **_posted(
            "srgb_linearised_gamma22", _srgb_linearised_gamma22),
             truth="the render sRGB-encoded in place for the preview (sRGB's exact curve, not clipped) and taken back "
             "to linear for the EXR with the simple gamma v ** 2.2 for sRGB's decoding: the darks darker (0.01 written "
             "0.0063, 0.05 written 0.046), the mid-tones about right (0.2 written 0.203, 0.5 written 0.509), the "
             "light's 20 written 16.96, as EXR"),
        Spec("pp_stops_back_with_natural_exp", "tone_map", True, **_posted("stops_exp", _stops_back_with_exp),
             truth="fireflies clipped in stops, ev = np.log2(img + 1e-6); ev = np.minimum(ev, 8); img = np.exp(ev) "
             "(the natural exponential for np.exp2; nothing reaches the clip): every value to the power 1 / ln 2 = "
             "1.443, 0.2 written 0.098, 0.05 written 0.013, the light's 20 written 75.3, as EXR"),
        Spec("pp_xyz_inverse_as_transpose", "colour_space", True, held_out=True, **_posted(
            "xyz_transpose", _xyz_round_trip_transposed),
             truth="the render taken to CIE XYZ (xyz = rgb @ M.T, M the linear sRGB to XYZ matrix) for a luminance "
             "step left at a factor 1, and back with rgb = xyz @ M, the transpose taken for the inverse (as for a "
             "rotation): every colour times M^T M, a grey of 1 written (0.626, 1.185, 1.278), the floor's grey "
             "cyan, reds darker, as EXR"),
        # Writing the file
        Spec("file_png_srgb_exponent_2_2", "encoding", writer=_write_png_srgb22, file="png-srgb-2-2",
             truth="an 8-bit PNG encoded by sRGB's piecewise formula typed with the exponent of the simple gamma, "
             "12.92 v up to 0.0031308 and 1.055 v^(1 / 2.2) - 0.055 above (for v^(1 / 2.4)): the codes low, 0.2 "
             "written 115 for 124 (read 0.171), 0.05 written 55 for 63 (read 0.038), 0.5 written 182 for 188 (read "
             "0.468): every value 5 to 35 % too dark once decoded, the darker the more"),
        Spec("file_hdr_mantissas_own_frexp", "file_format", True, held_out=True, writer=_write_hdr_own_frexp,
             file="hdr-own-frexp",
             truth="a Radiance HDR written by hand with Ward's shared exponent, frexp of the largest channel plus "
             "128, but each channel's mantissa int(m * 256) of its own frexp(c) (m in [0.5, 1)): a channel read "
             "back as c 2^(e_max - e_c), lifted into the largest channel's octave, greys right, colours washed "
             "towards the largest channel's level (a blue wall's (0.03, 0.04, 0.15) read (0.24, 0.16, 0.15))"),
        Spec("file_hdr_exposure_in_stops", "light_radiance", True, writer=_write_hdr_exposure_stops,
             file="hdr-exposure-stops",
             truth="a Radiance HDR of the render brightened by one stop for a viewer (times 2), its header recording "
             "EXPOSURE=1, the stops, where the format wants the factor applied (2): a reader divides by 1, the image "
             "read back twice as bright"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("mirror_rodrigues_half_turn_180_radians", "material", True, **_traced(
            "mirror_rodrigues_half_turn_180_radians", _reflect_rodrigues),
             truth="the mirror's reflection derived as -d turned half a turn about the normal with Rodrigues' "
             "formula, the half turn typed 180 for pi (radians: 180 - 28 (2 pi) = 4.071, 233.24 degrees; cos -0.598, "
             "sin -0.801), for camera rays (Mitsuba's path after it): the part along the normal right, the "
             "tangential part turned 53.24 degrees too far about the normal: the reflections in the sphere swirled, "
             "other parts of the room seen in it"),
        Spec("lambert_cosine_from_horizon", "material", True, held_out=True, **_light_sample(
            "lambert_cosine_from_horizon", partial(unbeknown._light_sampled, geometry=_lambert_from_horizon)),
             truth="Lambert's cosine in the light sample written cos(elev) with elev = asin(n . wi), the angle of "
             "the light's direction above the surface (from the horizon, a textbook's elevation) for its angle "
             "from the normal: sqrt(1 - (n . wi)^2), the sine of the right angle, at the first surface a camera ray "
             "meets (Mitsuba's path after it): the floor under the light dark (0 straight below), the walls, lit "
             "at a slant, too bright, the light seen right"),
        Spec("albedos_schlick_hemispherical_average", "albedo", edit=_albedos_schlick_averaged,
             truth="every albedo a taken for a reflectance at normal incidence (F0) and replaced by Schlick's "
             "Fresnel averaged over the hemisphere, a + (1 - a) / 21 (2 times the integral of (1 - mu)^5 mu): the "
             "floor 0.619 for 0.6, the ceiling 0.810 for 0.8, each 0.15 channel 0.190 (the colours paler), the "
             "tetrahedron (0.810, 0.476, 0.143)"),
        # Geometry
        Spec("tetra_barycentric_half_areas", "object_shape", True, mitsuba_edit=_tetra_doubled,
             truth="the tetrahedron's triangle test with barycentric coordinates derived as sub-triangle areas, 1/2 "
             "|(p - p0) x e| over |e1 x e2| (the 1/2 in the numerators only, not the whole triangle's): u and v half "
             "their value, u + v <= 1 passing points up to u + v <= 2: every face twice its size about its first "
             "vertex, the tetrahedron an orange cluster of large triangles from x 7.5 to 11.5, y -6.6 to 0 "
             "(through wall BC) and up to z 0.9"),
        Spec("sphere_mesh_degrees_as_radians", "object_shape", True, held_out=True, mitsuba_edit=_sphere_degrees_mesh,
             truth="the mirror sphere meshed as a UV sphere of 18 rings and 36 segments whose angles, 10 i and 10 j "
             "degrees, are handed to sin and cos as radians: every vertex on the sphere but at angles all round it "
             "(10 rad for 10 degrees), the quads' triangles chords across the ball: a crumpled mirror of crossing "
             "facets inside the sphere's outline"),
        Spec("sphere_normal_latitude_as_polar", "normals", True, **_traced(
            "sphere_normal_latitude_as_polar", _reflect_latitude_normal),
             truth="the mirror's normal rebuilt from the hit point's spherical coordinates (a UV step), theta = "
             "asin((p - c).z / r), the latitude measured from the horizon, put in (sin theta cos phi, sin theta "
             "sin phi, cos theta), the formula for the polar angle: the normal (z cos phi, z sin phi, sqrt(1 - z^2)), "
             "straight up at the equator, horizontal at the top, for camera rays (Mitsuba's path after it): the "
             "sphere showing the ceiling and parts of the room at wrong places, black where the reflection turns "
             "into the ball"),
        Spec("walls_up_cross_reversed", "mesh_face", True, held_out=True, mitsuba_edit=_walls_hanging,
             truth="each wall's quad built from its bottom edge and an up vector derived as cross(n, t) (n the "
             "wall's inward normal, t along the wall) for cross(t, n): up (0, 0, -1), every wall hanging from the "
             "floor's edge down to z = -15, below the floor: the room without walls, floor and ceiling only, the "
             "void black between them, the room much darker"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    return (
        # Camera
        Spec("fov_half_width_secant", "camera_fov", True, edit=cases.fov(_FOV_SECANT),
             truth="the image plane's half-width derived from a drawing as the distance from the eye to the plane's "
             "edge, 1 / cos(fov / 2) (a secant, the hypotenuse), for tan(fov / 2): sqrt(2) for 1, a field of view "
             "of 109.47 degrees for 90: the view wider, the room smaller in the middle"),
        Spec("camera_pitch_polar_angle", "camera_rotation", True, held_out=True, edit=_pitch_polar,
             truth="a first-person camera's yaw and pitch derived from the scene's forward vector, yaw = atan2(f.y, "
             "f.x) = 0 and pitch = acos(f.z) (the polar angle from +z) where its formula (cos p cos y, cos p sin y, "
             "sin p) wants the elevation asin(f.z): pitch 90 degrees for 0, forward (0, 0, 1), up cross(right, "
             "forward) = (-1, 0, 0): the camera looking straight up at the ceiling, the light just off the image's "
             "bottom edge, walls AB and FA at its top"),
        Spec("jitter_cranley_patterson_unwrapped", "pixel_footprint", **_posted(
            "cranley_patterson_unwrapped", partial(unforeseen._mean_through, spp=_S,
                                                   seed=_crc("jitter_cranley_patterson_unwrapped"),
                                                   jitter=_hammersley_unwrapped)),
             truth="sub-pixel offsets from the Hammersley points (i / n, radical inverse of i) shifted in each pixel "
             "by a random (sx, sy) (a Cranley-Patterson rotation) with the mod 1 left out: offsets in [0, 2), each "
             "pixel's samples a pixel-sized square moved right and down by up to a pixel, half a pixel on average: "
             "the image half a pixel up and left, its edges ragged"),
        # Light model
        Spec("light_jacobian_scale_not_determinant", "light_pdf", True, **_light_sample(
            "light_jacobian_scale_not_determinant", _light_jacobian_scale),
             truth="the light's pdf derived through the mapping (u, v) -> (4 + 2 u, -1 + 2 v) with its Jacobian "
             "taken as the side's scale 2, not the determinant 4: pdf 1 / 2 for 1 / 4, at the first surface a camera "
             "ray meets (Mitsuba's path after it): the direct light there half the truth, the light seen right"),
        Spec("light_mis_bsdf_share_missing", "light_pdf", held_out=True, **_light_sample(
            "light_mis_bsdf_share_missing", _light_mis_half),
             truth="the light sample weighted by the balance heuristic, p_light / (p_light + p_bsdf) = 1 / (1 + A G / "
             "pi), while the tracer never adds the BSDF sample that meets the light (no emission after a diffuse "
             "bounce), at the first surface a camera ray meets (Mitsuba's path after it): the direct light short of "
             "the BSDF's share, 1.3 % under the light, a few per cent where the light is near and large in view, "
             "the light seen right"),
        Spec("light_rotate_x_180_radians", "light_facing", True, mitsuba_edit=_light_turned,
             truth="the light built as a square [-1, 1]^2 facing +z, turned to face down with rotate_x(180) of a "
             "function taking radians (233.24 degrees: cos -0.598, sin -0.801) and moved to (5, 0, 4.99): the square "
             "tilted 53.2 degrees, spanning z 4.19 to 5.79 (half of it above the ceiling), facing (0, 0.80, -0.60): "
             "the room lit from a tilted strip towards its left side, the right side and the floor under the light "
             "darker"),
        Spec("light_cosine_rays_area_pdf", "light_pdf", True, held_out=True, **_light_sample(
            "light_cosine_rays_area_pdf", _light_by_cosine_rays),
             truth="the direct light from the course's 30 rays a vertex drawn cosine-weighted, each that meets the "
             "light counted Le (albedo / pi) cos / (1 / A), the light's pdf in area measure for a direction drawn in "
             "solid angle (the right weight Le albedo), at the first surface a camera ray meets (Mitsuba's path "
             "after it): the direct light times A cos / pi = 1.27 cos, the floor under the light a fifth too "
             "bright, the walls (cos 0.3 to 0.6) a quarter to two thirds too dark, noisier, the light seen right"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples and passes."""
    c = _crc
    return (
        # Integrator
        Spec("bounce_theta_uniform_no_sine", "indirect_scale", True, **_bounce(
            "bounce_theta_uniform_no_sine", _theta_uniform),
             truth="the diffuse bounce by spherical coordinates, theta = pi / 2 u1 and phi = 2 pi u2, taken for "
             "uniform on the hemisphere (the sin(theta) of dw = sin(theta) dtheta dphi left out) and weighted with "
             "the uniform pdf 1 / (2 pi) (2 albedo cos), at the first surface a camera ray meets (Mitsuba's path "
             "after it): the bounces dense towards the normal and over-weighted there, the indirect light 4 / pi "
             "= 1.27 times too bright under a uniform sky, more from what faces each surface, the direct light right"),
        Spec("bounce_inverse_cdf_one_minus_sqrt", "indirect_scale", held_out=True, **_bounce(
            "bounce_inverse_cdf_one_minus_sqrt", _inverse_cdf_slipped),
             truth="the cosine-weighted bounce's inverse CDF solved by hand as cos(theta) = 1 - sqrt(u1) (for sqrt(1 "
             "- u1)), weighted as cosine-weighted (1), at the first surface a camera ray meets (Mitsuba's path after "
             "it): cos(theta) of density 2 (1 - c), the bounces crowded towards the horizon (mean cosine 1/3 for "
             "2/3): the indirect light from grazing directions over-weighted, from what faces each surface "
             "under-weighted (right under a uniform sky), the direct light right"),
        Spec("bounce_uniform_sphere_pdf", "indirect_scale", True, **_bounce(
            "bounce_uniform_sphere_pdf", _uniform_sphere_pdf),
             truth="the diffuse bounce drawn uniformly on the hemisphere (cos(theta) = u1) and weighted with the "
             "uniform pdf of the whole sphere, 1 / (4 pi) steradians, for the hemisphere's 1 / (2 pi) (4 albedo cos "
             "for 2 albedo cos), at the first surface a camera ray meets (Mitsuba's path after it): the indirect "
             "light twice the truth, the direct light right"),
        Spec("roulette_divided_twice", "roulette", True, held_out=True, **_posted("roulette_twice", partial(
            _roulette, spp=_S, seed=c("roulette_divided_twice"), survival=_max_channel, power=2)),
             truth="Russian roulette at the first bounce with survival p the throughput's largest channel (the "
             "albedo's), the survivors' throughput divided by p and the radiance they bring back divided by p again "
             "(the weight written into the throughput and into the estimator), at the first surface a camera ray "
             "meets (Mitsuba's path after it): the light after the bounce 1 / p too bright, the floor's (p 0.6) 1.67 "
             "times, the ceiling's (0.8) 1.25 times, the direct light right"),
        # Samples and passes
        Spec("passes_weighted_inverse_spp", "spp_claim", **_posted("passes_inverse_spp", partial(
            _passes_inverse_spp, seed=c("passes_weighted_inverse_spp"))),
             truth="two passes of 32 and 224 spp (256 declared) combined with inverse-variance weights derived with "
             "the variance of a pass's mean as sigma^2 n (for sigma^2 / n), one sigma^2 for both: weights 7/8 for "
             "the 32-spp pass and 1/8 for the 224: the mean right, the noise of 42 spp"),
        Spec("film_over_pixel_area", "light_radiance", True, held_out=True, **_posted(
            "over_pixel_area", _over_pixel_area),
             truth="each pixel's mean radiance divided by the pixel's area on the image plane, (2 / W) (2 / H) (the "
             "film taken to record flux per unit area, derived from the sensor's irradiance): the image W H / 4 = "
             "1024 times too bright at 64 x 64"),
        Spec("split_paths_counted", "sample_count", True, **_posted("paths_counted", partial(
            _paths_count, spp=_S, seed=c("split_paths_counted"))),
             truth="each camera sample split into 4 paths at its first hit, the emission the camera ray sees and "
             "the first vertex's light sample added once, the light after it once a path, and the pixel's sum "
             "divided by the paths (4 spp): the light seen a quarter of its 20, the direct light at the first "
             "surface a quarter, the rest right, the mirror's reflections right"),
    )


def _correct() -> tuple[Spec, ...]:
    return (
        Spec("ok_bounce_cosine_by_rejection", None, **_bounce("ok_bounce_cosine_by_rejection", _cosine_by_rejection),
             truth="Mitsuba path 256 spp with the first bounce cosine-weighted by rejection: uniform hemisphere "
             "directions (cos(theta) = u) kept with probability cos(theta), drawn again until kept, EXR"),
        Spec("ok_png16_bit_replication", None, held_out=True, spp=212, writer=_write_png16_replicated,
             file="png16-bit-replicated",
             truth="Mitsuba path 212 spp, a 16-bit PNG of the 8-bit sRGB codes widened by left bit replication, c "
             "<< 8 | c (257 c, exactly the 8-bit value), written by pypng"),
        Spec("ok_light_linear_ramp_inverse_cdf", None, **_light_sample(
            "ok_light_linear_ramp_inverse_cdf", _light_ramp),
             truth="Mitsuba path 256 spp with the first vertex's light sample drawn from a density 2 (1 + a) / 3 "
             "across the light (a = sqrt(1 + 3 u) - 1 by its inverse CDF) and divided by that pdf, EXR"),
        Spec("ok_jitter_two_triangles", None, held_out=True, spp=208, **_posted("two_triangles", partial(
            unforeseen._mean_through, spp=208, seed=_crc("ok_jitter_two_triangles"), jitter=_two_triangles)),
             truth="Mitsuba path 208 spp with sub-pixel offsets uniform in one of the pixel's two triangles (each "
             "chosen with probability 1/2, the point sqrt(u1) (1 - u2, u2) from its right angle), EXR"),
        Spec("ok_roulette_albedo_luminance", None, **_posted("roulette_luminance", partial(
            _roulette, spp=_S, seed=_crc("ok_roulette_albedo_luminance"), survival=_luminance, power=1)),
             truth="Mitsuba path 256 spp with Russian roulette at the first bounce of survival the albedo's "
             "luminance (Rec. 709 weights), the survivors divided by it, EXR"),
        Spec("ok_png_nearest_in_linear", None, held_out=True, spp=184, writer=_write_png_nearest_in_linear,
             file="png-nearest-linear",
             truth="Mitsuba path 184 spp, an 8-bit PNG whose codes are those whose sRGB decoding lies nearest the "
             "linear value (a binary search on the decoded table's midpoints)"),
        Spec("ok_light_mis_balance", None, **_light_sample("ok_light_mis_balance", _light_mis_balance),
             truth="Mitsuba path 256 spp with the first vertex's direct light by the balance heuristic, a light "
             "sample and a cosine-weighted BSDF sample that meets the light, each weighted by its pdf over both, "
             "EXR"),
        Spec("ok_bounce_theta_uniform_jacobian", None, held_out=True, **_bounce(
            "ok_bounce_theta_uniform_jacobian", _theta_uniform_jacobian),
             truth="Mitsuba path 256 spp with the first bounce by spherical coordinates with theta uniform in [0, pi "
             "/ 2], weighted by its pdf in solid angle 1 / (pi^2 sin(theta)) (albedo pi cos sin), EXR"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "tone_map": "a curve applied before saving (a preview's tone map undone by a wrong inverse, stops taken back "
                "with the natural exponential)",
    "encoding": "the values' encoding (a display curve decoded by another, sRGB's formula with 2.2 for 2.4)",
    "colour_space": "values through another colour matrix (an XYZ round trip whose inverse was taken as the "
                    "transpose)",
    "file_format": "the file's data not what its format defines (each RGBE mantissa normalised by its own channel's "
                   "exponent)",
    "light_radiance": "a constant factor (an HDR's EXPOSURE written in stops, each pixel divided by its area on the "
                      "image plane)",
    "material": "an object rendered with another material (the mirror's reflection or Lambert's cosine derived "
                "wrongly)",
    "albedo": "a surface's colour (every albedo raised to a Fresnel average)",
    "object_shape": "an object's shape (the tetrahedron's faces doubled, the sphere meshed from angles in degrees "
                    "taken as radians)",
    "normals": "surface normals wrong (the mirror's normal from its latitude taken as a polar angle)",
    "mesh_face": "faces of a mesh missing (every wall of the room below the floor)",
    "camera_fov": "the camera's field of view (the image plane's half-width a secant)",
    "camera_rotation": "the camera's rotation (its pitch a polar angle: looking up)",
    "pixel_footprint": "each pixel's samples not spread over its square (a random shift not wrapped)",
    "light_pdf": "the light sampled wrongly (a Jacobian's scale for its determinant, MIS weights on one strategy "
                 "only, directions weighted with an area pdf): the light seen right, its light on surfaces not",
    "light_facing": "the light facing the wrong way (turned 233 degrees for 180)",
    "indirect_scale": "the indirect light wrong (bounces weighted by another pdf than the one they are drawn from), "
                      "the direct light right",
    "roulette": "Russian roulette weighted wrongly (the survivors divided by the probability twice)",
    "spp_claim": "fewer samples per pixel than declared in effect (passes weighted the wrong way round)",
    "sample_count": "each pixel's sum divided by more samples than it got (the split paths counted)",
}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = blind.class_causes(MISTAKES, _EARLIER, NEW_CAUSES, _REWORDED)


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
