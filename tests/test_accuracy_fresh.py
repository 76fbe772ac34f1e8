"""The fourth class (mcrt.grade.accuracy.fresh) builds what its specs say, and the report leaves out an empty half.

These check the construction of the hand-ins at a tiny resolution (the files
written, and the images' relations to a plain render of the same seed or to
the relation the mistake implies); they never grade them (the class was
written to be held out). Mitsuba renders, seeds fixed per case.
"""

from __future__ import annotations

import math
from functools import partial
from dataclasses import replace

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import H, W, build as _build, by_name
from mcrt.grade.accuracy import cases, fresh, outside, programs
from mcrt.grade.accuracy.cases import write_submission
from mcrt.image_files import XYZ_TO_RGB, read_exr, read_hdr, read_image, read_netpbm, read_pfm, srgb_oetf

_by_name = partial(by_name, fresh.SPECS)


def _pair(name, tmp_path, **plain_changes):
    """The case, its file, and a render of the same spec (same seed) with no post-process or writer."""
    spec = _by_name(name)
    case = _build(spec)
    plain = _build(replace(spec, post=None, post_fn=None, writer=None, file="exr", **plain_changes))
    return case, write_submission(case, tmp_path / name), plain


def test_specs_are_new_consistent_and_held_out_as_one():
    names = [s.name for s in fresh.SPECS]
    assert len(names) == len(set(names))
    others = {s.name for s in cases.SPECS + outside.SPECS + programs.SPECS}
    assert not others & set(names)
    assert all(s.cause in fresh.CAUSES and fresh.CAUSES[s.cause] for s in fresh.MISTAKES)
    assert all(s.cause is None for s in fresh.CORRECT)
    assert all(s.held_out == fresh.HELD_OUT for s in fresh.SPECS)
    # A new cause key is one no other class uses, and every new one is used here.
    old = set(cases.CAUSES) | set(outside.CAUSES) | set(programs.NEW_CAUSES)
    assert not old & set(fresh.NEW_CAUSES)
    assert set(fresh.NEW_CAUSES) <= set(fresh.CAUSES)
    assert len(fresh.MISTAKES) >= 20 and len(fresh.CORRECT) >= 5


def test_the_command_knows_the_class():
    import importlib

    from mcrt.grade.accuracy.cli import CLASSES

    assert importlib.import_module(f"mcrt.grade.accuracy.{CLASSES['fresh']}").SPECS is fresh.SPECS


def test_field_of_view_slips():
    # tan(45 rad) = 1.62: the half-angle in degrees read as radians; W - 1 at 64 pixels: 64/63 of the tangent.
    assert math.tan(math.radians(fresh.FOV_RADIANS_SLIP) / 2) == pytest.approx(math.tan(45.0))
    assert 116 < fresh.FOV_RADIANS_SLIP < 117
    assert math.tan(math.radians(fresh.FOV_W_MINUS_1) / 2) == pytest.approx(64 / 63)


def test_every_case_writes_a_readable_file_of_its_kind(tmp_path):
    """Each hand-in's folder: the image file(s) its writer makes and a manifest with the declared spp."""
    want = {"pfm_big_endian_header": ".pfm", "pfm_over_max": ".pfm", "pair_same_seed": ".exr", "ok_hdr_by_hand": ".hdr",
            "ok_two_averaged_ppm16": ".ppm", "ok_mcrt_48_tga": ".tga"}
    for spec in fresh.SPECS:
        if spec.name.startswith("roulette"):  # nine renders each: built in their own test
            continue
        case = _build(spec)
        folder = tmp_path / spec.name
        path = write_submission(case, folder)
        ext = want.get(spec.name, ".png" if spec.file.startswith("png") else ".exr")
        assert path.suffix == ext, spec.name
        images = sorted(p.name for p in folder.iterdir() if p.name != "manifest.toml")
        assert len(images) == (2 if spec.name == "pair_same_seed" else 1), images
        manifest = (folder / "manifest.toml").read_text()
        assert manifest.startswith(f"spp = {spec.declared_spp or case.spp}\n")
        img = read_image(path, linear_png="linear = true" in manifest).mean
        assert img.shape == (H, W, 3)
        if spec.name != "pfm_big_endian_header":
            assert np.isfinite(img).all() and img.mean() > 0, spec.name


def test_writers_of_the_file_mistakes(tmp_path):
    from PIL import Image

    case, path, plain = _pair("png_truncated", tmp_path)
    codes = np.asarray(Image.open(path), np.float64)
    exact = srgb_oetf(np.clip(plain.image, 0, 1)) * 255
    np.testing.assert_array_equal(codes, np.floor(exact))
    assert (codes < np.floor(exact + 0.5)).mean() > 0.3  # rounding would have given a higher code about half the time

    case, path, plain = _pair("pfm_big_endian_header", tmp_path)
    assert path.read_bytes().split(b"\n")[2] == b"1.0"
    np.testing.assert_array_equal(read_pfm(path).view(np.uint32), plain.image.astype("<f4").byteswap().view(np.uint32))

    case, path, plain = _pair("pfm_over_max", tmp_path)
    np.testing.assert_allclose(read_pfm(path), plain.image / plain.image.max(), rtol=1e-6)

    case, path, plain = _pair("xyz_as_rgb", tmp_path)
    np.testing.assert_allclose(read_exr(path).mean @ XYZ_TO_RGB.T, plain.image, rtol=1e-4, atol=1e-5)


