"""The thirty-fourth class (mcrt.grade.accuracy.unlisted) is well formed and builds what its specs say: the same
checks as test_accuracy_unexamined's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x 16,
never graded), on this class's cases, the BVHs, intersection tests, epsilons, buffers and number formats its Mitsuba
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
from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unanticipated, unasked, unattended,
                                 unattested, unbeknown, unbidden, unconfirmed, unconsidered, unexamined, unforeseen,
                                 unguessed, unheard, unheralded, unlisted, unlooked, unmet, unnoticed, unprompted,
                                 unrecorded, unremarked, unremembered, unsaid, unseen, unsought, untold, untried,
                                 unvisited, unwonted)
from mcrt.image_files import read_image, srgb_oetf

_by_name = partial(by_name, unlisted.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought, unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted,
           unremarked, unremembered, unnoticed, unrecorded, unattended, unattested, unconsidered, unanticipated,
           unexamined, unconfirmed)  # the last, its twin: written the same day, apart


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


@pytest.fixture(scope="module")
def scene():
    from mcrt.scene import load_scene

    return load_scene()


def test_specs_are_new_worded_and_in_categories():
    check_specs(unlisted, _OTHERS, mistakes=28)
    check_new_truths(unlisted, _OTHERS)
    assert len(unlisted.MISTAKES) == 28 and {len(v) for v in unlisted.CATEGORIES.values()} <= {3, 4}
    assert list(unlisted.CATEGORIES) == list(unnoticed.CATEGORIES)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unlisted)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unlisted)
    assert sum(s.held_out for s in unlisted.MISTAKES) == 12 and sum(s.held_out for s in unlisted.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    check_old_causes(unlisted, _OTHERS)
    assert unlisted._EARLIER[-1] is unexamined and unlisted._EARLIER[-2] is unanticipated
    assert unconsidered in unlisted._EARLIER and unattested in unlisted._EARLIER
    assert set(unlisted._REWORDED) == set(unlisted.CAUSES)


def test_seeds_differ_from_the_other_classes():
    check_seeds(unlisted, _OTHERS, 2101000)


def test_the_command_knows_the_class():
    check_command(unlisted, "unlisted")


def test_correct_writers_read_back(tmp_path):
    """np.rint's PNG is within a code of the rounded one (half to even only on exact halves) and reads back."""
    x = _image()
    path = unlisted._write_png_rint(x, tmp_path)
    codes = pillow_codes(path).astype(int)
    np.testing.assert_array_equal(codes, np.rint(fresh._srgb(x) * 255.0))
    assert np.abs(codes - blind._srgb8(x).astype(int)).max() <= 1
    assert np.rint(2.5) == 2.0 and np.rint(3.5) == 4.0  # half to even
    np.testing.assert_allclose(read_image(path).mean, x, atol=0.01)


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    import png

    x = _image()
    for d in "abc":
        (tmp_path / d).mkdir()
    # The float16 buffer: 65535 * 1.0 overflows to inf, cast to 0; a code of 0.5's sRGB kept to float16's precision.
    with np.errstate(over="ignore"):
        assert np.isinf(np.float16(65535.0)) and np.float16(65504.0) == 65504.0 and np.isinf(np.float16(65520.0))
    codes = unlisted._float16_codes16(np.array([[[20.0, 1.0, 0.0], [0.5, 0.2, 0.01]]]))
    assert codes[0, 0].tolist() == [0, 0, 0]
    c5 = srgb_oetf(0.5) * 65535  # 48190.4: float16 steps of 32 from 32768, 48192
    assert codes[0, 1, 0] == 48192 == int(np.float16(c5)) and abs(int(codes[0, 1, 0]) - c5) < 16
    path = unlisted._write_png16_float16(x, tmp_path / "a")
    w, h, rows, info = png.Reader(filename=str(path)).read()
    arr = np.array([list(r) for r in rows]).reshape(h, w, 3)
    assert info["bitdepth"] == 16 and (w, h) == (W, W)
    np.testing.assert_array_equal(arr, unlisted._float16_codes16(x))
    np.testing.assert_allclose(arr / 65535.0, srgb_oetf(x), atol=2e-3)  # x under 0.95: no overflow here
    # The half-float EXR of the render times 1/256.
    path = unlisted._write_exr_half_prescaled(x, tmp_path / "b")
    np.testing.assert_allclose(read_image(path).mean, x / 256.0, rtol=1e-3)
    # sRGB by the floats' bits: log2 and exp2 exact at powers of two, linear between; 0.5 -> 199 (188), 0.2 -> 120.
    assert unlisted._fast_log2(np.array([1.0, 2.0, 0.25, 1.5])).tolist() == [0.0, 1.0, -2.0, 0.5]
    assert unlisted._fast_exp2(np.array([0.0, 3.0, -1.0, 0.5])).tolist() == [1.0, 8.0, 0.5, 1.5]
    # 0.5 ** (1 / 2.4): log2 -1, times 1 / 2.4 = -0.41667, exp2 ~ 0.5 (1 + 0.58333) = 0.79167; 1.055 * - 0.055.
    v = 1.055 * 0.5 * (1 + (1 - 1 / 2.4)) - 0.055
    assert unlisted._srgb_fast(np.array([0.5]))[0] == pytest.approx(v, abs=1e-6)
    assert math.floor(v * 255 + 0.5) == 199 and math.floor(srgb_oetf(0.5) * 255 + 0.5) == 188
    codes = pillow_codes(unlisted._write_png_srgb_fast(x, tmp_path / "c")).astype(int)
    np.testing.assert_array_equal(codes, np.floor(unlisted._srgb_fast(x) * 255 + 0.5))
    assert 0 < np.abs(codes - blind._srgb8(x).astype(int)).max() <= 12


