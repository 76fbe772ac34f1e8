"""The tenth class (mcrt.grade.accuracy.unmet) is well formed and builds what its specs say: the same checks as
test_accuracy_untold's (specs, writers read back, post-processes, scene edits, a few hand-ins built at 16 x 16, never
graded), on this class's cases.
"""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import (H, W, build as _build, by_name, check_builds, check_held_out_rule,
                              check_not_catalogued, check_specs, image as _image, plain as _plain)
from mcrt.grade.accuracy import blind, cases, fresh, novel, outside, programs, unmet, unseen, untold, untried
from mcrt.image_files import read_image, srgb_eotf, srgb_oetf

_by_name = partial(by_name, unmet.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unmet, _OTHERS, mistakes=28)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unmet)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unmet)


def test_new_causes_have_their_equivalences_fixed():
    from mcrt.grade.accuracy.run import SAME_MISTAKE, is_named

    assert set(unmet.NEW_CAUSES) <= set(SAME_MISTAKE)
    assert is_named("grain", ["blur"]) and not is_named("grain", ["spp_claim"])
    assert is_named("direct_missing", ["light_pdf"]) and not is_named("direct_missing", ["light_radiance"])
    assert is_named("specular_weight", ["material"]) and is_named("sample_count", ["spp_claim"])
    assert is_named("wrong_buffer", ["tone_map"]) and not is_named("wrong_buffer", ["light_radiance"])


def test_the_command_knows_the_class():
    import importlib

    from mcrt.grade.accuracy.cli import CLASSES

    assert importlib.import_module(f"mcrt.grade.accuracy.{CLASSES['unmet']}").SPECS is unmet.SPECS


def test_correct_writers_read_back(tmp_path):
    """The correct hand-ins' files read back as the image: a PNG with an sRGB chunk, an EXR stored bottom line
    first."""
    x = _image()
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    png = unmet._write_png_srgb_chunk(x, tmp_path / "a")
    assert b"sRGB" in png.read_bytes()[:64]
    np.testing.assert_allclose(read_image(png).mean, srgb_eotf(blind._srgb8(x) / 255.0), atol=1e-6)
    np.testing.assert_allclose(read_image(unmet._write_exr_decreasing_y(x, tmp_path / "b")).mean, x, rtol=1e-6)


def test_wrong_writers_read_back_as_their_specs_say(tmp_path):
    x = _image()
    # floor(log2) for frexp's exponent: the largest channel read short by 2^e (its mantissa wrapped), the exponent
    # one lower than a correct writer's.
    r = read_image(unmet._write_hdr_log2_exponent(x, tmp_path)).mean
    big = x.argmax(axis=2)[..., None]
    top = np.take_along_axis(x, big, axis=2)
    wrapped = top - 2.0 ** np.floor(np.log2(top))
    np.testing.assert_allclose(np.take_along_axis(r, big, axis=2), wrapped, atol=top.max() / 128)
    # The power 1/2.4 alone: brighter than sRGB in the shadows, equal at 0 and 1.
    v = np.array([0.0, 0.01, 0.2, 1.0])
    codes = unmet._power_2_4(v)
    assert codes[0] == 0 and codes[3] == 255 and np.all(codes[1:3] > blind._srgb8(v)[1:3])
    assert srgb_oetf(0.01) < 0.01 ** (1 / 2.4)


def test_post_processes_do_what_they_say():
    x = _image()
    grain = unmet._grain(x, seed=1)
    assert grain.min() >= 0 and not np.allclose(grain, x)
    d = grain - x
    np.testing.assert_allclose(d[..., 0], d[..., 1], atol=1e-12)  # one number a pixel, in all channels
    eq = unmet._equalised(x)
    order = np.argsort(x.ravel())
    assert eq.shape == x.shape and eq.max() == pytest.approx(1.0) and np.all(np.diff(eq.ravel()[order]) >= 0)
    k = unmet._soft_knee(np.array([0.5, 0.8, 1.0, 20.0]))
    assert k[0] == 0.5 and k[1] == pytest.approx(0.8) and 0.8 < k[2] < k[3] < 1.0
    flat = np.full((H, W, 3), 0.3)
    np.testing.assert_allclose(unmet._edges_smoothed(flat), flat)
    step = flat.copy()
    step[:, W // 2:] = 0.9
    out = unmet._edges_smoothed(step)
    assert np.allclose(out[:, :W // 2 - 1], 0.3) and not np.allclose(out, step)
    w = unmet._disk_weights(8)
    assert w.sum() == pytest.approx(1.0) and w[0, 0] == 0 and w[3, 3] == w.max()


def test_scene_edits():
    from mcrt.scene import load_scene

    s = load_scene()
    tet = next(o for o in unmet._tetra_model_space(s).objects if o.name == "tetrahedron")
    np.testing.assert_allclose(np.mean(tet.vertices, axis=0), 0.0, atol=1e-12)
    n = unmet._albedos_normalised(s)
    assert np.linalg.norm(n.room.floor_albedo) == pytest.approx(1.0)
    assert all(np.linalg.norm(w.albedo) == pytest.approx(1.0) for w in n.room.walls)
    assert unmet._forward_negated(s).cameras["near"].forward == (-1.0, -0.0, -0.0)
    assert _by_name("light_z_sign").edit(s).light.center == pytest.approx((5.0, 0.0, -4.99))
    v = np.arange(18, dtype=np.float32).reshape(2, 3, 3)
    np.testing.assert_allclose(unmet._doubled_about_centre(v.copy()).reshape(-1, 3).mean(axis=0), v.reshape(-1, 3)
                               .mean(axis=0), rtol=1e-6)


def test_correct_hand_ins_agree_with_a_plain_render():
    """Welford passes, Mitsuba's film and mcrt's caustics rendered apart are the plain render to the noise."""
    plain = _plain(W, 1024)
    for name in ("ok_welford_passes", "ok_mi_render_film", "ok_mcrt_caustics_apart"):
        case = _build(_by_name(name))
        rel = np.abs(case.image - plain).mean(axis=2) / (plain.mean(axis=2) + 0.05)
        assert np.median(rel) < 0.15 and case.image.shape == (H, W, 3), name


def test_first_hit_unlit_darkens_what_the_camera_sees():
    case, plain = _build(_by_name("first_hit_unlit")), _plain(W)
    lit = plain.mean(axis=2) < 5
    assert case.image[lit].mean() < 0.8 * plain[lit].mean()


@pytest.mark.parametrize("name", ["floor_checkerboard", "tetra_see_through", "sphere_normal_from_origin",
                                  "light_sampled_4x4", "light_face_wound_up", "roulette_unstopped",
                                  "mirror_cosine_weighted", "squares_written", "ok_mcrt_bidirectional",
                                  "ok_mcrt_plugin", "ok_mcrt_sobol"])
def test_hand_ins_build(name, tmp_path):
    check_builds(_by_name(name), tmp_path)
