r"""A thirty-fourth class of hand-ins: intersection code, acceleration structures and floating-point robustness as
students write them, blind.

How it was written: from what goes wrong where a tracer finds what its rays meet and where its numbers run out of
range or precision, not from the grader: bounding volume hierarchies as *Ray Tracing: The Next Week* builds
them (``bvh_node``, its ``box_compare`` sort) and traverses them (the right child's interval left at ``ray_t.max``, an
any-hit query that returns at the first leaf, a shadow query that takes a leaf's box for a hit, a build that reorders
the primitives and not their colours), the hit record (its normal and its material assigned outside the ``if t <
t_best``), the triangle test by projection (``np.argmax(n)`` for ``np.argmax(np.abs(n))``), a rasterised first hit with
a 16-bit depth buffer, the self-intersection epsilon (scaled by the scene, 0.22; along the light's normal; the shadow
ray's ``t_max`` from the light's centre; the room skipped as the object just left; the bounce about the mesh's normal
as wound), clamps against division by zero (``max(cos, 0.1)``), the tangent's pole (``tan(radians(90))`` is 1.6e16,
not inf), a sphere's material index counted before the light's triangles were appended, and the output's range and
precision (GPU render-target formats R11G11B10_FLOAT and RGB10_A2, float16's 65504 and its integers past 2048, a
half-float EXR scaled down to keep the light in range, float32's running totals, bit-trick ``exp`` and ``pow``,
random numbers that reach 1.0). Its author read the other classes' specs and cause words, the catalogue
(:mod:`mcrt.mutants`), the scene files and design notes, mcrt's scene, camera and image code,
:data:`~mcrt.grade.accuracy.run.CAUSE_OF` and :data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and
to stay clear of their mistakes; never the grader's rules (what decides a cause) nor its reports, and graded none of
it, not one case. Each cause and ``major`` flag was set from the mistake alone; every mistake is worded by a cause the
other classes already have (:data:`NEW_CAUSES` is empty), so ``SAME_MISTAKE`` needed no new entry. The mistakes differ
from those of the thirty-two other classes (:mod:`~mcrt.grade.accuracy.cases`, :mod:`~mcrt.grade.accuracy.outside`
and the modules of :data:`_EARLIER`, from :mod:`~mcrt.grade.accuracy.programs` to
:mod:`~mcrt.grade.accuracy.unexamined`) and from the catalogue's bugs (``no_offset`` among them: no mistake here is
an offset left out):

* **post-processing**: the render resolved into an R11G11B10_FLOAT target by a packing function that shifts the
  mantissas off (truncates) and read back for the EXR; read back from the swap chain's RGB10_A2 UNORM image (clamped
  to 1, 10 bits); an exposure of 0 EV applied with Schraudolph's fast ``exp`` (times 0.971);
* **writing the file**: a 16-bit PNG's codes passed through a float16 buffer, ``buf[:] = srgb * 65535``,
  ``buf.astype(np.uint16)`` (65535 overflows float16 to inf, cast to 0: the light black); a half-float EXR of the
  render times 1/256 (to keep the light in half's range), never scaled back; an 8-bit PNG whose sRGB curve takes
  ``x ** (1 / 2.4)`` by the floats' bits (``log2`` and ``exp2`` read off the exponent and mantissa);
* **materials**: the hit record's material assigned for every shape the ray meets (outside the ``if t < t_best``),
  the list objects, light, room: the tetrahedron, the sphere and the light take the material of the room face behind
  them; the BVH's build reordering the triangles while their colours stay in the scene's order; the albedos packed
  as RGB565 by truncation in a GPU material buffer; the sphere's material index the number of triangles counted
  before the light's two were appended: the light's material (it glows, for camera rays);
* **geometry**: RTNW's ``bvh_node::hit`` with the right child searched over the whole ``ray_t`` (its hit overwriting
  the left's): the primitive last in the tree's order wins (the tetrahedron seen from inside); the triangle test by
  projection dropping ``np.argmax(n)`` (signed): walls DE and EF, the ceiling, the tetrahedron's base and the light
  never met; a shadow query that returns True at the first leaf whose box its ray meets (box-shaped shadows); the
  hit record's normal assigned outside the ``if`` (the tetrahedron shaded with its far face's normal);
* **camera**: the first hits rasterised with a 16-bit depth buffer (near 0.01, far 100): the light 0.01 below the
  ceiling fights with it; camera rays traced with the shadow rays' any-hit query (the first leaf visited front to
  back); the image plane's half-width ``tan(radians(fov))`` for ``tan(radians(fov) / 2)``, at the tangent's pole;
* **light model**: the light's sample point moved 0.22 along the light's normal (off it, to keep the shadow ray from
  hitting it); the shadow ray's ``t_max`` the distance to the light's centre (the samples nearer than it blocked by
  the light itself); the cosine at the light clamped with ``max(cos, 0.1)``; the light appended to the shapes after
  the BVH was built (never met by a ray, sampled all the same);
* **integrator**: the hit point pushed 0.22 (1e-2 of the scene's extent) along the normal for every ray leaving it;
  the bounce drawn about (and started along) the mesh's normal as wound (the walls and the ceiling wound outwards):
  their bounces leave the room; the object just left skipped by the next ray, the room being one object: a room
  face's bounce finds only the tetrahedron, the sphere and the light; the shadow ray's origin offset along the
  light's normal for the surface's;
* **samples and passes**: each pixel's sample count kept in float16 beside float32 sums, 4096 spp (the count stops at
  2048: twice as bright); the sub-pixel offsets ``(rand() % 16) / 15.0``, 0 to 1 both included; the pixels' sums as
  differences of one float32 running total over the whole image (``np.cumsum``).

The correct hand-ins come in ways no class used: Mitsuba with the whole scene moved by (1000, 1000, 0) (float32 far
from the origin), with the scene in centimetres (times 100, radiance kept), with the floor and the ceiling fanned
about the hexagon's centre, with the room's triangles subdivided in four, Mitsuba's path from the first hits of the
student's own BVH (right: its closest hit), an 8-bit PNG rounded by ``np.rint`` (half to even), camera rays made in
float32 throughout, and sub-pixel offsets from random bytes at their cells' midpoints ((k + 0.5) / 256, never 0
nor 1).

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s ``edit`` and ``mitsuba_edit``: meshes rebuilt
triangle by triangle, faces dropped, albedos repacked), renders at other spp, Mitsuba's path integrator on rays a
student's camera makes (:func:`mcrt.grade.accuracy.unsaid._traced`: the tangent's pole, camera rays started where a
student's BVH, depth buffer or shape list puts their first hit), the first vertex's light redone and its bounce
redrawn (by hand at the first surface a camera ray meets, Mitsuba's path after it), Mitsuba's samples summed as the
students' programs sum them, or correct renders post-processed and written as students' programs do (the packing,
float16 and bit tricks emulated with NumPy, written with OpenEXR, Pillow and pypng). mcrt renders none of it.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over :data:`CATEGORIES`: the 2nd, 4th, ... of
each category and of the correct hand-ins) are as in :mod:`~mcrt.grade.accuracy.unexamined`, fixed before any case
was graded.
"""

from __future__ import annotations

import functools
import math
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, fresh, novel, programs, unanticipated, unasked, unattended, unattested,
                                 unbeknown, unbidden, unconsidered, unexamined, unforeseen, unguessed, unheard,
                                 unheralded, unlooked, unmet, unnoticed, unprompted, unrecorded, unremarked,
                                 unremembered, unsaid, unseen, unsought, untold, untried, unvisited, unwonted)
from mcrt.grade.accuracy.cases import Spec

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


#: The classes after the first two, in the order they were written (their causes' words are this class's too).
_EARLIER = (programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked, unsought,
            unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted,
            unremarked, unremembered, unnoticed, unrecorded, unattended, unattested, unconsidered, unanticipated,
            unexamined)

_render = unseen._render
_posted = unseen._posted
_scene = unprompted._scene

#: The class's spp and the assignment's maximum depth.
_S = 256
_DEPTH = 8


def _crc(name: str) -> int:
    return 2101000 + zlib.crc32(name.encode()) % 100000


def _scene_extent() -> float:
    """The diagonal of the room's bounding box: sqrt(16^2 + 12^2 + 10^2) = 22.36."""
    s = _scene()
    xy = np.array(list(s.room.corners.values()), np.float64)
    ext = np.r_[xy.max(axis=0) - xy.min(axis=0), s.room.ceiling_z - s.room.floor_z]
    return float(np.linalg.norm(ext))


#: The students' scene-scaled epsilon: 1e-2 of the room's bounding-box diagonal (0.2236).
_EPS_SCENE = 1e-2 * _scene_extent()


# --------------------------------------------------------------------------
# The students' primitives, their intersections and their BVH
# --------------------------------------------------------------------------


def _triangles() -> tuple[tuple[str, ...], np.ndarray]:
    """The scene's triangles in its surfaces' order (walls AB to FA, floor, ceiling, tetrahedron, light), wound as
    the scene winds them: (their surfaces' names, (T, 3, 3))."""
    names, tris = [], []
    for sf in _scene().surfaces():
        for t in np.asarray(sf.triangles, np.float64):
            names.append(sf.name)
            tris.append(t)
    return tuple(names), np.array(tris)


