r"""A twenty-eighth class of hand-ins: mistakes of students' tracers, scene input and output no class tried, blind.

How it was written: from the habits students carry into this assignment from the tutorials and small public tracers
their programs grew from (Ray Tracing in One Weekend and its sequels: ``write_color``'s ``sqrt`` and ``clamp(0,
0.999)``, ``255.999``, the descending row loop, ``random_in_unit_sphere`` added to the normal, ``vup``, ``metal``'s
albedo and fuzz, ``defocus_angle``, ``max_depth = 50``, ``diffuse_light`` of 15 that emits from both faces, ``quad(Q,
u, v)``, ``write_color`` dividing by the samples; smallpt: its 2 x 2 sub-pixels, their tent filter and ``clamp``,
``toInt``'s gamma 2.2, its explicit-light ``E`` flag; Scratchapixel: ``radius2``, ``lookAt`` for a camera looking down
-z, its y-up hemisphere; pbrt's ``R * InvPi`` and its light pdf in area measure, its ``WritePFM``; Shadertoy's
``ACESFilm``, iq's vignette, per-pixel hashes and frame blending; Peter Shirley's ONB), not from the grader. Its
author read the other classes' specs and cause words, the catalogue (:mod:`mcrt.mutants`), the scene files and design
notes, mcrt's scene, camera and image code, :data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to stay clear of their mistakes; never the
grader's rules (what decides a cause) nor its reports, and graded none of it, not one case. Each cause and ``major``
flag was set from the mistake alone; every mistake is worded by a cause the other classes already have
(:data:`NEW_CAUSES` is empty), so ``SAME_MISTAKE`` needed no new entry. The mistakes differ from those of the
twenty-six other classes (:mod:`~mcrt.grade.accuracy.cases`, :mod:`~mcrt.grade.accuracy.outside` and the modules of
:data:`_EARLIER`, from :mod:`~mcrt.grade.accuracy.programs` to :mod:`~mcrt.grade.accuracy.unnoticed`) and from the
catalogue's bugs:

* **post-processing**: Ray Tracing in One Weekend's ``write_color`` (``sqrt`` and ``clamp(0, 0.999)``) kept before an
  EXR; smallpt's ``clamp`` of each 2 x 2 sub-pixel's mean before the pixel's; Shadertoy's ``ACESFilm`` (Narkowicz's
  fit) before an EXR; iq's vignette ``0.5 + 0.5 pow(16 u v (1 - u) (1 - v), 0.1)``;
* **writing the file**: a P3 PPM written by One Weekend's descending row loop from an image whose row 0 is the top
  (upside down); One Weekend's ``int(256 * clamp(r, 0, 0.999))`` with the gamma chapter skipped (linear codes);
  smallpt's ``toInt`` (gamma 2.2, not sRGB); a PFM written top row first (pbrt's ``WritePFM`` writes the bottom
  first);
* **materials**: pbrt's Lambertian ``R * InvPi`` used as the albedo of formulas that divide by pi already; the mirror
  as One Weekend's final scene's ``metal(color(0.7, 0.6, 0.5), 0.0)``; the mirror with ``metal``'s fuzz 0.3;
* **geometry**: Scratchapixel's sphere with ``radius2`` set to the radius; the walls as ``quad(Q, u, v)`` with the
  second corner passed for the edge ``u``; the tetrahedron's faces as ``combinations(range(4), 3)``, normals from their
  winding (one-sided: the inward ones black);
* **camera**: One Weekend's ``vup = (0, 1, 0)`` in a z-up scene (turned 90 degrees); Scratchapixel's ``lookAt``
  (forward from the target to the eye) with rays along +z (the view behind, mirrored); One Weekend's ``defocus_angle =
  0.6``, ``focus_dist = 10`` kept (a thin lens);
* **light model**: One Weekend's Cornell-box ``diffuse_light(color(15, 15, 15))``; the light sample's pdf 1 / A in
  area measure, not turned into solid angle; ``diffuse_light`` emitting from both faces;
* **integrator**: the bounce ``normal + random_in_unit_sphere()``; ``max_depth = 50``; smallpt's explicit-light ``E``
  left 1 after diffuse bounces (the light counted twice); a y-up cosine direction through Shirley's z-up ONB;
* **samples and passes**: a Shadertoy hash seeded by the pixel and ``iFrame`` left 0 (every sample the same);
  frames blended ``mix(acc, col, 0.1)`` from black; smallpt's tent filter about its sub-pixels; One Weekend's
  ``write_color`` dividing a mean by the samples again.

The correct hand-ins come in ways no class used: Mitsuba with the first bounce the normal plus One Weekend's
(second edition's) ``random_unit_vector`` (z and an angle, exactly cosine-distributed), Mitsuba with the first
bounce Peter Shirley's ``random_cosine_direction`` in his ONB, Mitsuba at twice the resolution and a quarter of the
samples averaged 2 x 2 (smallpt's sub-pixels, box-jittered), a P3 PPM as One Weekend writes it with the sRGB curve,
Shadertoy frames blended ``mix(acc, col, 1 / (frame + 1))`` (a running mean), Mitsuba with the first vertex's light
sample in pbrt's solid-angle pdf, Mitsuba with the first vertex's light sample on one of the light's two triangles
(pbrt's ``UniformSampleTriangle``), and an 8-bit PNG from a bottom-up framebuffer flipped on write (``stb``'s
``stbi_flip_vertically_on_write``).

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s ``edit`` and ``mitsuba_edit``), Mitsuba
renders at another spp, depth, resolution, camera or lens, Mitsuba's path integrator on rays a student's camera or
mirror makes (:func:`mcrt.grade.accuracy.unsaid._traced`, :func:`_fuzzy_metal`), its first vertex's direct light redone
as a student's light sample makes it (:func:`mcrt.grade.accuracy.unheralded._first_vertex`), its first bounce redrawn
(:func:`mcrt.grade.accuracy.unprompted._first_bounce`), or correct renders post-processed and written with NumPy,
Pillow and the standard library as students' programs do. mcrt renders none of it.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over :data:`CATEGORIES`: the 2nd, 4th, ... of
each category and of the correct hand-ins) are as in :mod:`~mcrt.grade.accuracy.unnoticed`, fixed before any case
was graded.
"""

