"""The thirty-first class (mcrt.grade.accuracy.unanticipated) is well formed and builds what its specs say: the same
checks as test_accuracy_unconsidered's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x
16, never graded), on this class's cases, the light samples, mirror, bounces, cameras, sub-pixel offsets and
estimators its Mitsuba renders are made of, each against values worked out by hand.
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import (W, build as _build, by_name, check_builds, check_command, check_correct_agree,
                              check_held_out_rule, check_new_truths, check_not_catalogued, check_old_causes,
                              check_seeds, check_specs, image as _image, pillow_codes, plain as _plain)
from mcrt.grade.accuracy import (unexamined, blind, cases, fresh, novel, outside, programs, unanticipated, unasked, unattended,
                                 unattested, unbeknown, unbidden, unconsidered, unforeseen, unguessed, unheard,
                                 unheralded, unlooked, unmet, unnoticed, unprompted, unrecorded, unremarked,
                                 unremembered, unsaid, unseen, unsought, untold, untried, unvisited, unwonted)
from mcrt.image_files import RGB_TO_XYZ, read_image, srgb_eotf

_by_name = partial(by_name, unanticipated.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought, unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted,
           unremarked, unremembered, unnoticed, unrecorded, unattended, unattested, unconsidered,
           unexamined)  # the last, its twin: written the same day, apart

#: The sphere's centre and radius, the light's centre, size and radiance (scene.md).
_C, _R = np.array([9.5, 2.0, -3.3]), 1.5
_LIGHT_Z, _AREA, _LE = 4.99, 4.0, 20.0


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


@pytest.fixture(scope="module")
def mscene():
    """The canonical scene loaded in Mitsuba (for the shadow rays of the light samples)."""
    return unsaid._loaded(2)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unanticipated, _OTHERS, mistakes=28)
    check_new_truths(unanticipated, _OTHERS)
    assert len(unanticipated.MISTAKES) == 28 and {len(v) for v in unanticipated.CATEGORIES.values()} <= {3, 4}
    assert list(unanticipated.CATEGORIES) == list(unnoticed.CATEGORIES)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unanticipated)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unanticipated)
    assert sum(s.held_out for s in unanticipated.MISTAKES) == 12
    assert sum(s.held_out for s in unanticipated.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    check_old_causes(unanticipated, _OTHERS)
    assert unanticipated._EARLIER[-1] is unconsidered and unattested in unanticipated._EARLIER
    assert set(unanticipated._REWORDED) == set(unanticipated.CAUSES)


def test_seeds_differ_from_the_other_classes():
    check_seeds(unanticipated, _OTHERS, 1801000)


def test_the_command_knows_the_class():
    check_command(unanticipated, "unanticipated")


def test_correct_writers_read_back(tmp_path):
    """The bit-replicated 16-bit PNG holds 257 c exactly; the codes nearest in linear light are the table's argmin."""
    import png

    x = _image()
    c8 = blind._srgb8(x).astype(int)
    for d in "ab":
        (tmp_path / d).mkdir()
    assert unanticipated._bit_replicated(np.array([0, 1, 128, 255], np.uint8)).tolist() == [0, 257, 32896, 65535]
    path = unanticipated._write_png16_replicated(x, tmp_path / "a")
    w, h, rows, info = png.Reader(filename=str(path)).read()
    assert (w, h, info["bitdepth"]) == (W, W, 16)
    np.testing.assert_array_equal(np.array(list(rows)).reshape(W, W, 3), 257 * c8)
    np.testing.assert_allclose(read_image(path).mean, srgb_eotf(c8 / 255.0), atol=1e-6)
    # Nearest in linear light: brute force over the 256 decoded codes.
    path = unanticipated._write_png_nearest_in_linear(x, tmp_path / "b")
    codes = pillow_codes(path).astype(int)
    table = srgb_eotf(np.arange(256) / 255.0)
    np.testing.assert_array_equal(codes, np.argmin(np.abs(table - x[..., None]), axis=-1))
    assert np.abs(codes - c8).max() <= 1
    assert unanticipated._nearest_in_linear(np.array([[[0.0, 1.0, 2.0]]]))[0, 0].tolist() == [0, 255, 255]


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    x = _image()
    for d in "abc":
        (tmp_path / d).mkdir()
    # sRGB's formula with 1 / 2.2: 0.2 -> 115 (124 right), 0.05 -> 55 (63), 0.5 -> 182 (188); 12.92 v below.
    v = np.array([[[0.2, 0.05, 0.5], [0.001, 1.0, 0.0]]])
    assert unanticipated._srgb22_codes(v).tolist() == [[[115, 55, 182], [3, 255, 0]]]
    assert blind._srgb8(v)[0, 0].tolist() == [124, 63, 188]
    assert 1.055 * 0.2 ** (1 / 2.2) - 0.055 == pytest.approx(115 / 255, abs=0.5 / 255)
    codes = pillow_codes(unanticipated._write_png_srgb22(x, tmp_path / "a")).astype(int)
    expected = np.floor((1.055 * x ** (1 / 2.2) - 0.055) * 255 + 0.5)
    np.testing.assert_array_equal(codes, expected)
    assert np.all(codes <= blind._srgb8(x))
    # RGBE with each mantissa its own channel's: (0.03, 0.04, 0.15) -> (245, 163, 153), exponent -2 + 128.
    px = np.array([[[0.03, 0.04, 0.15], [0.3, 0.3, 0.3], [0.0, 0.0, 0.0]]])
    assert unanticipated._rgbe_own_frexp(px).tolist() == [[[245, 163, 153, 126], [153, 153, 153, 127], [0, 0, 0, 0]]]
    got = read_image(unanticipated._write_hdr_own_frexp(px, tmp_path / "b")).mean
    np.testing.assert_allclose(got[0, 0], np.array([245, 163, 153]) / 1024.0, rtol=1e-6)
    np.testing.assert_allclose(got[0, 1], 153 / 512.0, rtol=1e-6)
    assert got[0, 2].max() == 0.0
    # The channels lifted into the largest one's octave: read c 2^(e_max - e_c), within one part in 128.
    y = _image()
    got = read_image(unanticipated._write_hdr_own_frexp(y, tmp_path / "b")).mean
    lift = np.exp2(np.frexp(y.max(axis=2, keepdims=True))[1] - np.frexp(y)[1])
    np.testing.assert_allclose(got, y * lift, rtol=1 / 128)
    # EXPOSURE in stops: pixels times 2, the header's factor 1: read twice as bright.
    path = unanticipated._write_hdr_exposure_stops(x, tmp_path / "c")
    assert b"\nEXPOSURE=1\n" in path.read_bytes()[:80]
    got = read_image(path).mean
    assert np.all(np.abs(got - 2.0 * x) <= 2.0 * x.max(axis=2, keepdims=True) / 128)  # a shared exponent's steps
    assert got.mean() == pytest.approx(2.0 * x.mean(), rel=2e-3)


