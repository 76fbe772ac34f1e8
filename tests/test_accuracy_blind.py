"""The fifth class (mcrt.grade.accuracy.blind) is well formed and builds what its specs say.

These check the specs (names, causes, the held-out rule) and the construction
of a few hand-ins at a tiny resolution (the files written and read back, and
the images' relations to a plain render); they never grade them (the class
was written blind to the grader, with a held-out half). Mitsuba renders,
seeds fixed per case.
"""

from __future__ import annotations

from functools import partial
from dataclasses import replace

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import H, W, build as _build, by_name, check_held_out_rule
from mcrt.grade.accuracy import blind, cases, fresh, novel, outside, programs, unheard, unmet, unseen, untold, untried
from mcrt.grade.accuracy.cases import write_submission
from mcrt.image_files import read_image, srgb_eotf, srgb_oetf

_by_name = partial(by_name, blind.SPECS)


def test_specs_are_new_worded_and_in_categories():
    names = [s.name for s in blind.SPECS]
    assert len(names) == len(set(names))
    others = {s.name for s in cases.SPECS + outside.SPECS + programs.SPECS + fresh.SPECS}
    assert not others & set(names)
    assert all(s.cause in blind.CAUSES and blind.CAUSES[s.cause] for s in blind.MISTAKES)
    assert all(s.cause is None for s in blind.CORRECT)
    # A new cause key is one no other class uses, and every new one is used here.
    old = set(cases.CAUSES) | set(outside.CAUSES) | set(programs.NEW_CAUSES) | set(fresh.NEW_CAUSES)
    assert not old & set(blind.NEW_CAUSES)
    assert set(blind.NEW_CAUSES) <= set(blind.CAUSES)
    # Every mistake lies in exactly one category.
    listed = [n for names in blind.CATEGORIES.values() for n in names]
    assert sorted(listed) == sorted(s.name for s in blind.MISTAKES)
    assert len(blind.MISTAKES) >= 20 and len(blind.CORRECT) >= 6


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(blind, first_kept=False)


def test_new_causes_have_their_equivalences_fixed():
    from mcrt.grade.accuracy.run import SAME_MISTAKE, is_named

    assert is_named("sharpen", ["blur"]) and is_named("light_shape", ["light_size"])
    assert is_named("resolution_crop", ["resampling"]) and not is_named("light_pdf", ["light_radiance"])
    # The unseen, untried, novel, untold, unmet and unheard classes' equivalences came later (their own tests check
    # them).
    later = (set(fresh.NEW_CAUSES) | set(unseen.NEW_CAUSES) | set(untried.NEW_CAUSES) | set(novel.NEW_CAUSES)
             | set(untold.NEW_CAUSES) | set(unmet.NEW_CAUSES) | set(unheard.NEW_CAUSES))
    # A tone curve worded as an encoding's power curve (an old cause's equivalence, added after unheralded).
    assert set(SAME_MISTAKE) - later - {"tone_map"} <= set(blind.NEW_CAUSES)
    assert is_named("tone_map", ["encoding"]) and not is_named("encoding", ["tone_map"])


def test_the_command_knows_the_class():
    import importlib

    from mcrt.grade.accuracy.cli import CLASSES

    assert importlib.import_module(f"mcrt.grade.accuracy.{CLASSES['blind']}").SPECS is blind.SPECS


def test_file_writers_read_back(tmp_path):
    """The files written by hand or with the bindings, read back against the image written: a BMP with its rows
    upside down, a big-endian PFM, an HDR stored bottom row first (to RGBE's precision, a code of the largest
    channel), a tiled EXR, 12-bit codes in a 16-bit PNG."""
    x = np.random.default_rng(3).random((H, W, 3)) * 0.9 + 0.05
    codes = np.floor(srgb_oetf(x) * 255 + 0.5)
    for k, (writer, check) in enumerate((
            (blind._write_bmp_by_hand, lambda r: np.allclose(r, _decoded(codes[::-1]), atol=1e-6)),
            (blind._write_bmp_pillow, lambda r: np.allclose(r, _decoded(codes), atol=1e-6)),
            (blind._write_pfm_big_endian, lambda r: np.allclose(r, x, rtol=1e-6)),
            (blind._write_hdr_bottom_up, lambda r: np.all(np.abs(r - x) <= x.max(axis=2, keepdims=True) / 128)),
            (blind._write_exr_tiled, lambda r: np.allclose(r, x, rtol=1e-6)),
            (blind._write_exr_with_luma, lambda r: np.allclose(r, x, rtol=1e-6)),
            (blind._write_png_gama, lambda r: np.allclose(r, _decoded(codes), atol=1e-6)))):
        folder = tmp_path / str(k)
        folder.mkdir()
        assert check(read_image(writer(x, folder)).mean), writer
    folder = tmp_path / "12bit"
    folder.mkdir()
    r = read_image(blind._write_png16_codes(x, folder, bits=12), linear_png=True).mean
    np.testing.assert_allclose(r * 65535, np.floor(srgb_oetf(x) * 4095 + 0.5), atol=1e-2)


def _decoded(codes):
    return srgb_eotf(codes / 255.0)


def test_buffer_mistakes():
    x = np.arange(H * W * 3, dtype=np.float64).reshape(H, W, 3)
    planar = blind._planar_as_interleaved(x)
    np.testing.assert_array_equal(planar[0, 0], x[0, :3, 0])  # three red values as one pixel
    sheared = blind._row_stride_slip(x)
    # Row 1 starts one pixel in: its first pixel sits at the end of row 0.
    np.testing.assert_array_equal(sheared[1, 0], x[1, 1])
    np.testing.assert_array_equal(sheared[0, W - 1], x[1, 0])
    assert np.all(sheared[-1, W - H + 1:] == 0)


@pytest.mark.parametrize("name", ["render_63_padded", "jitter_two_pixels"])
def test_resolution_cases_are_the_assignment_size(name):
    case = _build(_by_name(name))
    assert case.image.shape == (H, W, 3) and np.isfinite(case.image).all()
    if name == "render_63_padded":
        assert np.all(case.image[-1] == 0) and np.all(case.image[:, -1] == 0)


def test_correct_box_reduction_matches_a_plain_render():
    """A 2x render's 2 x 2 means are the pixels' integrals: the mean agrees with a plain render's to its noise."""
    spec = _by_name("ok_2x_box_reduced")
    case, plain = _build(spec), _build(replace(spec, post=None, post_fn=None, spp=1024))
    assert abs(case.image.mean() / plain.image.mean() - 1) < 0.03


def test_one_mistake_folder_and_its_sidecar(tmp_path):
    case = _build(_by_name("pp_exposure_sidecar"))
    path = write_submission(case, tmp_path / "s")
    assert path.name == "render.exr" and "+2 EV" in (tmp_path / "s" / "exposure.txt").read_text()
    assert (tmp_path / "s" / "manifest.toml").read_text().startswith("spp = 256\n")