def _prims() -> tuple[tuple[str, ...], np.ndarray, tuple[np.ndarray, float]]:
    """The primitives of a student's tracer: the scene's triangles (:func:`_triangles`), then the sphere."""
    names, tris = _triangles()
    return names + ("sphere",), tris, unsaid._sphere()


def _prim_boxes(tris: np.ndarray, sphere=None) -> np.ndarray:
    """(P, 2, 3): each triangle's bounding box, then the sphere's (centre -+ radius) if given."""
    lo, hi = tris.min(axis=1), tris.max(axis=1)
    if sphere is not None:
        c, r = sphere
        lo, hi = np.vstack([lo, c - r]), np.vstack([hi, c + r])
    return np.stack([lo, hi], axis=1)


def _triangle_hits(o: np.ndarray, d: np.ndarray, tris: np.ndarray, tmin: float = 1e-4) -> np.ndarray:
    """(N, T): Moller-Trumbore's distance along each ray to each triangle (inf where it misses or t <= tmin)."""
    e1, e2 = tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]
    p = np.cross(d[:, None, :], e2[None])
    det = np.einsum("ntk,tk->nt", p, e1)
    ok = np.abs(det) > 1e-12
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = o[:, None, :] - tris[None, :, 0]
    u = np.einsum("ntk,ntk->nt", s, p) * inv
    q = np.cross(s, e1[None])
    v = np.einsum("nk,ntk->nt", d, q) * inv
    t = np.einsum("ntk,tk->nt", q, e2) * inv
    hit = ok & (u >= 0.0) & (v >= 0.0) & (u + v <= 1.0) & (t > tmin)
    return np.where(hit, t, np.inf)


def _sphere_hits(o: np.ndarray, d: np.ndarray, sphere, tmin: float = 1e-4) -> np.ndarray:
    """(N,): the distance along each (unit) ray to the sphere, the near root if past tmin, else the far one."""
    c, r = sphere
    oc = o - c
    b = np.einsum("ij,ij->i", oc, d)
    disc = b * b - (np.einsum("ij,ij->i", oc, oc) - r * r)
    sq = np.sqrt(np.maximum(disc, 0.0))
    t0, t1 = -b - sq, -b + sq
    t = np.where(t0 > tmin, t0, np.where(t1 > tmin, t1, np.inf))
    return np.where(disc > 0.0, t, np.inf)


def _all_hits(o: np.ndarray, d: np.ndarray, *, batch: int = 16384) -> np.ndarray:
    """(N, P): each ray's distance to each primitive of :func:`_prims` (inf where it misses)."""
    _, tris, sphere = _prims()
    out = np.empty((len(o), len(tris) + 1))
    for a in range(0, len(o), batch):
        oo, dd = o[a:a + batch], d[a:a + batch]
        out[a:a + batch, :-1] = _triangle_hits(oo, dd, tris)
        out[a:a + batch, -1] = _sphere_hits(oo, dd, sphere)
    return out


def _rtnw_bvh(boxes: np.ndarray):
    """Ray Tracing: The Next Week's ``bvh_node`` over primitives with ``boxes`` (P, 2, 3), in list order: each node
    splits along the longest axis of its span's bounding box; a span of 1 is a leaf (left = right), a span of 2 a
    node of its two (in list order), a longer one sorted by its boxes' minima on the axis (``box_compare``; ties in
    list order) and halved. Returns (the primitives in the tree's left-to-right order, each primitive's path from
    the root as (axis, 0 left / 1 right) pairs, the leaves' boxes (L, 2, 3))."""
    order: list[int] = []
    paths: dict[int, tuple] = {}
    leaves: list[np.ndarray] = []

    def build(idx: list[int], path: tuple) -> None:
        lo, hi = boxes[idx, 0].min(axis=0), boxes[idx, 1].max(axis=0)
        axis = int(np.argmax(hi - lo))
        if len(idx) <= 2:
            leaves.append(np.stack([lo, hi]))
            for k, i in enumerate(idx):
                paths[i] = path + (((axis, k),) if len(idx) == 2 else ())
            order.extend(idx)
            return
        idx = sorted(idx, key=lambda i: (boxes[i, 0, axis], i))
        mid = len(idx) // 2
        build(idx[:mid], path + ((axis, 0),))
        build(idx[mid:], path + ((axis, 1),))

    build(list(range(len(boxes))), ())
    return order, paths, np.array(leaves)


def _student_bvh():
    """The RTNW BVH over :func:`_prims` (the triangles, then the sphere)."""
    _, tris, sphere = _prims()
    return _rtnw_bvh(_prim_boxes(tris, sphere))


def _ordered_keys(d: np.ndarray, paths: dict[int, tuple]) -> np.ndarray:
    """(N, P): the rank of each primitive in a front-to-back traversal of each ray (the near child first: the left one
    unless the ray runs towards -axis), as a binary number of the children taken (0 the first visited)."""
    depth = max(len(p) for p in paths.values())
    keys = np.zeros((len(d), len(paths)), np.int64)
    for i, path in paths.items():
        for level, (axis, side) in enumerate(path):
            bit = np.where(d[:, axis] < 0.0, 1 - side, side)
            keys[:, i] += bit.astype(np.int64) << (depth - 1 - level)
    return keys


def _winner_last_in_order(hits: np.ndarray, order) -> np.ndarray:
    """(N,): the primitive a traversal keeps when each child's hit overwrites the record (its t_max never shrunk):
    the hit primitive last in the tree's left-to-right order (-1 where none is hit)."""
    rank = np.empty(hits.shape[1], np.int64)
    rank[np.asarray(order)] = np.arange(len(order))
    r = np.where(np.isfinite(hits), rank[None], -1)
    best = r.argmax(axis=1)
    return np.where(r.max(axis=1) >= 0, best, -1)


def _winner_first_visited(hits: np.ndarray, keys: np.ndarray) -> np.ndarray:
    """(N,): the primitive an any-hit traversal returns: the hit primitive of the first leaf visited front to back."""
    big = np.iinfo(np.int64).max
    k = np.where(np.isfinite(hits), keys, big)
    best = k.argmin(axis=1)
    return np.where(k.min(axis=1) < big, best, -1)


def _moved_to(o, d, hits, winner, *, back: float = 1e-3):
    """The camera rays started just before the primitive ``winner`` (N,) each meets (where it is not the nearest),
    so that Mitsuba's path goes on from there: (origins, directions, no segment used)."""
    n = np.arange(len(o))
    t_w = np.where(winner >= 0, hits[n, np.maximum(winner, 0)], np.inf)
    t_near = hits.min(axis=1)
    move = np.isfinite(t_w) & (t_w > t_near + 1e-6)
    o2 = np.where(move[:, None], o + (t_w - back)[:, None] * d, o)
    return o2, d, np.zeros(len(o), int)


def _after_rtnw_unshrunk(o, d):
    hits = _all_hits(o, d)
    order, _, _ = _student_bvh()
    return _moved_to(o, d, hits, _winner_last_in_order(hits, order))


def _after_any_hit(o, d):
    hits = _all_hits(o, d)
    _, paths, _ = _student_bvh()
    return _moved_to(o, d, hits, _winner_first_visited(hits, _ordered_keys(d, paths)))


def _after_closest(o, d):
    """The student's BVH right (closest hit): every camera ray started just before its nearest primitive."""
    hits = _all_hits(o, d)
    winner = np.where(np.isfinite(hits).any(axis=1), hits.argmin(axis=1), -1)
    n = np.arange(len(o))
    t_w = np.where(winner >= 0, hits[n, np.maximum(winner, 0)], np.inf)
    o2 = np.where(np.isfinite(t_w)[:, None], o + (t_w - 1e-3)[:, None] * d, o)
    return o2, d, np.zeros(len(o), int)


# --------------------------------------------------------------------------
# The first vertex of a camera ray, shaded as a student's tracer shades it
# --------------------------------------------------------------------------


def _light_points(rng, n: int) -> np.ndarray:
    return unbeknown._light_points(rng, n)


def _lit(p, n, q, rho, visible, *, cos_light=None) -> np.ndarray:
    """(N, 3): a light sample rho Le G A / pi towards the points ``q`` on the light (pdf 1 / A), G = max(0, n . wi)
    cos_l / d^2 (cos_l = wi's z, the light facing down, or ``cos_light(wi)``), where ``visible``."""
    lt = _scene().light
    wi = unsaid._unit(q - p)
    cl = np.maximum(wi[:, 2], 0.0) if cos_light is None else cos_light(wi)
    g = np.maximum(np.einsum("ij,ij->i", n, wi), 0.0) * cl / np.sum((q - p) ** 2, axis=1)
    g = np.where(visible, g, 0.0)
    return rho * (g * lt.area / math.pi)[:, None] * np.asarray(lt.radiance, np.float64)


def _unblocked(mscene, o, q, *, shorten: float = 1e-4) -> np.ndarray:
    """Whether nothing lies between each o and q (Mitsuba's ray test, stopping short of q)."""
    dist = np.linalg.norm(q - o, axis=1)
    return ~unheralded._occluded(mscene, o, unsaid._unit(q - o), dist * (1.0 - shorten))