from __future__ import annotations

import math
import zlib
from functools import partial
from itertools import combinations
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unbeknown, unbidden,
                                 unforeseen, unguessed, unheard, unheralded, unlooked, unmet, unnoticed, unprompted,
                                 unremarked, unremembered, unsaid, unseen, unsought, untold, untried, unvisited,
                                 unwonted)
from mcrt.grade.accuracy.cases import Spec
from mcrt.image_files import srgb_oetf

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


#: The classes after the first two, in the order they were written (their causes' words are this class's too).
_EARLIER = (programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked, unsought,
            unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted,
            unremarked, unremembered, unnoticed)


def _crc(name: str) -> int:
    return 1501000 + zlib.crc32(name.encode()) % 100000


_render = unseen._render
_posted = unseen._posted
_scene = unprompted._scene
_bsdf = unremarked._bsdf

#: The class's spp (the class is built at 64 x 64).
_S = 256
#: The assignment's maximum depth.
_DEPTH = 8


# --------------------------------------------------------------------------
# Post-processing (linear render in, what the program writes out)
# --------------------------------------------------------------------------


def _rtow_write_color(x):
    """One Weekend's ``write_color`` before the file: ``linear_to_gamma`` (``sqrt`` where positive, else 0), then
    ``interval(0.000, 0.999).clamp``: the values gamma-2 encoded and capped at 0.999."""
    return np.minimum(np.sqrt(np.maximum(np.asarray(x, np.float64), 0.0)), 0.999)


def _subpixels(x, *, spp: int, seed: int, clamp: bool):
    """smallpt's 2 x 2 sub-pixels: Mitsuba at twice the resolution and a quarter of the samples, each sub-pixel's mean
    (with ``clamp``, smallpt's ``clamp`` to [0, 1]) times 0.25 summed into its pixel."""
    h, w = x.shape[:2]
    sub = _render(2 * w, 2 * h, max(spp // 4, 1), seed)
    if clamp:
        sub = np.clip(sub, 0.0, 1.0)
    return sub.reshape(h, 2, w, 2, 3).mean(axis=(1, 3))


def _aces_narkowicz(x):
    """Shadertoy's ``ACESFilm`` (Krzysztof Narkowicz's fit) on the linear render: x (2.51 x + 0.03) / (x (2.43 x +
    0.59) + 0.14), clamped to [0, 1]."""
    v = np.maximum(np.asarray(x, np.float64), 0.0)
    return np.clip(v * (2.51 * v + 0.03) / (v * (2.43 * v + 0.59) + 0.14), 0.0, 1.0)


def _iq_vignette(x):
    """iq's vignette of Shadertoy, ``col *= 0.5 + 0.5 * pow(16.0 * q.x * q.y * (1.0 - q.x) * (1.0 - q.y), 0.1)``, q
    the pixel centre's ``fragCoord / iResolution``."""
    img = np.asarray(x, np.float64)
    h, w = img.shape[:2]
    qx, qy = (np.arange(w) + 0.5) / w, (np.arange(h) + 0.5) / h
    f = 0.5 + 0.5 * (16.0 * qy[:, None] * (1.0 - qy[:, None]) * qx[None, :] * (1.0 - qx[None, :])) ** 0.1
    return img * f[:, :, None]


# --------------------------------------------------------------------------
# Writers (the render in, the file a program writes)
# --------------------------------------------------------------------------


def _p3(codes: np.ndarray) -> bytes:
    """A plain (P3) PPM as One Weekend and smallpt print it: the header, then each pixel's three codes."""
    h, w = codes.shape[:2]
    body = "\n".join(" ".join(str(int(c)) for c in px) for px in np.asarray(codes).reshape(-1, 3))
    return f"P3\n{w} {h}\n255\n{body}\n".encode()


def _write_p3(codes: np.ndarray, folder: Path) -> Path:
    path = folder / "render.ppm"
    path.write_bytes(_p3(codes))
    return path


def _write_ppm_rows_from_bottom(image: np.ndarray, folder: Path) -> Path:
    """A P3 PPM printed by One Weekend's ``for (int j = image_height - 1; j >= 0; --j)`` from an image whose row 0 is
    the top: the bottom row written first."""
    return _write_p3(blind._srgb8(image)[::-1], folder)


def _rtow_linear_codes(image: np.ndarray) -> np.ndarray:
    """One Weekend's ``int(256 * interval(0.000, 0.999).clamp(r))`` of the linear value (no ``linear_to_gamma``)."""
    v = np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 0.999)
    return np.floor(256.0 * v).astype(np.uint8)


def _write_ppm_rtow_linear(image: np.ndarray, folder: Path) -> Path:
    return _write_p3(_rtow_linear_codes(image), folder)


def _smallpt_codes(image: np.ndarray) -> np.ndarray:
    """smallpt's ``toInt(x) = int(pow(clamp(x), 1 / 2.2) * 255 + .5)``."""
    v = np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 1.0)
    return np.floor(v ** (1.0 / 2.2) * 255.0 + 0.5).astype(np.uint8)


def _write_ppm_smallpt(image: np.ndarray, folder: Path) -> Path:
    return _write_p3(_smallpt_codes(image), folder)


def _write_pfm_top_first(image: np.ndarray, folder: Path) -> Path:
    """A PFM (scale -1: little-endian) whose rows are written top first (``img.astype('<f4').tobytes()``), where the
    format, and pbrt's ``WritePFM``, put the bottom row first."""
    h, w = image.shape[:2]
    path = folder / "render.pfm"
    path.write_bytes(f"PF\n{w} {h}\n-1\n".encode() + np.ascontiguousarray(image, "<f4").tobytes())
    return path


def _rtow_srgb_codes(image: np.ndarray) -> np.ndarray:
    """One Weekend's ``int(256 * interval(0.000, 0.999).clamp(c))`` of the sRGB-encoded value (its ``linear_to_gamma``
    replaced by the sRGB curve)."""
    v = srgb_oetf(np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 1.0))
    return np.floor(256.0 * np.clip(v, 0.0, 0.999)).astype(np.uint8)


