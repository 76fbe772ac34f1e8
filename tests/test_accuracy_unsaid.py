"""The twelfth class (mcrt.grade.accuracy.unsaid) is well formed and builds what its specs say: the same checks as
test_accuracy_unheard's (specs, writers read back, post-processes, scene edits, a few hand-ins built at 16 x 16, never
graded), on this class's cases, and the rays its Mitsuba renders trace.
"""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import (H, W, build as _build, by_name, check_builds, check_held_out_rule,
                              check_not_catalogued, check_specs, image as _image, plain as _plain)
from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unheard, unmet, unsaid, unseen, untold,
                                 untried)
from mcrt.image_files import ImageError, read_image, srgb_eotf

_by_name = partial(by_name, unsaid.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unsaid, _OTHERS, mistakes=28)
    assert all(s.truth for s in unsaid.SPECS)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unsaid)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unsaid)
    assert sum(s.held_out for s in unsaid.MISTAKES) == 12 and sum(s.held_out for s in unsaid.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    from mcrt.grade.accuracy.run import CAUSE_OF

    assert unsaid.NEW_CAUSES == {}
    old = set(cases.CAUSES) | set(outside.CAUSES) | {c for m in _OTHERS for c in getattr(m, "NEW_CAUSES", ())}
    assert {s.cause for s in unsaid.MISTAKES} <= old
    named = {c for causes in CAUSE_OF.values() for c in causes}
    assert {"blur", "tone_map", "albedo", "material", "light_pdf", "light_seen", "indirect_scale"} <= named


def test_the_command_knows_the_class():
    import importlib

    from mcrt.grade.accuracy.cli import CLASSES

    assert importlib.import_module(f"mcrt.grade.accuracy.{CLASSES['unsaid']}").SPECS is unsaid.SPECS


def test_correct_writers_read_back(tmp_path):
    """The correct hand-ins' files read back as the image: a TGA stored top row first (its origin bit set), a 16-bit
    PNG with an alpha channel."""
    x = _image()
    for d in "ab":
        (tmp_path / d).mkdir()
    tga = unsaid._write_tga_top_left(x, tmp_path / "a")
    assert tga.read_bytes()[17] == 0x20 and len(tga.read_bytes()) == 18 + 3 * W * H
    np.testing.assert_allclose(read_image(tga).mean, srgb_eotf(blind._srgb8(x) / 255.0), atol=1e-6)
    png = unsaid._write_png16_rgba(x, tmp_path / "b")
    np.testing.assert_allclose(read_image(png).mean, srgb_eotf(untried._codes16(x) / 65535.0), atol=1e-5)


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    from matplotlib import colormaps

    x = _image()
    for d in "abcde":
        (tmp_path / d).mkdir()
    # The channels' mean through viridis over its range: the darkest pixel viridis(0), the brightest viridis(1).
    path = unsaid._write_png_viridis(x, tmp_path / "a")
    from PIL import Image

    rgba = np.asarray(Image.open(path))
    assert rgba.shape == (H, W, 4) and np.all(rgba[..., 3] == 255)
    m = x.mean(axis=2)
    ends = (np.round(np.asarray(colormaps["viridis"]([0.0, 1.0]))[:, :3] * 255)).astype(int)
    np.testing.assert_allclose(rgba[np.unravel_index(m.argmin(), m.shape)][:3], ends[0], atol=1)
    np.testing.assert_allclose(rgba[np.unravel_index(m.argmax(), m.shape)][:3], ends[1], atol=1)
    # A P6 header over text: digits, spaces and newlines after it; the reader refuses the file.
    path = unsaid._write_ppm_p6_ascii(x, tmp_path / "b")
    header = unheard._ppm_header(W, H)
    data = path.read_bytes()
    assert data.startswith(header) and set(data[len(header):]) <= set(b"0123456789 \n")
    assert data[len(header):].split()[:3] == [str(int(v)).encode() for v in blind._srgb8(x)[0, 0]]
    with pytest.raises(ImageError):
        read_image(path)
    # Each row's channels one after another: pixel (0, 0) read back holds the row's first three reds.
    path = unsaid._write_ppm_rows_planar(x, tmp_path / "c")
    codes = blind._srgb8(x)
    raster = np.frombuffer(path.read_bytes()[len(header):], np.uint8).reshape(H, 3, W)
    np.testing.assert_array_equal(raster[2], codes[2].T)
    np.testing.assert_allclose(read_image(path).mean[0, 0], srgb_eotf(codes[0, :3, 0] / 255.0), atol=1e-6)
    # BT.709's curve: darker than sRGB's codes between 0 and 1 once decoded as sRGB, equal at both ends.
    v = np.array([0.0, 0.01, 0.05, 0.18, 0.5, 1.0])
    c709 = np.floor(unsaid._bt709(v) * 255.0 + 0.5)
    assert c709[0] == 0 and c709[-1] == 255 and np.all(c709[1:-1] < blind._srgb8(v)[1:-1])
    assert 0.7 < srgb_eotf(c709[3] / 255.0) / 0.18 < 0.85
    r = read_image(unsaid._write_png_bt709(x, tmp_path / "d")).mean
    assert r.shape == (H, W, 3) and r.mean() < srgb_eotf(blind._srgb8(x) / 255.0).mean()
    # A caption: white pixels drawn at the top left, the rest of the image untouched.
    cap = read_image(unsaid._write_png_captioned(np.full((64, 64, 3), 0.05), tmp_path / "e")).mean
    drawn = np.any(np.abs(cap - srgb_eotf(blind._srgb8(np.full(3, 0.05)) / 255.0)) > 1e-6, axis=2)
    assert drawn[:16, :48].sum() > 30 and not drawn[20:].any() and cap.max() > 0.9


def test_post_processes_do_what_they_say():
    x = _image()
    flat = np.full((H, W, 3), 0.3)
    np.testing.assert_allclose(unsaid._binomial_over_9(flat), flat * 16.0 / 9.0)
    b = unsaid._binomial_over_9(x)
    assert b.std() < (16.0 / 9.0) * x.std()
    np.testing.assert_allclose(unsaid._exponential(np.array([0.0, 1.0, 20.0])), [0.0, 1 - np.exp(-1.0), 1.0])
    dot = np.zeros((H, W, 3))
    dot[5, 7] = 2.0
    grown = unsaid._max_filter(dot)
    assert (grown[..., 0] == 2.0).sum() == 9 and np.all(grown[4:7, 6:9] == 2.0)
    order = unsaid._finish_order(64, 4, seed=5)
    assert sorted(order) == list(range(64)) and np.any(order != np.arange(64))
    assert np.abs(order - np.arange(64)).max() <= 4
    np.testing.assert_array_equal(unsaid._rows_unordered(x, workers=4, seed=5), x[unsaid._finish_order(H, 4, 5)])


def test_scene_edits():
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    s = load_scene()
    d = scene_dict(s, "near", 4, 4, 8)  # sets Mitsuba's variant too

    import mitsuba as mi

    r = unsaid._albedos_one_decimal(s)
    walls = {"".join(w.corners): w.albedo for w in r.room.walls}
    assert walls["AB"] == (0.8, 0.1, 0.1) and r.room.floor_albedo == (0.6, 0.6, 0.6)
    assert next(o for o in r.objects if o.name == "tetrahedron").material.albedo == (0.8, 0.5, 0.1)
    fa = {"".join(w.corners): w.albedo for w in unsaid._wall_fa_as_ef(s).room.walls}
    assert fa["FA"] == fa["EF"] == (0.15, 0.70, 0.15)
    m = unsaid._mirrored(s)
    poly = m.room.polygon()
    area = 0.5 * np.sum(poly[:, 0] * np.roll(poly[:, 1], -1) - np.roll(poly[:, 0], -1) * poly[:, 1])
    assert area > 0 and next(o for o in m.objects if o.name == "sphere").center == (9.5, -2.0, -3.3)
    box = unsaid._box((0.0, 0.0, 0.0), (1.0, 2.0, 3.0))
    areas = 0.5 * np.linalg.norm(np.cross(box[:, 1] - box[:, 0], box[:, 2] - box[:, 0]), axis=1)
    assert box.shape == (12, 3, 3) and areas.sum() == pytest.approx(2 * (2 + 3 + 6))
    walls_low = unsaid._walls_top_at_zero(d)
    z = np.array(mi.traverse(walls_low["wall_BC"])["vertex_positions"]).reshape(-1, 3)[:, 2]
    assert set(np.round(z, 6)) == {-5.0, 0.0}
    assert unsaid._ceiling_emits(d)["ceiling"].emitter() is not None and d["ceiling"].emitter() is None
    assert unsaid._sphere_passes_rays(d)["sphere"]["bsdf"]["int_ior"] == 1.0
    first = unsaid._light_first_triangle(d)
    assert first["light"].emitter() is not None and first["light_second"].emitter() is None
    assert first["light"].surface_area()[0] == pytest.approx(2.0)
    large, under = unsaid._light_seen_large(d), unsaid._light_sampled_under_large(d)
    assert large["light"].surface_area()[0] == pytest.approx(16.0) and large["light"].emitter() is not None
    assert under["light"].emitter() is None and under["light_sampled"].surface_area()[0] == pytest.approx(4.0)


def test_rays_of_the_camera_mistakes():
    """The pinhole's rays are Mitsuba's sensor's; the mistakes' rays are what their specs say."""
    from mcrt.mitsuba_scene import sensor_rays
    from mcrt.scene import load_scene

    rng = np.random.default_rng(1)
    i, j = rng.integers(0, W, 40), rng.integers(0, H, 40)
    u, v = rng.random((2, 40))
    _, d = sensor_rays(load_scene(), "near", W, H, i, j, u, v)
    fx, fy = (i + u) / W, (j + v) / H
    np.testing.assert_allclose(unsaid._pinhole(fx, fy)[1], d, atol=1e-6)
    o, across = unsaid._eye_not_subtracted(fx, fy)
    assert np.allclose(across[:, 0], 0.0) and np.allclose(o, (-1.0, 0.0, 0.0))
    assert np.all(unsaid._plane_without_minus_one(fx, fy)[1][:, 1] <= 0.0)  # all right of the view's centre (-y)
    np.testing.assert_allclose(unsaid._rotation_transposed(np.array([0.5]), np.array([0.5]))[1], [[0.0, 1.0, 0.0]],
                               atol=1e-12)


def test_reflections_off_the_sphere():
    """Camera rays meeting the sphere leave it reflected (angle in = angle out with the true normal; bent towards the
    normal with one 1.5 long); the others go on as they came."""
    eye = np.array([-1.0, 0.0, 0.0])
    c, radius = unsaid._sphere()
    aim = c + np.array([[0.0, 0.6, 0.5], [0.0, -0.3, 0.2], [0.0, 5.0, 0.0]])
    d = unsaid._unit(aim - eye)
    o = np.broadcast_to(eye, d.shape)
    p, r, used = unsaid._reflected(o, d)
    assert list(used) == [1, 1, 0] and np.allclose(r[2], d[2]) and np.allclose(p[2], eye)
    n = unsaid._unit(p[:2] - c)
    np.testing.assert_allclose(np.einsum("ij,ij->i", r[:2], n), -np.einsum("ij,ij->i", d[:2], n), atol=1e-9)
    _, bent, _ = unsaid._reflected(o, d, unnormalised=True)
    assert np.all(np.einsum("ij,ij->i", bent[:2], n) > np.einsum("ij,ij->i", r[:2], n))


def test_traced_renders_agree_with_a_plain_render():
    """Mitsuba's integrator on the pinhole's rays, and on rays reflected off the sphere by hand (a path of 7 after),
    is the plain render to the noise."""
    plain = _plain(W, 1024)
    x = np.zeros((H, W, 3))
    for im in (unsaid._traced(x, spp=512, seed=3), unsaid._traced(x, spp=512, seed=4, after=unsaid._reflected)):
        rel = np.abs(im - plain).mean(axis=2) / (plain.mean(axis=2) + 0.05)
        assert np.median(rel) < 0.06 and abs(im.mean() / plain.mean() - 1) < 0.05


def test_correct_hand_ins_agree_with_a_plain_render():
    plain = _plain(W, 1024)
    for name in ("ok_mcrt_mirrored_world", "ok_channels_lit_apart", "ok_mcrt_and_mitsuba", "ok_xyz_converted",
                 "ok_light_in_other_units", "ok_mcrt_no_roulette"):
        case = _build(_by_name(name))
        rel = np.abs(case.image - plain).mean(axis=2) / (plain.mean(axis=2) + 0.05)
        assert np.median(rel) < 0.15 and case.image.shape == (H, W, 3), name


def test_combined_mistakes_differ_from_the_plain_render_as_they_say():
    plain = _plain(W, 1024)
    lum = plain.mean(axis=2)
    lit = lum < 5
    assert 2.0 < _build(_by_name("pass_buffer_uncleared")).image[lit].mean() / plain[lit].mean() < 3.0
    assert _build(_by_name("shadow_rays_summed")).image[lit].mean() > 15 * plain[lit].mean()
    assert _build(_by_name("adaptive_full_divisor")).image[~lit].mean() < 0.5 * plain[~lit].mean()
    assert _build(_by_name("first_albedo_skipped")).image[lit].mean() > 1.03 * plain[lit].mean()
    seen = lum > 5
    half = _build(_by_name("light_seen_first_triangle")).image.mean(axis=2)
    assert half[seen].mean() < 0.9 * lum[seen].mean() and abs(half[lit].mean() / lum[lit].mean() - 1) < 0.1
    wide = _build(_by_name("light_seen_twice_as_wide")).image.mean(axis=2)
    assert wide[wide > 5].sum() > 1.8 * lum[seen].sum()  # a 4 x 4 light, its nearest quarter above the view
    across = _build(_by_name("eye_not_subtracted")).image
    assert np.abs(across - plain).mean() > 0.5 * plain.mean()


@pytest.mark.parametrize("name", ["pp_binomial_over_9", "pp_caption_drawn", "file_png_viridis_mean",
                                  "file_ppm_rows_planar", "mirror_direction_unused", "ceiling_light_material",
                                  "sphere_normal_unnormalised", "walls_top_at_zero", "tetra_bounding_box",
                                  "plane_minus_one_forgotten", "camera_rotation_transposed",
                                  "mirror_for_camera_rays_only", "sphere_not_in_shadow_test",
                                  "strata_isqrt_divided_by_asked", "rows_unordered", "ok_tga_top_left",
                                  "ok_png16_rgba"])
def test_hand_ins_build(name, tmp_path):
    check_builds(_by_name(name), tmp_path)
