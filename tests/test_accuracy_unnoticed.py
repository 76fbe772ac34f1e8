"""The twenty-sixth class (mcrt.grade.accuracy.unnoticed) is well formed and builds what its specs say: the same
checks as test_accuracy_unremarked's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x 16,
never graded), on this class's cases, the light samples, mirror, bounces and sample loops its Mitsuba renders are made
of.
"""

from __future__ import annotations

import math
import struct
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

_by_name = partial(by_name, unnoticed.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought, unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted,
           unremarked, unremembered)  # the last, its twin: written the same day, apart


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unnoticed, _OTHERS, mistakes=28)
    check_new_truths(unnoticed, _OTHERS)
    assert len(unnoticed.MISTAKES) == 28 and {len(v) for v in unnoticed.CATEGORIES.values()} <= {3, 4}
    assert list(unnoticed.CATEGORIES) == list(unremarked.CATEGORIES) == list(unwonted.CATEGORIES)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unnoticed)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unnoticed)
    assert sum(s.held_out for s in unnoticed.MISTAKES) == 12 and sum(s.held_out for s in unnoticed.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    check_old_causes(unnoticed, _OTHERS)
    assert unnoticed._EARLIER[-1] is unremarked and unwonted in unnoticed._EARLIER


def test_seeds_differ_from_the_other_classes():
    check_seeds(unnoticed, _OTHERS, 1301000)


def test_the_command_knows_the_class():
    check_command(unnoticed, "unnoticed")


def test_correct_writers_read_back(tmp_path):
    """The one-line-header PPM and R's edge-to-edge PNG read back as their 8-bit codes."""
    x = _image()
    c8 = blind._srgb8(x)
    for writer, d in ((unnoticed._write_ppm_one_line_header, "a"), (unnoticed._write_png_r_exact, "b")):
        (tmp_path / d).mkdir()
        path = writer(x, tmp_path / d)
        np.testing.assert_array_equal(pillow_codes(path), c8)
        np.testing.assert_allclose(read_image(path).mean, srgb_eotf(c8 / 255.0), atol=1e-6)


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    x = _image()
    h, w = x.shape[:2]
    for d in "abcd":
        (tmp_path / d).mkdir()
    c8 = blind._srgb8(x)
    # R's raster: a white frame, the middle the image shrunk (bilinear).
    codes = pillow_codes(unnoticed._write_png_r_raster(x, tmp_path / "a"))
    assert np.all(codes[0] == 255) and np.all(codes[:, 0] == 255) and np.all(codes[-1] == 255)
    assert not np.all(codes[1:-1, 1:-1] == 255)
    inner = unnoticed._r_raster_codes(c8, extend=0.0)
    np.testing.assert_array_equal(inner, c8)
    # Fortran's record: the 4-byte marker read as the first pixel and a byte, every code 4 bytes late.
    path = unnoticed._write_ppm_fortran_records(x, tmp_path / "b")
    codes = pillow_codes(path)
    stream = struct.pack("<i", c8.size) + c8.tobytes()
    np.testing.assert_array_equal(codes, np.frombuffer(stream[:c8.size], np.uint8).reshape(h, w, 3))
    np.testing.assert_array_equal(codes[0, 2:, 1], c8[0, 1:-1, 0])  # green from the red of the pixel before
    np.testing.assert_array_equal(read_image(path).mean.shape, (h, w, 3))
    # MATLAB's fwrite: the array's memory in column-major order.
    codes = pillow_codes(unnoticed._write_ppm_fwrite(x, tmp_path / "c")).reshape(-1)
    np.testing.assert_array_equal(codes, c8.reshape(-1, order="F"))
    # The table read one entry late: the code of v + 1/1023 (at the table's points).
    v = np.arange(1023.0) / 1023.0
    y = np.broadcast_to(v[:, None, None], (1023, 1, 3))
    got = unnoticed._lut_plus_one_codes(y)[:, 0, 0].astype(int)
    want = np.floor(srgb_oetf((np.arange(1023.0) + 1) / 1023.0) * 255 + 0.5).astype(int)
    np.testing.assert_array_equal(got, want)
    assert got[0] == 3
    codes = pillow_codes(unnoticed._write_png_lut_plus_one(x, tmp_path / "d")).astype(int)
    assert np.all(codes >= c8) and np.abs(codes - c8).max() <= 3


def test_post_processes_do_what_they_say():
    x = _image()
    h, w = x.shape[:2]
    # R's recycling: element (i, j, c) times gains[(i + H j + H W c) % 3].
    g = unnoticed._gains_recycled(x)
    m = x.reshape(-1, 3).mean(axis=0)
    gains = m.mean() / m
    for i, j, c in ((0, 0, 0), (1, 0, 0), (0, 1, 2), (5, 7, 1)):
        assert g[i, j, c] == pytest.approx(x[i, j, c] * gains[(i + h * j + h * w * c) % 3])
    # conv2 'full' cropped: the block up and left of each pixel, zeros outside.
    b = unnoticed._conv2_full_cropped(x)
    np.testing.assert_allclose(b[5, 7], x[3:6, 5:8].mean(axis=(0, 1)))
    np.testing.assert_allclose(b[0, 0], x[0, 0] / 9)
    # The guided filter: a flat image unchanged, the noise smoothed.
    np.testing.assert_allclose(unnoticed._guided_self(np.full((8, 8, 3), 0.3)), 0.3)
    assert unnoticed._guided_self(x * 0.1).std() < (x * 0.1).std()
    # max along the first dimension: every column's largest value 1 in each channel.
    n = unnoticed._max_first_dim(x)
    np.testing.assert_allclose(n.max(axis=0), 1.0)
    np.testing.assert_allclose(n[:, 3], x[:, 3] / x[:, 3].max(axis=0))
    # Julia's ÷, a pass short, R's length.
    np.testing.assert_array_equal(unnoticed._mean_floor_divided(np.array([0.5, 1.5, 20.0])), [0.0, 1.0, 20.0])
    np.testing.assert_allclose(unnoticed._passes_one_short(x), x * 7 / 8)
    np.testing.assert_allclose(unnoticed._divided_by_r_length(x), x / 3)


def test_scene_edits_do_what_they_say():
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    s = load_scene()
    walls = {"".join(wl.corners): wl.albedo for wl in unnoticed._walls_filled_by_column(s).room.walls}
    assert walls["AB"] == (0.75, 0.75, 0.15) and walls["BC"] == (0.15, 0.7, 0.7) and walls["CD"] == (0.15,) * 3
    assert walls["FA"] == (0.7, 0.75, 0.7)
    u8 = unnoticed._albedos_uint8_divided(s)
    assert u8.room.floor_albedo == (1.0, 1.0, 1.0)
    assert {"".join(wl.corners): wl.albedo for wl in u8.room.walls}["BC"] == (1.0, 0.0, 1.0)
    assert next(o for o in u8.objects if o.name == "tetrahedron").material.albedo == (1.0, 0.0, 0.0)
    sph = next(o for o in unnoticed._sphere_sliced_from_1(s).objects if o.name == "sphere")
    assert sph.center == (2.0, -3.3, 1.5) and sph.radius == 1.5
    assert cases.light(center=unnoticed._LIGHT_AT_4)(s).light.center == (5.0, 0.0, 4.0)
    assert unnoticed._FOV_PI_3 == pytest.approx(85.94, abs=0.01)
    assert unnoticed._fov_wider(16, 2) == pytest.approx(math.degrees(2 * math.atan(18 / 16)))
    # The recycled heights: the lower halves under each diagonal.
    q = unnoticed._wall_quad_recycled((0.0, 0.0), (1.0, 0.0), -5.0, 5.0)
    assert sorted(map(tuple, q[0].tolist())) == sorted([(0, 0, -5), (1, 0, -5), (1, 0, 5)])
    assert sorted(map(tuple, q[1].tolist())) == sorted([(0, 0, -5), (1, 0, -5), (0, 0, 5)])
    # Faces transposed: the corners (x0, x1, x2), (y0, y1, y2), (z0, z1, z2).
    tris = np.asarray(fresh._surface("tetrahedron").triangles)
    t = unnoticed._faces_transposed(tris)
    np.testing.assert_allclose(t[:, 0], tris[:, :, 0])
    d = scene_dict(s, "near", 4, 4, 8)
    assert unnoticed._walls_z_recycled(d)["wall_CD"].face_count() == 2
    assert unnoticed._tetra_faces_transposed(d)["tetrahedron"].face_count() == 4
    assert unnoticed._radiance_uniform(d)["light"].face_count() == 2


def test_light_samples_are_as_they_say():
    rng = np.random.default_rng(2)
    u = unnoticed._linspace_strata(rng, 40000)
    assert u.min() >= 0 and u.max() < 1.25 and ((u > 0.25) & (u < 1 / 3)).sum() == 0
    assert u.mean() == pytest.approx(0.625, abs=0.01)
    u = unnoticed._one_based_strata(rng, 40000)
    assert u.min() >= 0 and u.max() < 1 and u.mean() == pytest.approx(0.5, abs=0.01)
    q = unnoticed._light_points(np.array([0.0, 1.0]), np.array([0.5, 0.5]))
    np.testing.assert_allclose(q, [(4.0, 0.0, 4.99), (6.0, 0.0, 4.99)])
    m = np.arange(12.0).reshape(4, 3)
    np.testing.assert_allclose(unnoticed._light_loop_inclusive(None, None, None, None, None, m), m * 1.25)


def test_bounces_are_as_they_say():
    rng = np.random.default_rng(3)
    n = unsaid._unit(rng.normal(size=(20000, 3)))
    for draw, cosine in ((unnoticed._sph2cart_elevation, True), (unnoticed._rejection_plus_normal, True),
                         (unnoticed._cube_plus_normal, False), (unnoticed._azimuth_julia_range, True)):
        d, w = draw(rng, n)
        cos = np.einsum("ij,ij->i", d, n)
        np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0)
        assert np.all(w == 1.0) and np.all(cos >= -1e-9)
        if cosine:  # cosine-weighted: E[cos] = 2/3, E[cos^2] = 1/2
            assert cos.mean() == pytest.approx(2 / 3, abs=0.01) and np.mean(cos ** 2) == pytest.approx(0.5, abs=0.01)
    # The cube's points normalised: not uniform on the sphere (more towards the corners).
    v = unsaid._unit(rng.random((200000, 3)) - 0.5)
    assert np.mean(np.abs(v).min(axis=1)) > 1.05 * np.mean(np.abs(unsaid._unit(rng.normal(size=(200000, 3)))).min(
        axis=1))
    # Julia's rand(0:2π): 7 azimuths.
    t, b = unforeseen._frame_of(n[:1].repeat(2000, axis=0))
    d, _ = unnoticed._azimuth_julia_range(rng, n[:1].repeat(2000, axis=0))
    phi = np.mod(np.arctan2(d @ b[0], d @ t[0]), 2 * math.pi)
    phi = np.round(np.where(np.isclose(phi, 2 * math.pi), 0.0, phi), 6)
    assert set(np.unique(phi)) == set(range(7))