def _write_ppm_rtow_srgb(image: np.ndarray, folder: Path) -> Path:
    return _write_p3(_rtow_srgb_codes(image), folder)


def _write_png_flipped_framebuffer(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB PNG from a framebuffer read bottom row first (``glReadPixels``) and written with ``stb``'s
    ``stbi_flip_vertically_on_write(1)``: the rows turned back, the codes as they are."""
    from PIL import Image

    gl = np.ascontiguousarray(blind._srgb8(image)[::-1])  # the framebuffer, bottom row first
    path = folder / "render.png"
    Image.fromarray(np.ascontiguousarray(gl[::-1]), "RGB").save(path, format="PNG", compress_level=1)
    return path


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _albedo_inv_pi(albedo) -> tuple[float, ...]:
    return tuple(float(a) / math.pi for a in albedo)


def _albedos_inv_pi(s):
    """Every Lambertian's albedo divided by pi: pbrt's ``f = R * InvPi`` used as the reflectance of formulas that
    divide by pi already (the light sample's rho Le G A / pi, the cosine bounce's weight rho)."""
    return unbidden._albedos_mapped(s, _albedo_inv_pi)


#: The mirror as the metal of One Weekend's final scene, ``metal(color(0.7, 0.6, 0.5), 0.0)``.
_METAL_TINT = (0.7, 0.6, 0.5)


def _mirror_tinted(d: dict) -> dict:
    from mcrt.scene import Mirror

    d = dict(d)
    d["sphere"] = dict(d["sphere"], bsdf=_bsdf(Mirror(reflectance=_METAL_TINT)))
    return d


#: Scratchapixel's sphere intersection tests against ``radius2``; set to the radius (1.5), its radius is sqrt(1.5).
_RADIUS_UNSQUARED = math.sqrt(1.5)


def _sphere_radius2_unsquared(s):
    from dataclasses import replace

    return replace(s, objects=tuple(replace(o, radius=_RADIUS_UNSQUARED) if o.name == "sphere" else o
                                    for o in s.objects))


def _quad_corner_as_edge(a, b, zf: float, zc: float) -> np.ndarray:
    """(2, 3, 3): One Weekend's ``quad(Q, u, v)`` of a wall with ``Q = (a, zf)``, ``v = (0, 0, zc - zf)`` and ``u`` the
    second corner ``(b, 0)`` itself for the edge ``b - a``: the corners Q, Q + u, Q + u + v, Q + v."""
    q = np.array([(*a, zf), (a[0] + b[0], a[1] + b[1], zf), (a[0] + b[0], a[1] + b[1], zc), (*a, zc)], np.float64)
    return q[np.array([(0, 1, 2), (0, 2, 3)])]


def _walls_quad_corner_as_edge(d: dict) -> dict:
    room = _scene().room
    for wl in room.walls:
        a, b = room.corners[wl.corners[0]], room.corners[wl.corners[1]]
        name = "wall_" + "".join(wl.corners)
        d = fresh._rebuilt(d, name, _quad_corner_as_edge(a, b, room.floor_z, room.ceiling_z),
                           _bsdf(fresh._surface(name).material))
    return d


def _tetra_combination_faces() -> np.ndarray:
    """(4, 3, 3): the tetrahedron's faces as ``combinations(range(4), 3)`` of its vertices, each wound in that order."""
    v = np.asarray(next(o for o in _scene().objects if o.name == "tetrahedron").vertices, np.float64)
    return np.stack([v[list(f)] for f in combinations(range(4), 3)])


def _inward(tris: np.ndarray) -> np.ndarray:
    """(n,) whether each face's winding normal (p1 - p0) x (p2 - p0) points into the tetrahedron."""
    centre = _tetra_combination_faces().reshape(-1, 3).mean(axis=0)
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    return np.einsum("ij,ij->i", n, tris.mean(axis=1) - centre) < 0


def _tetra_normals_by_winding(d: dict) -> dict:
    """The tetrahedron's faces wound as listed, one-sided (a Lambertian black from its back, as a shader that clamps
    ``dot(n, wi)`` at 0 is)."""
    sf = fresh._surface("tetrahedron")
    return fresh._rebuilt(d, "tetrahedron", _tetra_combination_faces(), _bsdf(sf.material)["bsdf"])


#: The upper face of the two-sided light, this far above the lower (between the light and the ceiling).
_UPPER_FACE = 0.002


def _light_both_faces(d: dict) -> dict:
    """The light emitting from both faces (One Weekend's ``diffuse_light``, whose ``emitted`` ignores the face): a
    second emitting square facing up, :data:`_UPPER_FACE` above the first."""
    from mcrt.mitsuba_scene import _light_surface, _mesh
    from mcrt.scene import Surface

    s = _scene()
    sf = next(x for x in s.surfaces() if x.material is None)
    up = np.asarray(sf.triangles, np.float64) + np.array([0.0, 0.0, _UPPER_FACE])
    emitter = {"type": "area", "radiance": {"type": "rgb", "value": [float(c) for c in s.light.radiance]}}
    return dict(d, light_upper=_mesh(_light_surface(Surface("light_upper", up, None), (0.0, 0.0, 1.0)), _bsdf(None),
                                     emitter))


def _no_roulette(d: dict) -> dict:
    """Russian roulette off (its depth past the maximum), as One Weekend's tracer has none."""
    return dict(d, integrator=dict(d["integrator"], rr_depth=1000))


# --------------------------------------------------------------------------
# The camera
# --------------------------------------------------------------------------

#: One Weekend's final scene's lens: ``defocus_angle = 0.6`` (degrees), ``focus_dist = 10``: an aperture of radius
#: focus_dist tan(defocus_angle / 2).
_FOCUS = 10.0
_APERTURE = _FOCUS * math.tan(math.radians(0.6 / 2.0))
_THIN_LENS = {"type": "thinlens", "aperture_radius": _APERTURE, "focus_distance": _FOCUS}


def _lookat_backwards(x, *, spp: int, seed: int):
    """Scratchapixel's ``lookAt`` (its forward from the target to the eye, for a camera that looks down -z) with rays
    along +z in camera space: the view behind the eye with the image's right kept: Mitsuba turned 180 degrees, its
    columns mirrored."""
    h, w = x.shape[:2]
    return _render(w, h, spp, seed, scene_edit=cases.yaw(180.0))[:, ::-1]


def _smallpt_tent(fx, fy, *, w: int, h: int):
    """smallpt's sub-pixel tent: the sample of pixel (i, j) at ``i + (sx + 0.5 + dx) / 2`` (dx from ``r1 = 2 rand``,
    ``r1 < 1 ? sqrt(r1) - 1 : 1 - sqrt(2 - r1)``), sx its sub-pixel, the same down; the uniform numbers those of the
    jitter within the pixel (sx its half, r1 the place within it)."""

    def axis(f, n):
        s = np.asarray(f, np.float64) * n
        i = np.minimum(np.floor(s), n - 1)
        frac = s - i
        sx = np.floor(2.0 * frac)
        r1 = 2.0 * (2.0 * frac - sx)
        dx = np.where(r1 < 1.0, np.sqrt(r1) - 1.0, 1.0 - np.sqrt(np.maximum(2.0 - r1, 0.0)))
        return (i + (sx + 0.5 + dx) / 2.0) / n

    return unsaid._pinhole(axis(fx, w), axis(fy, h))


def _smallpt_tent_render(x, *, spp: int, seed: int):
    h, w = x.shape[:2]
    return unsaid._traced(x, spp=spp, seed=seed, camera=partial(_smallpt_tent, w=w, h=h))


# --------------------------------------------------------------------------
# Light samples at the first vertex (unheralded._first_vertex's ``direct``)
# --------------------------------------------------------------------------


def _cos_surface(p, n, q) -> np.ndarray:
    """The estimator's geometry with the pdf 1 / A left in area measure: only the surface's max(0, n . wi)."""
    return np.maximum(np.einsum("ij,ij->i", n, unsaid._unit(q - p)), 0.0)


def _light_area_pdf(mscene, rng, p, n, rho, mitsuba):
    """pbrt's estimator f Le |n . wi| / pdf with the light's pdf 1 / A in area measure (not d^2 / (cos_light A)):
    rho / pi Le cos A where nothing lies between."""
    return unbeknown._light_sampled(mscene, rng, p, n, rho, mitsuba, geometry=_cos_surface)


def _light_twice(mscene, rng, p, n, rho, mitsuba):
    """The light sample's direct light and the bounce's own hit of the light (smallpt's ``E`` left 1): twice it."""
    return 2.0 * np.asarray(mitsuba, np.float64)


def _light_solid_angle(mscene, rng, p, n, rho, mitsuba):
    """pbrt's light sample: q uniform on the square, its pdf turned into solid angle, pdf = d^2 / (cos_light A), and
    f Le |n . wi| / pdf with f = rho / pi where nothing lies between."""
    lt = _scene().light
    q = unbeknown._light_points(rng, len(p))
    wi = unsaid._unit(q - p)
    cos_light = np.abs(wi[:, 2])
    pdf = np.sum((q - p) ** 2, axis=1) / np.maximum(cos_light * lt.area, 1e-12)
    cos_s = np.maximum(np.einsum("ij,ij->i", n, wi), 0.0) * (wi[:, 2] > 0.0)
    f = np.where(unbeknown._unblocked(mscene, p, q), cos_s / pdf / math.pi, 0.0)
    return rho * f[:, None] * np.asarray(lt.radiance, np.float64)


def _light_triangles() -> np.ndarray:
    s = _scene()
    return np.asarray(next(x for x in s.surfaces() if x.material is None).triangles, np.float64)


def _triangle_points(rng, m: int) -> np.ndarray:
    """(m, 3) points on the light: one of its two triangles (of equal area) at random, a point in it by pbrt's
    ``UniformSampleTriangle`` (b0 = 1 - sqrt(u0), b1 = u1 sqrt(u0))."""
    tris = _light_triangles()
    k = rng.integers(0, len(tris), m)
    u0, u1 = rng.random((2, m))
    su = np.sqrt(u0)
    b0, b1 = 1.0 - su, u1 * su
    t = tris[k]
    return b0[:, None] * t[:, 0] + b1[:, None] * t[:, 1] + (1.0 - b0 - b1)[:, None] * t[:, 2]


def _light_on_triangles(mscene, rng, p, n, rho, mitsuba):
    lt = _scene().light
    q = _triangle_points(rng, len(p))
    g = np.where(unbeknown._unblocked(mscene, p, q), unbeknown._geometry(p, n, q), 0.0)
    return rho * (g * lt.area / math.pi)[:, None] * np.asarray(lt.radiance, np.float64)


def _light_sample(name: str, direct) -> dict:
    """A spec's post-process: Mitsuba's path with its first vertex's light sample made by ``direct``."""
    return _posted(name, partial(unheralded._first_vertex, spp=_S, seed=_crc(name), direct=direct))


# --------------------------------------------------------------------------
# Mirror and bounces
# --------------------------------------------------------------------------

#: One Weekend's ``metal`` fuzz the program kept.
_FUZZ = 0.3


def _unit_vectors(rng, m: int) -> np.ndarray:
    """(m, 3) unit vectors uniform on the sphere, as One Weekend's second edition draws ``random_unit_vector``: an
    angle a in [0, 2 pi), z in [-1, 1], r = sqrt(1 - z^2)."""
    a = 2.0 * math.pi * rng.random(m)
    z = 2.0 * rng.random(m) - 1.0
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(a), r * np.sin(a), z], axis=1)


