"""Hard cases: the catalogue renders finite, non-negative and in agreement; the float32 guard; shared edges.

Statistical tests compare two renders with :func:`mcrt.stats.compare_images`
(Welch per 8x8 tile and channel, each side with its own per-sample
variance, Holm at a family-wise level of 0.01). Seeds are pinned (mcrt 11,
Mitsuba 12), so every test always passes or always fails for a given code:
a pass at these seeds is not luck that could turn on the next run.

Cases that fail because of a known defect are marked
``xfail(strict=True)`` with the defect in the reason, so they turn into
failures (XPASS) the day the defect is fixed and the mark must go.
"""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np
import pytest

import mcrt  # noqa: F401  (sets DRJIT_LIBLLVM_PATH before drjit loads)
import drjit as dr
import drjit.llvm as m

from mcrt import hardcases
from mcrt.geometry import OFFSET_SCALE, Geometry
from mcrt.precision import LIMIT_RATIO, check_precision, precision_report
from mcrt.scene import Sphere, load_scene
from mcrt.stats import compare_images

ALPHA = 0.01  # family-wise error rate of each image comparison (Holm over tiles and channels)
RES, SPP = 64, 256  # the modest budget: 64x64, 256 spp per side
SEED_MCRT, SEED_MITSUBA = 11, 12


# --------------------------------------------------------------------------
# The catalogue, rendered by both renderers
# --------------------------------------------------------------------------


def _case_params():
    return [
        pytest.param(case, id=case.name, marks=[pytest.mark.xfail(strict=True, reason=case.known_issue)] if case.known_issue else [])
        for case in hardcases.CATALOGUE
    ]


def _finite_non_negative(r, who):
    bad = int(np.count_nonzero(~np.isfinite(r.mean)) + np.count_nonzero(~np.isfinite(r.variance)))
    neg = int(np.count_nonzero(r.mean < 0))
    assert bad == 0, f"{who}: {bad} NaN/Inf values"
    assert neg == 0, f"{who}: {neg} negative values"


@pytest.mark.parametrize("case", _case_params())
def test_case_finite_non_negative_and_agreeing(case):
    """Both renderers finite and non-negative, and consistent at 64x64, 256 spp each (alpha 0.01 Holm).

    Transformed cases (scaled, moved) must also match the untransformed scene's
    image: mcrt's render against Mitsuba's render of the original scene.
    Cases the precision guard must refuse are checked for the refusal.
    """
    scene = case.scene()
    if case.expect == "refused":
        with pytest.raises(ValueError, match="float32 rendering would be wrong"):
            check_precision(scene)
        return
    check_precision(scene)  # every other case lies within float32's limits
    a = hardcases.render_mcrt(case, scene, RES, SPP, SEED_MCRT)
    b = hardcases.render_mitsuba_case(case, scene, RES, SPP, SEED_MITSUBA)
    _finite_non_negative(a, "mcrt")
    _finite_non_negative(b, "Mitsuba")
    c = compare_images(a, b, alpha=ALPHA)
    assert c.passed, c.summary()
    if case.transformed:
        base = hardcases.render_mitsuba_case(case, case.reference_scene(), RES, SPP, SEED_MITSUBA + 1)
        c = compare_images(a, base, alpha=ALPHA)
        assert c.passed, "image changed by the transform: " + c.summary()


def test_catalogue_is_complete_and_loads():
    names = [c.name for c in hardcases.CATALOGUE]
    assert len(names) == len(set(names))
    for case in hardcases.CATALOGUE:
        scene = case.scene()
        assert case.camera in scene.cameras, case.name
        assert case.sentence and case.sentence.endswith("."), case.name
        if not case.transformed:
            assert scene.description == case.sentence, f"{case.name}: the file's description is the catalogue's sentence"
    files = {p.stem for p in hardcases.HARD_DIR.glob("*.toml")}
    assert files <= set(names), f"scene files missing from the catalogue: {files - set(names)}"