def test_post_processes_do_what_they_say():
    # R11G11B10_FLOAT truncated: 0.3 = 0.6 * 2^-1 kept to 7 significant bits, floor(0.3 * 256) / 256 = 0.296875;
    # blue to 6, floor(0.3 * 128) / 128 = 0.296875; 0.7 = 0.7 * 2^0: floor(0.7 * 128) / 128, floor(0.7 * 64) / 64;
    # 1 and 20 exact; at most 1 / 64 (1 / 32) low.
    got = unlisted._r11g11b10(np.array([[[0.3, 1.0, 0.3], [20.0, 0.7, 0.7]]]))
    assert got[0, 0].tolist() == [0.296875, 1.0, 0.296875]
    assert got[0, 1].tolist() == [20.0, 89 / 128, 44 / 64] == [20.0, math.floor(0.7 * 128) / 128,
                                                                math.floor(0.7 * 64) / 64]
    x = np.geomspace(1e-3, 30, 1001)
    r = unlisted._packed_float_truncated(x, 6) / x
    assert r.max() <= 1.0 and r.min() > 1 - 1 / 64 and (unlisted._packed_float_truncated(x, 5) / x).min() > 1 - 1 / 32
    assert unlisted._packed_float_truncated(np.array([1e6, -1.0]), 6).tolist() == [65024.0, 0.0]
    # RGB10_A2 UNORM: 20 -> 1, 0.5 -> 512 / 1023.
    assert unlisted._rgb10a2(np.array([20.0, 0.5, -0.1])).tolist() == [1.0, 512 / 1023, 0.0]
    # Schraudolph's exp(0): the double of high word 1072693248 - 60801 = 0x3FEF127F: (1 + 0xF127F / 2^20) / 2.
    assert 1072693248 - 60801 == 0x3FEF127F
    assert unlisted._exposed_fast(np.array(1.0)) == pytest.approx((1 + 0xF127F / 2 ** 20) / 2, rel=1e-12)
    assert unlisted._exposed_fast(np.array(1.0)) == pytest.approx(0.97101, abs=1e-5)
    assert float(unlisted._schraudolph_exp(np.array(1.0))) == pytest.approx(math.e, rel=0.04)


