"""The thirtieth class (mcrt.grade.accuracy.unconsidered) is well formed and builds what its specs say: the same checks
as test_accuracy_unattended's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x 16, never
graded), on this class's cases, the light samples, mirror, bounces, cameras and shared random numbers its Mitsuba
renders are made of, each against values worked out by hand.
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
from mcrt.grade.accuracy import (unattested, blind, cases, fresh, novel, outside, programs, unasked, unattended, unbeknown,
                                 unbidden, unconsidered, unforeseen, unguessed, unheard, unheralded, unlooked, unmet,
                                 unnoticed, unprompted, unrecorded, unremarked, unremembered, unsaid, unseen, unsought,
                                 untold, untried, unvisited, unwonted)
from mcrt.image_files import read_image, srgb_eotf

_by_name = partial(by_name, unconsidered.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought, unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted,
           unremarked, unremembered, unnoticed, unrecorded, unattended, unattested)  # the last, its twin: written the same day, apart


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unconsidered, _OTHERS, mistakes=28)
    check_new_truths(unconsidered, _OTHERS)
    assert len(unconsidered.MISTAKES) == 28 and {len(v) for v in unconsidered.CATEGORIES.values()} <= {3, 4}
    assert list(unconsidered.CATEGORIES) == list(unnoticed.CATEGORIES)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unconsidered)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unconsidered)
    assert sum(s.held_out for s in unconsidered.MISTAKES) == 12 and sum(s.held_out for s in unconsidered.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    check_old_causes(unconsidered, _OTHERS)
    assert unconsidered._EARLIER[-1] is unattended and unrecorded in unconsidered._EARLIER
    assert set(unconsidered._REWORDED) == set(unconsidered.CAUSES)


def test_seeds_differ_from_the_other_classes():
    check_seeds(unconsidered, _OTHERS, 1701000)


def test_the_command_knows_the_class():
    check_command(unconsidered, "unconsidered")


def test_correct_writers_read_back(tmp_path):
    """Haskell's Char8 PPM is the plain P6 of the codes; Java's TYPE_INT_BGR PNG and C#'s PFM read back as the image."""
    x = _image()
    c8 = blind._srgb8(x)
    for d in "abcd":
        (tmp_path / d).mkdir()
    path = unconsidered._write_ppm_char8(x, tmp_path / "a")
    assert path.read_bytes() == blind._write_ppm8(x, tmp_path / "b").read_bytes()
    np.testing.assert_array_equal(pillow_codes(path), c8)
    path = unconsidered._write_png_int_bgr(x, tmp_path / "c")
    np.testing.assert_array_equal(pillow_codes(path), c8)
    np.testing.assert_allclose(read_image(path).mean, srgb_eotf(c8 / 255.0), atol=1e-6)
    path = fresh._write_pfm(x, tmp_path / "d")
    np.testing.assert_allclose(read_image(path).mean, x.astype(np.float32))


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    x = _image()
    for d in "abcdefg":
        (tmp_path / d).mkdir()
    c8 = blind._srgb8(x).astype(int)
    # RescaleOp(1.2f, 15): (int) (1.2 c + 15), clamped.
    codes = pillow_codes(unconsidered._write_png_rescaleop(x, tmp_path / "a"))
    np.testing.assert_array_equal(codes, np.minimum((12 * c8 + 150) // 10, 255))
    assert list(unconsidered._rescaleop_codes(np.array([[[0.0, 0.2, 0.58]]]))[0, 0]) == [15, 163, 255]
    # TYPE_BYTE_GRAY: one grey channel, the luminance of the linearised codes, linear.
    from PIL import Image

    path = unconsidered._write_png_byte_gray(x, tmp_path / "b")
    assert Image.open(path).mode == "L"
    grey = np.asarray(Image.open(path), int)
    expected = np.round(srgb_eotf(c8 / 255.0) @ [0.2125, 0.7154, 0.0721] * 255)
    assert np.abs(grey - expected).max() <= 1
    assert unconsidered._byte_gray_codes(np.full((1, 1, 3), 0.2))[0, 0] == 51
    # Signed bytes: a blue of 128 or more makes red and green 255, a green of 128 or more red 255.
    px = np.array([[[10, 20, 200], [10, 200, 20], [200, 20, 10], [10, 20, 30]]], np.uint8)
    assert unconsidered._signed_bytes_packed(px).tolist() == [[[255, 255, 200], [255, 200, 20], [200, 20, 10],
                                                              [10, 20, 30]]]
    codes = pillow_codes(unconsidered._write_png_signed_bytes(x, tmp_path / "c"))
    high_b, high_g = c8[..., 2] >= 128, c8[..., 1] >= 128
    np.testing.assert_array_equal(codes[..., 2], c8[..., 2])
    np.testing.assert_array_equal(codes[..., 1], np.where(high_b, 255, c8[..., 1]))
    np.testing.assert_array_equal(codes[..., 0], np.where(high_b | high_g, 255, c8[..., 0]))
    # Kotlin's infix: the red channel 0.
    codes = pillow_codes(unconsidered._write_png_infix(x, tmp_path / "d"))
    assert codes[..., 0].max() == 0
    np.testing.assert_array_equal(codes[..., 1:], c8[..., 1:])
    # BlockCopy: the top quarter of the rows (a quarter of the floats), the rest 0, a PFM the right way up.
    got = read_image(unconsidered._write_pfm_block_copied(x, tmp_path / "e")).mean
    np.testing.assert_allclose(got[:4], x[:4].astype(np.float32))
    assert np.all(got[4:] == 0)
    # The dither's wrap: a saturated pixel plus 1 written 0, in a quarter of the positions.
    codes = pillow_codes(unconsidered._write_png_dither_wrapped(np.ones((8, 8, 3)), tmp_path / "f"))
    assert sorted(np.unique(codes).tolist()) == [0, 253, 254, 255]
    assert (codes[..., 0] == 0).mean() == 0.25 and codes[1, 0, 0] == 0 and codes[0, 0, 0] == 253
    assert codes[1, 1, 0] == 254 and codes[0, 1, 0] == 255
    mid = blind._srgb8(np.full((1, 1, 3), 0.5))[0, 0, 0]
    offsets = unconsidered._dither_wrapped_codes(np.full((4, 4, 3), 0.5)).astype(int)[..., 0] - mid
    np.testing.assert_array_equal(offsets, np.tile([[-2, 0], [1, -1]], (2, 2)))
    # ConvolveOp: a black frame, the 3 x 3 mean of the codes inside.
    codes = pillow_codes(unconsidered._write_png_convolveop(x, tmp_path / "g")).astype(int)
    assert codes[0].max() == codes[-1].max() == codes[:, 0].max() == codes[:, -1].max() == 0
    assert abs(codes[5, 7, 1] - c8[4:7, 6:9, 1].mean()) <= 0.5


def test_post_processes_do_what_they_say():
    # Go's median over slices of the row: one row's running maximum carried to its right end.
    row = np.array([[[5.0], [1.0], [4.0], [2.0], [3.0]]]).repeat(3, axis=2)
    out = unconsidered._median_window_sorted(row)[0, :, 0]
    # [5,1,4] -> [1,4,5]; [4,5,2] -> [2,4,5]; [4,5,3] -> [3,4,5]: 1, 2, 3, 4, 5
    assert out.tolist() == [1.0, 2.0, 3.0, 4.0, 5.0]
    x = _image()
    y = unconsidered._median_window_sorted(x)
    assert np.allclose(np.sort(y, axis=1), np.sort(x, axis=1))  # the rows' values kept, moved
    assert np.all(y[:, -1] == x.max(axis=1)) and np.all(y[:, -2] == np.sort(x, axis=1)[:, -2])
    # Go's late goroutines: rows 4, 8, 12 of 16 kept, the rest black.
    z = unconsidered._rows_of_late_workers(x)
    assert [j for j in range(16) if z[j].any()] == [4, 8, 12]
    np.testing.assert_array_equal(z[8], x[8])
    # Swift's stride: 4 batches of 64 over 200.
    assert unconsidered._SPP_BATCHED == 256 and unconsidered._SPP_U8 == 44 and 300 % 256 == 44
    spec = _by_name("batches_swift_stride_last_full")
    np.testing.assert_allclose(spec.post_fn(x), x * 1.28)


def test_scene_edits_do_what_they_say():
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    s = load_scene()
    # Go's two map orders: every surface another's colour, none its own.
    m = unconsidered._albedos_map_order(s)
    assert m.room.floor_albedo == s.room.walls[3].albedo and m.room.ceiling_albedo == (0.8, 0.45, 0.1)
    walls = {"".join(w.corners): w.albedo for w in m.room.walls}
    assert walls["AB"] == (0.8, 0.8, 0.8) and walls["DE"] == (0.75, 0.15, 0.15) and walls["CD"] == (0.6, 0.6, 0.6)
    tetra = next(o for o in m.objects if o.name == "tetrahedron")
    assert tetra.material.albedo == (0.55, 0.15, 0.7)
    assert sorted(unconsidered._MAP_ORDER) == sorted(unconsidered._SURFACES)
    assert all(a != b for a, b in zip(unconsidered._SURFACES, unconsidered._MAP_ORDER))
    # Swift's copy: radius 1, centre kept.
    sph = next(o for o in unconsidered._sphere_default_radius(s).objects if o.name == "sphere")
    assert sph.radius == 1.0 and sph.center == (9.5, 2.0, -3.3)
    # Go's RGBA(): 257 times.
    assert unconsidered._light_rgba16(s).light.radiance == pytest.approx((5140.0,) * 3)
    # glam's reversed quaternion product: forward +y, up +x, the image's right -z.
    cam = unconsidered._camera_quat_reversed(s).cameras["near"]
    r, u, f = cam.frame()
    np.testing.assert_allclose((r, u, f), ((0, 0, -1), (1, 0, 0), (0, 1, 0)), atol=1e-12)
    # Kotlin's toDegrees: tan(2578.31) = -1.362: 107.4 degrees, turned over.
    assert unconsidered._TO_DEGREES_TAN == pytest.approx(-1.36204, abs=1e-4)
    cam = unconsidered._fov_to_degrees(s).cameras["near"]
    assert cam.fov_x_deg == pytest.approx(107.43, abs=0.01)
    np.testing.assert_allclose(cam.up, (0.0, 0.0, -1.0), atol=1e-12)
    # nalgebra's arguments: tan(0.5) down, pi / 2 tan(0.5) across.
    assert math.degrees(2 * math.atan(unconsidered._HALF_WIDTH)) == pytest.approx(81.3, abs=0.05)
    o, dd = unconsidered._perspective_swapped(np.array([1.0, 0.5]), np.array([0.5, 0.0]))
    np.testing.assert_allclose(dd[0] / dd[0, 0], (1.0, -math.pi / 2 * math.tan(0.5), 0.0), atol=1e-12)
    np.testing.assert_allclose(dd[1] / dd[1, 0], (1.0, 0.0, math.tan(0.5)), atol=1e-12)
    # libGDX's sub: vertices changed face after face; by hand for a unit tetrahedron's faces (0, 1, 2), (0, 1, 3).
    v = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]
    t = unconsidered._libgdx_sub_triangles(v, ((1, 2, 3), (0, 1, 3)))
    # face 1: v2 = (-1, 1, 0), v3 = (-1, 0, 1); face 2: v1 -= v0, v3 -= v0 (v0 = 0): unchanged
    np.testing.assert_allclose(t[0], [(1, 0, 0), (0, 1, 0), (0, 0, 1)])
    np.testing.assert_allclose(t[1], [(0, 0, 0), (1, 0, 0), (-1, 0, 1)])
    tris = unconsidered._libgdx_sub_triangles(next(o for o in s.objects if o.name == "tetrahedron").vertices,
                                              unconsidered._tetra_faces())
    assert tris.shape == (4, 3, 3) and tris[:, :, 0].min() == pytest.approx(-21.5)
    own = next(o for o in s.objects if o.name == "tetrahedron").triangles()
    np.testing.assert_allclose(np.asarray(own), np.asarray(next(o for o in s.objects if o.name == "tetrahedron")
                                                           .vertices)[list(unconsidered._tetra_faces())])
    d = scene_dict(s, "near", 4, 4, 8)
    assert unconsidered._tetra_libgdx(d)["tetrahedron"].face_count() == 4
    chunked = unconsidered._walls_chunked(d)
    assert {k for k in d if k.startswith("wall_")} - set(chunked) == {"wall_BC", "wall_DE", "wall_FA"}


def test_light_samples_are_as_they_say():
    p, n = np.array([[5.0, 0.0, -5.0], [5.0, 0.0, -5.0]]), np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
    q = np.array([[5.0, 0.0, 4.99], [4.0, 0.0, 4.99]])
    # C#'s Distance: the geometry term times the distance.
    np.testing.assert_allclose(unconsidered._over_distance(p, n, q)[0], 1 / 9.99)
    assert unconsidered._over_distance(p, n, q)[1] == pytest.approx(
        unbeknown._geometry(p, n, q)[1] * math.hypot(1.0, 9.99))
    # Java's quotient: 0, the corner (4, -1).
    assert (2**31 - 2) // (2**31 - 1) == 0
    np.testing.assert_allclose(unconsidered._light_corner(), (4.0, -1.0, 4.99))
    # Kotlin's dot: the channels' sum in all three.
    m = np.array([[0.75, 0.15, 0.15], [0.6, 0.6, 0.6]])
    np.testing.assert_allclose(unconsidered._light_times_as_dot(None, None, None, None, None, m),
                               [[1.05] * 3, [1.8] * 3])
    # Antithetic pairs and 2 x 2 strata: uniform points of the square (mean centre, variance 1/3 along x).
    rng = np.random.default_rng(5)
    u, v = rng.random((2, 40000))
    pts = np.concatenate([unnoticed._light_points(u, v), unnoticed._light_points(1 - u, 1 - v)])
    np.testing.assert_allclose(pts[:, :2].mean(axis=0), (5.0, 0.0), atol=1e-9)  # antithetic: exactly the centre
    np.testing.assert_allclose(np.var(pts[:, 0]), 1 / 3, atol=0.01)


def _cosine_check(d, n, *, about=None):
    cos = np.einsum("ij,ij->i", d, n if about is None else about)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0)
    return cos


