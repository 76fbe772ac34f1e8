"""The ninth class (mcrt.grade.accuracy.untold) is well formed and builds what its specs say: the same checks as
test_accuracy_novel's (specs, writers read back, post-processes, scene edits, a few hand-ins built at 16 x 16, never
graded), on this class's cases.
"""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import (H, W, build as _build, by_name, check_builds, check_held_out_rule,
                              check_not_catalogued, check_specs, image as _image, plain as _plain)
from mcrt.grade.accuracy import blind, cases, fresh, novel, outside, programs, unseen, untold, untried
from mcrt.image_files import ImageError, read_image, srgb_eotf, srgb_oetf

_by_name = partial(by_name, untold.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel)


def test_specs_are_new_worded_and_in_categories():
    check_specs(untold, _OTHERS, mistakes=28)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(untold)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(untold)


def test_new_causes_have_their_equivalences_fixed():
    from mcrt.grade.accuracy.run import SAME_MISTAKE, is_named

    assert set(untold.NEW_CAUSES) <= set(SAME_MISTAKE)
    assert is_named("object_emits", ["ambient"]) and is_named("object_emits", ["material"])
    assert not is_named("object_emits", ["light_radiance"])
    assert is_named("specular_unseen", ["material"]) and is_named("specular_unseen", ["albedo"])
    assert is_named("buffer_reused", ["preview_kept"]) and not is_named("buffer_reused", ["camera_eye"])


def test_the_command_knows_the_class():
    import importlib

    from mcrt.grade.accuracy.cli import CLASSES

    assert importlib.import_module(f"mcrt.grade.accuracy.{CLASSES['untold']}").SPECS is untold.SPECS


def _decoded(codes, maxval=255):
    return srgb_eotf(codes / maxval)


def test_correct_writers_read_back(tmp_path):
    """The correct hand-ins' files read back as the image: a PXR24 EXR (to 24-bit floats), a PNG with an ICC
    profile, a 16-bit .pnm, an HDR by Mitsuba's Bitmap (to RGBE's precision)."""
    x = _image()
    codes = blind._srgb8(x)
    for k, (writer, check) in enumerate((
            (untold._write_exr_pxr24, lambda r: np.allclose(r, x, rtol=1e-4)),
            (untold._write_png_icc, lambda r: np.allclose(r, _decoded(codes), atol=1e-6)),
            (untold._write_pnm16, lambda r: np.allclose(r, _decoded(untried._codes16(x), 65535), atol=1e-6)),
            (untold._write_mitsuba_hdr, lambda r: np.all(np.abs(r - x) <= x.max(axis=2, keepdims=True) / 128)))):
        folder = tmp_path / str(k)
        folder.mkdir()
        assert check(read_image(writer(x, folder)).mean), writer


def test_wrong_writers_read_back_as_their_specs_say(tmp_path):
    x = _image()
    x[0, 0] = 20.0
    for d in "abcd":
        (tmp_path / d).mkdir()
    # The linear segment to 0.04045: dark values brighter than sRGB's, the rest as sRGB.
    r = read_image(untold._write_png_threshold_mixed(x, tmp_path / "a"), linear_png=True).mean
    v = np.array([0.003, 0.02, 0.04, 0.5])
    assert np.all(untold._srgb_threshold_mixed(v)[1:3] > srgb_oetf(v)[1:3])
    assert untold._srgb_threshold_mixed(v)[3] == pytest.approx(srgb_oetf(v)[3])
    assert r.shape == (H, W, 3)
    # Cast before scaling: only values of 1 and over are 255, the rest 0.
    r = np.round(read_image(untold._write_png_cast_before_scale(x, tmp_path / "b"), linear_png=True).mean * 255)
    assert set(np.unique(r)) <= {0.0, 255.0} and tuple(r[0, 0]) == (255, 255, 255) and r[1:].max() == 0
    # Linear quantised first: at most 256 codes, and few in the shadows.
    c = untold._linear_quantised_first(np.linspace(0.0, 0.05, 1000))
    assert len(np.unique(c)) <= 14 and len(np.unique(blind._srgb8(np.linspace(0.0, 0.05, 1000)))) > 60
    # maxval 256 over one byte a sample: netpbm wants two, so the file is refused.
    with pytest.raises(ImageError):
        read_image(untold._write_ppm_maxval_256(x, tmp_path / "d"))


