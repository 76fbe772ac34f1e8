"""The twenty-second class (mcrt.grade.accuracy.unlooked) is well formed and builds what its specs say: the same checks
as test_accuracy_unvisited's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x 16, never
graded), on this class's cases, the light samples, bounces and sample loops its Mitsuba renders are made of.
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
                                 unforeseen, unguessed, unheard, unheralded, unlooked, unmet, unprompted, unsaid,
                                 unseen, unsought, untold, untried, unvisited)
from mcrt.image_files import read_image, srgb_eotf

_by_name = partial(by_name, unlooked.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought, unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited)


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unlooked, _OTHERS, mistakes=28)
    check_new_truths(unlooked, _OTHERS)
    assert len(unlooked.MISTAKES) == 28 and {len(v) for v in unlooked.CATEGORIES.values()} <= {3, 4}
    assert list(unlooked.CATEGORIES) == list(unvisited.CATEGORIES)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unlooked)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unlooked)
    assert sum(s.held_out for s in unlooked.MISTAKES) == 12 and sum(s.held_out for s in unlooked.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    check_old_causes(unlooked, _OTHERS)
    assert unlooked._EARLIER[-1] is unvisited


def test_seeds_differ_from_the_other_classes():
    check_seeds(unlooked, _OTHERS, 901000)


def test_the_command_knows_the_class():
    check_command(unlooked, "unlooked")


def test_correct_writers_read_back(tmp_path):
    """The TGA bottom-up and the 32-bit BMP read back as their 8-bit codes; the EXR of mixed types as the image (its
    blue within half-float's step)."""
    x = _image()
    c8 = blind._srgb8(x)
    for writer, d in ((unlooked._write_tga_bottom_up, "a"), (unlooked._write_bmp32, "b")):
        (tmp_path / d).mkdir()
        path = writer(x, tmp_path / d)
        np.testing.assert_array_equal(pillow_codes(path), c8)
        np.testing.assert_allclose(read_image(path).mean, srgb_eotf(c8 / 255.0), atol=1e-6)
    (tmp_path / "c").mkdir()
    r = read_image(unlooked._write_exr_mixed_types(x, tmp_path / "c")).mean
    np.testing.assert_allclose(r[..., :2], x[..., :2], rtol=1e-6)
    np.testing.assert_allclose(r[..., 2], x[..., 2], rtol=1e-3)


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    x = _image()
    for d in "abcde":
        (tmp_path / d).mkdir()
    c8 = blind._srgb8(x)
    # The Average filter in uint8: a valid PNG that decodes to other codes, right where no sum wrapped.
    codes = pillow_codes(unlooked._write_png_average_uint8(x, tmp_path / "a")).astype(int)
    assert codes.shape == c8.shape and (codes != c8).mean() > 0.3
    np.testing.assert_array_equal(codes[0, :2], c8[0, :2])
    # The encoding from the decoding's formula: black 74, white 255.
    codes = pillow_codes(unlooked._write_png_decode_inverted(x, tmp_path / "b"))
    v = np.clip(x, 0.0, 1.0)
    np.testing.assert_array_equal(codes, np.floor(((v + 0.055) / 1.055) ** (1 / 2.4) * 255 + 0.5))
    np.testing.assert_array_equal(unlooked._decode_inverted_codes(np.array([[[0.0, 1.0, 0.0]]])), [[[74, 255, 74]]])
    # The coarse table: exact at its entries, too dark between 0 and 1/16.
    grid = np.array([[[0.0, 0.0625, 0.5]]])
    np.testing.assert_array_equal(unlooked._coarse_table_codes(grid), blind._srgb8(grid))
    dark = np.full((1, 1, 3), 1 / 32)
    assert unlooked._coarse_table_codes(dark)[0, 0, 0] == 35 and blind._srgb8(dark)[0, 0, 0] == 49
    codes = pillow_codes(unlooked._write_png_coarse_table(x, tmp_path / "c")).astype(int)
    assert np.all(codes <= c8) and np.abs(codes - c8)[x > 0.25].max() <= 1  # chords under the curve
    # The rounded mantissa: within half of RGBE's step, but 256 wraps to 0 for a largest channel just under a power
    # of two (as at pixel (12, 3) of this image).
    y = x.copy()
    y[0, 0] = (0.999, 0.5, 0.25)
    r = read_image(unlooked._write_hdr_rounded_wrapping(y, tmp_path / "d")).mean
    np.testing.assert_allclose(r[0, 0], (0.0, 0.5, 0.25), atol=1e-6)
    e = np.frexp(y.max(axis=2))[1][..., None]
    m = np.round(y * np.ldexp(1.0, 8 - e))
    np.testing.assert_allclose(r, np.where(m == 256, 0, m) * np.ldexp(1.0, e - 8), atol=1e-7)
    assert (m == 256).sum() == 2
    # Pillow's sharpness: the border kept, the inside moved away from its smoothed value.
    codes = pillow_codes(unlooked._write_png_sharpened(x, tmp_path / "e")).astype(int)
    np.testing.assert_array_equal(codes[0], c8[0])
    assert np.abs(codes[1:-1, 1:-1] - c8[1:-1, 1:-1].astype(int)).mean() > 3


def test_post_processes_do_what_they_say():
    from scipy.ndimage import median_filter

    x = _image()
    # The median over the channels too: the 3 x 3 x 3 median, not each channel's 3 x 3.
    m = unlooked._median_all_axes(x)
    np.testing.assert_allclose(m[5, 5, 1], np.median(x[4:7, 4:7, :]))
    assert not np.allclose(m, median_filter(x, size=(3, 3, 1)))
    np.testing.assert_allclose(unlooked._tanh_curve(x), np.tanh(x))
    # Adobe RGB to sRGB: greys kept, a pure green more saturated.
    np.testing.assert_allclose(unlooked._adobe_to_srgb(np.full((1, 1, 3), 0.4)), 0.4, atol=1e-4)
    g = unlooked._adobe_to_srgb(np.array([[[0.2, 0.6, 0.2]]]))[0, 0]
    assert g[1] > 0.6 and g[0] < 0.2 and g[2] < 0.2
    # Grey means, the counter per row.
    np.testing.assert_allclose(unlooked._grey_mean(x), np.repeat(x.mean(axis=2, keepdims=True), 3, axis=2))
    np.testing.assert_allclose(unlooked._count_per_row(np.ones((2, 4, 3)))[1, :, 0], [1, 1 / 2, 1 / 3, 1 / 4])


def test_scene_edits_do_what_they_say():
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    s = load_scene()
    edited = unlooked._albedos_over_sum(s)
    assert edited.room.ceiling_albedo == pytest.approx((1 / 3,) * 3)
    walls = {"".join(w.corners): w.albedo for w in edited.room.walls}
    assert walls["CD"] == pytest.approx((0.75 / 1.6, 0.7 / 1.6, 0.15 / 1.6))
    assert unlooked._over_channel_sum((0.3, 0.2, 0.1)) == (0.3, 0.2, 0.1)
    assert cases.fov(unlooked._FOV_OVER_57)(s).cameras["near"].fov_x_deg == pytest.approx(90.4666, abs=1e-3)
    # The sorted fans: four triangles of the floor's plane, wound up, leaving triangle B C (0, -1.38) uncovered.
    tris = unlooked._fan_sorted_by_x("floor")
    assert tris.shape == (4, 3, 3) and np.all(tris[..., 2] == -5.0)
    assert np.all(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])[:, 2] > 0)
    top = unlooked._fan_sorted_by_x("ceiling")
    assert np.all(top[..., 2] == 5.0) and np.all(np.cross(top[:, 1] - top[:, 0], top[:, 2] - top[:, 0])[:, 2] < 0)
    d = scene_dict(s, "near", 4, 4, 8)
    assert unlooked._floor_ceiling_sorted(d)["floor"].face_count() == 4
    half = unlooked._sphere_upper_half(d)["sphere"]
    assert half.face_count() == 96 + 23 * 192 and half.bbox().min.z == pytest.approx(-3.3, abs=1e-5)


