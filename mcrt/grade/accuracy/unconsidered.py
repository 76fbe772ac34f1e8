r"""A thirtieth class of hand-ins: mistakes of students' tracers, scene input and output no class tried, blind.

How it was written: from what goes wrong in students' tracers written in Rust, Go, Java, C#, Swift, Kotlin and
Haskell and in their standard libraries and popular crates and packages (Rust's ``as`` casts, which saturate from
floats and wrap between integers, ``rand``'s ``gen_range`` on an integer range, ``chunks`` for ``windows``, glam's
quaternions and ``from_rotation_arc``, nalgebra's ``Perspective3::new``; Go's integer conversions, slices that alias
their array, ``sort.Float64s``, ``map`` iteration order, a goroutine's closure over its loop variable,
``color.Color.RGBA()``'s 16-bit values; Java's signed ``byte``, ``BufferedImage`` types, ``RescaleOp``,
``ConvolveOp``'s edges, javax.vecmath's ``scaleAdd``, libGDX's mutating ``Vector3.sub``, an integer quotient cast;
C#'s ``Buffer.BlockCopy``, ``Vector3.Distance``, ``System.Random`` on .NET Framework; Swift's value types and
``stride``, ``simd_quatf(from:to:)``; Kotlin's infix functions and their precedence, an operator overloaded as the dot
product, ``IntRange.random()``, ``Math.toDegrees``; Haskell's ``until``), not from the grader. Its author read the
other classes' specs and cause words, the catalogue (:mod:`mcrt.mutants`), the scene files and design notes, mcrt's
scene, camera and image code, :data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to stay clear of their mistakes; never the
grader's rules (what decides a cause) nor its reports, and graded none of it, not one case. Each cause and ``major``
flag was set from the mistake alone; every mistake is worded by a cause the other classes already have
(:data:`NEW_CAUSES` is empty), so ``SAME_MISTAKE`` needed no new entry. The mistakes differ from those of the
twenty-eight other classes (:mod:`~mcrt.grade.accuracy.cases`, :mod:`~mcrt.grade.accuracy.outside` and the modules
of :data:`_EARLIER`, from :mod:`~mcrt.grade.accuracy.programs` to :mod:`~mcrt.grade.accuracy.unattended`) and from
the catalogue's bugs:

* **post-processing**: Java's ``new RescaleOp(1.2f, 15, null)`` on the 8-bit image (the usual brightening snippet);
  a horizontal 3-tap median in Go whose window ``row[x-1 : x+2]`` is sorted by ``sort.Float64s`` in place (the row
  itself sorted as the window slides); an ordered dither in Rust whose ``i32`` code is cast ``as u8`` (wrapping,
  where a float's ``as`` saturates); a 3 x 3 blur by Java's ``ConvolveOp`` with its default ``EDGE_ZERO_FILL`` (a
  black frame);
* **writing the file**: Java's ``BufferedImage.TYPE_BYTE_GRAY`` filled with ``setRGB`` (a linear grey); Java's
  ``setRGB`` of codes kept in a signed ``byte``, sign-extended into the channels above; Kotlin's ``r shl 16 or g shl
  8 or b`` (infix functions of one precedence, left to right: the red in the alpha byte); C#'s
  ``Buffer.BlockCopy`` given the floats' count for a count of bytes (a quarter copied);
* **materials**: the mirror's reflection with javax.vecmath's ``scaleAdd`` (this = s this + t, not this + s t);
  the albedos' names and values taken from two ranges over a Go ``map`` (two random orders); the light sample's
  ``albedo * Le`` with Kotlin's ``*`` overloaded as the dot product (a grey);
* **geometry**: the tetrahedron's edges precomputed with libGDX's ``Vector3.sub`` (which changes the vertex it is
  called on); the walls from Rust's ``corners.chunks(2)`` for ``windows(2)`` (three of six); the sphere's radius set
  in Swift's ``for var`` loop (on a copy: the default radius 1);
* **camera**: the camera's rotation as glam's ``from_rotation_x(pi / 2) * from_rotation_z(-pi / 2)`` (the order
  reversed); nalgebra's ``Perspective3::new(fovy, aspect, ...)`` for ``new(aspect, fovy, ...)``; Kotlin's
  ``tan(Math.toDegrees(fov) / 2)`` for ``toRadians``;
* **light model**: the light's point from Java's ``(double) (rng.nextInt(Integer.MAX_VALUE) / Integer.MAX_VALUE)``
  (0: its corner); C#'s ``Vector3.Distance`` for ``DistanceSquared`` in the geometry term; its colour read with Go's
  ``color.White.RGBA()`` (16-bit) over 255 (257 times its radiance);
* **integrator**: the bounce's first number from ``rng.gen_range(0..1)`` (an integer: 0, every bounce along the
  normal); the bounce's sample turned by Swift's ``simd_quatf(from: n, to: z)`` for ``(from: z, to: n)``; Russian
  roulette with Kotlin's ``(0..1).random()`` (an ``Int``: half the paths ended, the rest divided by p); Haskell's
  ``until (\s -> depth s < maxDepth)`` (no bounce);
* **samples and passes**: the spp cast ``as u8`` in Rust (300 wraps to 44); Swift's ``stride(from: 0, to: spp, by:
  64)`` with every batch full (256 samples over 200); one ``new Random()`` a pixel on .NET Framework (seeded by the
  millisecond: 16 pixels in a row with the same numbers); Go goroutines closing over their worker index (every
  fourth row rendered, the rest black).

The correct hand-ins come in ways no class used: Mitsuba with the first bounce's cosine sample about +z turned to the
normal by glam's ``Quat::from_rotation_arc(Vec3::Z, n)``, Mitsuba with the first vertex's light sample an antithetic
pair, (u, v) and (1 - u, 1 - v), averaged (Swift), a binary PPM built by Haskell's ``Data.ByteString.Char8.pack``,
Mitsuba with the first bounce the normal plus a unit vector from Go's ``rand.NormFloat64`` (three normal numbers,
normalised), Mitsuba with the first vertex's four light samples in 2 x 2 strata from Kotlin's ``0 until 2``, an
8-bit PNG from Java's ``TYPE_INT_BGR`` filled with ``setRGB``, a PFM written by C#'s ``BinaryWriter`` and Mitsuba
with the first bounce in the frame of glam's ``any_orthonormal_pair`` (Duff et al.'s branchless basis).

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s ``edit`` and ``mitsuba_edit``), Mitsuba
renders at another spp or depth, Mitsuba's path integrator on rays a student's camera or mirror makes
(:func:`mcrt.grade.accuracy.unsaid._traced`), its first vertex's direct light redone as a student's light sample
makes it (:func:`mcrt.grade.accuracy.unheralded._first_vertex`), its first bounce redrawn
(:func:`mcrt.grade.accuracy.unprompted._first_bounce`), its samples reweighted where a student's roulette changes
them (same-seed samples of max depth 2 and 8), its samples drawn with the random numbers a student's generators
share, or correct renders post-processed and written with NumPy, Pillow and the standard library as the students'
programs do (the Java, Kotlin, C#, Go and Rust libraries' arithmetic emulated). mcrt renders none of it.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over :data:`CATEGORIES`: the 2nd, 4th, ... of
each category and of the correct hand-ins) are as in :mod:`~mcrt.grade.accuracy.unattended`, fixed before any case
was graded.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unattended, unbeknown,
                                 unbidden, unforeseen, unguessed, unheard, unheralded, unlooked, unmet, unnoticed,
                                 unprompted, unrecorded, unremarked, unremembered, unsaid, unseen, unsought, untold,
                                 untried, unvisited, unwonted)
from mcrt.grade.accuracy.cases import Spec
from mcrt.image_files import srgb_eotf

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


#: The classes after the first two, in the order they were written (their causes' words are this class's too).
_EARLIER = (programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked, unsought,
            unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted,
            unremarked, unremembered, unnoticed, unrecorded, unattended)


def _crc(name: str) -> int:
    return 1701000 + zlib.crc32(name.encode()) % 100000


_render = unseen._render
_posted = unseen._posted
_scene = unprompted._scene
_bsdf = unremarked._bsdf

#: The class's spp (the class is built at 64 x 64).
_S = 256
#: The assignment's maximum depth.
_DEPTH = 8


# --------------------------------------------------------------------------
# Post-processing (the render or its 8-bit codes in, what the program writes out)
# --------------------------------------------------------------------------

#: Java's brightening snippet, ``new RescaleOp(1.2f, 15, null)``: scale and offset of every 8-bit sample.
_RESCALE = (1.2, 15.0)


def _rescaleop_codes(image: np.ndarray, *, scale: float = _RESCALE[0], offset: float = _RESCALE[1]) -> np.ndarray:
    """The sRGB codes through Java's ``RescaleOp(scale, offset, null)``: ``(int) (c * scale + offset)`` (truncated),
    clamped to [0, 255]."""
    c = blind._srgb8(image).astype(np.float64)
    return np.clip(np.floor(c * scale + offset), 0, 255).astype(np.uint8)


def _write_png_rescaleop(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_rescaleop_codes(image), folder)


def _median_window_sorted(x):
    """A horizontal 3-tap median in Go over each channel's rows, ``win := row[x-1 : x+2]; sort.Float64s(win); row[x] =
    win[1]``: the window is a slice of the row itself, so each step sorts the row's three values in place, from the
    left: the row's two largest values carried to its right end, the values they pass moved a pixel left."""
    img = np.array(x, np.float64)
    for c in range(1, img.shape[1] - 1):
        img[:, c - 1:c + 2] = np.sort(img[:, c - 1:c + 2], axis=1)
    return img


