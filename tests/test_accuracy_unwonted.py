"""The twenty-third class (mcrt.grade.accuracy.unwonted) is well formed and builds what its specs say: the same checks
as test_accuracy_unlooked's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x 16, never
graded), on this class's cases, the cameras, light samples, bounces and sample loops its Mitsuba renders are made of.
"""

from __future__ import annotations

import itertools
import math
from functools import partial

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import (W, build as _build, by_name, check_builds, check_command, check_correct_agree,
                              check_held_out_rule, check_new_truths, check_not_catalogued, check_old_causes,
                              check_seeds, check_specs, image as _image, pillow_codes, plain as _plain)
from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unbeknown, unbidden,
                                 unforeseen, unguessed, unheard, unheralded, unlooked, unmet, unprompted, unsaid,
                                 unseen, unsought, untold, untried, unvisited, unwonted)
from mcrt.image_files import read_image, srgb_eotf

_by_name = partial(by_name, unwonted.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought, unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked)


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unwonted, _OTHERS, mistakes=28)
    check_new_truths(unwonted, _OTHERS)
    assert len(unwonted.MISTAKES) == 28 and {len(v) for v in unwonted.CATEGORIES.values()} <= {3, 4}
    assert list(unwonted.CATEGORIES) == list(unvisited.CATEGORIES) == list(unlooked.CATEGORIES)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unwonted)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unwonted)
    assert sum(s.held_out for s in unwonted.MISTAKES) == 12 and sum(s.held_out for s in unwonted.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    check_old_causes(unwonted, _OTHERS)
    assert unwonted._EARLIER[-1] is unlooked


def test_seeds_differ_from_the_other_classes():
    check_seeds(unwonted, _OTHERS, 1001000)


def test_the_command_knows_the_class():
    check_command(unwonted, "unwonted")


def test_correct_writers_read_back(tmp_path):
    """The TGA 2.0 reads back as its 8-bit codes; the EXR whose windows start at (128, 64) as the image; the Radiance
    picture within RGBE's step; the EXR written by hand as the image's half floats."""
    import OpenEXR

    x = _image()
    c8 = blind._srgb8(x)
    (tmp_path / "a").mkdir()
    path = unwonted._write_tga2(x, tmp_path / "a")
    np.testing.assert_array_equal(pillow_codes(path), c8)
    np.testing.assert_allclose(read_image(path).mean, srgb_eotf(c8 / 255.0), atol=1e-6)
    assert path.read_bytes().endswith(b"TRUEVISION-XFILE.\x00")
    (tmp_path / "b").mkdir()
    path = unwonted._write_exr_window_origin(x * 3.0, tmp_path / "b")
    np.testing.assert_allclose(read_image(path).mean, x * 3.0, rtol=1e-6)
    np.testing.assert_array_equal(OpenEXR.File(str(path)).header()["dataWindow"][0], (128, 64))
    (tmp_path / "c").mkdir()
    path = unwonted._write_pic(x * 3.0, tmp_path / "c")
    assert path.suffix == ".pic" and b"VIEW=" in path.read_bytes()[:200]
    np.testing.assert_allclose(read_image(path).mean, x * 3.0, rtol=1e-2, atol=1e-2)
    (tmp_path / "d").mkdir()
    r = read_image(unwonted._write_exr_by_hand(x * 3.0, tmp_path / "d")).mean
    np.testing.assert_array_equal(r, (x * 3.0).astype(np.float16).astype(np.float32))


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    x = _image()
    for d in "abc":
        (tmp_path / d).mkdir()
    # RGBM: the RGBA codes written, rgb M 6 the render (within a code), the colours read as sRGB.
    y = x.copy()
    y[0, 0] = (0.1, 0.1, 0.1)
    path = unwonted._write_png_rgbm(y, tmp_path / "a")
    from PIL import Image

    rgba = np.asarray(Image.open(path))
    np.testing.assert_array_equal(rgba, unwonted._rgbm(y))
    back = rgba[..., :3] / 255.0 * rgba[..., 3:] / 255.0 * unwonted._RGBM_RANGE
    np.testing.assert_allclose(back, y, atol=0.03)
    assert rgba[0, 0, 0] == 217 and read_image(path).mean[0, 0, 0] == pytest.approx(0.694, abs=1e-3)
    # stb's stride: row 3 is the buffer's row 1 (W bytes a row for 3 W), rows 1 and 2 start a third of a row in.
    codes = pillow_codes(unwonted._write_png_stride_width(x, tmp_path / "b"))
    c8 = blind._srgb8(x)
    np.testing.assert_array_equal(codes[3], c8[1])
    np.testing.assert_array_equal(codes[1].reshape(-1)[:3 * W - W], c8.reshape(-1)[W:3 * W])
    # The floats' upper halves read as halves: 1 as 1.875, 0.1 as 1.449, 20 as 2.8125, the order kept.
    z = np.zeros((16, 16, 3))
    z[0, :4, 0] = (1.0, 0.1, 20.0, 0.01)
    r = read_image(unwonted._write_exr_high_halves(z, tmp_path / "c")).mean
    np.testing.assert_allclose(r[0, :4, 0], (1.875, 1.449, 2.8125, 1.034), atol=1e-3)
    assert r[1, 1, 1] == 0.0
    v = np.sort(np.random.default_rng(1).random(100) * 20)
    assert np.all(np.diff(unwonted._high_halves(v).astype(np.float64)) >= 0)


def test_post_processes_do_what_they_say():
    x = _image()
    # Khronos' neutral: the offset off the darks, greys under 0.76 otherwise kept, the light compressed under 1.
    grey = np.array([[[0.02] * 3, [0.1] * 3, [0.5] * 3, [20.0] * 3]])
    np.testing.assert_allclose(unwonted._pbr_neutral(grey)[0, :3, 0], (0.0025, 0.06, 0.46))
    assert 0.99 < unwonted._pbr_neutral(grey)[0, 3, 0] <= 1.0
    # CAS: a flat image kept, a lone bright pixel brighter and its neighbours darker; neighbourhoods over 1 kept.
    flat = np.full((5, 5, 3), 0.3)
    np.testing.assert_allclose(unwonted._cas(flat), flat)
    spot = flat.copy()
    spot[2, 2] = 0.4
    out = unwonted._cas(spot)
    assert out[2, 2, 0] > 0.4 and out[2, 1, 0] < 0.3
    hot = flat.copy()
    hot[2, 2] = 5.0
    np.testing.assert_allclose(unwonted._cas(hot)[1:4, 1:4], hot[1:4, 1:4])
    # The LUT without its half texel: (16 v - 0.5) / 15, clamped.
    np.testing.assert_allclose(unwonted._lut_half_texel(np.array([[[0.01, 0.1, 0.5]]])), [[[0.0, 1.1 / 15, 0.5]]])
    assert unwonted._lut_half_texel(np.array([[[20.0] * 3]])).max() == 1.0
    # A physical camera at f/16, 1/125 s, ISO 100.
    assert unwonted._ev100() == pytest.approx(14.966, abs=1e-3)
    np.testing.assert_allclose(unwonted._physical_exposure(x), x / (1.2 * 32000.0))
    # ACEScg: greys kept, a red wall desaturated.
    np.testing.assert_allclose(unwonted._to_acescg(np.full((1, 1, 3), 0.4)), 0.4, atol=1e-4)
    np.testing.assert_allclose(unwonted._to_acescg(np.array([[[0.75, 0.15, 0.15]]]))[0, 0], (0.518, 0.192, 0.162),
                               atol=1e-3)
    # The checkerboard: even pixels kept, the others their 4 neighbours' mean.
    cb = unwonted._checkerboard(x)
    np.testing.assert_array_equal(cb[2, 2], x[2, 2])
    np.testing.assert_allclose(cb[2, 3], (x[1, 3] + x[3, 3] + x[2, 2] + x[2, 4]) / 4)
    np.testing.assert_allclose(cb[0, 1], (x[1, 1] + x[0, 0] + x[0, 2]) / 3)


def test_scene_edits_do_what_they_say():
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    s = load_scene()
    edited = unwonted._albedos_bytes(s)
    assert edited.room.floor_albedo == pytest.approx((153 / 256,) * 3)
    walls = {"".join(w.corners): w.albedo for w in edited.room.walls}
    assert walls["AB"] == pytest.approx((191 / 256, 38 / 256, 38 / 256))
    assert unwonted._albedos_pi_int(s).room.ceiling_albedo == pytest.approx((0.8 * math.pi / 3,) * 3)
    assert unwonted._light_gamma_decoded(s).light.radiance == pytest.approx((20.0 ** 2.2,) * 3)
    assert unwonted._light_gamma_decoded(s).light.center == s.light.center
    cam = s.cameras["near"]
    assert unwonted._view_translation(cam.eye, cam.forward, cam.up) == pytest.approx(unwonted._VIEW_TRANSLATION)
    moved = unwonted._eye_from_view(s).cameras["near"]
    assert moved.eye == (0.0, 0.0, -1.0) and moved.forward == cam.forward
    d = scene_dict(s, "near", 4, 4, 8)
    flat = unwonted._flat_boxes_missed(d)
    assert not set(unwonted._FLAT) & set(flat) and flat["tetrahedron"].face_count() == 3 and "light" in flat
    # The light met as the ceiling 0.01 above it (half-size 0: never met), still emitting for its samples.
    import mitsuba as mi

    light = unwonted._light_as_ceiling(d)["light"]
    assert light.emitter() is not None
    np.testing.assert_allclose(np.array(mi.traverse(light.bsdf())["brdf_0.reflectance.value"]).reshape(-1), 0.8)
    # The icosahedron: 320 coplanar triangles in 20 faces wound outwards, vertices on the sphere, faces 1.19 in.
    sph = s.spheres()[0]
    ico = unwonted._icosahedron(sph.center, sph.radius)
    c = np.asarray(sph.center)
    np.testing.assert_allclose(np.linalg.norm(ico - c, axis=2), sph.radius)
    nrm = np.cross(ico[:, 1] - ico[:, 0], ico[:, 2] - ico[:, 0])
    assert np.all(np.einsum("ij,ij->i", nrm, ico.mean(axis=1) - c) > 0)
    np.testing.assert_allclose(np.linalg.norm(ico.mean(axis=1) - c, axis=1), 1.192, atol=1e-3)
    tris = unwonted._flat_subdivided(ico)
    assert tris.shape == (320, 3, 3) and unwonted._sphere_icosahedron(d)["sphere"].face_count() == 320
    # The camera's up not orthogonal: the same sensor; the y-flipped sensor mirrors the rows.
    a = np.array(d["sensor"]["to_world"].matrix)
    np.testing.assert_allclose(np.array(unwonted._up_not_orthogonal(d)["sensor"]["to_world"].matrix), a, atol=1e-6)
    b = np.array(unwonted._sensor_y_flipped(d)["sensor"]["to_world"].matrix)
    np.testing.assert_allclose(b[:3, 1], -a[:3, 1])
    np.testing.assert_allclose(b[:3, [0, 2, 3]], a[:3, [0, 2, 3]])


def test_cameras_and_offsets_are_as_they_say():
    eye, r, u, f, _ = unsaid._frame()
    # Panini (distance 1): the centre along the view, the edges' middles 45 degrees off, the middle magnified.
    o, d = unwonted._panini(np.array([0.5, 0.0, 1.0, 0.5, 0.75]), np.array([0.5, 0.5, 0.5, 0.0, 0.5]))
    np.testing.assert_allclose(o, np.tile(eye, (5, 1)))
    np.testing.assert_allclose(d[0], f, atol=1e-12)
    assert math.degrees(math.acos(d[1] @ f)) == pytest.approx(45.0) and d[1] @ r < 0 < d[2] @ r
    assert math.degrees(math.atan2(d[3] @ u, d[3] @ f)) == pytest.approx(math.degrees(math.atan(2 * math.tan(
        math.radians(22.5)))))
    _, pin = unsaid._pinhole(np.array([0.75]), np.array([0.5]))
    assert math.acos(d[4] @ f) < math.acos(pin[0] @ f)
    # The TAA's table: 8 points in every pixel, mean (0.445, 0.5).
    rng = np.random.default_rng(1)
    uu, vv = unwonted._taa_halton(rng, 64, w=4, pixels=3)
    assert uu.shape == (3, 64) and len(set(zip(uu[0], vv[0]))) == 8
    np.testing.assert_allclose(uu[1, :8], [0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875, 0.0625])
    assert uu.mean() == pytest.approx(0.4453, abs=1e-4) and vv.mean() == pytest.approx(0.5)
    # The PCG offsets: uniform on the pixel, different from pixel to pixel and chunk to chunk.
    uu, vv = unwonted._pcg_offsets(rng, 256, w=8, pixels=64)
    assert uu.shape == (64, 256) and np.all((0 <= uu) & (uu < 1)) and np.all((0 <= vv) & (vv < 1))
    assert uu.mean() == pytest.approx(0.5, abs=0.01) and vv.mean() == pytest.approx(0.5, abs=0.01)
    assert abs(np.corrcoef(uu.reshape(-1), vv.reshape(-1))[0, 1]) < 0.02
    assert not np.allclose(uu[0], uu[1]) and not np.allclose(unwonted._pcg_offsets(rng, 256, w=8, pixels=64)[0], uu)


def test_light_samples_are_as_they_say():
    rng = np.random.default_rng(2)
    q = unbeknown._light_points(rng, 2000)
    p = np.tile([[9.0, -5.999, -1.0]], (2000, 1))
    n = np.tile([[0.0, 1.0, 0.0]], (2000, 1))
    wi = unsaid._unit(q - p)
    d2 = np.sum((q - p) ** 2, axis=1)
    # The half vector.
    h = unsaid._unit(wi + unsaid._unit(unsaid._frame()[0] - p))
    np.testing.assert_allclose(unwonted._half_vector(p, n, q), np.maximum(h[:, 1], 0) * wi[:, 2] / d2)
    # The undecoded normal map: every normal tilted 35.4 degrees.
    ns = unsaid._unit(np.random.default_rng(3).normal(size=(100, 3)))
    cos = np.einsum("ij,ij->i", unwonted._normal_mapped(ns), ns)
    np.testing.assert_allclose(np.degrees(np.arccos(cos)), 35.37, atol=0.01)
    # The light's normal as a point: (0.78, 0, 0.62); the floor under the light unlit, a far wall's top lit.
    np.testing.assert_allclose(unwonted._light_normal_as_point(), (0.7816, 0.0, 0.6237), atol=1e-4)
    assert not unwonted._normal_as_point_geometry(np.tile([[5.0, 0.0, -4.999]], (2000, 1)),
                                                  np.tile([[0.0, 0.0, 1.0]], (2000, 1)), q).any()
    wall = np.tile([[12.4, -1.2, 4.0]], (2000, 1))
    inward = np.tile([[-0.894, 0.447, 0.0]], (2000, 1))
    assert unwonted._normal_as_point_geometry(wall, inward, q).mean() > 0.5 * unbeknown._geometry(wall, inward,
                                                                                                  q).mean()
    # The light from its centre.
    full = unsaid._loaded(2)
    rho = np.ones((2000, 3))
    c = np.tile(unwonted._scene().light.center, (4, 1))
    got = unwonted._light_sample_at_centre(full, rng, p[:4], n[:4], rho[:4], None)
    np.testing.assert_allclose(got[:, 0], unbeknown._geometry(p[:4], n[:4], c) * 4.0 / math.pi * 20.0)


def test_bounces_are_as_they_say():
    rng = np.random.default_rng(3)
    n = np.tile([[0.0, 0.0, 1.0]], (20000, 1))
    # One octant: unit directions over the hemisphere leaning towards +x and +y (on the floor), weight 1.
    d, wt = unwonted._one_octant_plus_normal(rng, n)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0)
    assert np.all(wt == 1.0) and np.all(d >= 0.0)
    ok, _ = unprompted._cosine_directions(np.random.default_rng(4), n)
    assert np.mean(d[:, 0]) > 0.2 and abs(np.mean(ok[:, 0])) < 0.01
    # The height pow(1 - u1, 1 / 2) = 1: every direction within 45 degrees of the normal, tan of its angle sqrt(u1).
    d, wt = unwonted._height_pow_half(np.random.default_rng(5), n)
    assert np.all(wt == 1.0) and np.all(d[:, 2] >= math.cos(math.pi / 4) - 1e-12)
    tan2 = (d[:, 0] ** 2 + d[:, 1] ** 2) / d[:, 2] ** 2
    assert tan2.mean() == pytest.approx(0.5, abs=0.01)
    # The transposed frame: cosine-weighted about the floor's normal, half lost on a wall facing +y.
    d, wt = unwonted._frame_transposed(rng, n)
    assert np.all(wt == 1.0) and np.mean(d[:, 2]) == pytest.approx(2 / 3, abs=0.01)
    d, wt = unwonted._frame_transposed(rng, np.tile([[0.0, 1.0, 0.0]], (20000, 1)))
    assert wt.mean() == pytest.approx(0.5, abs=0.02)
    np.testing.assert_allclose(np.mean(d, axis=0), (-2 / 3, 0.0, 0.0), atol=0.02)


