r"""A twenty-sixth class of hand-ins: mistakes of students' tracers, scene input and output no class tried, blind.

How it was written: from what goes wrong in students' programs written in
column-major, 1-based numeric languages and their libraries (MATLAB and
Octave's first non-singleton dimension, ``conv2``'s default shape,
``imguidedfilt``'s defaults, ``fwrite`` of an array, integer classes that round,
1-based indices and ``linspace``'s endpoints; Julia's ``÷``, ranges and
column-major matrices; Fortran's implicit typing, integer division, inclusive
``DO`` bounds and unformatted records; R's recycling, ``matrix``'s fill by
column, ``ifelse``, ``length`` and its ``png()`` device), not from the grader.
Its author read the other classes' specs and cause words, the catalogue
(:mod:`mcrt.mutants`), the scene files and design notes, mcrt's scene, camera and
image code, :data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to stay
clear of their mistakes; never the grader's rules (what decides a cause) nor its
reports, and graded none of it, not one case. Each cause and ``major`` flag was
set from the mistake alone; every mistake is worded by a cause the other classes
already have (:data:`NEW_CAUSES` is empty), so ``SAME_MISTAKE`` needed no new
entry. The mistakes differ from those of the twenty-four other classes
(:mod:`~mcrt.grade.accuracy.cases`, :mod:`~mcrt.grade.accuracy.outside` and the
modules of :data:`_EARLIER`, from :mod:`~mcrt.grade.accuracy.programs` to
:mod:`~mcrt.grade.accuracy.unremarked`) and from the catalogue's bugs:

* **post-processing**: a grey-world white balance ``img * gains`` in R, the
  3-vector recycled down the array (diagonal stripes); a box blur with MATLAB's
  ``conv2`` ('full', cropped at the top left: moved a pixel, its edges dark);
  MATLAB's ``imguidedfilt`` at its defaults; ``img ./ max(img)`` (each column
  over its own maximum);
* **writing the file**: R's ``rasterImage`` on a ``png()`` device with the axes'
  4 % extension (the image shrunk in a white border); a PPM's codes written as
  Fortran's unformatted record (its length markers read as codes: channels
  turned); MATLAB's ``fwrite`` of the H x W x 3 array (column-major, planar); an
  sRGB table indexed with MATLAB's ``+ 1`` kept;
* **materials**: the walls' albedos in R's ``matrix(v, nrow = 6)`` (filled by
  column); the mirror's direction from R's ``ifelse`` with a scalar test (one
  coordinate, recycled); albedos as ``uint8`` codes divided by 255 in the integer
  class (0 or 1);
* **geometry**: the sphere's centre sliced ``rec[1:4]`` from its record; each
  wall's quad from R's ``cbind`` with the heights recycled (the top quarter
  missing); the tetrahedron's faces stored as columns, read as rows;
* **camera**: ``pi = 22/7`` in Fortran (3: 85.9 degrees); the half-width
  ``tan(deg2rad(fov) ÷ 2)`` (0: one colour); the column ``mod(k, W)`` of a
  1-based linear index (the last column from past the left edge);
* **light model**: ``do i = 0, 4`` for 4 light samples (5, over 4); light strata
  from ``linspace(0, 1, 4)`` (past the light's edge); the light's height in an
  implicit INTEGER (4 for 4.99);
* **integrator**: the bounce the normal plus a cube's point normalised; roulette
  ``if rand < beta`` on the RGB throughput; the azimuth from Julia's
  ``rand(0:2π)`` (7 values); the survival probability an implicit INTEGER (every
  path ended where roulette begins);
* **samples and passes**: the mean with Julia's ``÷`` (floored); a pass loop
  ``1:nPasses-1`` divided by ``nPasses``; the sums over R's ``length`` of an spp x 3
  matrix; the passes counted by Fortran's integer division (192 of 200).

The correct hand-ins come in ways no class used: Mitsuba with the first bounce
from MATLAB's ``sph2cart`` given the polar angle as an elevation (Malley's method
all the same), Mitsuba with the light's radiance a uniform spectrum, Mitsuba's
samples summed in single precision, a PPM whose header is one line, Mitsuba's
samples averaged into a column-major film, Mitsuba with the first vertex's light
sample in 1-based strata, Mitsuba with the first bounce from a cube's point
rejected outside the ball, and an 8-bit PNG as R's ``png()`` device writes it
edge to edge with a pHYs chunk.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s ``edit``
and ``mitsuba_edit``), Mitsuba renders at another field of view, depth or width,
Mitsuba's path integrator on rays a student's mirror makes
(:func:`mcrt.grade.accuracy.unsaid._traced`), its first vertex's direct light
redone as a student's light sample makes it
(:func:`mcrt.grade.accuracy.unheralded._first_vertex`), its first bounce redrawn
(:func:`mcrt.grade.accuracy.unprompted._first_bounce`), its samples, one by one,
reweighted where a student's roulette changes them (same-seed samples of max
depth 2 and 8, :func:`mcrt.grade.accuracy.unbeknown._camera_samples`), or correct
renders post-processed and written with NumPy, SciPy, Pillow and the standard
library as students' programs do. mcrt renders none of it.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over
:data:`CATEGORIES`: the 2nd, 4th, ... of each category and of the correct
hand-ins) are as in :mod:`~mcrt.grade.accuracy.unremarked`, fixed before any case
was graded.
"""

from __future__ import annotations

import math
import struct
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unbeknown, unbidden,
                                 unforeseen, unguessed, unheard, unheralded, unlooked, unmet, unprompted, unremarked,
                                 unsaid, unseen, unsought, untold, untried, unvisited, unwonted)
from mcrt.grade.accuracy.cases import Spec
from mcrt.image_files import srgb_oetf

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


#: The classes after the first two, in the order they were written (their causes' words are this class's too).
_EARLIER = (programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked, unsought,
            unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted,
            unremarked)


def _crc(name: str) -> int:
    return 1301000 + zlib.crc32(name.encode()) % 100000


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


def _column_major_index(h: int, w: int) -> np.ndarray:
    """(H, W, 3): each element's linear index in R's (and MATLAB's, Fortran's) column-major order, i + H j + H W c."""
    i, j, c = np.meshgrid(np.arange(h), np.arange(w), np.arange(3), indexing="ij")
    return i + h * j + h * w * c


