"""The thirty-third class (mcrt.grade.accuracy.unconfirmed) is well formed and builds what its specs say: the same
checks as test_accuracy_unexamined's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x 16,
never graded), on this class's cases, the debug views, narrowed loops, toggled flags, reordered parameters, merges,
stale caches and profiling hacks its Mitsuba renders are made of, each against values worked out by hand.
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
from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unanticipated, unasked, unattended,
                                 unattested, unbeknown, unbidden, unconfirmed, unconsidered, unexamined, unforeseen,
                                 unguessed, unheard, unheralded, unlisted, unlooked, unmet, unnoticed, unprompted,
                                 unrecorded, unremarked, unremembered, unsaid, unseen, unsought, untold, untried,
                                 unvisited, unwonted)
from mcrt.image_files import read_image

_by_name = partial(by_name, unconfirmed.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought, unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted,
           unremarked, unremembered, unnoticed, unrecorded, unattended, unattested, unconsidered, unanticipated,
           unexamined, unlisted)  # the last, its twin: written the same day, apart


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


@pytest.fixture(scope="module")
def scene():
    from mcrt.scene import load_scene

    return load_scene()


def test_specs_are_new_worded_and_in_categories():
    check_specs(unconfirmed, _OTHERS, mistakes=28)
    check_new_truths(unconfirmed, _OTHERS)
    assert len(unconfirmed.MISTAKES) == 28 and {len(v) for v in unconfirmed.CATEGORIES.values()} <= {3, 4}
    assert list(unconfirmed.CATEGORIES) == list(unnoticed.CATEGORIES)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unconfirmed)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unconfirmed)
    assert sum(s.held_out for s in unconfirmed.MISTAKES) == 12 and sum(s.held_out for s in unconfirmed.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    check_old_causes(unconfirmed, _OTHERS)
    assert unconfirmed._EARLIER[-1] is unexamined and unconfirmed._EARLIER[-2] is unanticipated
    assert unconsidered in unconfirmed._EARLIER and unrecorded in unconfirmed._EARLIER
    assert set(unconfirmed._REWORDED) == set(unconfirmed.CAUSES)


def test_seeds_differ_from_the_other_classes():
    check_seeds(unconfirmed, _OTHERS, 2001000)


def test_the_command_knows_the_class():
    check_command(unconfirmed, "unconfirmed")


def test_correct_writers_read_back(tmp_path):
    """OpenEXR's File API from one 'RGB' array reads back as the image with its commit attribute; the pre-commit
    hook's optimised PNG holds the rounded sRGB codes."""
    import OpenEXR

    x = _image()
    for d in "ab":
        (tmp_path / d).mkdir()
    path = unconfirmed._write_exr_rgb_key(x, tmp_path / "a")
    f = OpenEXR.File(str(path))
    assert f.header()["gitCommit"] == "3f9c2ab"
    np.testing.assert_allclose(read_image(path).mean, x.astype(np.float32), atol=0)
    path = unconfirmed._write_png_optimized(x, tmp_path / "b")
    np.testing.assert_array_equal(pillow_codes(path), blind._srgb8(x))


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    x = _image()
    for d in "ab":
        (tmp_path / d).mkdir()
    # fast_pow: log2 exact at powers of two, linear between; 2^(-1/2.4) read as 2^-1 (1 + 0.5833) = 0.7917.
    assert unconfirmed._fast_log2(np.array([1.0, 0.5, 0.25, 0.75])).tolist() == [0.0, -1.0, -2.0, -0.5]
    assert unconfirmed._fast_exp2(np.array([0.0, -1.0, -0.5]))[:2].tolist() == [1.0, 0.5]
    assert unconfirmed._fast_exp2(np.array([-0.5]))[0] == 0.75
    p = unconfirmed._fast_pow(np.array([0.5]), 1 / 2.4)[0]
    assert p == pytest.approx(0.5 * (1 + (1 - 1 / 2.4)), abs=1e-6) == pytest.approx(0.79167, abs=1e-5)
    assert p / 0.5 ** (1 / 2.4) == pytest.approx(1.0567, abs=1e-3)
    codes = unconfirmed._fast_srgb_codes(np.array([[[0.5, 0.0, 1.0]]]))[0, 0]
    assert codes.tolist() == [math.floor(255 * (1.055 * p - 0.055) + 0.5), 0, 255] == [199, 0, 255]
    assert math.floor(255 * (1.055 * 0.5 ** (1 / 2.4) - 0.055) + 0.5) == 188
    assert unconfirmed._fast_srgb_codes(np.array([[[0.002, 0.0, 0.0]]]))[0, 0, 0] == math.floor(
        255 * 12.92 * 0.002 + 0.5)
    got = pillow_codes(unconfirmed._write_png_fast_pow(x, tmp_path / "a")).astype(int)
    c8 = blind._srgb8(x).astype(int)
    assert 0 < np.abs(got - c8).max() <= 16 and got.mean() > c8.mean()  # the bit trick's powers run high
    # The writer's bits given the gamma: 2 ** 2.2 - 1 = 3.59, the codes 0 to 4; gamma 2.2 by default.
    top = 2 ** 2.2 - 1
    codes = unconfirmed._writer_codes(np.array([[[1.0, 0.5, 0.0]]]), 2.2)[0, 0]
    assert codes.tolist() == [round(top), round(0.5 ** (1 / 2.2) * top), 0] == [4, 3, 0]
    np.testing.assert_array_equal(unconfirmed._writer_codes(x), np.round(x ** (1 / 2.2) * 255))
    got = pillow_codes(unconfirmed._write_png_bits_given_gamma(x, tmp_path / "b"))
    assert got.max() <= 4 and got.min() >= 1