def _camera_vertex(x, *, spp: int, seed: int, shade, every: bool = False):
    """Each pixel the mean of Mitsuba's path on the pinhole's rays, where a camera ray meets a Lambertian first its
    sample replaced by ``shade(ctx)`` (N_sel, 3): ctx a dict of the scenes (``full``, ``two``, ``one``, ``rest``: max
    depth 8, 2, 1, 7), the rng, the chunk seed, the rays ``o``, ``d``, the hit point ``p`` (on the surface),
    its normal ``n`` (facing the ray), albedo ``rho``, Mitsuba's own direct light there ``theirs`` (its max-depth-2
    sample less its max-depth-1 one, same seed) and its sample ``L``. Mirror and light hits, Mitsuba's."""
    h, w = x.shape[:2]
    ctx = {k: unsaid._loaded(m) for k, m in (("full", _DEPTH), ("two", 2), ("one", 1), ("rest", _DEPTH - 1))}
    ctx["rng"] = np.random.default_rng(seed + 29)
    total = np.zeros((h * w, 3))
    for cseed, n, fx, fy in unsaid._lanes(w, h, spp, seed):
        o, d = (np.array(a, np.float64) for a in unsaid._pinhole(fx, fy))
        L = unsaid._sampled(ctx["full"], o, d, cseed)
        rho = unsaid._first_albedo(ctx["full"], o, d)
        t, valid = unguessed._first_hit(ctx["full"], o, d)
        sel = valid & ((rho.max(axis=1) > 0.0) | every)
        if sel.any():
            od, dd = o[sel], d[sel]
            theirs = unsaid._sampled(ctx["two"], od, dd, cseed) - unsaid._sampled(ctx["one"], od, dd, cseed)
            nrm = unforeseen._first_normal(ctx["full"], od, dd)
            L[sel] = shade(dict(ctx, cseed=cseed, o=od, d=dd, p=od + t[sel, None] * dd, n=nrm, rho=rho[sel],
                                theirs=theirs, L=L[sel], t=t[sel]))
        total += L.reshape(h * w, n, 3).sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _direct_replaced(direct):
    """A ``shade`` that keeps Mitsuba's sample but for its first vertex's direct light, ``direct(ctx)``."""
    def shade(ctx):
        return ctx["L"] - ctx["theirs"] + direct(ctx)
    return shade


def _continued(ctx, origin, dirs) -> np.ndarray:
    """(N, 3): Mitsuba's path of the 7 segments left from ``origin`` along ``dirs``, less the emission it meets at
    once (the student's tracer counts the light by its light samples)."""
    s = ctx["cseed"] + 104729
    return unsaid._sampled(ctx["rest"], origin, dirs, s) - unsaid._sampled(ctx["one"], origin, dirs, s)


def _cosine(rng, n):
    return unprompted._cosine_directions(rng, n)[0]


_LIGHT_NORMAL = np.array([0.0, 0.0, -1.0])


def _direct_light_point_offset(ctx):
    p, n = ctx["p"] + 1e-4 * ctx["n"], ctx["n"]
    q = _light_points(ctx["rng"], len(p)) + _EPS_SCENE * _LIGHT_NORMAL
    return _lit(p, n, q, ctx["rho"], _unblocked(ctx["full"], p, q))


def _direct_shadow_along_light_normal(ctx):
    p, n = ctx["p"], ctx["n"]
    q = _light_points(ctx["rng"], len(p))
    o = p + 1e-4 * _LIGHT_NORMAL
    return _lit(p, n, q, ctx["rho"], _unblocked(ctx["full"], o, q))


def _direct_tmax_from_centre(ctx):
    p, n = ctx["p"] + 1e-4 * ctx["n"], ctx["n"]
    q = _light_points(ctx["rng"], len(p))
    c = np.asarray(_scene().light.center, np.float64)
    short = np.linalg.norm(c - p, axis=1) - 1e-4 < np.linalg.norm(q - p, axis=1)
    return _lit(p, n, q, ctx["rho"], short & _unblocked(ctx["full"], p, q))


#: The floor under the cosine at the light (against dividing by zero in the pdf's conversion).
_COS_FLOOR = 0.1


def _direct_cos_light_floored(ctx):
    p, n = ctx["p"] + 1e-4 * ctx["n"], ctx["n"]
    q = _light_points(ctx["rng"], len(p))
    return _lit(p, n, q, ctx["rho"], _unblocked(ctx["full"], p, q),
                cos_light=lambda wi: np.maximum(wi[:, 2], _COS_FLOOR))


def _segments_meet_boxes(o, q, boxes, *, shorten: float = 1e-4) -> np.ndarray:
    """(N,): whether each segment from o towards q (t in [0, (1 - shorten) |q - o|]) meets any of the boxes (B, 2, 3)
    (the slab test, inclusive)."""
    d = q - o
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        t0 = (boxes[None, :, 0] - o[:, None]) * inv[:, None]
        t1 = (boxes[None, :, 1] - o[:, None]) * inv[:, None]
    t0 = np.where(np.isnan(t0), -np.inf, t0)
    t1 = np.where(np.isnan(t1), np.inf, t1)
    lo = np.maximum(np.minimum(t0, t1).max(axis=2), 0.0)
    hi = np.minimum(np.maximum(t0, t1).min(axis=2), 1.0 - shorten)
    return (lo <= hi).any(axis=1)


def _direct_leaf_boxes(ctx):
    p, n = ctx["p"] + 1e-4 * ctx["n"], ctx["n"]
    q = _light_points(ctx["rng"], len(p))
    _, _, leaves = _student_bvh()
    return _lit(p, n, q, ctx["rho"], _unblocked(ctx["full"], p, q) & ~_segments_meet_boxes(p, q, leaves))


def _tetra_face_normals() -> np.ndarray:
    t = next(o for o in _scene().objects if o.name == "tetrahedron").triangles()
    return unsaid._unit(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]))


def _direct_normal_of_last_face(ctx):
    """Where a camera ray meets the tetrahedron first, the normal of the last of its faces (in the list) that the ray
    meets, turned towards the ray."""
    o, d, p = ctx["o"], ctx["d"], ctx["p"]
    tris = np.asarray(next(o_ for o_ in _scene().objects if o_.name == "tetrahedron").triangles(), np.float64)
    th = _triangle_hits(o, d, tris)
    on = np.isfinite(th).any(axis=1) & (np.abs(th.min(axis=1) - ctx["t"]) < 1e-3)
    last = np.where(np.isfinite(th), np.arange(4)[None], -1).max(axis=1)
    nf = _tetra_face_normals()[np.maximum(last, 0)]
    nf = np.where((np.einsum("ij,ij->i", nf, d) > 0.0)[:, None], -nf, nf)
    n = np.where(on[:, None], nf, ctx["n"])
    q = _light_points(ctx["rng"], len(p))
    po = p + 1e-4 * n
    mine = _lit(po, n, q, ctx["rho"], _unblocked(ctx["full"], po, q))
    return np.where(on[:, None], mine, ctx["theirs"])


def _reflect(d, n):
    return unsaid._unit(d - 2.0 * np.einsum("ij,ij->i", d, n)[:, None] * n)


def _is_sphere(ctx) -> np.ndarray:
    c, r = unsaid._sphere()
    return np.abs(np.linalg.norm(ctx["p"] - c, axis=1) - r) < 1e-3


def _spawned(ctx, *, lift: float = 0.0, tmin: float = 1e-4):
    """The first vertex shaded by hand with its hit point lifted ``lift`` along the normal (the light sample, its
    shadow ray and the bounce all from there) and every ray leaving it started ``tmin`` along itself: a Lambertian's
    light sample and cosine-weighted bounce, the mirror's reflection (the light's own hits, Mitsuba's)."""
    p, n, d = ctx["p"] + lift * ctx["n"], ctx["n"], ctx["d"]
    rho = ctx["rho"]
    out = ctx["L"].copy()
    diffuse = rho.max(axis=1) > 0.0
    mirror = ~diffuse & _is_sphere(ctx)
    if diffuse.any():
        pd, nd, rd = p[diffuse], n[diffuse], rho[diffuse]
        q = _light_points(ctx["rng"], len(pd))
        wi = unsaid._unit(q - pd)
        far = np.linalg.norm(q - pd, axis=1) > tmin
        vis = far & _unblocked(ctx["full"], pd + tmin * wi, q)
        bounce = _cosine(ctx["rng"], nd)
        out[diffuse] = _lit(pd, nd, q, rd, vis) + rd * _continued(ctx, pd + tmin * bounce, bounce)
    if mirror.any():
        r = _reflect(d[mirror], n[mirror])
        out[mirror] = unsaid._sampled(ctx["rest"], p[mirror] + tmin * r, r, ctx["cseed"] + 7919)
    return out


def _lifted(x, *, spp: int, seed: int):
    return _camera_vertex(x, spp=spp, seed=seed, every=True, shade=partial(_spawned, lift=_EPS_SCENE))