def test_post_processes_do_what_they_say():
    # Reinhard undone by y / (1 + y): x / (1 + 2 x).
    f = unanticipated._reinhard_inverse_slipped
    np.testing.assert_allclose(f(np.array([0.2, 1.0, 20.0, 0.0])), [1 / 7, 1 / 3, 20 / 41, 0.0])
    # The sRGB buffer decoded by 2.2: 0.01 -> 0.00629, 0.2 -> 0.2031, 1 -> 1, 20 -> 16.958.
    g = unanticipated._srgb_linearised_gamma22
    np.testing.assert_allclose(g(np.array([0.01, 0.2, 1.0, 20.0])), [0.006289, 0.203097, 1.0, 16.9575], rtol=2e-4)
    assert g(np.array([0.001]))[0] == pytest.approx((12.92 * 0.001) ** 2.2)
    # Stops back with exp: (v + 1e-6) ** (1 / ln 2), 0.2 -> 0.09808, 20 -> 75.33.
    s = unanticipated._stops_back_with_exp
    np.testing.assert_allclose(s(np.array([0.2, 20.0, 1.0])), [0.098085, 75.3337, 1.0], rtol=1e-4)
    assert 1 / math.log(2) == pytest.approx(1.4427, abs=1e-4)
    # XYZ and back by the transpose: M^T M, white to (0.626, 1.185, 1.278).
    x = _image()
    np.testing.assert_allclose(unanticipated._xyz_round_trip_transposed(x), x @ (RGB_TO_XYZ.T @ RGB_TO_XYZ).T)
    np.testing.assert_allclose(unanticipated._xyz_round_trip_transposed(np.ones((1, 1, 3)))[0, 0],
                               (0.6257, 1.1848, 1.2782), atol=2e-4)
    np.testing.assert_allclose(RGB_TO_XYZ[1], (0.2126, 0.7152, 0.0722), atol=2e-4)  # the matrix is sRGB's
    # The film over the pixel's area: 16 x 16 pixels of (2/16)^2: times 64.
    np.testing.assert_allclose(unanticipated._over_pixel_area(x), 64.0 * x)
    assert 1 / unanticipated._pixel_area(64, 64) == 1024.0
    # Passes weighted 1 / n: 7/8 and 1/8, the noise of 1 / ((7/8)^2 / 32 + (1/8)^2 / 224) = 41.7 spp.
    np.testing.assert_allclose(unanticipated._inverse_spp_weights(), (7 / 8, 1 / 8))
    assert unanticipated._effective_spp() == pytest.approx(41.67, abs=0.01) and sum(unanticipated._PASSES) == 256


