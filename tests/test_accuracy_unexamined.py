"""The thirty-second class (mcrt.grade.accuracy.unexamined) is well formed and builds what its specs say: the same
checks as test_accuracy_unconsidered's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x
16, never graded), on this class's cases, the configs, exporters, tools, checkpoints, passes and merges its Mitsuba
renders are made of, each against values worked out by hand (or by the library whose behaviour it emulates, PyYAML,
where it is installed).
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
from mcrt.grade.accuracy import (unanticipated, blind, cases, fresh, novel, outside, programs, unasked, unattended, unattested,
                                 unbeknown, unbidden, unconsidered, unexamined, unforeseen, unguessed, unheard,
                                 unheralded, unlooked, unmet, unnoticed, unprompted, unrecorded, unremarked,
                                 unremembered, unsaid, unseen, unsought, untold, untried, unvisited, unwonted)
from mcrt.image_files import read_image, srgb_eotf, srgb_oetf

_by_name = partial(by_name, unexamined.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought, unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted,
           unremarked, unremembered, unnoticed, unrecorded, unattended, unattested, unconsidered,
           unanticipated)  # the last, its twin: written the same day, apart


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


@pytest.fixture(scope="module")
def scene():
    from mcrt.scene import load_scene

    return load_scene()


def test_specs_are_new_worded_and_in_categories():
    check_specs(unexamined, _OTHERS, mistakes=28)
    check_new_truths(unexamined, _OTHERS)
    assert len(unexamined.MISTAKES) == 28 and {len(v) for v in unexamined.CATEGORIES.values()} <= {3, 4}
    assert list(unexamined.CATEGORIES) == list(unnoticed.CATEGORIES)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unexamined)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unexamined)
    assert sum(s.held_out for s in unexamined.MISTAKES) == 12 and sum(s.held_out for s in unexamined.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    check_old_causes(unexamined, _OTHERS)
    assert unexamined._EARLIER[-1] is unconsidered and unattested in unexamined._EARLIER
    assert unrecorded in unexamined._EARLIER and unattended in unexamined._EARLIER
    assert set(unexamined._REWORDED) == set(unexamined.CAUSES)


def test_seeds_differ_from_the_other_classes():
    check_seeds(unexamined, _OTHERS, 1901000)


def test_the_command_knows_the_class():
    check_command(unexamined, "unexamined")


def test_correct_writers_read_back(tmp_path):
    """GIMP's Floyd-Steinberg PNG is within a code of the rounded one, its error carried on as worked out by hand;
    ffmpeg's 16-bit PNG reads back as the image."""
    import png

    x = _image()
    for d in "ab":
        (tmp_path / d).mkdir()
    path = unexamined._write_png_floyd_steinberg(x, tmp_path / "a")
    codes = pillow_codes(path).astype(int)
    c8 = blind._srgb8(x).astype(int)
    assert np.abs(codes - c8).max() <= 1 and abs(codes.mean() - (fresh._srgb(x) * 255).mean()) < 0.05
    # A row of 0.3 codes: 0 (error 0.3), 0.43 -> 0, 0.49 -> 0, 0.51 -> 1.
    row = np.full((1, 4, 3), srgb_eotf(0.3 / 255.0))
    assert unexamined._floyd_steinberg_codes(row)[0, :, 0].tolist() == [0, 0, 0, 1]
    # Down-left, down, down-right: a 2 x 2 of 0.3 codes: (0, 0) carries 0.3 * 5/16 down, 0.3 * 1/16 down-right.
    sq = unexamined._floyd_steinberg_codes(np.full((2, 2, 3), srgb_eotf(0.3 / 255.0)))
    assert sq[..., 0].tolist() == [[0, 0], [0, 1]]
    path = unexamined._write_png16_ffmpeg(x, tmp_path / "b")
    w, h, rows, info = png.Reader(filename=str(path)).read()
    assert info["bitdepth"] == 16 and not info["greyscale"] and (w, h) == (W, W)
    arr = np.array([list(r) for r in rows]).reshape(h, w, 3)
    np.testing.assert_array_equal(arr, np.floor(srgb_oetf(x) * 65535 + 0.5))
    np.testing.assert_allclose(read_image(path).mean, x, atol=2e-4)


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    x = _image()
    for d in "abcd":
        (tmp_path / d).mkdir()
    c8 = blind._srgb8(x).astype(int)
    # -auto-gamma: one gamma, the mean's value taken to 50 %; black and white kept.
    flat = np.full((4, 4, 3), srgb_eotf(64 / 255.0))
    assert np.all(np.isin(unexamined._auto_gamma_codes(flat), (127, 128)))  # 255 * 0.5, rounded
    two = np.zeros((2, 2, 3))
    two[0] = 1.0
    two[1, 0] = srgb_eotf(100 / 255.0)
    got = unexamined._auto_gamma_codes(two).astype(int)
    mean = (2 * 3 * 255 + 3 * 100) / 12 / 255
    g = math.log(mean) / math.log(0.5)
    assert got[0].min() == 255 and got[1, 1].max() == 0 and got[1, 0, 0] == math.floor(255 * (100 / 255) ** (1 / g)
                                                                                        + 0.5)
    codes = pillow_codes(unexamined._write_png_auto_gamma(x, tmp_path / "a"))
    assert c8.mean() / 255 > 0.5 and codes.mean() < c8.mean()  # a bright image's mean brought down to 50 %
    assert unexamined._auto_gamma_codes(0.25 * x).mean() > blind._srgb8(0.25 * x).mean()  # a dark one's lifted
    # The screenshot: a flat image kept, a lone bright pixel spread over its neighbours.
    assert np.all(np.abs(unexamined._screenshot_codes(np.full((16, 16, 3), 0.2)).astype(int) - 124) <= 1)
    dot = np.zeros((16, 16, 3))
    dot[8, 8] = 1.0
    shot = unexamined._screenshot_codes(dot).astype(int)
    assert shot[8, 8, 0] < 255 and (shot[7:10, 7:10, 0] > 0).sum() >= 4
    # montage in the glob's text order: tile 10 at place 2, tile 2 at place 8.
    assert unexamined._glob_order() == [0, 1, 10, 11, 12, 13, 14, 15, 2, 3, 4, 5, 6, 7, 8, 9]
    codes = pillow_codes(unexamined._write_png_montage(x, tmp_path / "b")).astype(int)
    np.testing.assert_array_equal(codes[:4, :8], c8[:4, :8])
    np.testing.assert_array_equal(codes[:4, 8:12], c8[8:12, 8:12])  # place 2 (row 0, col 2) <- tile 10 (row 2, col 2)
    np.testing.assert_array_equal(codes[8:12, :4], c8[:4, 8:12])  # place 8 (row 2, col 0) <- tile 2 (row 0, col 2)
    # ProPhoto: white kept, a grey's code 124 (linear 0.2016) written 0.2016 ** (1 / 1.8), a red washed out.
    np.testing.assert_allclose(unexamined._srgb_to_prophoto() @ np.ones(3), 1.0, atol=1e-4)
    grey = unexamined._prophoto_codes(np.full((1, 1, 3), 0.2))[0, 0]
    assert grey.tolist() == [math.floor(255 * srgb_eotf(124 / 255) ** (1 / 1.8) + 0.5)] * 3 == [105] * 3
    red = unexamined._prophoto_codes(np.array([[[0.6, 0.02, 0.02]]]))[0, 0].astype(int)
    assert red[0] < 255 * srgb_oetf(0.6) and red[1] > blind._srgb8(np.array([0.02]))[0]
    assert unexamined._romm_encode(np.array([1 / 1024]))[0] == pytest.approx(16 / 1024)
    codes = pillow_codes(unexamined._write_png_prophoto(x, tmp_path / "c"))
    np.testing.assert_array_equal(codes, unexamined._prophoto_codes(x))
    # The viewer's +0.5 EV: the values times sqrt(2) before the curve.
    codes = pillow_codes(unexamined._write_png_viewer(x, tmp_path / "d"))
    np.testing.assert_array_equal(codes, blind._srgb8(x * math.sqrt(2)))
    assert unexamined._viewer_codes(np.full((1, 1, 3), 0.1))[0, 0, 0] == blind._srgb8(np.array([0.1 * 2 ** 0.5]))[0]


