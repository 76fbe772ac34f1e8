"""The eighteenth class (mcrt.grade.accuracy.unbidden) is well formed and builds what its specs say: the same checks as
test_accuracy_unprompted's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x 16, never
graded), on this class's cases, the rays its Mitsuba renders trace and the samples its loops add up.
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import (H, W, build as _build, by_name, check_builds, check_held_out_rule,
                              check_not_catalogued, check_specs, image as _image, plain as _plain)
from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unbidden, unforeseen,
                                 unguessed, unheard, unmet, unprompted, unsaid, unseen, unsought, untold, untried)
from mcrt.image_files import read_image, srgb_eotf

_by_name = partial(by_name, unbidden.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought, unguessed, unforeseen, unprompted)


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unbidden, _OTHERS, mistakes=28)
    assert len(unbidden.MISTAKES) == 28
    assert all(s.truth for s in unbidden.SPECS)
    truths = {s.truth for m in _OTHERS for s in m.SPECS}
    assert not truths & {s.truth for s in unbidden.SPECS}
    assert {len(v) for v in unbidden.CATEGORIES.values()} <= {3, 4}
    assert list(unbidden.CATEGORIES) == list(unforeseen.CATEGORIES) == list(unprompted.CATEGORIES)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unbidden)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unbidden)
    assert sum(s.held_out for s in unbidden.MISTAKES) == 12 and sum(s.held_out for s in unbidden.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    assert unbidden.NEW_CAUSES == {}
    old = set(cases.CAUSES) | set(outside.CAUSES) | {c for m in _OTHERS for c in getattr(m, "NEW_CAUSES", ())}
    assert {s.cause for s in unbidden.MISTAKES} <= old


def test_seeds_differ_from_the_other_classes():
    assert unbidden._crc("x") != unprompted._crc("x")
    assert 501000 <= unbidden._crc("pp_gaussian_over_channels") < 601000


def test_the_command_knows_the_class():
    import importlib

    from mcrt.grade.accuracy.cli import CLASSES

    assert importlib.import_module(f"mcrt.grade.accuracy.{CLASSES['unbidden']}").SPECS is unbidden.SPECS


def test_correct_writers_read_back(tmp_path):
    """The two-part and the HTJ2K EXRs, the hand-written Average-filtered PNG and Mitsuba's PNG read back as
    written."""
    import OpenEXR

    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene
    from mcrt.srgb import srgb_oetf

    scene_dict(load_scene(), "near", 4, 4, 8)  # sets Mitsuba's variant (for mi.Bitmap)
    x = _image()
    for d in "abcd":
        (tmp_path / d).mkdir()
    path = unbidden._write_exr_two_parts(x, tmp_path / "a")
    np.testing.assert_allclose(read_image(path).mean, x, rtol=1e-6)
    f = OpenEXR.File(str(path), separate_channels=True)
    assert len(f.parts) == 2 and f.parts[1].name() == "preview"
    np.testing.assert_allclose(f.channels(1)["G"].pixels, srgb_oetf(x[..., 1]), rtol=1e-6)
    np.testing.assert_allclose(read_image(unbidden._write_exr_htj2k(x, tmp_path / "b")).mean, x, rtol=1e-6)
    path = unbidden._write_png_average(x, tmp_path / "c")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    np.testing.assert_allclose(read_image(path).mean, srgb_eotf(blind._srgb8(x) / 255.0), atol=1e-6)
    raw = unbidden._average_filtered(blind._srgb8(x))
    assert all(raw[k * (1 + 3 * W)] == 3 for k in range(H))
    from PIL import Image

    np.testing.assert_array_equal(np.asarray(Image.open(path)), blind._srgb8(x))
    codes = np.asarray(Image.open(unbidden._write_png_mitsuba_bitmap(x, tmp_path / "d")))
    assert codes.shape == (H, W, 3) and np.abs(codes.astype(int) - blind._srgb8(x)).max() <= 1


def test_wrong_writer_and_conversions_write_what_their_specs_say(tmp_path):
    x = _image()
    # The sRGB curve's branches swapped: 12.92 v above the threshold (white from 1 / 12.92 on), the power below.
    v = np.array([[[0.0005, 0.002, 0.003], [0.01, 0.05, 0.5]]])
    codes = unbidden._srgb_branches_swapped(v)
    expected = np.where(v <= 0.0031308, 1.055 * v ** (1 / 2.4) - 0.055, 12.92 * v)
    np.testing.assert_array_equal(codes, np.floor(np.clip(expected, 0, 1) * 255 + 0.5).astype(np.uint8))
    assert codes[0, 0, 0] == 0 and codes[0, 1, 2] == 255 and codes[0, 1, 1] == 165
    r = read_image(unbidden._write_png_srgb_branches_swapped(x, tmp_path)).mean
    np.testing.assert_allclose(r, srgb_eotf(unbidden._srgb_branches_swapped(x) / 255.0), atol=1e-6)
    assert r.mean() > 0.9  # values of 0.05 and over are white
    # The XYZ matrix on RGB: the greys' white point kept, a saturated green greener, no negatives.
    from mcrt.image_files import XYZ_TO_RGB

    y = unbidden._xyz_matrix_on_rgb(x)
    np.testing.assert_allclose(y, np.maximum(x @ XYZ_TO_RGB.T, 0.0))
    g = unbidden._xyz_matrix_on_rgb(np.array([[[0.15, 0.70, 0.15]]]))[0, 0]
    assert g[0] == 0.0 and g[1] > 1.1 and y.min() >= 0.0
    np.testing.assert_allclose(unbidden._photometric(x), 683.0 * x)


def test_post_processes_do_what_they_say():
    x = _image()
    # The Gaussian over all three axes: a flat grey kept, the channels mixed (a pure red pixel field gains green).
    np.testing.assert_allclose(unbidden._gaussian_all_axes(np.full((6, 6, 3), 0.3)), 0.3)
    red = np.zeros((6, 6, 3))
    red[..., 0] = 1.0
    mixed = unbidden._gaussian_all_axes(red)
    assert 0.1 < mixed[3, 3, 1] < mixed[3, 3, 0] < 1.0 and mixed[3, 3, 2] > 0.0
    # The contrast stretch: linear between the 2nd and 98th percentiles of all values, clipped to [0, 1].
    p2, p98 = np.percentile(x, (2, 98))
    np.testing.assert_allclose(unbidden._contrast_stretched(x), np.clip((x - p2) / (p98 - p2), 0.0, 1.0), atol=1e-12)
    # Values over 10 set to 0, the rest kept.
    y = x.copy()
    y[1, 2] = (20.0, 20.0, 20.0)
    y[3, 4] = (12.0, 9.0, 3.0)
    z = unbidden._bright_zeroed(y)
    assert list(z[1, 2]) == [0.0, 0.0, 0.0] and list(z[3, 4]) == [0.0, 9.0, 3.0]
    np.testing.assert_array_equal(z[y <= 10], y[y <= 10])
    # The 2 x 2 box: a spike spread over itself and the pixels below, right and below-right (half a pixel down and
    # right), a quarter each.
    spike = np.zeros((6, 6, 3))
    spike[2, 2] = 4.0
    b = unbidden._box_2x2(spike)[..., 0]
    np.testing.assert_allclose(b[2:4, 2:4], 1.0)
    assert b.sum() == pytest.approx(4.0)
    # The row buffer never cleared: each row the running sum of the rows above it and itself.
    np.testing.assert_allclose(unbidden._row_sums_carried(np.ones((4, 2, 3)))[:, 0, 0], [1, 2, 3, 4])


def test_scene_edits():
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    s = load_scene()
    d = scene_dict(s, "near", 4, 4, 8)  # sets Mitsuba's variant too
    import mitsuba as mi

    # Gamma-encoded albedos; the colour table read one number late.
    g = unbidden._albedos_gamma_encoded(s)
    np.testing.assert_allclose(g.room.floor_albedo, (0.6 ** (1 / 2.2),) * 3)
    np.testing.assert_allclose(g.room.walls[0].albedo, np.array(s.room.walls[0].albedo) ** (1 / 2.2))
    late = unbidden._one_number_late(s)
    assert late.room.floor_albedo == (0.6, 0.6, 0.8) and late.room.ceiling_albedo == (0.8, 0.8, 0.75)
    assert late.room.walls[0].albedo == (0.15, 0.15, 0.55) and late.room.walls[5].albedo == (0.65, 0.7, 0.8)
    tet = next(o for o in late.objects if o.name == "tetrahedron")
    assert tet.material.albedo == (0.45, 0.1, 0.0)
    assert unbidden._colour_table(s)[:3] == [(0.6, 0.6, 0.6), (0.8, 0.8, 0.8), (0.75, 0.15, 0.15)]
    # The walls emitting their colours, black.
    em = unbidden._walls_emitting(d)
    wall = em["wall_AB"]
    assert wall.emitter() is not None and wall.surface_area()[0] == pytest.approx(d["wall_AB"].surface_area()[0])
    # The walls' quads in Z order: three quarters of each wall's area covered (two triangles of half the quad each,
    # overlapping by a quarter).
    zw = unbidden._z_order_tris(s, s.room.walls[1])
    n = np.cross(zw[:, 1] - zw[:, 0], zw[:, 2] - zw[:, 0])
    assert 0.5 * np.linalg.norm(n, axis=1).sum() == pytest.approx(10.0 * 10.0)
    mi.load_dict(unbidden._walls_z_order(d))
    # The room's corners (y, x), its walls listed the other way round: the same walls, a floor and a ceiling.
    yx = unbidden._corners_yx(s)
    assert yx.room.corners["D"] == (0.0, 13.0) and yx.room.corners["B"] == (-6.0, 0.0)
    names = {sf.name for sf in yx.surfaces() if len(sf.triangles)}
    assert {"floor", "ceiling"} <= names and len([n for n in names if n.startswith("wall_")]) == 6
    # The sphere's z positive; the eye turned with the frame; the field of view of the full width.
    assert next(o for o in unbidden._sphere_z_positive(s).objects if o.name == "sphere").center == (9.5, 2.0, 3.3)
    np.testing.assert_allclose(unbidden._eye_rotated(s).cameras["near"].eye, (0.0, 1.0, 0.0), atol=1e-12)
    assert unbidden._fov_full_width(s).cameras["near"].fov_x_deg == pytest.approx(math.degrees(2 * math.atan(2)))
    # The light's height from the ceiling; its first three corners; its samples' radiance (the power kept).
    assert unbidden._light_z_from_ceiling(s).light.center[2] == pytest.approx(0.01)
    tri = unbidden._light_three_corners(d)["light"]
    assert tri.emitter() is not None and tri.surface_area()[0] == pytest.approx(2.0)
    tex = unbidden._light_gaussian_texture()
    assert tex.mean() == pytest.approx(20.0, rel=0.01) and tex.max() == pytest.approx(55.8, rel=0.01)
    assert tex[0, 0, 0] < 1.5 and np.allclose(tex, tex[::-1]) and np.allclose(tex, tex[:, ::-1])
    light = mi.load_dict(unbidden._light_gaussian(d)["light"])
    assert light.surface_area()[0] == pytest.approx(4.0) and light.emitter() is not None
    # Correct edits load: the focal length's 90 degrees, the y-up world, the tetrahedron's vertices permuted.
    sensor = mi.load_dict(unbidden._focal_length(d)["sensor"])
    ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(0.0, 0.5), mi.Point2f(0.5))
    assert float(ray.d.y[0]) == pytest.approx(float(ray.d.x[0]), rel=1e-5)  # 45 degrees from the axis
    up = unbidden._y_up_world(d)
    assert up["sphere"]["center"] == [9.5, -3.3, -2.0]
    mi.load_dict(up)
    perm = next(o for o in unbidden._tetra_permuted(s).objects if o.name == "tetrahedron")
    tetra = next(o for o in s.objects if o.name == "tetrahedron")
    assert set(perm.vertices) == set(tetra.vertices) and perm.vertices != tetra.vertices


def test_rays_offsets_and_sample_loops_are_as_they_say():
    rng = np.random.default_rng(0)
    # The bracket misplaced: offsets over the whole image in pixel units.
    u, v = unbidden._bracket_misplaced(rng, 5000, w=8, pixels=32)
    assert u.shape == (32, 5000) and u.max() > 7.9 and u.mean() == pytest.approx(4.0, abs=0.1)
    assert v.max() < 4.0 and v.mean() == pytest.approx(2.0, abs=0.1)
    # The Latin hypercube: one offset in each of the n strata in x and in y, in every pixel.
    u, v = unbidden._latin_hypercube(rng, 16, w=4, pixels=5)
    assert u.shape == (5, 16) and np.all((0 <= u) & (u < 1)) and np.all((0 <= v) & (v < 1))
    for a in (u, v):
        assert all(sorted(np.floor(row * 16).astype(int)) == list(range(16)) for row in a)
    # The reach kept: cosine-weighted directions, the camera's distance as the bounce's t_max.
    n = np.tile([[0.0, 0.0, 1.0]], (1000, 1))
    dirs, reach = unbidden._reach_kept(np.random.default_rng(1), np.zeros((1000, 3)), n, np.full(1000, 3.0))
    assert np.all(reach == 3.0) and dirs[:, 2].min() >= 0.0
    # A bounce reaching 3 from the floor's centre meets nothing, an unbounded one the room.
    mscene = unsaid._loaded(2)
    o, d = np.array([[5.0, 0.0, -4.99]]), np.array([[0.0, 0.0, 1.0]])
    assert unguessed._first_hit(mscene, o, d)[1][0]
    assert unbidden._sampled_within(mscene, o, d, [3.0], 7)[0].max() == 0.0
    assert unbidden._sampled_within(mscene, o, d, None, 7)[0].max() > 0.0
    # Towards the light sample: unit directions ending on the light's square.
    p = np.array([[5.0, 0.0, -5.0], [9.0, 3.0, -2.0]] * 500)
    dirs, reach = unbidden._towards_light_sample(np.random.default_rng(2), p, None, None)
    t = (4.99 - p[:, 2]) / dirs[:, 2]
    q = p + t[:, None] * dirs
    assert reach is None and np.all(np.abs(q[:, 0] - 5.0) <= 1.0 + 1e-9) and np.all(np.abs(q[:, 1]) <= 1.0 + 1e-9)
    # reflect's arguments swapped: n - 2 (n . d) d for the rays meeting the sphere, unit, from the hit point.
    c, r = unsaid._sphere()
    o = np.array([[-1.0, 0.0, 0.0]] * 3)
    d = unsaid._unit(np.array([c - o[0], c + [0.0, 0.8, 0.5] - o[0], [1.0, -1.0, 0.0]]))
    ro, rd, hit = unbidden._reflect_swapped(o, d)
    p, _, _ = unsaid._reflected(o, d)
    assert list(hit) == [1, 1, 0]
    nh = unsaid._unit(p[:2] - c)
    np.testing.assert_allclose(rd[:2], unsaid._unit(nh - 2 * np.einsum("ij,ij->i", nh, d[:2])[:, None] * d[:2]))
    np.testing.assert_allclose(rd[0], d[0], atol=1e-6)  # head-on: on into the sphere
    np.testing.assert_allclose(np.linalg.norm(rd, axis=1), 1.0)
    np.testing.assert_array_equal(rd[2], d[2])
    # The tetrahedron found by its colour alone.
    rho = np.array([[0.8, 0.45, 0.1], [0.75, 0.7, 0.15], [0.0, 0.0, 0.0]], np.float32)
    assert list(unbidden._is_tetra(rho)) == [True, False, False]
    # The median and the loop left at a black sample, against the samples themselves.
    x = np.zeros((4, 4, 3))
    L = unbidden._all_samples(4, 4, 8, 5)
    np.testing.assert_array_equal(L, np.concatenate([a for a, _, _ in unasked._samples(4, 4, 8, 5)], axis=1))
    np.testing.assert_allclose(unbidden._median_of_samples(x, spp=8, seed=5).reshape(16, 3), np.median(L, axis=1))
    stopped = unbidden._stopped_at_black(x, spp=8, seed=5).reshape(16, 3)
    for k in range(16):
        black = np.flatnonzero(L[k].max(axis=1) <= 0.0)
        np.testing.assert_allclose(stopped[k], L[k, :black[0] if len(black) else 8].sum(axis=0) / 8)


def test_albedo_aov_and_tiles(plain):
    # The albedo AOV: the first hit's colours, the light's black surface 0, nothing over the brightest albedo.
    aov = unbidden._albedo_aov(np.zeros((H, W, 3)), spp=8, seed=3)
    whole = plain.mean(axis=2) > 19.9
    assert aov.min() == 0.0 and aov.max() <= 0.8 + 1e-6
    assert whole.any() and aov[whole].max() < 0.15  # at most one of 8 rays off the light
    # Each tile the whole view at its size: four tiles alike but for their noise.
    t = unbidden._tiles_whole_view(np.zeros((8, 8, 3)), spp=64, seed=1, tiles=2)
    a, b = t[:4, :4], t[4:, 4:]
    assert np.median(np.abs(a - b).mean(axis=2) / (a.mean(axis=2) + 0.05)) < 0.2


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    for name in ("ok_latin_hypercube_offsets", "ok_focal_length_15mm", "ok_exr_two_parts", "ok_png_average_filter",
                 "ok_mcrt_tetra_permuted", "ok_y_up_world", "ok_exr_htj2k", "ok_png_mitsuba_bitmap"):
        case = _build(_by_name(name))
        rel = np.abs(case.image - plain).mean(axis=2) / (plain.mean(axis=2) + 0.05)
        assert np.median(rel) < 0.15 and case.image.shape == (H, W, 3), name
        assert abs(case.image.mean() / plain.mean() - 1) < 0.1, name


def test_combined_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    seen, lit = lum > 5, lum < 1
    # The light's samples from a normal about its centre: the same power on surfaces, the light seen right.
    normal = _build(_by_name("light_samples_normal_about_centre")).image.mean(axis=2)
    assert normal[lit].mean() == pytest.approx(lum[lit].mean(), rel=0.1)
    assert normal[seen].mean() == pytest.approx(lum[seen].mean(), rel=0.02)
    # The bounce's reach kept and the bounce along the light sample: darker lit surfaces, the light right.
    for name, high in (("bounce_ray_tmax_kept", 0.95), ("bounce_along_light_sample", 0.8)):
        im = _build(_by_name(name)).image.mean(axis=2)
        assert im[lit].mean() < high * lum[lit].mean(), name
        assert im[seen].mean() == pytest.approx(lum[seen].mean(), rel=0.02), name
    # No light sample on the tetrahedron and reflect swapped: close to the truth in the mean, not equal to it.
    for name in ("tetra_not_light_sampled", "mirror_reflect_arguments_swapped"):
        m = _build(_by_name(name)).image.mean() / plain.mean()
        assert 0.85 < m < 1.15, (name, m)
    # The median of the samples: darker lit surfaces; the loop left at black: no pixel brighter than the truth allows.
    med = _build(_by_name("pixel_median_of_samples")).image.mean(axis=2)
    assert med[lit].mean() < 0.97 * lum[lit].mean()
    stop = _build(_by_name("sample_loop_breaks_at_black")).image
    assert stop.mean() < plain.mean()
    # The film position's bracket misplaced: every pixel a mean over a wide window, a smooth image.
    wide = _build(_by_name("jitter_bracket_misplaced")).image.mean(axis=2)
    assert np.abs(np.diff(wide, axis=1)).mean() < 0.5 * np.abs(np.diff(lum, axis=1)).mean()


@pytest.mark.parametrize("name", [s.name for s in unbidden.SPECS])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back."""
    check_builds(_by_name(name), tmp_path)