def test_offsets_are_as_they_say():
    rng = np.random.default_rng(1)
    u, v = unlooked._strata_centred_twice(rng, 64, w=4, pixels=5)
    assert u.shape == (5, 64) and np.all((-1 / 8 <= u) & (u < 7 / 8)) and np.all((-1 / 8 <= v) & (v < 7 / 8))
    assert u.mean() == pytest.approx(3 / 8, abs=0.03)
    u, v = unlooked._poisson_disk_shifted(rng, 64, w=4, pixels=3)
    assert u.shape == (3, 64) and np.all((0 <= u) & (u < 1)) and np.all((0 <= v) & (v < 1))
    # One point set a chunk, shifted: the gaps between a pixel's points the same in every pixel (modulo 1).
    np.testing.assert_allclose(np.mod(u[0] - u[1], 1.0), np.mod(u[0, 0] - u[1, 0], 1.0), atol=1e-12)


def test_light_samples_are_as_they_say():
    rng = np.random.default_rng(2)
    q = unbeknown._light_points(rng, 2000)
    wall = np.tile([[5.0, -5.999, 3.0]], (2000, 1))
    inward = np.tile([[0.0, 1.0, 0.0]], (2000, 1))
    g = unbeknown._geometry(wall, inward, q)
    wi = unsaid._unit(q - wall)
    d2 = np.sum((q - wall) ** 2, axis=1)
    np.testing.assert_allclose(unlooked._half_lambert(wall, inward, q), (0.5 * wi[:, 1] + 0.5) ** 2 * wi[:, 2] / d2)
    np.testing.assert_allclose(unlooked._spot_cone(wall, inward, q), g * (wi[:, 2] > 0.5))
    assert not unlooked._spot_cone(wall, inward, q).any()  # the light seen from 69 to 74 degrees off its normal
    np.testing.assert_allclose(unlooked._light_cosine_twice(wall, inward, q), g * wi[:, 2])
    np.testing.assert_allclose(unlooked._light_cosine_clamped(wall, inward, q),
                               wi[:, 1] * np.maximum(wi[:, 2], 0.1) / d2)
    # The walls' normals one off: wall BC (y = -6) takes AB's inward normal, the floor keeps its own.
    p = np.array([[5.0, -5.9999, 3.0], [5.0, 0.0, -4.9999]])
    n = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    shifted = unlooked._previous_wall_normals(p, n)
    np.testing.assert_allclose(shifted[0], -unbeknown._scene().room.planes()[0, :3])
    np.testing.assert_allclose(shifted[1], n[1])
    # From the ray's origin: the eye's geometry term with the surface's normal.
    eye = unsaid._frame()[0]
    got = unlooked._from_ray_origin(unsaid._loaded(2), np.random.default_rng(5), wall[:4], inward[:4],
                                    np.ones((4, 3)), None)
    want = unbeknown._light_sampled(unsaid._loaded(2), np.random.default_rng(5), np.tile(eye, (4, 1)), inward[:4],
                                    np.ones((4, 3)), None)
    np.testing.assert_allclose(got, want)