def test_post_processes_do_what_they_say():
    # The debug marker: the 8 pixels round (41, 23) at 64 x 64, (10, 5) at 16 x 16.
    ring = unconfirmed._marker_ring(64, 64)
    assert len(ring) == 8 and (23, 41) not in ring and {(22, 40), (24, 42), (23, 40), (22, 41)} <= set(ring)
    assert set(unconfirmed._marker_ring(16, 16)) == {(r, c) for r in (4, 5, 6) for c in (9, 10, 11)} - {(5, 10)}
    x = _image()
    m = unconfirmed._debug_marker(x)
    assert (m != x).any(axis=2).sum() == 8 and m[4, 9].tolist() == [1.0, 0.0, 1.0]
    np.testing.assert_array_equal(m[5, 10], x[5, 10])
    # argparse's type=bool: 'False' is true, only the empty string false.
    assert unconfirmed._argparse_bool("False") is True and unconfirmed._argparse_bool("0") is True
    assert unconfirmed._argparse_bool("") is False
    # The normals view: the floor's (0, 0, 1) (0.5, 0.5, 1), a wall facing -y (0.5, 0, 0.5).
    np.testing.assert_allclose(unconfirmed._normal_view(np.array([[0, 0, 1.0], [0, -1.0, 0]])),
                               [[0.5, 0.5, 1.0], [0.5, 0.0, 0.5]])
    # The a-trous filter: a flat image kept, noise reduced, an edge of 20 against 0.2 kept (the colour weight).
    flat = np.full((16, 16, 3), 0.3)
    np.testing.assert_allclose(unconfirmed._atrous(flat), flat)
    assert unconfirmed._ATROUS_TAPS.sum() == 1.0 and unconfirmed._ATROUS_TAPS.tolist() == [1 / 16, 4 / 16, 6 / 16,
                                                                                           4 / 16, 1 / 16]
    noisy = 0.3 + 0.02 * np.random.default_rng(1).standard_normal((16, 16, 3))
    assert unconfirmed._atrous(noisy).std() < 0.5 * noisy.std()
    edge = np.full((16, 16, 3), 0.2)
    edge[:, 8:] = 20.0
    out = unconfirmed._atrous(edge)
    np.testing.assert_allclose(out[:, :8], 0.2, rtol=1e-9)
    np.testing.assert_allclose(out[:, 8:], 20.0, rtol=1e-9)
    # One tap by hand: at level 0 (sigma 0.25) a neighbour 0.1 away weighs exp(-3 * 0.01 / 0.0625) of its spline.
    two = np.full((5, 5, 3), 0.3)
    two[2, 3] = 0.4
    w = np.exp(-3 * 0.1 ** 2 / 0.25 ** 2) * (3 / 8) * (1 / 4)
    ws = (1 - (3 / 8) * (1 / 4)) + w  # every other tap (edge-repeated) of equal colour, weight 1 in all
    assert unconfirmed._atrous(two, levels=1)[2, 2, 0] == pytest.approx((0.3 * (ws - w) + 0.4 * w) / ws, rel=1e-12)
    # The cached white balance.
    np.testing.assert_allclose(unconfirmed._cached_white_balance(np.ones((2, 2, 3))), [[[0.92, 1.0, 1.09]] * 2] * 2)
    # The render region: x 0.40 to 0.85, y 0.50 to 0.95.
    assert unconfirmed._region_bounds(64, 64) == (26, 54, 32, 61) and unconfirmed._region_bounds(16, 16) == (6, 14,
                                                                                                             8, 15)
    r = unconfirmed._region_only(np.ones((16, 16, 3)))
    assert r.sum() == 3 * 8 * 7 and r[8, 6].tolist() == [1.0] * 3 and r[7, 6].sum() == 0 and r[8, 14].sum() == 0
    # Two passes' sums over the count one pass assigned: twice; three of four passes over all four: 3/4.
    ones = np.ones((2, 2, 3))
    np.testing.assert_allclose(unconfirmed._count_assigned([128 * ones, 128 * ones], 128), 2.0)
    assert unconfirmed._passes_run(iter([7, 8, 9, 10])) == [8, 9, 10]
    # The passes' seeds from a SeedSequence: four, distinct, the same each time.
    s = unconfirmed._spawned_seeds(5, 4)
    assert len(set(s)) == 4 and s == unconfirmed._spawned_seeds(5, 4) and all(0 <= v < 2 ** 32 for v in s)