def test_post_processes_do_what_they_say():
    # ACESFitted by hand: a grey stays grey (both matrices' rows sum to 1), 0.18 -> 0.10559, 20 -> 0.9953, 0 -> 0.
    assert unexamined._ACES_IN.sum(axis=1) == pytest.approx(np.ones(3), abs=2e-5)
    assert unexamined._ACES_OUT.sum(axis=1) == pytest.approx(np.ones(3), abs=2e-5)
    v = 0.18
    fit = (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.4329510) + 0.238081)
    got = unexamined._aces_fitted(np.array([[[0.18, 0.18, 0.18], [20.0, 20.0, 20.0], [0.0, 0.0, 0.0]]]))
    np.testing.assert_allclose(got[0, 0], fit, atol=1e-5)
    assert fit == pytest.approx(0.10559, abs=1e-5)
    big = (20 * (20 + 0.0245786) - 0.000090537) / (20 * (0.983729 * 20 + 0.4329510) + 0.238081)
    np.testing.assert_allclose(got[0, 1], big, atol=1e-5)
    assert big == pytest.approx(0.9953, abs=1e-4)
    np.testing.assert_array_equal(got[0, 2], 0.0)
    # The config's 'off' is a boolean: the default branch, ACES; 'none' skips it.
    assert unexamined._tonemap_setting("off") is False and unexamined._tonemap_chosen("off") == "aces"
    assert unexamined._tonemap_chosen("none") == "none" and unexamined._tonemap_chosen("reinhard") == "reinhard"
    # Three machines, the last read top row first.
    a, b, c = (np.full((4, 2, 3), k, np.float64) for k in (1.0, 2.0, 3.0))
    c[0] = 9.0
    out = unexamined._merge_one_flipped([a, b, c], flipped=2)
    np.testing.assert_allclose(out[-1], (1 + 2 + 9) / 3)
    np.testing.assert_allclose(out[0], 2.0)