def test_bounces_are_as_they_say():
    rng = np.random.default_rng(3)
    n = unsaid._unit(rng.normal(size=(4000, 3)))
    d, w = unlooked._square_lifted(rng, n)
    cos = np.einsum("ij,ij->i", d, n)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0)
    assert np.all(w == 1.0) and np.all(cos >= -1e-12)
    # The square's corners outside the unit disk: 1 - pi / 4 of the directions along the tangent plane.
    assert (cos < 1e-9).mean() == pytest.approx(1 - math.pi / 4, abs=0.03)


def test_samples_cut_weighted_or_counted_as_they_say():
    x = np.zeros((4, 4, 3))
    full, two = unsaid._loaded(8), unsaid._loaded(2)
    white = unbeknown._albedo_scene((1.0, 1.0, 1.0))
    eye = np.array([-1.0, 0.0, 0.0])
    dirs = unsaid._unit(np.array([[10.0, 0.5, -5.0], [4.0, -6.0, 0.5], [9.5, 2.0, -3.3], [5.0, 0.0, 4.99]]) - eye)
    o = np.tile(eye, (4, 1))
    L8, L2 = (unsaid._sampled(m, o, dirs, 7) for m in (full, two))
    # Roulette on the radiance: the full sample where the path had light after its first vertex, else that light.
    got = unlooked._roulette_on_radiance_sample(o, dirs, 7, full=full, direct=two)
    np.testing.assert_allclose(got, np.where((L2.max(axis=1) > 0)[:, None], L8, L2))
    assert got[3].max() > 10.0  # the light seen
    # The first albedo only: the white scene's sample times the first albedo, the mirror's and the light's kept.
    rho = unsaid._first_albedo(full, o, dirs)
    got = unlooked._first_albedo_only_sample(o, dirs, 7, full=full, white=white)
    np.testing.assert_allclose(got[:2], rho[:2] * unsaid._sampled(white, o[:2], dirs[:2], 7), rtol=1e-6)
    np.testing.assert_allclose(got[2:], L8[2:])
    # The root mean square and the fancy-index add over a pixel's samples.
    L = unbidden._all_samples(4, 4, 128, 5)
    np.testing.assert_allclose(unlooked._root_mean_square(x, spp=128, seed=5).reshape(16, 3),
                               np.sqrt((L ** 2).mean(axis=1)))
    np.testing.assert_allclose(unlooked._fancy_index_added(x, spp=128, seed=5).reshape(16, 3),
                               (L[:, 63] + L[:, 127]) / 128)
    # The image plane in pixels: a render at the field of view 2 atan(W / 2).
    np.testing.assert_allclose(unlooked._plane_in_pixels(x, spp=4, seed=3),
                               unseen._render(4, 4, 4, 3, sensor={"fov": math.degrees(2 * math.atan(2))}))


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    check_correct_agree(unlooked, plain)


def test_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    seen, lit = lum > 5, lum < 1

    def image(name):
        return _build(_by_name(name)).image.mean(axis=2)

    # Darker lit surfaces, the light seen right.
    for name, high in (("lambert_inv_pi_floor_division", 0.1), ("albedo_energy_check_sum", 0.8),
                       ("light_cosine_twice", 0.95), ("roulette_on_radiance", 0.97)):
        im = image(name)
        assert im[lit].mean() < high * lum[lit].mean(), name
        assert im[seen].mean() == pytest.approx(lum[seen].mean(), rel=0.05), name
    # Brighter lit surfaces.
    for name, low in (("albedo_first_bounce_only", 1.3), ("pixel_root_mean_square", 1.2),
                      ("light_sample_half_lambert", 1.01)):
        assert image(name)[lit].mean() > low * lum[lit].mean(), name
    # A fancy-index add: 4 of 256 samples; the counter per row: column i divided by i + 1.
    assert image("fancy_index_add_batches").mean() < 0.05 * lum.mean()
    im = image("sample_counter_per_row")
    assert im[:, 0].mean() == pytest.approx(lum[:, 0].mean(), rel=0.1) and im[:, -1].mean() < 0.1 * lum[:, -1].mean()


@pytest.mark.parametrize("name", [s.name for s in unlooked.SPECS])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back."""
    check_builds(_by_name(name), tmp_path)
