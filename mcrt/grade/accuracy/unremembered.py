r"""A twenty-fifth class of hand-ins: mistakes of students' tracers, scene input and output no class tried, blind.

How it was written: from what goes wrong in programs ported from or written in the browser and its
JavaScript and TypeScript world (the 2D canvas and its ``ImageData``, ``devicePixelRatio`` and compositing;
WebGL's viewport and GLSL's constant loop bounds; three.js's conventions: its tone mappings, its camera's
projection matrix, Euler orders, ``geometry.center()``, ``Color.fromArray``, ``MathUtils.randFloatSpread``,
``Spherical``'s y-up poles, ``Vector3.length()``, its legacy lights and ``RectAreaLight``'s missing shadows;
JavaScript's numbers and arrays: ``Array.prototype.sort``'s string order, chained assignments, objects held by
reference, ``toPrecision``, typed arrays' offsets, clamping and silently ignored fractional indices, CSS colour
strings; web workers splitting the image; ``toDataURL``'s encoders), not from the grader. Its author read the
other classes' specs and cause words, the catalogue (:mod:`mcrt.mutants`), the scene files and design notes,
mcrt's scene, camera and image code, :data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to stay clear of their mistakes; never
the grader's rules (what decides a cause) nor its reports, and graded none of it, not one case. Each cause and
``major`` flag was set from the mistake alone; every mistake is worded by a cause the other classes already have
(:data:`NEW_CAUSES` is empty), so ``SAME_MISTAKE`` needed no new entry. The mistakes differ from those of the
twenty-four other classes (:mod:`~mcrt.grade.accuracy.cases`, :mod:`~mcrt.grade.accuracy.outside` and the modules
of :data:`_EARLIER`, from :mod:`~mcrt.grade.accuracy.programs` to :mod:`~mcrt.grade.accuracy.unremarked`) and
from the catalogue's bugs:

* **post-processing**: three.js's ``OptimizedCineonToneMapping`` (Hejl and Dawson's filmic curve) run on the
  render before the EXR; the render drawn onto a canvas sized for ``devicePixelRatio`` 1.25 and read back with
  ``getImageData(0, 0, W, H)`` (the top-left of a bilinear enlargement); a 3 x 3 median whose window is sorted
  with ``Array.prototype.sort()`` (as strings: "100" before "25"); the frame saved with ``toDataURL`` while a
  fade-in (``globalAlpha`` 0.9 over the page's white) was still running;
* **writing the file**: every pixel drawn with ``fillRect`` under a ``fillStyle`` of ``'#' +
  c.toString(16)``, neither padded nor clamped (a channel over 1 three digits: seven or nine digits no colour,
  the last colour kept; eight a colour with alpha); the values passed through JSON as ``toPrecision(3)``
  strings on their way to the EXR; the PNG made
  from ``toDataURL('image/webp')`` (lossy, quality 0.8); codes ``v * 256`` stored in a ``Uint8ClampedArray``
  (rounded, clamped at 255);
* **materials**: the surfaces' numeric ids sorted with ``.sort()`` (1, 10, 2, ...) and given the materials in
  numeric order; the mirror's reflections looked up in a cube map rendered from the sphere's centre
  (``CubeCamera``); each colour read with ``color.fromArray(colours, i)`` for ``i * 3``;
* **geometry**: each wall a ``PlaneGeometry`` turned with ``rotation.x = pi / 2`` and ``rotation.z =
  atan2(dy, dx)`` in three.js's default Euler order XYZ (the turn about z applied first, within the plane);
  the tetrahedron placed with ``geometry.center()`` (its bounding box's centre) and moved back to its vertices'
  centroid; the sphere a ``SphereGeometry(1.5, 32, 16)`` indexed through a ``Uint8Array`` (indices modulo 256);
* **camera**: ``camera.fov = 90`` set without ``updateProjectionMatrix()`` (three.js's default 50 degrees
  kept); a WebGL viewport left at the canvas's default 300 x 150 after the canvas was resized; the jitter drawn
  as ``let jx = jy = Math.random()`` (the same number twice);
* **light model**: three.js's legacy lighting's factor pi kept on the light's intensity; the direct light
  computed as three.js's ``RectAreaLight`` does, without a shadow test; the light turned with
  ``light.lookAt(0, 0, 0)`` (three.js's documentation's example), facing the origin;
* **integrator**: the cosine-weighted bounce's disk point from ``MathUtils.randFloatSpread(1)`` on each axis (a
  square of half-width 0.5, the disk's rejection never rejecting); the bounce built in place on the hit's
  normal object (JavaScript objects held by reference), the light sample after it taking the bounce's
  direction for the normal; Russian roulette's survival ``throughput.length()`` (Vector3's Euclidean length);
  the bounce's direction from ``setFromSphericalCoords`` (its pole +y) mapped to the tangent frame as if z
  were the pole, the directions below the surface negated;
* **samples and passes**: four web workers' RGBA strips placed with ``image.set(strip, k * rows * W)`` (the 4
  channels left out of the offset); six workers given ``H / 6`` rows each, a fractional start row's writes
  silently ignored by the typed array; passes counted by a progress fraction ``for (let f = 0; f < 1; f +=
  0.1)`` (11 passes, divided as 10); a GLSL ES 1.0 sample loop whose constant bound (48) cuts the 64 samples a
  frame asked for.

The correct hand-ins come in ways no class used: Mitsuba with sub-pixel offsets from mulberry32 (JavaScript's
favourite small generator) run per pixel, a PNG made from lossless WebP, Mitsuba's samples averaged as a WebGL
float target accumulates frames (a running mean in float32), an EXR of values through JSON (shortest round-trip
strings), Mitsuba with the light's square split into four triangles about its centre, mcrt as a PNG decoded from
a ``data:`` URL, Mitsuba with the first bounce drawn by spherical coordinates about the normal, and four
workers' strips rendered as Mitsuba windows with their own seeds.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s ``edit`` and ``mitsuba_edit``),
Mitsuba renders at another field of view or of a window of the view, Mitsuba's path integrator on rays a
student's mirror makes (:func:`mcrt.grade.accuracy.unsaid._traced`) or on sub-pixel offsets a student's loop
makes (:func:`mcrt.grade.accuracy.unforeseen._mean_through`), its first vertex's direct light redone as a
student's light sample makes it (:func:`mcrt.grade.accuracy.unheralded._first_vertex`), its first bounce
redrawn (:func:`mcrt.grade.accuracy.unprompted._first_bounce`), its samples cut or reweighted where a student's
path changes (same-seed samples of max depth 2 and 8, :func:`mcrt.grade.accuracy.unbeknown._camera_samples`),
or correct renders post-processed and written as students' programs do. mcrt renders only a correct hand-in.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over :data:`CATEGORIES`: the 2nd, 4th,
... of each category and of the correct hand-ins) are as in :mod:`~mcrt.grade.accuracy.unlooked`, fixed before
any case was graded.
"""

from __future__ import annotations

import base64
import io
import json
import math
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
    return 1201000 + zlib.crc32(name.encode()) % 100000


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