def test_yaml_readings_match_pyyaml():
    """The YAML 1.1 readings emulated are PyYAML's (checked where PyYAML is installed)."""
    assert unexamined._yaml11_int("051") == 41 and unexamined._yaml11_int("026") == 22
    assert unexamined._yaml11_int("038") == "038" and unexamined._yaml11_int("191") == 191
    assert unexamined._yaml11_int("0") == 0
    yaml = pytest.importorskip("yaml")
    codes = ["191", "038", "051", "026", "140", "000", "007", "099", "255"]
    assert yaml.safe_load("[" + ", ".join(codes) + "]") == [unexamined._yaml11_int(c) for c in codes]
    for word in ("off", "on", "no", "yes", "none", "aces", "reinhard"):
        assert yaml.safe_load(f"t: {word}")["t"] == unexamined._tonemap_setting(word)


def test_scene_edits_do_what_they_say(scene):
    from mcrt.mitsuba_scene import scene_dict

    s = scene
    # YAML's octal codes: wall DE's green 051 -> 41, the tetrahedron's blue 026 -> 22, the rest within half a code.
    m = unexamined._albedos_yaml_octal(s)
    walls = {"".join(w.corners): w.albedo for w in m.room.walls}
    assert walls["DE"][1] == pytest.approx(41 / 255) and walls["DE"][0] == pytest.approx(38 / 255)
    tetra = next(o for o in m.objects if o.name == "tetrahedron")
    assert tetra.material.albedo[2] == pytest.approx(22 / 255) and tetra.material.albedo[1] == pytest.approx(115 / 255)
    own = {"".join(w.corners): w.albedo for w in s.room.walls}
    for k, a in walls.items():
        if k != "DE":
            assert np.abs(np.subtract(a, own[k])).max() <= 0.5 / 255 + 1e-12
    assert m.room.floor_albedo == pytest.approx((153 / 255,) * 3)
    # The MTL's default Kd on every wall, the floor and the tetrahedron kept.
    k = unexamined._walls_kd_default(s)
    assert {w.albedo for w in k.room.walls} == {(0.8, 0.8, 0.8)} and k.room.floor_albedo == s.room.floor_albedo
    # three.js's sRGB decoding: the floor 0.6 -> 0.319, the tetrahedron's blue 0.1 -> 0.010.
    dec = unexamined._albedos_srgb_decoded(s)
    assert dec.room.floor_albedo[0] == pytest.approx(((0.6 + 0.055) / 1.055) ** 2.4, rel=1e-6)
    tetra = next(o for o in dec.objects if o.name == "tetrahedron")
    assert tetra.material.albedo[2] == pytest.approx(0.01002, abs=1e-5)
    # Y up turned to Z up once too often: (x, y, z) -> (x, -z, y).
    moved = next(o for o in unexamined._tetra_y_up_converted(s).objects if o.name == "tetrahedron")
    assert moved.vertices[0] == (7.5, 4.9, -2.0) and moved.vertices[3] == (8.5, 2.0, -2.3)
    assert math.dist(moved.vertices[3], (9.5, 2.0, -3.3)) < 1.5  # the apex inside the mirror sphere
    assert all(s.room.contains(v) for v in moved.vertices)
    # Integer normals: the slanted walls' (0.894, 0.447) truncated to 0, BC's and EF's kept.
    n = unexamined._truncated_wall_normals(s)
    assert {k for k, v in n.items() if not v.any()} == {"AB", "CD", "DE", "FA"}
    assert n["BC"].tolist() == [0, -1] and n["EF"].tolist() == [0, 1]
    black = {"".join(w.corners): w.albedo for w in unexamined._walls_zero_normals_black(s).room.walls}
    assert black["CD"] == (0.0, 0.0, 0.0) and black["BC"] == own["BC"]
    # Blender's vertical field of view of 1920 x 1080 at 90 degrees across: 58.7 degrees.
    assert unexamined._FOV_VERTICAL == pytest.approx(58.7155, abs=1e-3)
    cam = cases.fov(unexamined._FOV_VERTICAL)(s).cameras["near"]
    assert math.tan(math.radians(cam.fov_x_deg) / 2) == pytest.approx(1080 / 1920)
    # The eye's sign dropped by the regular expression.
    assert unexamined._length("-1 m") == 1.0 and unexamined._length("4.99 m") == 4.99
    assert unexamined._eye_sign_dropped(s).cameras["near"].eye == (1.0, 0.0, 0.0)
    # The lamp: 1 x 1 at radiance 80, the same power as the 2 x 2 at 20.
    lamp = unexamined._lamp_unscaled(s).light
    assert lamp.size == (1.0, 1.0) and lamp.radiance == pytest.approx((80.0,) * 3)
    np.testing.assert_allclose(lamp.power(), s.light.power())
    assert lamp.center == s.light.center
    # The plane's origin at the cursor, the room's box centre (5, 0, 0).
    assert unexamined._light_at_origin(s).light.center == (5.0, 0.0, 0.0)
    assert unexamined._light_at_origin(s).light.size == s.light.size
    # Ke without its strength.
    assert cases.light(radiance=unexamined._KE_COLOUR)(s).light.radiance == (1.0, 1.0, 1.0)
    d = scene_dict(s, "near", 4, 4, 8)
    assert unexamined._tetra_bevelled(d)["tetrahedron"].face_count() == 20


