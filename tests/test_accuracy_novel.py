"""The eighth class (mcrt.grade.accuracy.novel) is well formed and builds what its specs say: the same checks as
test_accuracy_untried's (specs, writers read back, post-processes, scene edits, a few hand-ins built at 16 x 16, never
graded), on this class's cases.
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import (H, W, build as _build, by_name, check_builds, check_held_out_rule,
                              check_not_catalogued, check_specs, image as _image, plain as _plain)
from mcrt.grade.accuracy import blind, cases, fresh, novel, outside, programs, unseen, untried
from mcrt.image_files import ImageError, read_image, srgb_eotf, srgb_oetf

_by_name = partial(by_name, novel.SPECS)


def test_specs_are_new_worded_and_in_categories():
    check_specs(novel, (cases, outside, programs, fresh, blind, unseen, untried), mistakes=24)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(novel)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(novel)


def test_new_causes_have_their_equivalences_fixed():
    from mcrt.grade.accuracy.run import SAME_MISTAKE, is_named

    assert set(novel.NEW_CAUSES) <= set(SAME_MISTAKE)
    assert is_named("channel_misaligned", ["resampling"]) and is_named("channel_misaligned", ["pixel_offset"])
    assert is_named("lossy_compression", ["quantisation"]) and is_named("lossy_compression", ["blur"])
    assert is_named("light_seen", ["light_hidden"]) and not is_named("light_seen", ["light_radiance"])
    assert not is_named("channel_misaligned", ["channels"])


def test_the_command_knows_the_class():
    import importlib

    from mcrt.grade.accuracy.cli import CLASSES

    assert importlib.import_module(f"mcrt.grade.accuracy.{CLASSES['novel']}").SPECS is novel.SPECS


def _decoded(codes, maxval=255):
    return srgb_eotf(codes / maxval)


def test_correct_writers_read_back(tmp_path):
    """The correct hand-ins' files read back as the image: a PPM of maxval 1023, a 16-bit PNG by hand, a half EXR
    (to half's precision), an EXR by Mitsuba's Bitmap."""
    x = _image()
    for k, (writer, check) in enumerate((
            (novel._write_ppm_maxval_1023,
             lambda r: np.allclose(r, _decoded(np.floor(srgb_oetf(x) * 1023 + 0.5), 1023), atol=1e-6)),
            (novel._write_png16_by_hand,
             lambda r: np.allclose(r, _decoded(np.floor(srgb_oetf(x) * 65535 + 0.5), 65535), atol=1e-6)),
            (novel._write_exr_half_zips, lambda r: np.allclose(r, x, rtol=1e-3)),
            (novel._write_mitsuba_bitmap, lambda r: np.allclose(r, x, rtol=1e-6)))):
        folder = tmp_path / str(k)
        folder.mkdir()
        assert check(read_image(writer(x, folder)).mean), writer


def test_wrong_writers_read_back_as_their_specs_say(tmp_path):
    x = _image()
    x[0, 0] = 20.0
    for d in "abcd":
        (tmp_path / d).mkdir()
    codes8 = blind._srgb8(x)
    # A JPEG on the way: close to the codes on average, not equal.
    r = read_image(novel._write_jpeg_then_png(x, tmp_path / "a"), linear_png=True).mean * 255
    assert 0 < np.abs(r - codes8).mean() < 40
    # float64 data under a PFM header: twice the bytes, which the reader refuses.
    path = novel._write_pfm_float64(x, tmp_path / "b")
    assert len(path.read_bytes()) == len(f"PF\n{W} {H}\n-1.0\n") + 8 * W * H * 3
    with pytest.raises(ImageError):
        read_image(path)
    # RGB565: red and blue multiples of 8, green of 4, white (248, 252, 248).
    r = np.round(read_image(novel._write_png_rgb565(x, tmp_path / "c"), linear_png=True).mean * 255).astype(int)
    assert np.all(r[..., 0] % 8 == 0) and np.all(r[..., 1] % 4 == 0) and np.all(r[..., 2] % 8 == 0)
    assert tuple(r[0, 0]) == (248, 252, 248)
    # Unsigned-integer channels: the reader refuses them (every value truncated in the file).
    with pytest.raises(ImageError):
        read_image(novel._write_exr_uint(x, tmp_path / "d"))


def test_post_processes_do_what_they_say():
    x = _image()
    e = novel._auto_exposure(x)
    lum = e @ programs._LUMA
    assert math.exp(np.mean(np.log(1e-4 + lum))) == pytest.approx(0.18, rel=0.01)
    np.testing.assert_allclose(novel._log1p(x), np.log1p(x))
    np.testing.assert_allclose(novel._to_d50(np.ones(3)).sum(), 3.0, rtol=0.05)
    white = novel._to_d50(np.ones(3))
    assert white[0] > 1.0 > white[2]  # warmer
    ca = novel._chromatic_aberration(x)
    np.testing.assert_array_equal(ca[..., 1], x[..., 1])
    assert not np.allclose(ca[..., 0], x[..., 0]) and ca.shape == x.shape
    flat = np.full((H, W, 3), 0.5)
    np.testing.assert_allclose(novel._chromatic_aberration(flat), flat)
    assert novel._rgb565(np.full((1, 1, 3), 255, np.uint8)).tolist() == [[[248, 252, 248]]]


def test_scene_edits():
    from mcrt.scene import load_scene

    s = load_scene()
    assert novel._corner(s, "D", (12.0, 0.0)).room.corners["D"] == (12.0, 0.0)
    tet = next(o for o in novel._tetra_scaled_about_origin(s, 0.9).objects if o.name == "tetrahedron")
    orig = next(o for o in s.objects if o.name == "tetrahedron")
    np.testing.assert_allclose(tet.vertices, 0.9 * np.asarray(orig.vertices))
    wall = next(w for w in novel._wall_channels_rotated(s, "BC").room.walls if "".join(w.corners) == "BC")
    assert tuple(wall.albedo) == pytest.approx((0.15, 0.70, 0.55))
    cam = novel._look_at_sphere(s).cameras["near"]
    f = np.asarray(cam.forward)
    assert f[1] > 0 and f[2] < 0 and np.linalg.norm(f) == pytest.approx(1.0)
    sph = next(o for o in _by_name("sphere_y_negated").edit(s).objects if o.name == "sphere")
    assert sph.center == pytest.approx((9.5, -2.0, -3.3))


def test_correct_reductions_agree_with_a_plain_render():
    """The window tiles and the 4x reduction are the plain render to the noise."""
    plain = _plain(W, 1024)
    for name in ("ok_window_tiles", "ok_4x_box_reduced"):
        case = _build(_by_name(name))
        rel = np.abs(case.image - plain).mean(axis=2) / (plain.mean(axis=2) + 0.05)
        assert np.median(rel) < 0.15 and case.image.shape == (H, W, 3), name


def test_light_seen_half_halves_only_the_light():
    case, plain = _build(_by_name("light_seen_half"), 32), _plain(32)
    seen, lit = plain.mean(axis=2) > 19.99, plain.mean(axis=2) < 5
    np.testing.assert_allclose(case.image[seen], 10.0, rtol=1e-3)
    assert 0.9 < case.image[lit].mean() / plain[lit].mean() < 1.1


@pytest.mark.parametrize("name", ["fisheye", "jitter_constant", "light_parallelogram", "sphere_ellipsoid",
                                  "light_sphere", "jitter_sum_of_two", "spp_depth_swapped"])
def test_hand_ins_build(name, tmp_path):
    check_builds(_by_name(name), tmp_path, floor=0.0)


def test_film_filters_blur():
    """The jitter mistakes are rendered with their film filter, not the box a scene dictionary's film is given: the
    energy of the image's differences between neighbours (the light's edges, mostly) drops well below a box render's
    (two seeds of the box differ by about 1 %)."""
    def energy(x):
        x = x.mean(axis=2)
        return float((np.diff(x, axis=0) ** 2).sum() + (np.diff(x, axis=1) ** 2).sum())

    plain = energy(_plain(32))
    for name in ("jitter_sum_of_two", "jitter_gaussian"):
        assert energy(_build(_by_name(name), 32).image) < 0.92 * plain, name