def _fuzzed(rng, r: np.ndarray, nrm: np.ndarray, *, fuzz: float = _FUZZ):
    """One Weekend's ``metal::scatter``: ``unit_vector(reflected) + fuzz * random_unit_vector()``, absorbed (black)
    where it points below the surface: (directions, absorbed)."""
    s = unsaid._unit(r) + fuzz * _unit_vectors(rng, len(r))
    return unsaid._unit(s), np.einsum("ij,ij->i", s, nrm) <= 0.0


def _fuzzy_metal(x, *, spp: int, seed: int):
    """Camera rays that meet the sphere scattered by :func:`_fuzzed` there (the absorbed ones black), Mitsuba's path
    of the 7 segments left from there; the rest Mitsuba's path."""
    h, w = x.shape[:2]
    scenes = {0: unsaid._loaded(_DEPTH), 1: unsaid._loaded(_DEPTH - 1)}
    c, _ = unsaid._sphere()
    rng = np.random.default_rng(seed + 29)
    total = np.zeros((h * w, 3))
    for cseed, n, fx, fy in unsaid._lanes(w, h, spp, seed):
        o, d = (np.array(a, np.float64) for a in unsaid._pinhole(fx, fy))
        o, r, used = unsaid._reflected(o, d)
        hit = used == 1
        nd, absorbed = _fuzzed(rng, r, unsaid._unit(o - c))
        d = np.where(hit[:, None], nd, r)
        L = np.zeros((len(o), 3))
        for k in (0, 1):
            sel = used == k
            if sel.any():
                L[sel] = unsaid._sampled(scenes[k], o[sel], d[sel], cseed + 7919 * k)
        L[hit & absorbed] = 0.0
        total += L.reshape(h * w, n, 3).sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _ball_points(rng, m: int) -> np.ndarray:
    """(m, 3) points uniform in the unit ball: One Weekend's ``random_in_unit_sphere`` (the cube's points kept inside)."""
    return unnoticed._ball_by_rejection(rng, m)