def _cineon(x, *, exposure: float = 1.0):
    """three.js's ``OptimizedCineonToneMapping`` (Jim Hejl and Richard Burgess-Dawson's filmic curve):
    ``c = max(0, exposure x - 0.004)``, ``pow(c (6.2 c + 0.5) / (c (6.2 c + 1.7) + 0.06), 2.2)`` (its own sRGB
    curve undone by the 2.2), channel by channel: 0 below 0.004, 1 at infinity."""
    c = np.maximum(np.asarray(x, np.float64) * exposure - 0.004, 0.0)
    return np.power(c * (6.2 * c + 0.5) / (c * (6.2 * c + 1.7) + 0.06), 2.2)


#: The device pixel ratio of the laptop's screen the canvas was sized for.
_DPR = 1.25


def _dpr_codes(codes: np.ndarray, *, dpr: float = _DPR) -> np.ndarray:
    """What ``getImageData(0, 0, W, H)`` reads of a canvas of ``dpr`` W x ``dpr`` H device pixels onto which the
    W x H image was drawn with ``drawImage(img, 0, 0, canvas.width, canvas.height)`` (image smoothing on: bilinear
    in the 8-bit sRGB codes, edges clamped): the top-left W x H of the enlarged image, device pixel (x, y) sampled at
    ((x + 0.5) / dpr - 0.5, (y + 0.5) / dpr - 0.5)."""
    from scipy.ndimage import map_coordinates

    h, w = codes.shape[:2]
    yy, xx = np.meshgrid((np.arange(h) + 0.5) / dpr - 0.5, (np.arange(w) + 0.5) / dpr - 0.5, indexing="ij")
    out = np.stack([map_coordinates(codes[..., c].astype(np.float64), [yy, xx], order=1, mode="nearest")
                    for c in range(3)], axis=2)
    return np.clip(np.round(out), 0, 255).astype(np.uint8)


def _write_png_dpr(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_dpr_codes(blind._srgb8(image)), folder)


#: The codes 0 to 255 in the order ``Array.prototype.sort()`` puts them (as strings: 0, 1, 10, 100, 101, ...).
_STRING_ORDER = np.array(sorted(range(256), key=str))
#: Each code's place in :data:`_STRING_ORDER`.
_STRING_RANK = np.argsort(_STRING_ORDER)


def _median_string_sorted(codes: np.ndarray) -> np.ndarray:
    """A 3 x 3 median of each channel's 8-bit codes whose window is sorted with ``window.sort()`` (no comparator:
    the numbers compared as strings) and its 5th taken, over the inside pixels (the border kept)."""
    c = np.asarray(codes).astype(np.int64)
    h, w = c.shape[:2]
    ranks = _STRING_RANK[c]
    stack = np.stack([ranks[1 + dy:h - 1 + dy, 1 + dx:w - 1 + dx] for dy in (-1, 0, 1) for dx in (-1, 0, 1)])
    out = c.copy()
    out[1:-1, 1:-1] = _STRING_ORDER[np.sort(stack, axis=0)[4]]
    return out.astype(np.uint8)


def _write_png_median_strings(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_median_string_sorted(blind._srgb8(image)), folder)


def _faded_codes(image: np.ndarray, *, alpha: float = 0.9) -> np.ndarray:
    """The 8-bit sRGB codes drawn with ``globalAlpha = alpha`` over the page's white (a fade-in not finished when
    ``toDataURL`` took the frame): ``round(alpha c + (1 - alpha) 255)``, the canvas blending in its sRGB codes."""
    c = blind._srgb8(image).astype(np.float64)
    return np.clip(np.round(alpha * c + (1.0 - alpha) * 255.0), 0, 255).astype(np.uint8)


def _write_png_faded(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_faded_codes(image), folder)


# --------------------------------------------------------------------------
# Writers (the render in, the file a program writes)
# --------------------------------------------------------------------------


def _fill_style(r: int, g: int, b: int):
    """What a canvas does with ``fillStyle = '#' + r.toString(16) + g.toString(16) + b.toString(16)`` (no
    ``padStart``, no clamp): (colour, alpha) for six digits, the short ``#rgb`` (each digit doubled) for three, the
    short ``#rgba`` for four, ``#rrggbbaa`` for eight, None for five, seven or nine (not a colour: the assignment
    ignored, the last fillStyle kept)."""
    digits = "".join(format(int(c), "x") for c in (r, g, b))
    if len(digits) in (6, 8):
        v = [int(digits[k:k + 2], 16) for k in range(0, len(digits), 2)]
        return tuple(v[:3]), (v[3] / 255.0 if len(digits) == 8 else 1.0)
    if len(digits) in (3, 4):
        v = [int(ch, 16) * 17 for ch in digits]
        return tuple(v[:3]), (v[3] / 255.0 if len(digits) == 4 else 1.0)
    return None


def _unclamped_codes(image: np.ndarray) -> np.ndarray:
    """The sRGB codes ``Math.round(srgb(v) * 255)`` never clamped (the ``Uint8ClampedArray`` the program used
    before clamped them): the light's 20 code 923."""
    v = np.maximum(np.nan_to_num(np.asarray(image, np.float64)), 0.0)
    return np.floor(srgb_oetf(v) * 255.0 + 0.5).astype(np.int64)


def _fill_rect_codes(codes: np.ndarray) -> np.ndarray:
    """The canvas, cleared to opaque black, after ``fillRect(x, y, 1, 1)`` of every pixel in row order under
    :func:`_fill_style`'s colour of its (unclamped) codes (a colour with alpha blended over the black; an invalid
    string leaving the last colour set, from the default ``'#000000'``)."""
    h, w = codes.shape[:2]
    out = np.zeros((h, w, 3), np.uint8)
    style = ((0, 0, 0), 1.0)
    for j in range(h):
        for i in range(w):
            s = _fill_style(*codes[j, i])
            if s is not None:
                style = s
            colour, alpha = style
            out[j, i] = np.round(np.asarray(colour, np.float64) * alpha)
    return out


def _write_png_fill_rect(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_fill_rect_codes(_unclamped_codes(image)), folder)


def _to_precision(x, digits: int = 3):
    """Each value as JavaScript's ``v.toPrecision(digits)`` writes it and ``Number`` reads it back: rounded to
    ``digits`` significant digits (0 stays 0)."""
    v = np.asarray(x, np.float64)
    safe = np.where(v != 0.0, np.abs(v), 1.0)
    scale = 10.0 ** (digits - 1 - np.floor(np.log10(safe)))
    return np.where(v != 0.0, np.round(v * scale) / scale, 0.0)


def _webp_codes(codes: np.ndarray, *, quality: int = 80, lossless: bool = False) -> np.ndarray:
    """The 8-bit codes after ``canvas.toDataURL('image/webp', quality / 100)`` (libwebp, lossy unless
    ``lossless``), decoded again."""
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(codes), "RGB").save(buf, format="WEBP", quality=quality, lossless=lossless)
    buf.seek(0)
    return np.asarray(Image.open(buf).convert("RGB"))


def _write_png_webp(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_webp_codes(blind._srgb8(image)), folder)


def _write_png_webp_lossless(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_webp_codes(blind._srgb8(image), lossless=True), folder)


def _clamped_256_codes(image: np.ndarray) -> np.ndarray:
    """sRGB values times 256 stored in a ``Uint8ClampedArray`` (the '256 levels' for 255): rounded half to even
    and clamped at 255, as the typed array stores them: every code about 0.4 % high, the values over 0.998 255."""
    v = srgb_oetf(np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 1.0))
    return np.clip(np.round(v * 256.0), 0, 255).astype(np.uint8)


def _write_png_clamped_256(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_clamped_256_codes(image), folder)


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------