def test_the_student_bvh_is_rtnw_s(scene):
    names, tris, sphere = unlisted._prims()
    assert len(tris) == 26 and names[-1] == "sphere" and names[:2] == ("wall_AB", "wall_AB")
    boxes = unlisted._prim_boxes(tris, sphere)
    np.testing.assert_allclose(boxes[-1], [[8.0, 0.5, -4.8], [11.0, 3.5, -1.8]])
    order, paths, leaves = unlisted._student_bvh()
    assert sorted(order) == list(range(27)) and order[-1] == 26 and len(leaves) == 16
    # The root's longest axis is x (16 of 16 x 12 x 10): the left half the 13 boxes starting furthest towards -x.
    assert all(paths[i][0] == (0, 0) for i in order[:13]) and all(paths[i][0] == (0, 1) for i in order[13:])
    assert {names[i] for i in order[:4]} == {"wall_AB", "wall_FA"}
    # Every leaf's box holds its primitives'.
    for i, path in paths.items():
        assert any(np.all(lf[0] <= boxes[i, 0] + 1e-12) and np.all(boxes[i, 1] <= lf[1] + 1e-12) for lf in leaves)
    # A span of 3 sorted on its longest axis and halved 1 | 2; a span of 2 kept in list order.
    toy = np.array([[[2, 0, 0], [3, 1, 1]], [[0, 0, 0], [1, 1, 1]], [[4, 0, 0], [5, 1, 1]]], np.float64)
    o, p, lv = unlisted._rtnw_bvh(toy)
    assert o == [1, 0, 2] and p[1] == ((0, 0),) and p[0] == ((0, 1), (0, 0)) and p[2] == ((0, 1), (0, 1))
    # The traversals' winners: the last hit in the tree's order; the first leaf visited front to back.
    hits = np.array([[5.0, 2.0, np.inf], [np.inf, 7.0, 3.0]])
    np.testing.assert_array_equal(unlisted._winner_last_in_order(hits, o), [0, 2])
    keys = unlisted._ordered_keys(np.array([[1.0, 0, 0], [-1.0, 0, 0]]), p)
    # Prim 0's path right then left: bits 1, 0 (key 2) for a ray towards +x, 0, 1 (key 1) towards -x.
    np.testing.assert_array_equal(keys, [[2, 0, 3], [1, 2, 0]])
    np.testing.assert_array_equal(unlisted._winner_first_visited(hits, keys), [1, 2])


def test_intersections_agree_with_mitsuba():
    eye, r, u, f, k = unsaid._frame()
    rng = np.random.default_rng(4)
    o, d = unsaid._pinhole(rng.random(400), rng.random(400))
    o, d = np.array(o, np.float64), np.asarray(d, np.float64)
    t = unlisted._all_hits(o, d).min(axis=1)
    tm, valid = unguessed._first_hit(unsaid._loaded(8), o, d)
    assert valid.all()
    np.testing.assert_allclose(t, tm, rtol=1e-4, atol=1e-4)
    # The sphere by hand: from (9.5, 2, 0) straight down, 3.3 - 1.5 = 1.8 to the top.
    assert unlisted._sphere_hits(np.array([[9.5, 2.0, 0.0]]), np.array([[0.0, 0.0, -1.0]]), unsaid._sphere())[0] == (
        pytest.approx(1.8))
    # The RTNW and closest moves: a ray to the tetrahedron's nearest face started just before it, or left.
    o1, d1, used = unlisted._after_closest(o, d)
    np.testing.assert_allclose(np.linalg.norm(o1 - o, axis=1), t - 1e-3, atol=1e-9)
    assert not used.any()


