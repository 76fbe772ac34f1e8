"""The twenty-fifth class (mcrt.grade.accuracy.unremembered) is well formed and builds what its specs say: the same
checks as test_accuracy_unremarked's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x
16, never graded), on this class's cases, the offsets, light samples, bounces, windows and sample loops its Mitsuba
renders are made of.
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
from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unbeknown, unbidden,
                                 unforeseen, unguessed, unheard, unheralded, unlooked, unmet, unnoticed, unprompted,
                                 unremarked, unremembered, unsaid, unseen, unsought, untold, untried, unvisited,
                                 unwonted)
from mcrt.image_files import read_image, srgb_eotf, srgb_oetf

u = unremembered
_by_name = partial(by_name, u.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought, unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted,
           unremarked, unnoticed)  # the last, its twin: written the same day, apart


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


def test_specs_are_new_worded_and_in_categories():
    check_specs(u, _OTHERS, mistakes=28)
    check_new_truths(u, _OTHERS)
    assert len(u.MISTAKES) == 28 and {len(v) for v in u.CATEGORIES.values()} <= {3, 4}
    assert list(u.CATEGORIES) == list(unremarked.CATEGORIES) == list(unlooked.CATEGORIES)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(u)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(u)
    assert sum(s.held_out for s in u.MISTAKES) == 12 and sum(s.held_out for s in u.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    check_old_causes(u, _OTHERS)
    assert u._EARLIER[-1] is unremarked and u._EARLIER[-2] is unwonted


def test_seeds_differ_from_the_other_classes():
    check_seeds(u, _OTHERS, 1201000)


def test_the_command_knows_the_class():
    check_command(u, "unremembered")


def test_correct_writers_read_back(tmp_path):
    """The lossless-WebP PNG and the data-URL PNG read back as their 8-bit codes; JSON's round trip keeps every
    float32."""
    x = _image()
    c8 = blind._srgb8(x)
    for writer, d in ((u._write_png_webp_lossless, "a"), (u._write_png_data_url, "b")):
        (tmp_path / d).mkdir()
        path = writer(x, tmp_path / d)
        np.testing.assert_array_equal(pillow_codes(path), c8)
        np.testing.assert_allclose(read_image(path).mean, srgb_eotf(c8 / 255.0), atol=1e-6)
    np.testing.assert_array_equal(u._json_round_trip(x), x.astype(np.float32))


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    x = _image()
    for d in "abcdefg":
        (tmp_path / d).mkdir()
    c8 = blind._srgb8(x)
    # devicePixelRatio 1.25: the first pixel the source's own, the top-left magnified (pixel 4 from source 3.1).
    codes = pillow_codes(u._write_png_dpr(x, tmp_path / "a")).astype(int)
    np.testing.assert_array_equal(codes[0, 0], c8[0, 0])
    want = c8[0, 3].astype(float) * 0.9 + c8[0, 4].astype(float) * 0.1
    assert np.abs(codes[0, 4] - want).max() <= 0.51 and codes.shape == c8.shape
    # The median of a window sorted as strings: the string order's 5th of the 9 codes.
    m = u._median_string_sorted(c8)
    win = c8[0:3, 0:3, 0].reshape(-1).tolist()
    assert m[1, 1, 0] == sorted(win, key=str)[4]
    np.testing.assert_array_equal(m[0], c8[0])
    assert list(u._STRING_ORDER[:5]) == [0, 1, 10, 100, 101]
    np.testing.assert_array_equal(pillow_codes(u._write_png_median_strings(x, tmp_path / "b")), m)
    # The fade over white: 0.9 c + 25.5, rounded.
    codes = pillow_codes(u._write_png_faded(x, tmp_path / "c")).astype(int)
    np.testing.assert_array_equal(codes, np.round(0.9 * c8 + 25.5).astype(int))
    # fillStyle strings: six digits kept, three doubled, five and seven ignored, eight with alpha.
    assert u._fill_style(200, 100, 50) == ((200, 100, 50), 1.0)
    assert u._fill_style(1, 2, 3) == ((17, 34, 51), 1.0)
    assert u._fill_style(923, 100, 50) is None and u._fill_style(5, 100, 50) is None
    assert u._fill_style(300, 255, 12) == ((0x12, 0xcf, 0xfc), 1.0)
    assert u._fill_style(300, 255, 384) == ((0x12, 0xcf, 0xf1), 0x80 / 255)
    y = x.copy()
    y[2, 5] = 20.0
    codes = pillow_codes(u._write_png_fill_rect(y, tmp_path / "d"))
    np.testing.assert_array_equal(codes[2, 5], codes[2, 4])
    np.testing.assert_array_equal(np.delete(codes.reshape(-1, 3), 2 * 16 + 5, axis=0),
                                  np.delete(c8.reshape(-1, 3), 2 * 16 + 5, axis=0))
    assert u._unclamped_codes(np.full((1, 1, 3), 20.0))[0, 0, 0] == 923
    # WebP at 0.8: near the codes, not equal.
    codes = pillow_codes(u._write_png_webp(x, tmp_path / "e")).astype(int)
    assert 0 < np.abs(codes - c8).mean() < 40
    # Uint8ClampedArray of v * 256: rounded, clamped.
    codes = pillow_codes(u._write_png_clamped_256(y, tmp_path / "f")).astype(int)
    v = srgb_oetf(np.clip(y, 0, 1))
    np.testing.assert_array_equal(codes, np.clip(np.round(v * 256), 0, 255))
    assert codes[2, 5, 0] == 255 and (codes >= c8).all()


def test_post_processes_do_what_they_say():
    x = _image()
    # Cineon: 0 under 0.004, towards 1, three.js's formula.
    t = u._cineon(np.array([0.0, 0.003, 0.5, 1e4]))
    assert t[0] == 0 and t[1] == 0 and 0.49 < t[2] < 0.51 and t[3] == pytest.approx(1.0, abs=1e-3)
    c = 0.5 - 0.004
    assert t[2] == pytest.approx((c * (6.2 * c + 0.5) / (c * (6.2 * c + 1.7) + 0.06)) ** 2.2)
    # Three significant digits.
    np.testing.assert_allclose(u._to_precision(np.array([0.012345, 19.87, 0.0, 1.0049])), [0.0123, 19.9, 0.0, 1.0])
    # Strips placed without the channels: strip k from row k rows / 4, the rest 0.
    s = u._strips_offset_unscaled(x)
    np.testing.assert_allclose(s[0], x[0])
    np.testing.assert_allclose(s[1], x[4])  # strip 1 (rows 4 to 7) from row 1
    np.testing.assert_allclose(s[3:7], x[12:16])
    np.testing.assert_allclose(s[7:], 0.0)
    # Six workers' fractional starts: rows of workers 0 and 3 only.
    assert list(np.flatnonzero(u._rows_written(64))) == list(range(11)) + list(range(32, 43))
    f = u._fractional_rows(x)
    keep = u._rows_written(16)
    np.testing.assert_allclose(f[keep], x[keep])
    assert np.all(f[~keep] == 0) and (~keep).sum() > 8
    # The progress fraction: 11 passes, divided as 10.
    assert u._progress_passes() == 11
    np.testing.assert_allclose(u._passes_over_ten(x), 1.1 * x)


def test_scene_edits_do_what_they_say():
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import Lambertian, Mirror, load_scene

    s = load_scene()
    owner = u._ids_string_sorted()
    assert owner["sphere"] == "ceiling" and owner["tetrahedron"] == "sphere" and owner["floor"] == "floor"
    e = u._materials_by_string_ids(s)
    objs = {o.name: o.material for o in e.objects}
    assert isinstance(objs["tetrahedron"], Mirror) and objs["sphere"] == Lambertian((0.8, 0.8, 0.8))
    walls = {"".join(wl.corners): wl.albedo for wl in e.room.walls}
    assert e.room.ceiling_albedo == (0.75, 0.15, 0.15) and walls["AB"] == (0.55, 0.15, 0.70)
    assert walls["FA"] == (0.8, 0.45, 0.1) and e.room.floor_albedo == s.room.floor_albedo
    a = u._from_array_offset(s)
    walls = {"".join(wl.corners): wl.albedo for wl in a.room.walls}
    assert a.room.floor_albedo == (0.6, 0.6, 0.6) and a.room.ceiling_albedo == (0.6, 0.6, 0.8)
    assert walls["AB"] == (0.6, 0.8, 0.8) and walls["FA"] == (0.15, 0.15, 0.55)
    assert next(o for o in a.objects if o.name == "tetrahedron").material.albedo == (0.15, 0.55, 0.15)
    assert cases.light(radiance=(20 * math.pi,) * 3)(s).light.radiance[0] == pytest.approx(62.83, abs=0.01)
    assert cases.fov(u._FOV_THREE_DEFAULT)(s).cameras["near"].fov_x_deg == 50.0
    # Euler XYZ: wall BC where it was, wall AB in the plane y = -3 turned within it.
    bc = u._euler_xyz_wall((0, -6), (10, -6), -5.0, 5.0)
    assert sorted(map(tuple, np.unique(bc.reshape(-1, 3), axis=0))) == [
        (0, -6, -5), (0, -6, 5), (10, -6, -5), (10, -6, 5)]
    ab = u._euler_xyz_wall((-3, 0), (0, -6), -5.0, 5.0)
    assert np.all(ab[..., 1] == -3.0) and np.ptp(ab[..., 2]) > 10.0
    # The tetrahedron's move, the sphere's wrapped indices.
    np.testing.assert_allclose(u._tetra_bbox_shift(), (0.0, 0.125, -0.725), atol=1e-12)
    verts, index = u._three_sphere(1.5)
    assert len(verts) == 561 and index.max() == 560 and len(index) == 32 * 15 * 2
    np.testing.assert_allclose(np.linalg.norm(verts, axis=1), 1.5)
    tris = u._sphere_uint8_triangles()
    c, _ = unsaid._sphere()
    assert tris[..., 2].min() > c[2] - 0.2  # only the upper rings' vertices
    # The light looking at the origin: its normal towards it, its corners 45 degrees tilted.
    xa, ya, nrm = u._look_at_origin_frame()
    np.testing.assert_allclose(nrm, -np.array([5.0, 0.0, 4.99]) / np.linalg.norm([5.0, 0.0, 4.99]))
    np.testing.assert_allclose(ya, (0.0, 1.0, 0.0), atol=1e-12)
    d = scene_dict(s, "near", 4, 4, 8)
    assert u._light_looking_at_origin(d)["light"].face_count() == 2
    assert u._light_four_triangles(d)["light"].face_count() == 4
    assert u._walls_euler_xyz(d)["wall_AB"].face_count() == 2
    assert u._tetra_bbox_centred(d)["tetrahedron"].face_count() == 4
    assert u._sphere_uint8_indexed(d)["sphere"].face_count() == len(tris)


def test_camera_offsets_and_windows_are_as_they_say():
    rng = np.random.default_rng(1)
    uu, vv = u._chained_jitter(rng, 32, w=4, pixels=5)
    assert uu.shape == (5, 32) and np.array_equal(uu, vv) and uu.std() > 0.2
    sensor = u._viewport_sensor(64, 64)
    assert sensor["fov"] == pytest.approx(math.degrees(2 * math.atan(64 / 300)))
    assert sensor["principal_point_offset_x"] == pytest.approx(-1.84375)
    assert sensor["principal_point_offset_y"] == pytest.approx(0.671875)
    # mulberry32: its first number from the state 0 as JavaScript gives it.
    state = np.zeros(1, np.uint32)
    assert u._mulberry32(state)[0] == pytest.approx(0.26642920868471265, abs=1e-15)
    assert state[0] == 0x6D2B79F5
    state = np.arange(4, dtype=np.uint32)
    draws = np.array([u._mulberry32(state) for _ in range(2000)])
    assert draws.min() >= 0 and draws.max() < 1 and draws.mean() == pytest.approx(0.5, abs=0.03)


def test_light_samples_and_bounces_are_as_they_say():
    rng = np.random.default_rng(3)
    n = unsaid._unit(rng.normal(size=(4000, 3)))
    d, w = u._disk_spread_directions(rng, n)
    cos = np.einsum("ij,ij->i", d, n)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0)
    assert np.all(w == 1.0) and np.all(cos >= math.sqrt(0.5) - 1e-12)
    d, w = u._spherical_y_pole(rng, n)
    t, b = unforeseen._frame_of(n)
    cos = np.einsum("ij,ij->i", d, n)
    assert np.all(cos >= 0.0) and np.abs(np.einsum("ij,ij->i", d, b)).mean() == pytest.approx(2 / 3, abs=0.02)
    d, w = u._spherical_about_normal(rng, n)
    cos = np.einsum("ij,ij->i", d, n)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0)
    assert cos.mean() == pytest.approx(2 / 3, abs=0.02) and np.mean(cos ** 2) == pytest.approx(0.5, abs=0.02)
    d = u._cosine_about(rng, n)
    assert np.einsum("ij,ij->i", d, n).mean() == pytest.approx(2 / 3, abs=0.02)
    # The unshadowed light sample: the geometry term alone; the aliased normal's: darker on average.
    p = np.tile([[5.0, -5.999, 3.0]], (2000, 1))
    inward = np.tile([[0.0, 1.0, 0.0]], (2000, 1))
    rho = np.ones((2000, 3))
    mscene = unsaid._loaded(2)
    got = u._unshadowed_light(mscene, np.random.default_rng(5), p, inward, rho, None)
    q = unbeknown._light_points(np.random.default_rng(5), 2000)
    np.testing.assert_allclose(got[:, 0], unbeknown._geometry(p, inward, q) * 4.0 / math.pi * 20.0)
    right = unbeknown._light_sampled(mscene, np.random.default_rng(6), p, inward, rho, None)
    aliased = u._normal_aliased_light(mscene, np.random.default_rng(6), p, inward, rho, None)
    assert aliased.mean() < 0.9 * right.mean()


def test_mirror_and_samples_are_as_they_say():
    eye = np.array([-1.0, 0.0, 0.0])
    c, radius = unsaid._sphere()
    targets = c + radius * np.array([[-0.9, 0.3, 0.3], [-0.8, -0.5, 0.2]])
    dirs = unsaid._unit(np.vstack([targets, [[10.0, -3.0, 0.0]]]) - eye)
    o = np.tile(eye, (3, 1))
    po, r, used = u._cube_map_reflection(o, dirs)
    _, r0, _ = unsaid._reflected(o, dirs)
    assert list(used) == [1, 1, 0]
    np.testing.assert_allclose(r, r0)
    np.testing.assert_allclose(po[:2], c + (radius + 1e-4) * r[:2])
    np.testing.assert_allclose(po[2], eye)
    # Roulette by the Vector3's length: over 1 never stopped, divided by it.
    full, two = unsaid._loaded(8), unsaid._loaded(2)
    pts = np.array([[10.0, 0.5, -5.0], [4.0, -6.0, 0.5], [5.0, 0.0, 4.99], [9.5, 2.0, 5.0], [5.0, 6.0, 1.0]])
    d = unsaid._unit(pts - eye)
    o = np.tile(eye, (5, 1))
    L8, L2 = unsaid._sampled(full, o, d, 7), unsaid._sampled(two, o, d, 7)
    rho = unsaid._first_albedo(full, o, d)
    got = u._roulette_length_sample(o, d, 7, full=full, direct=two)
    p = np.linalg.norm(rho, axis=1)
    alive = (p > 0) & (np.random.default_rng(7 + 37).random(5) < p)
    want = np.where((p > 0)[:, None], L2 + (L8 - L2) * (alive / np.where(p > 0, p, 1))[:, None], L8)
    np.testing.assert_allclose(got, want, rtol=1e-6)
    assert p[0] == pytest.approx(math.sqrt(3) * 0.6) and alive[0]  # the floor: always kept, divided by 1.04
    # The running mean in float32: the samples' mean.
    x = np.zeros((4, 4, 3))
    L = unbidden._all_samples(4, 4, 64, 5)
    np.testing.assert_allclose(u._running_mean_float32(x, spp=64, seed=5).reshape(16, 3), L.mean(axis=1),
                               rtol=1e-4, atol=1e-5)


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    check_correct_agree(u, plain)


def test_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    lit = lum < 1

    def image(name):
        return _build(_by_name(name)).image

    # pi too bright; 10 % too bright.
    assert image("light_legacy_intensity_pi").mean() == pytest.approx(plain.mean() * math.pi, rel=0.1)
    assert image("passes_float_progress_step").mean() == pytest.approx(plain.mean() * 1.1, rel=0.05)
    # The strips: the bottom rows black.
    assert np.all(image("workers_set_offset_without_channels")[8:] == 0.0)
    # The viewport: a magnified corner, not the view.
    im = image("webgl_viewport_default_300x150")
    assert np.abs(im - plain).mean() > 0.2 * plain.mean()
    # The Cineon curve: nothing over 1.
    assert image("pp_three_cineon_tone_mapping").max() <= 1.0


@pytest.mark.parametrize("name", [s.name for s in u.SPECS])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back."""
    check_builds(_by_name(name), tmp_path)
