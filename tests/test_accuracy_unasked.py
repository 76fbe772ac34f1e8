"""The thirteenth class (mcrt.grade.accuracy.unasked) is well formed and builds what its specs say: the same checks as
test_accuracy_unsaid's (specs, writers read back, post-processes, scene edits, a few hand-ins built at 16 x 16, never
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
                                 unseen, untold, untried)
from mcrt.image_files import read_image, srgb_eotf

_by_name = partial(by_name, unasked.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unasked, _OTHERS, mistakes=28)
    assert all(s.truth for s in unasked.SPECS)
    truths = {s.truth for m in _OTHERS for s in m.SPECS}
    assert not truths & {s.truth for s in unasked.SPECS}


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unasked)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unasked)
    assert sum(s.held_out for s in unasked.MISTAKES) == 12 and sum(s.held_out for s in unasked.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    assert unasked.NEW_CAUSES == {}
    old = set(cases.CAUSES) | set(outside.CAUSES) | {c for m in _OTHERS for c in getattr(m, "NEW_CAUSES", ())}
    assert {s.cause for s in unasked.MISTAKES} <= old


def test_the_command_knows_the_class():
    import importlib

    from mcrt.grade.accuracy.cli import CLASSES

    assert importlib.import_module(f"mcrt.grade.accuracy.{CLASSES['unasked']}").SPECS is unasked.SPECS


def test_correct_writers_read_back(tmp_path):
    """Matplotlib's RGBA PNG and imageio's PNG read back as the 8-bit sRGB codes written."""
    x = _image()
    for d in "ab":
        (tmp_path / d).mkdir()
    want = srgb_eotf(blind._srgb8(x) / 255.0)
    np.testing.assert_allclose(read_image(unasked._write_png_matplotlib(x, tmp_path / "a")).mean, want, atol=1e-6)
    np.testing.assert_allclose(read_image(unasked._write_png_imageio(x, tmp_path / "b")).mean, want, atol=1e-6)


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    x = _image()
    for d in "abcde":
        (tmp_path / d).mkdir()
    # The EXR holds the values times 255.
    np.testing.assert_allclose(read_image(unasked._write_exr_times_255(x, tmp_path / "a")).mean, 255.0 * x, rtol=1e-6)
    # (255 v) ** (1 / 2.2): 1.0 becomes code 12, 20 (the light) code 48, everything else darker.
    codes = unasked._gamma_after_scaling(np.array([[[0.0, 1.0, 20.0]]]))
    assert list(codes[0, 0]) == [0, 12, 48]
    r = read_image(unasked._write_png_gamma_after_scaling(x, tmp_path / "b")).mean
    assert r.max() <= srgb_eotf(np.array(13 / 255.0)) and r.shape == (H, W, 3)
    # Float32 bytes taken as codes: the first pixel's three codes are the first value's first three bytes.
    f = unasked._float_bytes_as_codes(x)
    first = np.frombuffer(np.float32(fresh._srgb(x)[0, 0, 0]).tobytes(), np.uint8)
    np.testing.assert_array_equal(f[0, 0], first[:3])
    from PIL import Image

    np.testing.assert_array_equal(np.asarray(Image.open(unasked._write_png_float_bytes(x, tmp_path / "c"))), f)
    # The low byte of 16-bit codes.
    low = unasked._low_byte(x)
    np.testing.assert_array_equal(low, untried._codes16(x) % 256)
    np.testing.assert_allclose(read_image(unasked._write_png_low_byte(x, tmp_path / "d")).mean, srgb_eotf(low / 255.0),
                               atol=1e-6)
    # A one-pixel white frame, the inside untouched.
    r = read_image(unasked._write_png_framed(x, tmp_path / "e")).mean
    assert np.all(r[0] == 1.0) and np.all(r[:, -1] == 1.0)
    np.testing.assert_allclose(r[1:-1, 1:-1], srgb_eotf(blind._srgb8(x) / 255.0)[1:-1, 1:-1], atol=1e-6)


def test_post_processes_do_what_they_say():
    x = _image()
    rb = unasked._row_box(x)
    np.testing.assert_allclose(rb[:, 1:-1], (x[:, :-2] + x[:, 1:-1] + x[:, 2:]) / 3.0)
    np.testing.assert_allclose(rb[3], unasked._row_box(x)[3])  # rows apart: no vertical mixing
    np.testing.assert_allclose(unasked._smoothstep(np.array([-1.0, 0.25, 0.5, 3.0])), [0.0, 0.15625, 0.5, 1.0])
    c = unasked._clahe(np.concatenate([x, 20 * x], axis=1))
    assert c.min() >= 0.0 and c.max() <= 1.0 and c.shape == (H, 2 * W, 3)


def test_scene_edits():
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    s = load_scene()
    d = scene_dict(s, "near", 4, 4, 8)  # sets Mitsuba's variant too

    import mitsuba as mi

    assert {w.albedo for w in unasked._walls_first_colour(s).room.walls} == {(0.75, 0.15, 0.15)}
    tetra = next(o for o in unasked._tetra_last_material(s).objects if o.name == "tetrahedron")
    assert tetra.material.albedo == (0.15, 0.65, 0.70)
    assert unasked._light_yx(s).light.center == (0.0, 5.0, 4.99)
    assert unasked._mirror_red(d)["sphere"]["bsdf"]["specular_reflectance"]["value"] == [1.0, 0.0, 0.0]
    normals = np.array(mi.traverse(unasked._tetra_one_normal(d)["tetrahedron"])["vertex_normals"]).reshape(-1, 3)
    assert np.allclose(normals, normals[0]) and np.isclose(np.linalg.norm(normals[0]), 1.0)
    floor = unasked._floor_holed(d)["floor"]
    assert floor.surface_area()[0] == pytest.approx(d["floor"].surface_area()[0] - 4.0, rel=1e-5)
    corners = unasked._under_light(d, unasked._light_corners())
    assert corners["light"].emitter() is None and all(corners[f"light_sample_{k}"].emitter() is not None
                                                      for k in range(4))
    assert corners["light_sample_0"].surface_area()[0] == pytest.approx(0.01, rel=1e-5)
    assert sorted(unasked._light_corners()) == [(4.0, -1.0), (4.0, 1.0), (6.0, -1.0), (6.0, 1.0)]
    halves = [unasked._one_triangle_lit(d, k=k) for k in range(2)]
    assert all(h["light"].emitter() is not None and h["light_other"].emitter() is None for h in halves)
    assert unasked._light_rectangle(d)["light"]["type"] == "rectangle"
    moved = unasked._moved(s)
    assert moved.cameras["near"].eye == (2.0, -2.0, 1.5) and moved.room.floor_z == -3.5
    re = unasked._reordered(s)
    assert "".join(re.room.walls[0].corners) == "CD" and re.objects[0].name == "sphere"


def test_rays_of_the_camera_and_sphere_mistakes():
    rng = np.random.default_rng(1)
    fx, fy = rng.random((2, 40))
    _, d = unsaid._pinhole(fx, fy)
    _, lin = unasked._angles_linear(fx, fy)
    _, r, u, f, _ = unsaid._frame()
    # The angles from the view axis are linear in the pixel (45 degrees at the edges).
    np.testing.assert_allclose(np.degrees(np.arctan2(lin @ r, lin @ f)), (2 * fx - 1) * 45.0, atol=1e-9)
    np.testing.assert_allclose(np.degrees(np.arctan2(lin @ u, lin @ f)), (1 - 2 * fy) * 45.0, atol=1e-9)
    # The sphere test with a = 1 takes far more camera rays for hits than the true test, a superset of them.
    jj, ii = np.mgrid[0:32, 0:32]
    o, d = unsaid._pinhole((ii.ravel() + 0.5) / 32, (jj.ravel() + 0.5) / 32)
    o = np.array(o, np.float64)
    p, _, used = unasked._sphere_test_unit_a(o, d)
    _, _, true = unsaid._reflected(o, d)
    assert np.all(used >= true) and used.sum() > 8 * true.sum()
    c, radius = unsaid._sphere()
    assert np.all(np.linalg.norm(p[used == 1] - c, axis=1) > radius)  # off the sphere, outside it


def test_sample_loops_add_up_as_they_say():
    """The samples' loops on the same samples: the running mean weighs them as its docstring says; break on the
    light keeps the samples before it; the mean over the columns is each row's mean."""
    x = np.zeros((4, 4, 3))
    L = np.concatenate([a for a, _, _ in unasked._samples(4, 4, 8, 5)], axis=1)
    wts = (1 - 1 / 8) ** (7 - np.arange(8)) / 8
    np.testing.assert_allclose(unasked._running_mean_fixed_n(x, spp=8, seed=5).reshape(16, 3),
                               np.einsum("pkc,k->pc", L, wts), rtol=1e-9)
    cols = unasked._mean_over_columns(x, seed=5)
    L4 = np.concatenate([a for a, _, _ in unasked._samples(4, 4, 4, 5)], axis=1)
    np.testing.assert_allclose(cols, L4.reshape(4, 4, 4, 3).mean(axis=1))
    o = np.array([[0.0, 0.0, 0.0]] * 3)
    d = np.array([[5.0, 0.0, 4.99], [5.0, 1.5, 4.99], [1.0, 0.0, 0.0]])
    assert list(unasked._hits_light(o, d / np.linalg.norm(d, axis=1, keepdims=True))) == [True, False, False]