def test_bevel_is_as_blender_makes_it(scene):
    t = next(o for o in scene.objects if o.name == "tetrahedron")
    v = np.asarray(t.vertices, np.float64)
    tris = unexamined._bevelled(v, 0.1)
    assert tris.shape == (20, 3, 3)
    # Every point inside the tetrahedron (on or within its four planes).
    faces = unexamined._tetra_face_indices(v)
    for i, (a, b, c) in enumerate(faces):
        nrm = np.cross(v[b] - v[a], v[c] - v[a])
        nrm /= np.linalg.norm(nrm)
        assert np.all((tris.reshape(-1, 3) - v[a]) @ nrm <= 1e-9)
        # The inset face lies in the face's plane, each of its edges 0.1 from the original edge in that plane.
        inset = tris[i]
        np.testing.assert_allclose((inset - v[a]) @ nrm, 0.0, atol=1e-9)
        for p, q in ((a, b), (b, c), (c, a)):
            e = (v[q] - v[p]) / np.linalg.norm(v[q] - v[p])
            dist = [np.linalg.norm(np.cross(pt - v[p], e)) for pt in inset]
            assert sorted(dist)[:2] == pytest.approx([0.1, 0.1], abs=1e-9)
    # A width of 0 gives the faces themselves (the strips and corners of no area).
    zero = unexamined._bevelled(v, 0.0)
    for i, (a, b, c) in enumerate(faces):
        np.testing.assert_allclose(zero[i], v[[a, b, c]], atol=1e-12)
    area = lambda t_: 0.5 * np.linalg.norm(np.cross(t_[:, 1] - t_[:, 0], t_[:, 2] - t_[:, 0]), axis=1).sum()
    assert area(zero) == pytest.approx(area(np.asarray(t.triangles())), rel=1e-12)
    assert 0.8 * area(zero) < area(tris) < area(zero)