#: The 4 x 4 Bayer matrix of the ordered dither.
_BAYER = np.array([[0, 8, 2, 10], [12, 4, 14, 6], [3, 11, 1, 9], [15, 7, 13, 5]])


def _dither_wrapped_codes(image: np.ndarray) -> np.ndarray:
    """Rust's ``let c = (srgb.min(1.0) * 255.0).round() as i32 + BAYER[y % 4][x % 4] / 4 - 2; px = c as u8;``: the
    dither adds -2 to 1 to the rounded code, and ``i32 as u8`` keeps the low byte (256 wraps to 0, -1 to 255)."""
    v = fresh._srgb(image)  # the sRGB values, clamped to [0, 1]
    h, w = v.shape[:2]
    offset = _BAYER[np.arange(h)[:, None] % 4, np.arange(w)[None, :] % 4] // 4 - 2
    c = np.floor(v * 255.0 + 0.5).astype(np.int64) + offset[:, :, None]
    return (c % 256).astype(np.uint8)


def _write_png_dither_wrapped(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_dither_wrapped_codes(image), folder)


def _convolveop_codes(image: np.ndarray) -> np.ndarray:
    """The sRGB codes through Java's ``new ConvolveOp(new Kernel(3, 3, ninths))``: each inner pixel the 3 x 3 mean of
    its codes (rounded), the pixels of the edge, where the kernel would reach past the image, set to 0
    (``EDGE_ZERO_FILL``, the default)."""
    c = blind._srgb8(image).astype(np.float64)
    h, w = c.shape[:2]
    out = np.zeros_like(c)
    inner = sum(c[a:h - 2 + a, b:w - 2 + b] for a in range(3) for b in range(3)) / 9.0
    out[1:-1, 1:-1] = np.floor(inner + 0.5)
    return np.clip(out, 0, 255).astype(np.uint8)


def _write_png_convolveop(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_convolveop_codes(image), folder)


# --------------------------------------------------------------------------
# Writers (the render in, the file a program writes)
# --------------------------------------------------------------------------

#: Java's luminance weights for a linear grey ColorSpace (ComponentColorModel's, on linear RGB).
_JAVA_GREY = np.array([0.2125, 0.7154, 0.0721])


def _byte_gray_codes(image: np.ndarray) -> np.ndarray:
    """(H, W) the bytes Java's ``setRGB`` stores in a ``TYPE_BYTE_GRAY`` image (a linear grey ColorSpace): the sRGB
    codes linearised to 16 bits, their luminance, ``(byte) (grey * 255 + 0.5)``: no sRGB curve on the way out."""
    lin16 = np.floor(srgb_eotf(blind._srgb8(image) / 255.0) * 65535.0 + 0.5)
    grey = lin16 @ _JAVA_GREY / 65535.0
    return np.floor(grey * 255.0 + 0.5).astype(np.uint8)


def _write_png_byte_gray(image: np.ndarray, folder: Path) -> Path:
    from PIL import Image

    path = folder / "render.png"
    Image.fromarray(_byte_gray_codes(image), "L").save(path, format="PNG")
    return path


def _signed_bytes_packed(codes: np.ndarray) -> np.ndarray:
    """(H, W, 3) the codes Java's ``img.setRGB(x, y, (r << 16) | (g << 8) | b)`` stores when r, g and b are ``byte``
    (signed): each is widened to an int with its sign, so a code of 128 or more sets every bit above its own; the
    packed int's low three bytes kept (``TYPE_INT_RGB`` has no alpha)."""
    c = np.asarray(codes).astype(np.int64)
    signed = np.where(c >= 128, c - 256, c)
    word = (signed[..., 0] << 16) | (signed[..., 1] << 8) | signed[..., 2]
    word &= 0xFFFFFF
    return np.stack([(word >> 16) & 0xFF, (word >> 8) & 0xFF, word & 0xFF], axis=-1).astype(np.uint8)


def _write_png_signed_bytes(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_signed_bytes_packed(blind._srgb8(image)), folder)


def _infix_packed(codes: np.ndarray) -> np.ndarray:
    """(H, W, 3) what Kotlin's ``val rgb = r shl 16 or g shl 8 or b`` packs: infix functions share one precedence and
    run left to right, ``(((r shl 16) or g) shl 8) or b`` = ``r shl 24 or g shl 8 or b``: the red in the alpha byte
    (dropped by ``TYPE_INT_RGB``), the red byte 0."""
    c = np.asarray(codes).astype(np.int64)
    word = ((((c[..., 0] << 16) | c[..., 1]) << 8) | c[..., 2]) & 0xFFFFFF
    return np.stack([(word >> 16) & 0xFF, (word >> 8) & 0xFF, word & 0xFF], axis=-1).astype(np.uint8)