def _wound_outwards(n, p) -> np.ndarray:
    """Whether the scene's room face at p with normal n (facing the ray) was wound outwards by a student's mesh: the
    walls ((b - a) x up) and the ceiling (the floor's fan copied)."""
    return (np.abs(n[:, 2]) < 1e-3) | ((n[:, 2] < -0.999) & (p[:, 2] > 4.995))


def _bounce_outwards(ctx):
    """Walls and ceiling: the direct light only (the bounce leaves the room); the rest, Mitsuba's."""
    out = np.where(_wound_outwards(ctx["n"], ctx["p"])[:, None], ctx["theirs"], ctx["L"])
    return out


def _room_names() -> tuple[str, ...]:
    return unbeknown._room_names()


def _objects_only(d: dict) -> dict:
    return {k: v for k, v in d.items() if k not in _room_names()}


def _skip_room(ctx):
    """Where a camera ray meets a room face first: its light sample Mitsuba's, its bounce finding only what is not
    the room (the room one object, the one just left), Mitsuba's path from what it meets; else Mitsuba's."""
    tetra = next(o for o in _scene().objects if o.name == "tetrahedron").material.albedo
    room = np.abs(ctx["rho"] - np.asarray(tetra)).max(axis=1) > 1e-6
    out = ctx["L"].copy()
    if room.any():
        p, n = ctx["p"][room] + 1e-4 * ctx["n"][room], ctx["n"][room]
        b = _cosine(ctx["rng"], n)
        objs = _objects_scene()
        si = objs.ray_intersect(unsaid._rays(p, b))
        t = np.array(si.t, np.float64)
        rho_hit = unsaid._first_albedo(objs, p, b)
        lit_hit = np.array(si.is_valid(), bool) & ((rho_hit.max(axis=1) > 0.0) | _hits_sphere(p, b, t))
        cont = np.zeros((len(p), 3))
        if lit_hit.any():
            o2 = p[lit_hit] + (t[lit_hit] - 1e-3)[:, None] * b[lit_hit]
            cont[lit_hit] = unsaid._sampled(ctx["rest"], o2, b[lit_hit], ctx["cseed"] + 104729)
        out[room] = ctx["theirs"][room] + ctx["rho"][room] * cont
    return out


def _hits_sphere(o, d, t) -> np.ndarray:
    c, r = unsaid._sphere()
    return np.abs(np.linalg.norm(o + t[:, None] * d - c, axis=1) - r) < 1e-3


def _skip_room_render(x, *, spp: int, seed: int):
    return _camera_vertex(x, spp=spp, seed=seed, shade=_skip_room)


@functools.lru_cache(maxsize=None)
def _objects_scene():
    """The scene without its room (the tetrahedron, the sphere and the light), loaded in Mitsuba."""
    return unsaid._loaded(_DEPTH - 1, _objects_only)


@functools.lru_cache(maxsize=None)
def _room_scene():
    """The room alone (walls, floor, ceiling), loaded in Mitsuba."""
    return unsaid._loaded(1, _room_only)


def _room_only(d: dict) -> dict:
    return {k: v for k, v in d.items() if k not in ("tetrahedron", "sphere", "light")}


def _material_of_last(ctx):
    """Where a camera ray meets the tetrahedron, the sphere or the light first: shaded as a Lambertian of the
    albedo of the room face behind it (the last shape in the list it meets), no emission; elsewhere Mitsuba's."""
    roomonly = _room_scene()
    behind = unsaid._first_albedo(roomonly, ctx["o"], ctx["d"])
    rho = ctx["rho"]
    tetra = next(o for o in _scene().objects if o.name == "tetrahedron").material.albedo
    obj = (rho.max(axis=1) <= 0.0) | (np.abs(rho - np.asarray(tetra)).max(axis=1) <= 1e-6)
    out = ctx["L"].copy()
    if obj.any():
        p, n, rb = ctx["p"][obj] + 1e-4 * ctx["n"][obj], ctx["n"][obj], behind[obj]
        q = _light_points(ctx["rng"], len(p))
        b = _cosine(ctx["rng"], n)
        out[obj] = _lit(p, n, q, rb, _unblocked(ctx["full"], p, q)) + rb * _continued(ctx, p, b)
    return out


def _material_last_render(x, *, spp: int, seed: int):
    return _camera_vertex(x, spp=spp, seed=seed, every=True, shade=_material_of_last)


def _sphere_emits(ctx):
    out = ctx["L"].copy()
    sph = (ctx["rho"].max(axis=1) <= 0.0) & _is_sphere(ctx)
    out[sph] = np.asarray(_scene().light.radiance, np.float64)
    return out


def _sphere_emits_render(x, *, spp: int, seed: int):
    return _camera_vertex(x, spp=spp, seed=seed, every=True, shade=_sphere_emits)


def _first_vertex_render(x, *, spp: int, seed: int, direct):
    return _camera_vertex(x, spp=spp, seed=seed, shade=_direct_replaced(direct))


# --------------------------------------------------------------------------
# Cameras
# --------------------------------------------------------------------------

#: The depth buffer of the rasterised first hits: 16-bit, near 0.01, far 100.
_NEAR, _FAR, _DEPTH_BITS = 0.01, 100.0, 16


def _depth_code(z) -> np.ndarray:
    """The D16 code of view depth z: round((2^16 - 1) f / (f - n) (1 - n / z))."""
    return np.round((2 ** _DEPTH_BITS - 1) * _FAR / (_FAR - _NEAR) * (1.0 - _NEAR / np.asarray(z, np.float64)))


def _after_depth_buffer(o, d):
    """The camera rays whose first hit is the light, where its depth code is not below the ceiling's behind it (the
    ceiling drawn first, GL_LESS): started just past the light's plane, so that they meet the ceiling."""
    lt = _scene().light
    f = unsaid._frame()[3]
    with np.errstate(divide="ignore", invalid="ignore"):
        t_l = (lt.center[2] - o[:, 2]) / d[:, 2]
        t_c = (_scene().room.ceiling_z - o[:, 2]) / d[:, 2]
    pl = o + np.where(np.isfinite(t_l), t_l, 0.0)[:, None] * d
    inside = ((d[:, 2] > 0.0) & (np.abs(pl[:, 0] - lt.center[0]) <= lt.size[0] / 2)
              & (np.abs(pl[:, 1] - lt.center[1]) <= lt.size[1] / 2))
    fd = d @ f
    hidden = inside & (_depth_code(t_l * fd) >= _depth_code(t_c * fd))
    o2 = np.where(hidden[:, None], o + (t_l + 1e-4)[:, None] * d, o)
    return o2, d, np.zeros(len(o), int)


def _pinhole_tan(fx, fy, *, half_tan: float):
    eye, r, u, f, _ = unsaid._frame()
    s, t = half_tan * (2.0 * fx - 1.0), half_tan * (1.0 - 2.0 * fy)
    return np.broadcast_to(eye, (len(fx), 3)), unsaid._unit(f + s[:, None] * r + t[:, None] * u)


#: tan(radians(90)): the tangent's pole, 1.633e16 in floating point.
_TAN_90 = math.tan(math.radians(90.0))


# --------------------------------------------------------------------------
# Scene and dict edits
# --------------------------------------------------------------------------


def _triangle_normals(tris: np.ndarray) -> np.ndarray:
    return unsaid._unit(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]))


def _projection_degenerate(tris: np.ndarray) -> np.ndarray:
    """(T,): whether the triangle's projection along the axis ``np.argmax(n)`` (the signed largest component of its
    normal as wound, for ``np.argmax(np.abs(n))``) has no area: that component zero."""
    n = _triangle_normals(tris)
    return np.abs(n[np.arange(len(n)), n.argmax(axis=1)]) < 1e-9


def _projection_edit(d: dict) -> dict:
    """Every triangle whose projection is degenerate dropped from the meshes (the light's hidden from camera rays by
    the spec instead, as it must still be sampled)."""
    from mcrt.mitsuba_scene import _bsdf_dict

    s = _scene()
    out = dict(d)
    for sf in s.surfaces():
        if sf.name == "light":
            continue
        tris = np.asarray(sf.triangles, np.float64)
        keep = ~_projection_degenerate(tris)
        if not keep.any():
            out.pop(sf.name)
        elif not keep.all():
            out = fresh._rebuilt(out, sf.name, tris[keep], _bsdf_dict(sf.material))
    return out


def _triangle_colours() -> np.ndarray:
    """(T, 3): each triangle's colour in the scene's order (the light's black)."""
    out = []
    for sf in _scene().surfaces():
        a = (0.0, 0.0, 0.0) if sf.material is None else sf.material.albedo
        out += [a] * len(sf.triangles)
    return np.asarray(out, np.float64)


def _colours_after_build() -> np.ndarray:
    """(T, 3): the colour each triangle gets when the BVH's build reorders the triangles (RTNW's sort, over the
    triangles alone) and the colour array is left in the scene's order: triangle order[k] gets colour k."""
    _, tris = _triangles()
    order, _, _ = _rtnw_bvh(_prim_boxes(tris))
    cols = _triangle_colours()
    out = np.empty_like(cols)
    out[np.asarray(order)] = cols
    return out


