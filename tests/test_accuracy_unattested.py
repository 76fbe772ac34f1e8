"""The twenty-ninth class (mcrt.grade.accuracy.unattested) is well formed and builds what its specs say: the same
checks as test_accuracy_unattended's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x 16,
never graded), on this class's cases, the frameworks' behaviour it emulates with NumPy checked against values worked
out by hand or by another library (Pillow, SciPy, the standard library).
"""

from __future__ import annotations

import math
import struct
from functools import partial

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import (W, build as _build, by_name, check_builds, check_command, check_correct_agree,
                              check_held_out_rule, check_new_truths, check_not_catalogued, check_old_causes,
                              check_seeds, check_specs, image as _image, pillow_codes, plain as _plain)
from mcrt.grade.accuracy import (unconsidered, blind, cases, fresh, novel, outside, programs, unasked, unattended, unattested,
                                 unbeknown, unbidden, unforeseen, unguessed, unheard, unheralded, unlooked, unmet,
                                 unnoticed, unprompted, unrecorded, unremarked, unremembered, unsaid, unseen, unsought,
                                 untold, untried, unvisited, unwonted)
from mcrt.image_files import read_image, srgb_eotf, srgb_oetf

_by_name = partial(by_name, unattested.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought, unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted,
           unremarked, unremembered, unnoticed, unrecorded, unattended, unconsidered)  # the last, its twin: written the same day, apart


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unattested, _OTHERS, mistakes=28)
    check_new_truths(unattested, _OTHERS)
    assert len(unattested.MISTAKES) == 28 and {len(v) for v in unattested.CATEGORIES.values()} <= {3, 4}
    assert list(unattested.CATEGORIES) == list(unnoticed.CATEGORIES)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unattested)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unattested)
    assert sum(s.held_out for s in unattested.MISTAKES) == 12 and sum(s.held_out for s in unattested.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    check_old_causes(unattested, _OTHERS)
    assert unattested._EARLIER[-1] is unattended and unrecorded in unattested._EARLIER
    assert set(unattested._EARLIER) | {cases, outside, unconsidered} == set(_OTHERS)  # its twin not earlier


def test_seeds_differ_from_the_other_classes():
    check_seeds(unattested, _OTHERS, 1601000)


def test_the_command_knows_the_class():
    check_command(unattested, "unattested")


def _srgb_values(*codes) -> np.ndarray:
    """Linear values whose sRGB encodings are ``codes`` / 65535 (a row of pixels, the same in each channel)."""
    v = srgb_eotf(np.asarray(codes, np.float64) / 65535.0)
    return np.repeat(v[None, :, None], 3, axis=2)


def test_correct_writers_read_back(tmp_path):
    """save_image's clamp, the channels_last storage, OpenCV's saturation and Taichi's field read back as the codes."""
    x = _image()
    c8 = blind._srgb8(x)
    for d in "abcd":
        (tmp_path / d).mkdir()
    # save_image(normalize=True, value_range=(0, 1)): a clamp; the light's values past 1 written 255.
    hot = x.copy()
    hot[0, 0] = 20.0
    path = unattested._write_png_save_image_value_range(hot, tmp_path / "a")
    want = np.floor(np.clip(srgb_oetf(hot), 0, 1) * 255 + 0.5).astype(np.uint8)
    np.testing.assert_array_equal(pillow_codes(path), want)
    assert tuple(pillow_codes(path)[0, 0]) == (255, 255, 255)
    # The channels_last storage: NHWC bytes, each pixel's three codes together, row by row.
    path = unattested._write_ppm_channels_last(x, tmp_path / "b")
    raw = path.read_bytes()
    assert raw.startswith(b"P6\n16 16\n255\n") and raw[13:] == bytes(c8[..., c].flat[k] for k in range(256)
                                                                       for c in range(3))
    np.testing.assert_array_equal(pillow_codes(path), c8)
    # OpenCV's saturate_cast: rounded, clamped to 255.
    path = unattested._write_png_cv2_float(hot, tmp_path / "c")
    got = pillow_codes(path).astype(int)
    assert np.abs(got - want).max() <= 1 and tuple(got[0, 0]) == (255, 255, 255)
    assert list(unattested._cv2_float_codes(np.array([0.0, 1.0, 20.0]))) == [0, 255, 255]
    # Taichi's field (W, H), origin at the bottom left: written the right way up.
    path = unattested._write_png_taichi_field(x, tmp_path / "d")
    np.testing.assert_array_equal(pillow_codes(path), c8)
    np.testing.assert_allclose(read_image(path).mean, srgb_eotf(c8 / 255.0), atol=1e-6)


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    from PIL import Image

    x = _image()
    for d in "abc":
        (tmp_path / d).mkdir()
    c8 = blind._srgb8(x)
    # plt.imsave(origin='lower'): an RGBA PNG upside down.
    path = unattested._write_png_imsave_origin_lower(x, tmp_path / "a")
    assert Image.open(path).mode == "RGBA"
    np.testing.assert_array_equal(pillow_codes(path), c8[::-1])
    # save_image(normalize=True): min-max of the sRGB values (the light's 3.62 the maximum).
    row = np.array([[[0.0] * 3, [1.0] * 3, [20.0] * 3]])
    top = 1.055 * 20 ** (1 / 2.4) - 0.055
    assert list(unattested._save_image_codes(row)[0, :, 0]) == [0, math.floor(255 / top + 0.5), 255]
    path = unattested._write_png_save_image_normalize(x, tmp_path / "b")
    s = srgb_oetf(x)
    np.testing.assert_array_equal(pillow_codes(path), np.floor((s - s.min()) / (s.max() - s.min()) * 255 + 0.5))
    # int16 codes saturated to 8 bits by OpenCV: 0..255 kept, 256..32767 white, 32768 and up (wrapped) black.
    v = _srgb_values(0, 66, 255, 256, 16384, 32767, 32768, 49151, 65535)
    assert list(unattested._cv2_int16_codes(v)[0, :, 0]) == [0, 66, 255, 255, 255, 255, 0, 0, 0]
    path = unattested._write_png_cv2_int16(x, tmp_path / "c")
    c16 = np.floor(srgb_oetf(x) * 65535 + 0.5).astype(np.int64)
    np.testing.assert_array_equal(pillow_codes(path), np.where(c16 >= 32768, 0, np.minimum(c16, 255)))


def test_post_processes_do_what_they_say():
    from scipy.ndimage import uniform_filter

    x = _image()
    # conv2d without groups: each channel the 3 x 3 mean of all three channels, summed (zeros past the border).
    c = np.ones((6, 5, 3)) * np.array([0.2, 0.3, 0.5])
    y = unattested._conv2d_groups_missing(c)
    assert y[2, 2].tolist() == pytest.approx([1.0] * 3) and y[0, 0].tolist() == pytest.approx([4 / 9] * 3)
    assert y[0, 2].tolist() == pytest.approx([6 / 9] * 3)
    box = uniform_filter(x, size=(3, 3, 1), mode="constant")
    np.testing.assert_allclose(unattested._conv2d_groups_missing(x), np.repeat(box.sum(axis=2, keepdims=True), 3, 2))
    # avg_pool2d, count_include_pad: the zero-padded box mean.
    np.testing.assert_allclose(unattested._avg_pool_padded(x), box)
    # grid_sample with corners mixed: a constant image half at its border, a ramp sampled at i W / (W - 1) - 1/2.
    g = unattested._grid_sample_corners_mixed(np.ones((16, 16, 3)))
    assert g[5, 5, 0] == pytest.approx(1.0) and g[0, 5, 0] == pytest.approx(0.5) and g[0, 0, 0] == pytest.approx(0.25)
    ramp = np.repeat(np.repeat(np.arange(16.0)[None, :, None], 16, axis=0), 3, axis=2)
    got = unattested._grid_sample_corners_mixed(ramp)[8, 1:-1, 0]
    np.testing.assert_allclose(got, np.arange(1, 15) * 16 / 15 - 0.5)
    # F.normalize(dim=1): each pixel's colour of length 1, its direction kept.
    n = unattested._normalized_per_pixel(x)
    np.testing.assert_allclose(np.linalg.norm(n, axis=2), 1.0)
    np.testing.assert_allclose(np.cross(n, x), 0.0, atol=1e-12)
    # The pitched film read as packed, against a byte buffer built with struct.
    img = x.astype(np.float32)
    row, pitch = 16 * 12, 512
    dev = b"".join(struct.pack("<48f", *img[r].reshape(-1)) + bytes(pitch - row) for r in range(16))
    want = np.frombuffer(dev[:16 * row], "<f4").reshape(16, 16, 3)
    got = unattested._pitch_ignored(x)
    np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(got[0], img[0])
    np.testing.assert_array_equal(got[1], 0.0)


def test_grids_indices_and_accumulators_are_as_they_say():
    x = _image()
    big = np.random.default_rng(5).random((64, 64, 3))
    # blockDim.x for blockDim.y: rows 16 b + 8 to 16 b + 15 never written.
    rows = unattested._rows_written(64)
    assert [r for r in range(64) if not rows[r]] == [r for r in range(64) if r % 16 >= 8]
    y = unattested._blockdim_typo(big)
    np.testing.assert_array_equal(y[8:16], 0.0)
    np.testing.assert_array_equal(y[16:24], big[16:24])
    assert unattested._rows_written(16).tolist() == [True] * 8 + [False] * 8
    # torch.meshgrid's 'ij': the image transposed.
    np.testing.assert_array_equal(unattested._meshgrid_ij(x), x.transpose(1, 0, 2))
    # Numba's private copies: each thread's block of pixels a running sum (8 blocks of 512 at 64 x 64).
    ones = unattested._prange_private_sums(np.ones((64, 64, 3)))
    flat = ones.reshape(-1, 3)[:, 0]
    assert flat[0] == 1 and flat[511] == 512 and flat[512] == 1 and flat[-1] == 512
    assert ones[7, 63, 0] == 512 and ones[8, 0, 0] == 1
    # uint8 indices: wrapped at 256, rows 60 to 63 in rows 0 to 3, the rest black; no wrap at 16 x 16.
    y = unattested._uint8_indices(big)
    np.testing.assert_array_equal(y[:4], big[60:])
    np.testing.assert_array_equal(y[4:], 0.0)
    np.testing.assert_array_equal(unattested._uint8_indices(x), x)


def test_scene_edits_do_what_they_say():
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    s = load_scene()
    d = scene_dict(s, "near", 4, 4, 8)
    # ids == MIRROR & hit: the id 1 (the ceiling) where a ray hits.
    ids = np.array([9, 1, 0, 5, 1])
    hit = np.array([True, True, True, False, False])
    assert unattested._mask_precedence(ids, hit).tolist() == [False, True, False, False, False]
    assert unattested._IDS[1] == "ceiling"
    e = unattested._ceiling_mirror_sphere_white(d)
    assert "Conductor" in str(e["ceiling"].bsdf()) and e["sphere"]["bsdf"]["type"] == "diffuse"
    # The channel-first table read with reshape(9, 3).
    r = unattested._albedos_reshaped(s)
    assert r.room.floor_albedo == (0.6, 0.8, 0.75) and r.room.ceiling_albedo == (0.55, 0.75, 0.15)
    assert [w.albedo for w in r.room.walls][0] == (0.15, 0.15, 0.8)
    assert next(o for o in r.objects if o.name == "tetrahedron").material.albedo == (0.15, 0.7, 0.1)
    # np.searchsorted's side='left': each surface's first triangle read as the surface before's.
    surfaces, own, read = unattested._triangle_materials()
    starts = np.cumsum([0] + [len(sf.triangles) for sf in surfaces])[1:-1]
    assert (read != own).sum() == len(surfaces) - 1 and np.all(read[starts] == own[starts] - 1)
    e = unattested._materials_searchsorted(d)
    assert e["wall_BC_as_wall_AB"].face_count() == 1 and e["wall_BC"].face_count() == 1
    assert e["floor_as_wall_FA"].face_count() == 1 and e["floor"].face_count() == 3
    assert e["tetrahedron_as_ceiling"].face_count() == 1
    # Six references to one quad: FA's, in AB's colour, the other walls gone.
    e = unattested._walls_one_array(d)
    assert not {"wall_AB", "wall_BC", "wall_CD", "wall_DE", "wall_EF"} & set(e) and e["wall_FA"].face_count() == 2
    # np.diff's edges: (v0, v1, v0 + v2 - v1), in the triangle's plane.
    t = unattested._diff_edge_triangles(np.array([[[0.0, 0, 0], [1, 0, 0], [1, 1, 0]]]))
    assert t.tolist() == [[[0, 0, 0], [1, 0, 0], [0, 1, 0]]]
    assert unattested._triangles_diff_edges(d)["wall_AB"].face_count() == 2
    # The floor discarded, the light's wrapped radiance and Mitsuba's rectangle.
    assert "floor" not in unattested._floor_discarded(d) and "ceiling" in unattested._floor_discarded(d)
    assert unattested._WRAPPED_RADIANCE == pytest.approx((236 / 255,) * 3)
    assert cases.light(size=unattested._RECTANGLE_SIZE)(s).light.size == (4.0, 4.0)
    assert unattested._LENS["aperture_radius"] == 0.05 and unattested._LENS["focus_distance"] == 1.0


def test_bounces_and_roulette_are_as_they_say():
    rng = np.random.default_rng(3)
    n = unsaid._unit(rng.normal(size=(60000, 3)))

    def cosines(d):
        return np.einsum("ij,ij->i", d, n)

    # randn_like: about 34 % of the bounces kept (a normal number in [0, 1]), nearer the normal than cosine.
    d, w = unattested._randn_like_bounce(rng, n)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0)
    from scipy.stats import norm

    assert w.mean() == pytest.approx(norm.cdf(1) - 0.5, abs=0.01) and set(np.unique(w)) <= {0.0, 1.0}
    assert cosines(d)[w > 0].mean() > 2 / 3 + 0.02
    # The roulette on u1: the survivors within asin(sqrt(0.8)) of the normal, weight 1 on average.
    d, w = unattested._roulette_on_u1(rng, n)
    assert w.mean() == pytest.approx(1.0, abs=0.02) and cosines(d)[w > 0].min() >= math.sqrt(0.2) - 1e-9
    # Uniform on the hemisphere, weighted 2 cos: E[w] = 1, E[cos] = 1/2.
    d, w = unattested._uniform_hemisphere(rng, n)
    assert np.all(cosines(d) >= 0) and w.mean() == pytest.approx(1.0, abs=0.02)
    assert cosines(d).mean() == pytest.approx(0.5, abs=0.01)
    # Mitsuba's concentric warp in its Frame3f: cosine-weighted.
    x, y = unattested._concentric_disk(*rng.random((2, 60000)))
    assert np.all(x * x + y * y <= 1 + 1e-12) and np.mean(x * x + y * y) == pytest.approx(0.5, abs=0.01)
    s, t = unattested._frame3f(n)
    np.testing.assert_allclose(np.einsum("ij,ij->i", s, t), 0, atol=1e-9)
    np.testing.assert_allclose(np.cross(s, t), n, atol=1e-9)
    d, w = unattested._warp_cosine(rng, n)
    assert np.all(w == 1) and cosines(d).mean() == pytest.approx(2 / 3, abs=0.01)
    assert np.mean(cosines(d) ** 2) == pytest.approx(0.5, abs=0.01)
    # beta.max(dim=1)[1]: the first largest channel's index; 0 never survives, 1 weighs 1, 2 weighs 1/2.
    beta = np.array([[0.6, 0.6, 0.6], [0.75, 0.7, 0.15], [0.15, 0.7, 0.15], [0.55, 0.15, 0.7], [0.15, 0.65, 0.7]])
    assert unattested._max_index_weight(beta, np.full(5, 0.99)).tolist() == [0.0, 0.0, 1.0, 0.5, 0.5]


