r"""A twenty-third class of hand-ins: mistakes of students' tracers, scene input and output no class tried, blind.

How it was written: from what goes wrong in code ported from C++ and GLSL, shader
tutorials, game engines and textbook renderers (Khronos' neutral tone map, AMD's
contrast-adaptive sharpening, a grading LUT's half-texel offset, a physical camera's
default exposure, RGBM in a PNG, stb_image_write's stride, an engine's ACEScg working
space, a float's high half taken for a half float, colours kept in bytes, Blinn-Phong's
half vector, ``PI`` declared ``int``, a BVH's slab test on flat boxes, a normal map
never decoded, an icosphere never projected, a Panini projection, the eye read from a
view matrix, a TAA's Halton table, C's ``1 / 2``, a direction transformed as a point, a
colour class's gamma on an HDR radiance, Ray Tracing in One Weekend's unit vector in a
shader, HLSL's ``float3x3`` rows in GLSL's ``mat3`` columns, C's ``1 / 2`` again, the
roulette's division on the wrong variable, an RGBA8 accumulation target, a TAA
resolve's tone map, fixed-point atomics and checkerboard rendering), not from the
grader. Its author
read the other classes' specs and cause words, the catalogue (:mod:`mcrt.mutants`),
the scene files and design notes, mcrt's scene, camera and image code,
:data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to stay
clear of their mistakes; never the grader's rules (what decides a cause) nor its
reports, and graded none of it, not one case. Each cause and ``major`` flag was set
from the mistake alone; every mistake is worded by a cause the other classes
already have (:data:`NEW_CAUSES` is empty), so ``SAME_MISTAKE`` needed no new
entry. The mistakes differ from those of the twenty-two other classes
(:mod:`~mcrt.grade.accuracy.cases`, :mod:`~mcrt.grade.accuracy.outside` and the
modules of :data:`_EARLIER`, from :mod:`~mcrt.grade.accuracy.programs` to
:mod:`~mcrt.grade.accuracy.unlooked`) and from the catalogue's bugs:

* **post-processing**: Khronos' PBR Neutral tone map (a glTF viewer's); AMD's
  contrast-adaptive sharpening (CAS) at its default sharpness; an identity
  colour-grading LUT of 16 entries a side sampled without the half-texel scale
  and offset; a physical camera's exposure at Filament's defaults (f/16, 1/125 s,
  ISO 100) on an indoor render;
* **writing the file**: RGBM (range 6) in an RGBA PNG, as an engine stores HDR
  in 8 bits; ``stbi_write_png`` given the width for the stride in bytes; the EXR
  in ACEScg, an engine's working space; a float's upper 16 bits written as a half
  float;
* **materials**: the albedos kept as bytes (``uint8_t(a * 255)``) and read back
  over 256; Lambert's cosine taken with Blinn-Phong's half vector in the light
  sample; ``const int PI = 3.14159;`` (3) in the BRDF;
* **geometry**: a BVH whose slab test wants ``tmax > tmin``, so that the flat
  boxes of axis-aligned faces are never met; a flat normal map's texel never
  decoded (``* 2 - 1``); the sphere an icosphere whose midpoints were never pushed
  onto it;
* **camera**: a Panini projection (distance 1); the eye read from the view
  matrix's translation column; the jitter from a TAA's 8-entry Halton table;
* **light model**: the light's half-size ``1 / 2 * size`` (C's integer 1 / 2); the
  light's normal transformed as a point (``vec4(n, 1.0)``) in its sample; the
  radiance gamma-decoded by a colour class (``pow(c, 2.2)``);
* **integrator**: Ray Tracing in One Weekend's ``random_unit_vector`` in a shader
  whose ``rand()`` lies in [0, 1) (no ``* 2 - 1``: one octant); HLSL's ``mul(l,
  float3x3(T, B, N))`` ported as GLSL's ``l * mat3(T, B, N)``; the bounce's height
  ``pow(1 - u1, 1 / 2)`` (an exponent of 0); Russian roulette dividing the radiance,
  not the throughput;
* **samples and passes**: 1-spp frames blended into an RGBA8 target; the frames
  resolved in a tone-mapped space (a TAA trick); the film as 32-bit fixed-point
  atomics; checkerboard rendering with the missing half filled from neighbours.

The correct hand-ins come in ways no class used: Mitsuba with sub-pixel offsets
from a PCG hash (a shader's stateless random numbers), a float EXR whose windows
start at the viewport's origin in an engine's window, Mitsuba with the camera's
up not perpendicular to its view (the look-at orthogonalises it), a 32-bit TGA
2.0 with its footer, mcrt with MIS and one light sample a vertex, a Radiance
picture named ``.pic`` with its VIEW line, Mitsuba rendering bottom row first
(its sensor's y flipped) and flipped back, and an EXR written byte by byte as
miniexr writes one.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s ``edit``
and ``mitsuba_edit``), Mitsuba's path integrator on the rays or sub-pixel offsets a
student's camera makes (:func:`mcrt.grade.accuracy.unsaid._traced`,
:func:`mcrt.grade.accuracy.unforeseen._mean_through`), its first vertex's direct
light redone as a student's light sample makes it
(:func:`mcrt.grade.accuracy.unheralded._first_vertex`), its first bounce redrawn
(:func:`mcrt.grade.accuracy.unprompted._first_bounce`), same-seed renders and
samples combined where light transport is linear in them (paths of each length, the
light seen, :func:`mcrt.grade.accuracy.unbeknown._camera_samples`), its samples
combined as a student's loop combines them
(:func:`mcrt.grade.accuracy.unbidden._all_samples`), or correct renders
post-processed and written with NumPy, Pillow, OpenEXR's bindings and the standard
library as students' programs do. mcrt renders only a correct hand-in.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over
:data:`CATEGORIES`: the 2nd, 4th, ... of each category and of the correct
hand-ins) are as in :mod:`~mcrt.grade.accuracy.unlooked`, fixed before any case
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
                                 unforeseen, unguessed, unheard, unheralded, unlooked, unmet, unprompted, unsaid,
                                 unseen, unsought, untold, untried, unvisited)
from mcrt.grade.accuracy.cases import Spec

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


#: The classes after the first two, in the order they were written (their causes' words are this class's too).
_EARLIER = (programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked, unsought,
            unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked)


def _crc(name: str) -> int:
    return 1001000 + zlib.crc32(name.encode()) % 100000


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


def _pbr_neutral(x):
    """Khronos' PBR Neutral tone map (``PBRNeutralToneMapping``, the glTF sample viewer's), each pixel: the smallest
    channel's offset (``x - 6.25 x^2`` under 0.08, else 0.04) taken off, a peak over 0.76 compressed towards 1 and the
    colour desaturated towards it by 0.15."""
    c = np.asarray(x, np.float64)
    start, desaturation = 0.8 - 0.04, 0.15
    lo = c.min(axis=2, keepdims=True)
    c = c - np.where(lo < 0.08, lo - 6.25 * lo * lo, 0.04)
    peak = c.max(axis=2, keepdims=True)
    d = 1.0 - start
    new_peak = 1.0 - d * d / (peak + d - start)
    g = 1.0 - 1.0 / (desaturation * (peak - new_peak) + 1.0)
    compressed = c * (new_peak / np.where(peak > 0.0, peak, 1.0)) * (1.0 - g) + new_peak * g
    return np.where(peak < start, c, compressed)


def _cas(x, *, sharpness: float = 0.0):
    """AMD FidelityFX CAS (contrast-adaptive sharpening) at ``sharpness`` 0, its default, on each channel: the cross's
    and the 3 x 3's minima and maxima added, the amplitude ``sqrt(clip(min(mn, 2 - mx) / mx, 0, 1))``, the weight
    ``amp * -1 / lerp(8, 5, sharpness)``, the pixel ``(w (b + d + f + h) + e) / (1 + 4 w)`` (the edges replicated, as a
    clamped texture), negatives clipped to 0 (no final saturate: run on the HDR render)."""
    c = np.asarray(x, np.float64)
    h, w = c.shape[:2]
    p = np.pad(c, ((1, 1), (1, 1), (0, 0)), mode="edge")

    def at(dy, dx):
        return p[1 + dy:1 + dy + h, 1 + dx:1 + dx + w]

    cross = [at(-1, 0), at(0, -1), c, at(0, 1), at(1, 0)]
    diag = [at(-1, -1), at(-1, 1), at(1, -1), at(1, 1)]
    mn = np.minimum.reduce(cross) + np.minimum.reduce(cross + diag)
    mx = np.maximum.reduce(cross) + np.maximum.reduce(cross + diag)
    amp = np.sqrt(np.clip(np.minimum(mn, 2.0 - mx) / np.where(mx > 0.0, mx, 1.0), 0.0, 1.0))
    wt = amp * (-1.0 / (8.0 + (5.0 - 8.0) * sharpness))
    out = (wt * (cross[0] + cross[1] + cross[3] + cross[4]) + c) / (1.0 + 4.0 * wt)
    return np.maximum(out, 0.0)


#: The grading LUT's entries a side.
_LUT = 16


def _lut_half_texel(x, *, n: int = _LUT):
    """An identity colour-grading LUT of ``n`` entries a side (trilinear), sampled at the linear colour as its
    texture coordinate, without the half-texel scale and offset ``v (n - 1) / n + 0.5 / n``: each channel ``(n v - 0.5)
    / (n - 1)``, the coordinate and the result clamped to [0, 1] (a texture's clamp, an RGBA8 target)."""
    v = np.clip(np.asarray(x, np.float64), 0.0, 1.0)
    return np.clip((n * v - 0.5) / (n - 1), 0.0, 1.0)


#: A physical camera's settings at Filament's defaults: aperture f/16, shutter 1/125 s, ISO 100 (sunny 16).
_APERTURE, _SHUTTER, _ISO = 16.0, 1.0 / 125.0, 100.0


def _ev100(aperture: float = _APERTURE, shutter: float = _SHUTTER, iso: float = _ISO) -> float:
    return math.log2(aperture * aperture / shutter * 100.0 / iso)


def _physical_exposure(x):
    """The render times a physical camera's exposure ``1 / (1.2 * 2^EV100)`` (Filament's and Frostbite's formula) at
    f/16, 1/125 s and ISO 100: EV100 14.97, 2.6e-5."""
    return np.asarray(x, np.float64) / (1.2 * 2.0 ** _ev100())


# --------------------------------------------------------------------------
# Writers (the render in, the file a program writes)
# --------------------------------------------------------------------------

#: RGBM's range (the largest value it stores).
_RGBM_RANGE = 6.0


def _rgbm(image: np.ndarray, *, scale: float = _RGBM_RANGE) -> np.ndarray:
    """(H, W, 4) 8-bit RGBM of the linear render: ``rgb / range``, M its largest channel (at least 1e-6, clipped to 1)
    rounded up to a code, ``rgb / (range M)`` and M rounded to 8-bit codes."""
    a = np.maximum(np.nan_to_num(np.asarray(image, np.float64)), 0.0) / scale
    m = np.clip(np.maximum(a.max(axis=2, keepdims=True), 1e-6), 0.0, 1.0)
    m = np.ceil(m * 255.0) / 255.0
    rgbm = np.concatenate([a / m, m], axis=2)
    return np.floor(np.clip(rgbm, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def _write_png_rgbm(image: np.ndarray, folder: Path) -> Path:
    from PIL import Image

    path = folder / "render.png"
    Image.fromarray(_rgbm(image), "RGBA").save(path, format="PNG")
    return path


def _stride_width(codes: np.ndarray) -> np.ndarray:
    """(H, W, 3) codes as ``stbi_write_png(name, W, H, 3, data, W)`` reads them: the stride in bytes W for 3 W, row r
    the 3 W bytes from byte r W of the buffer."""
    h, w = codes.shape[:2]
    flat = np.ascontiguousarray(codes).reshape(-1)
    return np.stack([flat[r * w:r * w + 3 * w] for r in range(h)]).reshape(h, w, 3)


def _write_png_stride_width(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_stride_width(blind._srgb8(image)), folder)


#: Linear sRGB (D65) to ACEScg (AP1 primaries, D60 white, Bradford-adapted).
_SRGB_TO_ACESCG = np.array([[0.6130974, 0.3395231, 0.0473795], [0.0701937, 0.9163539, 0.0134524],
                            [0.0206156, 0.1095698, 0.8698147]])


def _to_acescg(x):
    """The linear render converted to ACEScg (an engine's ACES working space) for the EXR: greys kept, colours
    desaturated once read as sRGB."""
    return np.asarray(x, np.float64) @ _SRGB_TO_ACESCG.T


def _high_halves(image: np.ndarray) -> np.ndarray:
    """The float32 values' upper 16 bits (``bits >> 16``: bfloat16's truncation) as half-float bit patterns."""
    bits = np.ascontiguousarray(np.asarray(image, np.float32)).view(np.uint32)
    return (bits >> 16).astype(np.uint16).view(np.float16)


def _write_exr_high_halves(image: np.ndarray, folder: Path) -> Path:
    """An EXR of HALF channels holding each float's upper 16 bits (a float-to-half conversion by a shift)."""
    path = folder / "render.exr"
    halves = _high_halves(np.maximum(np.nan_to_num(np.asarray(image, np.float64)), 0.0))
    fresh._exr_file(path, {c: np.ascontiguousarray(halves[..., i]) for i, c in enumerate("RGB")})
    return path


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _byte_over_256(albedo) -> tuple[float, ...]:
    """An albedo stored as bytes, ``uint8_t(a * 255.0f)`` (truncated, in float), read back as ``c / 256.0f``."""
    codes = np.floor(np.asarray(albedo, np.float32) * np.float32(255.0))
    return tuple(float(c) / 256.0 for c in codes)


def _albedos_bytes(s):
    """Every Lambertian albedo through :func:`_byte_over_256`: 0.6 0.5977, 0.75 0.7461, 0.15 0.1484, 0.1 0.0977."""
    return unbidden._albedos_mapped(s, _byte_over_256)


def _times_pi_over_3(albedo) -> tuple[float, ...]:
    return tuple(float(a) * math.pi / 3.0 for a in albedo)


def _albedos_pi_int(s):
    """Every Lambertian's BRDF albedo / 3 (``const int PI = 3.14159;``), in the light sample and the bounce alike:
    the scene with every albedo times pi / 3."""
    return unbidden._albedos_mapped(s, _times_pi_over_3)


#: The meshes whose per-triangle boxes are flat (an axis-aligned face: zero extent along one axis).
_FLAT = ("floor", "ceiling", "wall_BC", "wall_EF")


def _flat_boxed(tris: np.ndarray) -> np.ndarray:
    """Whether each triangle's axis-aligned box has no thickness along some axis."""
    return np.any(np.ptp(tris, axis=1) <= 1e-9, axis=1)


def _flat_boxes_missed(d: dict) -> dict:
    """The scene as a BVH whose slab test wants ``tmax > tmin`` finds it: the flat-boxed triangles (the floor, the
    ceiling, walls BC and EF, the tetrahedron's base) gone. (The light, flat too, is removed from what the camera sees
    by :func:`_flat_boxes_render`; its samples still light the room.)"""
    from mcrt.mitsuba_scene import _bsdf_dict

    d = {k: v for k, v in d.items() if k not in _FLAT}
    tetra = next(sf for sf in _scene().surfaces() if sf.name == "tetrahedron")
    tris = np.asarray(tetra.triangles, np.float64)
    return fresh._rebuilt(d, "tetrahedron", tris[~_flat_boxed(tris)], _bsdf_dict(tetra.material))


def _flat_boxes_render(x, *, spp: int, seed: int):
    """:func:`_flat_boxes_missed`'s scene less the light seen, directly and in the mirror (same-seed renders: the light
    sampled, never met)."""
    h, w = x.shape[:2]
    return (_render(w, h, spp, seed, dict_edit=_flat_boxes_missed)
            - unsaid._seen(w, h, spp, seed, dict_edit=_flat_boxes_missed))


def _icosahedron(center, radius: float) -> np.ndarray:
    """(20, 3, 3): the icosahedron inscribed in the sphere (its 12 vertices on it), each face wound outwards."""
    g = (1.0 + math.sqrt(5.0)) / 2.0
    v = np.array([[-1, g, 0], [1, g, 0], [-1, -g, 0], [1, -g, 0], [0, -1, g], [0, 1, g], [0, -1, -g], [0, 1, -g],
                  [g, 0, -1], [g, 0, 1], [-g, 0, -1], [-g, 0, 1]], np.float64)
    v = v / np.linalg.norm(v, axis=1, keepdims=True) * radius + np.asarray(center, np.float64)
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
             (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
             (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    tris = v[np.array(faces)]
    out = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    inward = np.einsum("ij,ij->i", out, tris.mean(axis=1) - np.asarray(center, np.float64)) < 0.0
    return np.where(inward[:, None, None], tris[:, [0, 2, 1]], tris)


def _flat_subdivided(tris: np.ndarray, levels: int = 2) -> np.ndarray:
    """Each triangle split in four ``levels`` times at its edges' midpoints, the midpoints left where they are (never
    normalised onto the sphere)."""
    for _ in range(levels):
        a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
        ab, bc, ca = (a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0
        tris = np.concatenate([np.stack(t, axis=1) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])
    return tris


def _sphere_icosahedron(d: dict) -> dict:
    """The mirror sphere as an icosphere subdivided twice with its midpoints never pushed onto the sphere: the
    icosahedron's 20 flat faces (320 coplanar triangles), its vertices on the sphere."""
    from mcrt.mitsuba_scene import _bsdf_dict

    sph = _scene().spheres()[0]
    return fresh._rebuilt(d, "sphere", _flat_subdivided(_icosahedron(sph.center, sph.radius)), _bsdf_dict(sph.material))


#: glm::lookAt's translation column, (-s . eye, -u . eye, f . eye), for the near camera: read as the eye.
_VIEW_TRANSLATION = (0.0, 0.0, -1.0)


def _eye_from_view(s):
    return cases._camera(s, eye=_VIEW_TRANSLATION)


def _view_translation(eye, forward, up) -> tuple[float, float, float]:
    """glm::lookAt(eye, eye + forward, up)'s last column: (-dot(s, eye), -dot(u, eye), dot(f, eye))."""
    f = np.asarray(forward, np.float64) / np.linalg.norm(forward)
    s = np.cross(f, up)
    s = s / np.linalg.norm(s)
    u = np.cross(s, f)
    e = np.asarray(eye, np.float64)
    return float(-s @ e), float(-u @ e), float(f @ e)


#: The gamma a colour class decodes every colour with, the light's radiance included.
_GAMMA = 2.2


def _light_gamma_decoded(s):
    """The light's radiance through ``pow(c, 2.2)``: 728 for 20."""
    return cases._light(s, radiance=tuple(float(r) ** _GAMMA for r in s.light.radiance))


#: The camera's up as a pitched body's, (0.6, 0, 0.8): not perpendicular to the view (1, 0, 0).
_PITCHED_UP = (0.6, 0.0, 0.8)


def _up_not_orthogonal(d: dict) -> dict:
    """The sensor's look-at given the up (0.6, 0, 0.8), which Mitsuba's look_at makes perpendicular to the view (as
    GLM's lookAt does): the same camera."""
    import mitsuba as mi

    cam = _scene().cameras["near"]
    eye = np.asarray(cam.eye, np.float64)
    to_world = mi.ScalarTransform4f().look_at(origin=eye.tolist(), target=(eye + cam.forward).tolist(),
                                              up=list(_PITCHED_UP))
    return dict(d, sensor=dict(d["sensor"], to_world=to_world))


def _sensor_y_flipped(d: dict) -> dict:
    """The sensor's y axis flipped (``to_world @ scale(1, -1, 1)``): the image rendered bottom row first, as an
    OpenGL framebuffer holds it."""
    import mitsuba as mi

    flipped = d["sensor"]["to_world"] @ mi.ScalarTransform4f().scale([1, -1, 1])
    return dict(d, sensor=dict(d["sensor"], to_world=flipped))


def _rows_flipped_back(x, *, spp: int, seed: int):
    """Mitsuba's render with :func:`_sensor_y_flipped`, its rows flipped back with ``np.flipud``."""
    h, w = x.shape[:2]
    return np.flipud(_render(w, h, spp, seed, dict_edit=_sensor_y_flipped))


# --------------------------------------------------------------------------
# Cameras (fx, fy) -> (origins, directions), and sub-pixel offsets (rng, n) -> (u, v), each (pixels, n)
# --------------------------------------------------------------------------

#: A Panini projection's distance (1: the stereographic cylinder).
_PANINI = 1.0


def _panini(fx, fy, *, dist: float = _PANINI):
    """Rays of a Panini projection of distance ``dist`` spanning the camera's horizontal field of view: the image
    point (x, y) (``x = S sin phi``, ``y = S h``, ``S = (d + 1) / (d + cos phi)``) taken back to the azimuth phi and the
    height h on the unit cylinder, the ray along (sin phi, h, cos phi) in the camera's frame."""
    eye, r, u, f, k = unsaid._frame()
    half = math.atan(k)
    xm = (dist + 1.0) * math.sin(half) / (dist + math.cos(half))
    x, y = xm * (2.0 * np.asarray(fx) - 1.0), xm * (1.0 - 2.0 * np.asarray(fy))
    # x (d + cos phi) = (d + 1) sin phi, solved for phi.
    a, b = dist + 1.0, x
    phi = np.arcsin(np.clip(b * dist / np.sqrt(a * a + b * b), -1.0, 1.0)) + np.arctan2(b, a)
    hgt = y * (dist + np.cos(phi)) / (dist + 1.0)
    d = np.sin(phi)[:, None] * r + hgt[:, None] * u + np.cos(phi)[:, None] * f
    return np.broadcast_to(eye, (len(x), 3)), unsaid._unit(d)


def _radical_inverse(i: np.ndarray, base: int) -> np.ndarray:
    out, f = np.zeros(len(i)), 1.0 / base
    i = np.asarray(i, np.int64).copy()
    while np.any(i > 0):
        out += f * (i % base)
        i //= base
        f /= base
    return out


#: The TAA's jitter table: Halton (2, 3) points 1 to 8 (Unreal's default of 8 samples).
_HALTON8 = np.stack([_radical_inverse(np.arange(1, 9), 2), _radical_inverse(np.arange(1, 9), 3)], axis=1)


def _taa_halton(rng, n: int, *, w: int, pixels: int):
    """Every sample's offset the TAA's Halton table's entry ``s % 8``, s its index (each chunk of samples starts at a
    multiple of 8): 8 points in every pixel."""
    k = np.arange(n) % len(_HALTON8)
    return np.broadcast_to(_HALTON8[k, 0], (pixels, n)), np.broadcast_to(_HALTON8[k, 1], (pixels, n))


def _pcg(v: np.ndarray) -> np.ndarray:
    """The PCG hash (Jarzynski and Olano 2020's ``pcg``) of uint32 values."""
    with np.errstate(over="ignore"):
        state = v.astype(np.uint32) * np.uint32(747796405) + np.uint32(2891336453)
        word = ((state >> ((state >> np.uint32(28)) + np.uint32(4))) ^ state) * np.uint32(277803737)
        return (word >> np.uint32(22)) ^ word


def _pcg_offsets(rng, n: int, *, w: int, pixels: int):
    """Offsets of a PCG hash of the pixel, the sample index and a frame seed a chunk (``u = pcg(pcg(pixel) + s +
    frame) / 2^32``, v the hash of that): a shader's stateless random numbers."""
    frame = np.uint32(rng.integers(0, 2 ** 32, dtype=np.uint64))
    with np.errstate(over="ignore"):
        key = _pcg(np.arange(pixels, dtype=np.uint32))[:, None] + np.arange(n, dtype=np.uint32)[None, :] + frame
    hu = _pcg(key)
    hv = _pcg(hu)
    return hu / 2.0 ** 32, hv / 2.0 ** 32


# --------------------------------------------------------------------------
# Light samples at the first vertex (unheralded._first_vertex's ``direct``)
# --------------------------------------------------------------------------


def _half_vector(p, n, q) -> np.ndarray:
    """The geometry term with Lambert's cosine taken with the half vector, ``max(0, n . normalize(wi + wo))``, wo the
    way back to the eye (a first vertex is a camera ray's hit)."""
    wi = unsaid._unit(q - p)
    wo = unsaid._unit(unsaid._frame()[0] - p)
    cos = np.maximum(np.einsum("ij,ij->i", n, unsaid._unit(wi + wo)), 0.0)
    return cos * np.maximum(wi[:, 2], 0.0) / np.sum((q - p) ** 2, axis=1)


#: A flat normal map's texel, (128, 128, 255) / 255, never decoded with ``* 2 - 1``.
_NORMAL_TEXEL = (128.0 / 255.0, 128.0 / 255.0, 1.0)


def _normal_mapped(n) -> np.ndarray:
    """(N, 3): the shading normal ``normalize(TBN * texel)`` of the undecoded texel, T and B the tangent frame
    (:func:`mcrt.grade.accuracy.unforeseen._frame_of`): n tilted 35.4 degrees towards t + b."""
    t, b = unforeseen._frame_of(np.asarray(n, np.float64))
    tx, ty, tz = _NORMAL_TEXEL
    return unsaid._unit(tx * t + ty * b + tz * np.asarray(n, np.float64))


def _normal_map_geometry(p, n, q) -> np.ndarray:
    return unbeknown._geometry(p, _normal_mapped(n), q)


def _light_normal_as_point() -> np.ndarray:
    """The light's normal (0, 0, -1) transformed by its model matrix (the translation to its centre) as
    ``vec4(n, 1.0)``, a point: ``normalize(n + centre)`` = (0.78, 0, 0.62)."""
    lt = _scene().light
    return unsaid._unit(np.asarray(lt.normal, np.float64) + np.asarray(lt.center, np.float64))


def _normal_as_point_geometry(p, n, q) -> np.ndarray:
    """The geometry term with the cosine at the light ``max(0, n_l . -wi)`` of :func:`_light_normal_as_point`."""
    wi = unsaid._unit(q - p)
    cos_l = np.maximum(-(wi @ _light_normal_as_point()), 0.0)
    return np.maximum(np.einsum("ij,ij->i", n, wi), 0.0) * cos_l / np.sum((q - p) ** 2, axis=1)


def _light_sample_at_centre(mscene, rng, p, n, rho, mitsuba):
    """The first vertex's light sample from the light's centre (its corners all there: a quad of no area) with the
    pdf of its 4 square units: rho Le G A / pi, G to the centre."""
    lt = _scene().light
    q = np.broadcast_to(np.asarray(lt.center, np.float64), p.shape)
    g = np.where(unbeknown._unblocked(mscene, p, q), unbeknown._geometry(p, n, q), 0.0)
    return rho * (g * lt.area / math.pi)[:, None] * np.asarray(lt.radiance, np.float64)


def _light_sample(name: str, direct) -> dict:
    """A spec's post-process: Mitsuba's path with its first vertex's light sample made by ``direct``."""
    return _posted(name, partial(unheralded._first_vertex, spp=_S, seed=_crc(name), direct=direct))


def _geometry_sample(name: str, geometry) -> dict:
    """:func:`_light_sample` by :func:`mcrt.grade.accuracy.unbeknown._light_sampled` with ``geometry``."""
    return _light_sample(name, partial(unbeknown._light_sampled, geometry=geometry))


def _light_as_ceiling(d: dict) -> dict:
    """The light's rectangle given the ceiling's diffuse material (it emits as before): where a ray meets it, what the
    whole ceiling 0.01 above it reflects."""
    from mcrt.mitsuba_scene import _bsdf_dict, _light_surface, _mesh

    light, ceiling = (next(sf for sf in _scene().surfaces() if sf.name == k) for k in ("light", "ceiling"))
    lt = _scene().light
    emitter = {"type": "area", "radiance": {"type": "rgb", "value": [float(v) for v in lt.radiance]}}
    return dict(d, light=_mesh(_light_surface(light, lt.normal), _bsdf_dict(ceiling.material), emitter))


def _black_light_as_ceiling(d: dict) -> dict:
    return untold._black_diffuse(_light_as_ceiling(d))


def _half_size_zero_sample(o, d, seed, *, full, two, one, black2, black1, rng):
    """A sample of the student's tracer whose light has half-size 0: the light never met (its emission seen directly
    and in the mirror taken off; the ceiling, which is whole above it, stands in where it was), the first vertex's
    light sample from the light's centre (:func:`_light_sample_at_centre`), Mitsuba's path after it."""
    L = (unsaid._sampled(full, o, d, seed) - unsaid._sampled(one, o, d, seed)
         - (unsaid._sampled(black2, o, d, seed) - unsaid._sampled(black1, o, d, seed)))
    rho = unsaid._first_albedo(full, o, d)
    t, valid = unguessed._first_hit(full, o, d)
    sel = valid & (rho.max(axis=1) > 0.0)
    if sel.any():
        od, dd = o[sel], d[sel]
        theirs = unsaid._sampled(two, od, dd, seed) - unsaid._sampled(one, od, dd, seed)
        nrm = unforeseen._first_normal(full, od, dd)
        p = od + t[sel, None] * dd + 1e-4 * nrm
        L[sel] += _light_sample_at_centre(full, rng, p, nrm, rho[sel], theirs) - theirs
    return L


def _half_size_zero(x, *, spp: int, seed: int):
    loaded = {k: unsaid._loaded(m, _light_as_ceiling) for k, m in (("full", _DEPTH), ("two", 2), ("one", 1))}
    black = {k: unsaid._loaded(m, _black_light_as_ceiling) for k, m in (("black2", 2), ("black1", 1))}
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(
        _half_size_zero_sample, rng=np.random.default_rng(seed + 17), **loaded, **black))


# --------------------------------------------------------------------------
# Bounces at the first vertex (unprompted._first_bounce's ``draw``)
# --------------------------------------------------------------------------


def _one_octant_plus_normal(rng, n):
    """Ray Tracing in One Weekend's ``normal + random_unit_vector()`` in a shader whose random vector is
    ``normalize(vec3(rand(), rand(), rand()))``, rand() in [0, 1), the ``* 2 - 1`` (and the book's rejection loop)
    left out: every unit vector in the positive octant, the bounce leaning towards +x, +y and +z, weighted by the
    albedo (the book's attenuation)."""
    v = unsaid._unit(rng.random((len(n), 3)))
    return unsaid._unit(n + v), np.ones(len(n))


def _height_pow_half(rng, n):
    """A cosine-weighted bounce (Malley's disk of radius sqrt(u1)) whose height is ``pow(1 - u1, 1 / 2)``, C's
    integer 1 / 2 an exponent of 0: the height 1, the direction ``normalize(r cos phi t + r sin phi b + n)`` within 45
    degrees of the normal, weighted by the albedo as a cosine sample."""
    u1, u2 = rng.random((2, len(n)))
    r, phi = np.sqrt(u1), 2.0 * math.pi * u2
    t, b = unforeseen._frame_of(n)
    d = (r * np.cos(phi))[:, None] * t + (r * np.sin(phi))[:, None] * b + (1.0 - u1)[:, None] ** (1 // 2) * n
    return unsaid._unit(d), np.ones(len(n))


def _frame_transposed(rng, n):
    """A cosine-weighted local direction l taken to the world by the tangent frame's transpose, (t . l, b . l, n . l)
    (HLSL's ``mul(l, float3x3(T, B, N))``, rows, ported as GLSL's ``l * mat3(T, B, N)``, columns), weighted by the
    albedo; a direction under the surface leaves the room through it (weight 0)."""
    u1, u2 = rng.random((2, len(n)))
    r, phi = np.sqrt(u1), 2.0 * math.pi * u2
    local = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(1.0 - u1, 0.0))], axis=1)
    t, b = unforeseen._frame_of(n)
    d = np.stack([np.einsum("ij,ij->i", t, local), np.einsum("ij,ij->i", b, local),
                  np.einsum("ij,ij->i", n, local)], axis=1)
    return d, (np.einsum("ij,ij->i", d, n) > 0.0).astype(np.float64)


# --------------------------------------------------------------------------
# Paths, samples and frames combined as a student's loop combines them
# --------------------------------------------------------------------------


def _radiance_divided_weights(survival: float, first: int, depth: int = _DEPTH) -> np.ndarray:
    """(depth,): the expected weight of the light of paths of k = 1 .. depth segments when Russian roulette runs after
    the light sample of vertices ``first`` to depth - 1 (vertex v's light sample makes the paths of v + 1 segments) and
    a survivor's radiance so far, not its throughput, is divided by ``survival``. Backwards from the last test: the
    expected result of a test at vertex v given the radiance X so far is ``a_v X + sum_k c_v[k] S_k``, a_v = a_{v+1} +
    1 - p and c_v = p (a_{v+1} e_{v+2} + c_{v+1}) (the next vertex adding S_{v+2}), a = 1 and c = 0 after the last."""
    a, c = 1.0, np.zeros(depth)
    for v in range(depth - 1, first - 1, -1):
        nxt = np.zeros(depth)
        if v + 2 <= depth:
            nxt[v + 1] = 1.0
        a, c = a + 1.0 - survival, survival * (a * nxt + c)
    w = c.copy()
    w[:first + 1] += a
    return w


def _roulette_divides_radiance(x, *, spp: int, seed: int, survival: float = 0.5, first: int = 3):
    """Russian roulette from vertex ``first`` with survival ``survival`` whose survivors' radiance so far is divided
    by it (``L /= p`` for ``beta /= p``): the expected image, each length's light (same-seed renders of max depth 1 to
    8, Mitsuba's roulette off) times :func:`_radiance_divided_weights`."""
    w = _radiance_divided_weights(survival, first)
    renders = [np.zeros(x.shape[:2] + (3,))] + [fresh._mitsuba(x.shape, spp, seed, max_depth=k, rr_depth=100)
                                                 for k in range(1, _DEPTH + 1)]
    return sum(w[k - 1] * (renders[k] - renders[k - 1]) for k in range(1, _DEPTH + 1))


def _code(v: np.ndarray) -> np.ndarray:
    """A UNORM8 target's stored value: clamped to [0, 1], rounded to a code."""
    return np.floor(np.clip(v, 0.0, 1.0) * 255.0 + 0.5) / 255.0


def _rgba8_blended(samples: np.ndarray) -> np.ndarray:
    """(pixels, 3): 1-spp frames (``samples`` (pixels, n, 3) in order) blended into an RGBA8 target with alpha 1 / k
    for frame k, ``dst = src / k + dst (1 - 1 / k)``, the fragment's output and each result stored as 8-bit codes."""
    acc = np.zeros((samples.shape[0], 3))
    for k in range(samples.shape[1]):
        acc = _code(np.clip(samples[:, k], 0.0, 1.0) / (k + 1) + acc * (1.0 - 1.0 / (k + 1)))
    return acc


def _rgba8_accumulated(x, *, spp: int, seed: int):
    h, w = x.shape[:2]
    return _rgba8_blended(unbidden._all_samples(w, h, spp, seed)).reshape(h, w, 3)


def _tonemapped_resolve(samples: np.ndarray) -> np.ndarray:
    """(pixels, 3): each sample mapped by ``c / (1 + luma(c))`` (Rec. 709 luma), averaged, and the mean mapped back by
    ``t / (1 - luma(t))`` (a TAA resolve's trick against fireflies)."""
    t = samples / (1.0 + samples @ programs._LUMA)[..., None]
    m = t.mean(axis=1)
    return m / (1.0 - m @ programs._LUMA)[:, None]


def _resolved_tonemapped(x, *, spp: int, seed: int):
    h, w = x.shape[:2]
    return _tonemapped_resolve(unbidden._all_samples(w, h, spp, seed)).reshape(h, w, 3)


#: The fixed-point film's fractional bits (32-bit unsigned atomics).
_FRACTION = 20


def _fixed_point_sum(samples: np.ndarray, *, bits: int = _FRACTION) -> np.ndarray:
    """(pixels, 3): the samples' sum in 32-bit unsigned fixed point of ``bits`` fractional bits (each sample
    ``uint(L * 2^bits)``, ``atomicAdd``, wrapping at 2^32), divided back by 2^bits."""
    q = np.floor(np.maximum(samples, 0.0) * 2.0 ** bits).astype(np.uint64)
    return (q.sum(axis=1) % (1 << 32)).astype(np.float64) / 2.0 ** bits


def _fixed_point_film(x, *, spp: int, seed: int):
    h, w = x.shape[:2]
    return (_fixed_point_sum(unbidden._all_samples(w, h, spp, seed)) / spp).reshape(h, w, 3)


def _checkerboard(x):
    """Checkerboard rendering without its other frame: the pixels with i + j even kept, each other one the mean of
    its rendered 4-neighbours (those inside the image)."""
    x = np.asarray(x, np.float64)
    h, w = x.shape[:2]
    jj, ii = np.indices((h, w))
    kept = (ii + jj) % 2 == 0
    p = np.pad(x, ((1, 1), (1, 1), (0, 0)))
    inside = np.pad(np.ones((h, w)), 1)
    total = sum(p[1 + dy:1 + dy + h, 1 + dx:1 + dx + w] for dy, dx in ((-1, 0), (1, 0), (0, -1), (0, 1)))
    count = sum(inside[1 + dy:1 + dy + h, 1 + dx:1 + dx + w] for dy, dx in ((-1, 0), (1, 0), (0, -1), (0, 1)))
    return np.where(kept[..., None], x, total / count[..., None])


# --------------------------------------------------------------------------
# Correct files made in other ways
# --------------------------------------------------------------------------


#: The viewport's origin in the engine's window, kept as the EXR's windows' origin.
_VIEWPORT_ORIGIN = (128, 64)


def _write_exr_window_origin(image: np.ndarray, folder: Path) -> Path:
    """A float EXR whose data and display windows both start at the viewport's origin (128, 64) in the engine's
    window, not at (0, 0) (the OpenEXR bindings, ZIP)."""
    import OpenEXR

    h, w = image.shape[:2]
    x0, y0 = _VIEWPORT_ORIGIN
    window = ((x0, y0), (x0 + w - 1, y0 + h - 1))
    path = folder / "render.exr"
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage, "dataWindow": window,
              "displayWindow": window}
    channels = {c: np.ascontiguousarray(image[..., i], np.float32) for i, c in enumerate("RGB")}
    OpenEXR.File(header, channels).write(str(path))
    return path


def _tga2_bgra(codes: np.ndarray) -> bytes:
    """A 32-bit TGA 2.0: uncompressed true colour, 8 attribute (alpha) bits, the bottom row first, BGRA (an opaque
    alpha), and the TGA 2.0 footer (no extension or developer area, ``TRUEVISION-XFILE.``)."""
    h, w = codes.shape[:2]
    head = struct.pack("<BBBHHBHHHHBB", 0, 0, 2, 0, 0, 0, 0, 0, w, h, 32, 8)
    bgra = np.concatenate([codes[::-1, :, ::-1], np.full((h, w, 1), 255, np.uint8)], axis=2)
    return head + np.ascontiguousarray(bgra).tobytes() + struct.pack("<II", 0, 0) + b"TRUEVISION-XFILE.\x00"


def _write_tga2(image: np.ndarray, folder: Path) -> Path:
    path = folder / "render.tga"
    path.write_bytes(_tga2_bgra(blind._srgb8(image)))
    return path


def _write_pic(image: np.ndarray, folder: Path) -> Path:
    """A Radiance picture named ``render.pic`` (rpict's extension): its header with the VIEW line of the near camera,
    the scanlines run-length encoded new-style (mcrt's RGBE encoding and encoder), top row first."""
    from mcrt.image_files import _rgbe_encode, _rle_channel

    h, w = image.shape[:2]
    path = folder / "render.pic"
    rgbe = _rgbe_encode(path, np.nan_to_num(np.asarray(image, np.float64)))
    marker = bytes((2, 2, w >> 8, w & 255))
    body = b"".join(marker + b"".join(_rle_channel(rgbe[y, :, c]) for c in range(4)) for y in range(h))
    head = (b"#?RADIANCE\nrpict -vtv -vp -1 0 0 -vd 1 0 0 -vu 0 0 1 -vh 90 -vv 90\n"
            b"VIEW= -vtv -vp -1 0 0 -vd 1 0 0 -vu 0 0 1 -vh 90 -vv 90\nFORMAT=32-bit_rle_rgbe\n\n")
    path.write_bytes(head + f"-Y {h} +X {w}\n".encode() + body)
    return path


def _exr_attribute(name: str, kind: str, value: bytes) -> bytes:
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value


def _exr_by_hand(image: np.ndarray) -> bytes:
    """A scanline OpenEXR written byte by byte as miniexr does: magic and version 2, the required header attributes
    (channels B, G, R half, no compression, the windows, line order, aspect, screen window), the offset table, then
    each line (its y, its size, the channels' halves in the channel list's order)."""
    h, w = image.shape[:2]
    channels = b"".join(c.encode() + b"\0" + struct.pack("<iB3xii", 1, 0, 1, 1) for c in "BGR") + b"\0"
    box = struct.pack("<iiii", 0, 0, w - 1, h - 1)
    head = (b"\x76\x2f\x31\x01" + struct.pack("<I", 2) + _exr_attribute("channels", "chlist", channels)
            + _exr_attribute("compression", "compression", b"\0") + _exr_attribute("dataWindow", "box2i", box)
            + _exr_attribute("displayWindow", "box2i", box) + _exr_attribute("lineOrder", "lineOrder", b"\0")
            + _exr_attribute("pixelAspectRatio", "float", struct.pack("<f", 1.0))
            + _exr_attribute("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0))
            + _exr_attribute("screenWindowWidth", "float", struct.pack("<f", 1.0)) + b"\0")
    half = np.asarray(image, np.float64).astype("<f2")
    lines = [struct.pack("<ii", y, 3 * 2 * w) + b"".join(half[y, :, c].tobytes() for c in (2, 1, 0)) for y in range(h)]
    offsets = len(head) + 8 * h + np.concatenate([[0], np.cumsum([len(b) for b in lines])[:-1]])
    return head + struct.pack(f"<{h}Q", *(int(o) for o in offsets)) + b"".join(lines)


def _write_exr_by_hand(image: np.ndarray, folder: Path) -> Path:
    path = folder / "render.exr"
    path.write_bytes(_exr_by_hand(np.maximum(np.nan_to_num(np.asarray(image, np.float64)), 0.0)))
    return path


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_pbr_neutral_tone_map", "pp_cas_sharpening", "pp_grading_lut_half_texel",
                        "pp_physical_camera_sunny_16"),
    "file": ("file_png_rgbm", "file_png_stb_stride_width", "file_exr_acescg", "file_exr_float_high_halves"),
    "materials": ("albedos_bytes_over_256", "lambert_cosine_half_vector", "lambert_pi_declared_int"),
    "geometry": ("bvh_flat_boxes_missed", "normal_map_texel_undecoded", "sphere_icosphere_unprojected"),
    "camera": ("panini_projection", "eye_from_view_matrix", "jitter_taa_halton_8"),
    "light": ("light_half_size_integer_division", "light_normal_as_point", "light_radiance_gamma_decoded"),
    "integrator": ("bounce_unit_vector_one_octant", "bounce_frame_transposed", "bounce_height_pow_half",
                   "roulette_divides_radiance"),
    "samples": ("frames_rgba8_blended", "frames_resolved_tonemapped", "film_fixed_point_atomics",
                "checkerboard_half_filled"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_pbr_neutral_tone_map", "tone_map", **_posted("pbr_neutral", _pbr_neutral),
             truth="Khronos' PBR Neutral tone map (a glTF viewer's shader) run on the render before the EXR: the "
             "smallest channel's offset taken off every pixel (x - 6.25 x^2 under 0.08, 0.04 above: 0.02 to 0.0025, "
             "0.1 to 0.06), peaks over 0.76 compressed towards 1 and desaturated, the light 1"),
        Spec("pp_cas_sharpening", "sharpen", held_out=True, **_posted("cas", _cas),
             truth="AMD's contrast-adaptive sharpening (FidelityFX CAS, sharpness 0, from a game's post chain) run on "
             "the HDR render before the EXR, negatives clipped to 0: each pixel pushed from its 4 neighbours by a "
             "weight that falls where the 3 x 3 range is large (none near the light, whose values exceed 1), the "
             "noise and the dim surfaces' edges sharpened"),
        Spec("pp_grading_lut_half_texel", "colour_grade", **_posted("lut_half_texel", _lut_half_texel),
             truth="an identity colour-grading LUT of 16 entries a side, trilinear, sampled at the linear colour "
             "without the half-texel scale and offset (uv = v for v 15 / 16 + 1 / 32), before the EXR: each channel "
             "(16 v - 0.5) / 15, clamped to [0, 1]: values under 1/32 black, 0.1 to 0.073, 0.5 kept, the light 1"),
        Spec("pp_physical_camera_sunny_16", "light_radiance", True, held_out=True,
             **_posted("physical_exposure", _physical_exposure),
             truth="a physical camera's exposure 1 / (1.2 x 2^EV100) (Filament's formula) at its defaults, f/16, "
             "1/125 s, ISO 100 (sunny 16: EV100 14.97), applied to the indoor render before the EXR: every value "
             "times 2.6e-5, the light 0.0005"),
        # Writing the file
        Spec("file_png_rgbm", "encoding", True, writer=_write_png_rgbm, file="png-rgbm",
             truth="an RGBA PNG of the render in RGBM (range 6), as an engine stores HDR colours in 8 bits: rgb / 6 "
             "divided by M, its largest channel rounded up to a code, M in the alpha: read as sRGB colours (alpha "
             "dropped) every pixel near its own largest channel's full scale, a dark wall of 0.1 read as 0.69, the "
             "image flat and bright"),
        Spec("file_png_stb_stride_width", "row_stride", True, held_out=True, writer=_write_png_stride_width,
             file="png-stride-width",
             truth="an 8-bit sRGB PNG saved with stbi_write_png(name, W, H, 3, data, W): the stride in bytes given "
             "the width, W for 3 W: row r the 3 W bytes from byte r W, the top third of the image stretched down the "
             "whole height, each row shifted by a third of the width and its channels rotated two rows in three"),
        Spec("file_exr_acescg", "colour_space", **_posted("acescg", _to_acescg),
             truth="the EXR written in ACEScg (AP1 primaries, D60), a game engine's ACES working space: the linear "
             "sRGB values through the sRGB-to-ACEScg matrix, read as sRGB: the greys kept, the colours desaturated "
             "(a red wall (0.75, 0.15, 0.15) as (0.52, 0.19, 0.16))"),
        Spec("file_exr_float_high_halves", "file_format", True, held_out=True, writer=_write_exr_high_halves,
             file="exr-high-halves",
             truth="an EXR of half-float channels filled by a float-to-half conversion by a shift, each float's "
             "upper 16 bits (bits >> 16, bfloat16's truncation) taken as a half: 0.01 read as 1.03, 0.1 as 1.45, 1 "
             "as 1.875, the light as 2.81: the image a flat bright grey, its values in order but 0 only where black"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    c = _crc
    return (
        # Materials
        Spec("albedos_bytes_over_256", "albedo", edit=_albedos_bytes,
             truth="the albedos kept as bytes (uint8_t(a * 255.0f), truncated) and read back over 256 (c / 256.0f, "
             "a shift's habit): 0.6 as 0.598, 0.75 as 0.746, 0.15 as 0.148, 0.1 as 0.098: every surface 0.4 to 2.3 % "
             "darker at each bounce, the room about 1 % darker"),
        Spec("lambert_cosine_half_vector", "material", held_out=True, **_geometry_sample(
            "lambert_cosine_half_vector", _half_vector),
             truth="Lambert's cosine taken with the half vector, max(0, dot(N, H)), H = normalize(L + V) (Blinn-Phong's"
             " specular line copied into the diffuse), in the light sample at the first surface a camera ray meets "
             "(Mitsuba's path after it): surfaces lit more the more they face the eye, the floor about 7 % darker in "
             "the image's lower part, the far walls about 5 % brighter, the light seen right"),
        Spec("lambert_pi_declared_int", "brdf_norm", edit=_albedos_pi_int,
             truth="the BRDF's PI declared const int PI = 3.14159; (a C narrowing to 3): every Lambertian albedo / "
             "3 for albedo / pi, in the light sample and the bounce alike: every diffuse reflection 4.7 % too "
             "bright, the room about a tenth brighter, the light seen right"),
        # Geometry
        Spec("bvh_flat_boxes_missed", "object_missing", True, **_posted("flat_boxes", partial(
            _flat_boxes_render, spp=_S, seed=c("bvh_flat_boxes_missed"))),
             truth="a BVH whose box test accepts a ray only where tmax > tmin (strictly): an axis-aligned face's box "
             "has no thickness, tmin = tmax, so the floor, the ceiling, walls BC and EF, the tetrahedron's base and "
             "the light are never met (the light still sampled): the void seen through them, black, the light "
             "black where seen and in the mirror, the other walls and the tetrahedron lit"),
        Spec("normal_map_texel_undecoded", "normals", True, held_out=True, **_geometry_sample(
            "normal_map_texel_undecoded", _normal_map_geometry),
             truth="every surface's shading normal from a flat normal map's texel (128, 128, 255) never decoded with "
             "* 2 - 1: normalize(TBN (0.5, 0.5, 1)), the normal tilted 35 degrees towards its tangent frame's t + b, "
             "in the light sample at the first surface a camera ray meets (Mitsuba's path after it): each face lit "
             "as if turned, the floor and the far walls about a tenth darker, some faces brighter, the light seen "
             "right"),
        Spec("sphere_icosphere_unprojected", "object_shape", True, mitsuba_edit=_sphere_icosahedron,
             truth="the mirror sphere built as an icosphere subdivided twice whose new midpoints were never pushed "
             "out onto the sphere (the normalize forgotten): the icosahedron's 20 flat faces, its vertices on the "
             "sphere, its faces 1.19 from the centre: the room reflected in 20 flat mirrors"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera
        Spec("panini_projection", "camera_model", True, **_posted("panini", partial(
            unsaid._traced, spp=_S, seed=c("panini_projection"), camera=_panini)),
             truth="a Panini projection (a game engine's wide-angle option, distance 1) for the pinhole's rays, its "
             "horizontal 90 degrees kept: x = 2 tan(phi / 2) across, the heights on a cylinder: the middle "
             "magnified about a fifth, the verticals straight, the horizontals bent towards the image's edges"),
        Spec("eye_from_view_matrix", "camera_eye", True, held_out=True, edit=_eye_from_view,
             truth="the eye read from the look-at view matrix's translation column (glm::lookAt's V[3], (-s . eye, "
             "-u . eye, f . eye)) for the camera's position: (0, 0, -1) for (-1, 0, 0), the view from one unit "
             "forward and one lower, its direction right: the room seen from below, the light at the image's top "
             "edge"),
        Spec("jitter_taa_halton_8", "pixel_footprint", **_posted("taa_halton", partial(
            unforeseen._mean_through, spp=_S, seed=c("jitter_taa_halton_8"), jitter=_taa_halton)),
             truth="the sub-pixel offsets from a TAA's jitter table, the Halton (2, 3) points 1 to 8 (an engine's "
             "default of 8), indexed by the sample number mod 8: every pixel's 256 samples through the same 8 "
             "points, their mean (0.445, 0.5): edges aliased and the image 1/18 pixel right"),
        # Light model
        Spec("light_half_size_integer_division", "light_size", True, **_posted("half_size_zero", partial(
            _half_size_zero, spp=_S, seed=c("light_half_size_integer_division"))),
             truth="the light's half-size written 1 / 2 * size (C's integer 1 / 2: 0): its corners all at its "
             "centre, a quad of no area no ray meets, sampled with its 4 square units' pdf: its light on surfaces "
             "from one point at its centre (hard shadows), at the first surface a camera ray meets (Mitsuba's path "
             "after it), the light itself never seen (the ceiling above it in its place, directly and in the "
             "mirror)"),
        Spec("light_normal_as_point", "light_pdf", True, held_out=True, **_geometry_sample(
            "light_normal_as_point", _normal_as_point_geometry),
             truth="the light's normal transformed by its model matrix as a point, model * vec4(n, 1.0) for vec4(n, "
             "0.0): normalize(n + centre) = (0.78, 0, 0.62), in its sample's cosine, at the first surface a camera "
             "ray meets (Mitsuba's path after it): light only where it leaves the light towards +x and well to the "
             "side, the far walls' upper parts lit (a little more than right), a bright band on the ceiling along the "
             "light's +x edge, the floor and the lower walls lit only indirectly, the light seen right"),
        Spec("light_radiance_gamma_decoded", "light_radiance", True, edit=_light_gamma_decoded,
             truth="the light's radiance decoded by a colour class that linearises every colour it is given, "
             "pow(c, 2.2): 728 for 20, the light and every surface 36 times too bright"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples, passes and film."""
    c = _crc
    return (
        # Integrator
        Spec("bounce_unit_vector_one_octant", "indirect_scale", **_posted("one_octant", partial(
            unprompted._first_bounce, spp=_S, seed=c("bounce_unit_vector_one_octant"), draw=_one_octant_plus_normal)),
             truth="Ray Tracing in One Weekend's diffuse bounce, normal + random_unit_vector(), ported to a shader "
             "whose random vector is normalize(vec3(rand(), rand(), rand())) with rand() in [0, 1), the * 2 - 1 "
             "forgotten: every unit vector in the positive octant, the bounce leaning towards +x, +y and +z, at the "
             "first surface a camera ray meets (Mitsuba's path after it): the indirect light a tenth dark, the "
             "ceiling (lit by bounces alone) a quarter, the direct right"),
        Spec("bounce_frame_transposed", "indirect_scale", True, held_out=True, **_posted("frame_transposed", partial(
            unprompted._first_bounce, spp=_S, seed=c("bounce_frame_transposed"), draw=_frame_transposed)),
             truth="the cosine-weighted bounce's local direction taken to the world by the tangent frame's "
             "transpose (HLSL's mul(l, float3x3(T, B, N)), rows, ported as GLSL's l * mat3(T, B, N), columns), "
             "at the first surface a camera ray meets (Mitsuba's path after it): right on the floor and the ceiling "
             "(their frames symmetric), on the walls and the tetrahedron a lobe about another axis, half of it "
             "through the surface and lost: their indirect light wrong, the direct right"),
        Spec("bounce_height_pow_half", "indirect_scale", **_posted("height_pow_half", partial(
            unprompted._first_bounce, spp=_S, seed=c("bounce_height_pow_half"), draw=_height_pow_half)),
             truth="the cosine-weighted bounce's height written pow(1 - u1, 1 / 2) (C's integer 1 / 2: the exponent "
             "0, the height 1), the direction normalize(r cos phi t + r sin phi b + n), r = sqrt(u1): every bounce "
             "within 45 degrees of the normal, weighted as a cosine sample, at the first surface a camera ray meets "
             "(Mitsuba's path after it): the indirect light from straight ahead overweighted, the ceiling's a tenth "
             "too bright, the direct right"),
        Spec("roulette_divides_radiance", "roulette", True, held_out=True, **_posted("divides_radiance", partial(
            _roulette_divides_radiance, spp=_S, seed=c("roulette_divides_radiance"))),
             truth="Russian roulette from the 3rd vertex with survival 0.5 whose survivors' radiance so far is "
             "divided by it (L /= p for beta /= p): the light gathered before a test weighs more, after it less: the "
             "light seen and the paths of up to 4 segments 3.5 times, of 5 to 8 segments 1.5, 0.625, 0.25 and 0.094 "
             "times: the image about 3.4 times too bright"),
        # Samples, passes and film
        Spec("frames_rgba8_blended", "quantisation", True, **_posted("rgba8_blended", partial(
            _rgba8_accumulated, spp=_S, seed=c("frames_rgba8_blended"))),
             truth="256 frames of 1 spp accumulated on the GPU by blending into an RGBA8 target with alpha 1 / k "
             "(dst = src / k + dst (1 - 1 / k)), read back as the EXR: each frame and each result clamped to [0, 1] "
             "and rounded to 1/255: the light 1, updates under half a code lost once k is large (the mean stops "
             "moving), the dark parts in steps of 0.004"),
        Spec("frames_resolved_tonemapped", "biased_estimator", held_out=True, **_posted("resolved_tonemapped", partial(
            _resolved_tonemapped, spp=_S, seed=c("frames_resolved_tonemapped"))),
             truth="the samples resolved as a TAA resolves frames against fireflies: each mapped by c / (1 + "
             "luma(c)), averaged, and the mean mapped back by t / (1 - luma(t)): the bright rare samples discounted, "
             "every pixel whose samples vary too dark: the lit surfaces about 4 % on average, more where bright paths "
             "are rare, the light's edges much more, constant pixels right"),
        Spec("film_fixed_point_atomics", "code_overflow", **_posted("fixed_point", partial(
            _fixed_point_film, spp=_S, seed=c("film_fixed_point_atomics"))),
             truth="the film a 32-bit unsigned fixed-point buffer (20 fractional bits) added to with atomicAdd, "
             "each sample uint(L * 2^20): a pixel's sum past 4096 (a mean of 16 or more) wraps round: the light's "
             "own pixels and its reflection 4 for 20, the rest right"),
        Spec("checkerboard_half_filled", "resampling", held_out=True, **_posted("checkerboard", _checkerboard),
             truth="checkerboard rendering (a console engine's) without its other frame: the pixels with i + j even "
             "rendered, each of the others the mean of its 4 rendered neighbours: half the image interpolated, "
             "edges soft and jagged"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_pcg_hash_offsets", None, **_posted("pcg_offsets", partial(
            unforeseen._mean_through, spp=_S, seed=c("ok_pcg_hash_offsets"), jitter=_pcg_offsets)),
             truth="Mitsuba path 256 spp, sub-pixel offsets from a PCG hash of the pixel, the sample index and a "
             "frame seed (a shader's stateless random numbers), EXR"),
        Spec("ok_exr_window_origin", None, held_out=True, spp=220, writer=_write_exr_window_origin,
             file="exr-window-origin",
             truth="Mitsuba path 220 spp, a float EXR whose data and display windows start at (128, 64), the "
             "viewport's origin in the engine's window, not at (0, 0)"),
        Spec("ok_up_not_orthogonal", None, spp=148, mitsuba_edit=_up_not_orthogonal,
             truth="Mitsuba path 148 spp with the camera's up given as (0.6, 0, 0.8), not perpendicular to its view "
             "(the look-at orthogonalises it, as GLM's does), EXR"),
        Spec("ok_tga2_bgra_footer", None, held_out=True, spp=140, writer=_write_tga2, file="tga2-bgra",
             truth="Mitsuba path 140 spp, a 32-bit sRGB TGA 2.0 written by hand: BGRA with an opaque alpha, the "
             "bottom row first, and the TRUEVISION-XFILE footer"),
        Spec("ok_mcrt_mis_one_light_sample", None, spp=72, renderer="mcrt", **_posted("mcrt_mis_one", partial(
            untold._mcrt, spp=72, seed=c("ok_mcrt_mis_one_light_sample"), light_samples=1, mis=True)),
             truth="mcrt 72 spp with multiple importance sampling and one light sample a vertex, EXR"),
        Spec("ok_radiance_pic", None, held_out=True, spp=184, writer=_write_pic, file="pic",
             truth="Mitsuba path 184 spp, a Radiance picture named render.pic (rpict's extension) with its command "
             "and VIEW lines, run-length encoded"),
        Spec("ok_rendered_bottom_up", None, spp=208, **_posted("bottom_up", partial(
            _rows_flipped_back, spp=208, seed=c("ok_rendered_bottom_up"))),
             truth="Mitsuba path 208 spp rendered bottom row first as an OpenGL framebuffer holds it (the sensor's y "
             "axis flipped), the rows flipped back with np.flipud, EXR"),
        Spec("ok_exr_by_hand_miniexr", None, held_out=True, spp=164, writer=_write_exr_by_hand, file="exr-by-hand",
             truth="Mitsuba path 164 spp, an EXR written byte by byte as miniexr writes one: half-float B, G, R, "
             "uncompressed scanlines, the required header attributes and the offset table"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "tone_map": "a tone map applied before saving (Khronos' PBR Neutral)",
    "sharpen": "a sharpening filter after rendering (AMD's contrast-adaptive sharpening)",
    "colour_grade": "the colours graded after rendering (a grading LUT sampled without its half-texel offset)",
    "light_radiance": "the light's radiance or a constant factor (a physical camera's exposure, the radiance "
                      "gamma-decoded)",
    "encoding": "the values' encoding (RGBM in a PNG's colours)",
    "row_stride": "pixels written at the wrong addresses (the row stride in bytes given the width)",
    "colour_space": "values in another colour space (ACEScg written as sRGB)",
    "file_format": "the file's data not what its format says (floats' upper halves written as half floats)",
    "albedo": "a surface's colour (the albedos kept as bytes and read over 256)",
    "material": "an object rendered with another material (Lambert's cosine taken with the half vector)",
    "brdf_norm": "a BRDF's normalisation (pi declared an integer: albedo / 3)",
    "object_missing": "objects missing (a BVH's box test missing every flat box)",
    "normals": "surface normals wrong (a normal map's texel never decoded)",
    "object_shape": "an object's shape (the sphere an icosahedron)",
    "camera_model": "another camera model (a Panini projection)",
    "camera_eye": "the camera's eye position (read from the view matrix's translation)",
    "pixel_footprint": "each pixel's samples not spread over its square (a TAA's 8 jitter offsets)",
    "light_size": "the light's size (its half-size 0 by integer division)",
    "light_pdf": "the light sampled wrongly (its normal transformed as a point): the light seen right, its light on "
                 "surfaces not",
    "indirect_scale": "the indirect light wrong (a bounce's unit vector in one octant, its frame transposed, its "
                      "height 1), the direct light right",
    "roulette": "Russian roulette wrong (the radiance divided, not the throughput)",
    "quantisation": "values quantised wrongly (frames blended into an 8-bit target)",
    "biased_estimator": "a biased estimate of each pixel's mean (the samples averaged tone-mapped)",
    "code_overflow": "values wrapped round (a fixed-point film's sums)",
    "resampling": "rendered at a lower resolution and enlarged (half the pixels rendered in a checkerboard, the others "
                  "interpolated)",
}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = blind.class_causes(MISTAKES, _EARLIER, NEW_CAUSES, _REWORDED)


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