def _normal_plus_ball(rng, n):
    """One Weekend's first diffuse bounce, ``target = p + normal + random_in_unit_sphere()``: the direction the normal
    plus a point in the ball (not on its surface), normalised, weight 1 (times the albedo): more towards the normal
    than cosine (a cos^3-like density)."""
    s = n + _ball_points(rng, len(n))
    length = np.linalg.norm(s, axis=1, keepdims=True)
    return np.where(length > 1e-9, s / np.maximum(length, 1e-12), n), np.ones(len(n))


def _normal_plus_unit_vector(rng, n):
    """The normal plus One Weekend's (second edition's) ``random_unit_vector`` (:func:`_unit_vectors`), normalised:
    exactly cosine-distributed, weight 1."""
    s = n + _unit_vectors(rng, len(n))
    length = np.linalg.norm(s, axis=1, keepdims=True)
    return np.where(length > 1e-9, s / np.maximum(length, 1e-12), n), np.ones(len(n))


def _shirley_onb(w: np.ndarray):
    """Peter Shirley's ``onb::build_from_w``: a = |w.x| > 0.9 ? (0, 1, 0) : (1, 0, 0), v = unit(w x a), u = w x v:
    (u, v)."""
    a = np.where((np.abs(w[:, 0]) > 0.9)[:, None], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0])
    v = unsaid._unit(np.cross(w, a))
    return np.cross(w, v), v


def _cosine_local(rng, m: int) -> np.ndarray:
    """(m, 3) Shirley's ``random_cosine_direction``: phi = 2 pi r1, (cos phi sqrt(r2), sin phi sqrt(r2), sqrt(1 -
    r2)), about z."""
    r1, r2 = rng.random((2, m))
    phi = 2.0 * math.pi * r1
    return np.stack([np.cos(phi) * np.sqrt(r2), np.sin(phi) * np.sqrt(r2), np.sqrt(1.0 - r2)], axis=1)


def _shirley_cosine(rng, n):
    """``onb.local(random_cosine_direction())`` = a.x u + a.y v + a.z w: cosine-weighted about the normal, weight 1."""
    a = _cosine_local(rng, len(n))
    u, v = _shirley_onb(n)
    return unsaid._unit(a[:, :1] * u + a[:, 1:2] * v + a[:, 2:] * n), np.ones(len(n))


def _y_up_through_onb(rng, n):
    """Scratchapixel's y-up hemisphere sample (sin theta cos phi, cos theta, sin theta sin phi), cosine-weighted,
    through Shirley's ``onb.local`` (whose w, the normal, is z): the cosine axis along the tangent v, half the
    directions under the surface (they meet it again at once and go on from there), weight 1."""
    a = _cosine_local(rng, len(n))[:, [0, 2, 1]]  # (x, y, z) = (sin cos, cos, sin sin)
    u, v = _shirley_onb(n)
    return unsaid._unit(a[:, :1] * u + a[:, 1:2] * v + a[:, 2:] * n), np.ones(len(n))


# --------------------------------------------------------------------------
# Samples and passes
# --------------------------------------------------------------------------

#: Shadertoy frames of the program, and the spp of each.
_FRAMES, _FRAME_SPP = 8, 32


def _frames_blended(x, *, seed: int, alpha=None):
    """:data:`_FRAMES` Mitsuba frames of :data:`_FRAME_SPP` spp blended as a Shadertoy buffer does, ``acc = mix(acc,
    col, a)`` from a black buffer: ``a`` the constant ``alpha`` or, without it, 1 / (frame + 1) (a running mean)."""
    h, w = x.shape[:2]
    acc = np.zeros((h, w, 3))
    for k in range(_FRAMES):
        a = alpha if alpha is not None else 1.0 / (k + 1)
        acc = acc * (1.0 - a) + _render(w, h, _FRAME_SPP, seed + 7919 * k) * a
    return acc


#: The blend of a buffer that holds ``mix(acc, col, 0.1)``.
_MIX = 0.1


