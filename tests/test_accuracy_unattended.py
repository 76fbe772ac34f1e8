"""The twenty-eighth class (mcrt.grade.accuracy.unattended) is well formed and builds what its specs say: the same
checks as test_accuracy_unnoticed's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x 16,
never graded), on this class's cases, the light samples, mirror, bounces, cameras and frames its Mitsuba renders are
made of.
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
from mcrt.grade.accuracy import (unrecorded, blind, cases, fresh, novel, outside, programs, unasked, unattended, unbeknown,
                                 unbidden, unforeseen, unguessed, unheard, unheralded, unlooked, unmet, unnoticed,
                                 unprompted, unremarked, unremembered, unsaid, unseen, unsought, untold, untried,
                                 unvisited, unwonted)
from mcrt.image_files import read_image, srgb_eotf, srgb_oetf

_by_name = partial(by_name, unattended.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought, unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted,
           unremarked, unremembered, unnoticed, unrecorded)  # the last, its twin: written the same day, apart


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unattended, _OTHERS, mistakes=28)
    check_new_truths(unattended, _OTHERS)
    assert len(unattended.MISTAKES) == 28 and {len(v) for v in unattended.CATEGORIES.values()} <= {3, 4}
    assert list(unattended.CATEGORIES) == list(unnoticed.CATEGORIES)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unattended)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unattended)
    assert sum(s.held_out for s in unattended.MISTAKES) == 12 and sum(s.held_out for s in unattended.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    check_old_causes(unattended, _OTHERS)
    assert unattended._EARLIER[-1] is unnoticed and unremembered in unattended._EARLIER


def test_seeds_differ_from_the_other_classes():
    check_seeds(unattended, _OTHERS, 1501000)


def test_the_command_knows_the_class():
    check_command(unattended, "unattended")


def test_correct_writers_read_back(tmp_path):
    """One Weekend's P3 with the sRGB curve reads back as its codes; the flipped framebuffer's PNG as the image's."""
    x = _image()
    c8 = blind._srgb8(x)
    for d in "ab":
        (tmp_path / d).mkdir()
    path = unattended._write_ppm_rtow_srgb(x, tmp_path / "a")
    codes = pillow_codes(path)
    np.testing.assert_array_equal(codes, unattended._rtow_srgb_codes(x))
    assert np.abs(codes.astype(int) - c8).max() <= 1
    np.testing.assert_allclose(read_image(path).mean, srgb_eotf(codes / 255.0), atol=1e-6)
    path = unattended._write_png_flipped_framebuffer(x, tmp_path / "b")
    np.testing.assert_array_equal(pillow_codes(path), c8)
    np.testing.assert_allclose(read_image(path).mean, srgb_eotf(c8 / 255.0), atol=1e-6)


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    x = _image()
    for d in "abcd":
        (tmp_path / d).mkdir()
    c8 = blind._srgb8(x)
    # One Weekend's descending loop: the rows upside down.
    path = unattended._write_ppm_rows_from_bottom(x, tmp_path / "a")
    np.testing.assert_array_equal(pillow_codes(path), c8[::-1])
    assert path.read_bytes().startswith(b"P3\n16 16\n255\n")
    # The gamma chapter skipped: int(256 * clamp(v, 0, 0.999)) of the linear value.
    codes = pillow_codes(unattended._write_ppm_rtow_linear(x, tmp_path / "b"))
    np.testing.assert_array_equal(codes, np.floor(256 * np.clip(x, 0, 0.999)).astype(np.uint8))
    assert list(unattended._rtow_linear_codes(np.array([0.0, 0.2, 1.0, 20.0]))) == [0, 51, 255, 255]
    # smallpt's toInt: gamma 2.2, + .5.
    codes = pillow_codes(unattended._write_ppm_smallpt(x, tmp_path / "c"))
    np.testing.assert_array_equal(codes, np.floor(x ** (1 / 2.2) * 255 + 0.5).astype(np.uint8))
    assert list(unattended._smallpt_codes(np.array([0.002, 0.01]))) == [15, 31]
    # The PFM top row first: read upside down.
    got = read_image(unattended._write_pfm_top_first(x, tmp_path / "d")).mean
    np.testing.assert_allclose(got, x[::-1].astype(np.float32))