def test_estimator_algebra_is_as_it_says():
    # Paths counted: a diffuse hit's L2 / 4 + (L8 - L2); the light's L8 / 4; the mirror's L8.
    L8 = np.array([[1.0, 1.0, 1.0], [20.0, 20.0, 20.0], [0.5, 0.5, 0.5]])
    L2 = np.array([[0.4, 0.4, 0.4], [20.0, 20.0, 20.0], [0.3, 0.3, 0.3]])
    L1 = np.array([[0.0, 0.0, 0.0], [20.0, 20.0, 20.0], [0.0, 0.0, 0.0]])
    got = unanticipated._paths_counted(L8, L2, L1, np.array([True, False, False]), np.array([False, True, False]))
    np.testing.assert_allclose(got[:, 0], [0.1 + 0.6, 5.0, 0.5])
    # Roulette: 1 / p^2 for the survivors (1 / p is right), 0 for the rest.
    p, u = np.array([0.5, 0.5, 0.8, 0.0]), np.array([0.2, 0.7, 0.1, 0.5])
    np.testing.assert_allclose(unanticipated._roulette_weights(p, u, 2), [4.0, 0.0, 1.5625, 0.0])
    np.testing.assert_allclose(unanticipated._roulette_weights(p, u, 1), [2.0, 0.0, 1.25, 0.0])
    # In expectation over u: 1 / p twice, 1 once.
    uu = np.random.default_rng(2).random(200000)
    assert unanticipated._roulette_weights(np.full(200000, 0.6), uu, 2).mean() == pytest.approx(1 / 0.6, rel=0.01)
    assert unanticipated._roulette_weights(np.full(200000, 0.6), uu, 1).mean() == pytest.approx(1.0, rel=0.01)
    # Survival by the blue wall's luminance: 0.2126 0.15 + 0.7152 0.2 + 0.0722 0.75 = 0.2291; by its largest 0.75.
    rho = np.array([[0.15, 0.20, 0.75]])
    assert unanticipated._luminance(rho)[0] == pytest.approx(0.22908, abs=1e-5) and unanticipated._max_channel(rho)[0] == 0.75