def test_tracer_refuses_a_far_moved_scene():
    """The tracer itself fails loudly on the canonical scene moved 1e4 from the origin."""
    from mcrt.render import render

    far = load_scene().scaled(1.0, (1e4, 1e4, 1e4))
    with pytest.raises(ValueError, match="float32 rendering would be wrong"):
        render(far, far.settings(camera="near", width=4, height=4, spp=2, max_depth=2), seed=1, progress=False)


def test_triangle_and_convex_intersectors_agree_on_a_light_in_the_ceiling():
    """The light's rectangle is cut out of a coplanar ceiling (Scene.surfaces), so nothing z-fights."""
    case = hardcases.case("light_on_ceiling")
    scene = case.scene()
    a = hardcases.render_mcrt(case, scene, RES, 64, SEED_MCRT, intersector="convex", max_depth=1)
    b = hardcases.render_mcrt(case, scene, RES, 64, SEED_MCRT + 1, intersector="triangles", max_depth=1)
    assert compare_images(a, b, alpha=ALPHA).passed


def test_report_writer_on_a_tiny_run(tmp_path):
    """One case at 8x8 pixels and a few spp, with synthetic sweep and convergence rows: index.md and strict data.json."""
    import json

    r = hardcases.run_case(hardcases.case("light_on_ceiling"), res=8, spp=8, ref_spp=16, images=tmp_path)
    assert set(r.renders) == {"mcrt", "mitsuba", "mitsuba_equal_time", "reference"}
    assert {"mcrt_vs_mitsuba", "mcrt_vs_reference", "mitsuba_vs_reference"} <= set(r.comparisons)
    sweep = [hardcases.SweepRow("canonical", "near", kind, v, who, 1e-3, True, ok, 0, 0, 1.0, 0.001)
             for kind, v, ok in (("moved", 1e2, True), ("moved", 1e4, False), ("scaled", 1e-3, True), ("scaled", 1e3, True))
             for who in ("mcrt", "mitsuba")]
    conv = [hardcases.ConvergenceRow("light_low", "mcrt", n, 4, 0.1 / n ** 0.5, 4, -0.5, 0.1) for n in (64, 256)]
    md, js = hardcases.write_report([r], tmp_path, argv=["--res 8"], settings={"res": 8, "spp": 8, "ref_spp": 16},
                                    sweep=sweep, conv=conv)
    text = md.read_text()
    assert text.startswith("# Hard cases") and "`mcrt hardcases --res 8`" in text and "| light_on_ceiling |" in text
    assert "## Float32 limits" in text and "right up to an offset of 100, wrong from 10000" in text
    assert "## Fireflies and convergence" in text and "-0.50" in text
    data = json.loads(js.read_text(), parse_constant=lambda c: pytest.fail(f"non-strict JSON constant {c}"))
    assert data["cases"][0]["name"] == "light_on_ceiling" and len(data["sweep"]) == len(sweep)
    assert (tmp_path / "light_on_ceiling.png").exists()


# --------------------------------------------------------------------------
# The float32 guard
# --------------------------------------------------------------------------


def test_guard_limit_is_the_spawn_offset():
    """N / M = 2^17 is where the spawn offset 2^-17 (|p| + S) reaches the feature M (mcrt.precision)."""
    assert LIMIT_RATIO == 1.0 / OFFSET_SCALE


def test_guard_accepts_every_project_scene_at_home_and_any_scale():
    """Every scene the project renders passes, so the tracer can call the guard on every render."""
    from mcrt.closed_form import furnace_scene, lit_floor_scene

    scenes = [load_scene(p) for p in [hardcases.CANONICAL, *sorted(hardcases.HARD_DIR.glob("*.toml"))]]
    scenes += [furnace_scene(), furnace_scene(mirror=True), lit_floor_scene()]
    for scene in scenes:
        for factor in (1.0, 1e-3, 1e3, 1e-12, 1e12):
            check_precision(scene.scaled(factor))