def _colours_reordered(d: dict) -> dict:
    """Every triangle its own mesh with the colour :func:`_colours_after_build` gives it (the light still emitting)."""
    from mcrt.mitsuba_scene import _bsdf_dict, _light_surface, _mesh, _rgb
    from mcrt.scene import Lambertian, Surface

    s = _scene()
    cols = _colours_after_build()
    out = {k: v for k, v in d.items() if k not in {sf.name for sf in s.surfaces()}}
    k = 0
    for sf in s.surfaces():
        tris = np.asarray(sf.triangles, np.float64)
        if sf.material is None:
            tris = np.asarray(_light_surface(Surface(sf.name, tris, None), s.light.normal).triangles)
        for j, t in enumerate(tris):
            bsdf = _bsdf_dict(Lambertian(tuple(float(c) for c in cols[k])))
            em = {"type": "area", "radiance": _rgb(s.light.radiance)} if sf.material is None else None
            out[f"{sf.name}_{j}"] = _mesh(Surface(f"{sf.name}_{j}", t[None], None), bsdf, em)
            k += 1
    return out


def _rgb565_truncated(albedo) -> tuple[float, ...]:
    """An albedo packed as RGB565 by truncation, (int)(r * 31), (int)(g * 63), (int)(b * 31), and unpacked."""
    r, g, b = (float(a) for a in albedo)
    return (math.floor(r * 31) / 31, math.floor(g * 63) / 63, math.floor(b * 31) / 31)


def _albedos_rgb565(s):
    walls = tuple(replace(w, albedo=_rgb565_truncated(w.albedo)) for w in s.room.walls)
    room = replace(s.room, walls=walls, floor_albedo=_rgb565_truncated(s.room.floor_albedo),
                   ceiling_albedo=_rgb565_truncated(s.room.ceiling_albedo))
    objects = tuple(replace(o, material=replace(o.material, albedo=_rgb565_truncated(o.material.albedo)))
                    if o.name == "tetrahedron" else o for o in s.objects)
    return replace(s, room=room, objects=objects)


def _after_light_unlisted(o, d):
    """The light left out of the BVH (appended after the build): camera rays, and the camera rays the sphere reflects
    (reflected here, one segment used), that meet the light first started just past its plane (meeting the ceiling
    behind it)."""
    o, d, used = unsaid._reflected(o, d)
    lt = _scene().light
    with np.errstate(divide="ignore", invalid="ignore"):
        t_l = (lt.center[2] - o[:, 2]) / d[:, 2]
    pl = o + np.where(np.isfinite(t_l), t_l, 0.0)[:, None] * d
    inside = ((d[:, 2] > 0.0) & (t_l > 0.0) & (np.abs(pl[:, 0] - lt.center[0]) <= lt.size[0] / 2)
              & (np.abs(pl[:, 1] - lt.center[1]) <= lt.size[1] / 2))
    return np.where(inside[:, None], o + (t_l + 1e-4)[:, None] * d, o), d, used


# --------------------------------------------------------------------------
# Samples
# --------------------------------------------------------------------------


def _pixel_samples(w: int, h: int, spp: int, seed: int, jitter=None) -> np.ndarray:
    """(W H, spp, 3): Mitsuba path's samples of each pixel (independent offsets unless ``jitter``), in order."""
    jitter = jitter or partial(unsought._independent, pixels=w * h)
    return np.concatenate([L for L, _, _ in unsought._film_samples(w, h, spp, seed, jitter)], axis=1)


def _prefix_sums_float32(samples: np.ndarray) -> np.ndarray:
    """(P, 3): each pixel's sum as the difference of a float32 running total over the whole image (pixel after pixel,
    sample after sample: np.cumsum(..., dtype=np.float32)) at the pixel's last sample and at the one before it."""
    p, n, _ = samples.shape
    c = np.cumsum(samples.reshape(p * n, 3).astype(np.float32), axis=0, dtype=np.float32)
    ends = c[n - 1::n]
    starts = np.vstack([np.zeros((1, 3), np.float32), ends[:-1]])
    return (ends - starts).astype(np.float64)


def _prefix_summed(x, *, spp: int, seed: int):
    h, w = x.shape[:2]
    return (_prefix_sums_float32(_pixel_samples(w, h, spp, seed)) / spp).reshape(h, w, 3)


def _offsets_mod_16(rng, n: int, *, w: int, pixels: int):
    """Sub-pixel offsets (rand() % 16) / 15.0: 16 values from 0 to 1, both ends included."""
    return rng.integers(0, 16, (2, pixels, n)) / 15.0


def _half_count(n: int) -> float:
    """A sample count kept in float16 and incremented n times: it stops at 2048 (2048 + 1 rounds to 2048)."""
    c = np.float16(0.0)
    for _ in range(n):
        c = np.float16(c + np.float16(1.0))
    return float(c)


#: The spp of the render whose count was kept in float16.
_SPP_HALF_COUNT = 4096


def _count_stalled(x, *, seed: int):
    """The sums of 4096 samples a pixel over the float16 count (2048)."""
    h, w = x.shape[:2]
    return _render(w, h, _SPP_HALF_COUNT, seed) * _SPP_HALF_COUNT / _half_count(_SPP_HALF_COUNT)


def _offsets_8bit(rng, n: int, *, w: int, pixels: int):
    """Sub-pixel offsets from random bytes at their cells' midpoints, (k + 0.5) / 256: never 0 nor 1."""
    return (rng.integers(0, 256, (2, pixels, n)) + 0.5) / 256.0


# --------------------------------------------------------------------------
# Post-processing and writers
# --------------------------------------------------------------------------


def _packed_float_truncated(v, mantissa_bits: int) -> np.ndarray:
    """Unsigned packed floats (5-bit exponent, bias 15) with ``mantissa_bits`` stored, the rest of float32's
    mantissa shifted off (truncated): v = m 2^e (m in [0.5, 1)) kept as floor(m 2^(bits + 1)) / 2^(bits + 1) 2^e;
    under 2^-14, the denormals' fixed step 2^-14 / 2^bits; negatives 0, over the format's maximum, its maximum."""
    v = np.maximum(np.asarray(v, np.float64), 0.0)
    m, e = np.frexp(v)
    e = np.maximum(e, -13)
    step = np.ldexp(1.0, e - mantissa_bits - 1)
    out = np.floor(v / step) * step
    top = (2.0 - 2.0 ** -mantissa_bits) * 2.0 ** 15
    return np.minimum(out, top)


def _r11g11b10(x) -> np.ndarray:
    """R11G11B10_FLOAT with truncation: 6 mantissa bits for red and green, 5 for blue."""
    x = np.asarray(x, np.float64)
    return np.stack([_packed_float_truncated(x[..., 0], 6), _packed_float_truncated(x[..., 1], 6),
                     _packed_float_truncated(x[..., 2], 5)], axis=-1)


def _schraudolph_exp(x) -> np.ndarray:
    """Schraudolph's fast exp: the double whose high 32 bits are 1512775 x + 1072693248 - 60801 (its low bits 0)."""
    hi = np.floor(1512775.0 * np.asarray(x, np.float64) + (1072693248 - 60801)).astype(np.int64)
    return (hi << 32).view(np.float64)


#: The exposure, in stops, applied by the fast exp: 0.
_EV = 0.0


def _exposed_fast(x) -> np.ndarray:
    """``img *= fast_exp(ev * ln 2)`` at ev = 0: every value times 0.97101."""
    return np.asarray(x, np.float64) * float(_schraudolph_exp(np.array(_EV * math.log(2.0))))


def _rgb10a2(x) -> np.ndarray:
    """RGB10_A2 UNORM: clamped to [0, 1], rounded to tenths of 1023."""
    return np.round(np.clip(np.asarray(x, np.float64), 0.0, 1.0) * 1023.0) / 1023.0


def _float16_codes16(image: np.ndarray) -> np.ndarray:
    """The 16-bit codes as a program writes them through the float16 buffer its display pass uses: ``buf[:] = srgb *
    65535`` (buf float16), then ``buf.astype(np.uint16)``: float16 keeps 11 significant bits and its largest value is
    65504, so a code past 65519 (an sRGB value of 1, or within 2.3e-4 of it) becomes inf, which the cast makes 0."""
    srgb = fresh._srgb(image)
    with np.errstate(over="ignore"):
        buf = (srgb * 65535.0).astype(np.float16).astype(np.float64)
    return np.where(np.isfinite(buf), np.floor(buf), 0.0).astype(np.uint16)


def _write_png16_float16(image: np.ndarray, folder: Path) -> Path:
    import png

    h, w = image.shape[:2]
    path = folder / "render.png"
    with open(path, "wb") as f:
        png.Writer(w, h, greyscale=False, bitdepth=16).write(f, _float16_codes16(image).reshape(h, w * 3).tolist())
    return path


#: The scale put on the render to keep it in half-float's range, never undone.
_HALF_SCALE = 1.0 / 256.0


