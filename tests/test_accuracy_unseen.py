"""The sixth class (mcrt.grade.accuracy.unseen) is well formed and builds what its specs say.

These check the specs (names, causes, the held-out rule), the writers (read
back with mcrt's reader: equal where the file is meant to be correct, wrong
in the way the spec says where it is not), the post-processes on small
arrays, and the construction of a few hand-ins at a tiny resolution; they
never grade them (the class was written blind to the grader, with a held-out
half). Mitsuba renders, seeds fixed per case.
"""

from __future__ import annotations

from functools import partial
import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import H, W, build as _build, by_name, check_held_out_rule, image as _image
from mcrt.grade.accuracy import blind, cases, fresh, outside, programs, unseen
from mcrt.grade.accuracy.cases import build_class
from mcrt.image_files import ImageError, read_image, srgb_eotf, srgb_oetf

_by_name = partial(by_name, unseen.SPECS)


def test_specs_are_new_worded_and_in_categories():
    names = [s.name for s in unseen.SPECS]
    assert len(names) == len(set(names))
    others = {s.name for s in cases.SPECS + outside.SPECS + programs.SPECS + fresh.SPECS + blind.SPECS}
    assert not others & set(names)
    assert all(s.cause in unseen.CAUSES and unseen.CAUSES[s.cause] for s in unseen.MISTAKES)
    assert all(s.cause is None for s in unseen.CORRECT)
    # A new cause key is one no other class uses, and every new one is used here.
    old = (set(cases.CAUSES) | set(outside.CAUSES) | set(programs.NEW_CAUSES) | set(fresh.NEW_CAUSES)
           | set(blind.NEW_CAUSES))
    assert not old & set(unseen.NEW_CAUSES)
    assert set(unseen.NEW_CAUSES) <= set(unseen.CAUSES)
    # Every mistake lies in exactly one category, 3 to 5 a category.
    listed = [n for names in unseen.CATEGORIES.values() for n in names]
    assert sorted(listed) == sorted(s.name for s in unseen.MISTAKES)
    assert all(3 <= len(v) <= 5 for v in unseen.CATEGORIES.values())
    assert len(unseen.MISTAKES) >= 22 and len(unseen.CORRECT) == 8


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unseen)


def test_new_causes_have_their_equivalences_fixed():
    from mcrt.grade.accuracy.run import SAME_MISTAKE, is_named

    assert set(unseen.NEW_CAUSES) <= set(SAME_MISTAKE)
    assert is_named("bloom", ["blur"]) and is_named("white_balance", ["colour_grade"])
    assert is_named("shadow_self", ["depth"]) and is_named("biased_estimator", ["sample_clamp"])
    assert not is_named("ambient", ["light_radiance"]) and not is_named("pixel_footprint", ["resampling"])


def test_the_command_knows_the_class():
    import importlib

    from mcrt.grade.accuracy.cli import CLASSES

    assert importlib.import_module(f"mcrt.grade.accuracy.{CLASSES['unseen']}").SPECS is unseen.SPECS


def _decoded(codes, maxval=255):
    return srgb_eotf(codes / maxval)


def test_correct_writers_read_back(tmp_path):
    """The correct hand-ins' files read back as the image: an RGBA PNG, a plain PPM, an RLE HDR (to RGBE's
    precision), an interlaced 16-bit PNG, an RLE TGA."""
    x = _image()
    codes = np.floor(srgb_oetf(x) * 255 + 0.5)
    codes16 = np.floor(srgb_oetf(x) * 65535 + 0.5)
    for k, (writer, check) in enumerate((
            (unseen._write_png_rgba, lambda r: np.allclose(r, _decoded(codes), atol=1e-6)),
            (unseen._write_ppm_plain, lambda r: np.allclose(r, _decoded(codes), atol=1e-6)),
            (unseen._write_hdr_rle, lambda r: np.all(np.abs(r - x) <= x.max(axis=2, keepdims=True) / 128)),
            (unseen._write_png16_interlaced, lambda r: np.allclose(r, _decoded(codes16, 65535), atol=1e-6)),
            (unseen._write_tga_rle, lambda r: np.allclose(r, _decoded(codes), atol=1e-6)))):
        folder = tmp_path / str(k)
        folder.mkdir()
        assert check(read_image(writer(x, folder)).mean), writer