def test_scene_edits_do_what_they_say():
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    s = load_scene()
    # Schlick's average a + (1 - a) / 21: 0.6 -> 13/21, 0.15 -> 0.190476.
    m = unanticipated._albedos_schlick_averaged(s)
    assert m.room.floor_albedo == pytest.approx((13 / 21,) * 3) and m.room.ceiling_albedo == pytest.approx((17 / 21,) * 3)
    ab = next(w for w in m.room.walls if w.corners == ("A", "B"))
    assert ab.albedo == pytest.approx((0.761905, 0.190476, 0.190476), abs=1e-6)
    tetra = next(o for o in m.objects if o.name == "tetrahedron")
    assert tetra.material.albedo == pytest.approx((0.809524, 0.476190, 0.142857), abs=1e-6)
    assert 2 * math.gamma(2) * math.gamma(6) / math.gamma(8) == pytest.approx(1 / 21)  # 2 B(2, 6)
    # The half-area barycentrics: u, v half their value; their test is the triangle doubled about its first vertex.
    tri = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    u, v = unanticipated._half_area_barycentrics(np.array([[0.2, 0.3, 0.0], [1.5, 0.2, 0.0], [2.1, 0.0, 0.0]]), tri)
    np.testing.assert_allclose(u, [0.1, 0.75, 1.05])
    np.testing.assert_allclose(v, [0.15, 0.1, 0.0])
    np.testing.assert_allclose(unanticipated._doubled_about_first(tri[None])[0], [[0, 0, 0], [2, 0, 0], [0, 2, 0]])
    rng = np.random.default_rng(4)
    real = unanticipated._tetra_triangles()[1]
    pts = real[0] + (rng.uniform(-0.5, 2.5, (4000, 1)) * (real[1] - real[0])
                     + rng.uniform(-0.5, 2.5, (4000, 1)) * (real[2] - real[0]))
    u, v = unanticipated._half_area_barycentrics(pts, real)
    theirs = (u >= 0) & (v >= 0) & (u + v <= 1)
    U, V = (2.0 * c for c in unanticipated._half_area_barycentrics(
        pts, unanticipated._doubled_about_first(real[None])[0]))
    np.testing.assert_array_equal(theirs, (U >= 0) & (V >= 0) & (U + V <= 1))
    assert (theirs & (2 * (u + v) > 1)).sum() > 3 * (theirs & (2 * (u + v) <= 1)).sum() - 200  # 3/4 outside
    t4 = unanticipated._doubled_about_first(unanticipated._tetra_triangles()).reshape(-1, 3)
    np.testing.assert_allclose(t4.min(axis=0), (7.5, -6.6, -4.9))
    np.testing.assert_allclose(t4.max(axis=0), (11.5, 0.0, 0.9))
    d = scene_dict(s, "near", 4, 4, 8)
    assert unanticipated._tetra_doubled(d)["tetrahedron"].face_count() == 4
    # The sphere meshed in radians: vertex (1, 0) at 10 rad = (sin 10, 0, cos 10) r from the centre.
    vtx = unanticipated._sphere_degrees_vertices()
    np.testing.assert_allclose(np.linalg.norm(vtx - _C, axis=-1), _R)
    np.testing.assert_allclose(vtx[1, 0], _C + _R * np.array([-0.544021, 0.0, -0.839072]), atol=1e-6)
    np.testing.assert_allclose(vtx[0, 5], _C + (0.0, 0.0, _R), atol=1e-12)  # theta 0: the pole whatever phi
    assert unanticipated._sphere_degrees_triangles().shape == (2 * 18 * 36, 3, 3)
    assert unanticipated._sphere_degrees_mesh(d)["sphere"].face_count() == 1296
    # The walls: up cross(t, n) = +z for wall AB, cross(n, t) = -z; every wall's mesh from z -15 to -5.
    np.testing.assert_allclose(unanticipated._wall_up((-3, 0), (0, -6), reversed_order=False), (0, 0, 1), atol=1e-12)
    np.testing.assert_allclose(unanticipated._wall_up((10, 6), (0, 6), reversed_order=True), (0, 0, -1), atol=1e-12)
    hung = unanticipated._walls_hanging(d)
    for name in ("wall_AB", "wall_BC", "wall_CD", "wall_DE", "wall_EF", "wall_FA"):
        z = np.array(hung[name].vertex_positions_buffer()).reshape(-1, 3)[:, 2]
        assert z.min() == pytest.approx(-15.0) and z.max() == pytest.approx(-5.0)
    # The secant: a half-width sqrt(2), 109.47 degrees.
    assert unanticipated._HALF_WIDTH_SECANT == pytest.approx(math.sqrt(2))
    assert unanticipated._FOV_SECANT == pytest.approx(109.4712, abs=1e-4)
    # The polar pitch: forward up, up -x, right -y (the image's right as in the scene).
    f, r, up = unanticipated._first_person(0.0, 0.0)
    np.testing.assert_allclose((f, r, up), ((1, 0, 0), (0, -1, 0), (0, 0, 1)), atol=1e-12)
    cam = unanticipated._pitch_polar(s).cameras["near"]
    np.testing.assert_allclose(cam.frame(), ((0, -1, 0), (-1, 0, 0), (0, 0, 1)), atol=1e-12)
    assert cam.eye == s.cameras["near"].eye
    # The light turned by 180 rad = 233.24 degrees: normal (0, -sin, cos) = (0, 0.8012, -0.5985), z 4.19 to 5.79.
    assert math.degrees(180.0 % (2 * math.pi)) == pytest.approx(233.2403, abs=1e-4)
    tris = unanticipated._light_turned_triangles()
    n = np.cross(tris[0, 1] - tris[0, 0], tris[0, 2] - tris[0, 0])
    np.testing.assert_allclose(n / np.linalg.norm(n), (0.0, 0.801153, -0.598460), atol=1e-6)
    np.testing.assert_allclose([tris[..., 2].min(), tris[..., 2].max()], [4.188847, 5.791153], atol=1e-6)
    assert set(np.round(tris[..., 0].ravel(), 9)) == {4.0, 6.0}
    straight = unanticipated._light_turned_triangles(math.pi)
    n = np.cross(straight[0, 1] - straight[0, 0], straight[0, 2] - straight[0, 0])
    np.testing.assert_allclose(n / np.linalg.norm(n), (0, 0, -1), atol=1e-12)  # pi: the scene's light
    np.testing.assert_allclose(straight[..., 2], _LIGHT_Z)
    assert unanticipated._light_turned(d)["light"].face_count() == 2