def _write_png_infix(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_infix_packed(blind._srgb8(image)), folder)


def _block_copied(image: np.ndarray) -> np.ndarray:
    """The film copied with C#'s ``Buffer.BlockCopy(film, 0, data, 0, film.Length)``: the count is in bytes, so the
    first ``film.Length`` bytes, a quarter of the floats (row-major, the top first), land in ``data``; the rest stays
    0."""
    flat = np.ascontiguousarray(image, np.float32).reshape(-1)
    out = np.zeros_like(flat)
    n = flat.size // 4
    out[:n] = flat[:n]
    return out.reshape(np.shape(image))


def _write_pfm_block_copied(image: np.ndarray, folder: Path) -> Path:
    """A PFM (scale -1, little-endian, the bottom row first) as C#'s ``BinaryWriter`` writes it, of
    :func:`_block_copied`."""
    return fresh._write_pfm(_block_copied(image), folder)


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------

#: The surfaces' colours in the scene file's order (floor, ceiling, walls AB to FA, tetrahedron) and, for each, the
#: surface whose colour a Go loader gives it: two ``range`` loops over a ``map[string]Vec3``, one for the names and
#: one for the values, each in its own random order (this run's).
_MAP_ORDER = ("DE", "tetrahedron", "ceiling", "EF", "floor", "AB", "FA", "CD", "BC")
_SURFACES = ("floor", "ceiling", "AB", "BC", "CD", "DE", "EF", "FA", "tetrahedron")


def _albedos_map_order(s):
    """Every Lambertian's albedo replaced by the albedo of the surface :data:`_MAP_ORDER` gives it."""
    own = dict(zip(_SURFACES, [s.room.floor_albedo, s.room.ceiling_albedo,
                               *(w.albedo for w in s.room.walls),
                               next(o for o in s.objects if o.name == "tetrahedron").material.albedo]))
    given = {a: tuple(own[b]) for a, b in zip(_SURFACES, _MAP_ORDER)}
    walls = tuple(replace(w, albedo=given["".join(w.corners)]) for w in s.room.walls)
    room = replace(s.room, walls=walls, floor_albedo=given["floor"], ceiling_albedo=given["ceiling"])
    objects = tuple(replace(o, material=replace(o.material, albedo=given["tetrahedron"])) if o.name == "tetrahedron"
                    else o for o in s.objects)
    return replace(s, room=room, objects=objects)


def _tetra_faces() -> tuple[tuple[int, int, int], ...]:
    """The tetrahedron's faces as vertex indices, in the scene's order and winding (face i without vertex i)."""
    v = np.asarray(next(o for o in _scene().objects if o.name == "tetrahedron").vertices, np.float64)
    faces = []
    for i in range(4):
        f = [j for j in range(4) if j != i]
        if np.cross(v[f[1]] - v[f[0]], v[f[2]] - v[f[0]]) @ (v[i] - v[f[0]]) > 0:
            f = [f[0], f[2], f[1]]
        faces.append(tuple(f))
    return tuple(faces)


def _libgdx_sub_triangles(vertices, faces) -> np.ndarray:
    """(n, 3, 3): each face's edges precomputed with libGDX's ``Vector3 e1 = v[b].sub(v[a]); Vector3 e2 =
    v[c].sub(v[a]);`` and kept as (p0, e1, e2) references: ``sub`` changes the vector it is called on and returns
    it, so the shared vertices change face after face and every stored triangle, p0, p0 + e1, p0 + e2, reads their
    final values."""
    v = np.array(vertices, np.float64)
    for a, b, c in faces:
        v[b] = v[b] - v[a]
        v[c] = v[c] - v[a]
    return np.stack([np.stack([v[a], v[a] + v[b], v[a] + v[c]]) for a, b, c in faces])


def _tetra_libgdx(d: dict) -> dict:
    t = next(o for o in _scene().objects if o.name == "tetrahedron")
    return fresh._rebuilt(d, "tetrahedron", _libgdx_sub_triangles(t.vertices, _tetra_faces()), _bsdf(t.material))


#: The walls Rust's ``corners.chunks(2)`` gives (for ``windows(2)`` and the last wall): A-B, C-D, E-F.
_WALLS_MISSING = ("wall_BC", "wall_DE", "wall_FA")


def _walls_chunked(d: dict) -> dict:
    for name in _WALLS_MISSING:
        d = fresh._without_mesh(d, name)
    return d


#: The radius of the Swift ``struct Sphere``'s default (``var radius: Float = 1``), left by a ``for var`` loop.
_DEFAULT_RADIUS = 1.0


def _sphere_default_radius(s):
    return replace(s, objects=tuple(replace(o, radius=_DEFAULT_RADIUS) if o.name == "sphere" else o
                                    for o in s.objects))


#: The light's radiance read from Go's ``color.White.RGBA()`` (16-bit, 0xffff) over 255: 257 times.
_RGBA16 = 0xFFFF / 255.0


def _light_rgba16(s):
    return cases._light(s, radiance=tuple(float(r) * _RGBA16 for r in s.light.radiance))


# --------------------------------------------------------------------------
# The camera
# --------------------------------------------------------------------------


def _camera_quat_reversed(s):
    """glam's camera rotation ``from_rotation_x(FRAC_PI_2) * from_rotation_z(-FRAC_PI_2)`` (for ``from_rotation_z(...)
    * from_rotation_x(...)``), applied to a camera looking down -z with +y up: forward +y, up +x (right -z)."""
    return cases._camera(s, forward=(0.0, 1.0, 0.0), up=(1.0, 0.0, 0.0))


#: nalgebra's ``Perspective3::new(aspect, fovy, ...)`` called as ``new(FRAC_PI_2, 1.0, ...)``: aspect pi / 2, fovy 1
#: radian: the half-height tan(0.5) and the half-width pi / 2 tan(0.5).
_HALF_HEIGHT = math.tan(0.5)
_HALF_WIDTH = math.pi / 2.0 * _HALF_HEIGHT


def _perspective_swapped(fx, fy):
    eye, r, u, f, _ = unsaid._frame()
    s, t = _HALF_WIDTH * (2.0 * fx - 1.0), _HALF_HEIGHT * (1.0 - 2.0 * fy)
    return np.broadcast_to(eye, (len(fx), 3)), unsaid._unit(f + s[:, None] * r + t[:, None] * u)


#: Kotlin's ``tan(Math.toDegrees(fov) / 2)`` for fov = 90: tan(2578.31) = -1.362, a half-width of 1.362 and the
#: image turned over (both axes negated).
_TO_DEGREES_TAN = math.tan(math.degrees(90.0) / 2.0)
_TO_DEGREES_FOV = math.degrees(2.0 * math.atan(abs(_TO_DEGREES_TAN)))