@pytest.mark.parametrize("offset", [1e4, 1e5, 1e7])
def test_guard_refuses_a_far_moved_scene(offset):
    far = load_scene().scaled(1.0, (offset, offset, offset))
    with pytest.raises(ValueError, match=r"lies .* units from the origin but is only 0.032 units small .* move it closer"):
        check_precision(far)


def test_guard_boundary_follows_the_smallest_feature():
    """Canonical: accepted at 3e3 (renders right), refused at 1e4 (2 % too bright); tiny sphere: 100 vs 300."""
    canonical, tiny = load_scene(), load_scene(hardcases.HARD_DIR / "sphere_tiny.toml")
    check_precision(canonical.scaled(1.0, (3e3, 3e3, 3e3)))
    check_precision(tiny.scaled(1.0, (100.0, 100.0, 100.0)))
    with pytest.raises(ValueError, match=r"objects\[1\] \(sphere\)\.radius"):
        check_precision(tiny.scaled(1.0, (300.0, 300.0, 300.0)))
    r = precision_report(tiny)
    assert r.feature == 0.001 and r.offset_limit == pytest.approx(131.072)


def test_guard_refuses_a_feature_too_small_even_at_the_origin():
    scene = load_scene()
    sphere = scene.spheres()[0]
    tiny = replace(scene, objects=(scene.objects[0], Sphere(sphere.name, sphere.center, 1e-5, sphere.material)))
    with pytest.raises(ValueError, match="enlarge the feature"):
        check_precision(tiny)


@pytest.mark.parametrize("factor", [1e-18, 1e18])
def test_guard_refuses_squares_outside_float32(factor):
    """Measured: scaled by 1e-20 mcrt returns NaN, by 1e18 a dark image; the guard refuses with a margin."""
    with pytest.raises(ValueError, match="float32"):
        check_precision(load_scene().scaled(factor))


# --------------------------------------------------------------------------
# Rays through shared edges and vertices: no leaks, one surface per hit
# --------------------------------------------------------------------------

ROOM = ("wall_", "floor", "ceiling")


def _f32(a):
    return np.asarray(a, dtype=np.float32).astype(np.float64)


def _trace(geo, o, d):
    t, sid, n = geo.intersect(m.Array3f(o.T.astype(np.float32)), m.Array3f(d.T.astype(np.float32)))
    dr.eval(t, sid, n)
    return t.numpy().astype(np.float64), sid.numpy(), np.asarray(n.numpy()).T.astype(np.float64)


def _edges_and_vertices(surfaces):
    """{(p, q): names} for every triangle edge and {p: names} for every vertex, keyed by float32 coordinates."""
    edges, verts = {}, {}
    for s in surfaces:
        for tri in s.triangles:
            pts = [tuple(_f32(p)) for p in tri]
            for p in pts:
                verts.setdefault(p, set()).add(s.name)
            for a, b in itertools.combinations(pts, 2):
                edges.setdefault(tuple(sorted((a, b))), set()).add(s.name)
    return edges, verts


def _interior_origins(scene, n, seed):
    """n points inside the room at least 0.05 from every face (fixed seed: reproducible rays)."""
    rng = np.random.default_rng(seed)
    poly = scene.room.polygon()
    lo = np.array([*poly.min(axis=0), scene.room.floor_z])
    hi = np.array([*poly.max(axis=0), scene.room.ceiling_z])
    out = []
    while len(out) < n:
        p = rng.uniform(lo, hi)
        if scene.room.contains(p, 0.05):
            out.append(p)
    return _f32(out)