def _gains_recycled(x):
    """A grey-world white balance written in R as ``img * gains`` (``gains`` the 3 channel gains, the channels' mean
    over each channel's mean): R recycles the 3-vector down the array in column-major order, so element (i, j, c)
    is multiplied by ``gains[(i + H j + H W c) % 3]``, not ``gains[c]`` (12288 elements a multiple of 3: no
    warning)."""
    img = np.asarray(x, np.float64)
    h, w = img.shape[:2]
    m = img.reshape(-1, 3).mean(axis=0)
    gains = m.mean() / np.maximum(m, 1e-12)
    return img * gains[_column_major_index(h, w) % 3]


def _conv2_full_cropped(x):
    """A 3 x 3 box blur with MATLAB's ``conv2(img(:, :, c), ones(3) / 9)``, whose default shape is 'full' (H + 2 by
    W + 2, zeros outside the image), cropped as ``out(1:H, 1:W)``: pixel (i, j) the mean of the block from (i - 2,
    j - 2) to (i, j), zeros past the top and left edges: the blur moved a pixel down and right, the first row and
    column dark."""
    img = np.asarray(x, np.float64)
    h, w = img.shape[:2]
    p = np.pad(img, ((2, 2), (2, 2), (0, 0)))
    full = sum(p[a:a + h + 2, b:b + w + 2] for a in range(3) for b in range(3)) / 9.0
    return full[:h, :w]


def _guided_self(x, *, size: int = 5, eps: float = 0.01):
    """MATLAB's ``imguidedfilt(img)`` at its defaults on the linear render, each channel guided by itself: a 5 x 5
    neighbourhood, ``DegreeOfSmoothing`` 0.01 (a hundredth of a double image's range squared), the borders
    replicated: q = mean(a) I + mean(b), a = var / (var + eps), b = (1 - a) mean, over each window."""
    from scipy.ndimage import uniform_filter

    img = np.asarray(x, np.float64)
    box = partial(uniform_filter, size=(size, size, 1), mode="nearest")
    mean = box(img)
    var = np.maximum(box(img * img) - mean * mean, 0.0)
    a = var / (var + eps)
    b = mean - a * mean
    return box(a) * img + box(b)


def _max_first_dim(x):
    """The render normalised to [0, 1] as MATLAB's ``img ./ max(img)``: ``max`` works along the first non-singleton
    dimension (the rows), a 1 x W x 3 array, so each column is divided by its own largest value, channel by
    channel."""
    img = np.asarray(x, np.float64)
    return img / np.maximum(img.max(axis=0, keepdims=True), 1e-12)


# --------------------------------------------------------------------------
# Writers (the render in, the file a program writes)
# --------------------------------------------------------------------------

#: R's ``plot.new()`` extends each axis by 4 % at both ends (``xaxs = "r"``): [0, 1] drawn in [-0.04, 1.04].
_R_EXTEND = 0.04


def _r_raster_codes(codes: np.ndarray, *, extend: float = _R_EXTEND) -> np.ndarray:
    """The (H, W) PNG R's ``png(width = W, height = H); par(mar = c(0, 0, 0, 0)); plot.new(); rasterImage(img, 0, 0,
    1, 1)`` writes: the axes' 4 % extension left in (no ``xaxs = "i"``), so the image is drawn shrunk to 1 / 1.08
    of the device in the middle, bilinear (``interpolate = TRUE``, on the codes), the rest the device's white."""
    h, w = codes.shape[:2]

    def axis(n):
        u = (np.arange(n) + 0.5) / n * (1.0 + 2.0 * extend) - extend
        s = np.clip(u * n - 0.5, 0.0, n - 1.0)
        i0 = np.floor(s).astype(int)
        return (u >= 0.0) & (u <= 1.0), i0, np.minimum(i0 + 1, n - 1), s - i0

    iny, y0, y1, fy = axis(h)
    inx, x0, x1, fx = axis(w)
    c = codes.astype(np.float64)
    rows = c[y0] * (1.0 - fy)[:, None, None] + c[y1] * fy[:, None, None]
    out = np.floor(rows[:, x0] * (1.0 - fx)[None, :, None] + rows[:, x1] * fx[None, :, None] + 0.5)
    out[~iny] = 255.0
    out[:, ~inx] = 255.0
    return out.astype(np.uint8)


def _write_png_r_raster(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_r_raster_codes(blind._srgb8(image)), folder)


def _fortran_record_body(codes: np.ndarray) -> bytes:
    """The PPM's raster as Fortran's unformatted sequential ``write(10) pixels`` writes it: the record framed by its
    length in bytes, a 4-byte integer before and after (gfortran's record markers)."""
    data = np.ascontiguousarray(codes).tobytes()
    marker = struct.pack("<i", len(data))
    return marker + data + marker


def _write_ppm_fortran_records(image: np.ndarray, folder: Path) -> Path:
    """A binary PPM whose header is written formatted and whose codes are one unformatted sequential record: a
    reader takes the 4-byte marker for the first pixel and a byte, every pixel after (B of the pixel two before, R
    and G of the one before), the last 4 bytes of data and the closing marker left over."""
    h, w = image.shape[:2]
    path = folder / "render.ppm"
    path.write_bytes(unheard._ppm_header(w, h) + _fortran_record_body(blind._srgb8(image)))
    return path


def _column_major_bytes(codes: np.ndarray) -> bytes:
    """The bytes MATLAB's ``fwrite(fid, img, 'uint8')`` writes of an H x W x 3 array: its memory, column-major (the
    row index fastest, then the column, then the channel), for a PPM's pixel-interleaved, row-major raster."""
    return np.ascontiguousarray(np.asarray(codes).transpose(2, 1, 0)).tobytes()


def _write_ppm_fwrite(image: np.ndarray, folder: Path) -> Path:
    h, w = image.shape[:2]
    path = folder / "render.ppm"
    path.write_bytes(unheard._ppm_header(w, h) + _column_major_bytes(blind._srgb8(image)))
    return path


#: The entries of the program's sRGB table (linear 0 to 1, ``linspace(0, 1, 1024)``).
_LUT_N = 1024


def _lut_plus_one_codes(image: np.ndarray, *, n: int = _LUT_N) -> np.ndarray:
    """8-bit codes from an sRGB table of ``n`` entries indexed as MATLAB's ``lut(round(v * (n - 1)) + 1)`` ported to
    Python with the ``+ 1`` kept (clipped to the table's last entry when the top index failed): each value looked up
    one entry (1 / (n - 1)) too high."""
    lut = np.floor(srgb_oetf(np.linspace(0.0, 1.0, n)) * 255.0 + 0.5).astype(np.uint8)
    v = np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 1.0)
    return lut[np.minimum(np.round(v * (n - 1)).astype(int) + 1, n - 1)]


