"""The fifteenth class (mcrt.grade.accuracy.unguessed) is well formed and builds what its specs say: the same checks as
test_accuracy_unsought's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x 16, never
graded), on this class's cases, the rays its Mitsuba renders trace and the samples its loops add up.
"""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import (H, W, build as _build, by_name, check_builds, check_held_out_rule,
                              check_not_catalogued, check_specs, image as _image, plain as _plain)
from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unguessed, unheard, unmet,
                                 unsaid, unseen, unsought, untold, untried)
from mcrt.image_files import read_image, srgb_eotf

_by_name = partial(by_name, unguessed.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought)


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unguessed, _OTHERS, mistakes=28)
    assert all(s.truth for s in unguessed.SPECS)
    truths = {s.truth for m in _OTHERS for s in m.SPECS}
    assert not truths & {s.truth for s in unguessed.SPECS}


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unguessed)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unguessed)
    assert sum(s.held_out for s in unguessed.MISTAKES) == 12 and sum(s.held_out for s in unguessed.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    assert unguessed.NEW_CAUSES == {}
    old = set(cases.CAUSES) | set(outside.CAUSES) | {c for m in _OTHERS for c in getattr(m, "NEW_CAUSES", ())}
    assert {s.cause for s in unguessed.MISTAKES} <= old


def test_the_command_knows_the_class():
    import importlib

    from mcrt.grade.accuracy.cli import CLASSES

    assert importlib.import_module(f"mcrt.grade.accuracy.{CLASSES['unguessed']}").SPECS is unguessed.SPECS


def test_correct_writers_read_back(tmp_path):
    """The hand-written Sub-filtered PNG, the PFM of scale -0.5 and the EXR with AOV layers read back as written."""
    x = _image()
    for d in "abc":
        (tmp_path / d).mkdir()
    np.testing.assert_allclose(read_image(unguessed._write_png_sub_filter(x, tmp_path / "a")).mean,
                               srgb_eotf(blind._srgb8(x) / 255.0), atol=1e-6)
    assert (tmp_path / "a" / "render.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    np.testing.assert_allclose(read_image(unguessed._write_pfm_scale_half(x, tmp_path / "b")).mean, x, rtol=1e-6)
    assert (tmp_path / "b" / "render.pfm").read_bytes().split(b"\n")[2] == b"-0.5"
    r = read_image(unguessed._write_exr_aovs(x, tmp_path / "c"))
    np.testing.assert_allclose(r.mean, x, rtol=1e-6)
    assert "albedo.R" in r.extra["exr.ignored_channels"] and "normal.Z" in r.extra["exr.ignored_channels"]
    aovs = unguessed._aovs(x)
    n = np.stack([aovs[f"normal.{c}"] for c in "XYZ"], axis=-1)
    np.testing.assert_allclose(np.linalg.norm(n, axis=-1), 1.0, atol=1e-4)  # every pixel meets a surface
    assert aovs["albedo.R"].max() <= 0.8 + 1e-6 and aovs["albedo.R"].max() > 0.5


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    x = _image()
    for d in "abc":
        (tmp_path / d).mkdir()
    c8 = blind._srgb8(x)
    # ARGB read as RGBA: red 255, green the red, blue the green; the alpha (dropped) the blue.
    argb = unguessed._argb_as_rgba(x)
    assert np.all(argb[..., 0] == 255)
    np.testing.assert_array_equal(argb[..., 1:], c8)
    r = read_image(unguessed._write_png_argb_as_rgba(x, tmp_path / "a")).mean
    np.testing.assert_allclose(r[..., 0], 1.0, atol=1e-6)
    np.testing.assert_allclose(r[..., 1:], srgb_eotf(c8[..., :2] / 255.0), atol=1e-6)
    # The sRGB curve without its - 0.055: 14 codes high above the threshold, the same below, white from 0.88.
    codes = unguessed._srgb_without_offset(x)
    hi = x > 0.01
    assert np.all(np.abs(codes[hi].astype(int) - np.minimum(c8[hi].astype(int) + 14, 255)) <= 1)
    small = unguessed._srgb_without_offset(np.array([[[0.002, 0.0, 0.9]]]))
    assert list(small[0, 0]) == [round(0.002 * 12.92 * 255), 0, 255]
    np.testing.assert_allclose(read_image(unguessed._write_png_srgb_without_offset(x, tmp_path / "b")).mean,
                               srgb_eotf(codes / 255.0), atol=1e-6)
    # The HDR's EXPOSURE=2 line: read back at half what fresh's writer gives.
    path = unguessed._write_hdr_exposure_kept(x, tmp_path / "c")
    assert b"EXPOSURE=2\n" in path.read_bytes()[:80]
    plain_hdr = read_image(fresh._write_hdr(x, tmp_path / "a")).mean
    np.testing.assert_allclose(read_image(path).mean, plain_hdr / 2.0, rtol=1e-6)
    # The manifest declares the total sample count of the 64 x 64 grade.
    assert _by_name("manifest_spp_total_samples").declared_spp == 64 * 64 * 256


def test_post_processes_do_what_they_say():
    x = _image()
    # The denoisers smooth: less variation between neighbours, the mean kept inside; SciPy's Wiener window is
    # zero-padded, so the border darkens.
    for f in (unguessed._tv_denoised, unguessed._wiener):
        y = f(x)
        assert y.shape == x.shape and np.abs(np.diff(y, axis=1)).mean() < 0.8 * np.abs(np.diff(x, axis=1)).mean()
        assert abs(y[1:-1, 1:-1].mean() - x[1:-1, 1:-1].mean()) < 0.01 and np.all(np.isfinite(y))
    assert abs(unguessed._tv_denoised(x).mean() - x.mean()) < 0.01
    assert unguessed._wiener(x)[0].mean() < 0.9 * x[0].mean()
    # sRGB on the luminance: a grey pixel becomes its sRGB value, every pixel's channels keep their ratios.
    grey = unguessed._luma_srgb(np.full((1, 1, 3), 0.2))
    np.testing.assert_allclose(grey, 1.055 * 0.2 ** (1 / 2.4) - 0.055, rtol=1e-9)
    y = unguessed._luma_srgb(x)
    np.testing.assert_allclose(y[..., 0] / y[..., 1], x[..., 0] / x[..., 1], rtol=1e-9)
    # Half a pixel right and down: pixel (j, i) the mean of (j - 1 .. j, i - 1 .. i) inside the image.
    s = unguessed._half_pixel_shift(x)
    np.testing.assert_allclose(s[1:, 1:], (x[1:, 1:] + x[:-1, 1:] + x[1:, :-1] + x[:-1, :-1]) / 4.0, atol=1e-12)
    # Tiles at their transposes' places: the diagonal tiles kept, tile (0, 1) from (1, 0); twice is the identity.
    t = unguessed._tiles_transposed(x)
    q = W // 4
    np.testing.assert_array_equal(t[:q, :q], x[:q, :q])
    np.testing.assert_array_equal(t[:q, q:2 * q], x[q:2 * q, :q])
    np.testing.assert_array_equal(unguessed._tiles_transposed(t), x)
    assert np.all(unguessed._clipped_at_zero(x - 0.5) >= 0.0)


def test_scene_edits():
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    s = load_scene()
    d = scene_dict(s, "near", 4, 4, 8)  # sets Mitsuba's variant too

    walls = unguessed._walls_reversed(s).room.walls
    assert [w.albedo for w in walls] == [w.albedo for w in reversed(s.room.walls)]
    assert [w.corners for w in walls] == [w.corners for w in s.room.walls]
    capped = unguessed._albedos_capped(s)
    assert capped.room.walls[0].albedo == (0.7, 0.15, 0.15) and capped.room.ceiling_albedo == (0.7, 0.7, 0.7)
    assert next(o for o in capped.objects if o.name == "tetrahedron").material.albedo == (0.7, 0.45, 0.1)
    assert next(o for o in capped.objects if o.name == "sphere").material == \
        next(o for o in s.objects if o.name == "sphere").material
    base = next(o for o in unguessed._tetra_base_on_floor(s).objects if o.name == "tetrahedron").vertices
    assert [v[2] for v in base] == [-5.0, -5.0, -5.0, -2.0]
    # The walls 0.1 inward: every wall's plane offset 0.1 less, the same normals.
    inset = unguessed._walls_inset(s).room
    np.testing.assert_allclose(inset.planes()[:6, :3], s.room.planes()[:6, :3], atol=1e-12)
    np.testing.assert_allclose(inset.planes()[:6, 3], s.room.planes()[:6, 3] - 0.1, atol=1e-9)
    # The flat tetrahedron: its base triangle alone.
    flat = unguessed._tetra_flat(d)["tetrahedron"]
    assert flat.face_count() == 1 and flat.surface_area()[0] == pytest.approx(2.3, rel=1e-5)
    # The blend of a Lambertian and a mirror.
    t = unguessed._tetra_reflectivity(d)["tetrahedron"]
    assert "BlendBSDF" in str(t.bsdf()) and t.surface_area()[0] == pytest.approx(d["tetrahedron"].surface_area()[0])
    # The light turned 45 degrees: the same area, its corners on the axes through its centre, facing down.
    tris = unguessed._light_rotated_tris()
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    assert np.all(n[:, 2] < 0) and np.allclose(n[:, :2], 0.0)
    corners = np.unique(np.round(tris.reshape(-1, 3), 9), axis=0)
    np.testing.assert_allclose(sorted(np.abs(corners[:, 0] - 5.0) + np.abs(corners[:, 1])), [2 ** 0.5] * 4)
    rot = unguessed._light_rotated(d)["light"]
    assert rot.emitter() is not None and rot.surface_area()[0] == pytest.approx(4.0, rel=1e-5)
    # The light's strips: they tile each triangle, and their power is the triangle's.
    for tri in unsaid._light_tris():
        strips = unguessed._strips(tri, 8)
        areas = [0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1).sum() for t, _ in strips]
        assert sum(areas) == pytest.approx(2.0, rel=1e-9)
        assert sum(a * f for a, (_, f) in zip(areas, strips)) == pytest.approx(2.0, rel=1e-9)
        assert strips[-1][1] == pytest.approx(8.0) and strips[0][1] == pytest.approx(8 / 15)
        np.testing.assert_allclose(tri[0], (4.0, 1.0, 4.99))  # both triangles from the same corner
    strip_dict = unguessed._light_sqrt_missing(d)
    assert "light" not in strip_dict and sum(k.startswith("light_strip_") for k in strip_dict) == 16
    # One-sided Lambertians, floor and ceiling fanned from D, meshes through PLY files.
    one = unguessed._one_sided(d)
    assert "TwoSided" not in str(one["wall_AB"].bsdf()) and "TwoSided" in str(d["wall_AB"].bsdf())
    fans = unguessed._fans_from(d)
    for name in ("floor", "ceiling"):
        assert fans[name].surface_area()[0] == pytest.approx(d[name].surface_area()[0], rel=1e-5)
        assert fans[name].face_count() == 4
    assert not np.allclose(np.array(fans["floor"].vertex_positions_buffer()),
                           np.array(d["floor"].vertex_positions_buffer()))
    ply = unguessed._from_ply(d)
    for name in ("wall_AB", "floor", "tetrahedron", "light"):
        assert ply[name].surface_area()[0] == pytest.approx(d[name].surface_area()[0], rel=1e-5)
    assert ply["light"].emitter() is not None and ply["floor"].emitter() is None
    import mitsuba as mi

    mi.load_dict(unguessed._from_ply(d))  # loads


def test_sample_loops_add_up_as_they_say():
    """Offsets stratified in x, the accumulator never reset, the lost adds, the firefly rejection and the bounce's
    local directions."""
    rng = np.random.default_rng(0)
    u, v = unguessed._x_strata(rng, 8, pixels=5)
    assert u.shape == (5, 8) and np.all(np.sort(np.floor(u * 8), axis=1) == np.arange(8))
    assert 0.0 <= v.min() and v.max() < 1.0
    x = np.zeros((4, 4, 3))
    L = np.concatenate([a for a, _, _ in unasked._samples(4, 4, 8, 5)], axis=1)
    weights = np.arange(8, 0, -1)  # sample j (from 0) in 8 - j running totals
    np.testing.assert_allclose(unguessed._accumulator_not_reset(x, spp=8, seed=5).reshape(16, 3),
                               np.einsum("pnc,n->pc", L, weights) / 8, rtol=1e-9)
    lost = unguessed._race_lost(x, spp=8, seed=5, lost=0.0).reshape(16, 3)
    np.testing.assert_allclose(lost, L.mean(axis=1), rtol=1e-9)
    assert np.all(unguessed._race_lost(x, spp=8, seed=5, lost=1.0) == 0.0)
    # The firefly rejection: nothing rejected before the 16th sample, or with a factor no sample reaches.
    np.testing.assert_allclose(unguessed._firefly_rejection(x, spp=8, seed=5).reshape(16, 3), L.mean(axis=1),
                               rtol=1e-9)
    fly = np.ones((2, 20, 3))
    fly[0, 17] = 100.0  # past the 16th sample: dropped
    fly[1, 3] = 100.0  # before it: kept
    np.testing.assert_allclose(unguessed._rejected_mean(fly, factor=10.0, after=16), [[1.0] * 3, [119 / 20] * 3])
    # Cosine-distributed about +z: unit vectors, E[z] = 2/3.
    dz = unguessed._cosine_about_z(np.random.default_rng(1), 200000)
    np.testing.assert_allclose(np.linalg.norm(dz, axis=1), 1.0, atol=1e-12)
    assert dz[:, 2].min() >= 0.0 and dz[:, 2].mean() == pytest.approx(2 / 3, abs=0.005)


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    for name in ("ok_x_strata_offsets", "ok_meshes_from_ply", "ok_one_sided_surfaces", "ok_mcrt_passes_of_8",
                 "ok_fans_from_corner_d"):
        case = _build(_by_name(name))
        rel = np.abs(case.image - plain).mean(axis=2) / (plain.mean(axis=2) + 0.05)
        assert np.median(rel) < 0.15 and case.image.shape == (H, W, 3), name
        assert abs(case.image.mean() / plain.mean() - 1) < 0.1, name


def test_combined_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    sphere = unheard._sphere_hit(W, H, 1)
    # The ceiling (the top row but the light), lit only indirectly, black when every bounce off it leaves the room.
    local = _build(_by_name("bounce_in_local_frame")).image.mean(axis=2)
    ceiling = lum[0] < 5
    assert local[0][ceiling].max() < 1e-6 and lum[0][ceiling].min() > 0.03
    # The room in the mirror brighter with its light counted twice; elsewhere the image right.
    stuck = _build(_by_name("specular_flag_stuck")).image.mean(axis=2)
    assert stuck[sphere].mean() > 1.15 * lum[sphere].mean()
    assert abs(stuck[~sphere].mean() / lum[~sphere].mean() - 1) < 0.05
    over = _build(_by_name("mirror_weight_over_cosine")).image.mean(axis=2)
    assert over[sphere].mean() > 1.1 * lum[sphere].mean()
    # 256 samples, the running totals added: (256 + 1) / 2 times the truth.
    acc = _build(_by_name("accumulator_not_reset")).image
    assert acc.mean() / plain.mean() == pytest.approx(128.5, rel=0.1)
    race = _build(_by_name("race_lost_adds")).image
    assert race.mean() / plain.mean() == pytest.approx(0.97, abs=0.02)
    # The light's corners black where seen: the light's pixels dimmer, those that show none of it right.
    seen, lit = lum > 5, lum < 1
    disk = _build(_by_name("light_emission_disk_test")).image.mean(axis=2)
    assert disk[seen].mean() < 0.9 * lum[seen].mean()
    assert abs(disk[lit].mean() / lum[lit].mean() - 1) < 0.05
    half = _build(_by_name("indirect_half_resolution")).image
    assert abs(half.mean() / plain.mean() - 1) < 0.05
    assert _build(_by_name("film_filter_mitchell")).image.min() >= 0.0


@pytest.mark.parametrize("name", [s.name for s in unguessed.SPECS])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back."""
    check_builds(_by_name(name), tmp_path)