def _light_crossing(scene, o, d, t_max):
    """Per ray: 1 if it crosses the light's rectangle before t_max, 0 if not, -1 if too close to its border to say."""
    light = scene.light
    (cx, cy, cz), (hx, hy) = light.center, (light.size[0] / 2, light.size[1] / 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (cz - o[:, 2]) / d[:, 2]
    x, y = o[:, 0] + t * d[:, 0], o[:, 1] + t * d[:, 1]
    margin = np.minimum(hx - np.abs(x - cx), hy - np.abs(y - cy))
    before = (t > 0) & (t < t_max * (1 + 1e-6))
    out = np.where(before & (margin > 0), 1, 0)
    return np.where(before & (np.abs(margin) < 1e-4), -1, out)


@pytest.mark.parametrize("intersector", ["convex", "triangles"])
@pytest.mark.parametrize("scene_name", ["canonical", "tetra_on_floor"])
def test_rays_through_room_edges_and_vertices_hit_one_incident_surface(scene_name, intersector):
    """Rays from inside aimed at points of every shared edge and vertex of the room's triangles.

    Targets: every vertex, and the points at 1/4, 1/3, 1/2 and 4/5 of every
    edge (wall diagonals, vertical corners, floor and ceiling fans, wall-floor
    edges), rounded to float32. Each ray must hit (no leak), at the target's
    distance, on the front side of a surface that contains the target (no hit
    on a wrong or far surface); only an object or the light in front of the
    target may take the hit earlier.
    """
    scene = load_scene() if scene_name == "canonical" else load_scene(hardcases.HARD_DIR / f"{scene_name}.toml")
    geo = Geometry(scene, m, intersector)
    names = [s.name for s in geo.surfaces]
    room = [s for s in scene.surfaces() if s.name.startswith(ROOM)]
    objects = {o.name for o in scene.objects}
    edges, verts = _edges_and_vertices(room)
    targets, incident = [], []
    for (a, b), who in edges.items():
        for f in (0.25, 1 / 3, 0.5, 0.8):
            targets.append(_f32(np.add(a, f * np.subtract(b, a))))
            incident.append(who)
    for p, who in verts.items():
        targets.append(np.array(p))
        incident.append(who)
    origins = _interior_origins(scene, 24, seed=5)
    o = np.repeat(origins, len(targets), axis=0)
    q = np.tile(np.array(targets), (len(origins), 1))
    who = incident * len(origins)
    dist = np.linalg.norm(q - o, axis=1)
    d = _f32((q - o) / dist[:, None])
    t, sid, n = _trace(geo, o, d)

    assert np.isfinite(t).all(), f"{np.count_nonzero(~np.isfinite(t))} of {len(t)} rays leaked out of the room"
    assert (np.einsum("ij,ij->i", d, n) < 0).all(), "hits reported on the back side of a surface"
    light = _light_crossing(scene, o, d, dist)
    hit = np.array([names[k] for k in sid])
    at_target = np.abs(t - dist) <= 1e-4 * dist + 1e-5
    ok_room = at_target & np.array([h in w for h, w in zip(hit, who)])
    ok_light = (light == 1) & (hit == "light") & (t <= dist * (1 + 1e-4))
    ok_object = np.isin(hit, list(objects)) & (t <= dist * (1 + 1e-4))
    ambiguous = light == -1
    bad = ~(ok_room | ok_light | ok_object | ambiguous)
    assert not bad.any(), (
        f"{np.count_nonzero(bad)} of {len(t)} rays hit the wrong surface or distance, e.g. "
        + "; ".join(f"target {q[i]} ({sorted(who[i])}) got {hit[i]} at t={t[i]:.6g}, expected {dist[i]:.6g}" for i in np.flatnonzero(bad)[:3])
    )
    assert np.count_nonzero(ok_room) > 0.8 * len(t)  # most rays do reach their target


@pytest.mark.parametrize("intersector", ["convex", "triangles"])
@pytest.mark.parametrize("scene_name", ["canonical", "tetra_on_floor"])
def test_rays_into_the_tetrahedron_through_its_edges_and_vertices(scene_name, intersector):
    """A ray through an edge or vertex that enters the tetrahedron must hit it there, and shadow rays must be blocked.

    For a target q on the boundary and an interior point c, a ray from
    q + k (q - c) towards c is in front of every face through q, so it enters
    the solid at q: a miss there is a leak (the floor or a wall would show
    through the edge).
    """
    scene = load_scene() if scene_name == "canonical" else load_scene(hardcases.HARD_DIR / f"{scene_name}.toml")
    tet = next(o for o in scene.objects if o.name == "tetrahedron")
    geo = Geometry(scene, m, intersector)
    tet_id = [s.name for s in geo.surfaces].index("tetrahedron")
    v = np.asarray(tet.vertices, dtype=np.float64)
    rng = np.random.default_rng(7)
    inner = rng.dirichlet(np.ones(4), size=8) * 0.6 + 0.1  # interior points, every weight >= 0.1
    inner = (inner / inner.sum(axis=1, keepdims=True)) @ v
    targets = [v[i] for i in range(4)]
    targets += [v[i] + f * (v[j] - v[i]) for i, j in itertools.combinations(range(4), 2) for f in (0.2, 0.5, 0.7)]
    o, q = [], []
    for p in targets:
        p = _f32(p)
        for c in inner:
            for k in (1.0, 0.3, 0.1, 0.03):
                start = p + k * (p - c)
                if scene.room.contains(start, 0.01):
                    o.append(start)
                    q.append(p)
                    break
    o, q = _f32(o), np.array(q)
    dist = np.linalg.norm(q - o, axis=1)
    d = _f32((q - o) / dist[:, None])
    assert len(o) >= 40
    t, sid, n = _trace(geo, o, d)
    assert np.isfinite(t).all()
    leaked = (sid != tet_id) | (np.abs(t - dist) > 1e-4 * dist + 1e-5)
    assert not leaked.any(), f"{np.count_nonzero(leaked)} of {len(t)} rays passed through an edge or vertex of the tetrahedron"
    assert (np.einsum("ij,ij->i", d, n) < 0).all()
    blocked = geo.occluded(m.Array3f(o.T.astype(np.float32)), m.Array3f(d.T.astype(np.float32)), m.Float((2 * dist).astype(np.float32)))
    assert blocked.numpy().all(), "a shadow ray passed through an edge or vertex of the tetrahedron"


@pytest.mark.parametrize("intersector", ["convex", "triangles"])
def test_rays_through_the_light_diagonal_hit_the_light(intersector):
    """The light's two triangles share a diagonal: rays from below through it, and through its interior, hit the light."""
    scene = load_scene()
    geo = Geometry(scene, m, intersector)
    c = scene.light.corners()
    targets = [_f32(c[0] + f * (c[2] - c[0])) for f in np.linspace(0.05, 0.95, 19)]
    targets += [_f32(c[1] + f * (c[3] - c[1])) for f in np.linspace(0.05, 0.95, 19)]
    origins = _interior_origins(scene, 16, seed=9)
    origins = origins[origins[:, 2] < 3.0]
    o = np.repeat(origins, len(targets), axis=0)
    q = np.tile(np.array(targets), (len(origins), 1))
    dist = np.linalg.norm(q - o, axis=1)
    d = _f32((q - o) / dist[:, None])
    t, sid, _ = _trace(geo, o, d)
    blocked_by_object = np.isin(sid, [i for i, s in enumerate(geo.surfaces) if s.name in ("tetrahedron", "sphere")])
    on_light = (sid == geo.light_id) & (np.abs(t - dist) <= 1e-4 * dist)
    assert (on_light | blocked_by_object).all(), f"{np.count_nonzero(~(on_light | blocked_by_object))} rays missed the light at its diagonal"


@pytest.mark.parametrize("intersector", ["convex", "triangles"])
def test_random_rays_from_inside_always_hit(intersector):
    """A closed room: 20000 rays from random interior points in random directions all hit at t > 0."""
    scene = load_scene(hardcases.HARD_DIR / "tetra_on_floor.toml")
    geo = Geometry(scene, m, intersector)
    o = _interior_origins(scene, 20000, seed=3)
    d = np.random.default_rng(4).normal(size=o.shape)
    d = _f32(d / np.linalg.norm(d, axis=1, keepdims=True))
    t, _, _ = _trace(geo, o, d)
    assert np.isfinite(t).all() and (t > 0).all()