def test_pair_same_seed_is_one_image_twice(tmp_path):
    case = _build(_by_name("pair_same_seed"))
    write_submission(case, tmp_path / "p")
    a, b = (read_exr(tmp_path / "p" / f"render_{k}.exr").mean for k in (1, 2))
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(a, case.image)


def test_per_sample_curve_is_below_the_curve_of_the_mean():
    """sRGB is concave and clipped: the mean of encoded samples is at most the encoding of their mean (Jensen)."""
    case = _build(_by_name("srgb_per_sample"))
    s = fresh._mitsuba((H, W, 3), 1, fresh._crc("srgb_per_sample"), supersample=8)
    mean = s.reshape(H, 8, W, 8, 3).mean(axis=(1, 3))
    assert case.image.max() <= 1.0 + 1e-9
    assert np.all(case.image <= srgb_oetf(np.clip(mean, 0, 1)) + 1e-6)
    assert np.mean(case.image < srgb_oetf(np.clip(mean, 0, 1)) - 1e-3) > 0.5


def test_light_two_sided_adds_only_the_upper_face():
    case, plain = (_build(replace(_by_name("light_two_sided"), **kw)) for kw in ({}, {"post": None, "post_fn": None}))
    extra = case.image.astype(np.float64) - plain.image
    assert extra.min() >= -1e-5
    full = plain.image.mean(axis=2) > 19.99  # pixels wholly on the light: the camera sees its lower face only
    assert full.any() and np.allclose(extra[full], 0.0, atol=1e-5)
    assert extra[~full].mean() > 0.003 * plain.image[~full].mean()


def test_roulette_is_the_paths_of_each_length_reweighted():
    """With survival 1 the weighted sum telescopes to the full render (same seed: the renders share their paths'
    prefixes, so each length's share is non-negative); with 1/2 from the first hit, the light seen and the direct
    light are kept and the rest loses at least half."""
    shape, spp, seed = (H, W, 3), 16, 123
    full = fresh._mitsuba(shape, spp, seed, max_depth=8, rr_depth=100)
    np.testing.assert_allclose(fresh._roulette(np.zeros(shape), p=1.0, start=0, spp=spp, seed=seed), full,
                               rtol=1e-5, atol=1e-6)
    half = fresh._roulette(np.zeros(shape), p=0.5, start=0, spp=spp, seed=seed)
    direct = fresh._mitsuba(shape, spp, seed, max_depth=2, rr_depth=100)
    assert np.all(half <= full + 1e-5) and np.all(half >= direct - 1e-5)
    assert np.all(half <= direct + 0.5 * (full - direct) + 1e-5)
    assert half.mean() < full.mean() - 0.1 * (full.mean() - direct.mean())


def _black(img):
    return np.all(img < 1e-6, axis=2)


def test_normals_facing_away_are_black():
    plain = _build(replace(_by_name("wall_normal_out"), mitsuba_edit=None))
    assert not _black(plain.image).any()
    wall = _build(_by_name("wall_normal_out"))
    assert _black(wall.image).mean() > 0.1  # the purple wall fills the image's right side
    tetra = _build(_by_name("tetra_normals_in"), 32)  # at 16 x 16 no pixel lies wholly on the tetrahedron
    assert 0 < _black(tetra.image).sum() < 0.05 * 32 * 32


def test_mesh_edits():
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    d = scene_dict(load_scene(), "near", W, H, 8)
    assert fresh._tetra_without_face(d)["tetrahedron"].face_count() == 3
    assert "wall_FA" in d and "wall_FA" not in fresh._without_mesh(d, "wall_FA")
    o = fresh._orthographic(d)["sensor"]
    assert o["type"] == "orthographic" and "fov" not in o and o["to_world"] == d["sensor"]["to_world"]


def test_up_negated_turns_the_image_half_round():
    spec = _by_name("up_negated")
    case = _build(spec)
    plain = _build(replace(spec, edit=None))
    lit = lambda img: np.argwhere(img.mean(axis=2) > 19.99)  # noqa: E731  (pixels wholly on the light)
    np.testing.assert_array_equal(np.sort(lit(case.image), axis=0), np.sort((H - 1, W - 1) - lit(plain.image), axis=0))


def test_resampled_renders_have_the_resolution(tmp_path):
    case = _build(_by_name("every_other_pixel"))
    fine = fresh._mitsuba((H, W, 3), 64, fresh._crc("every_other_pixel"), supersample=2)
    np.testing.assert_array_equal(case.image, fine[1::2, 1::2].astype(np.float32))
    assert _build(_by_name("zoom_half")).image.shape == (H, W, 3)