def test_samples_and_paths_combined_as_they_say():
    # The roulette dividing the radiance: the weights, checked by enumerating every survival.
    w = unwonted._radiance_divided_weights(0.5, 3)
    np.testing.assert_allclose(w, [3.5, 3.5, 3.5, 3.5, 1.5, 0.625, 0.25, 0.09375])
    s = np.random.default_rng(6).random(8)

    def traced(lives):
        radiance = s[0]
        for v in range(1, 8):
            radiance += s[v]
            if v >= 3:
                if not lives[v - 3]:
                    break
                radiance /= 0.5
        return radiance

    expected = np.mean([traced(lives) for lives in itertools.product((False, True), repeat=5)])
    assert expected == pytest.approx(w @ s)
    # The RGBA8 target: constant frames kept to the code, the light 1, codes only.
    const = np.full((2, 64, 3), 0.5)
    np.testing.assert_allclose(unwonted._rgba8_blended(const), 128 / 255)
    samples = np.random.default_rng(7).random((3, 64, 3)) * 2.0
    out = unwonted._rgba8_blended(samples)
    assert out.max() <= 1.0 and np.allclose(out * 255, np.round(out * 255))
    # The tone-mapped resolve: constant pixels kept, varying ones under their mean.
    np.testing.assert_allclose(unwonted._tonemapped_resolve(np.full((2, 8, 3), 3.0)), 3.0)
    varying = np.random.default_rng(8).exponential(1.0, (50, 64, 3))
    assert np.all(unwonted._tonemapped_resolve(varying) @ programs._LUMA < varying.mean(axis=1) @ programs._LUMA)
    # The fixed-point film: right under 16, wrapped from there.
    sums = unwonted._fixed_point_sum(np.array([0.5, 20.0])[:, None, None] * np.ones((2, 256, 3)))
    np.testing.assert_allclose(sums[0] / 256, 0.5)
    np.testing.assert_allclose(sums[1] / 256, 4.0)


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    check_correct_agree(unwonted, plain)


