"""The convex fast path against the brute-force watertight triangles, ray by ray.

100,000 rays from random points inside the canonical room (outside the
objects), in random directions (NumPy seed 1, so the same rays every run):
both intersectors must name the same surface at the same distance, and the
convex one's normal must face the ray (the integrator relies on it and does
not flip it). Shadow segments towards random light points must agree too.
"""

from __future__ import annotations

import numpy as np
import pytest

import mcrt  # noqa: F401  (libLLVM before drjit)
from mcrt.geometry import Geometry
from mcrt.scene import Sphere, load_scene

N = 100_000


@pytest.fixture(scope="module")
def setup():
    import drjit.llvm as m

    scene = load_scene()
    rng = np.random.default_rng(1)
    lo, hi = scene.room.polygon().min(axis=0), scene.room.polygon().max(axis=0)
    o = rng.uniform([lo[0], lo[1], scene.room.floor_z], [hi[0], hi[1], scene.room.ceiling_z], (4 * N, 3))
    planes = scene.room.planes()
    keep = np.all(o @ planes[:, :3].T <= planes[:, 3] - 0.01, axis=1)
    for obj in scene.objects:
        if isinstance(obj, Sphere):
            keep &= np.linalg.norm(o - np.asarray(obj.center), axis=1) > obj.radius + 0.01
        else:  # the tetrahedron's bounding box, widened
            v = np.asarray(obj.vertices)
            keep &= ~np.all((o > v.min(axis=0) - 0.01) & (o < v.max(axis=0) + 0.01), axis=1)
    o = o[keep][:N].astype(np.float32)
    d = rng.normal(size=(len(o), 3))
    d = (d / np.linalg.norm(d, axis=1, keepdims=True)).astype(np.float32)
    return scene, m, o, d


def _arr(m, a):
    return m.Array3f(*(m.Float(np.ascontiguousarray(a[:, i])) for i in range(3)))


def _np(v):
    return np.stack([np.asarray(c.numpy()) for c in v], axis=1)


def test_closest_hits_agree(setup):
    scene, m, o, d = setup
    convex, triangles = Geometry(scene, m, "convex"), Geometry(scene, m, "triangles")
    ta, sa, na = convex.intersect(_arr(m, o), _arr(m, d))
    tb, sb, nb = triangles.intersect(_arr(m, o), _arr(m, d))
    ta, tb, sa, sb, na, nb = ta.numpy(), tb.numpy(), sa.numpy(), sb.numpy(), _np(na), _np(nb)
    assert np.all(np.isfinite(ta)) and np.all(ta > 0)
    assert np.mean(sa == sb) == 1.0, f"{np.sum(sa != sb)} rays hit different surfaces"
    assert np.allclose(ta, tb, rtol=1e-4, atol=1e-5)
    assert np.all(np.sum(na * d, axis=1) < 0), "a convex normal faces away from the ray"
    nb = np.where((np.sum(nb * d, axis=1) < 0)[:, None], nb, -nb)
    assert np.allclose(na, nb, atol=1e-5)


def _to_the_light(scene, m, o, seed: int):
    """Both intersectors' shadow tests of segments from ``o`` to random points of the light (NumPy ``seed``), ending
    just short of it: (convex's, triangles', the light points)."""
    rng = np.random.default_rng(seed)
    light = scene.light
    p = np.asarray(light.center) + np.stack([(rng.random(len(o)) - 0.5) * light.size[0],
                                             (rng.random(len(o)) - 0.5) * light.size[1], np.zeros(len(o))], axis=1)
    w = p - o
    dist = np.linalg.norm(w, axis=1)
    w = (w / dist[:, None]).astype(np.float32)
    tmax = m.Float((dist * 0.999).astype(np.float32))
    a, b = (Geometry(scene, m, kind).occluded(_arr(m, o), _arr(m, w), tmax).numpy() for kind in ("convex", "triangles"))
    return a, b, p


def test_shadow_segments_agree(setup):
    scene, m, o, _ = setup
    a, b, _ = _to_the_light(scene, m, o, 2)
    assert a.sum() > 200  # the objects do shadow some of these segments
    assert np.array_equal(a, b), f"{np.sum(a != b)} of {len(a)} shadow segments disagree"


def test_shadow_segments_near_the_tetrahedron_agree(setup):
    """Segments aimed through the tetrahedron's enclosing ball, where the shadow test's branch decides.

    The convex intersector tests the tetrahedron only in packets where some
    segment meets its enclosing ball; these segments all pass through the
    ball and end before it or inside it (some of them are blocked), and must
    agree with the triangles one by one (NumPy seed 3).
    """
    scene, m, o, _ = setup
    convex, triangles = Geometry(scene, m, "convex"), Geometry(scene, m, "triangles")
    (center, radius), = convex.convex_bounds
    rng = np.random.default_rng(3)
    target = center + radius * rng.uniform(-1, 1, (len(o), 3))
    planes = scene.room.planes()
    inside = np.all(target @ planes[:, :3].T <= planes[:, 3] - 0.01, axis=1)  # the ball reaches below the floor
    o, target = o[inside], target[inside]
    w = target - o
    dist = np.linalg.norm(w, axis=1)
    w = (w / dist[:, None]).astype(np.float32)
    tmax = m.Float((dist * rng.uniform(0.3, 1.0, len(o))).astype(np.float32))  # ending inside the room
    a = convex.occluded(_arr(m, o), _arr(m, w), tmax).numpy()
    b = triangles.occluded(_arr(m, o), _arr(m, w), tmax).numpy()
    assert a.mean() > 0.05
    assert np.array_equal(a, b), f"{np.sum(a != b)} of {len(a)} shadow segments disagree"


def test_enclosing_ball():
    """The smallest ball around a few points: it holds them all and no ball found by search is smaller (seed 4)."""
    from scipy.optimize import minimize

    from mcrt.geometry import enclosing_ball

    rng = np.random.default_rng(4)
    for k in (1, 2, 3, 4, 4, 4, 5):
        pts = rng.normal(size=(k, 3))
        center, radius = enclosing_ball(pts)
        assert np.all(np.linalg.norm(pts - center, axis=1) <= radius)
        spread = lambda c: np.max(np.linalg.norm(pts - c, axis=1))  # noqa: E731
        found = minimize(spread, pts.mean(axis=0), method="Nelder-Mead", options=dict(xatol=1e-9, fatol=1e-12, maxiter=20000))
        assert radius <= found.fun * (1 + 2.0**-9)


def test_shadow_segments_to_a_light_through_a_wall_agree(setup):
    """The light's centre read (y, x), (0, 5) for (5, 0), puts part of it through wall FA: the room blocks segments
    to that part, which the convex intersector (that skips the room for a light inside it) must see as the triangles
    do (NumPy seed 4)."""
    from dataclasses import replace

    scene, m, o, _ = setup
    x, y, z = scene.light.center
    scene = replace(scene, light=replace(scene.light, center=(y, x, z)))
    a, b, p = _to_the_light(scene, m, o, 4)
    beyond = ~np.array([scene.room.contains(q, -0.05) for q in p])  # clear of the wall by more than tmax spares
    assert b[beyond].all() and beyond.sum() > 1000  # the wall blocks every segment to the part beyond it
    assert np.array_equal(a, b), f"{np.sum(a != b)} of {len(a)} shadow segments disagree"
