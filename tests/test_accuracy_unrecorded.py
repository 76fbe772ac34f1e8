"""The twenty-seventh class (mcrt.grade.accuracy.unrecorded) is well formed and builds what its specs say: the same
checks as test_accuracy_unnoticed's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x 16,
never graded), on this class's cases, the light samples, mirror, bounces and sample loops its Mitsuba renders are made
of.
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import (W, build as _build, by_name, check_builds, check_command, check_correct_agree,
                              check_held_out_rule, check_new_truths, check_not_catalogued, check_old_causes,
                              check_seeds, check_specs, image as _image, pillow_codes, plain as _plain)
from mcrt.grade.accuracy import (unattended, blind, cases, fresh, novel, outside, programs, unasked, unbeknown, unbidden,
                                 unforeseen, unguessed, unheard, unheralded, unlooked, unmet, unnoticed, unprompted,
                                 unrecorded, unremarked, unremembered, unsaid, unseen, unsought, untold, untried,
                                 unvisited, unwonted)
from mcrt.image_files import read_image, srgb_eotf, srgb_oetf

_by_name = partial(by_name, unrecorded.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought, unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted,
           unremarked, unremembered, unnoticed, unattended)  # the last, its twin: written the same day, apart


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unrecorded, _OTHERS, mistakes=28)
    check_new_truths(unrecorded, _OTHERS)
    assert len(unrecorded.MISTAKES) == 28 and {len(v) for v in unrecorded.CATEGORIES.values()} <= {3, 4}
    assert list(unrecorded.CATEGORIES) == list(unnoticed.CATEGORIES)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unrecorded)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unrecorded)
    assert sum(s.held_out for s in unrecorded.MISTAKES) == 12 and sum(s.held_out for s in unrecorded.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    check_old_causes(unrecorded, _OTHERS)
    assert unrecorded._EARLIER[-1] is unnoticed and unremembered in unrecorded._EARLIER


def test_seeds_differ_from_the_other_classes():
    check_seeds(unrecorded, _OTHERS, 1401000)


def test_the_command_knows_the_class():
    check_command(unrecorded, "unrecorded")


def test_correct_writers_read_back(tmp_path):
    """The fwrite PPM and stb's PNG read back as their 8-bit codes; stb's HDR and tinyexr's half EXR as the image."""
    x = _image()
    c8 = blind._srgb8(x)
    for writer, d in ((unrecorded._write_ppm_fwrite_rows, "a"), (unrecorded._write_png_stride_3w, "b")):
        (tmp_path / d).mkdir()
        path = writer(x, tmp_path / d)
        np.testing.assert_array_equal(pillow_codes(path), c8)
        np.testing.assert_allclose(read_image(path).mean, srgb_eotf(c8 / 255.0), atol=1e-6)
    (tmp_path / "c").mkdir()
    y = x * 20.0
    got = read_image(unrecorded._write_hdr_stb(y, tmp_path / "c")).mean
    assert np.all(np.abs(got - y) <= y.max(axis=2, keepdims=True) / 128 + 1e-6)
    (tmp_path / "d").mkdir()
    got = read_image(unrecorded._write_exr_bgr_half(y, tmp_path / "d")).mean
    np.testing.assert_allclose(got, y, rtol=1e-3)


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    x = _image()
    h, w = x.shape[:2]
    for d in "abcd":
        (tmp_path / d).mkdir()
    c8 = blind._srgb8(x)
    # OpenEXR's strides swapped: the image transposed (half floats).
    got = read_image(unrecorded._write_exr_strides_swapped(x, tmp_path / "a")).mean
    np.testing.assert_allclose(got, x.transpose(1, 0, 2), rtol=1e-3)
    # tinyexr: red under B, blue under R.
    got = read_image(unrecorded._write_exr_names_bgr_data_rgb(x, tmp_path / "b")).mean
    np.testing.assert_allclose(got, x[..., ::-1], rtol=1e-6)
    # The HDR of the display buffer: sRGB-encoded values, clipped at 1.
    y = x * 3.0
    got = read_image(unrecorded._write_hdr_display_buffer(y, tmp_path / "c")).mean
    want = srgb_oetf(np.clip(y, 0.0, 1.0))
    assert np.all(np.abs(got - want) <= want.max(axis=2, keepdims=True) / 128 + 1e-6) and got.max() <= 1.0
    # The vec4 film read as 3 floats a pixel.
    v = unrecorded._vec4_read_as_3(x)
    np.testing.assert_array_equal(v[0, 1], [1.0, x[0, 1, 0], x[0, 1, 1]])
    np.testing.assert_array_equal(v[0, 0], x[0, 0])
    got = read_image(unrecorded._write_hdr_vec4_as_3(x, tmp_path / "d")).mean
    assert np.all(np.abs(got - v) <= v.max(axis=2, keepdims=True) / 128 + 1e-6)
    # stb's RGBE: truncated mantissas (never above the value).
    e = unrecorded._stb_rgbe(np.array([[[0.5, 0.25, 0.1], [0.0, 0.0, 0.0]]]))
    assert e[0, 0].tolist() == [128, 64, 25, 128] and e[0, 1].tolist() == [0, 0, 0, 0]