def test_light_samples_are_as_they_say():
    rng = np.random.default_rng(4)
    lt = unattested._scene().light
    q = np.concatenate([unattested._lattice_points(rng.random(2)) for _ in range(2000)])
    assert np.all(np.abs(q[:, 0] - lt.center[0]) <= 1) and np.all(np.abs(q[:, 1] - lt.center[1]) <= 1)
    np.testing.assert_allclose(q[:, :2].mean(axis=0), lt.center[:2], atol=0.02)
    grid = unattested._lattice_points((0.0, 0.0))
    assert sorted(set(np.round(grid[:, 0], 9))) == pytest.approx([4.0, 4.5, 5.0, 5.5])
    # ray_test taken for visibility: nothing counted in the open, the light counted under the tetrahedron.
    mscene = unsaid._loaded(8)
    p = np.array([[2.0, 0.0, -4.999], [8.5, -2.3, -4.999]])
    nrm = np.tile([0.0, 0.0, 1.0], (2, 1))
    ld = unattested._light_where_blocked(mscene, rng, p, nrm, np.ones((2, 3)), None)
    assert ld[0, 0] == 0.0 and ld[1, 0] > 0.0
    right = unheralded._shadowed_within(mscene, rng, p, nrm, np.ones((2, 3)), None, reach=np.inf)
    assert right[0, 0] > 0.0 and right[1, 0] == 0.0


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    check_correct_agree(unattested, plain)