#: The surfaces by the numeric ids the student's program gave them (1 to 10), in the scene file's order.
_IDS = ("floor", "ceiling", "wall_AB", "wall_BC", "wall_CD", "wall_DE", "wall_EF", "wall_FA", "tetrahedron",
        "sphere")


def _ids_string_sorted() -> dict[str, str]:
    """Each surface's material's owner when the ids are sorted with ``ids.sort()`` (as strings: 1, 10, 2, ..., 9)
    and the k-th of that order given the k-th material of the numeric list: the sphere (10) the ceiling's, each
    surface from the ceiling to the tetrahedron the next one's."""
    ids = sorted(range(1, len(_IDS) + 1), key=str)
    return {_IDS[i - 1]: _IDS[k] for k, i in enumerate(ids)}


def _materials_by_string_ids(s):
    """The scene with :func:`_ids_string_sorted`'s materials: the sphere a Lambertian of the ceiling's 0.8, the
    tetrahedron the mirror, the ceiling wall AB's red, walls AB to EF their next wall's colour, wall FA the
    tetrahedron's orange."""
    from mcrt.scene import Lambertian

    room = s.room
    mats = {"floor": Lambertian(room.floor_albedo), "ceiling": Lambertian(room.ceiling_albedo)}
    mats.update({"wall_" + "".join(wl.corners): Lambertian(wl.albedo) for wl in room.walls})
    mats.update({o.name: o.material for o in s.objects})
    owner = _ids_string_sorted()
    new = {name: mats[owner[name]] for name in _IDS}
    walls = tuple(replace(wl, albedo=new["wall_" + "".join(wl.corners)].albedo) for wl in room.walls)
    room = replace(room, floor_albedo=new["floor"].albedo, ceiling_albedo=new["ceiling"].albedo, walls=walls)
    return replace(s, room=room, objects=tuple(replace(o, material=new[o.name]) for o in s.objects))


def _cube_map_reflection(o, d):
    """Camera rays that meet the sphere reflected there, the reflected ray leaving from the sphere's centre (a
    cube map rendered by a ``CubeCamera`` at the sphere's position, the sphere hidden): the same as leaving from
    the point the reflected direction crosses the sphere from inside, ``c + r R``: (origins, directions, used)."""
    c, radius = unsaid._sphere()
    po, r, hit = unsaid._reflected(o, d)
    return np.where(hit[:, None], c + (radius + 1e-4) * r, po), r, hit


def _from_array_offset(s):
    """Each Lambertian's colour read with ``color.fromArray(colours, i)`` from the flat colour table (floor,
    ceiling, walls AB to FA, tetrahedron), the offset the colour's index ``i`` for ``i * 3``: colour i the numbers
    i to i + 2."""
    flat = np.asarray(unbidden._colour_table(s), np.float64).reshape(-1)
    it = iter(range(len(flat)))

    def read(_):
        k = next(it)
        return tuple(float(v) for v in flat[k:k + 3])

    return unbidden._albedos_mapped(s, read)


def _euler_xyz_wall(p, q, z0: float, z1: float) -> np.ndarray:
    """(2, 3, 3): a wall from corner p to q built as three.js's ``PlaneGeometry(length, height)`` with
    ``rotation.x = pi / 2`` and ``rotation.z = atan2(dy, dx)``, Euler order XYZ (the matrix Rx Ry Rz: the turn
    about z first, within the plane's own xy), placed at the wall's middle: a rectangle in the plane y = the
    middle's y, turned by atan2(dy, dx) within it."""
    p, q = np.asarray(p, np.float64), np.asarray(q, np.float64)
    length, height = float(np.linalg.norm(q - p)), z1 - z0
    theta = math.atan2(q[1] - p[1], q[0] - p[0])
    m = 0.5 * (p + q)
    local = np.array([(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)]) * (length, height)
    cz, sz = math.cos(theta), math.sin(theta)
    xr = local[:, 0] * cz - local[:, 1] * sz
    yr = local[:, 0] * sz + local[:, 1] * cz
    corners = np.stack([m[0] + xr, np.full(4, m[1]), 0.5 * (z0 + z1) + yr], axis=1)  # Rx(pi / 2): (x, y) -> (x, 0, y)
    return corners[np.array([[0, 1, 2], [0, 2, 3]])]


def _walls_euler_xyz(d: dict) -> dict:
    """Every wall as :func:`_euler_xyz_wall` builds it (its colour kept): walls BC and EF where they belong, the four
    slanted walls standing across the room in the planes y = -3 and y = 3, turned 63 or 117 degrees within them."""
    room = _scene().room
    for wl in room.walls:
        name = "wall_" + "".join(wl.corners)
        tris = _euler_xyz_wall(room.corners[wl.corners[0]], room.corners[wl.corners[1]], room.floor_z,
                               room.ceiling_z)
        d = fresh._rebuilt(d, name, tris, _bsdf(fresh._surface(name).material))
    return d


def _tetra_bbox_shift() -> np.ndarray:
    """The tetrahedron's move when ``geometry.center()`` takes off its bounding box's centre and
    ``mesh.position`` puts back its vertices' centroid: centroid - box centre, (0, 0.125, -0.725)."""
    v = np.asarray(next(o for o in _scene().objects if o.name == "tetrahedron").vertices, np.float64)
    return v.mean(axis=0) - 0.5 * (v.min(axis=0) + v.max(axis=0))


def _tetra_bbox_centred(d: dict) -> dict:
    sf = fresh._surface("tetrahedron")
    return fresh._rebuilt(d, "tetrahedron", np.asarray(sf.triangles) + _tetra_bbox_shift(), _bsdf(sf.material))


def _three_sphere(radius: float, width: int = 32, height: int = 16) -> tuple[np.ndarray, np.ndarray]:
    """three.js's ``SphereGeometry(radius, width, height)``: its (height + 1) (width + 1) vertices (poles on y, turned
    to the scene's z up: (x, y, z) -> (x, -z, y)) and its index list, as (vertices, (n, 3) indices)."""
    verts, grid = [], []
    for iy in range(height + 1):
        v = iy / height
        row = []
        for ix in range(width + 1):
            u = ix / width
            x = -radius * math.cos(u * 2 * math.pi) * math.sin(v * math.pi)
            y = radius * math.cos(v * math.pi)
            z = radius * math.sin(u * 2 * math.pi) * math.sin(v * math.pi)
            row.append(len(verts))
            verts.append((x, -z, y))
        grid.append(row)
    index = []
    for iy in range(height):
        for ix in range(width):
            a, b = grid[iy][ix + 1], grid[iy][ix]
            c, e = grid[iy + 1][ix], grid[iy + 1][ix + 1]
            if iy != 0:
                index.append((a, b, e))
            if iy != height - 1:
                index.append((b, c, e))
    return np.asarray(verts, np.float64), np.asarray(index, np.int64)


def _sphere_uint8_triangles() -> np.ndarray:
    """(n, 3, 3): the sphere's triangles when its 561 vertices are indexed through a ``Uint8Array`` (each index
    stored modulo 256): every triangle's corners among the first 256 vertices (the upper rings), the degenerate ones
    left out."""
    c, radius = unsaid._sphere()
    verts, index = _three_sphere(radius)
    tris = (verts + c)[index % 256]
    area = np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1)
    return tris[area > 1e-9]


