"""The seventh class (mcrt.grade.accuracy.untried) is well formed and builds what its specs say.

These check the specs (names, causes, the held-out rule), the writers (read
back with mcrt's reader: equal where the file is meant to be correct, wrong
in the way the spec says where it is not), the post-processes on small
arrays, the scene edits, and the construction of a few hand-ins at a tiny
resolution; they never grade them (the class was written blind to the
grader, with a held-out half). Mitsuba renders, seeds fixed per case.
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import (H, W, build as _build, by_name, check_held_out_rule,
                              check_not_catalogued, image as _image)
from mcrt.grade.accuracy import blind, cases, fresh, outside, programs, unseen, untried
from mcrt.grade.accuracy.cases import build_class
from mcrt.image_files import ImageError, read_image, srgb_eotf, srgb_oetf

_by_name = partial(by_name, untried.SPECS)


def test_specs_are_new_worded_and_in_categories():
    names = [s.name for s in untried.SPECS]
    assert len(names) == len(set(names))
    others = {s.name for s in cases.SPECS + outside.SPECS + programs.SPECS + fresh.SPECS + blind.SPECS
              + unseen.SPECS}
    assert not others & set(names)
    assert all(s.cause in untried.CAUSES and untried.CAUSES[s.cause] for s in untried.MISTAKES)
    assert all(s.cause is None for s in untried.CORRECT)
    # A new cause key is one no other class uses, and every new one is used here.
    old = (set(cases.CAUSES) | set(outside.CAUSES) | set(programs.NEW_CAUSES) | set(fresh.NEW_CAUSES)
           | set(blind.NEW_CAUSES) | set(unseen.NEW_CAUSES))
    assert not old & set(untried.NEW_CAUSES)
    assert set(untried.NEW_CAUSES) <= set(untried.CAUSES)
    # Every mistake lies in exactly one category, 3 to 5 a category.
    listed = [n for names in untried.CATEGORIES.values() for n in names]
    assert sorted(listed) == sorted(s.name for s in untried.MISTAKES)
    assert all(3 <= len(v) <= 5 for v in untried.CATEGORIES.values())
    assert len(untried.MISTAKES) >= 24 and len(untried.CORRECT) == 8


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(untried)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(untried)


def test_new_causes_have_their_equivalences_fixed():
    from mcrt.grade.accuracy.run import SAME_MISTAKE, is_named

    assert set(untried.NEW_CAUSES) <= set(SAME_MISTAKE)
    assert is_named("normalised", ["tone_map"]) and is_named("normalised", ["light_radiance"])
    assert is_named("code_overflow", ["quantisation"]) and is_named("object_shape", ["object_moved"])
    assert is_named("preview_kept", ["depth"]) and not is_named("preview_kept", ["spp_claim"])
    assert not is_named("object_shape", ["normals"]) and not is_named("code_overflow", ["bad_pixels"])


def test_the_command_knows_the_class():
    import importlib

    from mcrt.grade.accuracy.cli import CLASSES

    assert importlib.import_module(f"mcrt.grade.accuracy.{CLASSES['untried']}").SPECS is untried.SPECS


def _decoded(codes, maxval=255):
    return srgb_eotf(codes / maxval)


def test_correct_writers_read_back(tmp_path):
    """The correct hand-ins' files read back as the image: a PFM with a newline after it, a plain 16-bit PPM, an
    RGBA BMP, an HDR with an exposure (to RGBE's precision), an RLE EXR, a PPM with comments."""
    x = _image()
    codes = np.floor(srgb_oetf(x) * 255 + 0.5)
    codes16 = np.floor(srgb_oetf(x) * 65535 + 0.5)
    for k, (writer, check) in enumerate((
            (untried._write_pfm_newline, lambda r: np.allclose(r, x, rtol=1e-6)),
            (untried._write_ppm16_plain, lambda r: np.allclose(r, _decoded(codes16, 65535), atol=1e-6)),
            (untried._write_bmp_rgba, lambda r: np.allclose(r, _decoded(codes), atol=1e-6)),
            (untried._write_hdr_exposure, lambda r: np.all(np.abs(r - x) <= x.max(axis=2, keepdims=True) / 128)),
            (untried._write_exr_rle, lambda r: np.allclose(r, x, rtol=1e-6)),
            (untried._write_ppm_comments, lambda r: np.allclose(r, _decoded(codes), atol=1e-6)))):
        folder = tmp_path / str(k)
        folder.mkdir()
        assert check(read_image(writer(x, folder)).mean), writer
    assert b"EXPOSURE=2\n" in (tmp_path / "3" / "render.hdr").read_bytes()[:64]


def test_wrong_writers_read_back_as_their_specs_say(tmp_path):
    x = _image()
    x[0, 0] = 20.0  # a pixel of the light: past the top code
    for d in "abcd":
        (tmp_path / d).mkdir()
    codes8 = np.floor(srgb_oetf(np.clip(x, 0, 1)) * 255 + 0.5).astype(np.uint8)
    # The 16-bit samples (big-endian) under a maxval of 255: twice the data the header declares, which mcrt's reader
    # refuses, naming the maxval.
    codes16 = np.floor(srgb_oetf(np.clip(x, 0, 1)) * 65535 + 0.5).astype(">u2")
    path = untried._write_ppm_16bit_data(x, tmp_path / "a")
    assert path.read_bytes() == f"P6\n{W} {H}\n255\n".encode() + codes16.tobytes()
    with pytest.raises(ImageError, match="holds 2 times the data its header declares"):
        read_image(path)
    # 8-bit codes times 256: white 65280 of 65535.
    r = read_image(untried._write_png16_times_256(x, tmp_path / "b"), linear_png=True).mean
    np.testing.assert_allclose(r * 65535, codes8.astype(np.float64) * 256, atol=0.02)
    # The web palette: levels of 51 codes, dithered (close to the image only on average).
    r = read_image(untried._write_png_web_palette(x, tmp_path / "c"), linear_png=True).mean * 255
    assert set(np.unique(np.round(r))) <= set(range(0, 256, 51))
    assert abs(r.mean() - codes8.mean()) < 8
    # Codes past 255 wrap: the light's code is round(srgb(20) * 255) mod 256; the rest rounded as usual.
    r = read_image(untried._write_png_wrapped(x, tmp_path / "d"), linear_png=True).mean * 255
    assert r[0, 0, 0] == pytest.approx(round(float(srgb_oetf(20.0)) * 255) % 256, abs=1e-3)
    np.testing.assert_allclose(r[1:], codes8[1:], atol=1e-3)


def test_post_processes_do_what_they_say():
    x = _image()
    s = untried._stretched(x)
    assert s.min() == 0.0 and s.max() == pytest.approx(1.0)
    np.testing.assert_allclose(untried._srgb_decoded(srgb_oetf(x)), x, rtol=1e-9)
    # Display P3: white stays white, pure sRGB red is inside P3 (all channels non-negative), less saturated.
    np.testing.assert_allclose(untried._to_display_p3(np.ones(3)), 1.0, atol=1e-9)
    red = untried._to_display_p3(np.array([1.0, 0.0, 0.0]))
    assert np.all(red >= 0) and red[0] < 1 and red[1] > 0.01
    spot = x.copy()
    spot[8, 8] = 50.0
    assert untried._median3(spot)[8, 8, 0] < 1.0  # a firefly removed
    rows = untried._odd_rows_copied(x)
    np.testing.assert_array_equal(rows[1::2], x[0::2])
    np.testing.assert_array_equal(rows[0::2], x[0::2])


def test_geometry_edits():
    from mcrt.scene import load_scene

    s = load_scene()
    tris = untried._sphere_mesh((0.0, 0.0, 0.0), 1.5, 24, 12)
    assert tris.shape == (2 * 24 * 11, 3, 3)
    np.testing.assert_allclose(np.linalg.norm(tris, axis=2), 1.5)  # vertices on the sphere
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    assert np.all(np.einsum("ij,ij->i", n, tris.mean(axis=1)) > 0)  # wound outwards
    tet = next(o for o in untried._tetra_vertex(s, 3, (5.8, -2.3, -2.0)).objects if o.name == "tetrahedron")
    assert tet.vertices[3] == (5.8, -2.3, -2.0) and tet.vertices[:3] == next(
        o for o in s.objects if o.name == "tetrahedron").vertices[:3]
    sph = next(o for o in _by_name("sphere_centre_truncated").edit(s).objects if o.name == "sphere")
    assert sph.center == pytest.approx((9.0, 2.0, -3.0))
    assert untried._radiance_as_power(s).light.radiance == pytest.approx((20 / (4 * math.pi),) * 3)


def _plain(size, spp=256):
    return build_class(width=size, height=size, specs=(cases.Spec("plain", None, spp=spp),))[0].image


@pytest.mark.parametrize("name", ["strata_diagonal", "jitter_once_per_pixel"])
def test_sub_pixel_cells_cover_the_image(name):
    """Pixels made of sub-pixel cells (the diagonal strata, one random cell) agree with a plain render to the noise
    away from edges: each pixel's cells are its own."""
    case = _build(_by_name(name))
    plain = _plain(W)
    rel = np.abs(case.image - plain).mean(axis=2) / (plain.mean(axis=2) + 0.05)
    assert np.median(rel) < 0.15 and case.image.shape == (W, H, 3)


def test_light_at_the_ceiling_fights_with_it():
    """The light coplanar with the ceiling: some of the light's pixels show the ceiling instead."""
    case, plain = _build(_by_name("light_at_ceiling"), 32), _plain(32, 64)
    seen = plain.mean(axis=2) > 10
    assert seen.sum() > 5 and case.image.mean(axis=2)[seen].mean() < 0.9 * 20.0


def test_png_batches_are_display_codes():
    case = _build(_by_name("batches_as_png"))
    codes = case.image * 255
    assert case.image.max() <= 1.0 and np.allclose(codes * 8, np.round(codes * 8), atol=1e-3)  # means of 8 codes


def test_preview_pass_lowers_only_what_is_not_direct():
    """A depth-2 preview kept in the mean: the light seen is unchanged, the rest a little darker, never brighter than
    a full render beyond the noise."""
    case, plain = _build(_by_name("preview_pass_kept"), 32), _plain(32)
    seen, lit = plain.mean(axis=2) > 19.99, plain.mean(axis=2) < 10  # inside the light; not on it
    np.testing.assert_allclose(case.image[seen], 20.0, rtol=1e-4)
    ratio = case.image[lit].mean() / plain[lit].mean()
    assert 0.85 < ratio < 0.99
