"""The nineteenth class (mcrt.grade.accuracy.unheralded) is well formed and builds what its specs say: the same checks
as test_accuracy_unbidden's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x 16, never
graded), on this class's cases, the rays and shadow rays its Mitsuba renders trace and the samples its loops add up.
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import (H, W, build as _build, by_name, check_builds, check_held_out_rule,
                              check_not_catalogued, check_specs, image as _image, plain as _plain)
from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unbidden, unforeseen,
                                 unguessed, unheard, unheralded, unmet, unprompted, unsaid, unseen, unsought, untold,
                                 untried)
from mcrt.image_files import ImageError, read_image, srgb_eotf

_by_name = partial(by_name, unheralded.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought, unguessed, unforeseen, unprompted, unbidden)


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


def _variant():
    """Mitsuba's variant set (for mi.Bitmap, mi.load_dict and the meshes)."""
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    return scene_dict(load_scene(), "near", 4, 4, 8)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unheralded, _OTHERS, mistakes=28)
    assert len(unheralded.MISTAKES) == 28
    assert all(s.truth for s in unheralded.SPECS)
    truths = {s.truth for m in _OTHERS for s in m.SPECS}
    assert not truths & {s.truth for s in unheralded.SPECS}
    assert {len(v) for v in unheralded.CATEGORIES.values()} <= {3, 4}
    assert list(unheralded.CATEGORIES) == list(unforeseen.CATEGORIES) == list(unbidden.CATEGORIES)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unheralded)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unheralded)
    assert sum(s.held_out for s in unheralded.MISTAKES) == 12 and sum(s.held_out for s in unheralded.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    assert unheralded.NEW_CAUSES == {}
    old = set(cases.CAUSES) | set(outside.CAUSES) | {c for m in _OTHERS for c in getattr(m, "NEW_CAUSES", ())}
    assert {s.cause for s in unheralded.MISTAKES} <= old


def test_seeds_differ_from_the_other_classes():
    assert unheralded._crc("x") != unbidden._crc("x")
    assert 601000 <= unheralded._crc("pp_butterworth_lowpass") < 701000


def test_the_command_knows_the_class():
    import importlib

    from mcrt.grade.accuracy.cli import CLASSES

    assert importlib.import_module(f"mcrt.grade.accuracy.{CLASSES['unheralded']}").SPECS is unheralded.SPECS


def test_correct_writers_read_back(tmp_path):
    """The hand-written old-style RLE HDR, Mitsuba's PFM and the EXR with a sample-count channel read back as
    written."""
    import OpenEXR

    from mcrt.image_files import _rgbe_encode

    _variant()
    x = _image()
    x[2, 3:9] = 20.0  # a run of equal pixels
    for d in "abc":
        (tmp_path / d).mkdir()
    path = unheralded._write_hdr_old_rle(x, tmp_path / "a")
    rgbe = _rgbe_encode(path, x)
    m, e = rgbe[..., :3].astype(float), rgbe[..., 3:].astype(int)
    np.testing.assert_allclose(read_image(path).mean, m * np.ldexp(1.0, e - 136), rtol=1e-6)
    row = unheralded._old_rle_row(rgbe[2])
    assert bytes((1, 1, 1, 5)) in row and len(row) == 4 * (W - 5 + 1)
    np.testing.assert_array_equal(read_image(unheralded._write_pfm_mitsuba_bitmap(x, tmp_path / "b")).mean,
                                  x.astype(np.float32))
    path = unheralded._write_exr_counts(x, tmp_path / "c", spp=124)
    r = read_image(path)
    np.testing.assert_array_equal(r.mean, x.astype(np.float32))
    assert r.extra["exr.ignored_channels"] == "N"
    n = OpenEXR.File(str(path), separate_channels=True).channels()["N"].pixels
    assert n.dtype == np.uint32 and np.all(n == 124)


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    x = _image()
    for d in "abcd":
        (tmp_path / d).mkdir()
    # PQ: 0 at 0, 1 at 10000 cd/m^2 (a value of 100), 0.508 at a value of 1 (100 cd/m^2); read back as sRGB.
    assert unheralded._pq(0.0) < 1e-6 and unheralded._pq(1.0) == pytest.approx(1.0)
    assert unheralded._pq(0.01) == pytest.approx(0.508, abs=0.001)
    codes = unheralded._pq_codes(x)
    r = read_image(unheralded._write_png16_pq(x, tmp_path / "a")).mean
    np.testing.assert_allclose(r, srgb_eotf(codes / 65535.0), atol=1e-6)
    # The PPM of chr codes written as UTF-8 text: a byte more for every code of 128 or more; the reader refuses it,
    # naming the text mode (since the class was graded; before, it read slipped).
    c8 = blind._srgb8(x)
    data = (tmp_path / "b" / "render.ppm")
    unheralded._write_ppm_utf8(x, tmp_path / "b")
    head = f"P6\n{W} {H}\n255\n".encode()
    raw = data.read_bytes()
    assert raw.startswith(head) and len(raw) == len(head) + c8.size + int((c8 >= 128).sum())
    assert [ord(ch) for ch in raw[len(head):].decode("utf-8")] == c8.reshape(-1).tolist()
    with pytest.raises(ImageError, match="written as text encoded UTF-8"):
        read_image(data)
    # DWAA: lossy, close to the half floats (on a smooth image: a noisy block that packs no smaller is stored whole).
    g = np.linspace(0.05, 0.95, W)
    smooth = np.stack(np.broadcast_arrays(g[None, :], g[:, None], g[None, :] * g[:, None]), axis=2)
    r = read_image(unheralded._write_exr_dwaa(smooth, tmp_path / "c")).mean
    h16 = smooth.astype(np.float16).astype(np.float32)
    assert np.abs(r - h16).max() > 0 and np.median(np.abs(r - h16) / h16) < 0.05
    # 8-bit codes in a 16-bit PNG: each code read as code / 65535.
    r = read_image(unheralded._write_png16_8bit_codes(x, tmp_path / "d")).mean
    np.testing.assert_allclose(r, srgb_eotf(c8 / 65535.0), atol=1e-9)
    assert r.max() < 1e-3


def test_post_processes_do_what_they_say():
    x = _image()
    # The Butterworth low-pass: a flat image kept, a spike spread (its total kept), nothing negative.
    np.testing.assert_allclose(unheralded._butterworth(np.full((16, 16, 3), 0.3)), 0.3, atol=1e-9)
    spike = np.zeros((16, 16, 3))
    spike[8, 8] = 4.0
    b = unheralded._butterworth(spike)
    assert b.min() >= 0.0 and b[8, 8, 0] < 2.0 and b[7:10, 7:10, 0].sum() - b[8, 8, 0] > 1.0
    # adjust_gamma 0.8: v ** 0.8.
    np.testing.assert_allclose(unheralded._gamma_brightened(x), x ** 0.8)
    # The crosshair: the centre row and column red, the rest kept.
    c = unheralded._crosshair(x)
    assert np.all(c[H // 2] == (1.0, 0.0, 0.0)) and np.all(c[:, W // 2] == (1.0, 0.0, 0.0))
    keep = np.ones((H, W), bool)
    keep[H // 2], keep[:, W // 2] = False, False
    np.testing.assert_array_equal(c[keep], x[keep])
    # Halved and back: the same size, a flat image kept, smoother than the image.
    y = unheralded._halved_and_back(x)
    assert y.shape == x.shape
    np.testing.assert_allclose(unheralded._halved_and_back(np.full((16, 16, 3), 0.4)), 0.4, atol=1e-9)
    assert np.abs(np.diff(y, axis=1)).mean() < 0.6 * np.abs(np.diff(x, axis=1)).mean()
    # Every row the last one.
    np.testing.assert_array_equal(unheralded._rows_aliased(x), np.repeat(x[-1:], H, axis=0))


def test_scene_edits():
    from mcrt.scene import load_scene

    s = load_scene()
    d = _variant()
    import mitsuba as mi

    # Albedos over 255; one shared colour, the tetrahedron's.
    a = unheralded._albedos_over_255(s)
    np.testing.assert_allclose(a.room.floor_albedo, (0.6 / 255,) * 3)
    np.testing.assert_allclose(a.room.walls[0].albedo, np.array(s.room.walls[0].albedo) / 255)
    shared = unheralded._albedos_shared(s)
    tetra = next(o for o in s.objects if o.name == "tetrahedron")
    assert shared.room.floor_albedo == shared.room.ceiling_albedo == tetra.material.albedo
    assert {w.albedo for w in shared.room.walls} == {tetra.material.albedo}
    assert next(o for o in shared.objects if o.name == "sphere").material == \
        next(o for o in s.objects if o.name == "sphere").material
    # The ceiling wound as the floor: a one-sided diffuse facing up.
    ceiling = unheralded._ceiling_as_floor(d)["ceiling"]
    assert np.array(ceiling.face_normal(0).z)[0] > 0.0 and "TwoSided" not in str(ceiling.bsdf())
    # The tetrahedron's vertices sorted per axis; its apex at the origin.
    v = next(o for o in unheralded._tetra_sorted_per_axis(s).objects if o.name == "tetrahedron").vertices
    assert v == ((7.5, -3.8, -4.9), (8.5, -2.3, -4.9), (8.5, -2.0, -4.9), (9.5, -1.0, -2.0))
    v = next(o for o in unheralded._tetra_apex_at_origin(s).objects if o.name == "tetrahedron").vertices
    assert v[:3] == tetra.vertices[:3] and v[3] == (0.0, 0.0, 0.0)
    # atan for tan: 67.3 degrees.
    fov = unheralded._fov_atan(s).cameras["near"].fov_x_deg
    assert math.tan(math.radians(fov) / 2) == pytest.approx(math.atan(math.pi / 4))
    assert fov == pytest.approx(67.3, abs=0.05)
    # The light seen over pi: the same square, emitting 20 / pi.
    light = unheralded._light_over_pi(d)["light"]
    assert light.surface_area()[0] == pytest.approx(4.0) and light.emitter() is not None
    # Correct edits: the diagonal field of view gives 45 degrees at the image's side; the walls as rectangles load
    # with the walls' areas.
    sensor = mi.load_dict(unheralded._fov_diagonal(d)["sensor"])
    ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(0.0, 0.5), mi.Point2f(0.5))
    assert abs(float(ray.d.y[0])) == pytest.approx(float(ray.d.x[0]), rel=1e-5)
    rect = unheralded._walls_as_rectangles(d)
    for w in s.room.walls:
        name = f"wall_{w.corners[0]}{w.corners[1]}"
        assert mi.load_dict(rect[name]).surface_area()[0] == pytest.approx(d[name].surface_area()[0], rel=1e-5)
    mi.load_dict(rect)


def test_rays_offsets_and_shadow_rays_are_as_they_say():
    rng = np.random.default_rng(0)
    # Sub-pixel offsets: randint's corners only; R2's uniform on the pixel.
    u, v = unheralded._corner_offsets(rng, 4000, w=4, pixels=8)
    assert set(np.unique(u)) == set(np.unique(v)) == {0.0, 1.0} and u.mean() == pytest.approx(0.5, abs=0.02)
    u, v = unheralded._r2(rng, 512, w=4, pixels=8)
    assert u.shape == (8, 512) and np.all((0 <= u) & (u < 1)) and np.all((0 <= v) & (v < 1))
    assert np.histogram(v[0], bins=8, range=(0, 1))[0].min() > 0.8 * 512 / 8
    # The right vector reversed: the pinhole's rays mirrored about the view's vertical plane.
    fx, fy = rng.random((2, 50))
    o, d = unheralded._right_reversed(fx, fy)
    o2, d2 = unsaid._pinhole(1.0 - fx, fy)
    np.testing.assert_allclose(d, d2, atol=1e-12)
    np.testing.assert_array_equal(o, o2)
    # Points in the unit ball.
    assert np.linalg.norm(unheralded._in_ball(rng, 1000), axis=1).max() <= 1.0
    # Shadow rays from the floor beside the sphere: the sphere blocks the right one, t < 1 misses it.
    mscene = unsaid._loaded(2)
    p = np.array([[11.5, 2.0, -4.999]])
    wi = unsaid._unit(np.array([[5.0, 0.0, 4.99]]) - p)
    dist = np.linalg.norm(np.array([5.0, 0.0, 4.99]) - p, axis=1)
    assert not unheralded._visible_within(mscene, p, wi, dist, reach=np.inf)[0]
    assert unheralded._visible_within(mscene, p, wi, dist)[0]
    # A light sample on a white floor under the light, unoccluded: Le cos cos A / (pi d^2) near the exact value.
    q = np.tile([[5.0, 0.0, -5.0]], (20000, 1))
    n = np.tile([[0.0, 0.0, 1.0]], (20000, 1))
    est = unheralded._light_sample(mscene, rng, q, n, partial(unheralded._visible_within, reach=np.inf)).mean(axis=0)
    h = 4.99 + 5.0
    exact = 20.0 / math.pi * 4 * _square_form_factor(h)
    np.testing.assert_allclose(est, exact, rtol=0.02)


def _square_form_factor(h: float) -> float:
    """(1 / 4) * integral over the 2 x 2 square at height ``h`` of cos^2 / d^2 (an exact sum on a fine grid)."""
    t = (np.arange(400) + 0.5) / 400 * 2.0 - 1.0
    x, y = np.meshgrid(t, t)
    return float(np.mean(h * h / (x * x + y * y + h * h) ** 2))


def test_sample_loops_and_passes_add_up_as_they_say():
    x = np.zeros((4, 4, 3))
    L = unbidden._all_samples(4, 4, 8, 5)
    # The integer film: each add truncated.
    film = np.zeros((16, 3), np.int64)
    for k in range(8):
        film = np.floor(film + L[:, k]).astype(np.int64)
    np.testing.assert_allclose(unheralded._integer_film(x, spp=8, seed=5).reshape(16, 3), film / 8)
    # The trimmed mean, as scipy's.
    from scipy.stats import trim_mean

    np.testing.assert_allclose(unheralded._trimmed(x, spp=8, seed=5).reshape(16, 3), trim_mean(L, 0.05, axis=1))
    # The passes averaged with the empty image: 4/5 of the passes' mean.
    passes = [unseen._render(4, 4, 8, 9 + k) for k in range(4)]
    np.testing.assert_allclose(unheralded._passes_with_empty(x, passes=4, spp=8, seed=9), 0.8 * np.mean(passes, 0))


def test_first_vertex_with_the_right_shadow_ray_is_the_plain_render(plain):
    """The first vertex's light sample by hand, with the right shadow ray, agrees with Mitsuba's path: the changes
    made to it are the mistakes'."""
    right = partial(unheralded._shadowed_within, reach=np.inf)
    im = unheralded._first_vertex(np.zeros((H, W, 3)), spp=256, seed=3, direct=right)
    rel = np.abs(im - plain).mean(axis=2) / (plain.mean(axis=2) + 0.05)
    assert np.median(rel) < 0.1 and im.mean() / plain.mean() == pytest.approx(1.0, abs=0.03)


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    for name in ("ok_r2_offsets", "ok_fov_diagonal_axis", "ok_hdr_old_rle", "ok_pfm_mitsuba_bitmap",
                 "ok_mcrt_2x_box_reduced", "ok_walls_as_rectangles", "ok_film_crop_quarters", "ok_exr_sample_counts"):
        case = _build(_by_name(name))
        rel = np.abs(case.image - plain).mean(axis=2) / (plain.mean(axis=2) + 0.05)
        assert np.median(rel) < 0.15 and case.image.shape == (H, W, 3), name
        assert abs(case.image.mean() / plain.mean() - 1) < 0.1, name


def test_combined_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    seen, lit = lum > 5, lum < 1
    # The light's area halved, the BRDF's 1/pi left out of the light sample: the light on surfaces times 1/2 and pi,
    # the light seen right.
    for name, f in (("light_area_triangle_formula", 0.5), ("light_sample_brdf_without_inv_pi", math.pi)):
        im = _build(_by_name(name)).image.mean(axis=2)
        assert im[lit].mean() == pytest.approx(f * lum[lit].mean(), rel=0.1), name
        assert im[seen].mean() == pytest.approx(lum[seen].mean(), rel=0.02), name
    # The light seen over pi: its own pixels a third, the rest right.
    im = _build(_by_name("light_seen_over_pi")).image.mean(axis=2)
    assert im[seen].mean() < 0.4 * lum[seen].mean() and im[lit].mean() == pytest.approx(lum[lit].mean(), rel=0.1)
    # The albedo twice in the first light sample, the trimmed mean, the integer film: darker lit surfaces.
    for name, high in (("throughput_before_light_sample", 0.9), ("pixel_trimmed_mean", 0.99),
                       ("film_integer_buffer", 0.5)):
        im = _build(_by_name(name)).image.mean(axis=2)
        assert im[lit].mean() < high * lum[lit].mean(), name
    # Cosine samples weighted as uniform: brighter lit surfaces, the light right.
    im = _build(_by_name("bounce_cosine_as_uniform")).image.mean(axis=2)
    whole = lum > 15  # (the light's edge pixels hold some ceiling)
    assert im[lit].mean() > 1.03 * lum[lit].mean() and im[whole].mean() == pytest.approx(lum[whole].mean(), rel=0.02)
    # Shadow rays of t < 1 and the fuzzy mirror: close to the truth in the mean, not equal to it.
    for name in ("shadow_ray_t_below_one", "mirror_fuzzy_metal"):
        m = _build(_by_name(name)).image.mean() / plain.mean()
        assert 0.9 < m < 1.1, (name, m)
    # The image mirrored by the right vector reversed.
    im = _build(_by_name("camera_right_up_cross_forward")).image
    mirrored = np.abs(im - plain[:, ::-1]).mean(axis=2) / (lum[:, ::-1] + 0.05)
    assert np.median(mirrored) < 0.15 < np.median(np.abs(im - plain).mean(axis=2) / (lum + 0.05))


@pytest.mark.parametrize("name", [s.name for s in unheralded.SPECS if s.name != "file_ppm_chr_text_utf8"])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back (all but
    the PPM written as UTF-8 text, which the reader refuses, naming it: test_wrong_writers_write_what_their_specs_say)."""
    check_builds(_by_name(name), tmp_path)