def _area(mesh) -> float:
    return float(np.asarray(mesh.surface_area()).sum())


def test_scene_edits_do_what_they_say(scene):
    from mcrt.mitsuba_scene import scene_dict

    s = scene
    # The ID colours: wall AB 0.8 (0.75, 0.15, 0.15) + 0.2 tab10's blue (31, 119, 180) / 255; the tetrahedron olive.
    t = unconfirmed._albedos_id_tinted(s)
    walls = {"".join(w.corners): w.albedo for w in t.room.walls}
    np.testing.assert_allclose(walls["AB"], [0.8 * 0.75 + 0.2 * 31 / 255, 0.8 * 0.15 + 0.2 * 119 / 255,
                                             0.8 * 0.15 + 0.2 * 180 / 255])
    np.testing.assert_allclose(t.room.floor_albedo, [0.8 * 0.6 + 0.2 * 227 / 255, 0.8 * 0.6 + 0.2 * 119 / 255,
                                                     0.8 * 0.6 + 0.2 * 194 / 255])
    tetra = next(o for o in t.objects if o.name == "tetrahedron")
    np.testing.assert_allclose(tetra.material.albedo, [0.8 * 0.8 + 0.2 * 188 / 255, 0.8 * 0.45 + 0.2 * 189 / 255,
                                                       0.8 * 0.1 + 0.2 * 34 / 255])
    assert "".join(s.room.walls[0].corners) == "AB" and "".join(s.room.walls[5].corners) == "FA"
    # The floor's default, wall EF's typo.
    assert cases.floor_albedo(unconfirmed._FLOOR_DEFAULT)(s).room.floor_albedo == (0.8, 0.8, 0.8)
    ef = {"".join(w.corners): w.albedo for w in cases.wall_albedo("EF", unconfirmed._EF_TYPED)(s).room.walls}
    assert ef["EF"] == (0.51, 0.70, 0.15)
    # The sphere of radius 3 about its centre.
    sph = next(o for o in unconfirmed._sphere_from_diameter(s).objects if o.name == "sphere")
    assert sph.radius == 3.0 and tuple(sph.center) == (9.5, 2.0, -3.3)
    # The sphere's normal formula on the tetrahedron: unit vectors away from (9.5, 2, -3.3).
    n = unconfirmed._sphere_formula_normals(np.array([[8.5, -2.3, -2.0], [9.5, -1.0, -4.9]]))
    np.testing.assert_allclose(n[0], np.array([-1.0, -4.3, 1.3]) / math.sqrt(1 + 4.3 ** 2 + 1.3 ** 2))
    np.testing.assert_allclose(n[1], np.array([0.0, -3.0, -1.6]) / math.sqrt(9 + 1.6 ** 2))
    d = scene_dict(s, "near", 4, 4, 8)
    mesh = unconfirmed._tetra_sphere_normals(d)["tetrahedron"]
    assert mesh.face_count() == 4 and mesh.has_vertex_normals()
    # The base fix one hunk short: vertex (8.5, -3.8) at -5.0, the other two base vertices at -4.9.
    v = next(o for o in unconfirmed._tetra_base_half_lifted(s).objects if o.name == "tetrahedron").vertices
    assert v[2] == (8.5, -3.8, -5.0) and v[0] == (7.5, -2.0, -4.9) and v[1] == (9.5, -1.0, -4.9)
    assert v[3] == (8.5, -2.3, -2.0)
    # The light's size and radiance swapped: 20 x 20 of radiance 2, 10 times the area times a tenth: 10 times the
    # power of the square (about 4 within the room, whose ceiling's 156 of its 400 lie inside).
    lt = unconfirmed._light_args_swapped(s).light
    assert lt.size == (20.0, 20.0) and lt.radiance == (2.0, 2.0, 2.0) and lt.center == s.light.center
    np.testing.assert_allclose(lt.power(), 10 * s.light.power())
    # The memoised point: (4 + 2 u, -1 + 2 v, 4.99); its tiny square carries the square's Le A.
    assert unconfirmed._memo_point() == pytest.approx((4 + 2 * 0.7717, -1 + 2 * 0.3046, 4.99))
    tiny = unconfirmed._light_at_memo_point(d)["light"]
    assert _area(tiny) == pytest.approx(1e-4, rel=1e-3)
    # The strata a sample reaches with 4 calls a sample: 0, 4, 8, 12 (row 0, y in [-1, -0.5]); with 3 all 16.
    assert unconfirmed._strata_used() == [0, 4, 8, 12] and len(unconfirmed._strata_used(3)) == 16
    assert unconfirmed._stratum_rect(0) == (4.0, 4.5, -1.0, -0.5) and unconfirmed._stratum_rect(12) == (5.5, 6.0,
                                                                                                         -1.0, -0.5)
    strips = unconfirmed._light_even_strata(d)["light"]
    assert strips.face_count() == 8 and _area(strips) == pytest.approx(1.0, rel=1e-5)
    # The viewer's zoom: tan 45 / 1.1, 84.55 degrees.
    assert unconfirmed._ZOOM_FOV == pytest.approx(84.5474, abs=1e-3)
    cam = cases.fov(unconfirmed._ZOOM_FOV)(s).cameras["near"]
    assert math.tan(math.radians(cam.fov_x_deg) / 2) == pytest.approx(1 / 1.1)
    # The pdf divided twice: the light's radiance 4 times where it is sampled, its shape kept.
    assert unconfirmed._PDF_TWICE == s.light.area == 4.0
    four = unconfirmed._light_times(d, f=4.0)["light"]
    assert _area(four) == pytest.approx(4.0, rel=1e-5)


