"""The Mitsuba 3 side: scene built from the Scene object, pixel mapping, light orientation, determinism.

Renders are 32 x 32 with few samples so the file runs in seconds on two CPU cores.
"""

from __future__ import annotations

import numpy as np
import pytest

import mcrt
from mcrt.camera import primary_directions
from mcrt.mitsuba_scene import load_mitsuba_scene, scene_dict, sensor_rays, variant_for
from mcrt.render import render

import drjit as dr  # noqa: E402  (after mcrt: it sets DRJIT_LIBLLVM_PATH)
import mitsuba as mi  # noqa: E402

CAMERAS = ("near", "far")
W = H = 32


def _mitsuba(scene, seed, spp_per_pass=None, **settings):
    """Mitsuba's path integrator through mcrt.render.render at these settings."""
    return render(scene, scene.settings(**settings), renderer="mitsuba", seed=seed, progress=False, spp_per_pass=spp_per_pass)


@pytest.fixture(scope="module")
def scene():
    return mcrt.load_scene(mcrt.CANONICAL)


# --------------------------------------------------------------------------
# Variant
# --------------------------------------------------------------------------


def test_variant_for():
    assert variant_for("llvm") == "llvm_ad_rgb"
    with pytest.raises(ValueError):
        variant_for("metal")
    if dr.has_backend(dr.JitBackend.CUDA):
        assert variant_for("cuda") == "cuda_ad_rgb"
    else:
        with pytest.raises(RuntimeError) as e:
            variant_for("cuda")
        assert "cuda_ad_rgb" in str(e.value) and "\n" not in str(e.value)


# --------------------------------------------------------------------------
# Camera: Mitsuba's sensor against mcrt.camera (the scene.md mapping)
# --------------------------------------------------------------------------


