"""The eleventh class (mcrt.grade.accuracy.unheard) is well formed and builds what its specs say: the same checks as
test_accuracy_unmet's (specs, writers read back, post-processes, scene edits, a few hand-ins built at 16 x 16, never
graded), on this class's cases.
"""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import (H, W, build as _build, by_name, check_builds, check_held_out_rule,
                              check_not_catalogued, check_specs, image as _image, plain as _plain)
from mcrt.grade.accuracy import blind, cases, fresh, novel, outside, programs, unheard, unmet, unseen, untold, untried
from mcrt.image_files import ImageError, read_image, srgb_eotf

_by_name = partial(by_name, unheard.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unheard, _OTHERS, mistakes=28)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unheard)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unheard)
    assert sum(s.held_out for s in unheard.MISTAKES) == 12 and sum(s.held_out for s in unheard.CORRECT) == 4


def test_new_causes_have_their_equivalences_fixed():
    from mcrt.grade.accuracy.run import SAME_MISTAKE, is_named

    assert set(unheard.NEW_CAUSES) <= set(SAME_MISTAKE)
    assert is_named("indirect_scale", ["indirect_scale"]) and is_named("indirect_scale", ["brdf_norm"])
    assert not any(is_named("indirect_scale", [c]) for c in ("light_radiance", "depth", "roulette", "albedo"))


def test_the_command_knows_the_class():
    import importlib

    from mcrt.grade.accuracy.cli import CLASSES

    assert importlib.import_module(f"mcrt.grade.accuracy.{CLASSES['unheard']}").SPECS is unheard.SPECS


def test_correct_writers_read_back(tmp_path):
    """The correct hand-ins' files read back as the image: a PNG with text and pHYs chunks, an uncompressed EXR with
    an attribute of its own, a BMP stored top line first."""
    import OpenEXR

    x = _image()
    decoded = srgb_eotf(blind._srgb8(x) / 255.0)
    for d in "abc":
        (tmp_path / d).mkdir()
    png = unheard._write_png_text_chunks(x, tmp_path / "a")
    assert b"tEXt" in png.read_bytes() and b"pHYs" in png.read_bytes()
    np.testing.assert_allclose(read_image(png).mean, decoded, atol=1e-6)
    exr = unheard._write_exr_uncompressed(x, tmp_path / "b")
    with OpenEXR.File(str(exr)) as f:
        assert f.header()["compression"] == OpenEXR.NO_COMPRESSION and f.header()["student"] == "hexroom tracer"
    np.testing.assert_allclose(read_image(exr).mean, x, rtol=1e-6)
    bmp = unheard._write_bmp_top_down(x, tmp_path / "c")
    assert int.from_bytes(bmp.read_bytes()[22:26], "little", signed=True) == -H
    np.testing.assert_allclose(read_image(bmp).mean, decoded, atol=1e-6)


def test_wrong_writers_read_back_as_their_specs_say(tmp_path):
    x = _image()
    for d in "abcd":
        (tmp_path / d).mkdir()
    # The red plane in all three channels.
    r = read_image(unheard._write_exr_red_everywhere(x, tmp_path / "a")).mean
    for c in range(3):
        np.testing.assert_allclose(r[..., c], x[..., 0], rtol=1e-6)
    # An RGBA buffer under an RGB header: 4 bytes a pixel in the file, each pixel's sRGB codes then an opaque alpha;
    # the reader refuses it, naming the buffer (since 79507c1, after the class was graded: it read it as RGB, pixel 1
    # the (A, R, G) of the buffer's pixels 0 and 1).
    path = unheard._write_ppm_rgba(x, tmp_path / "b")
    header = unheard._ppm_header(W, H)
    raster = np.frombuffer(path.read_bytes()[len(header):], np.uint8)
    assert raster.size == 4 * W * H
    np.testing.assert_array_equal(raster.reshape(H, W, 4), np.concatenate(
        [blind._srgb8(x), np.full((H, W, 1), 255)], axis=2))
    with pytest.raises(ImageError, match="4 bytes a pixel where its RGB header declares 3: an RGBA buffer"):
        read_image(path)
    # The gamma the wrong way: darker than sRGB's codes between 0 and 1, equal at both ends.
    v = np.array([0.0, 0.01, 0.2, 0.7, 1.0])
    g = unheard._gamma_inverted(v)
    assert g[0] == 0 and g[-1] == 255 and np.all(g[1:-1] < blind._srgb8(v)[1:-1])
    # Text mode: every LF written as CR LF, the header's too; netpbm's single whitespace after maxval broken.
    y = x.copy()
    y[0, 0] = srgb_eotf(10 / 255.0)  # a code 10 among the samples
    path = unheard._write_ppm_text_mode(y, tmp_path / "d")
    data = path.read_bytes()
    assert data.startswith(b"P6\r\n") and data.count(b"\n") == data.count(b"\r\n") >= 4
    assert len(data) > len(unheard._ppm_header(W, H)) + 3 * W * H
    with pytest.raises(ImageError):
        read_image(path)