def test_light_samples_are_as_they_say(mscene):
    p = np.array([[5.0, 0.0, -4.9999]])
    up = np.array([[0.0, 0.0, 1.0]])
    q = np.array([[5.0, 0.0, _LIGHT_Z]])
    d2 = (_LIGHT_Z + 4.9999) ** 2
    # The balance heuristic's weight 1 / (1 + A G / pi): under the light's centre 0.98726.
    assert unanticipated._mis_light_weight(p, up, q)[0] == pytest.approx(1 / (1 + _AREA / (math.pi * d2)))
    assert unanticipated._mis_light_weight(p, up, q)[0] == pytest.approx(0.98741, abs=1e-5)
    # Lambert's cosine from the horizon: its sine; 0 straight below, sin 60 for cos 60.
    assert unanticipated._lambert_from_horizon(p, up, q)[0] == 0.0
    tilted = np.array([[math.sin(math.pi / 3), 0.0, 0.5]])
    assert unanticipated._lambert_from_horizon(p, tilted, q)[0] == pytest.approx(math.sqrt(3) / 2 / d2)
    assert unbeknown._geometry(p, tilted, q)[0] == pytest.approx(0.5 / d2)
    # Rays that meet the light: straight up from under it at t 9.99; past its edge, down, or from above it, not.
    pts = np.array([[5.0, 0.0, -4.9999], [5.0, 0.0, -4.9999], [5.0, 0.0, -4.9999], [5.0, 0.0, 4.995]])
    dirs = unsaid._unit(np.array([[0.0, 0.0, 1.0], [3.0, 0.0, 1.0], [0.0, 0.0, -1.0], [0.0, 0.0, 1.0]]))
    hit, qq, t = unanticipated._light_hit(mscene, pts, dirs)
    assert hit.tolist() == [True, False, False, False]
    assert t[0] == pytest.approx(_LIGHT_Z + 4.9999) and qq[0] == pytest.approx((5.0, 0.0, _LIGHT_Z))
    # The samples at one point under the light, many lanes: the Jacobian's scale halves the right estimate; the
    # cosine rays weighted 1 / A give A cos / pi = 1.27 of it; the ramp and the balance heuristic give it.
    m = 40000
    P, N, rho = np.repeat(p, m, axis=0), np.repeat(up, m, axis=0), np.full((m, 3), 0.5)
    right = unbeknown._light_sampled(mscene, np.random.default_rng(1), P, N, rho, None)
    half = unanticipated._light_jacobian_scale(mscene, np.random.default_rng(1), P, N, rho, None)
    np.testing.assert_allclose(half, 0.5 * right)
    exact = right.mean()
    rays = unanticipated._light_by_cosine_rays(mscene, np.random.default_rng(2), P, N, rho, None)
    assert rays.mean() == pytest.approx(4 / math.pi * exact, rel=0.05)
    ramp = unanticipated._light_ramp(mscene, np.random.default_rng(3), P, N, rho, None)
    assert ramp.mean() == pytest.approx(exact, rel=0.01)
    mis = unanticipated._light_mis_balance(mscene, np.random.default_rng(4), P, N, rho, None)
    assert mis.mean() == pytest.approx(exact, rel=0.02)
    miss = unanticipated._light_mis_half(mscene, np.random.default_rng(5), P, N, rho, None)
    assert miss.mean() == pytest.approx(0.9874 * exact, rel=0.005)
    # The ramp's inverse CDF: sqrt(1 + 3 u) - 1, 0 -> 0, 1/2 -> 0.5811, 1 -> 1; its mean 5/9.
    np.testing.assert_allclose(unanticipated._light_ramp_point(np.array([0.0, 0.5, 1.0])), [0.0, 0.581139, 1.0],
                               atol=1e-6)
    a = unanticipated._light_ramp_point(np.random.default_rng(6).random(200000))
    assert a.mean() == pytest.approx(5 / 9, abs=0.003)