def test_first_hits_of_the_camera_mistakes(scene):
    rng = np.random.default_rng(6)
    o, d = unsaid._pinhole(rng.random(4000), rng.random(4000))
    o, d = np.array(o, np.float64), np.asarray(d, np.float64)
    hits = unlisted._all_hits(o, d)
    near = hits.argmin(axis=1)
    names = unlisted._prims()[0]
    # RTNW's unshrunk right child: only rays meeting the tetrahedron change (its far face later in the tree).
    _, paths, _ = unlisted._student_bvh()
    order = unlisted._student_bvh()[0]
    w = unlisted._winner_last_in_order(hits, order)
    changed = w != near
    assert changed.any() and {names[i] for i in near[changed]} == {"tetrahedron"}
    assert {names[i] for i in w[changed]} == {"tetrahedron"}
    # The any-hit query: the tetrahedron and the light mostly lost, the sphere kept.
    a = unlisted._winner_first_visited(hits, unlisted._ordered_keys(d, paths))
    nm = np.array(names)
    lost = {n: np.mean(nm[a[nm[near] == n]] != n) for n in set(names) if (nm[near] == n).any()}
    assert lost["light"] == 1.0 and 0.5 < lost["tetrahedron"] < 0.8 and 0.1 < lost["sphere"] < 0.3
    assert all(lost[n] == 0.0 for n in lost if n.startswith("wall_") or n in ("floor", "ceiling"))
    assert set(nm[a[(nm[near] == "sphere") & (nm[a] != "sphere")]]) == {"floor"}
    # The depth buffer: codes by hand, a code about 0.04 deep at 5 and 0.07 at 7; the light mostly loses.
    z = np.array([5.0, 7.0])
    step = 1.0 / (65535 * 100.0 / (100.0 - 0.01) * 0.01 / z ** 2)
    np.testing.assert_allclose(step, [0.038, 0.075], atol=1e-3)
    assert unlisted._depth_code(5.0) == round(65535 * 100 / 99.99 * (1 - 0.01 / 5))
    o2, _, _ = unlisted._after_depth_buffer(o, d)
    moved = np.any(o2 != o, axis=1)
    on_light = np.array([names[i] == "light" for i in near])
    assert not (moved & ~on_light).any() and 0.6 < moved[on_light].mean() < 1.0
    assert np.all(o2[moved, 2] > 4.99) and np.all(o2[moved, 2] < 5.0)
    # The light out of the BVH: every camera ray on it moved past its plane; the mirror's reflections too.
    o3, d3, used = unlisted._after_light_unlisted(o, d)
    assert np.all(np.any(o3[on_light] != o[on_light], axis=1)) and np.all(o3[on_light, 2] > 4.99)
    assert set(np.unique(used)) == {0, 1} and np.all(np.array([names[i] for i in near[used == 1]]) == "sphere")
    # The tangent's pole: tan(radians(90)) finite, 1.633e16; a ray off the centre perpendicular to the view.
    assert unlisted._TAN_90 == pytest.approx(1.633123935319537e16) and math.isfinite(unlisted._TAN_90)
    _, dd = unlisted._pinhole_tan(np.array([0.75, 0.5]), np.array([0.5, 0.25]), half_tan=unlisted._TAN_90)
    np.testing.assert_allclose(dd, [[0.0, -1.0, 0.0], [0.0, 0.0, 1.0]], atol=1e-12)