def _fov_to_degrees(s):
    """The field of view of a half-width ``|tan(toDegrees(90) / 2)|`` and, its sign negative, the camera rolled 180
    degrees (right and up negated)."""
    return cases._roll(cases._fov(s, _TO_DEGREES_FOV), 180.0)


# --------------------------------------------------------------------------
# Light samples at the first vertex (unheralded._first_vertex's ``direct``)
# --------------------------------------------------------------------------

#: The light's point when u = v = 0 (Java's integer quotient cast: 0): its corner (4, -1).
def _light_corner() -> np.ndarray:
    lt = _scene().light
    return np.array([lt.center[0] - 0.5 * lt.size[0], lt.center[1] - 0.5 * lt.size[1], lt.center[2]])


def _light_at_corner(mscene, rng, p, n, rho, mitsuba):
    """Every light sample at the light's corner, weighted with the square's pdf 1 / A."""
    return unnoticed._light_at(mscene, p, n, rho, np.tile(_light_corner(), (len(p), 1)))


def _over_distance(p, n, q) -> np.ndarray:
    """The geometry term with C#'s ``Vector3.Distance`` for ``DistanceSquared``: cos_surface cos_light / |q - p|."""
    return unbeknown._geometry(p, n, q) * np.linalg.norm(q - p, axis=1)


def _light_over_distance(mscene, rng, p, n, rho, mitsuba):
    return unbeknown._light_sampled(mscene, rng, p, n, rho, mitsuba, geometry=_over_distance)


def _light_times_as_dot(mscene, rng, p, n, rho, mitsuba):
    """The light sample's ``albedo * Le`` with Kotlin's ``operator fun times(o: Vec3) = dot(o)``: a number, the
    channels' sum of Mitsuba's direct light (the light is white), given to all three channels."""
    return np.repeat(np.asarray(mitsuba, np.float64).sum(axis=1, keepdims=True), 3, axis=1)


def _light_antithetic(mscene, rng, p, n, rho, mitsuba):
    """Two light samples, at (u, v) and (1 - u, 1 - v) on the square, averaged (each uniform: unbiased)."""
    u, v = rng.random((2, len(p)))
    q1, q2 = unnoticed._light_points(u, v), unnoticed._light_points(1.0 - u, 1.0 - v)
    return 0.5 * (unnoticed._light_at(mscene, p, n, rho, q1) + unnoticed._light_at(mscene, p, n, rho, q2))


def _light_strata_2x2(mscene, rng, p, n, rho, mitsuba):
    """Four light samples, one in each of the square's 2 x 2 strata (``for (i in 0 until 2) for (j in 0 until 2)``,
    u = (i + rand) / 2), averaged."""
    total = np.zeros((len(p), 3))
    for i in range(2):
        for j in range(2):
            u, v = (i + rng.random(len(p))) / 2.0, (j + rng.random(len(p))) / 2.0
            total += unnoticed._light_at(mscene, p, n, rho, unnoticed._light_points(u, v))
    return total / 4.0


def _light_sample(name: str, direct) -> dict:
    """A spec's post-process: Mitsuba's path with its first vertex's light sample made by ``direct``."""
    return _posted(name, partial(unheralded._first_vertex, spp=_S, seed=_crc(name), direct=direct))


# --------------------------------------------------------------------------
# Mirror and bounces
# --------------------------------------------------------------------------


def _scale_add(d: np.ndarray, n: np.ndarray) -> np.ndarray:
    """javax.vecmath's ``r.set(d); r.scaleAdd(-2 * d.dot(n), n)``: ``scaleAdd(s, t)`` sets this = s this + t, so r
    = -2 (d . n) d + n, normalised (for d - 2 (d . n) n)."""
    return unsaid._unit(-2.0 * np.einsum("ij,ij->i", d, n)[:, None] * d + n)


def _reflect_scale_add(o, d):
    """Camera rays that meet the sphere sent on along :func:`_scale_add`'s direction from the hit point (a step
    along it: the ones it turns into the ball go on inside it): (origins, directions, segments used)."""
    c, _ = unsaid._sphere()
    ro, _, used = unsaid._reflected(o, d)
    hit = used == 1
    nrm = unsaid._unit(ro - c)
    r = _scale_add(d, nrm)
    p = ro - 1e-4 * nrm
    return np.where(hit[:, None], p + 1e-3 * r, o), np.where(hit[:, None], r, d), used


def _cosine_about_z(rng, m: int) -> np.ndarray:
    """(m, 3) cosine-weighted directions about +z: (r cos phi, r sin phi, sqrt(1 - u1)), r = sqrt(u1)."""
    u1, u2 = rng.random((2, m))
    r, phi = np.sqrt(u1), 2.0 * math.pi * u2
    return np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1.0 - u1)], axis=1)


