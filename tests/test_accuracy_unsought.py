"""The fourteenth class (mcrt.grade.accuracy.unsought) is well formed and builds what its specs say: the same checks as
test_accuracy_unasked's (specs, writers read back, post-processes, scene edits, a few hand-ins built at 16 x 16, never
graded), on this class's cases, the rays its Mitsuba renders trace and the samples its loops add up.
"""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import (H, W, build as _build, by_name, check_builds, check_held_out_rule,
                              check_not_catalogued, check_specs, image as _image, plain as _plain)
from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unheard, unmet, unsaid,
                                 unseen, unsought, untold, untried)
from mcrt.image_files import read_image, srgb_eotf

_by_name = partial(by_name, unsought.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unsought, _OTHERS, mistakes=28)
    assert all(s.truth for s in unsought.SPECS)
    truths = {s.truth for m in _OTHERS for s in m.SPECS}
    assert not truths & {s.truth for s in unsought.SPECS}


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unsought)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unsought)
    assert sum(s.held_out for s in unsought.MISTAKES) == 12 and sum(s.held_out for s in unsought.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    assert unsought.NEW_CAUSES == {}
    old = set(cases.CAUSES) | set(outside.CAUSES) | {c for m in _OTHERS for c in getattr(m, "NEW_CAUSES", ())}
    assert {s.cause for s in unsought.MISTAKES} <= old


def test_the_command_knows_the_class():
    import importlib

    from mcrt.grade.accuracy.cli import CLASSES

    assert importlib.import_module(f"mcrt.grade.accuracy.{CLASSES['unsought']}").SPECS is unsought.SPECS


def test_correct_writers_read_back(tmp_path):
    """scikit-image's PNG, Pillow's PPM and the PIZ EXR read back as what was written."""
    x = _image()
    for d in "abc":
        (tmp_path / d).mkdir()
    np.testing.assert_allclose(read_image(unsought._write_png_skimage(x, tmp_path / "a")).mean,
                               srgb_eotf(blind._srgb8(x) / 255.0), atol=1e-6)
    np.testing.assert_allclose(read_image(unsought._write_ppm_pillow(x, tmp_path / "b")).mean,
                               srgb_eotf(blind._srgb8(x) / 255.0), atol=1e-6)
    np.testing.assert_allclose(read_image(unsought._write_exr_piz(x, tmp_path / "c")).mean, x, rtol=1e-6)


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    x = _image()
    for d in "abcd":
        (tmp_path / d).mkdir()
    # The EXR's R, G, B hold the green, the blue and the red.
    np.testing.assert_allclose(read_image(unsought._write_exr_gbr(x, tmp_path / "a")).mean, x[..., [1, 2, 0]],
                               rtol=1e-6)
    # Red and green sRGB-encoded, blue linear codes.
    codes = unsought._srgb_red_green(x)
    np.testing.assert_array_equal(codes[..., :2], blind._srgb8(x)[..., :2])
    np.testing.assert_array_equal(codes[..., 2], np.floor(x[..., 2] * 255 + 0.5).astype(np.uint8))
    r = read_image(unsought._write_png_srgb_red_green(x, tmp_path / "b")).mean
    np.testing.assert_allclose(r, srgb_eotf(codes / 255.0), atol=1e-6)
    # The red plane one sample late: one pixel right, each row's first red the row above's last.
    late = unsought._red_one_late(x)
    c8 = blind._srgb8(x)
    np.testing.assert_array_equal(late[:, 1:, 0], c8[:, :-1, 0])
    np.testing.assert_array_equal(late[1:, 0, 0], c8[:-1, -1, 0])
    assert late[0, 0, 0] == 0
    np.testing.assert_array_equal(late[..., 1:], c8[..., 1:])
    np.testing.assert_allclose(read_image(unsought._write_png_red_one_late(x, tmp_path / "c")).mean,
                               srgb_eotf(late / 255.0), atol=1e-6)
    # Video range: black at 16, white (and the light) at 235.
    assert list(unsought._video_range(np.array([[[0.0, 1.0, 20.0]]]))[0, 0]) == [16, 235, 235]
    v = read_image(unsought._write_png_video_range(x, tmp_path / "d")).mean
    assert v.min() >= srgb_eotf(np.array(16 / 255.0)) - 1e-6 and v.max() <= srgb_eotf(np.array(235 / 255.0)) + 1e-6


def test_post_processes_do_what_they_say():
    x = _image()
    # A rotation by 0 changes nothing; by 2 degrees the centre stays, the corners move.
    np.testing.assert_allclose(unsought._rotated(x, deg=0.0), x, atol=1e-12)
    r = unsought._rotated(x)
    assert r.shape == x.shape and not np.allclose(r, x)
    # Only the dark pixels change.
    dark = unsought._dark_blurred(np.concatenate([0.1 * x, x], axis=1))
    np.testing.assert_allclose(dark[:, W:], x)
    assert not np.allclose(dark[:, :W], 0.1 * x)
    # An opening never brightens, and a lone bright pixel on black is removed.
    o = unsought._opened(x)
    assert np.all(o <= x + 1e-12)
    spot = np.zeros((H, W, 3))
    spot[5, 5] = 20.0
    assert np.all(unsought._opened(spot) == 0.0)
    # YCbCr there and back with the same matrices is the identity; mismatched it keeps grey grey only in Y's scale.
    m = unsought._ycbcr(0.299, 0.114)
    np.testing.assert_allclose(np.linalg.inv(m) @ m, np.eye(3), atol=1e-12)
    y = unsought._ycbcr_mismatched(x)
    assert y.shape == x.shape and 0.005 < np.abs(y - x).mean() < 0.1
    grey = unsought._ycbcr_mismatched(np.full((1, 1, 3), 0.5))
    np.testing.assert_allclose(grey, 0.5, atol=1e-9)
    # The first column black, the rest untouched.
    f = unsought._first_column_unrendered(x)
    assert np.all(f[:, 0] == 0.0)
    np.testing.assert_allclose(f[:, 1:], x[:, 1:])


def test_scene_edits():
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    s = load_scene()
    d = scene_dict(s, "near", 4, 4, 8)  # sets Mitsuba's variant too

    import mitsuba as mi

    assert unsought._floor_two_numbers(s).room.floor_albedo == (0.6, 0.6, 0.0)
    assert cases.wall_albedo("CD", (0.57, 0.7, 0.15))(s).room.walls[2].albedo == (0.57, 0.7, 0.15)
    cam = unsought._camera_space(s).cameras["near"]
    assert cam.forward == (0.0, 0.0, -1.0) and cam.up == (0.0, 1.0, 0.0)
    np.testing.assert_allclose(cam.frame()[0], (1.0, 0.0, 0.0), atol=1e-12)  # camera-space x is the world's x
    # Each wall split in two meshes of a triangle, wall k's in the colours of walls 2k % 6 and (2k + 1) % 6.
    walls = unsought._wall_colours(d)
    assert "wall_AB" not in walls and all(f"wall_{w}_{m}" in walls for w in ("AB", "CD", "FA") for m in (0, 1))
    albedo = lambda mesh: np.array(mi.traverse(mesh.bsdf())["brdf_0.reflectance.value"]).ravel()  # noqa: E731
    np.testing.assert_allclose(albedo(walls["wall_BC_0"]), s.room.walls[2].albedo, rtol=1e-6)
    np.testing.assert_allclose(albedo(walls["wall_DE_1"]), s.room.walls[1].albedo, rtol=1e-6)
    # Every triangle shrunk by 0.94 about its centroid: areas 0.94^2 of the scene's.
    shrunk = unsought._edge_tolerance(d)
    for name in ("wall_BC", "floor", "tetrahedron", "light"):
        assert shrunk[name].surface_area()[0] == pytest.approx(0.94 ** 2 * d[name].surface_area()[0], rel=1e-4)
    assert shrunk["light"].emitter() is not None
    # The tetrahedron's faces split into those facing the eye (two-sided) and those facing away (wound inwards).
    tetra = np.asarray(fresh._surface("tetrahedron").triangles)
    away = unsought._faces_away(tetra, s.cameras["near"].eye)
    assert 0 < away.sum() < 4
    t = unsought._tetra_normals_to_eye(d)
    total = t["tetrahedron"].surface_area()[0] + t["tetrahedron_away"].surface_area()[0]
    assert total == pytest.approx(d["tetrahedron"].surface_area()[0], rel=1e-5)
    # The light's square vertical, facing -y, the same area.
    tris = unsought._light_xz_tris()
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    assert np.all(n[:, 1] < 0) and np.allclose(n[:, [0, 2]], 0) and np.allclose(tris[..., 1], 0.0)
    xz = unsought._light_xz(d)["light"]
    assert xz.emitter() is not None and xz.surface_area()[0] == pytest.approx(4.0, rel=1e-5)
    four = unsought._light_four_squares(d)["light"]
    assert four.surface_area()[0] == pytest.approx(4.0, rel=1e-5) and four.face_count() == 8
    assert sorted(unsought._strata_centres(4))[0] == (4.25, -0.75) and len(unsought._strata_centres(4)) == 16
    spec = unsought._mirror_over_pi(d)["sphere"]["bsdf"]["specular_reflectance"]["value"]
    assert spec == pytest.approx([1 / np.pi] * 3)
    sph = unsought._sphere_transformed(d)["sphere"]
    assert "center" not in sph and "to_world" in sph
    mi.load_dict(dict(unsought._sphere_transformed(d)))  # loads


def test_rays_of_the_camera_and_mirror_mistakes():
    rng = np.random.default_rng(2)
    fx, fy = rng.random((2, 64))
    _, r, u, f, _ = unsaid._frame()
    # Rows of 100 at h = 50: the columns as the pinhole's, the rows the top half of the view.
    _, d = unsought._rows_of_100(fx, fy, h=50)
    _, p = unsaid._pinhole(fx, fy)
    np.testing.assert_allclose((d @ r) / (d @ f), (p @ r) / (p @ f), atol=1e-12)
    np.testing.assert_allclose((d @ u) / (d @ f), 1.0 - fy, atol=1e-12)
    # Integer division: four places in the view, each a pixel's worth wide.
    _, d = unsought._integer_division(fx, fy, w=16, h=16)
    s, t = (d @ r) / (d @ f), (d @ u) / (d @ f)
    left, top = fx < 0.5, fy < 0.5
    assert np.all(np.abs(s - np.where(left, -1.0, 0.0)) <= 1 / 16 + 1e-12)
    assert np.all(np.abs(t - np.where(top, 1.0, 0.0)) <= 1 / 16 + 1e-12)
    # The reflection without its 2 is perpendicular to the normal where a camera ray meets the sphere.
    jj, ii = np.mgrid[0:32, 0:32]
    o, d = unsaid._pinhole((ii.ravel() + 0.5) / 32, (jj.ravel() + 0.5) / 32)
    o = np.array(o, np.float64)
    p, dr, used = unsought._reflect_without_2(o, d)
    _, _, true = unsaid._reflected(o, d)
    np.testing.assert_array_equal(used, true)
    assert used.sum() > 0
    c, _ = unsaid._sphere()
    hit = used == 1
    n = unsaid._unit(p[hit] - c)
    np.testing.assert_allclose(np.einsum("ij,ij->i", dr[hit], n), 0.0, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(dr, axis=1), 1.0, atol=1e-9)


def test_sample_loops_add_up_as_they_say():
    """The film samples' offsets (shared, antithetic), the rounded bins and the count of non-zero samples."""
    rng = np.random.default_rng(0)
    sh = unsought._shared(rng, 6, pixels=5)
    assert sh.shape == (2, 5, 6) and np.all(sh == sh[:, :1])
    an = unsought._antithetic(rng, 6, pixels=5)
    np.testing.assert_allclose(an[..., 0::2] + an[..., 1::2], 1.0)
    x = np.zeros((4, 4, 3))
    # Rounded bins: with the same samples, every sample lands in the pixel round of its position.
    rb = unsought._rounded_bins(x, spp=8, seed=3)
    total = np.zeros((5, 5, 3))
    jj, ii = np.divmod(np.arange(16), 4)
    for L, u, v in unsought._film_samples(4, 4, 8, 3, partial(unsought._independent, pixels=16)):
        for k in range(L.shape[1]):
            np.add.at(total, (np.rint(jj + v[:, k]).astype(int), np.rint(ii + u[:, k]).astype(int)), L[:, k])
    np.testing.assert_allclose(rb, total[:4, :4] / 8, rtol=1e-9)
    # Zeros left out: the sum over the count of non-zero samples.
    L = np.concatenate([a for a, _, _ in unasked._samples(4, 4, 8, 5)], axis=1)
    nz = (L.max(axis=2) > 0).sum(axis=1)
    np.testing.assert_allclose(unsought._zeros_left_out(x, spp=8, seed=5).reshape(16, 3),
                               L.sum(axis=1) / np.maximum(nz, 1)[:, None], rtol=1e-9)


def test_correct_hand_ins_agree_with_a_plain_render():
    plain = _plain(W, 1024)
    for name in ("ok_shared_subpixel_offsets", "ok_light_four_squares", "ok_mcrt_two_light_samples",
                 "ok_antithetic_offsets", "ok_sphere_transformed"):
        case = _build(_by_name(name))
        rel = np.abs(case.image - plain).mean(axis=2) / (plain.mean(axis=2) + 0.05)
        assert np.median(rel) < 0.15 and case.image.shape == (H, W, 3), name
        assert abs(case.image.mean() / plain.mean() - 1) < 0.1, name


def test_combined_mistakes_differ_from_the_plain_render_as_they_say():
    plain = _plain(W, 1024)
    lum = plain.mean(axis=2)
    lit, seen = lum < 5, lum > 5
    mx = _build(_by_name("passes_combined_by_max")).image
    assert mx[lit].mean() > 1.03 * plain[lit].mean()
    zeros = _build(_by_name("zeros_left_out_of_count")).image
    assert zeros[lit].mean() >= plain[lit].mean() * 0.97
    rb = _build(_by_name("samples_rounded_to_pixel")).image.mean(axis=2)
    assert rb[0].mean() < 0.75 * lum[0].mean() and rb[:, 0].mean() < 0.75 * lum[:, 0].mean()  # half their samples
    blocks = _build(_by_name("pixel_integer_division")).image.mean(axis=2)
    assert blocks[:8, :8].std() < 0.5 * lum.std() and blocks[8:, 8:].std() < 0.5 * lum.std()
    down = _build(_by_name("camera_space_minus_z")).image.mean(axis=2)
    assert (down > 5).sum() == 0  # the light is not seen looking down
    pi = _build(_by_name("mirror_over_pi")).image
    assert pi.mean() < plain.mean()


@pytest.mark.parametrize("name", ["pp_rotated_2_degrees", "pp_grey_opening", "pp_ycbcr_601_709", "file_exr_gbr",
                                  "file_png_srgb_red_green", "file_png_red_one_late", "file_png_video_range",
                                  "wall_cd_red_typed_057", "walls_colour_by_triangle", "floor_blue_missing",
                                  "sphere_z_typed_3_8", "triangle_edge_tolerance", "tetra_normals_to_eye",
                                  "rows_mapped_with_100", "light_in_xz_plane", "light_strata_unjittered",
                                  "mirror_reflect_without_2", "depth_counted_twice", "ok_png_skimage",
                                  "ok_exr_piz", "ok_ppm_pillow"])
def test_hand_ins_build(name, tmp_path):
    check_builds(_by_name(name), tmp_path)