def test_post_processes_do_what_they_say():
    x = _image()
    # One Weekend's write_color: sqrt, capped at 0.999.
    y = unattended._rtow_write_color(np.array([0.0, 0.25, 0.999, 20.0, -1.0]))
    np.testing.assert_allclose(y, [0.0, 0.5, 0.999, 0.999, 0.0])
    # Narkowicz's ACES fit.
    a = unattended._aces_narkowicz(np.array([0.0, 0.3, 1.0, 20.0]))
    np.testing.assert_allclose(a, [0.0, 0.3 * 0.783 / (0.3 * 1.319 + 0.14), 2.54 / 3.16, 1.0])
    # iq's vignette: 1 nowhere, lowest at the corners, symmetric.
    v = unattended._iq_vignette(np.ones((64, 64, 3)))[..., 0]
    assert v.max() < 1 and v[0, 0] == pytest.approx(v.min()) and v[0, 0] == pytest.approx(0.75, abs=0.01)
    np.testing.assert_allclose(v, v[::-1, ::-1])
    np.testing.assert_allclose(unattended._iq_vignette(x), x * unattended._iq_vignette(np.ones_like(x)))
    # One Weekend's write_color handed a mean: divided by the spp again.
    np.testing.assert_allclose(unattended._divided_again(x), x / 256)


def test_scene_edits_do_what_they_say():
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    s = load_scene()
    inv = unattended._albedos_inv_pi(s)
    assert inv.room.floor_albedo == pytest.approx(tuple(a / math.pi for a in s.room.floor_albedo))
    sph = next(o for o in unattended._sphere_radius2_unsquared(s).objects if o.name == "sphere")
    assert sph.radius == pytest.approx(1.2247, abs=1e-4) and sph.center == (9.5, 2.0, -3.3)
    assert cases.light(radiance=(15.0, 15.0, 15.0))(s).light.radiance == (15.0, 15.0, 15.0)
    # vup = (0, 1, 0): the camera's up +y (rolled -90 degrees about its forward +x).
    np.testing.assert_allclose(cases.roll(-90.0)(s).cameras["near"].up, (0.0, 1.0, 0.0), atol=1e-12)
    assert unattended._APERTURE == pytest.approx(0.05236, abs=1e-4)
    # quad(Q, u, v) with u the second corner: from a to a + b.
    q = unattended._quad_corner_as_edge((1.0, 2.0), (3.0, 5.0), -5.0, 5.0)
    assert sorted(map(tuple, q.reshape(-1, 3).tolist())) == sorted(
        [(1, 2, -5), (4, 7, -5), (4, 7, 5), (1, 2, -5), (4, 7, 5), (1, 2, 5)])
    # combinations(range(4), 3): two faces wound inwards.
    faces = unattended._tetra_combination_faces()
    assert faces.shape == (4, 3, 3) and unattended._inward(faces).sum() == 2
    d = scene_dict(s, "near", 4, 4, 8)
    assert unattended._walls_quad_corner_as_edge(d)["wall_AB"].face_count() == 2
    t = unattended._tetra_normals_by_winding(d)["tetrahedron"]
    assert t.face_count() == 4 and "TwoSided" not in str(t.bsdf())  # one-sided: black from its back
    both = unattended._light_both_faces(d)
    assert both["light_upper"].face_count() == 2 and both["light_upper"].emitter() is not None
    assert unattended._mirror_tinted(d)["sphere"]["bsdf"]["type"] == "conductor"
    assert unattended._no_roulette(d)["integrator"]["rr_depth"] > 50


def test_light_samples_are_as_they_say():
    rng = np.random.default_rng(2)
    q = unattended._triangle_points(rng, 40000)
    lt = unattended._scene().light
    assert np.all(np.abs(q[:, 0] - lt.center[0]) <= 1 + 1e-9) and np.all(np.abs(q[:, 1] - lt.center[1]) <= 1 + 1e-9)
    np.testing.assert_allclose(q[:, :2].mean(axis=0), lt.center[:2], atol=0.02)
    np.testing.assert_allclose(np.var(q[:, 0]), 1 / 3, atol=0.02)  # uniform over the 2 x 2 square
    # The area-measure pdf: n . wi only; twice the light: twice Mitsuba's.
    p, n, qq = np.array([[5.0, 0.0, -5.0]]), np.array([[0.0, 0.0, 1.0]]), np.array([[5.0, 0.0, 4.99]])
    assert unattended._cos_surface(p, n, qq)[0] == pytest.approx(1.0)
    assert unbeknown._geometry(p, n, qq)[0] == pytest.approx(1 / 9.99 ** 2)
    m = np.arange(6.0).reshape(2, 3)
    np.testing.assert_allclose(unattended._light_twice(None, None, None, None, None, m), 2 * m)