def _sphere_uint8_indexed(d: dict) -> dict:
    """The mirror sphere as :func:`_sphere_uint8_triangles`' mesh (a two-sided mirror)."""
    from mcrt.scene import Mirror

    return fresh._rebuilt(d, "sphere", _sphere_uint8_triangles(), {"type": "twosided", "bsdf": _bsdf(Mirror())})


# --------------------------------------------------------------------------
# The camera
# --------------------------------------------------------------------------

#: three.js's ``PerspectiveCamera``'s default (vertical) field of view, kept by a projection matrix never updated.
_FOV_THREE_DEFAULT = 50.0
#: The canvas's default size (300 x 150), which the WebGL viewport kept.
_VIEWPORT = (300, 150)


def _viewport_sensor(w: int, h: int) -> dict:
    """Sensor entries of the window a W x H canvas shows of a view stretched over a viewport of :data:`_VIEWPORT`
    (gl.viewport never reset after the canvas was resized): the plane's s in [-1, -1 + 2 W / 300], t in [-1, -1 + 2 H
    / 150], rendered W x 2 H (square pixels of 2 / 300)."""
    vw, vh = _VIEWPORT
    width, height = 2.0 * w / vw, 2.0 * h / vh
    return {"fov": math.degrees(2.0 * math.atan(width / 2.0)),
            "principal_point_offset_x": (-1.0 + width / 2.0) / width,
            "principal_point_offset_y": (1.0 - height / 2.0) / height}


def _viewport_default(x, *, spp: int, seed: int):
    """Mitsuba's render of :func:`_viewport_sensor`'s window at W x 2 H, each pair of rows averaged (a canvas pixel
    is 2 / 300 wide and 2 / 150 high on the plane)."""
    h, w = x.shape[:2]
    img = _render(w, 2 * h, spp, seed, sensor=_viewport_sensor(w, h))
    return 0.5 * (img[0::2] + img[1::2])


def _chained_jitter(rng, n: int, *, w: int, pixels: int):
    """Sub-pixel offsets drawn as ``let jx = jy = Math.random()``: one number for both, every sample on its pixel's
    diagonal from the top-left corner."""
    u = rng.random((pixels, n))
    return u, u.copy()


# --------------------------------------------------------------------------
# The light
# --------------------------------------------------------------------------


def _look_at_origin_frame():
    """(x axis, y axis, normal): the light's square turned by three.js's ``lookAt(0, 0, 0)`` with its default up
    (0, 1, 0): its -z towards the origin, its x axis ``up x z``."""
    c = np.asarray(_scene().light.center, np.float64)
    z = c / np.linalg.norm(c)
    xa = np.cross([0.0, 1.0, 0.0], z)
    xa /= np.linalg.norm(xa)
    return xa, np.cross(z, xa), -z


def _light_looking_at_origin(d: dict) -> dict:
    """The light's square about its centre in :func:`_look_at_origin_frame`'s axes, emitting towards the origin
    (its radiance kept): tilted 45 degrees, its upper half above the ceiling."""
    lt = _scene().light
    xa, ya, nrm = _look_at_origin_frame()
    c = np.asarray(lt.center, np.float64)
    hx, hy = 0.5 * lt.size[0], 0.5 * lt.size[1]
    corners = np.array([c - hx * xa - hy * ya, c + hx * xa - hy * ya, c + hx * xa + hy * ya, c - hx * xa + hy * ya])
    return _light_rebuilt(d, corners[np.array([[0, 1, 2], [0, 2, 3]])], nrm)


def _light_rebuilt(d: dict, tris, normal) -> dict:
    """The dict with the light's mesh rebuilt from ``tris`` (n, 3, 3), emitting its radiance on the ``normal``
    side (its black surface kept)."""
    from mcrt.mitsuba_scene import _light_surface, _mesh, _rgb
    from mcrt.scene import Surface

    s = _scene()
    sf = next(x for x in s.surfaces() if x.material is None)
    emitter = {"type": "area", "radiance": _rgb(s.light.radiance)}
    return dict(d, **{sf.name: _mesh(_light_surface(Surface(sf.name, np.asarray(tris, np.float64), None), normal),
                                     _bsdf(None), emitter)})


def _unshadowed_light(mscene, rng, p, n, rho, mitsuba):
    """A first vertex's light sample as three.js's ``RectAreaLight`` lights a surface: a point uniform on the
    square, rho Le G A / pi, no shadow ray (nothing tested between)."""
    lt = _scene().light
    q = unbeknown._light_points(rng, len(p))
    return rho * (unbeknown._geometry(p, n, q) * lt.area / math.pi)[:, None] * np.asarray(lt.radiance, np.float64)


def _cosine_about(rng, n):
    """(N, 3): cosine-weighted directions about the unit normals ``n``."""
    u1, u2 = rng.random((2, len(n)))
    r, phi = np.sqrt(u1), 2.0 * math.pi * u2
    t, b = unforeseen._frame_of(n)
    return (r * np.cos(phi))[:, None] * t + (r * np.sin(phi))[:, None] * b + np.sqrt(1.0 - u1)[:, None] * n


def _normal_aliased_light(mscene, rng, p, n, rho, mitsuba):
    """A first vertex's light sample whose surface cosine is taken with the bounce's direction: the bounce was built
    in place on the hit's normal object (``const dir = hit.normal; dir.add(randomUnitVector()).normalize()``), so
    the normal the light sample reads is a cosine-weighted direction about it."""
    lt = _scene().light
    q = unbeknown._light_points(rng, len(p))
    nd = _cosine_about(rng, n)
    g = np.where(unbeknown._unblocked(mscene, p, q), unbeknown._geometry(p, nd, q), 0.0)
    return rho * (g * lt.area / math.pi)[:, None] * np.asarray(lt.radiance, np.float64)


# --------------------------------------------------------------------------
# Bounces and samples of the path
# --------------------------------------------------------------------------


def _disk_spread_directions(rng, n):
    """Cosine-weighted directions by Malley's method whose disk point has its coordinates from
    ``MathUtils.randFloatSpread(1)`` (a range of 1: [-0.5, 0.5], not [-1, 1]), kept while ``x * x + y * y < 1``
    (always: the square lies inside the disk), lifted with ``sqrt(1 - x^2 - y^2)``: every bounce within 45 degrees of
    the normal, weighted as a cosine sample (weight 1)."""
    x, y = rng.random((2, len(n))) - 0.5
    t, b = unforeseen._frame_of(n)
    z = np.sqrt(1.0 - x * x - y * y)
    return x[:, None] * t + y[:, None] * b + z[:, None] * n, np.ones(len(n))


def _spherical_y_pole(rng, n):
    """The bounce from ``new Vector3().setFromSphericalCoords(1, acos(sqrt(u1)), 2 pi u2)`` (x = sin phi sin theta,
    y = cos phi, z = sin phi cos theta: its pole +y) taken to the world as ``x t + y b + z n`` (as if z were the
    pole), negated where below the surface (``if (d.dot(n) < 0) d.negate()``): directions spread as |d . b| about
    the tangent b, weighted as a cosine sample (weight 1)."""
    u1, u2 = rng.random((2, len(n)))
    cphi = np.sqrt(u1)
    sphi = np.sqrt(1.0 - u1)
    theta = 2.0 * math.pi * u2
    t, b = unforeseen._frame_of(n)
    d = (sphi * np.sin(theta))[:, None] * t + cphi[:, None] * b + (sphi * np.cos(theta))[:, None] * n
    below = np.einsum("ij,ij->i", d, n) < 0.0
    return np.where(below[:, None], -d, d), np.ones(len(n))