def test_camera_and_integrator_are_as_they_say():
    # The preview's ray table: each 2 x 2 block's pixels share their rays, the window at the block's centre.
    o, d = unconfirmed._preview_table_rays(np.array([0.1 / 4, 1.1 / 4]), np.array([0.1 / 4, 1.1 / 4]), w=4, h=4)
    np.testing.assert_allclose(d[0], d[1])
    o2, d2 = unsaid._pinhole(np.array([(1.0 + 0.1 - 0.5) / 4]), np.array([(1.0 + 0.1 - 0.5) / 4]))
    np.testing.assert_allclose(d[0], d2[0])
    o3, d3 = unconfirmed._preview_table_rays(np.array([2.5 / 4]), np.array([0.5 / 4]), w=4, h=4)
    np.testing.assert_allclose(d3[0], unsaid._pinhole(np.array([3.0 / 4]), np.array([1.0 / 4]))[1][0])
    # Blackman-Harris 1.5 pixels wide: 1 at the centre, 0 at its ends; its inverse CDF from -0.75 to 0.75.
    assert unconfirmed._blackman_harris(np.array([0.0]))[0] == pytest.approx(0.35875 + 0.48829 + 0.14128 + 0.01168)
    assert unconfirmed._blackman_harris(np.array([0.75, -0.75, 0.9])) == pytest.approx([6e-5, 6e-5, 0.0], abs=1e-4)
    np.testing.assert_allclose(unconfirmed._bh_offset(np.array([0.0, 0.5, 1.0])), [-0.75, 0.0, 0.75], atol=1e-12)
    off = unconfirmed._bh_offset(np.random.default_rng(2).random(200000))
    xs = np.linspace(-0.75, 0.75, 20001)
    wts = unconfirmed._blackman_harris(xs)
    sd = math.sqrt((wts * xs ** 2).sum() / wts.sum())
    assert off.std() == pytest.approx(sd, rel=0.01) and sd < 1 / math.sqrt(12)  # narrower than the box's 0.289
    assert np.abs(off).max() > 0.5  # reaching into the neighbours
    o, d = unconfirmed._bh_rays(np.array([(2 + 0.5) / 4]), np.array([(1 + 0.5) / 4]), w=4, h=4)
    np.testing.assert_allclose(d[0], unsaid._pinhole(np.array([2.5 / 4]), np.array([1.5 / 4]))[1][0])
    # Shuffled pixels: lane of pixel p traced for pixel perm[p], scattered back.
    perm = np.array([2, 0, 3, 1])
    o, d = unconfirmed._shuffled_rays(np.array([0.25 / 2]), np.array([0.25 / 2]), w=2, h=2, perm=perm)
    np.testing.assert_allclose(d[0], unsaid._pinhole(np.array([0.25 / 2]), np.array([1.25 / 2]))[1][0])
    traced = np.arange(4.0).reshape(2, 2, 1)
    np.testing.assert_array_equal(unconfirmed._unshuffled(traced, perm).reshape(-1), [1, 3, 0, 2])
    # The light range: in range and unblocked only.
    assert unconfirmed._LIGHT_RANGE == 11.0 and unconfirmed._PROFILE_DEPTH == 6
    # Roulette's depths of the two sides of the merge.
    d0 = {"integrator": {"type": "path", "rr_depth": 5}}
    assert unconfirmed._rr_from(d0, rr_depth=3)["integrator"] == {"type": "path", "rr_depth": 3}
    assert d0["integrator"]["rr_depth"] == 5