def _cosine_check(d, n):
    cos = np.einsum("ij,ij->i", d, n)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0)
    assert np.all(cos >= -1e-9)
    return cos


def test_bounces_are_as_they_say():
    rng = np.random.default_rng(3)
    n = unsaid._unit(rng.normal(size=(40000, 3)))
    # theta uniform: E[cos] = 2 / pi, weights 2 cos: 4 / pi under a uniform sky.
    d, w = unanticipated._theta_uniform(rng, n)
    cos = _cosine_check(d, n)
    assert cos.mean() == pytest.approx(2 / math.pi, abs=0.01) and w.mean() == pytest.approx(4 / math.pi, abs=0.01)
    np.testing.assert_allclose(w, 2 * cos)
    # cos = 1 - sqrt(u): density 2 (1 - c), E[cos] = 1/3, E[cos^2] = 1/6, weight 1.
    d, w = unanticipated._inverse_cdf_slipped(rng, n)
    cos = _cosine_check(d, n)
    assert cos.mean() == pytest.approx(1 / 3, abs=0.01) and np.mean(cos ** 2) == pytest.approx(1 / 6, abs=0.01)
    assert np.all(w == 1.0)
    # Uniform with the sphere's pdf: E[cos] = 1/2, weights 4 cos: twice the right 1.
    d, w = unanticipated._uniform_sphere_pdf(rng, n)
    cos = _cosine_check(d, n)
    assert cos.mean() == pytest.approx(0.5, abs=0.01) and w.mean() == pytest.approx(2.0, abs=0.02)
    # Rejection: cosine-weighted (E[cos] 2/3, E[cos^2] 1/2), weight 1.
    d, w = unanticipated._cosine_by_rejection(rng, n)
    cos = _cosine_check(d, n)
    assert cos.mean() == pytest.approx(2 / 3, abs=0.01) and np.mean(cos ** 2) == pytest.approx(0.5, abs=0.01)
    assert np.all(w == 1.0)
    # theta uniform with its Jacobian: E[w g] = the integral of g cos / pi: 1 for g = 1, 2/3 for g = cos.
    d, w = unanticipated._theta_uniform_jacobian(rng, n)
    cos = _cosine_check(d, n)
    assert w.mean() == pytest.approx(1.0, abs=0.01) and np.mean(w * cos) == pytest.approx(2 / 3, abs=0.01)
    # Directions about a normal: polar cosine and azimuth as asked.
    z = np.tile([0.0, 0.0, 1.0], (3, 1))
    dz = unanticipated._about_normal(z, np.array([1.0, 0.5, 0.0]), np.array([0.0, 0.0, math.pi / 2]))
    np.testing.assert_allclose(dz[:, 2], [1.0, 0.5, 0.0], atol=1e-12)