def _write_exr_half_prescaled(image: np.ndarray, folder: Path) -> Path:
    import OpenEXR

    path = folder / "render.exr"
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage},
                 {c: np.ascontiguousarray(image[..., i] * _HALF_SCALE, np.float16)
                  for i, c in enumerate("RGB")}).write(str(path))
    return path


def _fast_log2(x) -> np.ndarray:
    """log2 by the float's bits: i / 2^23 - 127 (the exponent plus the mantissa taken linearly)."""
    i = np.asarray(x, np.float32).view(np.int32).astype(np.float64)
    return i / 2.0 ** 23 - 127.0


def _fast_exp2(y) -> np.ndarray:
    """exp2 by the float's bits: the float whose bits are (y + 127) 2^23."""
    i = np.round((np.asarray(y, np.float64) + 127.0) * 2.0 ** 23).astype(np.int64)
    return np.clip(i, 0, 2 ** 31 - 1).astype(np.int32).view(np.float32).astype(np.float64)


def _fast_pow(x, p: float) -> np.ndarray:
    return _fast_exp2(p * _fast_log2(x))


def _srgb_fast(v) -> np.ndarray:
    """sRGB's curve with x ** (1 / 2.4) by :func:`_fast_pow` (its linear part as it is)."""
    v = np.clip(np.asarray(v, np.float64), 0.0, 1.0)
    hi = 1.055 * _fast_pow(np.maximum(v, 1e-30), 1.0 / 2.4) - 0.055
    return np.clip(np.where(v <= 0.0031308, 12.92 * v, hi), 0.0, 1.0)