def _rotation_arc(frm: np.ndarray, to: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(N, 3) each ``v`` turned by the shortest rotation taking the unit ``frm`` to the unit ``to`` (a quaternion's
    ``from_rotation_arc`` / ``simd_quatf(from:to:)``); opposite vectors turned half a turn about x, parallel ones
    kept."""
    frm, to = np.broadcast_to(frm, v.shape), np.broadcast_to(to, v.shape)
    axis = np.cross(frm, to)
    s = np.linalg.norm(axis, axis=1)
    c = np.einsum("ij,ij->i", frm, to)
    flat = s < 1e-9
    a = np.where(flat[:, None], [1.0, 0.0, 0.0], axis / np.where(flat, 1.0, s)[:, None])
    s = np.where(flat, 0.0, s)
    c = np.where(flat, np.sign(c), c)
    return (v * c[:, None] + np.cross(a, v) * s[:, None]
            + a * (np.einsum("ij,ij->i", a, v) * (1.0 - c))[:, None])


_Z = np.array([0.0, 0.0, 1.0])


def _quat_from_normal(rng, n):
    """A cosine-weighted sample about +z turned by Swift's ``simd_quatf(from: n, to: [0, 0, 1])`` (for ``(from: [0,
    0, 1], to: n)``): +z goes to 2 (n . z) z - n: right on the floor and the ceiling, about -n on the walls, weight
    1."""
    return _rotation_arc(n, _Z, _cosine_about_z(rng, len(n))), np.ones(len(n))


def _quat_to_normal(rng, n):
    """A cosine-weighted sample about +z turned by glam's ``Quat::from_rotation_arc(Vec3::Z, n)``: about n, weight
    1."""
    return _rotation_arc(_Z, n, _cosine_about_z(rng, len(n))), np.ones(len(n))


def _along_normal(rng, n):
    """Rust's ``let u1 = rng.gen_range(0..1) as f32;`` (an integer range: always 0): r = sqrt(u1) = 0, every bounce
    along the normal, weight 1."""
    return np.array(n, np.float64), np.ones(len(n))


def _normal_plus_gaussian(rng, n):
    """The normal plus a unit vector from Go's ``rand.NormFloat64()`` three times (a normal 3-vector normalised:
    uniform on the sphere), normalised: cosine-weighted, weight 1."""
    s = n + unsaid._unit(rng.normal(size=(len(n), 3)))
    length = np.linalg.norm(s, axis=1, keepdims=True)
    return np.where(length > 1e-9, s / np.maximum(length, 1e-12), n), np.ones(len(n))


def _orthonormal_pair(n: np.ndarray):
    """glam's ``any_orthonormal_pair`` (Duff et al., 'Building an Orthonormal Basis, Revisited'): sign = signum(z), a
    = -1 / (sign + z), b = x y a, (1 + sign x^2 a, sign b, -sign x) and (b, sign + y^2 a, -y)."""
    x, y, z = n[:, 0], n[:, 1], n[:, 2]
    sign = np.copysign(1.0, z)
    a = -1.0 / (sign + z)
    b = x * y * a
    return (np.stack([1.0 + sign * x * x * a, sign * b, -sign * x], axis=1),
            np.stack([b, sign + y * y * a, -y], axis=1))


def _cosine_in_orthonormal_pair(rng, n):
    loc = _cosine_about_z(rng, len(n))
    t, b = _orthonormal_pair(n)
    return unsaid._unit(loc[:, :1] * t + loc[:, 1:2] * b + loc[:, 2:] * n), np.ones(len(n))


def _bounce(name: str, draw) -> dict:
    """A spec's post-process: Mitsuba's path with its first bounce drawn by ``draw``."""
    return _posted(name, partial(unprompted._first_bounce, spp=_S, seed=_crc(name), draw=draw))


def _roulette_coin_sample(o, d, seed, *, full, direct):
    """A sample whose path meets Kotlin's ``if ((0..1).random() > p) break`` at its first bounce (an ``Int``, 0 or 1,
    against p = max(albedo) < 1): ended when 1 (half the time), the survivors divided by p: L2 + (L8 - L2) [coin ==
    0] / p."""
    L, near = unsaid._sampled(full, o, d, seed), unsaid._sampled(direct, o, d, seed)
    rho = unsaid._first_albedo(full, o, d)
    p = rho.max(axis=1)
    diffuse = p > 0.0
    coin = np.random.default_rng(seed + 41).integers(0, 2, len(p))
    weight = np.where(diffuse & (coin == 0), 1.0 / np.where(diffuse, p, 1.0), 0.0)
    return np.where(diffuse[:, None], near + (L - near) * weight[:, None], L)


def _roulette_coin(x, *, spp: int, seed: int):
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(
        _roulette_coin_sample, full=unsaid._loaded(_DEPTH), direct=unsaid._loaded(2)))


# --------------------------------------------------------------------------
# Samples and passes
# --------------------------------------------------------------------------

#: Rust's ``spp as u8`` of the 300 asked for: 44.
_SPP_ASKED = 300
_SPP_U8 = _SPP_ASKED % 256

#: Swift's batches: ``stride(from: 0, to: 200, by: 64)`` gives 0, 64, 128, 192, each batch a full 64.
_SPP_DECLARED, _BATCH = 200, 64
_SPP_BATCHED = len(range(0, _SPP_DECLARED, _BATCH)) * _BATCH

#: Pixels a millisecond: .NET Framework's ``new Random()`` is seeded by ``Environment.TickCount``.
_RUN = 16


def _run_offsets(rng, runs: int, n: int):
    """(u, v), each (runs n,): one jitter a (run, sample), the pixels of a run sharing it (their generators, seeded
    alike, give the same numbers)."""
    return rng.random((2, runs * n))


def _pixel_runs_shared(x, *, spp: int, seed: int, run: int = _RUN):
    """Each run of ``run`` consecutive pixels (row order) drawing the same random numbers: the same sub-pixel offsets
    and, lane for lane, Mitsuba's sampler seeded alike (the run's pixels in batches of their place in the run, lanes
    run by run); each pixel its own rays through them."""
    from mcrt.mitsuba_scene import pass_seed

    h, w = x.shape[:2]
    runs = h * w // run
    mscene = unsaid._loaded(_DEPTH)
    rng = np.random.default_rng(seed)
    jj, ii = np.divmod(np.arange(h * w), w)
    total = np.zeros((h * w, 3))
    n_chunk = max(1, (1 << 18) // runs)
    done, k = 0, 0
    while done < spp:
        n = min(n_chunk, spp - done)
        u, v = _run_offsets(rng, runs, n)
        for j in range(run):
            pix = np.arange(runs) * run + j
            o, d = unsaid._pinhole((np.repeat(ii[pix], n) + u) / w, (np.repeat(jj[pix], n) + v) / h)
            L = unsaid._sampled(mscene, np.asarray(o), d, pass_seed(seed, k))
            total[pix] += L.reshape(runs, n, 3).sum(axis=1)
        done, k = done + n, k + 1
    return (total / spp).reshape(h, w, 3)


#: Go's workers: ``for w := 0; w < 4; w++ { go func() { for y := w; y < h; y += 4 { renderRow(y) } }() }``.
_WORKERS = 4


def _rows_of_late_workers(x, *, workers: int = _WORKERS):
    """Every goroutine reading its worker index after the loop has ended (Go before 1.22: one variable for the whole
    loop, ``workers`` by then): each renders rows ``workers``, 2 ``workers``, ...: those rows right, every other row
    never written, black."""
    img = np.array(x, np.float64)
    keep = np.zeros(img.shape[0], bool)
    keep[workers::workers] = True
    img[~keep] = 0.0
    return img


# --------------------------------------------------------------------------
# Correct files made in other ways
# --------------------------------------------------------------------------


def _write_ppm_char8(image: np.ndarray, folder: Path) -> Path:
    """A binary PPM as Haskell's ``Data.ByteString.Char8.pack (header ++ map chr codes)`` writes it: each Char cut to
    its low byte (the codes themselves)."""
    h, w = image.shape[:2]
    text = f"P6\n{w} {h}\n255\n" + "".join(map(chr, blind._srgb8(image).reshape(-1).tolist()))
    path = folder / "render.ppm"
    path.write_bytes(bytes(ord(ch) & 0xFF for ch in text))
    return path


def _int_bgr_codes(image: np.ndarray) -> np.ndarray:
    """(H, W, 3) the codes of Java's ``TYPE_INT_BGR`` image filled with ``setRGB`` (its DirectColorModel moves each
    channel to its own bits, ``0x00BBGGRR``) and written by ImageIO as RGB."""
    c = blind._srgb8(image).astype(np.int64)
    word = (c[..., 2] << 16) | (c[..., 1] << 8) | c[..., 0]
    return np.stack([word & 0xFF, (word >> 8) & 0xFF, (word >> 16) & 0xFF], axis=-1).astype(np.uint8)


def _write_png_int_bgr(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_int_bgr_codes(image), folder)


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_java_rescaleop_brighten", "pp_go_median_window_sorts_row", "pp_rust_dither_as_u8_wraps",
                        "pp_java_convolveop_zero_edges"),
    "file": ("file_png_java_byte_gray", "file_png_java_signed_bytes", "file_png_kotlin_shl_or_infix",
             "file_pfm_csharp_blockcopy_bytes"),
    "materials": ("mirror_javax_vecmath_scale_add", "albedos_go_map_range_order", "light_sample_kotlin_times_as_dot"),
    "geometry": ("tetra_libgdx_sub_in_place", "walls_rust_chunks_for_windows", "sphere_swift_for_var_copy"),
    "camera": ("camera_glam_quat_order_reversed", "fov_nalgebra_perspective_aspect_first", "fov_kotlin_to_degrees"),
    "light": ("light_java_quotient_cast_corner", "light_csharp_distance_unsquared", "light_go_rgba_sixteen_bit"),
    "integrator": ("bounce_rust_gen_range_integer", "bounce_swift_quat_from_normal_to_z",
                   "roulette_kotlin_int_range_coin", "depth_haskell_until_inverted"),
    "samples": ("samples_rust_spp_as_u8", "batches_swift_stride_last_full", "samples_dotnet_random_per_pixel",
                "workers_go_loop_variable_captured"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_java_rescaleop_brighten", "tone_map", True, writer=_write_png_rescaleop, file="png-rescaleop",
             truth="the 8-bit sRGB image brightened before ImageIO.write with Java's usual snippet, new "
             "RescaleOp(1.2f, 15, null).filter(img, img): every code (int) (1.2 c + 15), clamped to 255: black "
             "written 15, a wall of 0.2 (code 124) 163, every code from 200 (linear 0.58) up 255: the image lighter, "
             "its shadows grey, its bright parts flat white"),
        Spec("pp_go_median_window_sorts_row", "blur", True, held_out=True, **_posted(
            "go_median_sorted", _median_window_sorted),
             truth="a horizontal 3-tap median against fireflies written in Go over each channel's rows, win := "
             "row[x-1 : x+2]; sort.Float64s(win); row[x] = win[1]: the window is a slice of the row, so every step "
             "sorts the row's own three values in place, left to right: each row's two largest values carried to its "
             "right end (the light's 20 at the image's right edge in the light's rows), the values they passed "
             "shifted a pixel left, partly sorted, as EXR"),
        Spec("pp_rust_dither_as_u8_wraps", "code_overflow", True, writer=_write_png_dither_wrapped,
             file="png-dither-wrapped",
             truth="an ordered dither against banding in Rust, let c = (srgb.min(1.0) * 255.0) as i32 + BAYER[y % "
             "4][x % 4] / 4 - 2; px = c as u8 (with .round() before the cast; an integer's as wraps, where a "
             "float's saturates): the codes moved by -2 to 1, 255 + 1 written 0: a quarter of the saturated "
             "pixels (the light, its reflection), every other column of every other row, black, an 8-bit PNG"),
        Spec("pp_java_convolveop_zero_edges", "blur", held_out=True, writer=_write_png_convolveop,
             file="png-convolveop",
             truth="a 3 x 3 box blur against the noise with Java's new ConvolveOp(new Kernel(3, 3, ninths)) on the "
             "8-bit sRGB image, its edge condition left at the default EDGE_ZERO_FILL: each inner pixel the mean of "
             "its 3 x 3 codes, the pixels of the edge, where the kernel reaches past the image, set to 0: the image "
             "blurred in a black frame a pixel wide, an 8-bit PNG"),
        # Writing the file
        Spec("file_png_java_byte_gray", "colour_lost", True, writer=_write_png_byte_gray, file="png-byte-gray",
             truth="the image made as new BufferedImage(W, H, BufferedImage.TYPE_BYTE_GRAY) (for TYPE_INT_RGB) and "
             "filled with setRGB of the sRGB codes: its ColorSpace is a linear grey, so each pixel is stored as "
             "the luminance of its linearised colour, (byte) (Y * 255 + 0.5), with no curve on the way out: a grey "
             "8-bit PNG, the colours gone and every value written linear (a grey wall of 0.2 written 51 for 124): "
             "far too dark"),
        Spec("file_png_java_signed_bytes", "code_overflow", True, held_out=True, writer=_write_png_signed_bytes,
             file="png-signed-bytes",
             truth="the codes kept in Java byte arrays and packed as img.setRGB(x, y, (r << 16) | (g << 8) | b): a "
             "byte is signed, widened with its sign, so a code of 128 or more (linear 0.22) sets every bit above "
             "its own: where blue is 128 or more the pixel written (255, 255, b), where green is, its red 255: the "
             "floor and the lit blue and green walls, whose codes lie just under 128, speckled where the noise lifts "
             "them past it (yellow, orange and white specks), the brightest pixels white, the rest right, an 8-bit "
             "PNG"),
        Spec("file_png_kotlin_shl_or_infix", "channels", True, writer=_write_png_infix, file="png-kotlin-infix",
             truth="each pixel packed in Kotlin as val rgb = r shl 16 or g shl 8 or b for setRGB: infix functions "
             "share one precedence and run left to right, (((r shl 16) or g) shl 8) or b = r shl 24 or g shl 8 or "
             "b: the red code in the alpha byte, which TYPE_INT_RGB drops: the red channel 0 everywhere, green and "
             "blue right, an 8-bit PNG"),
        Spec("file_pfm_csharp_blockcopy_bytes", "bad_pixels", True, held_out=True, writer=_write_pfm_block_copied,
             file="pfm-blockcopy",
             truth="the film (a float[] of W H 3) copied into the writer's array with C#'s Buffer.BlockCopy(film, 0, "
             "data, 0, film.Length), whose count is in bytes, not elements: a quarter of the floats copied, the top "
             "quarter of the image right, the rest 0 (black), a PFM by BinaryWriter"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("mirror_javax_vecmath_scale_add", "material", True, **_posted("vecmath_scale_add", partial(
            unsaid._traced, spp=_S, seed=_crc("mirror_javax_vecmath_scale_add"), after=_reflect_scale_add)),
             truth="the mirror's reflection with javax.vecmath, r.set(d); r.scaleAdd(-2 * d.dot(n), n), taken for r "
             "+ s n: scaleAdd(s, t) sets this = s this + t, so r = -2 (d . n) d + n, normalised (for camera rays; "
             "Mitsuba's path after it): the rays that meet the ball within 45 degrees of head-on sent on into it "
             "(black), the rest between the ray and the normal: the sphere a dark disc in a bright, squeezed rim"),
        Spec("albedos_go_map_range_order", "albedo", True, held_out=True, edit=_albedos_map_order,
             truth="the surfaces' colours read into a Go map[string]Vec3 and listed by two range loops over it, one "
             "for the names (each surface's material index) and one for the colours: Go's map order is random, "
             "each loop its own: the floor blue (DE's), the ceiling orange (the tetrahedron's), AB grey 0.8, BC "
             "green, CD grey 0.6, DE red, EF cyan, FA yellow, the tetrahedron purple"),
        Spec("light_sample_kotlin_times_as_dot", "albedo", True, **_light_sample(
            "light_sample_kotlin_times_as_dot", _light_times_as_dot),
             truth="the light sample's albedo * Le with the Vec3 class's operator fun times(o: Vec3) = dot(o) (the * "
             "of a maths course), a number for a colour: at the first surface a camera ray meets (Mitsuba's path "
             "after it) the direct light grey, the albedo's channels' sum times the light's: the floor's direct "
             "light 3 times as bright (1.8 for 0.6), the red wall's a grey of 1.05, the surfaces' own colours "
             "only in the light that bounces"),
        # Geometry
        Spec("tetra_libgdx_sub_in_place", "object_shape", True, mitsuba_edit=_tetra_libgdx,
             truth="the tetrahedron's edges precomputed face by face with libGDX's Vector3, e1 = v[b].sub(v[a]), e2 "
             "= v[c].sub(v[a]), and kept as (p0, e1, e2): sub changes the vector it is called on and returns it, so "
             "the shared vertices are changed face after face and every triangle reads their last values: three of "
             "its four faces from (7.5, -2, -4.9) to points as far as (-8.5, 0.7, 7.8), one beyond the wall behind "
             "the camera: orange slabs across the room and out of it, the tetrahedron gone"),
        Spec("walls_rust_chunks_for_windows", "mesh_face", True, held_out=True, mitsuba_edit=_walls_chunked,
             truth="the walls built from the corners' pairs with Rust's corners.chunks(2) (for windows(2) and the "
             "wrap to the first corner): A-B, C-D and E-F only: walls BC (right), DE (far left) and FA (behind the "
             "camera) missing, the void black through them, the room darker"),
        Spec("sphere_swift_for_var_copy", "object_size", True, edit=_sphere_default_radius,
             truth="the spheres' radii set after loading in Swift with for var s in spheres { s.radius = r } (the "
             "loop variable a copy of the struct): the change lost, every sphere keeping its initialiser's default "
             "radius 1: the mirror sphere of radius 1 for 1.5 at the right centre"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    return (
        # Camera
        Spec("camera_glam_quat_order_reversed", "camera_rotation", True, edit=_camera_quat_reversed,
             truth="the camera's rotation from glam's quaternions, Quat::from_rotation_x(FRAC_PI_2) * "
             "Quat::from_rotation_z(-FRAC_PI_2) for from_rotation_z(-FRAC_PI_2) * from_rotation_x(FRAC_PI_2) (the "
             "product applies its right factor first), on a camera looking down -z with +y up: forward +y, up +x: "
             "the view of the room's left side towards wall EF, turned a quarter, the ceiling on the left, the floor "
             "on the right"),
        Spec("fov_nalgebra_perspective_aspect_first", "camera_fov", True, held_out=True, **_posted(
            "nalgebra_perspective", partial(unsaid._traced, spp=_S, seed=_crc("fov_nalgebra_perspective_aspect_first"),
                                            camera=_perspective_swapped)),
             truth="the camera's projection nalgebra's Perspective3::new(FRAC_PI_2, 1.0, near, far) written in "
             "glam's order (fovy, aspect) for nalgebra's (aspect, fovy): a vertical field of view of 1 radian "
             "(57.3 degrees) and an aspect of 1.571: 81.3 degrees across: the view narrower, more so up and down: "
             "the room larger and stretched upwards"),
        Spec("fov_kotlin_to_degrees", "camera_fov", True, edit=_fov_to_degrees,
             truth="the image plane's half-width tan(Math.toDegrees(fov) / 2) in Kotlin (for Math.toRadians): "
             "tan(2578.3) = -1.362: a field of view of 107.4 degrees for 90, and, the half-width negative, both "
             "axes reversed: the view wider and upside down (turned 180 degrees)"),
        # Light model
        Spec("light_java_quotient_cast_corner", "light_pdf", True, **_light_sample(
            "light_java_quotient_cast_corner", _light_at_corner),
             truth="the light's sample point from Java's u = (double) (rng.nextInt(Integer.MAX_VALUE) / "
             "Integer.MAX_VALUE) (the cast applied to the integer quotient: 0), at the first surface a camera ray "
             "meets (Mitsuba's path after it): every light sample at the light's corner (4, -1) with the square's "
             "pdf: its light on the surfaces from a point there, hard shadows moved, the light seen right"),
        Spec("light_csharp_distance_unsquared", "light_model", True, held_out=True, **_light_sample(
            "light_csharp_distance_unsquared", _light_over_distance),
             truth="the light sample's geometry term divided by C#'s Vector3.Distance(p, q) for "
             "Vector3.DistanceSquared(p, q), at the first surface a camera ray meets (Mitsuba's path after it): a "
             "fall-off of 1 / d for 1 / d^2: the surfaces' direct light times their distance to the light (up to "
             "13), the farthest the most, the light seen right"),
        Spec("light_go_rgba_sixteen_bit", "light_radiance", True, edit=_light_rgba16,
             truth="the light's radiance 20 times its colour color.White, read in Go with r, g, b, _ := "
             "c.RGBA() and divided by 255: RGBA returns 16-bit values (0xffff), so the radiance is 257 times the "
             "scene's, 5140: the light and everything it lights 257 times too bright"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples and passes."""
    c = _crc
    return (
        # Integrator
        Spec("bounce_rust_gen_range_integer", "indirect_scale", True, **_bounce(
            "bounce_rust_gen_range_integer", _along_normal),
             truth="the cosine-weighted bounce's first number drawn with rand's let u1 = rng.gen_range(0..1) as f32 "
             "(an integer range: always 0, for 0.0..1.0), r = sqrt(u1), at the first surface a camera ray meets "
             "(Mitsuba's path after it): every bounce along the normal, the indirect light only what lies straight "
             "in front of each surface, the direct light right"),
        Spec("bounce_swift_quat_from_normal_to_z", "indirect_scale", True, held_out=True, **_bounce(
            "bounce_swift_quat_from_normal_to_z", _quat_from_normal),
             truth="the cosine-weighted bounce drawn about +z and turned with Swift's simd_act(simd_quatf(from: n, "
             "to: [0, 0, 1]), s) for simd_quatf(from: [0, 0, 1], to: n), at the first surface a camera ray meets "
             "(Mitsuba's path after it): +z taken to 2 (n . z) z - n: right on the floor and the ceiling, on the "
             "walls the bounces about -n, into the wall they leave (which the ray meets again at once), on the "
             "tetrahedron tilted: the indirect light wrong on the walls and the tetrahedron, the direct light right"),
        Spec("roulette_kotlin_int_range_coin", "roulette", True, **_posted("kotlin_coin", partial(
            _roulette_coin, spp=_S, seed=c("roulette_kotlin_int_range_coin"))),
             truth="Russian roulette written in Kotlin as if ((0..1).random() > p) break, p the throughput's largest "
             "channel: an IntRange's random() is 0 or 1, so half the paths end whatever p is, the survivors still "
             "divided by p, at the first surface a camera ray meets (Mitsuba's path after it): the light after the "
             "bounce 0.5 / p (0.63 to 0.83) of the truth, the indirect light darker, the direct light right"),
        Spec("depth_haskell_until_inverted", "depth", True, held_out=True, max_depth=1,
             truth="the bounce loop written with Haskell's until (\\s -> depth s < maxDepth) step s0, until's "
             "predicate taken for a while's: until stops as soon as it holds, at depth 0: no bounce, no light "
             "sample: only the emission the camera's rays meet, the light; the room, the tetrahedron and the mirror "
             "black"),
        # Samples and passes
        Spec("samples_rust_spp_as_u8", "spp_claim", spp=_SPP_U8, declared_spp=_SPP_ASKED,
             truth="the 300 samples a pixel asked for stored in the settings' spp: u8 with args.spp as u8 (an "
             "integer's as keeps the low byte): 44 samples rendered and their mean right, 300 declared: the image "
             "as noisy as 44 spp"),
        Spec("batches_swift_stride_last_full", "sample_count", True, held_out=True, spp=_SPP_BATCHED,
             declared_spp=_SPP_DECLARED, **_posted("stride_batches", partial(
                 blind._scaled, f=_SPP_BATCHED / _SPP_DECLARED)),
             truth="200 samples a pixel in batches of 64, for start in stride(from: 0, to: spp, by: 64) with every "
             "batch a full 64: four batches, 256 samples summed and divided by the 200 asked for: the image 28 % too "
             "bright, 200 declared"),
        Spec("samples_dotnet_random_per_pixel", "same_seed", **_posted("dotnet_random", partial(
            _pixel_runs_shared, spp=_S, seed=c("samples_dotnet_random_per_pixel"))),
             truth="a new Random() made for each pixel (one generator a pixel, for Parallel.For) on .NET Framework, "
             "where it is seeded with Environment.TickCount: the pixels begun within one millisecond, 16 in a row, "
             "with the same seed, the same offsets and random numbers: the noise repeated along each run of 16 "
             "pixels, in short streaks"),
        Spec("workers_go_loop_variable_captured", "bad_pixels", True, held_out=True, **_posted(
            "go_loop_variable", _rows_of_late_workers),
             truth="four goroutines started as for w := 0; w < 4; w++ { go func() { for y := w; y < H; y += 4 { "
             "renderRow(y) } }() } (Go before 1.22: one w for the whole loop, read by the goroutines after the "
             "loop ends, 4): every goroutine renders rows 4, 8, ..., 60: those rows right, rows 0 to 3 and three "
             "of every four rows never written, black"),
    )