def _spherical_about_normal(rng, n):
    """The bounce from spherical coordinates about the normal, polar angle acos(sqrt(u1)), azimuth 2 pi u2, the pole
    mapped to the normal (``x t + z b + y n``): cosine-weighted (weight 1)."""
    u1, u2 = rng.random((2, len(n)))
    cphi, sphi, theta = np.sqrt(u1), np.sqrt(1.0 - u1), 2.0 * math.pi * u2
    t, b = unforeseen._frame_of(n)
    return (sphi * np.sin(theta))[:, None] * t + (sphi * np.cos(theta))[:, None] * b + cphi[:, None] * n, \
        np.ones(len(n))


def _roulette_length_sample(o, d, seed, *, full, direct):
    """A sample whose path meets Russian roulette at its first bounce with survival p = ``beta.length()`` (the
    throughput a Vector3: its Euclidean length, the albedo's there), ``if (Math.random() > p) break``, the survivors
    divided by p: L2 + (L8 - L2) [u < p] / p (p over 1: never stopped, yet divided)."""
    L, near = unsaid._sampled(full, o, d, seed), unsaid._sampled(direct, o, d, seed)
    rho = unsaid._first_albedo(full, o, d)
    p = np.linalg.norm(rho, axis=1)
    diffuse = p > 0.0
    survive = diffuse & (np.random.default_rng(seed + 37).random(len(p)) < p)
    weight = np.where(survive, 1.0 / np.where(diffuse, p, 1.0), 0.0)
    return np.where(diffuse[:, None], near + (L - near) * weight[:, None], L)


def _roulette_length(x, *, spp: int, seed: int):
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(
        _roulette_length_sample, full=unsaid._loaded(_DEPTH), direct=unsaid._loaded(2)))


#: The web workers the image's rows are shared among.
_WORKERS = 4


def _strips_offset_unscaled(x, *, workers: int = _WORKERS):
    """Each worker's strip of ``H / workers`` rows (RGBA floats, as the main thread's image) placed with
    ``image.set(strip, k * rows * W)``, the offset in pixels where ``set`` takes elements (the 4 channels left out):
    strip k from row ``k rows / 4``, each overwriting the last; the rows past the last strip left 0."""
    img = np.asarray(x, np.float64)
    h, w = img.shape[:2]
    rows = h // workers
    rgba = np.concatenate([img, np.ones((h, w, 1))], axis=2).reshape(-1)
    out = np.zeros(h * w * 4)
    for k in range(workers):
        strip = rgba[k * rows * w * 4:(k + 1) * rows * w * 4]
        out[k * rows * w:k * rows * w + len(strip)] = strip
    return out.reshape(h, w, 4)[..., :3]


#: The web workers of :func:`_fractional_rows` (``navigator.hardwareConcurrency`` on the student's laptop).
_SIX = 6


def _rows_written(h: int, workers: int = _SIX) -> np.ndarray:
    """Which rows the workers write when worker k is given the rows from ``k * (H / workers)`` (not floored) and
    loops ``for (let y = start; y < end; y++)``: a fractional y's ``image[(y * W + x) * 4 + c] = v`` sets a property,
    not an element, and is silently dropped; only the workers whose start is a whole number write."""
    rows = h / workers
    keep = np.zeros(h, bool)
    for k in range(workers):
        y, end = k * rows, (k + 1) * rows
        while y < end:
            if y == int(y) and int(y) < h:
                keep[int(y)] = True
            y += 1
    return keep


def _fractional_rows(x):
    """The render with the rows :func:`_rows_written` drops left 0 (the image's zero-filled ``Float32Array``)."""
    img = np.array(x, np.float64)
    img[~_rows_written(img.shape[0])] = 0.0
    return img


#: The passes counted by ``for (let f = 0; f < 1; f += 0.1)``: 11 (0.1 ten times is 0.9999999999999999).
def _progress_passes(step: float = 0.1) -> int:
    f, k = 0.0, 0
    while f < 1.0:
        f += step
        k += 1
    return k


def _passes_over_ten(x, *, passes: int = 10):
    """The sum of :func:`_progress_passes` passes divided by the 10 meant: the mean of the 11 times 11 / 10."""
    return np.asarray(x, np.float64) * (_progress_passes() / passes)


# --------------------------------------------------------------------------
# Correct hand-ins made in other ways
# --------------------------------------------------------------------------

_M32 = np.uint64(0xFFFFFFFF)


def _imul(a, b):
    return (a.astype(np.uint64) * b.astype(np.uint64)) & _M32


def _mulberry32(state: np.ndarray) -> np.ndarray:
    """One step of mulberry32 on each uint32 state (updated in place): the number in [0, 1) it returns."""
    state[:] = (state.astype(np.uint64) + np.uint64(0x6D2B79F5)) & _M32
    a = state.astype(np.uint64)
    t = _imul(a ^ (a >> np.uint64(15)), a | np.uint64(1))
    t = ((t + _imul(t ^ (t >> np.uint64(7)), t | np.uint64(61))) & _M32) ^ t
    return ((t ^ (t >> np.uint64(14))) & _M32).astype(np.float64) / 4294967296.0


def _mulberry_offsets(rng, n: int, *, w: int, pixels: int, state):
    """Sub-pixel offsets from one mulberry32 generator a pixel (its state seeded from the pixel's index), ``n`` a
    chunk."""
    u, v = np.empty((pixels, n)), np.empty((pixels, n))
    for k in range(n):
        u[:, k] = _mulberry32(state)
        v[:, k] = _mulberry32(state)
    return u, v


def _mulberry_mean(x, *, spp: int, seed: int):
    h, w = x.shape[:2]
    state = ((np.arange(w * h, dtype=np.uint64) * np.uint64(2654435761) + np.uint64(seed)) & _M32).astype(np.uint32)
    return unforeseen._mean_through(x, spp=spp, seed=seed, jitter=partial(_mulberry_offsets, state=state))


def _running_mean_float32(x, *, spp: int, seed: int):
    """Mitsuba's samples accumulated as a WebGL float target blends frames: ``mean = mix(mean, sample, 1 / k)`` in
    float32, k from 1."""
    h, w = x.shape[:2]
    L = unbidden._all_samples(w, h, spp, seed).astype(np.float32)
    mean = np.zeros((h * w, 3), np.float32)
    for k in range(spp):
        mean = mean + (L[:, k] - mean) * np.float32(1.0 / (k + 1))
    return mean.reshape(h, w, 3).astype(np.float64)


def _json_round_trip(x):
    """The values sent through ``JSON.stringify`` (shortest round-trip decimal strings) and read back."""
    v = np.asarray(x, np.float32)
    back = json.loads(json.dumps([float(a) for a in v.reshape(-1)]))
    return np.asarray(back, np.float32).reshape(v.shape)