def test_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    room = lum < 1
    light = lum > 10

    def image(name):
        return _build(_by_name(name)).image

    # conv2d without groups: grey, two to four times as bright in the room.
    im = image("pp_torch_conv2d_groups_missing")
    np.testing.assert_allclose(im[..., 0], im[..., 2])
    np.testing.assert_allclose(im[..., 0], im[..., 1])
    assert 2 < np.median(im[room].mean(axis=-1) / lum[room]) < 4
    # The 8-bit white times 20 wrapped: 0.046 times the light.
    assert image("light_uint8_colour_times_power").mean() == pytest.approx(236 / 255 / 20 * plain.mean(), rel=0.1)
    # Mitsuba's rectangle scaled by the size: four times the light on the room.
    assert image("light_mitsuba_rectangle_scaled")[room].mean() > 2.5 * plain[room].mean()
    # ray_test for visibility: the surfaces that see the light darker, the light as it was.
    im = image("light_ray_test_as_visible")
    assert im[room].mean() < 0.8 * plain[room].mean()
    assert im[light].mean() == pytest.approx(plain[light].mean(), rel=0.05)
    # Every other band of 8 rows black; the floor gone from the bottom rows.
    assert np.all(image("rows_cuda_blockdim_typo")[8:] == 0.0)
    assert image("floor_jax_at_discarded")[-3:].mean() < 0.3 * plain[-3:].mean()
    # Paths ended at their first diffuse vertex, bounces from normal numbers: less light on the room.
    assert image("throughput_int_ones_like")[room].mean() < 0.9 * plain[room].mean()
    assert image("bounce_torch_randn_like")[room].mean() < 0.95 * plain[room].mean()
    # The running sums of Numba's blocks: far brighter; one stream for every pixel: right on average.
    assert image("pixels_numba_prange_accumulator").mean() > 5 * plain.mean()
    assert image("samples_curand_sequence_zero").mean() == pytest.approx(plain.mean(), rel=0.1)
    # Every pixel's colour of length 1.
    np.testing.assert_allclose(np.linalg.norm(image("pp_torch_normalize_per_pixel"), axis=2), 1.0, rtol=1e-5)
    spec = _by_name("spp_taichi_frozen_global")
    assert spec.spp == 48 and spec.declared_spp == 256


@pytest.mark.parametrize("name", [s.name for s in unattested.SPECS])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back."""
    check_builds(_by_name(name), tmp_path)