def test_post_processes_do_what_they_say():
    x = _image()
    np.testing.assert_array_equal(unrecorded._int_abs(np.array([-1.7, -0.5, 0.9, 1.2, 20.6])), [1, 0, 0, 1, 20])
    # The blur over the floats: each value the mean of img[i + dx + dy W], clamped at the ends.
    b = unrecorded._blur_float_offsets(x).reshape(-1)
    f = x.reshape(-1)
    w = x.shape[1]
    i = 3 * (5 * w + 7) + 1
    np.testing.assert_allclose(b[i], np.mean([f[i + dx + dy * w] for dx in (-1, 0, 1) for dy in (-1, 0, 1)]))
    np.testing.assert_allclose(b[0], np.mean([f[max(dx + dy * w, 0)] for dx in (-1, 0, 1) for dy in (-1, 0, 1)]))
    y = x.copy()
    y[3, 4] = 20.7
    np.testing.assert_allclose(unrecorded._max_int_normalised(y), y / 20)
    # The saturation matrix transposed: out_c = s x_c - (s - 1) w_c (r + g + b).
    z = np.array([[[0.5, 0.1, 0.1]]])
    np.testing.assert_allclose(unrecorded._saturation_transposed(z)[0, 0], 1.2 * z[0, 0] - 0.2 * unrecorded._LUMA * 0.7)
    np.testing.assert_allclose(z @ unrecorded._saturation_matrix().T, 1.2 * z - 0.2 * (z @ unrecorded._LUMA)[..., None])


def test_scene_edits_do_what_they_say():
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    s = load_scene()
    a = unrecorded._albedos_atoi(s)
    assert a.room.floor_albedo == (0.0,) * 3 and all(wl.albedo == (0.0,) * 3 for wl in a.room.walls)
    sph = next(o for o in unrecorded._sphere_scaled_then_moved(s).objects if o.name == "sphere")
    assert sph.radius == 1.5 and sph.center == pytest.approx((14.25, 3.0, -4.95))
    assert "tetrahedron" not in {o.name for o in cases.without("tetrahedron")(s).objects}
    assert unrecorded._FOV_GLM_DEGREES == pytest.approx(116.63, abs=0.01)
    cam = unrecorded._lookat_as_camera_to_world(s).cameras["near"]
    assert cam.forward == (0.0, -1.0, 0.0) and cam.up == (-1.0, 0.0, 0.0)
    # The stride of 3 in a 6-float vertex: positions and normals in turn.
    tris = np.asarray(fresh._surface("tetrahedron").triangles)
    st = unrecorded._strided_vertices(tris)
    np.testing.assert_allclose(st[0, 0], tris[0, 0])
    np.testing.assert_allclose(st[0, 2], tris[0, 1])
    np.testing.assert_allclose(np.linalg.norm(st[0, 1]), 1.0)
    np.testing.assert_allclose(st[1, 1], tris[0, 2])
    d = scene_dict(s, "near", 4, 4, 8)
    assert unrecorded._tetra_strided(d)["tetrahedron"].face_count() == 4
    e = unrecorded._materials_strcmp_inverted(d)
    assert e["wall_AB"].face_count() == 2 and e["sphere"]["bsdf"]["type"] == "twosided"