def test_mirror_and_samples_are_as_they_say():
    eye = np.array([-1.0, 0.0, 0.0])
    c, radius = unsaid._sphere()
    targets = c + radius * np.array([[-0.9, 0.3, 0.3], [-0.8, -0.5, 0.2], [-0.7, 0.1, -0.6]])
    dirs = unsaid._unit(np.vstack([targets, [[10.0, -3.0, 0.0]]]) - eye)
    o = np.tile(eye, (4, 1))
    po, r, used = unnoticed._reflect_ifelse(o, dirs)
    assert list(used) == [1, 1, 1, 0]
    np.testing.assert_allclose(np.abs(r[:3]), 1 / math.sqrt(3))
    assert np.all(r[:3, 0] == r[:3, 1]) and np.all(r[:3, 1] == r[:3, 2])
    np.testing.assert_allclose(r[3], dirs[3])
    # Roulette by the smallest channel, divided by the largest.
    full, two = unsaid._loaded(8), unsaid._loaded(2)
    pts = np.array([[10.0, 0.5, -5.0], [4.0, -6.0, 0.5], [5.0, 0.0, 4.99], [9.5, 2.0, -3.3], [5.0, 6.0, 1.0]])
    d = unsaid._unit(pts - eye)
    o = np.tile(eye, (5, 1))
    L8, L2 = unsaid._sampled(full, o, d, 7), unsaid._sampled(two, o, d, 7)
    rho = unsaid._first_albedo(full, o, d)
    got = unnoticed._roulette_vector_if_sample(o, d, 7, full=full, direct=two)
    p = rho.max(axis=1)
    u = np.random.default_rng(7 + 37).random(5)
    alive = (p > 0) & (u < rho.min(axis=1))
    want = np.where((p > 0)[:, None], L2 + (L8 - L2) * (alive / np.where(p > 0, p, 1))[:, None], L8)
    np.testing.assert_allclose(got, want, rtol=1e-6)
    # The float32 sum and the column-major film: each pixel its samples' mean.
    x = np.zeros((4, 4, 3))
    L = unbidden._all_samples(4, 4, 64, 5)
    np.testing.assert_allclose(unnoticed._samples_float32(x, spp=64, seed=5).reshape(16, 3), L.mean(axis=1),
                               rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(unnoticed._film_column_major(x, spp=64, seed=5).reshape(16, 3), L.mean(axis=1))


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    check_correct_agree(unnoticed, plain)


def test_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    lit = lum < 1

    def image(name):
        return _build(_by_name(name)).image

    # The floored mean: the room black, the light kept.
    im = image("pixel_mean_julia_division_sign")
    assert np.all(im[lit] == 0.0) and im.max() >= 19.0
    # Albedos of 0 or 1: the room brighter.
    assert image("albedos_uint8_integer_division")[lit].mean() > 1.3 * plain[lit].mean()
    # A plane of width 0: one colour (within the noise).
    im = image("fov_julia_division_sign")
    assert im.std(axis=(0, 1)).max() < 0.2 * im.mean() and im[..., 2].mean() < 0.5 * im[..., 0].mean()
    # The last column from past the left edge, the rest as rendered.
    im = image("pixel_column_mod_one_based")
    rel = np.abs(im[:, :-1] - plain[:, :-1]).mean() / plain.mean()
    assert rel < 0.15
    # Direct light 25 % too bright: the lit surfaces brighter.
    assert image("light_samples_do_loop_inclusive")[lit].mean() > 1.1 * plain[lit].mean()


@pytest.mark.parametrize("name", [s.name for s in unnoticed.SPECS])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back."""
    check_builds(_by_name(name), tmp_path)