def test_bounces_are_as_they_say():
    rng = np.random.default_rng(3)
    n = unsaid._unit(rng.normal(size=(40000, 3)))
    for draw in (unconsidered._quat_to_normal, unconsidered._normal_plus_gaussian,
                 unconsidered._cosine_in_orthonormal_pair):
        d, w = draw(rng, n)
        cos = _cosine_check(d, n)
        assert np.all(w == 1.0) and np.all(cos >= -1e-9)
        assert cos.mean() == pytest.approx(2 / 3, abs=0.01) and np.mean(cos ** 2) == pytest.approx(0.5, abs=0.01)
    # Duff's basis: orthonormal and right-handed, also for z = 0 and z < 0.
    t, b = unconsidered._orthonormal_pair(n)
    for a, c in ((t, b), (t, n), (b, n)):
        np.testing.assert_allclose(np.einsum("ij,ij->i", a, c), 0.0, atol=1e-9)
    np.testing.assert_allclose(np.cross(t, b), n, atol=1e-9)
    # Rust's integer range: the normal itself.
    d, w = unconsidered._along_normal(rng, n)
    np.testing.assert_array_equal(d, n)
    # Swift's quaternion the wrong way: about 2 (n . z) z - n: the floor right, a wall's about -n.
    walls = np.tile([0.0, 1.0, 0.0], (40000, 1))
    d, _ = unconsidered._quat_from_normal(rng, walls)
    assert _cosine_check(d, walls).mean() == pytest.approx(-2 / 3, abs=0.01)
    for nz in (1.0, -1.0):
        flat = np.tile([0.0, 0.0, nz], (40000, 1))
        d, _ = unconsidered._quat_from_normal(rng, flat)
        assert _cosine_check(d, flat).mean() == pytest.approx(2 / 3, abs=0.01)
    tilt = np.tile(unsaid._unit(np.array([1.0, 0.0, 1.0])), (40000, 1))
    d, _ = unconsidered._quat_from_normal(rng, tilt)
    axis = d.mean(axis=0) / np.linalg.norm(d.mean(axis=0))
    np.testing.assert_allclose(axis, (-1 / math.sqrt(2), 0, 1 / math.sqrt(2)), atol=0.02)
    # The rotation itself: takes from to to, keeps lengths.
    v = unsaid._unit(rng.normal(size=(1000, 3)))
    np.testing.assert_allclose(unconsidered._rotation_arc(np.array([0.0, 0.0, 1.0]), v,
                                                          np.tile([0.0, 0.0, 1.0], (1000, 1))), v, atol=1e-9)