def test_light_samples_are_as_they_say():
    from mcrt.scene import load_scene

    lt = load_scene().light
    rng = np.random.default_rng(2)
    q = unrecorded._light_points(np.array([0.0, 1.0, -1.0]), np.array([0.0, 1.0, -1.0]))
    np.testing.assert_allclose(q, [(4.0, -1.0, 4.99), (6.0, 1.0, 4.99), (2.0, -3.0, 4.99)])
    assert lt.center == (5.0, 0.0, 4.99)
    # The light samples at the first vertex: points on a square beside the light, at its corners, the mean of two.
    seen = []

    def spy(mscene, p, n, rho, q):
        seen.append(q)
        return np.zeros((len(p), 3))

    orig = unrecorded._light_at
    unrecorded._light_at = spy
    try:
        p, n, rho = np.zeros((5000, 3)), np.tile([0.0, 0.0, 1.0], (5000, 1)), np.ones((5000, 3))
        unrecorded._light_rand_overflow(None, rng, p, n, rho, None)
        unrecorded._light_int_corners(None, rng, p, n, rho, None)
        unrecorded._light_two_averaged(None, rng, p, n, rho, None)
    finally:
        unrecorded._light_at = orig
    assert np.all((seen[0][:, 0] > 2.0) & (seen[0][:, 0] <= 4.0) & (seen[0][:, 1] > -3.0) & (seen[0][:, 1] <= -1.0))
    assert set(map(tuple, np.round(seen[1][:, :2], 9))) == {(4.0, -1.0), (4.0, 1.0), (6.0, -1.0), (6.0, 1.0)}
    assert np.all(unrecorded._light_one_over_n_int(None, rng, p, n, rho, np.ones((5, 3))) == 0.0)
    assert len(seen) == 4 and all(np.all(np.abs(s[:, :2] - [5.0, 0.0]) <= 1.0) for s in seen[2:])