def test_correct_files_read_back(tmp_path):
    from PIL import Image

    def written(name):
        case = _build(_by_name(name))
        return case, write_submission(case, tmp_path / name)

    case, path = written("ok_png16_declared_linear")
    assert "linear = true" in (path.parent / "manifest.toml").read_text()
    np.testing.assert_allclose(read_image(path, linear_png=True).mean, np.clip(case.image, 0, 1),
                               atol=0.5 / 65535 + 1e-7)
    case, path = written("ok_hdr_by_hand")
    step = case.image.max(axis=2, keepdims=True) / 256  # a code is 2^(e - 8), between this and twice it
    err = (read_hdr(path).astype(np.float64) - case.image) / step
    assert np.all(np.abs(err) <= 1.0 + 1e-5)
    assert abs(err.mean()) < 0.1  # rounded; truncated codes would read about 0.7 of this step low on average
    case, path = written("ok_exr_half_rgba")
    r = read_exr(path)
    np.testing.assert_allclose(r.mean, case.image, rtol=1e-3, atol=1e-6)
    assert "Z" in r.extra["exr.ignored_channels"]
    case, path = written("ok_two_averaged_ppm16")
    rgb, bits = read_netpbm(path)
    assert bits == 16
    np.testing.assert_allclose(srgb_oetf(np.clip(rgb, 0, 1)), srgb_oetf(np.clip(case.image, 0, 1)),
                               atol=0.5 / 65535 + 1e-6)
    case, path = written("ok_mcrt_48_tga")
    np.testing.assert_array_equal(np.asarray(Image.open(path)), np.floor(srgb_oetf(np.clip(case.image, 0, 1)) * 255 + 0.5))
    case, path = written("ok_png_dithered")
    codes = np.asarray(Image.open(path), np.float64)
    exact = srgb_oetf(np.clip(case.image, 0, 1)) * 255
    assert np.all(np.abs(codes - exact) <= 1.0 + 1e-9) and np.any(codes != np.floor(exact + 0.5))


def test_report_words_this_class_and_leaves_out_an_empty_half(tmp_path):
    """The report of --class fresh names the class and its causes; with every case in one half there is no row for
    the other (outcomes made up: nothing graded)."""
    from mcrt.grade.accuracy.markdown import write_report
    from mcrt.grade.accuracy.run import Outcome

    s = _by_name("roulette_half_from_3")
    for held_out, row, empty in ((True, "| held out | 1 |", "| tuned on |"), (False, "| tuned on | 1 |", "| held out |")):
        o = Outcome(s.name, s.truth, s.cause, s.major, held_out, 16, s.file, 1.0, 2.0, [], False, False, False, "", 0.1)
        text = write_report(tmp_path, [o], command="test", meta={}, gradescope=[], klass="fresh").read_text()
        assert "no other class tried" in text and "mcrt.grade.accuracy.fresh" in text
        assert f"`roulette` {fresh.NEW_CAUSES['roulette']}" in text
        assert row in text and empty not in text


def test_report_says_each_regrade_record(tmp_path):
    """Cases graded again after the run, on one commit or on two (a later record beside an earlier one), are each
    said with their commit (outcomes made up: nothing graded)."""
    from mcrt.grade.accuracy.markdown import write_report
    from mcrt.grade.accuracy.run import Outcome

    s = _by_name("roulette_half_from_3")
    o = Outcome(s.name, s.truth, s.cause, s.major, False, 16, s.file, 1.0, 2.0, [], False, False, False, "", 0.1)
    one = {"cases": [s.name], "commit": "abc1234", "why": "a family added"}
    two = [{"cases": ["x", "y"], "commit": "abc1234", "why": "a family added"},
           {"cases": [s.name], "commit": "def5678", "why": "read again"}]
    text = write_report(tmp_path, [o], command="test", meta={"regraded": one}, gradescope=[], klass="fresh").read_text()
    assert f"the case `{s.name}` was graded again on commit abc1234 (a family added)" in text
    text = write_report(tmp_path, [o], command="test", meta={"regraded": two}, gradescope=[], klass="fresh").read_text()
    assert "the cases `x`, `y` were graded again on commit abc1234 (a family added)" in text
    assert f"the case `{s.name}` was graded again on commit def5678 (read again)" in text


def test_the_same_mistake_in_other_words_is_named_right_only_where_fixed_in_advance():
    from mcrt.grade.accuracy.run import is_named

    assert is_named("quantisation", ["encoding"]) and is_named("camera_model", ["camera_fov"])
    assert is_named("depth", ["depth"]) and not is_named("depth", ["albedo"])
    # A black surface is not normals facing the wrong way; the depth setting is not roulette's re-weighting.
    assert not is_named("normals", ["object_missing", "albedo"]) and not is_named("roulette", ["depth"])