def test_camera_integrator_and_passes_are_as_they_say():
    # Blender's Shift Y 0.1: the image plane's height coordinate raised by 0.2 (a tenth of its width 2), the axis kept.
    o, d = unexamined._shifted(np.array([0.5, 0.5]), np.array([0.5, 0.0]))
    eye, r, u, f, k = unsaid._frame()
    np.testing.assert_allclose(d[0], unsaid._unit(f + 0.2 * u))
    np.testing.assert_allclose(d[1], unsaid._unit(f + 1.2 * u))
    np.testing.assert_allclose(o[0], eye)
    # Node's string concatenation.
    assert unexamined._DEPTH_CONCATENATED == 71 == int("7" + "1")
    # Roulette's 95: paths of up to 3 segments kept, each later segment divided by 95 once more.
    np.testing.assert_allclose(unexamined._roulette_weights(), [1, 1, 1, 1, 1 / 95, 1 / 95 ** 2, 1 / 95 ** 3,
                                                                1 / 95 ** 4, 1 / 95 ** 5])
    # A checkpoint's mean of 1 (128 spp) resumed as the sum, 128 samples of 1 added: 129 / 256.
    ones = np.ones((2, 2, 3))
    np.testing.assert_allclose(unexamined._mean_resumed_as_sum(ones, 128, ones, 128), 129 / 256)
    # The time budget: the first rows 7/6, the rest kept.
    out = unexamined._partial_pass(ones, ones, passes=6, rows=1)
    np.testing.assert_allclose(out[0], 7 / 6)
    np.testing.assert_allclose(out[1], 1.0)
    assert int(64 * unexamined._ROWS_REACHED) == 26
    # The quarter-resolution preview: each preview pixel's value over its 4 x 4 block, weighted 16 of 256.
    prev = np.arange(4.0).reshape(2, 2, 1).repeat(3, axis=2)
    full = np.zeros((8, 8, 3))
    got = unexamined._preview_kept(prev, full, factor=4, n_preview=16, n_full=240)
    np.testing.assert_allclose(got[:4, 4:], 1 * 16 / 256)
    np.testing.assert_allclose(got[4:, 4:], 3 * 16 / 256)
    # The frames: 256 samples in all; equal weights keep the variance of about 33 spp.
    frames = np.asarray(unexamined._FRAMES)
    assert frames.sum() == 256
    assert len(frames) / np.mean(1 / frames) == pytest.approx(33.2, abs=0.1)
    # The adaptive pilot's batches: 2 to 8, the largest relative variance 8.
    mean = np.full((1, 3, 3), 1.0)
    var = np.array([[[0.0] * 3, [1.0] * 3, [4.0] * 3]])
    assert unexamined._batches_for(mean, var).tolist() == [[2, 2, 8]]


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    check_correct_agree(unexamined, plain)


def test_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    lit = lum < 1
    light = lum > 10

    def image(name):
        return _build(_by_name(name)).image

    # The checkpoint's mean resumed as a sum: about half; Ke 1 for 20: a twentieth.
    assert image("checkpoint_mean_resumed_as_sum").mean() == pytest.approx(129 / 256 * plain.mean(), rel=0.1)
    assert image("light_mtl_ke_strength_dropped").mean() == pytest.approx(plain.mean() / 20, rel=0.1)
    # The lamp's power kept: the lit surfaces about as bright, the light smaller and brighter.
    im = image("light_lamp_size_unscaled")
    assert im[lit].mean() == pytest.approx(plain[lit].mean(), rel=0.1) and im.max() > plain.max()
    # The light at the eye's height: nothing as bright as the light in the top rows.
    assert image("light_plane_origin_at_cursor")[:4].max() < 10 < plain[:4].max()
    # The time budget: the top 6 rows 7/6.
    im = image("time_budget_partial_pass")
    assert im[:6].mean() == pytest.approx(7 / 6 * plain[:6].mean(), rel=0.1)
    assert im[6:].mean() == pytest.approx(plain[6:].mean(), rel=0.1)
    # Roulette's 95: darker, the light as it was.
    im = image("roulette_survival_percent")
    assert im[lit].mean() < 0.97 * plain[lit].mean() and im[light].mean() == pytest.approx(plain[light].mean(),
                                                                                           rel=0.05)
    # Cycles' clamp: nothing after the first vertex over 10 (the light's reflection dimmed), the light seen as it was.
    im = image("clamp_cycles_indirect_default")
    assert im[light].mean() == pytest.approx(plain[light].mean(), rel=0.05) and im.mean() < plain.mean()
    # Four walls black: darker.
    assert image("walls_json_integer_normals")[lit].mean() < 0.97 * plain[lit].mean()
    # The third machine's render upside down: a third of the light at the bottom.
    im = image("file_exr_merge_pfm_top_row_first")
    assert im[::-1][light].mean() == pytest.approx(plain[light].mean() / 3, rel=0.2)
    # The passes without the colour: every diffuse surface brighter.
    assert image("pp_passes_composited_without_colour")[lit].mean() > 1.5 * plain[lit].mean()


@pytest.mark.parametrize("name", [s.name for s in unexamined.SPECS])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back."""
    check_builds(_by_name(name), tmp_path)