def test_bounces_are_as_they_say():
    rng = np.random.default_rng(3)
    n = unsaid._unit(rng.normal(size=(20000, 3)))
    for draw, cosine in ((unrecorded._sphere_rand_plus_normal, True), (unrecorded._cosine_draw, True),
                         (unrecorded._bounce_eigen_frame, False)):
        d, w = draw(rng, n)
        cos = np.einsum("ij,ij->i", d, n)
        np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0)
        assert np.all(w == 1.0) and np.all(cos >= -1e-9)
        if cosine:  # cosine-weighted: E[cos] = 2/3, E[cos^2] = 1/2
            assert cos.mean() == pytest.approx(2 / 3, abs=0.01) and np.mean(cos ** 2) == pytest.approx(0.5, abs=0.01)
        else:  # pulled towards the normal
            assert cos.mean() > 2 / 3 + 0.02
    d, w = unrecorded._cosine_int_abs(rng, n)
    assert np.all(w == 0.0)
    d, w = unrecorded._bounce_fixed_seed(rng, n[:100])
    t, b = unforeseen._frame_of(n[:100])
    local = np.stack([np.einsum("ij,ij->i", d, t), np.einsum("ij,ij->i", d, b), np.einsum("ij,ij->i", d, n[:100])], 1)
    np.testing.assert_allclose(local, np.tile(local[0], (100, 1)), atol=1e-9)
    assert local[0, 2] == pytest.approx(math.sqrt(1 - 3499211612 / 2 ** 32))
    # The frame not normalised: t as long as the sine between n and a.
    tt, bb = unrecorded._frame_unnormalised(n[:10])
    a = np.where((np.abs(n[:10, 0]) < 0.9)[:, None], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    np.testing.assert_allclose(np.linalg.norm(tt, axis=1), np.sqrt(1 - np.einsum("ij,ij->i", n[:10], a) ** 2))


def test_mirror_and_samples_are_as_they_say():
    eye = np.array([-1.0, 0.0, 0.0])
    c, radius = unsaid._sphere()
    targets = c + radius * np.array([[-0.9, 0.3, 0.3], [-0.8, -0.5, 0.2], [-0.7, 0.1, -0.6]])
    dirs = unsaid._unit(np.vstack([targets, [[10.0, -3.0, 0.0]]]) - eye)
    o = np.tile(eye, (4, 1))
    po, r, used = unrecorded._reflect_glm_swapped(o, dirs)
    assert list(used) == [1, 1, 1, 0]
    nrm = unsaid._unit(po[:3] - c)
    want = nrm - 2 * np.einsum("ij,ij->i", dirs[:3], nrm)[:, None] * dirs[:3]
    np.testing.assert_allclose(r[:3], want, atol=1e-4)
    np.testing.assert_allclose(r[3], dirs[3])
    # Roulette that never ends a path: L2 + (L8 - L2) / max(albedo).
    full, two = unsaid._loaded(8), unsaid._loaded(2)
    pts = np.array([[10.0, 0.5, -5.0], [4.0, -6.0, 0.5], [5.0, 0.0, 4.99], [9.5, 2.0, -3.3], [5.0, 6.0, 1.0]])
    d = unsaid._unit(pts - eye)
    o = np.tile(eye, (5, 1))
    L8, L2 = unsaid._sampled(full, o, d, 7), unsaid._sampled(two, o, d, 7)
    p = unsaid._first_albedo(full, o, d).max(axis=1)
    got = unrecorded._roulette_never_sample(o, d, 7, full=full, direct=two)
    want = np.where((p > 0)[:, None], L2 + (L8 - L2) / np.where(p > 0, p, 1)[:, None], L8)
    np.testing.assert_allclose(got, want, rtol=1e-6)
    # The double sum and the reduction: each pixel its samples' mean; the race: fewer of them.
    x = np.zeros((4, 4, 3))
    L = unbidden._all_samples(4, 4, 64, 5)
    np.testing.assert_allclose(unrecorded._samples_double(x, spp=64, seed=5).reshape(16, 3), L.mean(axis=1))
    np.testing.assert_allclose(unrecorded._samples_reduction(x, spp=64, seed=5).reshape(16, 3), L.mean(axis=1),
                               rtol=1e-5, atol=1e-6)
    keep = np.random.default_rng(5 + 59).random((16, 64)) >= 0.25
    np.testing.assert_allclose(unrecorded._race_lost(x, spp=64, seed=5).reshape(16, 3),
                               (L * keep[..., None]).sum(axis=1) / 64)
    # One stream copied to 4 threads: every band the first band's samples (the same rays a row apart differ).
    y = np.zeros((8, 4, 3))
    bands = unrecorded._bands_one_stream(y, spp=4, seed=11)
    assert np.all(np.isfinite(bands)) and bands.shape == (8, 4, 3)


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    check_correct_agree(unrecorded, plain)


def test_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    lit = lum < 1

    def image(name):
        return _build(_by_name(name)).image

    # C's integer abs: the room black, the light kept.
    im = image("pp_c_abs_integer")
    assert np.all(im[lit] == 0.0) and im.max() >= 19.0
    # Albedos of 0: the room black but for the light and its reflection.
    assert image("albedos_atoi")[lit].mean() < 0.05 * plain[lit].mean()
    # No direct light at the first hit: the lit surfaces darker.
    assert image("light_samples_one_over_n_int")[lit].mean() < 0.7 * plain[lit].mean()
    # The sphere outside the room: what lies behind it seen.
    assert np.abs(image("sphere_glm_scale_then_translate") - plain).mean() > 0.02 * plain.mean()
    # Roulette that never ends a path: brighter; the race: darker; the preview left in: brighter.
    assert image("roulette_rand_int_division")[lit].mean() > 1.05 * plain[lit].mean()
    assert image("samples_omp_shared_race").mean() == pytest.approx(0.75 * plain.mean(), rel=0.08)
    assert image("passes_memset_sizeof_pointer").mean() == pytest.approx(1.25 * plain.mean(), rel=0.08)
    # No indirect light: darker, most in the shadows.
    assert image("bounce_cosine_c_abs")[lit].mean() < 0.9 * plain[lit].mean()


@pytest.mark.parametrize("name", [s.name for s in unrecorded.SPECS])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back."""
    check_builds(_by_name(name), tmp_path)