def test_mirror_is_as_it_says():
    z = np.array([[0.0, 0.0, 1.0]])
    d = np.array([[-0.6, 0.0, -0.8]])
    # Rodrigues' half turn in radians: the tangential part (0.6, 0) of -d turned 233.24 degrees; pi: the reflection.
    np.testing.assert_allclose(unanticipated._reflect_rodrigues(d, z)[0],
                               (0.6 * -0.598460, 0.6 * -0.801153, 0.8), atol=1e-6)
    np.testing.assert_allclose(unsaid._unit(unanticipated._rodrigues(-d, z, math.pi))[0], (-0.6, 0.0, 0.8), atol=1e-12)
    # The latitude in the polar angle's formula: up at the equator, horizontal at the pole, (0.8, 0, 0.6) at 53 deg.
    q = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.0, -1.0, 0.0]])
    np.testing.assert_allclose(unanticipated._normal_from_latitude(q),
                               [[0, 0, 1], [1, 0, 0], [0.8, 0, 0.6], [0, 0, 1]], atol=1e-12)
    rng = np.random.default_rng(8)
    qq = unsaid._unit(rng.normal(size=(1000, 3)))
    np.testing.assert_allclose(np.linalg.norm(unanticipated._normal_from_latitude(qq), axis=1), 1.0)
    # A ray at the sphere's equator from the side: the wrong normal is up, the ray goes on into the ball (from just
    # inside it); one at its top from above: the wrong normal horizontal.
    o = np.array([_C + (-5.0, 0.0, 0.0), _C + (0.0, 0.0, 5.0), _C + (-5.0, 3.0, 0.0)])
    dirs = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])
    start, r, used = unanticipated._mirror_after(o, dirs, turn=unanticipated._reflect_latitude_normal)
    assert used.tolist() == [1, 1, 0]
    np.testing.assert_allclose(start[0], _C + (-_R + 1e-4, 0.0, 0.0))
    np.testing.assert_allclose(r[0], (1.0, 0.0, 0.0), atol=1e-12)
    np.testing.assert_allclose(r[1], (0.0, 0.0, -1.0), atol=1e-12)  # d . n = 0 for the horizontal (1, 0, 0)
    np.testing.assert_allclose(start[2], o[2])
    np.testing.assert_allclose(r[2], dirs[2])
    # The Rodrigues mirror sends every ray outwards (its normal part is the reflection's).
    hit_o = np.tile(np.array([-1.0, 0.0, 0.0]), (500, 1))
    aim = unsaid._unit(_C + rng.uniform(-1.0, 1.0, (500, 3)) - hit_o)
    start, r, used = unanticipated._mirror_after(hit_o, aim, turn=unanticipated._reflect_rodrigues)
    h = used == 1
    qh = unsaid._unit(start[h] - _C)
    np.testing.assert_allclose(np.einsum("ij,ij->i", r[h], qh), -np.einsum("ij,ij->i", aim[h], qh), atol=1e-3)