def test_wrong_writers_read_back_as_their_specs_say(tmp_path):
    x = _image()
    for d in ("a", "b", "c", "d", "e"):
        (tmp_path / d).mkdir()
    # 16-bit codes with their bytes swapped.
    codes16 = np.floor(srgb_oetf(x) * 65535 + 0.5).astype(np.uint16)
    r = read_image(unseen._write_png16_little_endian(x, tmp_path / "a"), linear_png=True).mean
    np.testing.assert_allclose(r * 65535, codes16.byteswap(), atol=0.02)
    # A newline too many after the header, then the codes: read as netpbm says, every sample would be one byte late;
    # mcrt's reader refuses the file, naming the extra whitespace.
    codes8 = np.floor(srgb_oetf(x) * 255 + 0.5).astype(np.uint8)
    path = unseen._write_ppm_extra_newline(x, tmp_path / "b")
    assert path.read_bytes() == f"P6\n{W} {H}\n255\n\n".encode() + codes8.tobytes()
    with pytest.raises(ImageError, match="followed by 2 whitespace bytes where netpbm allows one"):
        read_image(path)
    # 'Pf' over the RGB floats (bottom row up): mcrt's reader refuses the file, naming the data its header lacks.
    path = unseen._write_pfm_grey_header(x, tmp_path / "c")
    data = path.read_bytes()
    assert data.startswith(f"Pf\n{W} {H}\n".encode())
    body = np.frombuffer(data[len(data) - H * W * 12:], "<f4").reshape(H, W, 3)[::-1]
    np.testing.assert_allclose(body, x.astype(np.float32), rtol=1e-6)
    with pytest.raises(ImageError, match="holds 3 times the data, as an RGB image does"):
        read_image(path)
    # Exponents one lower: half of what the same writer gives with the right bias.
    half = read_image(unseen._write_hdr_bias_127(x, tmp_path / "d")).mean
    whole = read_image(fresh._write_hdr(x, tmp_path / "e")).mean
    np.testing.assert_allclose(half, whole / 2, rtol=1e-6)


def test_post_processes_do_what_they_say():
    x = _image()
    grey = np.full((H, W, 3), 20.0)
    np.testing.assert_allclose(unseen._reinhard_luminance(grey), 1.0)  # the white point maps to 1
    y = unseen._reinhard_luminance(x)
    np.testing.assert_allclose(y / y.sum(axis=2, keepdims=True), x / x.sum(axis=2, keepdims=True))  # hue kept
    v = unseen._vignette(np.ones((H, W, 3)))
    assert v[H // 2, W // 2, 0] > 0.99 and 0.7 <= v.min() < v[0, W // 2, 0] < 1
    np.testing.assert_array_equal(unseen._bloom(x), x)  # nothing above 1: no glow
    spot = np.zeros((H, W, 3))
    spot[8, 8] = 21.0
    b = unseen._bloom(spot)
    assert b[8, 12, 0] > 0 and b[8, 8, 0] < 21.0 + 0.05 * 20
    m = unseen._grey_world(x).reshape(-1, 3).mean(axis=0)
    np.testing.assert_allclose(m, m.mean())
    r = unseen._rows_up_one(x)
    np.testing.assert_array_equal(r[0], x[1])
    np.testing.assert_array_equal(r[-1], x[0])


def test_smoothed_normals_are_shared_at_each_vertex():
    tris = np.asarray(fresh._surface("tetrahedron").triangles, np.float64)
    n = unseen._smooth_normals(tris)
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0)
    corners = tris.reshape(-1, 3)
    for p in corners:
        same = np.all(np.isclose(corners, p), axis=1)
        assert same.sum() == 3 and np.allclose(n[same], n[same][0])


@pytest.mark.parametrize("name", ["jitter_x_only", "rows_one_seed"])
def test_windowed_renders_cover_the_image(name):
    """Rows rendered as thin bands or as one-row windows put each pixel where a plain render has it: their
    images agree with a plain render's to the noise (jitter in x only changes only aliased pixels)."""
    size = 32 if name == "rows_one_seed" else W
    case = _build(_by_name(name), size)
    plain = build_class(width=size, height=size, specs=(cases.Spec("plain", None, spp=256),))[0].image
    rel = np.abs(case.image - plain).mean(axis=2) / (plain.mean(axis=2) + 0.05)
    assert np.median(rel) < 0.1 and case.image.shape == (size, size, 3)
    if name == "rows_one_seed":  # one random stream for every row: the noise changes less down than across
        lum = case.image.mean(axis=2)
        assert np.median(np.abs(np.diff(lum, axis=0))) < 0.85 * np.median(np.abs(np.diff(lum, axis=1)))


def test_shadow_rays_blocked_leave_only_the_light():
    case = _build(_by_name("shadow_rays_hit_light"))
    lum = case.image.mean(axis=2)
    assert np.mean(lum == 0) > 0.6 and lum.max() == pytest.approx(20.0, rel=1e-4)
