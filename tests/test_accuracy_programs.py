"""The class of students' programs' mistakes (mcrt.grade.accuracy.programs) builds what its specs say.

These check the construction of the hand-ins at a tiny resolution (the files
written and the images' relations to a plain render of the same seed); they
never grade them. Mitsuba renders, seeds fixed per case.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from mcrt.grade.accuracy import programs
from mcrt.grade.accuracy.cases import build_class, write_submission
from mcrt.image_files import read_exr, read_pfm, read_png, srgb_oetf

W = H = 16


def _by_name(name):
    return next(s for s in programs.SPECS if s.name == name)


def _pair(name, tmp_path, **plain_changes):
    """The case, its file read back, and a render of the same spec (same seed) with no post-process or writer."""
    spec = _by_name(name)
    case = build_class(width=W, height=H, specs=(spec,))[0]
    plain = build_class(width=W, height=H, specs=(replace(spec, post=None, post_fn=None, writer=None, file="exr",
                                                          **plain_changes),))[0]
    path = write_submission(case, tmp_path / name)
    return case, path, plain


def test_specs_are_consistent_and_hold_out_by_the_stated_rule():
    names = [s.name for s in programs.SPECS]
    assert len(names) == len(set(names))
    assert all(s.cause in programs.CAUSES for s in programs.MISTAKES)
    assert all(s.cause is None for s in programs.CORRECT)
    rule = programs.held_out_rule()
    assert {s.name: s.held_out for s in programs.SPECS} == rule
    held = sum(rule.values())
    assert abs(held - len(rule) / 2) <= 1, held


def test_pfm_top_down_reads_upside_down(tmp_path):
    case, path, plain = _pair("pfm_top_down", tmp_path)
    assert path.suffix == ".pfm"
    np.testing.assert_array_equal(case.image, plain.image)
    np.testing.assert_array_equal(read_pfm(path), plain.image[::-1])


def test_correct_pfm_reads_back_exactly(tmp_path):
    spec = _by_name("ok_ld_pfm")
    case = build_class(width=W, height=H, specs=(replace(spec, spp=16),))[0]
    np.testing.assert_array_equal(read_pfm(write_submission(case, tmp_path / "ok")), case.image)


def test_mirrored_and_transposed(tmp_path):
    case, path, plain = _pair("mirrored_x", tmp_path)
    np.testing.assert_array_equal(case.image, plain.image[:, ::-1])
    np.testing.assert_array_equal(read_exr(path).mean, plain.image[:, ::-1])
    case, path, plain = _pair("transposed", tmp_path)
    np.testing.assert_array_equal(case.image, np.swapaxes(plain.image, 0, 1))
    assert not np.allclose(case.image, plain.image)


def test_png_writers_hold_the_stated_encodings(tmp_path):
    import png

    case, path, plain = _pair("png_srgb_twice", tmp_path)
    # The reader undoes one sRGB curve: one is left over (8-bit codes: within half a code before decoding).
    once = read_png(path)
    want = srgb_oetf(np.clip(plain.image, 0, 1))
    assert np.max(np.abs(srgb_oetf(np.clip(once, 0, 1)) - srgb_oetf(want))) <= 0.5 / 255 + 1e-6
    case, path, plain = _pair("png16_linear", tmp_path)
    w, h, rows, info = png.Reader(filename=str(path)).read()
    assert info["bitdepth"] == 16 and not info["greyscale"]
    codes = np.vstack([np.asarray(r, np.uint16) for r in rows]).reshape(h, w, 3)
    np.testing.assert_allclose(codes / 65535.0, np.clip(plain.image, 0, 1), atol=0.5 / 65535 + 1e-7)
    case, path, plain = _pair("grey_luminance", tmp_path)
    g = read_png(path)
    assert np.array_equal(g[..., 0], g[..., 1]) and np.array_equal(g[..., 1], g[..., 2])
    assert np.ptp(plain.image, axis=2).max() > 0.05  # the render had colour


def test_direct_twice_is_brighter_where_direct_light_is(tmp_path):
    case, _, plain = _pair("plus_direct", tmp_path)
    extra = case.image - plain.image
    assert extra.min() >= 0.0
    light = plain.image.mean(axis=2) > 5.0  # the light seen directly: the direct pass hides it
    assert light.any() and np.allclose(extra[light], 0.0)
    assert extra[~light].mean() > 0.1 * plain.image[~light].mean()


def test_sample_clamp_bounds_every_pixel(tmp_path):
    case, _, plain = _pair("clamp_1", tmp_path, spp=64)
    assert case.image.max() <= 1.0 + 1e-6 and plain.image.max() > 5.0
    assert case.image.mean() < plain.image.mean()


def test_scene_edits_and_pixels(tmp_path):
    case, _, plain = _pair("tile_black", tmp_path)
    black = np.all(case.image == 0.0, axis=2)
    assert black.sum() == (H // 4) * (W // 4) and black[H // 4, W // 2]
    np.testing.assert_array_equal(case.image[~black], plain.image[~black])
    facing = build_class(width=W, height=H, specs=(replace(_by_name("light_facing_up"), spp=16),))[0]
    assert facing.image.mean() < 0.05 * plain.image.mean()  # only what leaks past the light from the ceiling


@pytest.mark.parametrize("name", ["walls_shifted", "no_ceiling", "depth_2"])
def test_scene_mistakes_change_the_render(name):
    spec = replace(_by_name(name), spp=64)
    case = build_class(width=W, height=H, specs=(spec,))[0]
    plain = build_class(width=W, height=H, specs=(replace(spec, edit=None, mitsuba_edit=None, max_depth=None),))[0]
    assert np.abs(case.image - plain.image).mean() > 0.05 * plain.image.mean()


def test_report_words_this_class(tmp_path):
    """The report of --class programs names this class and its own causes (outcomes made up: nothing graded)."""
    from mcrt.grade.accuracy.markdown import write_report
    from mcrt.grade.accuracy.run import Outcome

    s = _by_name("pfm_top_down")
    o = Outcome(s.name, s.truth, s.cause, s.major, s.held_out, 16, s.file, 1.0, 2.0, [], False, False, False, "", 0.1)
    text = write_report(tmp_path, [o], command="test", meta={}, gradescope=[], klass="programs").read_text()
    assert "mistakes of students' programs" in text and "mcrt.grade.accuracy.programs" in text
    assert f"`orientation` {programs.NEW_CAUSES['orientation']}" in text
