"""The twenty-first class (mcrt.grade.accuracy.unvisited) is well formed and builds what its specs say: the same checks
as test_accuracy_unbeknown's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x 16, never
graded), on this class's cases, the light samples, bounces and sample loops its Mitsuba renders are made of.
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import (H, W, build as _build, by_name, check_builds, check_command, check_correct_agree,
                              check_held_out_rule, check_new_truths, check_not_catalogued, check_old_causes,
                              check_seeds, check_specs, image as _image, pillow_codes, plain as _plain)
from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unbeknown, unbidden,
                                 unforeseen, unguessed, unheard, unheralded, unmet, unprompted, unsaid, unseen,
                                 unsought, untold, untried, unvisited)
from mcrt.image_files import read_image, srgb_eotf

_by_name = partial(by_name, unvisited.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought, unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown)


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unvisited, _OTHERS, mistakes=28)
    check_new_truths(unvisited, _OTHERS)
    assert len(unvisited.MISTAKES) == 28 and {len(v) for v in unvisited.CATEGORIES.values()} <= {3, 4}
    assert list(unvisited.CATEGORIES) == list(unbeknown.CATEGORIES)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unvisited)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unvisited)
    assert sum(s.held_out for s in unvisited.MISTAKES) == 12 and sum(s.held_out for s in unvisited.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    check_old_causes(unvisited, _OTHERS)
    assert unvisited._EARLIER[-1] is unbeknown


def test_seeds_differ_from_the_other_classes():
    check_seeds(unvisited, _OTHERS, 801000)


def test_the_command_knows_the_class():
    check_command(unvisited, "unvisited")


def test_correct_writers_read_back(tmp_path):
    """The HDR stored turned reads back as the image (within RGBE's step); the BMP bottom-up and the uncompressed PNG
    as its 8-bit codes."""
    x = _image()
    for d in "abc":
        (tmp_path / d).mkdir()
    r = read_image(unvisited._write_hdr_turned(x, tmp_path / "a")).mean
    step = np.ldexp(1.0, np.frexp(x.max(axis=2))[1] - 8)[..., None]
    assert np.all(np.abs(r - x) <= step)
    c8 = blind._srgb8(x)
    for writer, d in ((unvisited._write_bmp_bottom_up, "b"), (unvisited._write_png_stored, "c")):
        path = writer(x, tmp_path / d)
        np.testing.assert_array_equal(pillow_codes(path), c8)
        np.testing.assert_allclose(read_image(path).mean, srgb_eotf(c8 / 255.0), atol=1e-6)
    raw = (tmp_path / "c" / "render.png").read_bytes()
    assert len(raw) > H * W * 3  # stored, not compressed


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    x = _image()
    x[0, 0] = 20.0  # a pixel of the light
    for d in "abc":
        (tmp_path / d).mkdir()
    # The PFM's scale the image's maximum: read back times that maximum.
    r = read_image(unvisited._write_pfm_scale_max(x, tmp_path / "a")).mean
    np.testing.assert_allclose(r, x * 20.0, rtol=1e-5)
    # One RGBE exponent for the image: steps of 2^5 / 256 = 0.125, the light kept.
    r = read_image(unvisited._write_hdr_one_exponent(x, tmp_path / "b")).mean
    np.testing.assert_allclose(r, np.minimum(np.floor(x * 8.0 + 0.5), 255) / 8.0, atol=1e-6)
    assert r[0, 0, 0] == pytest.approx(20.0) and set(np.unique(r[1:] * 8.0)) <= set(range(9))
    # The dither half a code low: its codes' mean half a code under the exact ones', every code within one of them.
    c8 = blind._srgb8(x).astype(int)
    codes = pillow_codes(unvisited._write_png_dither_half_low(x, tmp_path / "c")).astype(int)
    assert np.abs(codes - c8).max() <= 1 and (codes - c8).mean() == pytest.approx(-0.5, abs=0.1)


def test_passes_averaged_in_uint8_wrap_past_255():
    x = np.zeros((4, 4, 3))
    a, b = (blind._srgb8(unseen._render(4, 4, 8, 1 + k)) for k in range(2))
    codes = blind._srgb8(unvisited._passes_uint8_mean(x, spp=16, seed=1))
    np.testing.assert_array_equal(codes, (a.astype(int) + b) % 256 // 2)


def test_post_processes_do_what_they_say():
    x = _image()
    # Perona-Malik: the noise smoothed, the mean kept, a step of 2 kept sharp.
    d = unvisited._perona_malik(x * 0.1)
    assert np.abs(np.diff(d, axis=1)).mean() < 0.6 * np.abs(np.diff(x * 0.1, axis=1)).mean()
    assert d.mean() == pytest.approx(0.1 * x.mean(), rel=1e-6)
    step = np.zeros((8, 8, 3))
    step[:, 4:] = 2.0
    np.testing.assert_allclose(unvisited._perona_malik(step), step, atol=1e-12)
    # OpenCV's tone map: the minimum 0, the maximum 1, a gamma of 2.2 between.
    t = unvisited._opencv_tonemap(x)
    assert t.min() == 0.0 and t.max() == pytest.approx(1.0)
    np.testing.assert_allclose(t, ((x - x.min()) / (x.max() - x.min())) ** (1 / 2.2))
    # The Sobel magnitude added: a flat image kept, an edge brightened on both sides.
    np.testing.assert_allclose(unvisited._sobel_added(np.full((6, 6, 3), 0.5)), 0.5)
    s = unvisited._sobel_added(step)
    assert s[4, 3, 0] == pytest.approx(0.8) and s[4, 4, 0] == pytest.approx(2.8) and s[4, 0, 0] == 0.0
    # The CDL grade: red 5 % up, green kept, blue 0.95 v raised to 1.1.
    g = unvisited._asc_cdl(np.full((2, 2, 3), 0.5))[0, 0]
    np.testing.assert_allclose(g, (0.525, 0.5, 0.475 ** 1.1))


def test_scene_edits_do_what_they_say():
    from mcrt.scene import load_scene

    s = load_scene()
    cam = unvisited._fov_height_then_width(s).cameras["near"]
    assert cam.fov_x_deg == pytest.approx(math.degrees(2 * math.atan(1.5)))
    objs = {o.name: o for o in unvisited._sphere_radius_int(s).objects}
    assert objs["sphere"].radius == 1.0 and objs["tetrahedron"] == next(o for o in s.objects if o.name == "tetrahedron")
    snapped = unvisited._snapped_to_floor(s)
    assert all(unvisited._lowest_z(o) == pytest.approx(s.room.floor_z) for o in snapped.objects)
    moved = {o.name: o for o in snapped.objects}
    assert moved["sphere"].center[2] == pytest.approx(-3.5)
    x = _image()
    np.testing.assert_array_equal(unvisited._rows_flipped(x), x[::-1])


def test_tetra_permutations_mesh_each_face_six_times():
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    d = unvisited._tetra_permutations(scene_dict(load_scene(), "near", 4, 4, 8))
    assert d["tetrahedron"].face_count() == 24


def test_offsets_are_as_they_say():
    rng = np.random.default_rng(1)
    u, v = unvisited._centre_plus_jitter(rng, 64, w=4, pixels=5)
    assert u.shape == (5, 64) and np.all((0.5 <= u) & (u < 1.5)) and np.all((0.5 <= v) & (v < 1.5))
    u, v = unvisited._rows_short(rng, 64, w=4, pixels=5)
    assert np.all((0 <= u) & (u < 1)) and np.all((0 <= v) & (v < 15 / 16)) and v.max() > 0.8
    u, v = unvisited._scipy_sobol(rng, 64, w=4, pixels=3)
    assert u.shape == (3, 64) and np.all((0 < u) & (u < 1))
    for a in (u, v):  # a scrambled Sobol set: one point in each of the 64 strata along each axis
        np.testing.assert_array_equal(np.sort(np.floor(a * 64), axis=1), np.broadcast_to(np.arange(64), (3, 64)))
    assert not np.allclose(u[0], u[1])


def test_light_samples_are_as_they_say():
    rng = np.random.default_rng(2)
    lt = unbeknown._scene().light
    q = unbeknown._light_points(rng, 2000)
    wall = np.tile([[5.0, -5.999, 3.0]], (2000, 1))
    inward = np.tile([[0.0, 1.0, 0.0]], (2000, 1))
    g = unbeknown._geometry(wall, inward, q)
    # Lambert's cosine twice: the geometry term times the surface's cosine again.
    np.testing.assert_allclose(unvisited._cos_twice(wall, inward, q), g * unsaid._unit(q - wall)[:, 1])
    # The attenuation: 1 / (1 + 0.09 d + 0.032 d^2).
    d = np.linalg.norm(q - wall, axis=1)
    np.testing.assert_allclose(unvisited._attenuated(wall, inward, q), g / (1 + 0.09 * d + 0.032 * d * d))
    # From the centre: the same value whatever the point drawn, near the mean of the right one.
    c = unvisited._from_centre(wall, inward, q)
    np.testing.assert_allclose(c, c[0])
    assert c[0] == pytest.approx(g.mean(), rel=0.1)
    # The unnormalised normal: twice the triangle's area on a wall, the floor's fan and the tetrahedron's faces.
    p = np.array([[5.0, -5.9999, 3.0], [5.0, 0.0, -4.9999], [100.0, 0.0, 0.0]])
    a = unvisited._doubled_areas(p)
    assert a[0] == pytest.approx(10.0 * 10.0) and a[2] == 1.0 and a[1] > 10.0
    mit = np.ones((3, 3))
    np.testing.assert_allclose(unvisited._normal_unnormalised(None, None, p, None, None, mit), a[:, None] * mit)
    assert lt.area == 4.0


def test_bounces_are_as_they_say():
    rng = np.random.default_rng(3)
    n = unsaid._unit(rng.normal(size=(4000, 3)))
    d, w = unvisited._times_pdf(rng, n)
    cos = np.einsum("ij,ij->i", d, n)
    np.testing.assert_allclose(w, (cos / math.pi) ** 2, rtol=1e-9)
    d, w = unvisited._one_number(rng, n)
    cos = np.einsum("ij,ij->i", d, n)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0)
    assert np.all(cos >= 0.0) and np.all(w == 1.0)
    # One number for both: the azimuth a function of the cosine (cos^2 = 1 - u, phi = 2 pi u).
    t, b = unforeseen._frame_of(n)
    phi = np.arctan2(np.einsum("ij,ij->i", d, b), np.einsum("ij,ij->i", d, t)) % (2 * math.pi)
    np.testing.assert_allclose(phi, 2 * math.pi * (1 - cos ** 2), atol=1e-6)


def test_samples_cut_weighted_or_counted_as_they_say():
    x = np.zeros((4, 4, 3))
    full, two, seen = unsaid._loaded(8), unsaid._loaded(2), unsaid._loaded(1)
    eye = np.array([-1.0, 0.0, 0.0])
    dirs = unsaid._unit(np.array([[10.0, 0.5, -5.0], [4.0, -6.0, 0.5], [9.5, 2.0, -3.3]]) - eye)
    o = np.tile(eye, (3, 1))
    L8, L2, L1 = (unsaid._sampled(m, o, dirs, 7) for m in (full, two, seen))
    # The indirect light clamped to 1: the max-depth-2 sample plus what follows, at most 1 a channel.
    got = unvisited._indirect_clamped_sample(o, dirs, 7, full=full, direct=two)
    np.testing.assert_allclose(got, L2 + np.minimum(L8 - L2, 1.0))
    # kD = 1 - F: the floor's and the wall's reflected light times it, the sphere's kept.
    cos = -np.einsum("ij,ij->i", unforeseen._first_normal(full, o[:2], dirs[:2]), dirs[:2])
    k = unvisited._fresnel_kd_sample(o, dirs, 7, full=full, seen=seen)
    np.testing.assert_allclose(k[:2], L1[:2] + (1 - unvisited._schlick(cos))[:, None] * (L8[:2] - L1[:2]), rtol=1e-6)
    np.testing.assert_allclose(k[2], L8[2])
    # The luminance-weighted mean: sum of w L over sum of w, at least the plain mean where samples vary.
    L = unbidden._all_samples(4, 4, 32, 5)
    wt = L @ programs._LUMA
    got = unvisited._luminance_weighted(x, spp=32, seed=5).reshape(16, 3)
    np.testing.assert_allclose(got, (wt[..., None] * L).sum(axis=1) / wt.sum(axis=1)[:, None])
    assert got.mean() > L.mean()
    # The uint8 counter: 320 samples counted 64.
    np.testing.assert_allclose(unvisited._count_wrapped(np.ones((2, 2, 3)), spp=320), 5.0)
    # The light seen once a pixel: the render less 255/256 of its max-depth-1 render.
    np.testing.assert_allclose(unvisited._light_seen_once(x, spp=8, seed=3),
                               unseen._render(4, 4, 8, 3) - (7 / 8) * unseen._render(4, 4, 8, 3, max_depth=1))
    # Roulette flipped: the paths of k segments weighted 1 to 4 segments, then 1/4, 1/16, ... from 5.
    r = {k: fresh._mitsuba(x.shape, 8, 3, max_depth=k, rr_depth=100) for k in range(4, 9)}
    want = r[4] + sum(0.25 ** (k - 4) * (r[k] - r[k - 1]) for k in range(5, 9))
    np.testing.assert_allclose(unvisited._roulette_flipped(x, spp=8, seed=3), want, rtol=1e-5, atol=1e-6)


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    check_correct_agree(unvisited, plain)


def test_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    seen, lit = lum > 5, lum < 1

    def image(name):
        return _build(_by_name(name)).image.mean(axis=2)

    # Darker lit surfaces, the light seen right.
    for name, high in (("light_opengl_attenuation", 0.8), ("bounce_times_pdf", 0.7), ("floor_albedo_typed_0_06", 0.7),
                       ("light_sample_cosine_squared", 0.97), ("roulette_comparison_flipped", 0.95)):
        im = image(name)
        assert im[lit].mean() < high * lum[lit].mean(), name
        assert im[seen].mean() == pytest.approx(lum[seen].mean(), rel=0.05), name
    # Brighter lit surfaces.
    for name, low in (("triangle_normal_unnormalised", 5.0), ("pixel_luminance_weighted_mean", 1.5),
                      ("sample_count_uint8", 4.0)):
        assert image(name)[lit].mean() > low * lum[lit].mean(), name
    # The light seen once a pixel: its own pixels 1/256, the rest right.
    im = image("light_seen_once_per_pixel")
    whole = lum > 15
    assert im[whole].mean() < 0.05 * lum[whole].mean()
    assert im[lit].mean() == pytest.approx(lum[lit].mean(), rel=0.05)
    # The strata one short: 15/16 of the image.
    assert image("strata_inner_loop_short").mean() == pytest.approx(15 / 16 * lum.mean(), rel=0.04)


@pytest.mark.parametrize("name", [s.name for s in unvisited.SPECS])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back."""
    check_builds(_by_name(name), tmp_path)