def test_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    seen, lit = lum > 5, lum < 1

    def image(name):
        return _build(_by_name(name)).image.mean(axis=2)

    # Constant factors.
    assert image("light_radiance_gamma_decoded").mean() == pytest.approx(20 ** 1.2 * lum.mean(), rel=0.05)
    assert image("roulette_divides_radiance").mean() > 2.5 * lum.mean()
    # Brighter or darker lit surfaces, the light seen right (for the tone-mapped resolve, its brightest pixel: the
    # light's edges, whose samples vary, are darker).
    for name, lo, hi in (("lambert_pi_declared_int", 1.04, 1.2), ("albedos_bytes_over_256", 0.97, 1.0),
                         ("frames_resolved_tonemapped", 0.7, 0.99)):
        im = image(name)
        assert lo * lum[lit].mean() < im[lit].mean() < hi * lum[lit].mean(), name
        if name == "frames_resolved_tonemapped":
            assert im.max() == pytest.approx(lum.max(), rel=0.05) and im[seen].mean() < 0.9 * lum[seen].mean()
        else:
            assert im[seen].mean() == pytest.approx(lum[seen].mean(), rel=0.05), name
    # The light's own pixels: 1 in the RGBA8 target, 4 for 20 in the fixed-point film; never met at half-size 0.
    assert image("frames_rgba8_blended").max() <= 1.0
    assert image("film_fixed_point_atomics")[seen].mean() < 0.5 * lum[seen].mean()
    assert image("light_half_size_integer_division")[seen].mean() < 1.0
    # The flat boxes: the void through the floor and the ceiling, black.
    assert (image("bvh_flat_boxes_missed") < 1e-4).mean() > 0.3


@pytest.mark.parametrize("name", [s.name for s in unwonted.SPECS])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back."""
    check_builds(_by_name(name), tmp_path)