def _write_png_lut_plus_one(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_lut_plus_one_codes(image), folder)


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _walls_filled_by_column(s):
    """The walls' 18 albedo numbers (wall by wall, r g b) put in R's ``matrix(v, nrow = 6, ncol = 3)``, which fills
    by column (``byrow = FALSE``): wall k's colour (v[k], v[k + 6], v[k + 12])."""
    v = [c for wl in s.room.walls for c in wl.albedo]
    n = len(s.room.walls)
    walls = tuple(replace(wl, albedo=(v[k], v[k + n], v[k + 2 * n])) for k, wl in enumerate(s.room.walls))
    return replace(s, room=replace(s.room, walls=walls))


def _uint8_over_255(albedo) -> tuple[float, ...]:
    """An albedo kept as MATLAB ``uint8`` codes (``uint8(a * 255)``, rounded) and divided by 255 in the integer class:
    the quotient rounded to 0 or 1."""
    return tuple(float(np.floor(np.floor(a * 255.0 + 0.5) / 255.0 + 0.5)) for a in albedo)


def _albedos_uint8_divided(s):
    return unbidden._albedos_mapped(s, _uint8_over_255)


#: The sphere's record in the program's scene array, (x, y, z, r).
def _sphere_record() -> tuple[float, ...]:
    sp = next(o for o in _scene().objects if o.name == "sphere")
    return (*sp.center, sp.radius)


def _sphere_sliced_from_1(s):
    """The sphere's centre taken as ``rec[1:4]`` from its record (x, y, z, r), MATLAB's ``rec(1:3)`` ported with the
    end made exclusive and the start left at 1 (its radius ``rec[-1]``, MATLAB's ``rec(end)``, right): (y, z, r)."""
    rec = _sphere_record()
    objects = tuple(replace(o, center=tuple(float(c) for c in rec[1:4])) if o.name == "sphere" else o
                    for o in s.objects)
    return replace(s, objects=objects)


_bsdf = unremarked._bsdf


def _wall_quad_recycled(a, b, zf: float, zc: float) -> np.ndarray:
    """(2, 3, 3): a wall's quad built in R as ``cbind(c(ax, bx, bx, ax), c(ay, by, by, ay), c(zf, zc))``: the
    heights recycled down the 4 rows, (zf, zc, zf, zc) for (zf, zf, zc, zc): corners q0 (a, floor), q1 (b,
    ceiling), q2 (b, floor), q3 (a, ceiling), triangles (q0, q1, q2) and (q0, q2, q3) (each wound as the wall's
    own): the lower right and the lower left halves, the top quarter between the diagonals missing."""
    q = np.array([(*a, zf), (*b, zc), (*b, zf), (*a, zc)], np.float64)
    return q[np.array([(0, 2, 1), (0, 2, 3)])]


def _walls_z_recycled(d: dict) -> dict:
    room = _scene().room
    for wl in room.walls:
        a, b = room.corners[wl.corners[0]], room.corners[wl.corners[1]]
        name = "wall_" + "".join(wl.corners)
        tris = _wall_quad_recycled(a, b, room.floor_z, room.ceiling_z)
        own = np.asarray(fresh._surface(name).triangles, np.float64)
        n_own = np.cross(own[0, 1] - own[0, 0], own[0, 2] - own[0, 0])
        n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
        flip = (n @ n_own) < 0
        tris = np.where(flip[:, None, None], tris[:, [0, 2, 1]], tris)
        d = fresh._rebuilt(d, name, tris, _bsdf(fresh._surface(name).material))
    return d


def _faces_transposed(tris: np.ndarray) -> np.ndarray:
    """(n, 3, 3): each face's 3 x 3 vertex matrix read the other way round: the program stores a face's vertices as
    its columns (Julia's ``hcat(v0, v1, v2)``) and its triangle test takes ``T[k, :]`` for vertex k: the vertices
    (x0, x1, x2), (y0, y1, y2), (z0, z1, z2)."""
    return np.ascontiguousarray(np.asarray(tris, np.float64).transpose(0, 2, 1))


def _tetra_faces_transposed(d: dict) -> dict:
    sf = fresh._surface("tetrahedron")
    return fresh._rebuilt(d, "tetrahedron", _faces_transposed(sf.triangles), _bsdf(sf.material))


def _radiance_uniform(d: dict) -> dict:
    """The light's radiance a uniform spectrum of 20 (``{'type': 'uniform', 'value': 20}``)."""
    from mcrt.mitsuba_scene import _light_surface, _mesh

    s = _scene()
    sf = next(x for x in s.surfaces() if x.material is None)
    emitter = {"type": "area", "radiance": {"type": "uniform", "value": float(s.light.radiance[0])}}
    return dict(d, **{sf.name: _mesh(_light_surface(sf, s.light.normal), _bsdf(None), emitter)})


# --------------------------------------------------------------------------
# The camera
# --------------------------------------------------------------------------

#: The field of view when ``pi = 22/7`` is an integer division (3) in the degrees-to-radians conversion: the
#: half-angle 45 * 3 / 180 = 0.75 radians.
_FOV_PI_3 = math.degrees(2.0 * 45.0 * 3.0 / 180.0)

#: A field of view for the half-angle ``deg2rad(fov) ÷ 2`` (Julia's ``÷``, floored division: 0.0): small enough that
#: every ray meets the same point.
_FOV_DIV_SIGN = 1e-4


def _fov_wider(w: int, extra: int) -> float:
    """The horizontal field of view of ``w + extra`` columns of the assignment's pixels (90 degrees over ``w``)."""
    return math.degrees(2.0 * math.atan((w + extra) / w))


def _plane_width_zero(x, *, spp: int, seed: int):
    """Every camera ray along the view's axis (an image plane of width 0), onto the corner D where the walls CD and
    DE meet: the program's loop over the walls keeps the first of two equal hits (``t < t_best``), CD's. Mitsuba
    rendered at a field of view of :data:`_FOV_DIV_SIGN` and twice as wide, the right half kept (its rays a hair to
    the right of the axis: on CD)."""
    h, w = x.shape[:2]
    return _render(2 * w, h, spp, seed, sensor={"fov": _FOV_DIV_SIGN})[:, w:]