def test_correct_hand_ins_agree_with_a_plain_render():
    plain = _plain(W, 1024)
    for name in ("ok_mcrt_row_bands", "ok_light_halves_summed", "ok_camera_rolled_back", "ok_light_rectangle",
                 "ok_mcrt_world_moved", "ok_mcrt_reordered"):
        case = _build(_by_name(name))
        rel = np.abs(case.image - plain).mean(axis=2) / (plain.mean(axis=2) + 0.05)
        assert np.median(rel) < 0.15 and case.image.shape == (H, W, 3), name
        assert abs(case.image.mean() / plain.mean() - 1) < 0.1, name


def test_combined_mistakes_differ_from_the_plain_render_as_they_say():
    plain = _plain(W, 1024)
    lum = plain.mean(axis=2)
    lit, seen = lum < 5, lum > 5
    assert 0.55 < _build(_by_name("running_mean_total_count")).image[lit].mean() / plain[lit].mean() < 0.7
    assert 0.28 < _build(_by_name("hero_channel_unweighted")).image[lit].mean() / plain[lit].mean() < 0.38
    brk = _build(_by_name("break_on_light")).image.mean(axis=2)
    assert brk[seen].mean() < 0.2 * lum[seen].mean() and abs(brk[lit].mean() / lum[lit].mean() - 1) < 0.1
    whole = _build(_by_name("bounce_on_whole_sphere")).image
    assert whole[lit].mean() < 0.9 * plain[lit].mean()
    last = _build(_by_name("radiance_assigned_per_vertex")).image.mean(axis=2)
    assert last[lit].mean() < 0.5 * lum[lit].mean() and abs(last[seen].mean() / lum[seen].mean() - 1) < 0.1
    box = _build(_by_name("letterboxed_16_9")).image
    assert np.all(box[:3] == 0) and np.all(box[-4:] == 0) and box[3:12].min() > 0
    clip = _build(_by_name("far_clip_10")).image.mean(axis=2)
    assert (clip == 0).sum() > 20 and (lum == 0).sum() == 0
    hole = _build(_by_name("floor_hole_under_light")).image.mean(axis=2)
    assert (hole == 0).sum() > 0
    rows = _build(_by_name("mean_over_columns_axis")).image.mean(axis=2)
    assert np.median(rows.std(axis=1)) < 0.5 * np.median(lum.std(axis=1))


@pytest.mark.parametrize("name", ["pp_row_box_3", "pp_white_frame", "pp_clahe", "file_exr_times_255",
                                  "file_png_gamma_after_255", "file_png_float_bytes", "file_png_low_byte",
                                  "mirror_red_only", "walls_first_colour", "tetra_material_minus_one",
                                  "tetra_first_face_normal", "sphere_test_unit_direction", "plane_angle_for_tangent",
                                  "angles_linear_per_axis", "light_point_once_per_pixel", "light_samples_at_corners",
                                  "light_centre_yx", "mirror_whitted", "ok_png_matplotlib", "ok_png_imageio"])
def test_hand_ins_build(name, tmp_path):
    check_builds(_by_name(name), tmp_path)