def _divided_again(x, *, spp: int = _S):
    """One Weekend's ``write_color(out, pixel_color, samples_per_pixel)`` (it scales by 1 / samples_per_pixel) handed
    the pixel's mean: divided by the spp twice."""
    return np.asarray(x, np.float64) / spp


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_rtow_write_color_before_exr", "pp_smallpt_subpixel_clamp", "pp_shadertoy_aces_fit",
                        "pp_shadertoy_iq_vignette"),
    "file": ("file_ppm_rtow_rows_from_bottom", "file_ppm_rtow_gamma_chapter_skipped", "file_ppm_smallpt_toint",
             "file_pfm_top_row_first"),
    "materials": ("lambertian_pbrt_inv_pi_kept", "mirror_rtow_final_scene_metal", "mirror_rtow_metal_fuzz"),
    "geometry": ("sphere_scratchapixel_radius2_unsquared", "walls_rtow_quad_corner_for_edge",
                 "tetra_faces_combinations_winding"),
    "camera": ("camera_rtow_vup_y_kept", "camera_scratchapixel_lookat_backwards", "camera_rtow_defocus_kept"),
    "light": ("light_rtow_cornell_radiance", "light_pbrt_pdf_area_measure", "light_rtow_emits_both_faces"),
    "integrator": ("bounce_rtow_normal_plus_in_unit_sphere", "depth_rtow_max_depth_50", "light_smallpt_e_flag_kept",
                   "bounce_y_up_sample_in_z_up_onb"),
    "samples": ("samples_shadertoy_hash_frame_zero", "frames_shadertoy_mix_constant", "pixel_smallpt_tent_subpixels",
                "samples_rtow_write_color_divides_again"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    c = _crc
    return (
        # Post-processing
        Spec("pp_rtow_write_color_before_exr", "encoding", True, **_posted("rtow_write_color", _rtow_write_color),
             truth="One Weekend's write_color kept in front of an EXR writer: linear_to_gamma (sqrt of each positive "
             "component) and interval(0.000, 0.999).clamp, the floats stored: every value its square root, the "
             "light and whatever is brighter than 0.998 written 0.999, as EXR"),
        Spec("pp_smallpt_subpixel_clamp", "tone_map", True, held_out=True, **_posted("smallpt_clamp", partial(
            _subpixels, spp=_S, seed=c("pp_smallpt_subpixel_clamp"), clamp=True)),
             truth="smallpt's accumulation c[i] = c[i] + Vec(clamp(r.x), clamp(r.y), clamp(r.z)) * .25 kept with "
             "an EXR writer: each of the 2 x 2 sub-pixels' means clamped to [0, 1] before the pixel's sum: the "
             "light 1 for 20, the edges of the light and its reflection in between, the rest right, as EXR"),
        Spec("pp_shadertoy_aces_fit", "tone_map", True, **_posted("aces_fit", _aces_narkowicz),
             truth="Shadertoy's ACESFilm (Narkowicz's fit x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14), clamped to "
             "[0, 1]) applied to the linear render before the EXR: the dark values a little lower (0.05 to 0.044), "
             "the middle raised (0.3 to 0.44), 1 lowered to 0.80, the light 1, as EXR"),
        Spec("pp_shadertoy_iq_vignette", "falloff", True, held_out=True, **_posted("iq_vignette", _iq_vignette),
             truth="iq's vignette of Shadertoy, col *= 0.5 + 0.5 * pow(16 q.x q.y (1 - q.x) (1 - q.y), 0.1) (q the "
             "pixel's fragCoord / iResolution), kept from a shader the tracer began as: the centre right, the "
             "image darker towards its edges and most in its corners (0.75 at the corner pixels at 64 x 64), as EXR"),
        # Writing the file
        Spec("file_ppm_rtow_rows_from_bottom", "orientation", True, writer=_write_ppm_rows_from_bottom,
             file="ppm-p3-bottom-first",
             truth="a P3 PPM printed by One Weekend's loop for (int j = image_height - 1; j >= 0; --j) from an image "
             "array whose row 0 is the top (its camera Scratchapixel's, Py = 1 - 2 (j + 0.5) / H): the bottom row "
             "written first, the image upside down, the floor at the top"),
        Spec("file_ppm_rtow_gamma_chapter_skipped", "encoding", True, held_out=True, writer=_write_ppm_rtow_linear,
             file="ppm-p3-linear",
             truth="a P3 PPM with One Weekend's int(256 * interval(0.000, 0.999).clamp(r)) of the linear value, its "
             "chapter on gamma (linear_to_gamma) skipped: linear codes read as sRGB, the image far too dark and "
             "contrasty (0.2 written 51 for 124)"),
        Spec("file_ppm_smallpt_toint", "encoding", writer=_write_ppm_smallpt, file="ppm-p3-smallpt",
             truth="a P3 PPM written with smallpt's toInt(x) = int(pow(clamp(x), 1 / 2.2) * 255 + .5), a pure "
             "gamma 2.2 for the sRGB curve: the dark values darker (0.002 written 15 for 7, 0.01 written 31 for 25), "
             "the bright ones within a code or two"),
        Spec("file_pfm_top_row_first", "orientation", True, held_out=True, writer=_write_pfm_top_first,
             file="pfm-top-first",
             truth="a PFM (scale -1, little-endian) written with the rows in the image's order, top first, by a port "
             "of pbrt's WritePFM that dropped its flip (the format stores the bottom row first): the image read "
             "upside down"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("lambertian_pbrt_inv_pi_kept", "brdf_norm", True, edit=_albedos_inv_pi,
             truth="the Lambertian's BRDF taken from pbrt as f = R * InvPi and used as the reflectance of the "
             "assignment's formulas that divide by pi already (the light sample's rho Le G A / pi, the cosine "
             "bounce's weight rho): every diffuse reflection a factor pi too dark, the light seen right"),
        Spec("mirror_rtow_final_scene_metal", "albedo", True, held_out=True, mitsuba_edit=_mirror_tinted,
             truth="the mirror made as the metal of One Weekend's final scene, metal(color(0.7, 0.6, 0.5), 0.0), for "
             "a perfect mirror: what the sphere reflects darker and tinted orange-brown"),
        Spec("mirror_rtow_metal_fuzz", "material", True, **_posted("metal_fuzz", partial(
            _fuzzy_metal, spp=_S, seed=_crc("mirror_rtow_metal_fuzz"))),
             truth="the mirror made with One Weekend's metal and its fuzz 0.3 kept (for camera rays; Mitsuba's path "
             "after it): unit_vector(reflected) + 0.3 * random_unit_vector(), rays under the surface absorbed: the "
             "reflection in the sphere blurred, its rim dark"),
        # Geometry
        Spec("sphere_scratchapixel_radius2_unsquared", "object_size", True, edit=_sphere_radius2_unsquared,
             truth="the sphere made with Scratchapixel's intersection, which tests against radius2, and its "
             "constructor's radius2(r * r) written radius2(r): 1.5 for 2.25, a sphere of radius sqrt(1.5) = 1.22 "
             "for 1.5 at the right centre"),
        Spec("walls_rtow_quad_corner_for_edge", "object_shape", True, held_out=True,
             mitsuba_edit=_walls_quad_corner_as_edge,
             truth="each wall built with One Weekend's quad(Q, u, v), Q its first corner at the floor, v its height, "
             "and u given the second corner (b.x, b.y, 0) for the edge b - a: every wall from its first corner to "
             "the sum of its corners, the room's sides out of place, the void seen between them"),
        Spec("tetra_faces_combinations_winding", "normals", True, mitsuba_edit=_tetra_normals_by_winding,
             truth="the tetrahedron's faces listed as combinations(range(4), 3) of its vertices and each face's "
             "normal taken from that winding, (v1 - v0) x (v2 - v0), dot(n, wi) clamped at 0: the faces wound "
             "inwards shaded from their back, black"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    return (
        # Camera
        Spec("camera_rtow_vup_y_kept", "camera_rotation", True, edit=cases.roll(-90.0),
             truth="One Weekend's camera with its vup = vec3(0, 1, 0) kept in the assignment's z-up scene: u = "
             "unit(cross(vup, w)) = +z, v = +y: the image turned a quarter, the ceiling on the right, the floor on "
             "the left"),
        Spec("camera_scratchapixel_lookat_backwards", "camera_rotation", True, held_out=True, **_posted(
            "lookat_backwards", partial(_lookat_backwards, spp=_S, seed=_crc("camera_scratchapixel_lookat_backwards"))),
             truth="Scratchapixel's lookAt matrix (forward = normalize(from - to), for a camera that looks down -z) "
             "with rays (Px, Py, 1) in camera space, One Weekend's way: the view behind the eye, towards the corner "
             "A, left and right as the forward view's (mirrored)"),
        Spec("camera_rtow_defocus_kept", "camera_model", sensor=_THIN_LENS,
             truth="One Weekend's camera with the final scene's defocus_angle = 0.6 and focus_dist = 10 kept: a thin "
             "lens of radius 10 tan(0.3 degrees) = 0.052 focused at 10: the near walls and objects slightly out of "
             "focus, the far wall sharp"),
        # Light model
        Spec("light_rtow_cornell_radiance", "light_radiance", True, edit=cases.light(radiance=(15.0, 15.0, 15.0)),
             truth="the light made as One Weekend's Cornell box light, diffuse_light(color(15, 15, 15)), for the "
             "assignment's 20: the light and everything it lights three quarters as bright"),
        Spec("light_pbrt_pdf_area_measure", "light_pdf", True, held_out=True, **_light_sample(
            "light_pbrt_pdf_area_measure", _light_area_pdf),
             truth="the light sample's estimator f Le AbsDot(wi, n) / pdf from pbrt with the pdf 1 / A in area "
             "measure, never turned into solid angle (d^2 / (cos_light A)), at the first surface a camera ray "
             "meets (Mitsuba's path after it): no falloff with distance nor cosine at the light: the surfaces many "
             "times too bright, the farthest most, the light seen right"),
        Spec("light_rtow_emits_both_faces", "light_twosided", True, mitsuba_edit=_light_both_faces,
             truth="the light made with One Weekend's diffuse_light, whose emitted() ignores the face a ray meets: "
             "the square emits from its upper face too, onto the ceiling a hundredth above it: the ceiling over "
             "the light lit (hidden from the eye by the light), the room a little brighter from what it sends "
             "back"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples and passes."""
    c = _crc
    return (
        # Integrator
        Spec("bounce_rtow_normal_plus_in_unit_sphere", "indirect_scale", **_posted("normal_plus_ball", partial(
            unprompted._first_bounce, spp=_S, seed=c("bounce_rtow_normal_plus_in_unit_sphere"),
            draw=_normal_plus_ball)),
             truth="the diffuse bounce as One Weekend first writes it, target = p + normal + random_in_unit_sphere() "
             "(a point in the ball, not on it), weighted as a cosine sample, at the first surface a camera ray meets "
             "(Mitsuba's path after it): the bounces too close to the normal (a cos^3-like density), the indirect "
             "light slightly off, the direct light right"),
        Spec("depth_rtow_max_depth_50", "depth", held_out=True, max_depth=50,
             truth="One Weekend's max_depth = 50 kept for the assignment's 8: paths of up to 50 segments, the "
             "image a little brighter, most in the shadows"),
        Spec("light_smallpt_e_flag_kept", "direct_twice", True, **_light_sample(
            "light_smallpt_e_flag_kept", _light_twice),
             truth="smallpt's explicit-light path tracer ported with its E flag left 1 after a diffuse bounce (it "
             "returns obj.e * E + e + ...): the light a bounce meets counted beside the light sample that already "
             "counted it, at the first surface a camera ray meets (Mitsuba's path after it): the direct light on "
             "the surfaces seen twice as bright, the light seen right"),
        Spec("bounce_y_up_sample_in_z_up_onb", "indirect_scale", True, held_out=True, **_posted(
            "y_up_onb", partial(unprompted._first_bounce, spp=_S, seed=c("bounce_y_up_sample_in_z_up_onb"),
                                draw=_y_up_through_onb)),
             truth="Scratchapixel's y-up hemisphere sample (sin theta cos phi, cos theta, sin theta sin phi) handed "
             "to Peter Shirley's onb.local, whose w (the normal) is z, at the first surface a camera ray meets "
             "(Mitsuba's path after it): the bounces about a tangent, half of them into the surface, the indirect "
             "light wrong, the direct light right"),
        # Samples and passes
        Spec("samples_shadertoy_hash_frame_zero", "same_seed", True, spp=1, declared_spp=256,
             truth="each sample's random numbers from a Shadertoy hash of the pixel and iFrame, the frame left 0 "
             "in a loop of 256 samples: every sample of a pixel the same path: the mean one sample's, as noisy as "
             "1 spp, 256 declared"),
        Spec("frames_shadertoy_mix_constant", "sample_count", True, held_out=True, **_posted(
            "mix_constant", partial(_frames_blended, seed=c("frames_shadertoy_mix_constant"), alpha=_MIX)),
             truth="8 frames of 32 spp blended as a Shadertoy buffer, col = mix(texelFetch(iChannel0, ...).rgb, col, "
             "0.1), from a black buffer: the last frame weighted 0.1, the first 0.048, the sum 1 - 0.9^8 = 0.57: "
             "the image 43 % too dark"),
        Spec("pixel_smallpt_tent_subpixels", "pixel_footprint", **_posted("smallpt_tent", partial(
            _smallpt_tent_render, spp=_S, seed=c("pixel_smallpt_tent_subpixels"))),
             truth="each pixel's samples placed by smallpt's 2 x 2 sub-pixels and tent filter, (sx + 0.5 + dx) / 2 "
             "with dx in [-1, 1]: a footprint from a quarter pixel before the pixel to a quarter after it, "
             "weighted to the sub-pixels' centres: the image a little soft"),
        Spec("samples_rtow_write_color_divides_again", "sample_count", True, held_out=True, **_posted(
            "divided_again", _divided_again),
             truth="each pixel's mean handed to One Weekend's write_color(out, pixel_color, samples_per_pixel), "
             "which scales by 1 / samples_per_pixel itself: divided by 256 twice, the image black but for the "
             "light (0.08)"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_bounce_rtow_unit_vector", None, **_posted("normal_plus_unit_vector", partial(
            unprompted._first_bounce, spp=_S, seed=c("ok_bounce_rtow_unit_vector"), draw=_normal_plus_unit_vector)),
             truth="Mitsuba path 256 spp with the first bounce the normal plus One Weekend's second edition's "
             "random_unit_vector (an angle and z uniform, r = sqrt(1 - z^2)), normalised: cosine-weighted, EXR"),
        Spec("ok_bounce_shirley_onb", None, held_out=True, **_posted("shirley_onb", partial(
            unprompted._first_bounce, spp=_S, seed=c("ok_bounce_shirley_onb"), draw=_shirley_cosine)),
             truth="Mitsuba path 256 spp with the first bounce Peter Shirley's random_cosine_direction in his "
             "onb::build_from_w of the normal, EXR"),
        Spec("ok_smallpt_subpixels_box", None, **_posted("smallpt_subpixels", partial(
            _subpixels, spp=_S, seed=c("ok_smallpt_subpixels_box"), clamp=False)),
             truth="Mitsuba path at twice the resolution, 64 spp, each 2 x 2 block's means times 0.25 summed (smallpt's "
             "sub-pixels, each jittered over its own square, no clamp): 256 spp a pixel, EXR"),
        Spec("ok_ppm_rtow_p3_srgb", None, held_out=True, spp=200, writer=_write_ppm_rtow_srgb, file="ppm-p3-srgb",
             truth="Mitsuba path 200 spp, a P3 PPM as One Weekend prints it, int(256 * interval(0.000, "
             "0.999).clamp(c)), with the sRGB curve in place of its linear_to_gamma"),
        Spec("ok_shadertoy_running_mean", None, **_posted("running_mean", partial(
            _frames_blended, seed=c("ok_shadertoy_running_mean"))),
             truth="Mitsuba path, 8 frames of 32 spp blended as a Shadertoy buffer with mix(acc, col, 1 / (frame + "
             "1)) from black: their running mean, 256 spp, EXR"),
        Spec("ok_light_pbrt_solid_angle", None, held_out=True, **_light_sample(
            "ok_light_pbrt_solid_angle", _light_solid_angle),
             truth="Mitsuba path 256 spp with the first vertex's light sample as pbrt makes it: a point uniform on "
             "the square, its pdf 1 / A turned into solid angle, d^2 / (cos_light A), f Le AbsDot(wi, n) / pdf, "
             "EXR"),
        Spec("ok_light_pbrt_triangle_samples", None, **_light_sample(
            "ok_light_pbrt_triangle_samples", _light_on_triangles),
             truth="Mitsuba path 256 spp with the first vertex's light sample on one of the light's two triangles "
             "drawn at random, a point in it by pbrt's UniformSampleTriangle (b0 = 1 - sqrt(u0), b1 = u1 sqrt(u0)), "
             "EXR"),
        Spec("ok_png_framebuffer_flipped", None, held_out=True, spp=184, writer=_write_png_flipped_framebuffer,
             file="png-flipped-framebuffer",
             truth="Mitsuba path 184 spp, an 8-bit sRGB PNG from a framebuffer read bottom row first and written "
             "with stb's stbi_flip_vertically_on_write(1): the rows turned back"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "encoding": "the values' encoding (a tutorial's gamma 2 or 2.2 for sRGB, linear codes in a display file)",
    "tone_map": "a tone map, clamp or curve applied before saving (sub-pixels clamped to 1, a filmic curve)",
    "falloff": "a fall-off across the image (a vignette kept from a shader)",
    "orientation": "the image written flipped (rows in the wrong order)",
    "brdf_norm": "a BRDF's normalisation (a Lambertian divided by pi where the formulas divide already)",
    "albedo": "a surface's colour (the mirror tinted)",
    "material": "an object rendered with another material (a fuzzy metal for the mirror)",
    "object_size": "an object's size (the sphere's squared radius set to the radius)",
    "object_shape": "an object's shape (walls built from a corner taken for an edge)",
    "normals": "surface normals facing the wrong way (faces wound inwards, one-sided shading)",
    "camera_rotation": "the camera's rotation (up or forward vector of another convention)",
    "camera_model": "another camera model (a thin lens)",
    "light_radiance": "the light's radiance (another scene's)",
    "light_pdf": "the light sampled wrongly (its pdf left in area measure): the light seen right, its light on "
                 "surfaces not",
    "light_twosided": "the light emitting from both faces",
    "indirect_scale": "the indirect light wrong (bounces not cosine-distributed), the direct light right",
    "depth": "the path depth (a tutorial's maximum depth)",
    "direct_twice": "direct light counted twice (the light a bounce meets and the light sample)",
    "same_seed": "samples that should be independent made with the same random numbers",
    "sample_count": "each pixel's sum divided or weighted wrongly (frames blended by a constant, divided twice)",
    "pixel_footprint": "each pixel's samples not spread over its square (a tent reaching past it)",
}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = blind.class_causes(MISTAKES, _EARLIER, NEW_CAUSES, _REWORDED)


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