def _last_column_mod(x, *, spp: int, seed: int):
    """Pixels from MATLAB's linear index k = 1..W H as ``col = mod(k, W)``, ``row = ceil(k / W)`` (for ``mod(k - 1,
    W) + 1``), the ray through ``(col - rand) / W``: every row's last pixel (k a multiple of W) given column 0,
    the pixel just left of the image. Mitsuba rendered two columns wider (the same pixels), the last column the
    one outside the left edge."""
    h, w = x.shape[:2]
    wide = _render(w + 2, h, spp, seed, sensor={"fov": _fov_wider(w, 2)})
    out = wide[:, 1:w + 1].copy()
    out[:, -1] = wide[:, 0]
    return out


# --------------------------------------------------------------------------
# Light samples at the first vertex (unheralded._first_vertex's ``direct``)
# --------------------------------------------------------------------------

#: Light samples a vertex the program means to take, and the ones a Fortran ``do k = 0, n`` loop takes.
_LIGHT_SAMPLES = 4


def _light_loop_inclusive(mscene, rng, p, n, rho, mitsuba, *, k: int = _LIGHT_SAMPLES):
    """``k`` light samples a vertex meant, looped ``do i = 0, k`` (Fortran's bounds are inclusive: k + 1 of them),
    their sum divided by k: the direct light (k + 1) / k times Mitsuba's."""
    return np.asarray(mitsuba, np.float64) * (k + 1) / k


def _linspace_strata(rng, m: int, *, k: int = 4) -> np.ndarray:
    """(m,) numbers in strata whose origins are MATLAB's ``linspace(0, 1, k)`` (0, 1/3, 2/3, 1: both ends) and whose
    width is 1 / k: ``s(i) + rand / k`` for a stratum i drawn at random: [0, 1/4), [1/3, 7/12), [2/3, 11/12), [1,
    5/4), past the light's edge in the last."""
    origins = np.linspace(0.0, 1.0, k)
    return origins[rng.integers(0, k, m)] + rng.random(m) / k


def _light_points(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    lt = _scene().light
    lo = np.asarray(lt.center[:2]) - 0.5 * np.asarray(lt.size)
    size = np.asarray(lt.size)
    return np.stack([lo[0] + u * size[0], lo[1] + v * size[1], np.full(len(u), lt.center[2])], axis=1)


def _light_at(mscene, p, n, rho, q):
    """A first vertex's light sample at the points ``q``, weighted with the square's pdf 1 / A: rho Le G A / pi
    where nothing lies between (points off the light counted as on it)."""
    lt = _scene().light
    g = np.where(unbeknown._unblocked(mscene, p, q), unbeknown._geometry(p, n, q), 0.0)
    return rho * (g * lt.area / math.pi)[:, None] * np.asarray(lt.radiance, np.float64)


def _light_linspace_strata(mscene, rng, p, n, rho, mitsuba):
    return _light_at(mscene, p, n, rho, _light_points(_linspace_strata(rng, len(p)), _linspace_strata(rng, len(p))))


def _one_based_strata(rng, m: int, *, k: int = 2) -> np.ndarray:
    """(m,) numbers ``(i - 1 + rand) / k`` for a stratum i in 1..k drawn at random (uniform on [0, 1))."""
    return (rng.integers(1, k + 1, m) - 1 + rng.random(m)) / k


def _light_one_based_strata(mscene, rng, p, n, rho, mitsuba):
    return _light_at(mscene, p, n, rho, _light_points(_one_based_strata(rng, len(p)), _one_based_strata(rng, len(p))))


def _light_sample(name: str, direct) -> dict:
    """A spec's post-process: Mitsuba's path with its first vertex's light sample made by ``direct``."""
    return _posted(name, partial(unheralded._first_vertex, spp=_S, seed=_crc(name), direct=direct))


#: The light's centre when its height is assigned to ``lz`` (implicitly INTEGER in Fortran): 4.99 truncated to 4.
_LIGHT_AT_4 = (5.0, 0.0, 4.0)


# --------------------------------------------------------------------------
# Mirror, bounces and samples of the path
# --------------------------------------------------------------------------


def _reflect_ifelse(o, d):
    """Camera rays that meet the sphere reflected through R's ``ifelse(is_mirror, reflect(d, n), d)`` with a scalar
    test: ``ifelse`` returns a value the shape of its test, the reflection's first coordinate only, which the
    3-vector arithmetic after it recycles: the direction (rx, rx, rx), normalised: (1, 1, 1) / sqrt(3) or its
    opposite by the sign of rx: (origins, directions, segments used)."""
    c, radius = unsaid._sphere()
    oc = o - c
    b = np.einsum("ij,ij->i", oc, d)
    disc = b * b - (np.einsum("ij,ij->i", oc, oc) - radius * radius)
    t = -b - np.sqrt(np.maximum(disc, 0.0))
    hit = (disc > 0.0) & (t > 0.0)
    p = o + t[:, None] * d
    n = (p - c) / radius
    r = d - 2.0 * np.einsum("ij,ij->i", d, n)[:, None] * n
    rx = np.where(r[:, 0] >= 0.0, 1.0, -1.0)
    diag = np.repeat(rx[:, None], 3, axis=1) / math.sqrt(3.0)
    return (np.where(hit[:, None], p + 1e-4 * n, o), np.where(hit[:, None], diag, d), hit.astype(int))


def _cube_plus_normal(rng, n):
    """Bounce directions as the normal plus MATLAB's ``v = rand(3, 1) - 0.5; v = v / norm(v)`` (a point of the cube
    pushed onto the sphere, thicker towards its 8 corners, for a uniform point on it), normalised: weight 1 (times
    the albedo), as a cosine sample."""
    v = unsaid._unit(rng.random((len(n), 3)) - 0.5)
    s = n + v
    length = np.linalg.norm(s, axis=1, keepdims=True)
    return np.where(length > 1e-9, s / np.maximum(length, 1e-12), n), np.ones(len(n))


def _azimuth_julia_range(rng, n):
    """Cosine-weighted directions whose azimuth is Julia's ``rand(0:2π)``: a random element of the range 0:2π, step
    1 (0.0, 1.0, ..., 6.0), 7 azimuths in the tangent plane for a uniform angle."""
    u1 = rng.random(len(n))
    phi = rng.integers(0, 7, len(n)).astype(np.float64)
    z, r = np.sqrt(1.0 - u1), np.sqrt(u1)
    t, b = unforeseen._frame_of(n)
    return unsaid._unit((r * np.cos(phi))[:, None] * t + (r * np.sin(phi))[:, None] * b + z[:, None] * n), \
        np.ones(len(n))


def _sph2cart_elevation(rng, n):
    """Cosine-weighted directions from a polar angle ``theta = acos(sqrt(u1))`` handed to MATLAB's ``sph2cart(phi,
    theta, 1)``, which takes an elevation: z = sin(theta) = sqrt(1 - u1), the radius cos(theta) = sqrt(u1), Malley's
    method all the same (u1 and 1 - u1 alike uniform)."""
    u1, u2 = rng.random((2, len(n)))
    theta = np.arccos(np.sqrt(u1))
    phi = 2.0 * math.pi * u2
    t, b = unforeseen._frame_of(n)
    x, y, z = np.cos(theta) * np.cos(phi), np.cos(theta) * np.sin(phi), np.sin(theta)
    return unsaid._unit(x[:, None] * t + y[:, None] * b + z[:, None] * n), np.ones(len(n))


def _ball_by_rejection(rng, m: int) -> np.ndarray:
    """(m, 3) points uniform in the unit ball, drawn from the cube [-1, 1]^3 and kept where inside."""
    out = np.empty((0, 3))
    while len(out) < m:
        c = rng.random((2 * m, 3)) * 2.0 - 1.0
        out = np.concatenate([out, c[np.einsum("ij,ij->i", c, c) <= 1.0]])
    return out[:m]


def _rejection_plus_normal(rng, n):
    """Cosine-weighted directions as the normal plus a point on the unit sphere, the point drawn in the cube, kept
    inside the ball (``while norm(v) > 1``) and normalised: weight 1."""
    v = unsaid._unit(_ball_by_rejection(rng, len(n)))
    s = n + v
    length = np.linalg.norm(s, axis=1, keepdims=True)
    return np.where(length > 1e-9, s / np.maximum(length, 1e-12), n), np.ones(len(n))


def _roulette_vector_if_sample(o, d, seed, *, full, direct):
    """A sample whose path meets Russian roulette at its first bounce, written in MATLAB as ``if rand < beta`` with
    the RGB throughput ``beta`` (an ``if`` on a vector is true when all its elements are): survival when u < min
    (albedo), the survivors divided by p = max(albedo) as meant: L2 + (L8 - L2) [u < min] / max."""
    L, near = unsaid._sampled(full, o, d, seed), unsaid._sampled(direct, o, d, seed)
    rho = unsaid._first_albedo(full, o, d)
    p = rho.max(axis=1)
    diffuse = p > 0.0
    u = np.random.default_rng(seed + 37).random(len(p))
    weight = np.where(diffuse & (u < rho.min(axis=1)), 1.0 / np.where(diffuse, p, 1.0), 0.0)
    return np.where(diffuse[:, None], near + (L - near) * weight[:, None], L)


def _roulette_vector_if(x, *, spp: int, seed: int):
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(
        _roulette_vector_if_sample, full=unsaid._loaded(_DEPTH), direct=unsaid._loaded(2)))