def test_post_processes_do_what_they_say():
    x = _image()
    np.testing.assert_allclose(untold._black_level(x), np.maximum(x - 0.01, 0.0))
    grey = np.full((4, 4, 3), 0.3)
    np.testing.assert_allclose(untold._hue_rotated(grey), grey, atol=1e-12)
    assert not np.allclose(untold._hue_rotated(x), x)
    m = untold._hue_matrix(10.0)
    np.testing.assert_allclose(m @ m.T, np.eye(3), atol=1e-12)
    spot = np.full((H, W, 3), 0.2)
    spot[5, 5] = 3.0
    out = untold._outliers_replaced(spot)
    assert out[5, 5, 0] == pytest.approx(0.2) and np.allclose(np.delete(out.reshape(-1, 3), 5 * W + 5, 0), 0.2)
    flat = np.full((H, W, 3), 0.5)
    np.testing.assert_allclose(untold._barrel(flat), flat)
    b = untold._barrel(x)
    assert b.shape == x.shape and not np.allclose(b, x)


def test_scene_edits():
    from mcrt.scene import load_scene

    s = load_scene()
    tet = next(o for o in untold._tetra_yz_swapped(s).objects if o.name == "tetrahedron")
    orig = next(o for o in s.objects if o.name == "tetrahedron")
    np.testing.assert_allclose(tet.vertices, np.asarray(orig.vertices)[:, [0, 2, 1]])
    assert untold._floor_z(s, -4.0).room.floor_z == -4.0
    assert untold._ceiling_albedo(s, (0.6,) * 3).room.ceiling_albedo == (0.6, 0.6, 0.6)
    sph = next(o for o in _by_name("sphere_r_for_r_squared").edit(s).objects if o.name == "sphere")
    assert sph.radius == pytest.approx(1.5 ** 0.5)
    assert _by_name("eye_at_image_plane").edit(s).cameras["near"].eye == pytest.approx((0.0, 0.0, 0.0))
    assert _by_name("light_height_4_9").edit(s).light.center[2] == pytest.approx(4.9)


def test_correct_combinations_agree_with_a_plain_render():
    """Direct plus indirect passes, and path plus volpath, are the plain render to the noise."""
    plain = _plain(W, 1024)
    for name in ("ok_direct_plus_indirect", "ok_path_volpath_halves"):
        case = _build(_by_name(name))
        rel = np.abs(case.image - plain).mean(axis=2) / (plain.mean(axis=2) + 0.05)
        assert np.median(rel) < 0.15 and case.image.shape == (H, W, 3), name


def test_light_seen_clamped_only_dims_the_light():
    case, plain = _build(_by_name("light_seen_clamped"), 32), _plain(32)
    seen, lit = plain.mean(axis=2) > 19.99, plain.mean(axis=2) < 5
    np.testing.assert_allclose(case.image[seen], 1.0, rtol=1e-3)
    assert 0.9 < case.image[lit].mean() / plain[lit].mean() < 1.1


@pytest.mark.parametrize("name", ["cylindrical_panorama", "jitter_quarter_pixel", "mirror_light_uncounted",
                                  "light_bow_tie", "tetra_emitting", "floor_polished", "light_tracer",
                                  "far_camera_in_buffer", "ok_mcrt_mis_k4", "ok_mcrt_solid_angle"])
def test_hand_ins_build(name, tmp_path):
    check_builds(_by_name(name), tmp_path)