def _write_png_srgb_fast(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(np.floor(_srgb_fast(image) * 255.0 + 0.5).astype(np.uint8), folder)


def _write_png_rint(image: np.ndarray, folder: Path) -> Path:
    """8-bit sRGB codes by np.rint (round half to even)."""
    return novel._write_png(np.rint(fresh._srgb(image) * 255.0).astype(np.uint8), folder)


# --------------------------------------------------------------------------
# Correct renders made in other ways
# --------------------------------------------------------------------------


def _translated(s):
    """The scene and its cameras moved by (1000, 1000, 0)."""
    return s.scaled(1.0, (1000.0, 1000.0, 0.0))


def _in_centimetres(s):
    return s.scaled(100.0)


def _centre_fan(z: float, *, up: bool) -> np.ndarray:
    """(6, 3, 3): the room's hexagon at height z as a fan about its corners' mean, wound to face up or down."""
    poly = np.asarray(_scene().room.polygon(), np.float64)
    c = poly.mean(axis=0)
    tris = []
    for a, b in zip(poly, np.roll(poly, -1, axis=0)):
        t = [(*c, z), (*a, z), (*b, z)] if up else [(*c, z), (*b, z), (*a, z)]
        tris.append(t)
    return np.array(tris, np.float64)


def _floor_ceiling_centre_fans(d: dict) -> dict:
    """The floor and the ceiling each a fan of 6 triangles about the hexagon's centre (for the scene's fans)."""
    from mcrt.mitsuba_scene import _bsdf_dict

    s = _scene()
    out = fresh._rebuilt(d, "floor", _centre_fan(s.room.floor_z, up=True), _bsdf_dict(
        next(sf for sf in s.surfaces() if sf.name == "floor").material))
    return fresh._rebuilt(out, "ceiling", _centre_fan(s.room.ceiling_z, up=False), _bsdf_dict(
        next(sf for sf in s.surfaces() if sf.name == "ceiling").material))


def _pinhole_float32(fx, fy):
    """The scene's camera with every step in float32: the frame, the image-plane point, the sum and its norm."""
    eye, r, u, f, k = (np.asarray(a, np.float32) for a in unsaid._frame())
    s = k * (np.float32(2.0) * np.asarray(fx, np.float32) - np.float32(1.0))
    t = k * (np.float32(1.0) - np.float32(2.0) * np.asarray(fy, np.float32))
    d = f + s[:, None] * r + t[:, None] * u
    d = d / np.sqrt(np.sum(d * d, axis=1, dtype=np.float32))[:, None]
    return np.broadcast_to(eye, (len(fx), 3)).astype(np.float64), d.astype(np.float64)


def _subdivided(tris: np.ndarray) -> np.ndarray:
    """Each triangle split at its edges' midpoints into 4, wound as it was."""
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    ab, bc, ca = (a + b) / 2, (b + c) / 2, (c + a) / 2
    return np.concatenate([np.stack(t, axis=1) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])


def _room_subdivided(d: dict) -> dict:
    from mcrt.mitsuba_scene import _bsdf_dict

    out = dict(d)
    for sf in _scene().surfaces():
        if sf.name in _room_names():
            out = fresh._rebuilt(out, sf.name, _subdivided(np.asarray(sf.triangles, np.float64)),
                                 _bsdf_dict(sf.material))
    return out


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_r11g11b10f_pack_truncated", "pp_rgb10a2_swapchain_readback",
                        "pp_exposure_schraudolph_fast_exp"),
    "file": ("file_png16_float16_codes_overflow", "file_exr_half_prescaled_1_256", "file_png_srgb_pow_by_float_bits"),
    "materials": ("hit_material_set_outside_if", "bvh_build_reorders_colours_not", "albedos_rgb565_truncated",
                  "sphere_material_index_before_light"),
    "geometry": ("bvh_rtnw_right_child_full_interval", "triangle_projection_argmax_signed",
                 "bvh_shadow_leaf_box_as_hit", "hit_normal_set_outside_if"),
    "camera": ("primary_hits_depth16_near_001", "primary_rays_any_hit_query", "fov_tan_full_angle_pole"),
    "light": ("light_point_offset_scene_eps", "shadow_tmax_from_light_centre", "light_cosine_floor_01",
              "light_appended_after_bvh_build"),
    "integrator": ("hit_point_lifted_scene_eps", "bounce_about_wound_normal", "bounce_skips_room_object",
                   "shadow_origin_along_light_normal"),
    "samples": ("count_float16_stalls_2048", "jitter_rand_mod_16_over_15", "pixel_sums_float32_running_total"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_r11g11b10f_pack_truncated", "quantisation", **_posted("r11g11b10f", _r11g11b10),
             truth="the render resolved into an R11G11B10_FLOAT target (a real-time renderer's HDR format: unsigned, "
             "a 5-bit exponent, 6 mantissa bits for red and green, 5 for blue) by a packing function that shifts the "
             "float's extra mantissa bits off (truncates), and read back for the EXR: every value up to 1.5 % low in "
             "red and green and 3 % in blue (0.6 % and 1.1 % on average), a slight yellow shift"),
        Spec("pp_rgb10a2_swapchain_readback", "tone_map", True, held_out=True, **_posted("rgb10a2", _rgb10a2),
             truth="the EXR written from the swap chain's image read back (glReadPixels of an RGB10_A2 UNORM "
             "framebuffer, the window's format) where the render had been drawn: every value clamped to [0, 1] and "
             "rounded to 10 bits: the light 1 for 20, its reflection and every value over 1 clipped, the rest within "
             "a 2046th"),
        Spec("pp_exposure_schraudolph_fast_exp", "light_radiance", **_posted("fast_exp", _exposed_fast),
             truth="an exposure step img *= fast_exp(ev * ln 2) at ev = 0, fast_exp Schraudolph's bit trick (the "
             "double whose high word is 1512775 x + 1072693248 - 60801): exp(0) = 0.97101: the whole image 2.9 % "
             "too dark, as EXR"),
        # Writing the file
        Spec("file_png16_float16_codes_overflow", "code_overflow", writer=_write_png16_float16,
             file="png16-float16",
             truth="a 16-bit sRGB PNG whose codes pass through the float16 buffer of the program's display pass, "
             "buf[:] = srgb * 65535, then buf.astype(np.uint16): 65535 is past float16's largest value 65504, so "
             "every channel whose sRGB value is 1 becomes inf and is cast to 0, the rest kept to 11 significant bits "
             "(steps of 32 codes at the top): the light and its reflection black, a few bright pixels with a "
             "channel black"),
        Spec("file_exr_half_prescaled_1_256", "light_radiance", True, held_out=True,
             writer=_write_exr_half_prescaled, file="exr-half-prescaled",
             truth="a half-float EXR of the render times 1/256, the scale put on to keep the light's sums inside "
             "half's range (65504) and never taken off again: the whole image 256 times too dark (the shadows near "
             "half's denormals)"),
        Spec("file_png_srgb_pow_by_float_bits", "encoding", writer=_write_png_srgb_fast, file="png-fast-pow",
             truth="an 8-bit sRGB PNG whose curve takes x ** (1 / 2.4) by the floats' bits, exp2(p log2(x)) with "
             "log2(x) = bits(x) / 2^23 - 127 and exp2(y) the float of bits (y + 127) 2^23 (the exponent exact, the "
             "mantissa taken linearly): the codes off by up to 12, mostly too high (0.5 written 199 for 188, 0.25 143 "
             "for 137, 0.2 120 for 124)"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    c = _crc
    return (
        # Materials
        Spec("hit_material_set_outside_if", "material", True, **_posted("material_outside_if", partial(
            _material_last_render, spp=_S, seed=c("hit_material_set_outside_if"))),
             truth="the nearest-hit loop over the shapes (the objects, then the light, then the room's faces) "
             "writing the hit's material for every shape the ray meets, outside the if t < t_best that guards its t "
             "and normal: the material of the last shape met, the room face behind: where a camera ray meets the "
             "tetrahedron, the sphere or the light first (Mitsuba's path after it), a Lambertian of that wall's, the "
             "floor's or the ceiling's colour, no emission: the sphere a matt ball in the colours behind it, the "
             "tetrahedron blue, yellow or grey, the light ceiling-grey"),
        Spec("bvh_build_reorders_colours_not", "albedo", True, held_out=True,
             mitsuba_edit=_colours_reordered,
             truth="the BVH built (RTNW's sort along the longest axis) over the triangles by reordering their array "
             "in place, the triangles' colours left in a separate array in the scene's order: triangle order[k] "
             "given colour k: wall BC the floor's grey, CD half white half orange, DE orange, EF white, FA purple, "
             "the floor yellow and blue, the ceiling green and cyan, two faces of the tetrahedron black and one grey "
             "(wall AB, one face and the light's emission right)"),
        Spec("albedos_rgb565_truncated", "albedo", edit=_albedos_rgb565,
             truth="every albedo packed into a GPU material buffer as RGB565 by truncation, (int)(r * 31), (int)(g "
             "* 63), (int)(b * 31): the floor 0.58 for 0.6, the ceiling 0.77 for 0.8, the walls' weak red and blue "
             "0.129 for 0.15, the tetrahedron's blue 0.097 for 0.1: the room a few per cent darker, its colours' weak "
             "channels 14 % low"),
        Spec("sphere_material_index_before_light", "object_emits", True, held_out=True, **_posted(
            "sphere_light_material", partial(_sphere_emits_render, spp=_S,
                                             seed=c("sphere_material_index_before_light"))),
             truth="the sphere's material index taken as the number of triangles (analytic shapes after the "
             "meshes), counted before the light's two triangles were appended: the light's material, black and "
             "emitting 20: where a camera ray meets the sphere (Mitsuba's path elsewhere), 20: a white disk for the "
             "mirror ball"),
        # Geometry
        Spec("bvh_rtnw_right_child_full_interval", "mesh_face", True, **_posted("bvh_right_child", partial(
            unsaid._traced, spp=_S, seed=c("bvh_rtnw_right_child_full_interval"), after=_after_rtnw_unshrunk)),
             truth="RTNW's bvh_node::hit with the right child searched over the whole interval, right->hit(r, ray_t, "
             "rec) for interval(ray_t.min, hit_left ? rec.t : ray_t.max): its hit overwrites the left's, so the "
             "primitive hit last in the tree's order wins, not the nearest: for camera rays (Mitsuba's path after "
             "it) the tetrahedron's far faces (later in the tree than its near ones) seen from inside, the "
             "tetrahedron dark; the rest right"),
        Spec("triangle_projection_argmax_signed", "mesh_face", True, held_out=True, hide_emitters=True,
             mitsuba_edit=_projection_edit,
             truth="the triangle test done in 2D, the triangle and the hit point projected along the axis of the "
             "normal's largest component found with np.argmax(n) for np.argmax(np.abs(n)): for a normal as wound with "
             "no positive component the axis is one along which it is 0, the projection has no area, its "
             "barycentrics divide by zero (NaN) and the test fails: walls DE and EF, the ceiling, the tetrahedron's "
             "base and the light never met (the light still sampled): the void seen through them, black, the light "
             "black where seen"),
        Spec("bvh_shadow_leaf_box_as_hit", "light_pdf", True, **_posted("leaf_boxes", partial(
            _first_vertex_render, spp=_S, seed=c("bvh_shadow_leaf_box_as_hit"), direct=_direct_leaf_boxes)),
             truth="the shadow query's BVH traversal returning True at the first leaf whose box the shadow ray "
             "meets (if node.is_leaf: return True, its triangles never tested), at the first surface a camera ray "
             "meets (Mitsuba's path after it): the leaves' boxes cast the shadows: the sphere's and the "
             "tetrahedron's shadows square, and wherever a leaf's box holds two of the room's triangles (a wall's "
             "pair reaching into the room, the floor's and the ceiling's fans) shadow rays starting in it blocked: "
             "half the room unlit, the light seen right"),
        Spec("hit_normal_set_outside_if", "normals", True, held_out=True, **_posted("normal_outside_if", partial(
            _first_vertex_render, spp=_S, seed=c("hit_normal_set_outside_if"), direct=_direct_normal_of_last_face)),
             truth="the nearest-hit loop writing the hit's normal for every triangle the ray meets, outside the if t "
             "< t_best (the t and the material inside it): the normal of the last triangle in the list the ray "
             "meets: where a camera ray meets the tetrahedron, the normal of whichever of its two faces on the ray "
             "comes later (its far face for some), turned to the ray, in the light sample (Mitsuba's path after "
             "it): parts of the tetrahedron's faces lit as another face, the rest right"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera
        Spec("primary_hits_depth16_near_001", "light_seen", **_posted("depth16", partial(
            unsaid._traced, spp=_S, seed=c("primary_hits_depth16_near_001"), after=_after_depth_buffer)),
             truth="the first hits rasterised into a G-buffer (a hybrid renderer) with a 16-bit depth buffer, near "
             "plane 0.01 and far 100, the room drawn before the light, GL_LESS: at 5 to 7 away a depth code spans "
             "0.04 to 0.07 along the view, the light 0.01 below the ceiling mostly gets the ceiling's code and loses: "
             "the light seen as a speckle of light and ceiling, about a fifth of its brightness, its reflection and "
             "its light on surfaces right"),
        Spec("primary_rays_any_hit_query", "object_missing", True, held_out=True, **_posted("any_hit", partial(
            unsaid._traced, spp=_S, seed=c("primary_rays_any_hit_query"), after=_after_any_hit)),
             truth="camera rays traced with the shadow rays' query, bvh.intersect(ray, any_hit=True) (its default "
             "left on): the traversal (the near child first) returns the first leaf with a hit, not the nearest "
             "hit: the floor's and the ceiling's triangles found before the tetrahedron, the sphere and the light: "
             "for camera rays (Mitsuba's path after it) two thirds of the tetrahedron and a fifth of the sphere (its "
             "lower part) replaced by the floor behind them, the light black (the ceiling above it seen), the walls "
             "right"),
        Spec("fov_tan_full_angle_pole", "camera_fov", True, **_posted("tan_pole", partial(
            unsaid._traced, spp=_S, seed=c("fov_tan_full_angle_pole"),
            camera=partial(_pinhole_tan, half_tan=_TAN_90))),
             truth="the image plane's half-width tan(radians(fov)) for tan(radians(fov) / 2): at 90 degrees the "
             "tangent's pole, which floating point does not reach (pi / 2 is not exact): 1.633e16, no inf, no NaN, "
             "nothing fails: every ray perpendicular to the view, each pixel the direction of its angle about the "
             "image's centre in the plane x = -1: four wedges, wall FA left, AB right, the ceiling up, the floor down"),
        # Light model
        Spec("light_point_offset_scene_eps", "light_pdf", **_posted("light_point_offset", partial(
            _first_vertex_render, spp=_S, seed=c("light_point_offset_scene_eps"),
            direct=_direct_light_point_offset)),
             truth="the light sample's point pushed off the light along its normal by the tracer's epsilon, 1e-2 "
             "of the scene's extent (the room's diagonal 22.4: 0.224), so that the shadow ray stops short of it, and "
             "the sample's distance and cosines taken to that point, at the first surface a camera ray meets "
             "(Mitsuba's path after it): the light on surfaces as from a light 0.22 lower, a few per cent brighter, "
             "most on the walls' tops, the light seen right"),
        Spec("shadow_tmax_from_light_centre", "light_pdf", True, held_out=True, **_posted("tmax_centre", partial(
            _first_vertex_render, spp=_S, seed=c("shadow_tmax_from_light_centre"),
            direct=_direct_tmax_from_centre)),
             truth="the shadow ray's t_max the distance to the light's centre less 1e-4, computed once, the ray aimed "
             "at the sample point: a point on the light nearer than its centre lies within the ray's range and the "
             "light's own surface blocks it, at the first surface a camera ray meets (Mitsuba's path after it): about "
             "half the light samples lost (the half of the light nearer each point): the direct light a quarter to a "
             "half too dark, the light seen right"),
        Spec("light_cosine_floor_01", "light_pdf", **_posted("cos_floor", partial(
            _first_vertex_render, spp=_S, seed=c("light_cosine_floor_01"), direct=_direct_cos_light_floored)),
             truth="the cosine at the light clamped with max(cos_light, 0.1) (against dividing by zero when the "
             "area pdf is turned into a solid-angle one), at the first surface a camera ray meets (Mitsuba's path "
             "after it): where the light is seen at a grazing angle (cos under 0.1) its light raised to 0.1's: the "
             "walls' top metre or so brighter, up to twice, the rest right, the light seen right"),
        Spec("light_appended_after_bvh_build", "light_hidden", held_out=True, **_posted("light_unlisted", partial(
            unsaid._traced, spp=_S, seed=c("light_appended_after_bvh_build"), after=_after_light_unlisted)),
             truth="the light's shape appended to the scene's shapes after bvh = BVH(shapes) was built, so no ray "
             "ever meets it, while the light samples come from the light's own record: camera rays and the camera "
             "rays the sphere reflects pass through it to the ceiling behind (Mitsuba's path after them): the light "
             "not seen, directly or in the mirror, the ceiling above it dark in its place, its light on surfaces "
             "right"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples and passes."""
    c = _crc
    return (
        # Integrator
        Spec("hit_point_lifted_scene_eps", "light_pdf", **_posted("lifted", partial(
            _lifted, spp=_S, seed=c("hit_point_lifted_scene_eps"))),
             truth="the hit point pushed off the surface once found, hit.p += EPS * n, EPS 1e-2 of the scene's extent "
             "(0.224), and every ray leaving it (light sample, shadow ray, bounce, mirror reflection) and the light "
             "sample's distance and cosines taken from there, at the first surface a camera ray meets (Mitsuba's "
             "path after it): the direct light a few per cent brighter (the points nearer the light), the mirror's "
             "image shifted a little"),
        Spec("bounce_about_wound_normal", "indirect_scale", True, held_out=True, **_posted("wound_normal", partial(
            _camera_vertex, spp=_S, seed=c("bounce_about_wound_normal"), shade=_bounce_outwards)),
             truth="the room meshed by the student with the walls wound (b - a) x up and the ceiling's fan copied "
             "from the floor's, both facing out; the light sample uses the normal turned to the viewer, but the "
             "bounce is drawn about, and started along, the mesh's normal as wound: where a camera ray meets a wall "
             "or the ceiling (Mitsuba's path elsewhere), the bounce leaves the room: their indirect light lost, the "
             "ceiling (lit by bounces alone) black, the walls darker, their direct light right"),
        Spec("bounce_skips_room_object", "indirect_scale", True, **_posted("skip_room", partial(
            _skip_room_render, spp=_S, seed=c("bounce_skips_room_object"))),
             truth="self-intersection avoided by skipping the object the ray leaves (if obj is last_obj: continue), "
             "the room's walls, floor and ceiling one mesh object: where a camera ray meets a room face first, its "
             "bounce can meet only the tetrahedron, the sphere or the light, else nothing (Mitsuba's path from what "
             "it meets): the room's light from the room lost, the ceiling nearly black, the rest darker, the direct "
             "light right"),
        Spec("shadow_origin_along_light_normal", "light_pdf", True, held_out=True, **_posted(
            "shadow_light_normal", partial(_first_vertex_render, spp=_S, seed=c("shadow_origin_along_light_normal"),
                                           direct=_direct_shadow_along_light_normal)),
             truth="the shadow ray's origin offset along the light's normal for the surface's, p + 1e-4 * "
             "light.normal (one variable n for two normals), the light facing down: at the first surface a camera "
             "ray meets (Mitsuba's path after it) the origin 1e-4 below the point: below the floor and inside the "
             "tetrahedron's upward faces, their shadow rays blocked: the floor and the tetrahedron lit by bounces "
             "only, the walls right, the light seen right"),
        # Samples and passes
        Spec("count_float16_stalls_2048", "sample_count", True, spp=_S, declared_spp=_SPP_HALF_COUNT,
             **_posted("count_float16", partial(_count_stalled, seed=c("count_float16_stalls_2048"))),
             truth="a progressive render of 4096 spp whose sums were kept in an RGBA32F target and each pixel's "
             "sample count in an R16F one (to save memory): float16 counts integers exactly only to 2048, 2048 + 1 "
             "rounds back to 2048, so the count stops there: the sums of 4096 samples over 2048, the whole image "
             "twice as bright, 4096 declared"),
        Spec("jitter_rand_mod_16_over_15", "pixel_footprint", held_out=True, **_posted("mod16", partial(
            unforeseen._mean_through, spp=_S, seed=c("jitter_rand_mod_16_over_15"), jitter=_offsets_mod_16)),
             truth="the sub-pixel offsets (rand() % 16) / 15.0, divided by 15 for 16 so that 1.0 is reached: 16 "
             "values from 0 to 1 both included, each pixel's samples on a 16 x 16 lattice spanning its square and "
             "the next pixel's first column and row: edges a little soft and aliased"),
        Spec("pixel_sums_float32_running_total", "quantisation", **_posted("running_total", partial(
            _prefix_summed, spp=_S, seed=c("pixel_sums_float32_running_total"))),
             truth="each pixel's sum taken as the difference of one float32 running total over the whole image "
             "(np.cumsum(samples.reshape(-1, 3), axis=0, dtype=np.float32), pixel after pixel) at the pixel's last "
             "sample and at the one before it: the total grows to about 5e5 and its step to 0.06, so the later "
             "pixels' small samples are rounded away: the bottom rows' shadows about a tenth too dark, the rest "
             "right to a few hundredths"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_scene_moved_1000", None, spp=200, edit=_translated,
             truth="Mitsuba path 200 spp with the room, its objects, the light and the camera moved by (1000, 1000, "
             "0) (float32 far from the origin), EXR"),
        Spec("ok_scene_in_centimetres", None, held_out=True, spp=224, edit=_in_centimetres,
             truth="Mitsuba path 224 spp with the scene in centimetres (every length times 100, the radiance "
             "kept), EXR"),
        Spec("ok_floor_ceiling_centre_fans", None, spp=208, mitsuba_edit=_floor_ceiling_centre_fans,
             truth="Mitsuba path 208 spp with the floor and the ceiling each triangulated as a fan of 6 triangles "
             "about the hexagon's centre, EXR"),
        Spec("ok_room_triangles_subdivided", None, held_out=True, spp=192, mitsuba_edit=_room_subdivided,
             truth="Mitsuba path 192 spp with every triangle of the walls, floor and ceiling split in four at its "
             "edges' midpoints, EXR"),
        Spec("ok_student_bvh_closest_hits", None, **_posted("bvh_closest", partial(
            unsaid._traced, spp=_S, seed=c("ok_student_bvh_closest_hits"), after=_after_closest)),
             truth="Mitsuba path 256 spp from the first hits of the student's RTNW BVH traversed right (t_max "
             "shrunk to each hit), EXR"),
        Spec("ok_png_rint_half_even", None, held_out=True, spp=236, writer=_write_png_rint, file="png-rint",
             truth="Mitsuba path 236 spp, an 8-bit sRGB PNG whose codes are np.rint(srgb * 255) (half to even)"),
        Spec("ok_camera_rays_float32", None, **_posted("rays_float32", partial(
            unsaid._traced, spp=_S, seed=c("ok_camera_rays_float32"), camera=_pinhole_float32)),
             truth="Mitsuba path 256 spp on camera rays made in float32 throughout (frame, image-plane point, "
             "normalisation), EXR"),
        Spec("ok_jitter_bytes_midpoints", None, held_out=True, spp=240, **_posted("bytes_midpoints", partial(
            unforeseen._mean_through, spp=240, seed=c("ok_jitter_bytes_midpoints"), jitter=_offsets_8bit)),
             truth="Mitsuba path 240 spp with sub-pixel offsets from random bytes at their cells' midpoints, (k + "
             "0.5) / 256, EXR"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "quantisation": "values quantised wrongly (a packed float format's mantissas truncated, float32 running totals)",
    "tone_map": "a clamp applied before saving (an RGB10_A2 framebuffer read back)",
    "light_radiance": "the light's radiance (or a constant factor: a fast exp's error, a scale never undone)",
    "code_overflow": "codes overflowing (16-bit codes computed in float16: 65535 is inf, cast to 0)",
    "encoding": "the values' encoding (sRGB's power taken by the floats' bits)",
    "material": "an object rendered with another material (the material of the shape behind it)",
    "albedo": "a surface's colour (colours not reordered with their triangles, albedos packed as RGB565)",
    "object_emits": "an object emitting light (the sphere given the light's material)",
    "mesh_face": "faces of meshes missing (a BVH keeping the last hit, a projected triangle test failing)",
    "light_pdf": "the light sampled wrongly (its shadow rays, their origin, range or boxes, its point or cosine): the "
                 "light seen right, its light on surfaces not",
    "normals": "surface normals wrong (the normal of another face the ray meets)",
    "light_seen": "the light's own pixels (where the camera sees it) wrong: it fights with the ceiling in a depth "
                  "buffer",
    "object_missing": "objects missing (the first hit a traversal finds, not the nearest)",
    "camera_fov": "the camera's field of view (the tangent of the whole angle)",
    "light_hidden": "the light not seen (left out of the BVH)",
    "indirect_scale": "the indirect light lost on some surfaces (bounces leaving the room or skipping it), the "
                      "direct light right",
    "sample_count": "each pixel's sum divided by a count it does not hold (a float16 count stopped at 2048)",
    "pixel_footprint": "each pixel's samples not spread over its square (offsets reaching 1.0, the next pixel's)",
}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = blind.class_causes(MISTAKES, _EARLIER, NEW_CAUSES, _REWORDED)


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