#: The depth at which the assignment's Russian roulette begins (where a Fortran ``kp``, INTEGER, ends every path).
_RR_DEPTH = 5


# --------------------------------------------------------------------------
# Samples and passes
# --------------------------------------------------------------------------


def _mean_floor_divided(x):
    """Each pixel's sum divided by the spp with Julia's ``÷`` (floored division, typed for ``/``): the mean's floor,
    an integer."""
    return np.floor(np.asarray(x, np.float64))


#: Passes the program means to render and the ones a loop ``for p = 1:nPasses-1`` renders.
_PASSES = 8


def _passes_one_short(x, *, passes: int = _PASSES):
    """The sum of ``passes - 1`` passes (the loop ``1:nPasses-1``, a 0-based ``range(n)`` ported) divided by
    ``passes``: the mean of the ones rendered times (passes - 1) / passes."""
    return np.asarray(x, np.float64) * (passes - 1) / passes


def _divided_by_r_length(x):
    """Each pixel's channel sums divided by R's ``length(S)`` of its spp x 3 matrix of samples (every element, 3
    spp) for ``nrow(S)``: a third of the mean."""
    return np.asarray(x, np.float64) / 3.0


def _samples_float32(x, *, spp: int, seed: int):
    """Mitsuba's samples summed in single precision (a Fortran ``REAL`` film), divided by the spp."""
    h, w = x.shape[:2]
    L = unbidden._all_samples(w, h, spp, seed).astype(np.float32)
    return (L.sum(axis=1, dtype=np.float32) / np.float32(spp)).astype(np.float64).reshape(h, w, 3)


def _film_column_major(x, *, spp: int, seed: int):
    """Mitsuba's samples accumulated in a column-major film (Julia's ``film[x, y]``, x fastest in memory) and turned
    into the row-major image with ``permutedims``: each pixel its own mean."""
    h, w = x.shape[:2]
    mean = unbidden._all_samples(w, h, spp, seed).mean(axis=1)
    film = np.asfortranarray(mean.reshape(h, w, 3).transpose(1, 0, 2))  # film[x, y, c]
    return np.ascontiguousarray(film.transpose(1, 0, 2))


# --------------------------------------------------------------------------
# Correct files made in other ways
# --------------------------------------------------------------------------


def _write_ppm_one_line_header(image: np.ndarray, folder: Path) -> Path:
    """A binary PPM whose header is one line, ``P6 W H 255``, from a Fortran formatted write ``(A, I0, 1X, I0,
    A)``, the codes after it by stream access (no record markers)."""
    h, w = image.shape[:2]
    path = folder / "render.ppm"
    path.write_bytes(f"P6 {w} {h} 255\n".encode() + np.ascontiguousarray(blind._srgb8(image)).tobytes())
    return path


