"""The efficiency tricks (mcrt.tricks): off by default, unbiased ones consistent with Mitsuba, biased ones flagged.

- Defaults: the trick options at their defaults render the default image
  bit for bit; the course's roulette as a trick is the catalogued bug.
- A bounce mistake (the grader's explanation renders them): a direction on
  the whole sphere weighted as the hemisphere's is, by the physics, twice a
  render with every albedo halved less the light no diffuse surface
  reflects (tile z-tests, Bonferroni at 0.01, seeds 21-24), which the cosine
  applied twice fails.
- Spherical rectangles: the solid angle against the closed form of a
  rectangle seen from a point (sums of arctangents over its corners, not
  the code's formula), the directions' distribution by a chi-square test
  (level 0.01, seed 5) against the bins' solid angles, which uniform area
  sampling fails; E[1 / pdf_area] = A over the sampler's own points (the
  density integrates to one) and the light sample's mean against Lambert's
  irradiance (z-tests at level 0.01, Weyl streams keyed (9, 10)).
- Renders against the committed Mitsuba reference (64 x 64, near camera,
  max depth 8), by the study's comparison (mcrt.tricks.study: policy
  reference-floor, tiles 8 and 32, each at 0.005, family-wise 0.01), one
  seed each (stated in the test): solid-angle sampling, fixed-probability
  roulette and two-stage adaptive sampling pass; the 2023 course's
  roulette, naive adaptive sampling and denoising are flagged.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.stats import norm

import mcrt
from mcrt.estimator import PathEstimator
from mcrt.options import EstimatorOptions
from mcrt.render import render
from mcrt.sampling import square_to_spherical_rectangle
from mcrt.stats import chi2_gof
from mcrt.tricks.adaptive import render_adaptive
from mcrt.tricks.study import compare_with_reference

import drjit as dr  # noqa: E402  (after mcrt: it sets DRJIT_LIBLLVM_PATH)

ALPHA = 0.01
RES = 64
TILES = (8, 32)


@pytest.fixture(scope="module")
def scene():
    return mcrt.load_scene()


@pytest.fixture(scope="module")
def reference(scene):
    from mcrt.groundtruth import load_reference

    return load_reference(scene, "near", (RES, RES), 8)


def _settings(scene, spp, seed=0, res=RES):
    return scene.settings(camera="near", width=res, height=res, spp=spp, max_depth=8, seed=seed)


# --------------------------------------------------------------------------
# Off by default
# --------------------------------------------------------------------------


def test_the_tricks_at_their_defaults_render_the_default_image_bit_for_bit(scene):
    s = _settings(scene, 16, res=32)
    plain = render(scene, s, seed=3, progress=False)
    explicit = render(scene, s, seed=3, progress=False, roulette="unbiased", roulette_survival=None, roulette_start=None,
                      light_sampling="area", sample_clamp=None, bounce="cosine", bounce_at="every", mirror="reflect",
                      mirror_at="every", mirror_normal_length=1.0, pixel_statistic="mean", adaptive=None, denoise=None)
    assert np.array_equal(plain.mean, explicit.mean) and np.array_equal(plain.variance, explicit.variance)
    assert "tricks" not in plain.extra
    moved = render(scene, s, seed=3, progress=False, roulette_start=1)
    assert not np.array_equal(plain.mean, moved.mean) and moved.extra["tricks"] == "roulette_start=1"


def test_a_sample_clamp_caps_every_sample_and_only_darkens(scene):
    """Each sample clamped at 1 (seed 5, 16 spp): no pixel's mean exceeds 1, the light (20 in the scene) shows 1,
    no pixel gets brighter than the same samples unclamped, and a clamp above every sample changes nothing."""
    s = _settings(scene, 16, res=32)
    plain = render(scene, s, seed=5, progress=False)
    clamped = render(scene, s, seed=5, progress=False, sample_clamp=1.0)
    assert float(plain.mean.max()) > 10.0 and float(clamped.mean.max()) <= 1.0 + 1e-6
    assert np.all(clamped.mean <= plain.mean + 1e-6) and clamped.extra["tricks"] == "sample_clamp=1.0"
    high = render(scene, s, seed=5, progress=False, sample_clamp=1e6)
    assert np.array_equal(high.mean, plain.mean)


def test_a_pixel_statistic_takes_the_renders_own_samples(scene):
    """Each pixel's median (and 10 % trimmed mean) of its 16 samples (seed 5): the light's pixels, whose every
    sample is its radiance, stay 20; elsewhere the statistic lies between the pixel's smallest and largest sample
    (the render's own paths, read back one sample at a time), it differs from the mean, and the same seed gives the
    same image bit for bit."""
    from mcrt.samplers import PixelSampler
    from mcrt.tracer import _tracer

    s = _settings(scene, 16, res=32)
    plain = render(scene, s, seed=5, progress=False)
    med = render(scene, s, seed=5, progress=False, pixel_statistic="median")
    trim = render(scene, s, seed=5, progress=False, pixel_statistic="trimmed_10")
    assert np.array_equal(med.mean, render(scene, s, seed=5, progress=False, pixel_statistic="median").mean)
    assert med.extra["tricks"] == "pixel_statistic=median" and np.array_equal(med.variance, plain.variance)
    light = np.all(plain.mean == 20.0, axis=2)
    assert light.any() and np.all(med.mean[light] == 20.0) and np.all(trim.mean[light] == 20.0)
    t = _tracer(scene, s.camera, s.width, s.height, s.max_depth, s.light_samples, s.rr_depth, "llvm", "convex",
                frozenset(), True, None, (), PixelSampler.of("independent", None))
    one = np.stack([t.pixel_sums(5, np.arange(32 * 32), k, 1)[0] for k in range(16)]).reshape(16, 32, 32, 3)
    assert np.allclose(one.mean(axis=0), plain.mean, rtol=1e-5, atol=1e-6)
    for img in (med.mean, trim.mean):
        assert np.all(img >= one.min(axis=0) - 1e-6) and np.all(img <= one.max(axis=0) + 1e-6)
        assert not np.allclose(img, plain.mean)


def test_the_course_roulette_as_a_trick_is_the_catalogued_bug(scene):
    s = _settings(scene, 16, res=32)
    trick = render(scene, s, seed=4, progress=False, roulette="course2023")
    bug = render(scene, s, seed=4, progress=False, mutants=("rr_no_divide",))
    assert np.array_equal(trick.mean, bug.mean)


def _albedos_scaled(scene, k: float):
    """The scene with every diffuse albedo times k (walls, floor, ceiling, the tetrahedron)."""
    from dataclasses import replace

    from mcrt.scene import Lambertian

    room = scene.room
    walls = tuple(replace(w, albedo=tuple(k * a for a in w.albedo)) for w in room.walls)
    room = replace(room, walls=walls, floor_albedo=tuple(k * a for a in room.floor_albedo),
                   ceiling_albedo=tuple(k * a for a in room.ceiling_albedo))
    objects = tuple(replace(o, material=replace(o.material, albedo=tuple(k * a for a in o.material.albedo)))
                    if isinstance(o.material, Lambertian) else o for o in scene.objects)
    return replace(scene, room=room, objects=objects)


def _tile_z(a, b, tile: int = 8) -> np.ndarray:
    """z of the difference of two estimates' tile means, (mean, variance of the mean) pairs per pixel."""
    (ma, va), (mb, vb) = a, b
    h, w = ma.shape[:2]
    blocks = lambda x: x.reshape(h // tile, tile, w // tile, tile, 3).sum(axis=(1, 3)) / tile**2  # noqa: E731
    return (blocks(ma) - blocks(mb)) / np.sqrt((blocks(va) + blocks(vb)) / tile**2)


def test_a_bounce_on_the_whole_sphere_is_half_a_bounce_by_the_physics(scene):
    """Each diffuse direction uniform on the sphere, weighted with the hemisphere's pdf (bounce 'uniform_sphere' at
    every vertex), leaves each bounce half its weight and each light sample right. A path with m diffuse vertices
    (the last one's light sample included) then weighs 2^(1 - m): twice a render with every albedo halved, less
    the light no diffuse surface reflects (a render with every albedo 0, which counts it once). Independent renders
    (seeds 21, 22, 23; 512 spp, 32 x 32), z-tests on 8 x 8 tiles with Bonferroni at 0.01; the same test rejects the
    cosine applied twice (seed 24), a mistake of another shape."""
    s = _settings(scene, 512, res=32)

    def est(sc, seed, **tricks):
        r = render(sc, s, seed=seed, progress=False, **tricks)
        return np.asarray(r.mean, np.float64), np.asarray(r.variance, np.float64) / 512

    (mh, vh), (m0, v0) = est(_albedos_scaled(scene, 0.5), 22), est(_albedos_scaled(scene, 0.0), 23)
    physics = (2.0 * mh - m0, 4.0 * vh + v0)
    z_max = norm.isf(ALPHA / 2 / (16 * 3))
    z = _tile_z(est(scene, 21, bounce="uniform_sphere"), physics)
    assert np.abs(z).max() < z_max, np.abs(z).max()
    z = _tile_z(est(scene, 24, bounce="cosine_squared"), physics)
    assert np.abs(z).max() > z_max


#: Sub-pixel points of a pixel: its corners and centre.
_CORNERS = ((0, 0), (0, 1), (1, 0), (1, 1), (0.5, 0.5))


def _sphere_seen(scene, res: int, *, points=_CORNERS, dilate: int = 1) -> np.ndarray:
    """(res, res, 1): pixels where a camera ray through any of ``points`` (sub-pixel (u, v)) meets the mirror sphere
    ahead, grown by ``dilate`` pixels (NumPy's ray-sphere test; no tracer)."""
    from scipy.ndimage import binary_dilation

    from mcrt.camera import primary_directions
    from mcrt.scene import Mirror

    cam = scene.camera("near")
    sph = next(o for o in scene.objects if isinstance(o.material, Mirror))
    oc = np.asarray(cam.eye, float) - np.asarray(sph.center, float)
    j, i = np.mgrid[0:res, 0:res]
    hit = np.zeros((res, res), bool)
    for u, v in points:
        d = primary_directions(cam, res, res, i, j, np.full(i.shape, u), np.full(i.shape, v))
        b = np.einsum("ijk,k->ij", d, oc)
        hit |= (b * b - (oc @ oc - sph.radius**2) >= 0.0) & (b < 0.0)
    return (binary_dilation(hit, iterations=dilate) if dilate else hit)[..., None]


def test_a_mirror_for_camera_rays_only_is_black_to_every_other_ray(scene):
    """The mirror handled for camera rays only (trick mirror 'camera_only'): a path that meets it after its first
    hit ends. By the physics, wherever the camera does not see the sphere, that is the scene with the sphere black
    (reflectance 0). Pixels away from the sphere (:func:`_sphere_seen`), z-tests on 8 x 8 tiles, Bonferroni at
    0.01, seeds 25 and 26 (512 spp, 32 x 32); the same test rejects the mirror right (seed 27)."""
    from dataclasses import replace

    from mcrt.scene import Mirror

    s = _settings(scene, 512, res=32)
    black = replace(scene, objects=tuple(replace(o, material=Mirror(reflectance=(0.0, 0.0, 0.0)))
                                         if isinstance(o.material, Mirror) else o for o in scene.objects))
    away = ~_sphere_seen(scene, 32)

    def est(sc, seed, **tricks):
        r = render(sc, s, seed=seed, progress=False, **tricks)
        m, v = np.asarray(r.mean, np.float64), np.asarray(r.variance, np.float64) / 512
        return np.where(away, m, 0.0), np.where(away, v, 0.0)

    physics = est(black, 26)
    z_max = norm.isf(ALPHA / 2 / (16 * 3))
    with np.errstate(invalid="ignore"):
        assert np.nanmax(np.abs(_tile_z(est(scene, 25, mirror="camera_only"), physics))) < z_max
        assert np.nanmax(np.abs(_tile_z(est(scene, 27), physics))) > z_max


def test_a_first_bounce_carrying_nothing_is_the_render_cut_after_the_first_light_sample(scene):
    """The bounce at the first hit weighted 0 (trick bounce 'zero', bounce_at 'first'): by the physics, wherever the
    camera sees a diffuse surface, the light seen directly and that surface's light sample, nothing more: the render
    cut at depth 2 (Mitsuba's convention). Pixels away from the sphere (:func:`_sphere_seen`), z-tests on 8 x 8 tiles,
    Bonferroni at 0.01, seeds 28 and 29 (512 spp, 32 x 32); the same test rejects the full render (seed 30)."""
    from dataclasses import replace

    s = _settings(scene, 512, res=32)
    away = ~_sphere_seen(scene, 32)

    def est(settings, seed, **tricks):
        r = render(scene, settings, seed=seed, progress=False, **tricks)
        m, v = np.asarray(r.mean, np.float64), np.asarray(r.variance, np.float64) / 512
        return np.where(away, m, 0.0), np.where(away, v, 0.0)

    physics = est(replace(s, max_depth=2), 29)
    z_max = norm.isf(ALPHA / 2 / (16 * 3))
    with np.errstate(invalid="ignore"):
        assert np.nanmax(np.abs(_tile_z(est(s, 28, bounce="zero", bounce_at="first"), physics))) < z_max
        assert np.nanmax(np.abs(_tile_z(est(s, 30), physics))) > z_max


@pytest.mark.parametrize("options, message", [
    ({"roulette_survival": 0.0}, "roulette_survival must be in"),
    ({"roulette_start": 0}, "roulette_start must be"),
    ({"light_sampling": "cosine"}, "light_sampling must be one of"),
    ({"sample_clamp": 0.0}, "sample_clamp must be > 0"),
    ({"bounce": "hemisphere"}, "bounce must be one of"),
    ({"bounce_at": "last"}, "bounce_at must be one of"),
    ({"mirror": "refract"}, "mirror must be one of"),
    ({"mirror_at": "last"}, "mirror_at must be one of"),
    ({"mirror_normal_length": 0.0}, "mirror_normal_length must be > 0"),
    ({"pixel_statistic": "mode"}, "pixel_statistic must be one of"),
    ({"light_sampling": "solid_angle", "mis": True}, "runs without MIS"),
    ({"light_sampling": "none", "mis": True}, "nothing for MIS to weigh"),
])
def test_bad_trick_values_are_refused(options, message):
    with pytest.raises(ValueError, match=message):
        EstimatorOptions.build(**options)


def test_whole_render_tricks_refuse_what_they_cannot_do(scene):
    s = _settings(scene, 4, res=8)
    with pytest.raises(ValueError, match="denoise must be one of"):
        render(scene, s, progress=False, denoise="median")
    with pytest.raises(ValueError, match="takes no option 'mutants'"):
        render(scene, s, progress=False, adaptive="two-stage", mutants=("no_jitter",))
    with pytest.raises(ValueError, match="adaptive scheme must be one of"):
        render(scene, s, progress=False, adaptive="greedy")


# --------------------------------------------------------------------------
# Spherical rectangles
# --------------------------------------------------------------------------

#: Rectangles [x0, x0 + 2] x [y0, y0 + 2] at depth h below the receiver: near, oblique, grazing, far.
RECTANGLES = [(-1.0, -1.0, 0.05), (2.0, -3.0, 1.0), (0.3, -0.5, 0.01), (-9.0, -1.0, 10.0)]


def _corner(a, b, h):
    """Solid angle of [0, a] x [0, b] at distance h, seen from above the corner (signed in a and b)."""
    return np.arctan(a * b / (h * np.sqrt(a * a + b * b + h * h)))


def closed_form_solid_angle(x0, y0, x1, y1, h):
    """The rectangle's solid angle by inclusion and exclusion of the corner formula."""
    return _corner(x1, y1, h) - _corner(x0, y1, h) - _corner(x1, y0, h) + _corner(x0, y0, h)


def _warp(u1, u2, x0, y0, h):
    from drjit.llvm import Float

    xu, yv, omega = square_to_spherical_rectangle(Float(u1), Float(u2), Float(x0), Float(y0), Float(-h),
                                                  Float(x0 + 2.0), Float(y0 + 2.0))
    return xu.numpy().astype(np.float64), yv.numpy().astype(np.float64), float(omega.numpy()[0])


@pytest.mark.parametrize("x0, y0, h", RECTANGLES)
def test_the_spherical_rectangle_has_the_closed_form_solid_angle(x0, y0, h):
    _, _, omega = _warp(np.zeros(1, np.float32), np.zeros(1, np.float32), x0, y0, h)
    assert omega == pytest.approx(closed_form_solid_angle(x0, y0, x0 + 2, y0 + 2, h), rel=1e-3)


def _uniformity_p(x, y, x0, y0, h, bins=8):
    """Chi-square p-value of points on the rectangle against bins weighted by their solid angles."""
    ex, ey = np.linspace(x0, x0 + 2, bins + 1), np.linspace(y0, y0 + 2, bins + 1)
    counts, _, _ = np.histogram2d(x, y, bins=[ex, ey])
    omega = np.array([[closed_form_solid_angle(ex[i], ey[j], ex[i + 1], ey[j + 1], h) for j in range(bins)]
                      for i in range(bins)])
    return chi2_gof(counts.ravel(), (omega / omega.sum() * len(x)).ravel())[2]


@pytest.mark.parametrize("x0, y0, h", [RECTANGLES[0], RECTANGLES[3]], ids=["near", "far"])
def test_spherical_rectangle_directions_are_uniform_in_solid_angle(x0, y0, h):
    rng = np.random.default_rng(5)
    u1, u2 = rng.random(1_000_000, dtype=np.float32), rng.random(1_000_000, dtype=np.float32)
    x, y, _ = _warp(u1, u2, x0, y0, h)
    assert _uniformity_p(x, y, x0, y0, h) > ALPHA


def test_uniform_area_points_fail_the_same_test_near_the_light():
    x0, y0, h = RECTANGLES[0]
    rng = np.random.default_rng(5)
    x, y = x0 + 2 * rng.random(1_000_000), y0 + 2 * rng.random(1_000_000)
    assert _uniformity_p(x, y, x0, y0, h) < 1e-6


def _light_sample(scene, strategy, x, n, samples=200_000):
    """The estimator's light sample at x with normal n, green channel, on mcrt's host."""
    import drjit.llvm as m

    from mcrt.geometry import Geometry
    from mcrt.host import McrtHost
    from mcrt.rng import WeylRng

    host = McrtHost(Geometry(scene, m, "convex"))
    est = PathEstimator(host, EstimatorOptions.build(light_sampling=strategy))
    origin = m.Array3f(*(dr.full(m.Float, c, samples) for c in x))
    value = est.light_sample(origin, m.Array3f(*n), WeylRng.seeded(m, samples, m.UInt32(9), m.UInt32(10)), m.Bool(True))
    return np.asarray(value[1].numpy(), dtype=np.float64)


def _z_ok(a: np.ndarray, expected: float) -> bool:
    return abs(a.mean() - expected) / (a.std(ddof=1) / math.sqrt(a.size)) < norm.isf(ALPHA / 2)


#: Receivers (point, unit normal) that see the whole light: just below it, beside it tilted, on the floor.
RECEIVERS = [((5.2, 0.1, 4.9), (0.0, 0.0, 1.0)), ((1.0, 5.0, 2.0), (0.0, -0.6, 0.8)), ((5.0, 0.0, -5.0), (0.0, 0.0, 1.0))]


@pytest.mark.parametrize("x, n", RECEIVERS, ids=["below", "beside", "floor"])
def test_solid_angle_light_samples_integrate_to_lamberts_irradiance(scene, x, n):
    from mcrt.closed_form import polygon_irradiance

    g = _light_sample(scene, "solid_angle", x, n)
    expected = polygon_irradiance(np.array([x]), np.array([n]), scene.light.corners(), scene.light.radiance[1])[0]
    assert _z_ok(g, expected), (g.mean(), expected)


@pytest.mark.parametrize("x, n", RECEIVERS, ids=["below", "beside", "floor"])
def test_the_solid_angle_density_integrates_to_one_over_the_light(scene, x, n):
    """E_p[1 / p_A(y)] = int_light p_A (1 / p_A) dA = A, for the sampler's own points and densities."""
    import drjit.llvm as m

    from mcrt.geometry import Geometry
    from mcrt.host import McrtHost
    from mcrt.rng import WeylRng

    host = McrtHost(Geometry(scene, m, "convex"))
    samples = 200_000
    rng = WeylRng.seeded(m, samples, m.UInt32(9), m.UInt32(10))
    origin = m.Array3f(*(dr.full(m.Float, c, samples) for c in x))
    ls = host.sample_light_solid_angle(origin, rng.next_1d(), rng.next_1d())
    inv = 1.0 / np.asarray(ls.pdf_area.numpy(), dtype=np.float64)
    assert _z_ok(inv, scene.light.area), (inv.mean(), scene.light.area)
    wrong = inv * np.asarray(ls.cos_y.numpy(), dtype=np.float64)  # a density without the cosine at the light
    assert not _z_ok(wrong, scene.light.area)


def test_solid_angle_sampling_wins_near_the_light(scene):
    """Per-sample variance of the direct light 0.05 below the light: area over solid angle > 100 (measured ~600)."""
    from mcrt.tricks.light_study import light_receiver_study

    rows = light_receiver_study(scene, samples=1 << 16, repeats=1)
    near = next(r for r in rows if r["receiver"].startswith("0.05 "))
    assert near["variance_ratio"] > 100
    assert all(r["variance_ratio"] > 1 for r in rows)


# --------------------------------------------------------------------------
# Renders against the Mitsuba reference
# --------------------------------------------------------------------------


def _passes(result, reference, adaptive=None) -> bool:
    return all(c.passed for c in compare_with_reference(result, reference, adaptive, alpha=ALPHA, tiles=TILES))


@pytest.mark.parametrize("options", [{"light_sampling": "solid_angle"}, {"light_sampling": "none"},
                                     {"roulette_survival": 0.8, "roulette_start": 1},
                                     {"roulette_survival": 0.5, "roulette_start": 3}],
                         ids=["solid_angle", "no_light_sampling", "fixed_q0.8_from_1", "fixed_q0.5_from_3"])
def test_unbiased_tricks_pass_against_the_reference(scene, reference, options):
    """1024 spp, seed 1."""
    r = render(scene, _settings(scene, 1024), seed=1, progress=False, **options)
    assert _passes(r, reference)


@pytest.mark.parametrize("options, spp", [({"roulette": "course2023"}, 256),
                                          ({"roulette": "course2023", "roulette_start": 5}, 1024)],
                         ids=["course2023_from_1", "course2023_from_5"])
def test_the_course_roulette_is_flagged_from_any_start_depth(scene, reference, options, spp):
    """Seed 1; from depth 5 it darkens only the paths of six segments and more, and needs more samples."""
    r = render(scene, _settings(scene, spp), seed=1, progress=False, **options)
    assert not _passes(r, reference)


@pytest.mark.slow
def test_two_stage_adaptive_passes_and_naive_is_flagged(scene, reference):
    """1024 spp on average, seed 1; the naive scheme's counts come from the same samples it averages."""
    two = render_adaptive(scene, _settings(scene, 1024, seed=1), scheme="two-stage")
    assert _passes(two.result, reference, two)
    assert two.used.max() > 4 * two.used.min()  # the counts did adapt
    assert abs(two.traced.mean() - 1024) < 0.01 * 1024  # to the budget
    naive = render_adaptive(scene, _settings(scene, 1024, seed=1), scheme="naive")
    assert not _passes(naive.result, reference, naive)


def test_denoising_helps_at_low_spp_and_is_flagged_where_the_comparison_can_tell(scene, reference):
    """OIDN with the albedo and normal buffers: relMSE at 16 spp at least halved (seed 2); flagged at 1024 spp (seed 1)."""
    from mcrt.metrics import relmse

    low = render(scene, _settings(scene, 16), seed=2, progress=False)
    low_dn = render(scene, _settings(scene, 16), seed=2, progress=False, denoise="albedo+normal")
    assert relmse(reference.mean, low_dn.mean) < 0.5 * relmse(reference.mean, low.mean)
    high_dn = render(scene, _settings(scene, 1024), seed=1, progress=False, denoise="albedo+normal")
    assert not _passes(high_dn, reference)


def test_first_hit_buffers_see_the_floor_albedo_and_normal():
    """In the lit-floor scene (floor albedo 0.5, every other surface black): pixels well inside the floor (NumPy rays)."""
    from scipy.ndimage import binary_erosion

    from mcrt.closed_form import lit_floor_image, lit_floor_scene
    from mcrt.tricks.aov import first_hit_buffers

    sc = lit_floor_scene(0.5)
    _, grid_floor = lit_floor_image(sc, "near", 32, 32, sub=4)
    floor = binary_erosion(grid_floor)  # an edge pixel's random rays may reach the wall where the grid of rays did not
    b = first_hit_buffers(sc, "near", 32, 32)
    assert floor.sum() > 100 and (~grid_floor).sum() > 100
    assert np.allclose(b.albedo[floor], 0.5, atol=1e-6)
    assert np.allclose(b.normal[floor], [0.0, 0.0, 1.0], atol=1e-6)
    assert (b.albedo[~grid_floor] < 0.5).mean() > 0.9  # black walls and ceiling, a white light, mixed edges


# --------------------------------------------------------------------------
# The report command
# --------------------------------------------------------------------------


def test_the_report_command_writes_index_data_and_figures(tmp_path):
    from mcrt.cli import main

    out = tmp_path / "tricks"
    rc = main(["tricks", "--only", "light", "--ladder", "4,8", "--seeds", "2", "--light-receiver-samples", "4096",
               "--out", str(out), "--quiet"])
    assert rc == 0
    d = json.loads((out / "data.json").read_text())
    assert d["command"].startswith("mcrt tricks ") and "--only light" in d["command"]
    assert [v["label"] for v in d["variants"]] == ["mcrt", "solid angle (spherical rectangle)", "K = 4 shadow rays"]
    assert len(d["verdicts"]) == 1 and d["verdicts"][0].startswith("Explicit light sampling")
    assert all((out / f).is_file() for f in d["files"])
    md = (out / "index.md").read_text()
    assert "## Verdicts" in md and d["verdicts"][0].split(":")[0] in md


def test_denoise_without_pyoidn_fails_before_rendering(scene, monkeypatch):
    """Without the denoise extra, --denoise says how to install it, and no render is spent first."""
    import sys

    import mcrt.tracer
    from mcrt.render import render_mcrt

    monkeypatch.setitem(sys.modules, "pyoidn", None)  # import pyoidn now raises ImportError
    monkeypatch.setattr(mcrt.tracer, "render_tracer", lambda *a, **k: pytest.fail("rendered before the check"))
    with pytest.raises(RuntimeError, match=r"pip install 'mcrt\[denoise\]'"):
        render_mcrt(scene, scene.settings(width=8, height=8, spp=1), denoise="color")