def test_sub_pixel_offsets_are_as_they_say():
    rng = np.random.default_rng(5)
    u, v = unanticipated._hammersley_unwrapped(rng, 8, w=4, pixels=6)
    assert u.shape == v.shape == (6, 8) and 0 <= u.min() and u.max() < 2 and v.max() < 2
    shift_u, shift_v = u[:, :1], v[:, :1]  # the first point is (0, 0)
    np.testing.assert_allclose(u - shift_u, np.tile(np.arange(8) / 8, (6, 1)), atol=1e-12)
    np.testing.assert_allclose(v - shift_v, np.tile([0, 0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875], (6, 1)),
                               atol=1e-12)
    assert (u > 1).any()  # past the pixel: no mod 1
    u, v = unanticipated._two_triangles(rng, 100000, w=4, pixels=2)
    assert 0 <= u.min() and u.max() < 1 and 0 <= v.min() and v.max() < 1
    assert u.mean() == pytest.approx(0.5, abs=0.005) and np.var(v) == pytest.approx(1 / 12, abs=0.002)
    quarters = np.histogram2d(u.ravel(), v.ravel(), bins=2, range=[[0, 1], [0, 1]])[0] / u.size
    np.testing.assert_allclose(quarters, 0.25, atol=0.005)
    assert np.mean(u + v > 1) == pytest.approx(0.5, abs=0.005)


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    check_correct_agree(unanticipated, plain)


def test_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    lit = lum < 1
    light = lum > 10

    def image(name):
        return _build(_by_name(name)).image

    # The paths counted: the light seen a quarter, the lit surfaces darker (their direct light a quarter).
    im = image("split_paths_counted")
    assert im[light].mean() == pytest.approx(plain[light].mean() / 4, rel=0.05)
    assert im[lit].mean() < 0.8 * plain[lit].mean()
    # Over the pixel area: 64 times at 16 x 16.
    assert image("film_over_pixel_area").mean() == pytest.approx(64 * plain.mean(), rel=0.1)
    # No walls: the room dark. Looking up: no light in view.
    assert image("walls_up_cross_reversed")[lit].mean() < 0.6 * plain[lit].mean()
    assert image("camera_pitch_polar_angle").max() < 10
    # The light tilted to the left: the right half darker than the left.
    im = image("light_rotate_x_180_radians")
    right, left = lit[:, W // 2:], lit[:, :W // 2]
    ratio_right = im[:, W // 2:][right].mean() / plain[:, W // 2:][right].mean()
    ratio_left = im[:, :W // 2][left].mean() / plain[:, :W // 2][left].mean()
    assert ratio_right < 0.6 and ratio_right < ratio_left
    # Direct light halved; indirect doubled; survivors over-weighted.
    assert image("light_jacobian_scale_not_determinant")[lit].mean() < 0.85 * plain[lit].mean()
    assert image("bounce_uniform_sphere_pdf")[lit].mean() > 1.2 * plain[lit].mean()
    assert image("roulette_divided_twice")[lit].mean() > 1.08 * plain[lit].mean()
    # The secant's wider view: the light (plane height 4.99 / 6 = 0.83 up) nearer the centre, 0.83 / sqrt(2) = 0.59.
    im = image("fov_half_width_secant").mean(axis=2)
    row = np.argmax(im.max(axis=1))
    assert row == int((1 - 4.99 / 6 / math.sqrt(2)) / 2 * W) and row > np.argmax(lum.max(axis=1)) + 1


@pytest.mark.parametrize("name", [s.name for s in unanticipated.SPECS])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back."""
    check_builds(_by_name(name), tmp_path)