def _light_four_triangles(d: dict) -> dict:
    """The light's square as four triangles fanned about its centre (its radiance and facing kept)."""
    lt = _scene().light
    c = np.asarray(lt.center, np.float64)
    hx, hy = 0.5 * lt.size[0], 0.5 * lt.size[1]
    ring = [c + (sx * hx, sy * hy, 0.0) for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    return _light_rebuilt(d, np.array([[c, ring[k], ring[(k + 1) % 4]] for k in range(4)]), lt.normal)


def _data_url_png(codes: np.ndarray) -> bytes:
    """The PNG bytes of the 8-bit codes as ``canvas.toDataURL()`` hands them over and a script writes them: the
    ``data:image/png;base64,`` URL decoded."""
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(codes), "RGB").save(buf, format="PNG")
    url = "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")
    return base64.b64decode(url.split(",", 1)[1])


def _write_png_data_url(image: np.ndarray, folder: Path) -> Path:
    path = folder / "render.png"
    path.write_bytes(_data_url_png(blind._srgb8(image)))
    return path


def _worker_strips(x, *, spp: int, seed: int, workers: int = _WORKERS):
    """The image as ``workers`` strips of rows, each a Mitsuba window of the view (90 degrees across, its centre
    ``k + 1/2 - workers / 2`` strips below the view's) with its own seed, stacked."""
    h, w = x.shape[:2]
    rows = h // workers
    return np.concatenate([_render(w, rows, spp, seed + 101 * k, sensor=unseen._window(
        w, w, 0.0, k + 0.5 - workers / 2.0)) for k in range(workers)])


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_three_cineon_tone_mapping", "pp_canvas_dpr_drawimage_crop",
                        "pp_median_window_string_sorted", "pp_canvas_fade_over_white"),
    "file": ("file_png_fillstyle_hex_unpadded", "file_exr_json_to_precision_3", "file_png_via_webp_lossy",
             "file_png_clamped_array_times_256"),
    "materials": ("surface_ids_sorted_as_strings", "mirror_cube_camera_at_centre", "colours_from_array_offset_index"),
    "geometry": ("walls_euler_order_xyz", "tetra_geometry_center_bbox", "sphere_index_uint8_wrapped"),
    "camera": ("fov_projection_matrix_stale", "webgl_viewport_default_300x150", "jitter_chained_assignment"),
    "light": ("light_legacy_intensity_pi", "light_rect_area_no_shadows", "light_look_at_origin"),
    "integrator": ("bounce_disk_rand_float_spread", "normal_aliased_by_bounce", "roulette_vector3_length",
                   "bounce_spherical_y_pole"),
    "samples": ("workers_set_offset_without_channels", "workers_rows_fractional_start", "passes_float_progress_step",
                "glsl_loop_bound_constant"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_three_cineon_tone_mapping", "tone_map", True, **_posted("three_cineon", _cineon),
             truth="three.js's OptimizedCineonToneMapping (Hejl and Burgess-Dawson's filmic curve, exposure 1) run "
             "on the render before the EXR: c = max(0, x - 0.004), (c (6.2 c + 0.5) / (c (6.2 c + 1.7) + 0.06))^2.2 "
             "each channel: the shadows darker (0.01 at 0.001, 0.05 at 0.043), the mid-tones nearly kept (0.1 at "
             "0.116, 0.5 at 0.501), the highlights compressed (1 at 0.68, 2 at 0.82), the light and its reflection "
             "0.98"),
        Spec("pp_canvas_dpr_drawimage_crop", "resolution_crop", True, held_out=True, writer=_write_png_dpr,
             file="png-canvas-dpr",
             truth="the render drawn with drawImage onto a canvas sized for devicePixelRatio 1.25 (80 x 80 device "
             "pixels, image smoothing on: bilinear in the sRGB codes) and read back with getImageData(0, 0, 64, 64) "
             "for the PNG: the top-left 64 x 64 of the enlarged image, the view's right and bottom fifth cut off, "
             "the rest magnified 1.25 times and softened"),
        Spec("pp_median_window_string_sorted", "blur", writer=_write_png_median_strings, file="png-median-strings",
             truth="a 3 x 3 median against fireflies on each channel's 8-bit codes whose window is sorted with "
             "window.sort() and no comparator, JavaScript comparing the numbers as strings (0, 1, 10, 100, ..., "
             "2, 20, ...), the 5th taken, inside pixels only: a median where the 9 codes have as many digits and "
             "start alike, elsewhere the wrong neighbour (a code of 100 to 199 taken as smaller than one of 20 to "
             "99), the shadows' and the edges' pixels blotched, as PNG"),
        Spec("pp_canvas_fade_over_white", "tone_map", True, held_out=True, writer=_write_png_faded,
             file="png-faded",
             truth="the frame saved with toDataURL while the page's fade-in still ran: the render drawn with "
             "globalAlpha 0.9 over the page's white, the canvas blending its sRGB codes: round(0.9 c + 25.5): "
             "black at code 26 (linear 0.010), white kept, every dark value lifted, a grey veil"),
        # Writing the file
        Spec("file_png_fillstyle_hex_unpadded", "bad_pixels", True, writer=_write_png_fill_rect,
             file="png-fillstyle-hex",
             truth="every pixel drawn with fillRect(x, y, 1, 1) under fillStyle = '#' + r.toString(16) + "
             "g.toString(16) + b.toString(16) of codes Math.round(srgb(v) * 255), neither padded nor clamped (the "
             "Uint8ClampedArray that clamped them dropped), on a canvas cleared to black: a channel over 1 gives "
             "three hex digits (the light's 20 is 923, '39b'), seven or nine digits are no colour (the assignment "
             "ignored, the last pixel's colour drawn again) and eight a colour with alpha: the light and its "
             "reflection painted with the ceiling's colour beside them, the rest right"),
        Spec("file_exr_json_to_precision_3", "quantisation", held_out=True, **_posted("to_precision_3",
                                                                                     _to_precision),
             truth="the values sent from the page to the script that writes the EXR as JSON of v.toPrecision(3) "
             "strings (to keep the file small): every value rounded to three significant digits, a relative step "
             "of 0.1 to 1 %: 0.01234 as 0.0123, 19.87 as 19.9, smooth gradients in faint bands"),
        Spec("file_png_via_webp_lossy", "lossy_compression", writer=_write_png_webp, file="png-via-webp",
             truth="the image taken from the canvas with toDataURL('image/webp') (lossy, the browser's quality "
             "0.8) and converted to the PNG handed in: WebP's 4 x 4 block prediction and its 4:2:0 colour, small "
             "errors everywhere, colours smeared at the walls' edges"),
        Spec("file_png_clamped_array_times_256", "quantisation", held_out=True, writer=_write_png_clamped_256,
             file="png-clamped-256",
             truth="the sRGB values times 256 (the '256 levels' for 255) stored in a Uint8ClampedArray for the "
             "ImageData, which rounds half to even and clamps at 255: every code about 0.4 % high (half a code to "
             "one code), the values over 0.998 written 255"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("surface_ids_sorted_as_strings", "material", True, edit=_materials_by_string_ids,
             truth="the surfaces' numeric ids (floor 1, ceiling 2, walls AB to FA 3 to 8, tetrahedron 9, sphere 10) "
             "sorted with ids.sort() (as strings: 1, 10, 2, ..., 9) and the k-th given the k-th material of the "
             "numeric list: the sphere a Lambertian of the ceiling's 0.8, the tetrahedron a mirror, the ceiling "
             "wall AB's red, walls AB to EF each its next wall's colour, wall FA the tetrahedron's orange"),
        Spec("mirror_cube_camera_at_centre", "material", held_out=True, **_posted(
            "cube_camera", partial(unsaid._traced, spp=_S, seed=_crc("mirror_cube_camera_at_centre"),
                                   after=_cube_map_reflection)),
             truth="the mirror sphere's reflections looked up in a cube map rendered from the sphere's centre by a "
             "CubeCamera (the sphere hidden), for the camera's rays (Mitsuba's path after it): each reflected "
             "direction right but seen from the centre, 1.5 behind the hit point: the room in the sphere without "
             "its parallax, the near things (the floor under it, the tetrahedron) shifted and too small"),
        Spec("colours_from_array_offset_index", "albedo", True, edit=_from_array_offset,
             truth="each Lambertian's colour read with color.fromArray(colours, i) from the flat colour table "
             "(floor, ceiling, walls AB to FA, tetrahedron), the offset the colour's index i for i * 3: colour i the "
             "numbers i to i + 2: the floor right, the ceiling (0.6, 0.6, 0.8), wall AB (0.6, 0.8, 0.8), BC 0.8 "
             "grey, CD (0.8, 0.8, 0.75), DE (0.8, 0.75, 0.15), EF (0.75, 0.15, 0.15), FA (0.15, 0.15, 0.55), the "
             "tetrahedron (0.15, 0.55, 0.15)"),
        # Geometry
        Spec("walls_euler_order_xyz", "object_shape", True, mitsuba_edit=_walls_euler_xyz,
             truth="each wall a PlaneGeometry(length, 10) at its middle turned with rotation.x = pi / 2 and "
             "rotation.z = atan2(dy, dx) in three.js's default Euler order XYZ (the turn about z applied first, "
             "within the plane, before it is stood up): walls BC and EF right, walls AB, CD, DE and FA standing in "
             "the planes y = -3 and y = 3 across the room, each a rectangle turned 63 or 117 degrees within them, "
             "the room's corners open onto the void"),
        Spec("tetra_geometry_center_bbox", "object_moved", True, held_out=True, mitsuba_edit=_tetra_bbox_centred,
             truth="the tetrahedron centred with geometry.center() (which takes off its bounding box's centre, "
             "(8.5, -2.4, -3.45)) and put back with mesh.position at its vertices' centroid (8.5, -2.275, -4.175): "
             "moved 0.725 down and 0.125 to the left, its base sunk under the floor, its lower part gone"),
        Spec("sphere_index_uint8_wrapped", "object_shape", True, mitsuba_edit=_sphere_uint8_indexed,
             truth="the mirror sphere a SphereGeometry(1.5, 32, 16) (561 vertices) whose index buffer was made a "
             "Uint8Array: every index stored modulo 256, each triangle's corners among the upper rings' vertices: "
             "the sphere's upper part a tangle of mirror triangles across its top and through its inside, its "
             "lower part missing"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera
        Spec("fov_projection_matrix_stale", "camera_fov", True, edit=cases.fov(_FOV_THREE_DEFAULT),
             truth="the camera made with new THREE.PerspectiveCamera() and given camera.fov = 90 afterwards, "
             "updateProjectionMatrix() never called: the projection keeps three.js's default 50 degrees (the "
             "square image's horizontal too): the view narrower, its middle magnified"),
        Spec("webgl_viewport_default_300x150", "resolution_crop", True, held_out=True, **_posted(
            "viewport_300x150", partial(_viewport_default, spp=_S, seed=c("webgl_viewport_default_300x150"))),
             truth="the canvas resized to 64 x 64 after its WebGL context was made, gl.viewport left at the "
             "canvas's default 300 x 150, the rays from the full-screen quad's interpolated uv: the canvas shows "
             "the viewport's bottom-left 64 x 64, the view's left fifth and lower three fifths (s in [-1, -0.57], t "
             "in [-1, -0.15]) stretched 4.7 times across and 2.3 times up"),
        Spec("jitter_chained_assignment", "pixel_footprint", **_posted("chained_jitter", partial(
            unforeseen._mean_through, spp=_S, seed=c("jitter_chained_assignment"), jitter=_chained_jitter)),
             truth="the sub-pixel offsets drawn as let jx = jy = Math.random() (a chained assignment: one random "
             "number for both): every sample on its pixel's diagonal from the top-left to the bottom-right corner, "
             "edges along the diagonal sharp, across it too soft"),
        # Light model
        Spec("light_legacy_intensity_pi", "light_radiance", True, edit=cases.light(
            radiance=(20.0 * math.pi,) * 3),
             truth="the light's intensity multiplied by pi as three.js's legacy lighting did (useLegacyLights, the "
             "'artist-friendly' units) while the BRDF kept its 1 / pi: radiance 62.8 for 20, the light and "
             "everything it lights pi times too bright"),
        Spec("light_rect_area_no_shadows", "light_pdf", True, held_out=True, **_posted(
            "rect_area_no_shadows", partial(unheralded._first_vertex, spp=_S, seed=c("light_rect_area_no_shadows"),
                                            direct=_unshadowed_light)),
             truth="the direct light computed as three.js's RectAreaLight computes it, without a shadow test "
             "(RectAreaLight casts no shadows), at the first surface a camera ray meets (Mitsuba's path after it): "
             "no shadow of the tetrahedron or the sphere, the floor under them lit, the light seen right"),
        Spec("light_look_at_origin", "light_facing", True, mitsuba_edit=_light_looking_at_origin,
             truth="the light aimed with light.lookAt(0, 0, 0) (three.js's documentation's example for a "
             "RectAreaLight), its default up (0, 1, 0): the square turned 45 degrees about the y axis to face the "
             "origin, its upper half above the ceiling, its lower half lighting the room's near end and the "
             "camera's side, the far end darker"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples and passes."""
    c = _crc
    return (
        # Integrator
        Spec("bounce_disk_rand_float_spread", "indirect_scale", **_posted("disk_rand_float_spread", partial(
            unprompted._first_bounce, spp=_S, seed=c("bounce_disk_rand_float_spread"), draw=_disk_spread_directions)),
             truth="the cosine-weighted bounce by Malley's method, its disk point's x and y from "
             "THREE.MathUtils.randFloatSpread(1) (a range of 1: [-0.5, 0.5], not [-1, 1]) kept while x * x + y * y "
             "< 1 (always: the square lies inside the disk), lifted with sqrt(1 - x^2 - y^2), at the first surface "
             "a camera ray meets (Mitsuba's path after it): every bounce within 45 degrees of the normal, weighted "
             "as a cosine sample: the indirect light from the grazing directions missing"),
        Spec("normal_aliased_by_bounce", "normals", True, held_out=True, **_posted("normal_aliased", partial(
            unheralded._first_vertex, spp=_S, seed=c("normal_aliased_by_bounce"), direct=_normal_aliased_light)),
             truth="the bounce built in place on the hit's normal object (const dir = hit.normal; "
             "dir.add(randomUnitVector()).normalize(): JavaScript objects held by reference), the light sample "
             "after it reading the normal, at the first surface a camera ray meets (Mitsuba's path after it): its "
             "surface cosine taken with a cosine-weighted direction about the normal: the direct light on every "
             "surface about a third too dark and noisy"),
        Spec("roulette_vector3_length", "roulette", **_posted("vector3_length", partial(
            _roulette_length, spp=_S, seed=c("roulette_vector3_length"))),
             truth="Russian roulette at the first bounce with survival p = throughput.length() (a Vector3's "
             "Euclidean length for its largest channel), if (Math.random() > p) break, the survivors divided by "
             "p, at the first surface a camera ray meets (Mitsuba's path after it): where p is over 1 (the ceiling "
             "1.39, the floor 1.04, wall CD 1.04) no path stops yet each is divided: the indirect light off the "
             "ceiling 28 % dark, off the floor and wall CD 4 %"),
        Spec("bounce_spherical_y_pole", "indirect_scale", held_out=True, **_posted("spherical_y_pole", partial(
            unprompted._first_bounce, spp=_S, seed=c("bounce_spherical_y_pole"), draw=_spherical_y_pole)),
             truth="the bounce's direction from new Vector3().setFromSphericalCoords(1, acos(sqrt(u1)), 2 pi u2), "
             "whose pole is +y, taken to the world as x t + y b + z n (as if z were the pole), the directions "
             "below the surface negated, at the first surface a camera ray meets (Mitsuba's path after it): the "
             "bounces spread as |d . b| about a tangent, grazing, weighted as cosine samples: the indirect light "
             "from the sides"),
        # Samples and passes
        Spec("workers_set_offset_without_channels", "row_stride", True, **_posted(
            "strips_offset", _strips_offset_unscaled),
             truth="four web workers each rendering 16 rows, their RGBA strips placed with image.set(strip, k * rows "
             "* W), the offset in pixels where set takes elements (the 4 channels left out): strip k from row 4 k, "
             "each over the last: rows 0 to 11 the first 4 rows of strips 0 to 2, rows 12 to 27 the last strip, "
             "rows 28 to 63 never written, black"),
        Spec("workers_rows_fractional_start", "bad_pixels", True, held_out=True, **_posted(
            "rows_fractional", _fractional_rows),
             truth="six web workers (navigator.hardwareConcurrency) given H / 6 rows each, not floored, looping "
             "for (let y = start; y < end; y++): a fractional y's write image[(y * W + x) * 4 + c] sets a "
             "property of the typed array, not an element, silently: only the workers starting at rows 0 and 32 "
             "write, rows 0 to 10 and 32 to 42 right, the other rows black"),
        Spec("passes_float_progress_step", "light_radiance", True, spp=275, declared_spp=250, **_posted(
            "progress_step", _passes_over_ten),
             truth="passes of 25 spp counted by a progress fraction, for (let f = 0; f < 1; f += 0.1): 0.1 added "
             "ten times is 0.9999999999999999, so 11 passes run, the sum divided by the 10 meant (250 spp "
             "declared): the image 10 % too bright"),
        Spec("glsl_loop_bound_constant", "spp_claim", held_out=True, spp=192, declared_spp=256,
             truth="a WebGL 1 shader's sample loop, for (int s = 0; s < MAX_SAMPLES; s++) { if (s >= uSamples) "
             "break; ... } (GLSL ES 1.0 wants a constant bound), MAX_SAMPLES 48 and 64 samples a frame asked: "
             "4 frames of 48, 192 spp rendered, 256 declared: the image right, noisier"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_mulberry32_offsets", None, **_posted("mulberry32", partial(
            _mulberry_mean, spp=_S, seed=c("ok_mulberry32_offsets"))),
             truth="Mitsuba path 256 spp, its sub-pixel offsets from mulberry32 (one generator a pixel, seeded from "
             "the pixel's index, 32-bit Math.imul arithmetic), EXR"),
        Spec("ok_png_via_webp_lossless", None, held_out=True, spp=180, writer=_write_png_webp_lossless,
             file="png-webp-lossless",
             truth="Mitsuba path 180 spp, the canvas taken as lossless WebP and converted to an 8-bit sRGB PNG"),
        Spec("ok_webgl_running_mean_float32", None, spp=128, **_posted("running_mean_f32", partial(
            _running_mean_float32, spp=128, seed=c("ok_webgl_running_mean_float32"))),
             truth="Mitsuba path 128 spp, its samples averaged as a WebGL float target accumulates frames, mean = "
             "mix(mean, sample, 1 / k) in float32, EXR"),
        Spec("ok_exr_json_round_trip", None, held_out=True, spp=220, **_posted("json_round_trip", _json_round_trip),
             truth="Mitsuba path 220 spp, the values sent through JSON.stringify (shortest round-trip strings) to "
             "the script writing the EXR"),
        Spec("ok_light_four_triangles", None, spp=172, mitsuba_edit=_light_four_triangles,
             truth="Mitsuba path 172 spp with the light's square built as four triangles fanned about its centre, "
             "EXR"),
        Spec("ok_mcrt_png_data_url", None, held_out=True, spp=76, renderer="mcrt", writer=_write_png_data_url,
             file="png-data-url",
             truth="mcrt 76 spp, an 8-bit sRGB PNG decoded from the data: URL toDataURL gives"),
        Spec("ok_bounce_spherical_about_normal", None, **_posted("spherical_about_normal", partial(
            unprompted._first_bounce, spp=_S, seed=c("ok_bounce_spherical_about_normal"),
            draw=_spherical_about_normal)),
             truth="Mitsuba path 256 spp with the first bounce drawn by spherical coordinates about the normal "
             "(polar angle acos(sqrt(u1)), azimuth 2 pi u2): cosine-weighted, EXR"),
        Spec("ok_worker_strips_windows", None, held_out=True, spp=160, **_posted("worker_strips", partial(
            _worker_strips, spp=160, seed=c("ok_worker_strips_windows"))),
             truth="Mitsuba path 160 spp rendered as four workers' strips of rows, each a window of the view with "
             "its own seed, stacked, EXR"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "tone_map": "a tone map applied before saving (three.js's Cineon curve, a fade over white)",
    "resolution_crop": "the image a part of the view, enlarged (a canvas's device pixel ratio, a viewport left at "
                       "300 x 150)",
    "blur": "a filter after rendering (a median whose window is sorted as strings)",
    "bad_pixels": "pixels not computed or wrongly set (colour strings unclamped, rows a typed array dropped)",
    "quantisation": "values quantised wrongly (three significant digits, codes times 256)",
    "lossy_compression": "the image saved with lossy compression on the way (WebP)",
    "material": "an object rendered with another material (materials by ids sorted as strings, the mirror's "
                "reflections from its centre)",
    "albedo": "a surface's colour (colours read at the wrong offset)",
    "object_shape": "an object's shape (walls turned in the wrong Euler order, the sphere's indices wrapped)",
    "object_moved": "an object moved (the tetrahedron centred by its box, placed by its centroid)",
    "camera_fov": "the camera's field of view (three.js's default 50 degrees kept)",
    "pixel_footprint": "each pixel's samples not spread over its square (on its diagonal only)",
    "light_radiance": "the light's radiance, or a constant factor (pi too bright; 11 passes divided as 10)",
    "light_pdf": "the light sampled wrongly (no shadow test): the light seen right, its light on surfaces not",
    "light_facing": "the light facing the wrong way (turned towards the origin)",
    "normals": "the normal wrong where the light sample reads it (the bounce's direction written into it)",
    "indirect_scale": "the indirect light wrong (bounces not cosine-weighted), the direct light right",
    "roulette": "Russian roulette wrong (its survival a length over 1, the survivors divided by it)",
    "row_stride": "pixels written at the wrong addresses (workers' strips placed without the channels)",
    "spp_claim": "fewer samples per pixel than declared (a shader loop's constant bound)",
}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = blind.class_causes(MISTAKES, _EARLIER, NEW_CAUSES, _REWORDED)


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