def test_light_samples_and_epsilons_are_as_they_say(scene):
    # The scene's extent: sqrt(16^2 + 12^2 + 10^2) = 22.36; its epsilon 0.2236.
    assert unlisted._EPS_SCENE == pytest.approx(0.01 * math.sqrt(500.0))
    # A light sample by hand: from (5, 0, -5) straight below the light's centre, normal up: 20 * rho / pi * A / d^2.
    p, n = np.array([[5.0, 0.0, -5.0]]), np.array([[0.0, 0.0, 1.0]])
    q = np.array([[5.0, 0.0, 4.99]])
    got = unlisted._lit(p, n, q, np.ones((1, 3)), np.array([True]))
    np.testing.assert_allclose(got, 20.0 / math.pi * 4.0 / 9.99 ** 2)
    np.testing.assert_allclose(unlisted._lit(p, n, q, np.ones((1, 3)), np.array([False])), 0.0)
    # The cosine at the light floored at 0.1: a grazing sample (cos 0.01) counted as 0.1.
    q2 = np.array([[15.0, 0.0, -4.9]])
    a = unlisted._lit(p, n, q2, np.ones((1, 3)), np.array([True]))
    b = unlisted._lit(p, n, q2, np.ones((1, 3)), np.array([True]), cos_light=lambda wi: np.maximum(wi[:, 2], 0.1))
    assert b[0, 0] / a[0, 0] == pytest.approx(0.1 / (0.1 / math.hypot(10.0, 0.1)))
    # Segments and boxes: a segment through a box, one stopping short of it, one beside it.
    boxes = np.array([[[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]])
    o = np.array([[-1.0, 0.5, 0.5], [-1.0, 0.5, 0.5], [-1.0, 2.0, 0.5]])
    qq = np.array([[2.0, 0.5, 0.5], [-0.01, 0.5, 0.5], [2.0, 2.0, 0.5]])
    assert unlisted._segments_meet_boxes(o, qq, boxes).tolist() == [True, False, False]
    # A flat box (the light's) met by a segment ending on its plane only if it reaches it.
    flat = np.array([[[4.0, -1.0, 4.99], [6.0, 1.0, 4.99]]])
    assert unlisted._segments_meet_boxes(np.array([[5.0, 0.0, -5.0]]), np.array([[5.0, 0.0, 4.99]]), flat).tolist() == [
        False]
    # The tetrahedron's normals outwards, its base facing down.
    nf = unlisted._tetra_face_normals()
    np.testing.assert_allclose(nf[3], [0.0, 0.0, -1.0])
    # The room wound outwards: walls (normal's z 0) and the ceiling; not the floor.
    wo = unlisted._wound_outwards(np.array([[0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]),
                                  np.array([[5.0, -6.0, 0.0], [5.0, 0.0, 5.0], [5.0, 0.0, -5.0], [8.5, -2.3, -4.9]]))
    assert wo.tolist() == [True, True, False, False]


def test_scene_edits_do_what_they_say(scene):
    from mcrt.mitsuba_scene import scene_dict

    names, tris = unlisted._triangles()
    # The projection along np.argmax(n): DE's inward normal (-0.89, -0.45, 0) picks z, EF's (0, -1, 0) x, the ceiling's
    # and the light's and the tetrahedron's base's (0, 0, -1) x: zero components, no area.
    dg = {n for n, g in zip(names, unlisted._projection_degenerate(tris)) if g}
    assert dg == {"wall_DE", "wall_EF", "ceiling", "tetrahedron", "light"}
    assert unlisted._projection_degenerate(tris)[names.index("tetrahedron"):][:4].tolist() == [False, False, False,
                                                                                               True]
    d = scene_dict(scene, "near", 4, 4, 8)
    e = unlisted._projection_edit(d)
    assert "wall_DE" not in e and "ceiling" not in e and "light" in e and e["tetrahedron"].face_count() == 3
    assert _by_name("triangle_projection_argmax_signed").hide_emitters
    # The colours left in the scene's order after the build: triangle order[k] gets colour k.
    cols = unlisted._colours_after_build()
    own = unlisted._triangle_colours()
    order, _, _ = unlisted._rtnw_bvh(unlisted._prim_boxes(tris))
    for k, i in enumerate(order):
        np.testing.assert_array_equal(cols[i], own[k])
    by = {n: set() for n in names}
    for n, c in zip(names, cols):
        by[n].add(tuple(c))
    assert by["wall_AB"] == {(0.75, 0.15, 0.15)} and by["wall_BC"] == {(0.6, 0.6, 0.6)}
    assert by["floor"] == {(0.75, 0.7, 0.15), (0.15, 0.2, 0.75)} and (0.0, 0.0, 0.0) in by["tetrahedron"]
    e = unlisted._colours_reordered(d)
    assert "wall_AB" not in e and "wall_AB_0" in e and "light_1" in e and sum(k.startswith("floor_") for k in e) == 4
    # RGB565 by truncation.
    assert unlisted._rgb565_truncated((0.6, 0.6, 0.6)) == (18 / 31, 37 / 63, 18 / 31)
    assert unlisted._rgb565_truncated((0.75, 0.15, 0.15)) == (23 / 31, 9 / 63, 4 / 31)
    m = unlisted._albedos_rgb565(scene)
    assert m.room.ceiling_albedo == (24 / 31, 50 / 63, 24 / 31)
    tetra = next(o for o in m.objects if o.name == "tetrahedron")
    assert tetra.material.albedo == (24 / 31, 28 / 63, 3 / 31)
    # The correct edits: moved and scaled scenes, the floor and ceiling fanned about their centre, the room subdivided.
    area = lambda t_: 0.5 * np.linalg.norm(np.cross(t_[:, 1] - t_[:, 0], t_[:, 2] - t_[:, 0]), axis=1)  # noqa: E731
    t = unlisted._translated(scene)
    assert t.cameras["near"].eye == (999.0, 1000.0, 0.0) and t.light.center == (1005.0, 1000.0, 4.99)
    c = unlisted._in_centimetres(scene)
    assert c.light.size == (200.0, 200.0) and c.light.radiance == scene.light.radiance
    assert c.cameras["near"].eye == (-100.0, 0.0, 0.0) and c.cameras["near"].fov_x_deg == 90.0
    fan = unlisted._centre_fan(-5.0, up=True)
    assert len(fan) == 6 and np.all(unlisted._triangle_normals(fan)[:, 2] > 0.99)
    assert np.all(unlisted._triangle_normals(unlisted._centre_fan(5.0, up=False))[:, 2] < -0.99)
    np.testing.assert_allclose(fan[:, 0], [[5.0, 0.0, -5.0]] * 6)
    assert area(fan).sum() == pytest.approx(area(unlisted._triangles()[1][12:16]).sum())
    e = unlisted._floor_ceiling_centre_fans(d)
    assert e["floor"].face_count() == 6 and e["ceiling"].face_count() == 6
    sub = unlisted._subdivided(tris[:2])
    assert len(sub) == 8 and area(sub).sum() == pytest.approx(area(tris[:2]).sum())
    np.testing.assert_allclose(unlisted._triangle_normals(sub), np.repeat(unlisted._triangle_normals(tris[:2]), 4,
                                                                          axis=0)[[0, 2, 4, 6, 1, 3, 5, 7]], atol=1e-12)
    assert unlisted._room_subdivided(d)["floor"].face_count() == 16


def test_samples_are_summed_as_they_say():
    # A float16 count stops at 2048.
    assert unlisted._half_count(2047) == 2047 and unlisted._half_count(3000) == 2048 and np.float16(2049) == 2048
    # (rand() % 16) / 15: 0 and 1 both reached.
    u, v = unlisted._offsets_mod_16(np.random.default_rng(1), 400, w=4, pixels=4)
    assert u.min() == 0.0 and u.max() == 1.0 and len(np.unique(u)) == 16
    u, v = unlisted._offsets_8bit(np.random.default_rng(1), 400, w=4, pixels=4)
    assert u.min() >= 0.5 / 256 and u.max() <= 255.5 / 256
    # A float32 running total: 1e5 + 0.001 loses the small sample, so its pixel's difference is 0.
    s = np.zeros((2, 2, 3))
    s[0] = 1e5 / 2
    s[1, 0] = 0.001
    got = unlisted._prefix_sums_float32(s)
    np.testing.assert_allclose(got[0], 1e5)
    np.testing.assert_array_equal(got[1], 0.0)
    # The float32 camera: its rays within float32's rounding of the float64 ones.
    fx, fy = np.random.default_rng(2).random((2, 100))
    o32, d32 = unlisted._pinhole_float32(fx, fy)
    o64, d64 = unsaid._pinhole(fx, fy)
    np.testing.assert_allclose(d32, d64, atol=1e-6)
    assert np.any(d32 != d64) and np.all(o32 == o64)


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    check_correct_agree(unlisted, plain)


def test_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    lit = lum < 1
    light = lum > 10

    def image(name):
        return _build(_by_name(name)).image

    # The float16 count: twice as bright; the half EXR's 1/256 and the fast exp's 0.971 are in the writer and post.
    assert image("count_float16_stalls_2048").mean() == pytest.approx(2 * plain.mean(), rel=0.1)
    assert _by_name("count_float16_stalls_2048").declared_spp == 4096
    # The light out of the BVH: not seen; the sphere given the light's material: brighter than the mirror.
    assert image("light_appended_after_bvh_build")[light].max() < 10
    assert image("sphere_material_index_before_light").mean() > plain.mean()
    # The shadow rays' origin below the floor: the lit surfaces darker; the leaves' boxes: darker still.
    assert image("shadow_origin_along_light_normal")[lit].mean() < 0.9 * plain[lit].mean()
    assert image("bvh_shadow_leaf_box_as_hit")[lit].mean() < 0.8 * plain[lit].mean()
    # The walls' and the ceiling's bounces out of the room: darker, the light as it was.
    im = image("bounce_about_wound_normal")
    assert im[lit].mean() < 0.9 * plain[lit].mean() and im[light].mean() == pytest.approx(plain[light].mean(),
                                                                                         rel=0.05)
    # The tangent's pole: the light nowhere, four wedges.
    assert image("fov_tan_full_angle_pole").max() < 10
    # The projected triangle test: the ceiling and the light gone.
    assert image("triangle_projection_argmax_signed")[:4].max() < 1


@pytest.mark.parametrize("name", [s.name for s in unlisted.SPECS])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back."""
    check_builds(_by_name(name), tmp_path)