def _pixel_samples(width, height):
    """Corner pixels with jitters 0 and ~1 in both axes, and the centre pixel."""
    top = 1.0 - 1e-6
    rows = []
    for i in (0, width - 1):
        for j in (0, height - 1):
            for u in (0.0, top):
                for v in (0.0, top):
                    rows.append((i, j, u, v))
    rows += [(width // 2, height // 2, 0.5, 0.5), (width // 2, height // 2, 0.0, 0.0)]
    return np.array(rows, dtype=np.float64).T


@pytest.mark.parametrize("camera", CAMERAS)
@pytest.mark.parametrize("size", [(W, H), (40, 24)])
def test_sensor_matches_camera_module(scene, camera, size):
    width, height = size
    i, j, u, v = _pixel_samples(width, height)
    o, d = sensor_rays(scene, camera, width, height, i, j, u, v)
    expected = primary_directions(scene.camera(camera), width, height, i, j, u, v)
    np.testing.assert_allclose(d, expected, atol=1e-5)
    # Origins lie on the ray from the eye (Mitsuba starts at the near clip, 0.01 ahead).
    eye = np.array(scene.camera(camera).eye)
    t = (o - eye) @ np.array(scene.camera(camera).forward) / (d @ np.array(scene.camera(camera).forward))
    assert np.all((t >= 0) & (t < 0.1))
    np.testing.assert_allclose(o, eye + t[:, None] * d, atol=1e-5)


def test_near_camera_top_left_is_plus_y_plus_z(scene):
    """scene.md: pixel (0, 0) with jitter (0, 0) passes through the plane point (0, 1, 1)."""
    o, d = sensor_rays(scene, "near", W, H, [0], [0], [0.0], [0.0])
    t = -o[0, 0] / d[0, 0]
    np.testing.assert_allclose(o[0] + t * d[0], [0.0, 1.0, 1.0], atol=1e-5)
    # and the bottom-right corner (jitter ~1) passes through (0, -1, -1)
    o, d = sensor_rays(scene, "near", W, H, [W - 1], [H - 1], [1 - 1e-6], [1 - 1e-6])
    t = -o[0, 0] / d[0, 0]
    np.testing.assert_allclose(o[0] + t * d[0], [0.0, -1.0, -1.0], atol=1e-5)


# --------------------------------------------------------------------------
# Geometry: closed room, consistent orientation, light facing down
# --------------------------------------------------------------------------


def test_scene_dict_materials(scene):
    d = scene_dict(scene, "near", W, H, 8)
    assert d["integrator"] == {"type": "path", "max_depth": 8, "rr_depth": 5, "hide_emitters": False}
    assert d["sensor"]["film"]["rfilter"] == {"type": "box"}
    names = {s.name for s in scene.surfaces()} | {s.name for s in scene.spheres()}
    assert names <= set(d)
    for s in scene.surfaces():
        mesh = d[s.name]
        assert isinstance(mesh, mi.Mesh) and mesh.face_count() == len(s.triangles)
        bsdf = mesh.bsdf().class_name()
        assert bsdf == ("SmoothDiffuse" if s.material is None else "TwoSidedBRDF"), (s.name, bsdf)
        assert mesh.is_emitter() == (s.material is None)
    sphere = d[scene.spheres()[0].name]["bsdf"]
    assert sphere["type"] == "conductor" and sphere["material"] == "none"


def _interior_points(scene):
    pts = np.array([[0.0, 0.0, 0.0], [5.0, 0.0, 0.0], [3.0, 3.0, -3.0], [8.0, -4.5, 3.0], [11.0, 0.0, -4.0], [-1.0, 0.0, 4.5]])
    for p in pts:
        assert scene.room.contains(p, 0.1)
    return pts


def test_room_is_closed_and_faces_point_at_the_interior(scene):
    """From points in the free space of the room every ray hits a face whose normal points back at it.

    Room faces are wound inwards, objects outwards and the light downwards, so
    seen from the free space every geometric normal faces the incoming ray.
    """
    ms = load_mitsuba_scene(scene, "near", W, H)
    rng = np.random.default_rng(7)  # fixed: the test is deterministic
    d = rng.normal(size=(4000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    for p in _interior_points(scene):
        ray = mi.Ray3f(mi.Point3f(*(float(x) for x in p)), mi.Vector3f(d.T.astype(np.float32)))
        si = ms.ray_intersect(ray)
        valid = si.is_valid().numpy()
        assert valid.all(), f"{(~valid).sum()} rays from {p} escaped the room"
        n = np.array(si.n).T
        cos = np.sum(n * d, axis=1)
        assert np.all(cos < 0), f"{(cos >= 0).sum()} faces seen from their back from {p}"
        hit = si.p.numpy().T
        assert np.all(np.isfinite(hit))


def test_light_emits_downward_only(scene):
    ms = load_mitsuba_scene(scene, "near", W, H)
    light = scene.light
    c = [float(x) for x in light.center]  # mi.Point3f rejects NumPy float64 scalars
    below = mi.Ray3f(mi.Point3f(c[0], c[1], scene.room.floor_z + 0.01), mi.Vector3f(0, 0, 1))
    si = ms.ray_intersect(below)
    assert si.is_valid()[0] and si.shape.is_emitter()[0]
    np.testing.assert_allclose(np.array(si.emitter(ms).eval(si)).ravel(), light.radiance, rtol=1e-6)
    above = mi.Ray3f(mi.Point3f(c[0], c[1], (c[2] + scene.room.ceiling_z) / 2), mi.Vector3f(0, 0, -1))
    si = ms.ray_intersect(above)
    assert si.is_valid()[0] and si.shape.is_emitter()[0]
    np.testing.assert_array_equal(np.array(si.emitter(ms).eval(si)).ravel(), 0.0)
    assert len(ms.emitters()) == 1


# --------------------------------------------------------------------------
# Renders
# --------------------------------------------------------------------------


@pytest.mark.parametrize("camera", CAMERAS)
def test_render_is_finite_and_oriented(scene, camera):
    r = _mitsuba(scene, camera=camera, width=W, height=H, spp=16, seed=3, max_depth=8)
    assert r.mean.shape == r.variance.shape == (H, W, 3)
    assert r.mean.dtype == r.variance.dtype == np.float32
    for a in (r.mean, r.variance):
        assert np.all(np.isfinite(a)) and np.all(a >= 0)
    assert np.any(r.variance > 0)
    assert r.renderer == "mitsuba" and r.camera == camera and r.spp == 16 and r.max_depth == 8
    assert r.scene_hash == scene.content_hash()
    assert r.extra["variant"] == "llvm_ad_rgb" and r.extra["integrator"] == "path" and r.extra["rr_depth"] == "5"
    assert r.wall_time > 0 and r.compile_time is not None and 0 <= r.compile_time
    if camera == "near":
        # Image left is the green wall EF, right the purple wall BC (scene.md).
        mid = slice(H // 4, 3 * H // 4)
        left, right = r.mean[mid, :2].mean(axis=(0, 1)), r.mean[mid, -2:].mean(axis=(0, 1))
        assert left[1] > left[0] and left[1] > left[2], left
        assert right[2] > right[1] and right[0] > right[1], right
        # Pixels that see only the (black, emitting) light are exactly its radiance, with no variance.
        lit = np.all(r.mean == np.float32(scene.light.radiance[0]), axis=-1)
        assert lit.sum() >= 4 and lit[: H // 4].sum() == lit.sum()
        assert np.all(r.variance[lit] == 0)


def test_render_is_deterministic(scene):
    kw = dict(camera="near", width=16, height=16, spp=8, max_depth=4, spp_per_pass=3)
    a = _mitsuba(scene, seed=11, **kw)
    b = _mitsuba(scene, seed=11, **kw)
    c = _mitsuba(scene, seed=12, **kw)
    assert np.array_equal(a.mean, b.mean) and np.array_equal(a.variance, b.variance)
    assert not np.array_equal(a.mean, c.mean)
    # One sample per pass: identical pass seeds would make every pixel's samples equal (zero variance).
    d = _mitsuba(scene, seed=11, **dict(kw, spp=4, spp_per_pass=1))
    assert np.mean(np.any(d.variance > 0, axis=-1)) > 0.5


def _light_coverage(scene, camera, width, height, k=16):
    """Fraction of each pixel whose rays (k x k grid of jitters) hit the light rectangle, by mcrt.camera."""
    g = np.linspace(0.0, 1.0 - 1e-9, k)  # pixel corners included: all inside => the pixel is (convexity)
    j, i, v, u = np.meshgrid(np.arange(height), np.arange(width), g, g, indexing="ij")
    d = primary_directions(scene.camera(camera), width, height, i, j, u, v)
    eye, light = np.array(scene.camera(camera).eye), scene.light
    with np.errstate(divide="ignore", invalid="ignore"):  # rays parallel to the light's plane
        t = (light.center[2] - eye[2]) / d[..., 2]
        p = eye + t[..., None] * d
    hx, hy = light.size[0] / 2, light.size[1] / 2
    inside = (t > 0) & (np.abs(p[..., 0] - light.center[0]) <= hx) & (np.abs(p[..., 1] - light.center[1]) <= hy)
    return inside.mean(axis=(2, 3))


@pytest.mark.parametrize("camera", CAMERAS)
def test_max_depth_1_shows_only_the_light(scene, camera):
    """With max_depth 1 only directly seen emitters count: 0 or the light's radiance, nothing else."""
    r = _mitsuba(scene, camera=camera, width=W, height=H, spp=16, seed=5, max_depth=1)
    Le = np.float32(scene.light.radiance[0])
    cov = _light_coverage(scene, camera, W, H)
    full, none = cov == 1.0, cov == 0.0
    # The light's image is convex, so a pixel whose corners all see it is covered. A pixel whose grid
    # misses it may still hold a sliver next to a partly covered pixel: use pixels amid uncovered ones.
    none_strict = none & np.all([np.roll(none, s, axis=a) for a in (0, 1) for s in (-1, 1)], axis=0)
    assert none_strict.sum() > W * H // 2
    if camera == "near":
        assert full.sum() >= 4  # the near camera sees the light near the top of the image
    else:
        assert cov.max() == 0 and np.all(r.mean == 0)  # the far camera's view ends below it
    assert np.all(r.mean[full] == Le) and np.all(r.variance[full] == 0)
    assert np.all(r.mean[none_strict] == 0) and np.all(r.variance[none_strict] == 0)
    # Every pixel is a fraction of the samples seeing Le: mean = Le k / n for an integer k.
    frac = r.mean * r.spp / Le
    np.testing.assert_allclose(frac, np.round(frac), atol=1e-3)
    assert np.all((r.mean >= 0) & (r.mean <= Le))
    # All three channels agree (white light, nothing reflected).
    assert np.all(r.mean[..., 0] == r.mean[..., 1]) and np.all(r.mean[..., 1] == r.mean[..., 2])


def test_matches_mi_render_on_average(scene):
    """Driving the integrator by hand estimates the same image as mi.render (image mean within 5 sigma)."""
    r = _mitsuba(scene, camera="near", width=W, height=H, spp=32, seed=9, max_depth=4)
    ms = load_mitsuba_scene(scene, "near", W, H, max_depth=4)
    ref = np.asarray(mi.render(ms, spp=32, seed=1234)).astype(np.float64)
    n_pix = W * H
    se = np.sqrt(r.variance.astype(np.float64).sum(axis=(0, 1)) / r.spp) / n_pix  # std error of the image mean
    diff = r.mean.astype(np.float64).mean(axis=(0, 1)) - ref.mean(axis=(0, 1))
    assert np.all(np.abs(diff) < 5 * np.sqrt(2) * se), (diff, se)


def test_a_room_surface_made_a_mirror_renders_as_mitsubas_conductor(scene):
    """The floor a mirror of reflectance 0.7 (Room.mirrors, what the grader renders a surface's other material with)
    in mcrt, against Mitsuba's scene with the floor's mesh given a smooth conductor of that reflectance in its
    dictionary (not through Room.mirrors): the images' tile means (8 x 8, 32 x 32, 1024 spp, seeds 61 and 62) agree
    by z-tests at 0.01 with Bonferroni; the floor left diffuse (mcrt, seed 63) is rejected by the same test."""
    from dataclasses import replace

    from mcrt.mitsuba_scene import _mesh, render_with_variance
    from scipy.stats import norm

    spp, tile = 1024, 8
    mirrored = replace(scene, room=replace(scene.room, mirrors=(("floor", (0.7, 0.7, 0.7)),)))
    d = scene_dict(scene, "near", W, H, 8, spp=spp)
    floor = next(s for s in scene.surfaces() if s.name == "floor")
    d["floor"] = _mesh(floor, {"type": "conductor", "material": "none",
                               "specular_reflectance": {"type": "rgb", "value": 0.7}})
    theirs = render_with_variance(d, spp=spp, seed=62)

    def tiles(r):
        m, v = np.asarray(r.mean, np.float64), np.asarray(r.variance, np.float64) / r.spp
        blocks = lambda x: x.reshape(H // tile, tile, W // tile, tile, 3).sum(axis=(1, 3)) / tile**2  # noqa: E731
        return blocks(m), blocks(v) / tile**2

    def z(r):
        (a, va), (b, vb) = tiles(r), tiles(theirs)
        return np.abs(a - b) / np.sqrt(va + vb)

    settings = scene.settings(camera="near", width=W, height=H, spp=spp, max_depth=8)
    z_max = norm.isf(0.01 / 2 / ((W // tile) * (H // tile) * 3))
    assert z(render(mirrored, settings, seed=61, progress=False)).max() < z_max
    assert z(render(scene, settings, seed=63, progress=False)).max() > z_max