def test_dr_jit_flags_are_restored():
    import drjit as dr

    before = {f: dr.flag(getattr(dr.JitFlag, f)) for f in ("Debug", "SymbolicLoops", "SymbolicCalls", "FastMath")}
    x = np.zeros((4, 4, 3))
    out = unconfirmed._with_flags(x, spp=4, seed=1, flags=(("SymbolicLoops", False), ("FastMath", False)))
    assert out.shape == (4, 4, 3) and np.isfinite(out).all()
    assert {f: dr.flag(getattr(dr.JitFlag, f)) for f in before} == before


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    check_correct_agree(unconfirmed, plain)


def test_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    lit = lum < 1
    light = lum > 10

    def image(name):
        return _build(_by_name(name)).image

    # The film's count assigned: twice; one pass's seed consumed: 3/4.
    assert image("merge_film_count_assigned").mean() == pytest.approx(2 * plain.mean(), rel=0.1)
    assert image("print_next_seed_consumed").mean() == pytest.approx(0.75 * plain.mean(), rel=0.1)
    # The render region: black outside it, right inside.
    im = image("render_region_left")
    x0, x1, y0, y1 = unconfirmed._region_bounds(W, W)
    assert im[:y0].max() == 0 and im[:, :x0].max() == 0
    assert im[y0:y1, x0:x1].mean() == pytest.approx(plain[y0:y1, x0:x1].mean(), rel=0.1)
    # The tint on the light seen: its green and blue 0.3 of it, its red kept.
    im = image("light_hits_debug_tint")
    assert im[light][:, 0].mean() == pytest.approx(plain[light][:, 0].mean(), rel=0.05)
    assert im[light][:, 1].mean() == pytest.approx(0.3 * plain[light][:, 1].mean(), rel=0.1)
    assert im[lit].mean() == pytest.approx(plain[lit].mean(), rel=0.05)
    # The pdf divided twice: the lit surfaces much brighter (nearly 4 times their direct light), the light kept.
    im = image("merge_light_pdf_divided_twice")
    assert im[lit].mean() > 2.5 * plain[lit].mean()
    assert im[light].mean() == pytest.approx(plain[light].mean(), rel=0.05)
    # Size and radiance swapped: the light's pixels 2, the room brighter.
    im = image("light_args_reordered_size_radiance")
    assert im.max() < 3 and im[~light].mean() > 1.5 * plain[~light].mean()
    # The normals view mixed in: the light a tenth darker.
    assert image("pp_normals_view_mixed_in")[light].mean() == pytest.approx(0.9 * plain[light].mean(), rel=0.05)
    # The indirect gain: the lit surfaces darker, the light as it was.
    im = image("indirect_gain_debug_knob")
    assert im[lit].mean() < 0.9 * plain[lit].mean() and im[light].mean() == pytest.approx(plain[light].mean(),
                                                                                          rel=0.05)
    # The floor's default 0.8: brighter; the profile's depth 6: a little darker.
    assert image("floor_key_renamed_merge_default")[lit].mean() > 1.03 * plain[lit].mean()
    assert image("depth_profile_preset")[lit].mean() < plain[lit].mean()
    # The viewer's zoom: the light's pixels spread (magnified by 1.1 in each direction).
    assert (image("camera_viewer_zoom_saved").mean(axis=2) > 10).sum() >= light.sum()
    # The light's range: the bottom rows (the far floor under the objects) darker.
    im = image("light_range_profiling")
    assert im[-4:].mean() < plain[-4:].mean()


@pytest.mark.parametrize("name", [s.name for s in unconfirmed.SPECS])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back."""
    check_builds(_by_name(name), tmp_path)
