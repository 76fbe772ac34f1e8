"""The seventeenth class (mcrt.grade.accuracy.unprompted) is well formed and builds what its specs say: the same checks
as test_accuracy_unforeseen's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x 16, never
graded), on this class's cases, the rays its Mitsuba renders trace and the samples its loops add up.
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import (H, W, build as _build, by_name, check_builds, check_held_out_rule,
                              check_not_catalogued, check_specs, image as _image, plain as _plain)
from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unforeseen, unguessed,
                                 unheard, unmet, unprompted, unsaid, unseen, unsought, untold, untried)
from mcrt.image_files import read_image, srgb_eotf

_by_name = partial(by_name, unprompted.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought, unguessed, unforeseen)


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unprompted, _OTHERS, mistakes=28)
    assert len(unprompted.MISTAKES) == 28
    assert all(s.truth for s in unprompted.SPECS)
    truths = {s.truth for m in _OTHERS for s in m.SPECS}
    assert not truths & {s.truth for s in unprompted.SPECS}
    assert {len(v) for v in unprompted.CATEGORIES.values()} <= {3, 4}
    assert list(unprompted.CATEGORIES) == list(unforeseen.CATEGORIES)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unprompted)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unprompted)
    assert sum(s.held_out for s in unprompted.MISTAKES) == 12 and sum(s.held_out for s in unprompted.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    assert unprompted.NEW_CAUSES == {}
    old = set(cases.CAUSES) | set(outside.CAUSES) | {c for m in _OTHERS for c in getattr(m, "NEW_CAUSES", ())}
    assert {s.cause for s in unprompted.MISTAKES} <= old


def test_seeds_differ_from_the_other_classes():
    assert unprompted._crc("x") != unforeseen._crc("x")
    assert 401000 <= unprompted._crc("pp_roll_box_blur") < 501000


def test_the_command_knows_the_class():
    import importlib

    from mcrt.grade.accuracy.cli import CLASSES

    assert importlib.import_module(f"mcrt.grade.accuracy.{CLASSES['unprompted']}").SPECS is unprompted.SPECS


def test_correct_writers_read_back(tmp_path):
    """The ZIP EXR and the hand-written Paeth-filtered PNG read back as written."""
    x = _image()
    for d in "ab":
        (tmp_path / d).mkdir()
    np.testing.assert_allclose(read_image(unprompted._write_exr_zip(x, tmp_path / "a")).mean, x, rtol=1e-6)
    path = unprompted._write_png_paeth(x, tmp_path / "b")
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    np.testing.assert_allclose(read_image(path).mean, srgb_eotf(blind._srgb8(x) / 255.0), atol=1e-6)
    # Every row filtered with type 4 (Paeth): the first byte of each decompressed scanline.
    raw = unprompted._paeth_filtered(blind._srgb8(x))
    assert all(raw[k * (1 + 3 * W)] == 4 for k in range(H))
    from PIL import Image

    np.testing.assert_array_equal(np.asarray(Image.open(path)), blind._srgb8(x))


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    x = _image()
    for d in "abc":
        (tmp_path / d).mkdir()
    # The red channel's exponent: where red is the largest channel, the file is right (to RGBE's precision); where
    # a channel reaches twice the red's power of two, its mantissa wraps.
    y = x.copy()
    y[0, 0] = (0.3, 0.9, 0.2)  # green 0.9 >= 2^-1 while red's exponent is -1: 0.9 * 512 = 460.8 -> 460 - 256 = 204
    rgbe = unprompted._rgbe_red_exponent(y)
    assert list(rgbe[0, 0]) == [153, 204, 102, 127]
    r = read_image(unprompted._write_hdr_red_exponent(y, tmp_path / "a")).mean
    red_max = (y[..., 0] >= y.max(axis=2))
    np.testing.assert_allclose(r[red_max], y[red_max], atol=1 / 200)  # 8-bit mantissas of values under 1
    assert r[0, 0, 1] < 0.5 * y[0, 0, 1]
    # The little-endian word: each pixel's bytes the correct RGBE bytes reversed.
    from mcrt.image_files import _rgbe_encode

    np.testing.assert_array_equal(unprompted._rgbe_word_little_endian(x), _rgbe_encode("x.hdr", x)[..., ::-1])
    path = unprompted._write_hdr_word_little_endian(x, tmp_path / "b")
    assert path.read_bytes().startswith(b"#?RADIANCE") and read_image(path).mean.shape == (H, W, 3)
    # v ** 1 / 2.2: the linear value over 2.2 as an 8-bit code.
    codes = unprompted._gamma_precedence_codes(x)
    np.testing.assert_array_equal(codes, np.floor(x / 2.2 * 255 + 0.5).astype(np.uint8))
    r = read_image(unprompted._write_png_gamma_precedence(x, tmp_path / "c")).mean
    np.testing.assert_allclose(r, srgb_eotf(codes / 255.0), atol=1e-6)
    assert r.mean() < 0.5 * x.mean()


def test_post_processes_do_what_they_say():
    x = _image()
    # The np.roll box blur: the mean kept exactly (wrapping), a flat image unchanged, a corner's neighbour across the
    # image wrapped in.
    b = unprompted._roll_box_blur(x)
    assert b.mean() == pytest.approx(x.mean(), rel=1e-12)
    np.testing.assert_allclose(unprompted._roll_box_blur(np.full((5, 5, 3), 0.3)), 0.3)
    spike = np.zeros((6, 6, 3))
    spike[5, 5] = 9.0
    assert unprompted._roll_box_blur(spike)[0, 0, 0] == pytest.approx(1.0)
    # The luminance cap: nothing above 4 times the mean luminance, the hue of a capped pixel kept, the rest untouched.
    y = x.copy()
    y[2, 3] = (30.0, 20.0, 10.0)
    cap = unprompted._luminance_capped(y)
    lum = unseen._luma(y)
    limit = 4 * lum.mean()
    assert unseen._luma(cap).max() == pytest.approx(limit)
    np.testing.assert_allclose(cap[2, 3] / cap[2, 3, 0], y[2, 3] / y[2, 3, 0])
    np.testing.assert_array_equal(cap[lum <= limit], y[lum <= limit])
    # The cos^4 division: the corners (s = t = 15/16 at 16 pixels) brighter by (1 + s^2 + t^2)^2, the centre nearly 1.
    d = unprompted._devignetted(np.ones((H, W, 3)))
    s = 1 - 1 / W
    assert d[0, 0, 0] == pytest.approx((1 + 2 * s * s) ** 2)
    assert d[H // 2, W // 2, 0] == pytest.approx((1 + 2 * (0.5 / W * 2) ** 2) ** 2)
    # The FFT low-pass shifted: with a pass-band wide enough to keep everything, the image's quadrants swapped.
    f = unprompted._fft_lowpass_shifted(x, sigma=1e6)
    np.testing.assert_allclose(f, np.roll(np.roll(x, H // 2, axis=0), W // 2, axis=1), atol=1e-9)
    assert unprompted._fft_lowpass_shifted(x).mean() == pytest.approx(x.mean(), rel=1e-9)


def test_sample_and_tile_posts():
    x = _image()
    rows = unprompted._rows_strided(x)
    q = H // 4
    for k in range(4):
        np.testing.assert_array_equal(rows[k * q:(k + 1) * q], x[k::4])
    t = unprompted._tiles_remainder_black(np.ones((64, 64, 3)))
    assert t[:60, :60].min() == 1.0 and t[60:].max() == 0.0 and t[:, 60:].max() == 0.0
    t = unprompted._tiles_remainder_black(np.ones((H, W, 3)))
    assert t[:12, :12].min() == 1.0 and t[12:].max() == 0.0


def test_scene_edits():
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    s = load_scene()
    d = scene_dict(s, "near", 4, 4, 8)  # sets Mitsuba's variant too
    import mitsuba as mi

    # Colours reversed: wall AB blue, the tetrahedron's channels reversed, greys unchanged.
    r = unprompted._reversed_colours(s)
    assert r.room.walls[0].albedo == (0.15, 0.15, 0.75) and r.room.floor_albedo == s.room.floor_albedo
    tet = next(o for o in r.objects if o.name == "tetrahedron")
    assert tet.material.albedo == (0.10, 0.45, 0.80)
    # The walls' mean.
    m = unprompted._walls_mean(s)
    assert {w.albedo for w in m.room.walls} == {tuple(np.mean([w.albedo for w in s.room.walls], axis=0))}
    np.testing.assert_allclose(m.room.walls[0].albedo, (2.5 / 6, 2.55 / 6, 2.6 / 6))
    # The regular hexagon: A and D kept, every side 8, counter-clockwise.
    c = unprompted._regular_corners(s)
    np.testing.assert_allclose(c["A"], (-3.0, 0.0), atol=1e-12)
    np.testing.assert_allclose(c["D"], (13.0, 0.0), atol=1e-12)
    np.testing.assert_allclose(c["B"], (1.0, -4 * math.sqrt(3)), atol=1e-12)
    hexagon = unprompted._regular_hexagon(s).room.polygon()
    sides = np.linalg.norm(np.roll(hexagon, -1, axis=0) - hexagon, axis=1)
    np.testing.assert_allclose(sides, 8.0)
    area2 = np.sum(hexagon[:, 0] * np.roll(hexagon[:, 1], -1) - np.roll(hexagon[:, 0], -1) * hexagon[:, 1])
    assert area2 > 0
    # The sphere's radius squared; the tetrahedron's numbers reshaped (3, 4) and transposed.
    assert next(o for o in unprompted._sphere_radius_squared(s).objects if o.name == "sphere").radius == 2.25
    tv = next(o for o in unprompted._tetra_column_major(s).objects if o.name == "tetrahedron").vertices
    assert tv == ((7.5, -1.0, -4.9), (-2.0, -4.9, 8.5), (-4.9, 8.5, -2.3), (9.5, -3.8, -2.0))
    # The look-at's arguments swapped: looking 45 degrees up, the image's up pointing forward and down.
    cam = unprompted._look_at_swapped(s).cameras["near"]
    right, up, fwd = cam.frame()
    np.testing.assert_allclose(fwd, np.array([1.0, 0.0, 1.0]) / math.sqrt(2))
    np.testing.assert_allclose(right, (0.0, 1.0, 0.0), atol=1e-12)
    np.testing.assert_allclose(up, np.array([1.0, 0.0, -1.0]) / math.sqrt(2), atol=1e-12)
    # The disk of the light's samples: radius sqrt(2) (area 2 pi, to the fan's precision), facing down, emitting.
    tris = unprompted._disk_tris()
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    assert np.all(n[:, 2] < 0) and 0.5 * np.linalg.norm(n, axis=1).sum() == pytest.approx(2 * math.pi, rel=0.01)
    disk = unprompted._light_disk_for_samples(d)["light"]
    assert disk.emitter() is not None
    # The OBJ text: shared vertices, every triangle read back.
    wall = np.asarray(fresh._surface("wall_AB").triangles)
    text = unprompted._obj_text(wall)
    v = np.array([[float(a) for a in ln.split()[1:]] for ln in text.splitlines() if ln.startswith("v ")])
    f = np.array([[int(a) for a in ln.split()[1:]] for ln in text.splitlines() if ln.startswith("f ")])
    assert len(v) == 4 and len(f) == 2
    np.testing.assert_array_equal(v[f - 1], wall)
    obj = unprompted._from_obj(d)
    for name in ("wall_AB", "tetrahedron", "light"):
        assert obj[name].surface_area()[0] == pytest.approx(d[name].surface_area()[0], rel=1e-5)
    assert obj["light"].emitter() is not None
    # Correct edits load: the sphere instanced, the walls one mesh coloured per face (same area), uniform greys.
    scene = mi.load_dict(unprompted._sphere_instanced(d))
    assert any("Instance" in str(type(sh)) or "instance" in str(sh).lower() for sh in scene.shapes())
    walls = unprompted._walls_face_coloured(d)
    assert not any(k.startswith("wall_") for k in walls) and walls["walls"].has_attribute("face_color")
    assert walls["walls"].surface_area()[0] == pytest.approx(sum(d[k].surface_area()[0] for k in d
                                                                 if k.startswith("wall_")), rel=1e-5)
    mi.load_dict(walls)
    mi.load_dict(unprompted._greys_uniform(d))


def test_rays_and_sample_loops_are_as_they_say():
    rng = np.random.default_rng(0)
    # Squared offsets: in [0, 1), their mean a third.
    u, v = unprompted._squared_offsets(rng, 20000, w=4, pixels=3)
    assert u.shape == (3, 20000) and 0 <= u.min() and u.max() < 1
    assert u.mean() == pytest.approx(1 / 3, abs=0.01) and v.mean() == pytest.approx(1 / 3, abs=0.01)
    # Halton offsets: the shifted points, less their shift, on the Halton (2, 3) points.
    u, v = unprompted._halton(rng, 8, w=4, pixels=5)
    assert u.shape == (5, 8) and np.all((0 <= u) & (u < 1)) and np.all((0 <= v) & (v < 1))
    base = np.array([0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875, 0.0625])
    np.testing.assert_allclose(np.mod(u - u[:, :1] + 0.5, 1.0), np.tile(base, (5, 1)), atol=1e-12)
    np.testing.assert_allclose(unprompted._radical_inverse(np.arange(1, 4), 3), [1 / 3, 2 / 3, 1 / 9])
    # Cosine-weighted directions: unit, above the surface, E[cos] = 2/3; the cosine twice weighs them by it; the
    # radius without its sqrt: E[cos] = pi / 4 (more directions near the normal), weight 1.
    n = np.tile([[0.0, 0.0, 1.0]], (200000, 1))
    dirs, w2 = unprompted._cosine_twice(np.random.default_rng(1), n)
    np.testing.assert_allclose(np.linalg.norm(dirs, axis=1), 1.0, atol=1e-12)
    assert dirs[:, 2].min() >= 0 and dirs[:, 2].mean() == pytest.approx(2 / 3, abs=0.005)
    np.testing.assert_allclose(w2, dirs[:, 2], atol=1e-12)
    dirs, w1 = unprompted._radius_without_sqrt(np.random.default_rng(2), n)
    np.testing.assert_allclose(np.linalg.norm(dirs, axis=1), 1.0, atol=1e-12)
    assert dirs[:, 2].mean() == pytest.approx(math.pi / 4, abs=0.005) and np.all(w1 == 1.0)
    # The mirror's ray from the eye: the reflection's direction, the camera ray's origin.
    c, r = unsaid._sphere()
    o = np.array([[-1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    d = unsaid._unit(np.array([c - o[0], c + [0.0, 0.8, 0.5] - o[0], [1.0, -1.0, 0.0]]))
    ro, rd, hit = unprompted._reflect_from_eye(o, d)
    p, rd_true, hit_true = unsaid._reflected(o, d)
    assert list(hit) == [1, 1, 0] and list(hit_true) == [1, 1, 0]
    np.testing.assert_array_equal(ro, o)
    np.testing.assert_allclose(rd, rd_true)
    assert not np.allclose(p[:2], o[:2])
    # The luminance clamp, sample by sample: no sample's luminance over 10 (so no pixel's), the dark ones kept.
    x = np.zeros((4, 4, 3))
    L = np.concatenate([a for a, _, _ in unasked._samples(4, 4, 8, 5)], axis=1)
    cl = unprompted._luminance_clamped_samples(x, spp=8, seed=5).reshape(16, 3)
    y = L @ programs._LUMA
    expected = (L * np.where(y > 10, 10 / np.maximum(y, 1e-300), 1.0)[..., None]).mean(axis=1)
    np.testing.assert_allclose(cl, expected, rtol=1e-9, atol=1e-12)
    assert (cl @ programs._LUMA).max() <= 10 + 1e-9


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    for name in ("ok_halton_offsets", "ok_meshes_from_obj", "ok_mcrt_light_halves", "ok_sphere_instanced",
                 "ok_walls_face_colours", "ok_greys_uniform", "ok_exr_zip", "ok_png_paeth_filter"):
        case = _build(_by_name(name))
        rel = np.abs(case.image - plain).mean(axis=2) / (plain.mean(axis=2) + 0.05)
        assert np.median(rel) < 0.15 and case.image.shape == (H, W, 3), name
        assert abs(case.image.mean() / plain.mean() - 1) < 0.1, name


def test_combined_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    seen, lit = lum > 5, lum < 1
    # The light's samples over pi: its light on surfaces about 1/pi (the indirect with it), the light seen right.
    over_pi = _build(_by_name("light_sample_radiance_over_pi")).image.mean(axis=2)
    assert over_pi[lit].mean() / lum[lit].mean() == pytest.approx(1 / math.pi, abs=0.05)
    assert over_pi[seen].mean() == pytest.approx(lum[seen].mean(), rel=0.02)
    # The disk's samples: more light on surfaces (about 2 pi / 4 the direct), the light seen right.
    disk = _build(_by_name("light_sampled_circumscribed_disk")).image.mean(axis=2)
    assert disk[lit].mean() > 1.2 * lum[lit].mean()
    assert disk[seen].mean() == pytest.approx(lum[seen].mean(), rel=0.02)
    # The roulette before the light sample: darker lit surfaces, the light itself right.
    rr = _build(_by_name("roulette_before_light_sample")).image.mean(axis=2)
    assert rr[lit].mean() < 0.97 * lum[lit].mean() and rr[seen].mean() == pytest.approx(lum[seen].mean(), rel=0.02)
    # The pixel's sum in the bounce loop: the light itself 8 times, the lit surfaces several times.
    loop = _build(_by_name("pixel_sum_in_bounce_loop")).image.mean(axis=2)
    assert loop[seen].mean() == pytest.approx(8 * lum[seen].mean(), rel=0.02)
    assert loop[lit].mean() > 4 * lum[lit].mean()
    # The luminance clamp: no pixel over 10, the pixels wholly on the light at 10.
    clamped = _build(_by_name("samples_luminance_clamped_10")).image @ programs._LUMA
    assert clamped.max() <= 10.0 + 1e-3 and clamped[seen].max() > 9.5
    # The variance buffer: 0 on the pixels wholly on the light, large on its edges' pixels, not the mean.
    var = _build(_by_name("file_exr_variance_buffer")).image.mean(axis=2)
    whole = lum > 19.9
    assert whole.any() and var[whole].max() < 1e-3 and var[seen & ~whole].mean() > lum[seen & ~whole].mean()
    # The first-bounce mistakes and the mirror's ray from the eye: near the truth in the mean, not equal to it.
    for name, low, high in (("bounce_cosine_twice", 0.75, 1.0), ("bounce_disk_radius_without_sqrt", 0.85, 1.15),
                            ("mirror_ray_from_eye", 0.85, 1.15)):
        m = _build(_by_name(name)).image.mean() / plain.mean()
        assert low < m < high, (name, m)
    cos2 = _build(_by_name("bounce_cosine_twice")).image.mean(axis=2)
    assert cos2[lit].mean() < 0.97 * lum[lit].mean()
    # The squared offsets: close to the truth at the pixel level.
    sq = _build(_by_name("jitter_squared")).image
    assert np.median(np.abs(sq - plain).mean(axis=2) / (lum + 0.05)) < 0.25


@pytest.mark.parametrize("name", [s.name for s in unprompted.SPECS])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back."""
    check_builds(_by_name(name), tmp_path)