def _correct() -> tuple[Spec, ...]:
    return (
        Spec("ok_bounce_glam_rotation_arc", None, **_bounce("ok_bounce_glam_rotation_arc", _quat_to_normal),
             truth="Mitsuba path 256 spp with the first bounce a cosine-weighted sample about +z turned to the normal "
             "by glam's Quat::from_rotation_arc(Vec3::Z, n) (half a turn where n is -z), EXR"),
        Spec("ok_light_swift_antithetic_pair", None, held_out=True, **_light_sample(
            "ok_light_swift_antithetic_pair", _light_antithetic),
             truth="Mitsuba path 256 spp with the first vertex's light sample an antithetic pair in Swift, points at "
             "(u, v) and (1 - u, 1 - v) on the square, averaged, EXR"),
        Spec("ok_ppm_haskell_char8_pack", None, spp=188, writer=_write_ppm_char8, file="ppm-char8",
             truth="Mitsuba path 188 spp, a binary PPM of 8-bit sRGB codes built with Haskell's "
             "Data.ByteString.Char8.pack (header ++ map chr codes) (each Char cut to its byte)"),
        Spec("ok_bounce_go_norm_float64", None, held_out=True, **_bounce(
            "ok_bounce_go_norm_float64", _normal_plus_gaussian),
             truth="Mitsuba path 256 spp with the first bounce the normal plus a unit vector made of three of Go's "
             "rand.NormFloat64() normalised, normalised: cosine-weighted, EXR"),
        Spec("ok_light_kotlin_until_strata", None, **_light_sample("ok_light_kotlin_until_strata", _light_strata_2x2),
             truth="Mitsuba path 256 spp with four light samples at the first vertex, one in each 2 x 2 stratum of "
             "the square (for (i in 0 until 2) for (j in 0 until 2), u = (i + rand) / 2), averaged, EXR"),
        Spec("ok_png_java_int_bgr", None, held_out=True, spp=236, writer=_write_png_int_bgr, file="png-int-bgr",
             truth="Mitsuba path 236 spp, an 8-bit sRGB PNG from Java's TYPE_INT_BGR image filled with setRGB (its "
             "colour model places each channel) and written by ImageIO"),
        Spec("ok_pfm_csharp_binary_writer", None, spp=172, writer=fresh._write_pfm, file="pfm-binarywriter",
             truth="Mitsuba path 172 spp, a PFM written with C#'s BinaryWriter (little-endian floats on every .NET "
             "platform, scale -1.0), the rows from the bottom"),
        Spec("ok_bounce_glam_orthonormal_pair", None, held_out=True, **_bounce(
            "ok_bounce_glam_orthonormal_pair", _cosine_in_orthonormal_pair),
             truth="Mitsuba path 256 spp with the first bounce a cosine-weighted direction in the frame of glam's "
             "n.any_orthonormal_pair() (Duff et al.'s branchless basis), EXR"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "tone_map": "a curve or clamp applied before saving (the 8-bit codes scaled and offset)",
    "blur": "a filter after rendering (a median that sorts its rows in place, a box blur in a black frame)",
    "code_overflow": "codes past the byte's range wrapped round (a dithered code past 255, signed bytes sign-extended)",
    "colour_lost": "colour lost (the image written as a grey)",
    "channels": "colour channels written at the wrong places (the red code shifted into the alpha byte)",
    "bad_pixels": "pixels not computed or not written (a quarter of the film copied, rows never rendered)",
    "material": "an object rendered with another material (the mirror's reflection computed wrongly)",
    "albedo": "a surface's colour (the surfaces' colours shuffled, the direct light's colour a dot product)",
    "object_shape": "an object's shape (the tetrahedron's vertices changed while its faces were built)",
    "mesh_face": "faces of a mesh missing (three walls of the room)",
    "object_size": "an object's size (the sphere's radius left at a default)",
    "camera_rotation": "the camera's rotation (a quaternion product in the wrong order)",
    "camera_fov": "the camera's field of view (a projection's arguments swapped, degrees converted the wrong way)",
    "light_pdf": "the light sampled wrongly (every sample at its corner): the light seen right, its light on "
                 "surfaces not",
    "light_model": "another light model (a fall-off of 1 / d)",
    "light_radiance": "the light's radiance (a 16-bit colour read as 8-bit)",
    "indirect_scale": "the indirect light wrong (bounces not cosine-distributed about the normal), the direct light "
                      "right",
    "roulette": "Russian roulette wrong (half the paths ended, the survivors divided by another probability)",
    "depth": "the path depth (no bounce at all)",
    "spp_claim": "fewer samples per pixel than declared (the count cast to a byte)",
    "sample_count": "each pixel's sum divided by fewer samples than it got",
    "same_seed": "samples that should be independent made with the same random numbers (generators seeded alike)",
}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = blind.class_causes(MISTAKES, _EARLIER, NEW_CAUSES, _REWORDED)


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