def test_mirror_and_shared_numbers_are_as_they_say():
    # scaleAdd: s d + n; head-on back along d, grazing along n; inwards past 45 degrees.
    n = np.array([[0.0, 0.0, 1.0]] * 3)
    d = np.array([[0.0, 0.0, -1.0], [1.0, 0.0, 0.0], unsaid._unit(np.array([1.0, 0.0, -1.2]))])
    r = unconsidered._scale_add(d, n)
    np.testing.assert_allclose(r[0], (0.0, 0.0, -1.0))
    np.testing.assert_allclose(r[1], (0.0, 0.0, 1.0))
    assert r[2, 2] < 0  # cos 50 degrees: into the ball
    # One jitter a (run, sample): a run's pixels share it.
    u, v = unconsidered._run_offsets(np.random.default_rng(1), 4, 8)
    assert u.shape == v.shape == (32,) and 0 <= u.min() and u.max() < 1
    assert unconsidered._RUN == 16 and 64 * 64 % unconsidered._RUN == 0 and W * W % unconsidered._RUN == 0


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    check_correct_agree(unconsidered, plain)


def test_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    lit = lum < 1
    light = lum > 10

    def image(name):
        return _build(_by_name(name)).image

    # Depth 1: only the light.
    im = image("depth_haskell_until_inverted")
    assert im[lit].max() < 0.05 and im[light].mean() == pytest.approx(plain[light].mean(), rel=0.05)
    # 257 times, and the stride's 1.28.
    assert image("light_go_rgba_sixteen_bit").mean() == pytest.approx(257 * plain.mean(), rel=0.1)
    assert image("batches_swift_stride_last_full").mean() == pytest.approx(1.28 * plain.mean(), rel=0.1)
    # 1 / d: the lit surfaces several times too bright, the light as it was.
    im = image("light_csharp_distance_unsquared")
    assert im[lit].mean() > 3 * plain[lit].mean() and im[light].mean() == pytest.approx(plain[light].mean(),
                                                                                         rel=0.05)
    # The roulette's coin: darker, the light as it was.
    im = image("roulette_kotlin_int_range_coin")
    assert im[lit].mean() < 0.97 * plain[lit].mean()
    # Three walls missing: darker.
    assert image("walls_rust_chunks_for_windows")[lit].mean() < 0.8 * plain[lit].mean()
    # The quarter turn: no light in view, the floor (lit by the light) on the right, the ceiling (not) on the left.
    im = image("camera_glam_quat_order_reversed").mean(axis=2)
    assert im.max() < 10 and im[:, -8:].mean() > im[:, :8].mean()
    # Turned over: the light (at the top of the true view) at the bottom.
    im = image("fov_kotlin_to_degrees").mean(axis=2)
    assert im[-8:].max() > 10 and im[:8].max() < 10


@pytest.mark.parametrize("name", [s.name for s in unconsidered.SPECS])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back."""
    check_builds(_by_name(name), tmp_path)