def _write_png_r_exact(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB PNG as R's ``png()`` device writes the raster drawn edge to edge (``par(mar = c(0, 0, 0, 0),
    xaxs = "i", yaxs = "i")``, ``interpolate = FALSE``): the codes as they are, with a pHYs chunk of 72 dpi."""
    from PIL import Image

    path = folder / "render.png"
    Image.fromarray(blind._srgb8(image), "RGB").save(path, format="PNG", dpi=(72, 72))
    return path


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_r_gains_recycled", "pp_conv2_full_cropped", "pp_imguidedfilt_defaults",
                        "pp_max_along_first_dimension"),
    "file": ("file_png_r_raster_axes_extended", "file_ppm_fortran_record_markers", "file_ppm_matlab_fwrite",
             "file_png_lut_index_plus_one"),
    "materials": ("albedos_r_matrix_by_column", "mirror_r_ifelse_scalar", "albedos_uint8_integer_division"),
    "geometry": ("sphere_record_sliced_from_1", "walls_r_cbind_heights_recycled", "tetra_faces_column_major"),
    "camera": ("fov_pi_as_22_over_7", "fov_julia_division_sign", "pixel_column_mod_one_based"),
    "light": ("light_samples_do_loop_inclusive", "light_strata_linspace_endpoints", "light_height_implicit_integer"),
    "integrator": ("bounce_cube_normalised", "roulette_matlab_if_on_vector", "bounce_julia_azimuth_range",
                   "roulette_probability_implicit_integer"),
    "samples": ("pixel_mean_julia_division_sign", "passes_loop_one_short", "samples_over_r_length",
                "passes_fortran_integer_division"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_r_gains_recycled", "white_balance", True, **_posted("r_gains_recycled", _gains_recycled),
             truth="a grey-world white balance written in R as img * gains, the 3 gains (the channels' mean over "
             "each channel's) recycled down the H x W x 3 array in column-major order: element (i, j, c) times "
             "gains[(i + H j + H W c) mod 3] (at 64 x 64, (i + j + c) mod 3), no warning: every channel scaled by "
             "all three gains in turn, diagonal stripes of colour a pixel wide, as EXR"),
        Spec("pp_conv2_full_cropped", "blur", held_out=True, **_posted("conv2_full", _conv2_full_cropped),
             truth="a 3 x 3 box blur against the noise with MATLAB's conv2(img(:, :, c), ones(3) / 9), its default "
             "shape 'full' (two pixels larger, zeros outside), cropped as out(1:H, 1:W): the blur moved a pixel "
             "down and right, the zeros taken in at the top and the left: the first row and column a third as "
             "bright, the second two thirds, as EXR"),
        Spec("pp_imguidedfilt_defaults", "blur", **_posted("guided_filter", _guided_self),
             truth="MATLAB's imguidedfilt(img) against the noise, at its defaults on the linear render (a 5 x 5 "
             "window, DegreeOfSmoothing 0.01), each channel its own guide: the noise of the dim surfaces smoothed "
             "away where its variance is under 0.01, the edges and the bright parts kept, as EXR"),
        Spec("pp_max_along_first_dimension", "normalised", True, held_out=True, **_posted(
            "max_first_dim", _max_first_dim),
             truth="the render normalised to [0, 1] with MATLAB's img ./ max(img): max works along the first "
             "non-singleton dimension, the rows, so every column is divided by its own largest value in each "
             "channel: the columns through the light or its reflection 20 times darker than the rest, the others "
             "stretched to 1, in vertical bands, as EXR"),
        # Writing the file
        Spec("file_png_r_raster_axes_extended", "resolution_crop", True, writer=_write_png_r_raster,
             file="png-r-raster",
             truth="the PNG drawn by R: png(width = W, height = H), par(mar = c(0, 0, 0, 0)), plot.new() and "
             "rasterImage(img, 0, 0, 1, 1), the axes' 4 % extension left in (no xaxs = 'i', yaxs = 'i'): the image "
             "shrunk to 1 / 1.08 of the frame, bilinear (interpolate = TRUE), in a white border of 4 % (two or "
             "three pixels at 64)"),
        Spec("file_ppm_fortran_record_markers", "channels", True, held_out=True, writer=_write_ppm_fortran_records,
             file="ppm-fortran-records",
             truth="a binary PPM written by Fortran, the header formatted, the codes one unformatted sequential "
             "record (write(10) pixels): gfortran frames it with its length, 4 bytes before and after, so a reader "
             "takes the marker for the first pixel and a byte: every pixel (B of the pixel two before, R and G of "
             "the pixel before), the channels turned (red read from blue, green from red, blue from green) and "
             "the image a pixel right"),
        Spec("file_ppm_matlab_fwrite", "row_stride", True, writer=_write_ppm_fwrite, file="ppm-fwrite",
             truth="a binary PPM whose codes are written with MATLAB's fwrite(fid, img, 'uint8') of the H x W x 3 "
             "array, without permute(img, [3 2 1]): its memory, column-major (down each column, all the red, then "
             "the green, then the blue) where the PPM wants pixel-interleaved rows: a scramble of grey stripes"),
        Spec("file_png_lut_index_plus_one", "encoding", held_out=True, writer=_write_png_lut_plus_one,
             file="png-lut-plus-one",
             truth="an 8-bit PNG whose sRGB curve is a table of 1024 entries indexed as MATLAB's lut(round(v * "
             "1023) + 1), ported to Python with the + 1 kept (the last index clipped): each value looked up 1/1023 "
             "too high: black written as code 3, the dark codes up to 3 higher (a value of 0.002 as 0.003), the "
             "rest within a code"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("albedos_r_matrix_by_column", "albedo", True, edit=_walls_filled_by_column,
             truth="the walls' 18 albedo numbers, wall by wall, put in R's matrix(v, nrow = 6, ncol = 3), which "
             "fills by column (byrow = FALSE): wall k (v[k], v[k + 6], v[k + 12]): AB yellow (0.75, 0.75, 0.15), "
             "BC cyan (0.15, 0.7, 0.7), CD dark grey 0.15, DE red (0.55, 0.15, 0.15), EF blue (0.15, 0.2, 0.65), "
             "FA pale grey (0.7, 0.75, 0.7)"),
        Spec("mirror_r_ifelse_scalar", "material", True, held_out=True, **_posted(
            "mirror_ifelse", partial(unsaid._traced, spp=_S, seed=_crc("mirror_r_ifelse_scalar"),
                                     after=_reflect_ifelse)),
             truth="the mirror's reflection chosen with R's ifelse(is_mirror, reflect(d, n), d) and a scalar test "
             "(for camera rays; Mitsuba's path after it): ifelse returns a value the shape of its test, the "
             "reflection's x only, recycled to (rx, rx, rx): every reflected ray along (1, 1, 1) or (-1, -1, -1) "
             "over sqrt(3): the sphere two flat patches of what those two directions meet"),
        Spec("albedos_uint8_integer_division", "albedo", True, edit=_albedos_uint8_divided,
             truth="the albedos kept as MATLAB uint8 codes and divided by 255 in the integer class (uint8(a * 255) "
             "/ 255 rounds to 0 or 1): every channel from 0.5 up 1, the rest 0: the floor, the ceiling white "
             "(albedo 1), the walls pure red, magenta, yellow, blue, green and cyan, the tetrahedron red: the room "
             "far brighter and saturated"),
        # Geometry
        Spec("sphere_record_sliced_from_1", "object_moved", True, edit=_sphere_sliced_from_1,
             truth="the sphere's centre taken from its record (x, y, z, r) = (9.5, 2, -3.3, 1.5) as rec[1:4], "
             "MATLAB's rec(1:3) ported with the end made exclusive and the start left at 1: centre (2, -3.3, 1.5), "
             "radius right: the mirror ball close in front of the camera, to the right and above the eye's "
             "height, the room behind it"),
        Spec("walls_r_cbind_heights_recycled", "mesh_face", True, held_out=True, mitsuba_edit=_walls_z_recycled,
             truth="each wall's quad built in R as cbind(c(ax, bx, bx, ax), c(ay, by, by, ay), c(zf, zc)): the two "
             "heights recycled down the four rows, (floor, ceiling, floor, ceiling) for (floor, floor, ceiling, "
             "ceiling): its two triangles the lower halves under each diagonal, the top quarter of every wall (the "
             "triangle from its top edge to its centre) missing onto the void"),
        Spec("tetra_faces_column_major", "object_shape", True, mitsuba_edit=_tetra_faces_transposed,
             truth="each face of the tetrahedron stored with its vertices as the columns of a 3 x 3 matrix "
             "(Julia's hcat(v0, v1, v2)) and read by the triangle test as rows, T[k, :]: the face's corners (x0, "
             "x1, x2), (y0, y1, y2), (z0, z1, z2): four large orange triangles far from the tetrahedron's place, "
             "through the room and out of it, the tetrahedron gone"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    return (
        # Camera
        Spec("fov_pi_as_22_over_7", "camera_fov", True, edit=cases.fov(_FOV_PI_3),
             truth="the field of view turned into radians with a Fortran PARAMETER pi = 22/7, an integer division "
             "(3): the half-angle 45 * 3 / 180 = 0.75 radians, a field of view of 85.9 degrees for 90: the view "
             "narrower, the room a little larger"),
        Spec("fov_julia_division_sign", "camera_fov", True, held_out=True, **_posted("plane_width_zero", partial(
            _plane_width_zero, spp=_S, seed=_crc("fov_julia_division_sign"))),
             truth="the image plane's half-width tan(deg2rad(fov) ÷ 2), Julia's ÷ (floored division) typed for /: "
             "1.571 ÷ 2 = 0.0, a plane of width 0: every ray along the view's axis, onto the corner D, where the "
             "wall CD, first in the program's list, wins the tie: the whole image one colour, CD's yellow"),
        Spec("pixel_column_mod_one_based", "row_stride", **_posted("column_mod", partial(
            _last_column_mod, spp=_S, seed=_crc("pixel_column_mod_one_based"))),
             truth="each pixel's column from MATLAB's linear index k = 1..W H as mod(k, W) (for mod(k - 1, W) + 1), "
             "its row ceil(k / W), the ray through (col - rand) / W: every row's last pixel given column 0, the "
             "pixel just left of the image: the right column of the image a copy of the view one pixel past the "
             "left edge, the rest right"),
        # Light model
        Spec("light_samples_do_loop_inclusive", "light_pdf", True, **_light_sample(
            "light_samples_do_loop_inclusive", _light_loop_inclusive),
             truth="4 light samples a vertex looped do i = 0, 4 (Fortran's bounds are inclusive: 5 samples) and "
             "their sum divided by 4, at the first surface a camera ray meets (Mitsuba's path after it): the "
             "direct light on the surfaces seen 25 % too bright, the light seen right"),
        Spec("light_strata_linspace_endpoints", "light_pdf", held_out=True, **_light_sample(
            "light_strata_linspace_endpoints", _light_linspace_strata),
             truth="the light's points stratified 4 x 4 with stratum origins from MATLAB's linspace(0, 1, 4) (0, "
             "1/3, 2/3, 1: both ends) and width 1/4, at the first surface a camera ray meets (Mitsuba's path "
             "after it): gaps between the strata, the last past the light's edge, points off the light counted: "
             "its light on the surfaces from a square 2.5 wide shifted 0.25 towards +x and +y, a little stronger "
             "and moved, the light seen right"),
        Spec("light_height_implicit_integer", "light_position", True, edit=cases.light(center=_LIGHT_AT_4),
             truth="the light's height assigned to lz in a Fortran program without IMPLICIT NONE (lz INTEGER, as "
             "every name from i to n): 4.99 truncated to 4: the light a unit under the ceiling, larger in the "
             "view, the ceiling above it unlit but by bounces, the floor and the walls' lower parts brighter"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples, passes and counters."""
    c = _crc
    return (
        # Integrator
        Spec("bounce_cube_normalised", "indirect_scale", **_posted("cube_normalised", partial(
            unprompted._first_bounce, spp=_S, seed=c("bounce_cube_normalised"), draw=_cube_plus_normal)),
             truth="the diffuse bounce drawn as the normal plus MATLAB's v = rand(3, 1) - 0.5; v = v / norm(v) (a "
             "point of the cube pushed onto the sphere, denser towards its 8 corners, for a uniform one), "
             "normalised and weighted as a cosine sample, at the first surface a camera ray meets (Mitsuba's path "
             "after it): the bounces a little biased towards the world's diagonals, the indirect light slightly "
             "off, the direct light right"),
        Spec("roulette_matlab_if_on_vector", "roulette", True, held_out=True, **_posted("roulette_vector_if", partial(
            _roulette_vector_if, spp=_S, seed=c("roulette_matlab_if_on_vector"))),
             truth="Russian roulette at the first bounce written in MATLAB as if rand < beta with the RGB "
             "throughput (an if on a vector is true only when all its elements are): survival with the smallest "
             "channel's probability, the survivors divided by the largest's as meant, at the first surface a "
             "camera ray meets (Mitsuba's path after it): the indirect light darker, most off the coloured walls "
             "(the red wall's 0.15 / 0.75: a fifth), the direct light right"),
        Spec("bounce_julia_azimuth_range", "indirect_scale", **_posted("azimuth_range", partial(
            unprompted._first_bounce, spp=_S, seed=c("bounce_julia_azimuth_range"), draw=_azimuth_julia_range)),
             truth="the cosine-weighted bounce's azimuth drawn with Julia's rand(0:2π), a random element of the "
             "range 0:2π whose step is 1: 7 azimuths, 0 to 6 radians, for a uniform angle, at the first surface a "
             "camera ray meets (Mitsuba's path after it): the indirect light from 7 half-planes about each normal, "
             "streaked and biased, the direct light right"),
        Spec("roulette_probability_implicit_integer", "roulette", held_out=True, max_depth=_RR_DEPTH,
             truth="the survival probability of Russian roulette assigned to kp in a Fortran program without "
             "IMPLICIT NONE (kp INTEGER): max(beta) truncated to 0, every path ended where roulette begins (after "
             "5 segments, for 8): the light of the longer paths lost, the image a little darker, most in the "
             "shadows"),
        # Samples, passes and counters
        Spec("pixel_mean_julia_division_sign", "quantisation", True, **_posted("mean_floor", _mean_floor_divided),
             truth="each pixel's sum divided by the spp with Julia's ÷ (floored division) typed for /: the mean's "
             "floor: every surface under 1 written 0, the room black, the light (20) and its reflection right"),
        Spec("passes_loop_one_short", "sample_count", True, held_out=True, spp=224, declared_spp=256, **_posted(
            "passes_one_short", _passes_one_short),
             truth="8 passes of 32 spp looped for p = 1:nPasses-1 (a 0-based range(n) ported to MATLAB): 7 passes "
             "rendered, their sum divided by 8: the image 12.5 % too dark, 256 declared"),
        Spec("samples_over_r_length", "sample_count", True, **_posted("over_r_length", _divided_by_r_length),
             truth="each pixel's channel sums divided by R's length(S) of its spp x 3 matrix of samples (every "
             "element: 3 spp) for nrow(S): the image a third as bright"),
        Spec("passes_fortran_integer_division", "spp_claim", held_out=True, spp=192, declared_spp=200,
             truth="passes of 64 spp counted as npass = spp / 64 in Fortran's integer division: 200 / 64 = 3 "
             "passes, 192 samples a pixel (their mean right), 200 declared: the image right, as noisy as 192 "
             "spp"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_bounce_sph2cart_elevation", None, **_posted("sph2cart_elevation", partial(
            unprompted._first_bounce, spp=_S, seed=c("ok_bounce_sph2cart_elevation"), draw=_sph2cart_elevation)),
             truth="Mitsuba path 256 spp with the first bounce from a polar angle acos(sqrt(u1)) handed to MATLAB's "
             "sph2cart as an elevation (Malley's method all the same: cosine-weighted), EXR"),
        Spec("ok_radiance_uniform_spectrum", None, held_out=True, spp=176, mitsuba_edit=_radiance_uniform,
             truth="Mitsuba path 176 spp with the light's radiance a uniform spectrum of 20 (R's c(20) recycled "
             "over the channels), EXR"),
        Spec("ok_samples_float32_sum", None, spp=128, **_posted("float32_sum", partial(
            _samples_float32, spp=128, seed=c("ok_samples_float32_sum"))),
             truth="Mitsuba path 128 spp, its samples summed in single precision (a Fortran REAL film), EXR"),
        Spec("ok_ppm_one_line_header", None, held_out=True, spp=196, writer=_write_ppm_one_line_header,
             file="ppm-one-line",
             truth="Mitsuba path 196 spp, a binary PPM whose header is one line, P6 W H 255, the codes after it by "
             "Fortran's stream access"),
        Spec("ok_film_column_major", None, spp=144, **_posted("film_column_major", partial(
            _film_column_major, spp=144, seed=c("ok_film_column_major"))),
             truth="Mitsuba path 144 spp, its samples averaged into a column-major film (Julia's film[x, y]) and "
             "turned into rows with permutedims, EXR"),
        Spec("ok_light_one_based_strata", None, held_out=True, **_light_sample(
            "ok_light_one_based_strata", _light_one_based_strata),
             truth="Mitsuba path 256 spp with the first vertex's light sample at a point of a 2 x 2 stratum drawn "
             "at random, (i - 1 + rand) / 2 for i in 1..2 (1-based and right), EXR"),
        Spec("ok_bounce_cube_rejection", None, **_posted("cube_rejection", partial(
            unprompted._first_bounce, spp=_S, seed=c("ok_bounce_cube_rejection"), draw=_rejection_plus_normal)),
             truth="Mitsuba path 256 spp with the first bounce the normal plus a point of the cube kept inside the "
             "unit ball (while norm(v) > 1) and normalised: cosine-weighted, EXR"),
        Spec("ok_png_r_raster_exact", None, held_out=True, spp=168, writer=_write_png_r_exact, file="png-r-exact",
             truth="Mitsuba path 168 spp, an 8-bit sRGB PNG as R's png() device writes a raster drawn edge to edge "
             "(no margins, xaxs = 'i', interpolate = FALSE), with a pHYs chunk of 72 dpi"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "white_balance": "each colour channel scaled after rendering (a white balance's gains recycled over the pixels)",
    "blur": "a filter after rendering (a box blur moved a pixel, a guided filter)",
    "normalised": "the values stretched after rendering (each column divided by its own maximum)",
    "resolution_crop": "rendered at another resolution, then padded or cropped to the assignment's (shrunk into a "
                       "white border)",
    "channels": "colour channels written in the wrong order (a Fortran record's markers before the codes)",
    "row_stride": "pixels written at the wrong addresses (a column-major array written whole, the last column "
                  "from the wrong pixel)",
    "encoding": "the values' encoding (the sRGB table read one entry late)",
    "albedo": "a surface's colour (the walls' colours filled by column, every albedo rounded to 0 or 1)",
    "material": "an object rendered with another material (the mirror reflecting along one diagonal)",
    "object_moved": "objects moved (the sphere's centre read from the wrong place of its record)",
    "mesh_face": "a face of a mesh missing (the top quarter of every wall)",
    "object_shape": "an object's shape (the tetrahedron's faces with their vertex matrices transposed)",
    "camera_fov": "the camera's field of view (pi taken as 3, a half-width of 0)",
    "light_pdf": "the light sampled wrongly (one sample too many, strata past its edge): the light seen right, its "
                 "light on surfaces not",
    "light_position": "the light's position (its height truncated to an integer)",
    "indirect_scale": "the indirect light wrong (bounces not cosine-distributed: a cube's corners, 7 azimuths), the "
                      "direct light right",
    "roulette": "Russian roulette wrong (survival by the smallest channel, every path ended where it begins)",
    "quantisation": "values quantised wrongly (each pixel's mean floored to an integer)",
    "sample_count": "each pixel's sum divided by more samples than it got (a pass short, three times the count)",
    "spp_claim": "fewer samples per pixel than declared (passes counted by integer division)",
}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = blind.class_causes(MISTAKES, _EARLIER, NEW_CAUSES, _REWORDED)


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