def test_bounces_are_as_they_say():
    rng = np.random.default_rng(3)
    n = unsaid._unit(rng.normal(size=(40000, 3)))
    for draw, cosine in ((unattended._normal_plus_unit_vector, True), (unattended._shirley_cosine, True),
                         (unattended._normal_plus_ball, False)):
        d, w = draw(rng, n)
        cos = np.einsum("ij,ij->i", d, n)
        np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0)
        assert np.all(w == 1.0) and np.all(cos >= -1e-9)
        if cosine:  # cosine-weighted: E[cos] = 2/3, E[cos^2] = 1/2
            assert cos.mean() == pytest.approx(2 / 3, abs=0.01) and np.mean(cos ** 2) == pytest.approx(0.5, abs=0.01)
        else:  # nearer the normal than cosine
            assert cos.mean() > 0.7
    # The y-up sample through the z-up ONB: about a tangent, half under the surface.
    d, _ = unattended._y_up_through_onb(rng, n)
    cos = np.einsum("ij,ij->i", d, n)
    assert abs(cos.mean()) < 0.02 and np.mean(cos < 0) == pytest.approx(0.5, abs=0.02)
    u, v = unattended._shirley_onb(n)
    assert np.einsum("ij,ij->i", d, v).mean() == pytest.approx(2 / 3, abs=0.01)
    # One Weekend's second-edition unit vectors: uniform on the sphere.
    s = unattended._unit_vectors(rng, 40000)
    np.testing.assert_allclose(np.linalg.norm(s, axis=1), 1.0)
    np.testing.assert_allclose(s.mean(axis=0), 0.0, atol=0.02)
    np.testing.assert_allclose((s ** 2).mean(axis=0), 1 / 3, atol=0.01)


def test_mirror_cameras_and_frames_are_as_they_say():
    rng = np.random.default_rng(4)
    nrm = np.tile([0.0, 0.0, 1.0], (20000, 1))
    r = np.tile(unsaid._unit(np.array([0.0, 0.2, 1.0])), (20000, 1))
    d, absorbed = unattended._fuzzed(rng, r, nrm)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0)
    assert not absorbed.any() and 0.9 < np.einsum("ij,ij->i", d, r).mean() < 0.99
    r = np.tile(unsaid._unit(np.array([1.0, 0.0, 0.05])), (20000, 1))
    _, absorbed = unattended._fuzzed(rng, r, nrm)
    assert 0.2 < absorbed.mean() < 0.6
    # smallpt's tent: a footprint from -1/4 to 5/4 of the pixel, its mean the pixel's centre.
    f = (3 + rng.random(40000)) / 8
    o, dd = unattended._smallpt_tent(f, np.full(40000, 0.5), w=8, h=8)
    eye, right, up, fwd, k = unsaid._frame()
    s = (dd @ right) / (dd @ fwd) / k  # image-plane x in [-1, 1]
    px = (s + 1) / 2 * 8 - 3
    assert px.min() >= -0.25 - 1e-9 and px.max() <= 1.25 + 1e-9 and px.mean() == pytest.approx(0.5, abs=0.01)
    assert px.min() < -0.2 and px.max() > 1.2
    # Frames blended by a constant 0.1 from black: the weights sum to 1 - 0.9^8.
    w = [unattended._MIX * (1 - unattended._MIX) ** (unattended._FRAMES - 1 - k) for k in range(unattended._FRAMES)]
    assert sum(w) == pytest.approx(1 - 0.9 ** 8)


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    check_correct_agree(unattended, plain)


def test_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    lit = lum < 1
    light = lum > 10

    def image(name):
        return _build(_by_name(name)).image

    # write_color: square roots, at most 0.999.
    im = image("pp_rtow_write_color_before_exr")
    assert im.max() <= 0.999 and im[lit].mean() > 1.5 * plain[lit].mean()
    # Sub-pixels clamped: the light at most 1.
    im = image("pp_smallpt_subpixel_clamp")
    assert im.max() <= 1.0 + 1e-6 and abs(im[lit].mean() / plain[lit].mean() - 1) < 0.1
    # vup = +y: the light on the right, not at the top.
    im = image("camera_rtow_vup_y_kept").mean(axis=2)
    assert im[:, -4:].mean() > 5 * im[:4].mean()
    # The pdf in area measure: the surfaces many times too bright.
    assert image("light_pbrt_pdf_area_measure")[lit].mean() > 5 * plain[lit].mean()
    # Radiance 15: three quarters.
    assert image("light_rtow_cornell_radiance").mean() == pytest.approx(0.75 * plain.mean(), rel=0.1)
    # The light counted twice: the lit surfaces brighter, the light as it was.
    im = image("light_smallpt_e_flag_kept")
    assert im[lit].mean() > 1.3 * plain[lit].mean() and im[light].mean() == pytest.approx(plain[light].mean(),
                                                                                           rel=0.05)
    # Divided twice, blended by 0.1, pi too dark.
    assert image("samples_rtow_write_color_divides_again").max() < 0.1
    assert image("frames_shadertoy_mix_constant").mean() == pytest.approx(0.57 * plain.mean(), rel=0.15)
    assert image("lambertian_pbrt_inv_pi_kept")[lit].mean() < 0.5 * plain[lit].mean()


@pytest.mark.parametrize("name", [s.name for s in unattended.SPECS])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back."""
    check_builds(_by_name(name), tmp_path)