def test_post_processes_do_what_they_say():
    x = _image()
    flat = np.full((H, W, 3), 0.3)
    b = unheard._bilateral(x)
    assert b.shape == x.shape and not np.allclose(b, x) and b.std() < x.std()
    np.testing.assert_allclose(unheard._bilateral(flat), flat, atol=1e-9)
    np.testing.assert_allclose(unheard._sepia(flat)[0, 0], 0.3 * unheard._SEPIA.sum(axis=1))
    np.testing.assert_allclose(unheard._contrast(np.array([0.05, 0.1, 0.5, 1.0])), [0.0, 0.02, 0.5, 1.1])
    np.testing.assert_allclose(unheard._border_cropped(flat), flat)
    ramp = np.broadcast_to(np.linspace(0.0, 1.0, W)[None, :, None], (H, W, 3))
    c = unheard._border_cropped(ramp)
    assert c.shape == ramp.shape and c[0, 0, 0] > ramp[0, 0, 0] and c[0, -1, 0] < ramp[0, -1, 0]
    w = unheard._strata_weights(4)
    assert w.sum() == pytest.approx(1.0) and np.allclose(w, w[::-1]) and w.argmax() == 3 and len(w) == 7
    g = unheard._gaussian_weights(8, 0.5)
    assert g.max() < 1 and g.min() > 0 and 0.6 < g.mean() < 0.8
    np.testing.assert_allclose(unheard._scaled(flat, 16.0), 16.0 * flat)


def test_scene_edits():
    from mcrt.scene import Mirror, load_scene

    s = load_scene()
    m = {o.name: o.material for o in unheard._materials_swapped(s).objects}
    assert isinstance(m["tetrahedron"], Mirror) and m["sphere"].albedo == (0.8, 0.45, 0.1)
    assert unheard._ceiling_black(s).room.ceiling_albedo == (0.0, 0.0, 0.0)
    a = unheard._albedos_complemented(s)
    assert a.room.floor_albedo == pytest.approx((0.4, 0.4, 0.4)) and a.room.walls[0].albedo == pytest.approx(
        (0.25, 0.85, 0.85))
    t = unheard._world_turned(s)
    assert t.cameras["near"].forward == pytest.approx((0.0, 1.0, 0.0)) and t.room.floor_z == -4.0
    assert t.light.center == pytest.approx((2.0, 2.0, 5.99))
    dm = unheard._in_decimetres(s)
    assert next(o for o in dm.objects if o.name == "sphere").radius == pytest.approx(15.0)
    assert dm.cameras["near"].eye == pytest.approx((-10.0, 0.0, 0.0)) and dm.light.area == pytest.approx(400.0)
    tri = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]])
    par = unheard._parallelograms(tri)
    area = 0.5 * np.linalg.norm(np.cross(par[:, 1] - par[:, 0], par[:, 2] - par[:, 0]), axis=1)
    assert par.shape == (2, 3, 3) and area.sum() == pytest.approx(1.0) and np.all(np.cross(
        par[:, 1] - par[:, 0], par[:, 2] - par[:, 0])[:, 2] > 0)
    assert unheard._fov_of_lens() == pytest.approx(39.6, abs=0.01)
    small = unheard._light_at_centre(s)
    assert small.light.area * small.light.radiance[0] == pytest.approx(s.light.area * s.light.radiance[0])


def test_correct_hand_ins_agree_with_a_plain_render():
    """The turned world, the light seen apart, mcrt in decimetres and with triangles are the plain render to the
    noise."""
    plain = _plain(W, 1024)
    for name in ("ok_world_turned", "ok_hidden_plus_seen", "ok_mcrt_decimetres", "ok_mcrt_triangles"):
        case = _build(_by_name(name))
        rel = np.abs(case.image - plain).mean(axis=2) / (plain.mean(axis=2) + 0.05)
        assert np.median(rel) < 0.15 and case.image.shape == (H, W, 3), name


def test_combined_mistakes_differ_from_the_plain_render_as_they_say():
    plain = _plain(W, 1024)
    lum = plain.mean(axis=2)
    lit = lum < 5
    k = _build(_by_name("strata_divided_by_n"))
    assert 12 < k.image[lit].mean() / plain[lit].mean() < 20
    tiles = _build(_by_name("tiles_overlapping")).image.mean(axis=2)
    border, inside = tiles[:, W // 4], tiles[:, W // 4 + 1]
    assert border.mean() / lum[:, W // 4].mean() > 1.6 and inside.mean() / lum[:, W // 4 + 1].mean() < 1.3
    summed = _build(_by_name("first_hit_rays_summed")).image
    assert summed[lit].mean() > 1.5 * plain[lit].mean()
    dim = _build(_by_name("cosine_pdf_without_pi")).image
    assert dim[lit].mean() < 0.8 * plain[lit].mean()


def test_ray_height_from_column_repeats_the_diagonal():
    case, plain = _build(_by_name("ray_height_from_column")), _plain(W, 1024)
    d = np.arange(W)
    diag = plain[d, d].mean(axis=1)
    cols = case.image.mean(axis=(0, 2))
    lit = diag < 5
    assert np.median(np.abs(cols[lit] - diag[lit]) / (diag[lit] + 0.05)) < 0.1
    assert case.image.mean(axis=2).std(axis=0)[lit].mean() < 0.5 * plain.mean(axis=2).std(axis=0)[lit].mean()


@pytest.mark.parametrize("name", ["pp_bilateral", "tetra_debug_colours",
                                  "tetra_parallelogram_faces", "floor_at_ceiling_height", "wall_quads_half",
                                  "strata_offsets_undivided", "light_samples_at_centre", "light_diamond",
                                  "no_light_after_mirror", "roulette_over_kill_probability",
                                  "filter_weights_unnormalised", "ok_mcrt_fixed_roulette", "ok_bmp_top_down",
                                  "ok_exr_uncompressed"])
def test_hand_ins_build(name, tmp_path):
    check_builds(_by_name(name), tmp_path)
