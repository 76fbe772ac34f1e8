"""The twenty-fourth class (mcrt.grade.accuracy.unremarked) is well formed and builds what its specs say: the same
checks as test_accuracy_unlooked's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x 16,
never graded), on this class's cases, the offsets, light samples, mirror, bounces and sample loops its Mitsuba
renders are made of.
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
from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unbeknown, unbidden,
                                 unforeseen, unguessed, unheard, unheralded, unlooked, unmet, unprompted, unremarked,
                                 unsaid, unseen, unsought, untold, untried, unvisited, unwonted)
from mcrt.image_files import read_image, srgb_eotf

_by_name = partial(by_name, unremarked.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought, unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted)


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unremarked, _OTHERS, mistakes=28)
    check_new_truths(unremarked, _OTHERS)
    assert len(unremarked.MISTAKES) == 28 and {len(v) for v in unremarked.CATEGORIES.values()} <= {3, 4}
    assert list(unremarked.CATEGORIES) == list(unvisited.CATEGORIES) == list(unlooked.CATEGORIES)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unremarked)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unremarked)
    assert sum(s.held_out for s in unremarked.MISTAKES) == 12 and sum(s.held_out for s in unremarked.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    check_old_causes(unremarked, _OTHERS)
    assert unremarked._EARLIER[-1] is unlooked


def test_seeds_differ_from_the_other_classes():
    check_seeds(unremarked, _OTHERS, 1101000)


def test_the_command_knows_the_class():
    check_command(unremarked, "unremarked")


def test_correct_writers_read_back(tmp_path):
    """The tRNS PNG and the BITMAPV4HEADER BMP read back as their 8-bit codes; scikit-image's PNG as the same codes
    (within one)."""
    x = _image()
    c8 = blind._srgb8(x)
    for writer, d in ((unremarked._write_png_trns, "a"), (unremarked._write_bmp_v4, "b")):
        (tmp_path / d).mkdir()
        path = writer(x, tmp_path / d)
        np.testing.assert_array_equal(pillow_codes(path), c8)
        np.testing.assert_allclose(read_image(path).mean, srgb_eotf(c8 / 255.0), atol=1e-6)
    assert unremarked._bmp_v4_bytes(c8)[14:18] == (108).to_bytes(4, "little")
    (tmp_path / "c").mkdir()
    codes = pillow_codes(unremarked._write_png_skimage_xyz(x, tmp_path / "c")).astype(int)
    assert np.abs(codes - c8).max() <= 1
    np.testing.assert_array_equal(unremarked._skimage_codes(np.array([[[0.0, 1.0, 2.0]]]))[0, 0], [0, 255, 255])


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    x = _image()
    for d in "abcde":
        (tmp_path / d).mkdir()
    c8 = blind._srgb8(x)
    # uint8 brightness: every code 40 up, modulo 256.
    codes = pillow_codes(unremarked._write_png_brightened(x, tmp_path / "a")).astype(int)
    np.testing.assert_array_equal(codes, (c8.astype(int) + 40) % 256)
    assert (codes < 40).any()
    # Taichi's imwrite: the image turned 90 degrees counter-clockwise.
    np.testing.assert_array_equal(pillow_codes(unremarked._write_png_taichi(x, tmp_path / "b")), np.rot90(c8))
    # The swap through views: (B, G, B).
    codes = pillow_codes(unremarked._write_png_view_swapped(x, tmp_path / "c"))
    np.testing.assert_array_equal(codes, np.stack([c8[..., 2], c8[..., 1], c8[..., 2]], axis=2))
    # interp1d past its table: channels over 1 written 0, the rest the sRGB codes (within one).
    y = x.copy()
    y[0, 0] = (20.0, 0.5, 1.2)
    codes = pillow_codes(unremarked._write_png_interp1d_nan(y, tmp_path / "d")).astype(int)
    np.testing.assert_array_equal(codes[0, 0, [0, 2]], [0, 0])
    assert abs(codes[0, 0, 1] - blind._srgb8(np.full((1, 1, 3), 0.5))[0, 0, 0]) <= 1
    assert np.abs(codes[1:] - c8[1:].astype(int)).max() <= 1
    # 16-bit bands converted to L: the 16-bit codes clipped at 255.
    codes = pillow_codes(unremarked._write_png16_bands_to_l(y, tmp_path / "e"))
    np.testing.assert_array_equal(codes, np.minimum(unremarked._codes16(y), 255))
    assert codes.min() == 255 and unremarked._codes16(np.full((1, 1, 3), 1e-5)).max() < 255


def test_post_processes_do_what_they_say():
    x = _image()
    # The preview view: a quarter of the pixels tone-mapped in place.
    t = unremarked._preview_tonemapped_in_place(x)
    np.testing.assert_allclose(t[::2, ::2], x[::2, ::2] / (1 + x[::2, ::2]))
    np.testing.assert_allclose(t[1::2], x[1::2])
    np.testing.assert_allclose(t[::2, 1::2], x[::2, 1::2])
    # The box blur in place: the first pixel its block's mean, the next ones from blurred neighbours, the border kept.
    b = unremarked._box_blur_in_place(x)
    np.testing.assert_allclose(b[1, 1], x[0:3, 0:3].mean(axis=(0, 1)))
    ref = x[1:3, 1:4].copy()
    ref[0, 0] = b[1, 1]
    np.testing.assert_allclose(b[1, 2], np.concatenate([x[0:1, 1:4], ref]).mean(axis=(0, 1)))
    assert not np.allclose(b[2, 2], x[1:4, 1:4].mean(axis=(0, 1)))
    np.testing.assert_allclose(b[0], x[0])
    np.testing.assert_allclose(b[:, -1], x[:, -1])
    # The white balance: the patch at row W / 2, column H / 4 made grey (the one at row H / 4, column W / 2 when not
    # swapped).
    h, w = x.shape[:2]
    for swapped, (r, c) in ((True, (w // 2, h // 4)), (False, (h // 4, w // 2))):
        wb = unremarked._white_balance_patch(x, swapped=swapped)
        patch = wb[r - 1:r + 2, c - 1:c + 2].reshape(-1, 3).mean(axis=0)
        np.testing.assert_allclose(patch, patch.mean())
    # Shuffled pixels: the same pixels elsewhere.
    s = unremarked._pixels_shuffled(x, seed=4).reshape(-1, 3)
    np.testing.assert_allclose(np.sort(s, axis=0), np.sort(x.reshape(-1, 3), axis=0))
    assert (np.abs(s - x.reshape(-1, 3)).max(axis=1) > 0).mean() > 0.9


def test_scene_edits_do_what_they_say():
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    s = load_scene()
    sig = unremarked._colours_through_sigmoid(s)
    assert sig.room.floor_albedo == pytest.approx((1 / (1 + math.exp(-0.6)),) * 3)
    walls = {"".join(wl.corners): wl.albedo for wl in sig.room.walls}
    assert walls["AB"] == pytest.approx((0.6792, 0.5374, 0.5374), abs=1e-4)
    mirror = next(o for o in sig.objects if o.name == "sphere").material
    assert mirror.reflectance == pytest.approx((0.7311,) * 3, abs=1e-4)
    grey = unremarked._defaults_merged_last(s)
    assert {grey.room.floor_albedo, grey.room.ceiling_albedo, *(wl.albedo for wl in grey.room.walls)} == {
        (0.5, 0.5, 0.5)}
    assert next(o for o in grey.objects if o.name == "tetrahedron").material.albedo == (0.5, 0.5, 0.5)
    assert cases.light(radiance=unremarked._FROZEN_RADIANCE)(s).light.radiance == (1.0, 1.0, 1.0)
    assert cases.fov(unremarked._FOV_LAST_CAMERA)(s).cameras["near"].fov_x_deg == pytest.approx(
        s.cameras["far"].fov_x_deg)
    # The wedges: each face's first vertex kept, its edges 60 times as long (u + v <= 1 never tested).
    tris = np.asarray(fresh._surface("tetrahedron").triangles)
    wedge = unremarked._wedge_triangles(tris)
    np.testing.assert_allclose(wedge[:, 0], tris[:, 0])
    np.testing.assert_allclose(wedge[:, 1] - wedge[:, 0], 60 * (tris[:, 1] - tris[:, 0]))
    # np.roll without axis: the corners' 12 numbers rolled.
    np.testing.assert_allclose(unremarked._rolled_next_corners(),
                               [(0, 0), (-6, 10), (-6, 13), (0, 10), (6, 0), (6, -3)])
    quads = unremarked._wall_quads_rolled()
    assert sorted(quads) == sorted(f"wall_{''.join(wl.corners)}" for wl in s.room.walls)
    np.testing.assert_allclose(quads["wall_AB"][0], [(-3, 0, -5), (0, 0, -5), (0, 0, 5)])
    # A quad's index list: the floor A B C, A C D wound up, the ceiling down, the half y > 0 missing.
    floor, ceiling = unremarked._quad_indexed("floor"), unremarked._quad_indexed("ceiling")
    assert floor.shape == (2, 3, 3) and np.all(floor[..., 2] == -5.0) and np.all(ceiling[..., 2] == 5.0)
    assert np.all(np.cross(floor[:, 1] - floor[:, 0], floor[:, 2] - floor[:, 0])[:, 2] > 0)
    assert np.all(np.cross(ceiling[:, 1] - ceiling[:, 0], ceiling[:, 2] - ceiling[:, 0])[:, 2] < 0)
    assert np.all(floor[..., 1] <= 0.0)
    d = scene_dict(s, "near", 4, 4, 8)
    assert unremarked._floor_ceiling_quad_indexed(d)["floor"].face_count() == 2
    assert unremarked._tetra_wedges(d)["tetrahedron"].face_count() == 4
    assert unremarked._walls_rolled(d)["wall_CD"].face_count() == 2
    assert unremarked._light_d65(d)["light"].face_count() == 2
    assert unremarked._flat_normal_map(d)["floor"].face_count() == 4


def test_camera_offsets_and_fields_of_view_are_as_they_say():
    # The batch normalisation: each world coordinate over its norm across the rays, the plane sqrt(3) times wider.
    assert unremarked._FOV_BATCH_NORM == pytest.approx(120.0)
    rng = np.random.default_rng(1)
    s, t = rng.random((2, 64 * 64)) * 2 - 1
    dirs = np.stack([np.ones_like(s), -s, t], axis=1)
    normed = dirs / np.linalg.norm(dirs, axis=0)
    np.testing.assert_allclose(-normed[:, 1] / normed[:, 0], math.sqrt(3) * s, rtol=0.02)
    # Sorted pairs: u <= v, each uniform pair's order statistics.
    u, v = unremarked._pairs_sorted(rng, 64, w=4, pixels=5)
    assert u.shape == (5, 64) and np.all(u <= v) and np.all((0 <= u) & (v < 1))
    assert u.mean() == pytest.approx(1 / 3, abs=0.05) and v.mean() == pytest.approx(2 / 3, abs=0.05)
    # The Sobol set of 2^m points shifted in each pixel, and one Sobol sequence run on: each pixel's 16 points one in
    # each cell of 4 x 4.
    u, v = unremarked._sobol_base2(rng, 16, w=4, pixels=3)
    assert u.shape == (3, 16) and np.all((0 <= u) & (u < 1))
    from scipy.stats import qmc

    pts = qmc.Sobol(2, scramble=True, rng=np.random.default_rng(2)).random(4 * 16).reshape(4, 16, 2)
    used = [0]
    for _ in range(2):
        u, v = unremarked._sobol_run_on(rng, 8, w=2, pixels=4, points=pts, used=used)
    assert used == [16] and u.shape == (4, 8)
    np.testing.assert_array_equal(u, pts[:, 8:16, 0])
    cells = np.floor(pts[..., 0] * 4) * 4 + np.floor(pts[..., 1] * 4)
    assert all(len(set(c)) == 16 for c in cells)


def test_light_samples_are_as_they_say():
    from scipy.stats import uniform

    rng = np.random.default_rng(2)
    q = unremarked._scipy_uniform_points(rng, 4000)
    assert uniform(4.0, 6.0).support() == (4.0, 10.0) and uniform(-1.0, 1.0).support() == (-1.0, 0.0)
    assert q[:, 0].min() >= 4.0 and q[:, 0].max() <= 10.0 and q[:, 0].max() > 9.9
    assert q[:, 1].min() >= -1.0 and q[:, 1].max() <= 0.0 and np.all(q[:, 2] == 4.99)
    wall = np.tile([[5.0, -5.999, 3.0]], (4, 1))
    inward = np.tile([[0.0, 1.0, 0.0]], (4, 1))
    mscene = unsaid._loaded(2)
    got = unremarked._light_from_scipy_uniform(mscene, np.random.default_rng(5), wall, inward, np.ones((4, 3)), None)
    qq = unremarked._scipy_uniform_points(np.random.default_rng(5), 4)
    g = np.where(unbeknown._unblocked(mscene, wall, qq), unbeknown._geometry(wall, inward, qq), 0.0)
    np.testing.assert_allclose(got, (g * 4.0 / math.pi * 20.0)[:, None] * np.ones(3))
    m = np.arange(12.0).reshape(4, 3)
    np.testing.assert_allclose(unremarked._batch_mean_light(None, None, None, None, None, m),
                               np.tile(m.mean(axis=0), (4, 1)))


def test_bounces_are_as_they_say():
    rng = np.random.default_rng(3)
    n = unsaid._unit(rng.normal(size=(4000, 3)))
    d, w = unremarked._sqrt_out_aliased(rng, n)
    cos = np.einsum("ij,ij->i", d, n)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0)
    assert np.all(w == 1.0) and np.all(cos <= math.sqrt(0.5) + 1e-12) and np.all(cos > 0.0)
    d, w = unremarked._sphere_plus_normal(rng, n)
    cos = np.einsum("ij,ij->i", d, n)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0)
    assert np.all(cos >= -1e-12) and cos.mean() == pytest.approx(2 / 3, abs=0.02)  # cosine-weighted: E[cos] = 2/3
    assert np.mean(cos ** 2) == pytest.approx(0.5, abs=0.02)


def test_mirror_and_samples_are_as_they_say():
    eye = np.array([-1.0, 0.0, 0.0])
    c, radius = unsaid._sphere()
    targets = c + radius * np.array([[-0.9, 0.3, 0.3], [-0.8, -0.5, 0.2], [-0.7, 0.1, -0.6]])
    dirs = unsaid._unit(np.vstack([targets, [[10.0, -3.0, 0.0]]]) - eye)
    o = np.tile(eye, (4, 1))
    po, r, used = unremarked._reflect_batch_sum(o, dirs)
    assert list(used) == [1, 1, 1, 0]
    nrm = unsaid._unit(po[:3] - c)
    assert np.all(np.einsum("ij,ij->i", r[:3], nrm) > 0.95)
    np.testing.assert_allclose(r[3], dirs[3])
    # Same-seed samples: the albedo's mean for the bounce, the compaction, roulette by the survivors' mean.
    full, two, one = unsaid._loaded(8), unsaid._loaded(2), unsaid._loaded(1)
    pts = np.array([[10.0, 0.5, -5.0], [4.0, -6.0, 0.5], [5.0, 0.0, 4.99], [9.5, 2.0, -3.3], [5.0, 6.0, 1.0]])
    d = unsaid._unit(pts - eye)
    o = np.tile(eye, (5, 1))
    L8, L2 = unsaid._sampled(full, o, d, 7), unsaid._sampled(two, o, d, 7)
    rho = unsaid._first_albedo(full, o, d)
    got = unremarked._albedo_mean_sample(o, d, 7, full=full, direct=two)
    np.testing.assert_allclose(got[[0, 1, 4]], (L2 + (L8 - L2) * rho.mean(axis=1, keepdims=True)
                                                / np.where(rho > 0, rho, 1))[[0, 1, 4]], rtol=1e-6)
    np.testing.assert_allclose(got[2:4], L8[2:4])
    got = unremarked._compacted_sample(o, d, 7, full=full, direct=two, seen=one)
    rest = (L8 - L2)[[0, 1, 3, 4]]  # the third ray meets the light
    np.testing.assert_allclose(got[:4], L2[:4] + rest, rtol=1e-6)
    np.testing.assert_allclose(got[4], L2[4])
    got = unremarked._survivors_mean_sample(o, d, 7, full=full, direct=two)
    p = rho.max(axis=1)
    alive = (p > 0) & (np.random.default_rng(7 + 31).random(5) < p)
    if alive.any():
        want = np.where((p > 0)[:, None], L2 + (L8 - L2) * (alive / p[alive].mean())[:, None], L8)
        np.testing.assert_allclose(got, want, rtol=1e-6)
    # Sample loops: the mode (the smallest of distinct samples), np.add.at, griddata.
    x = np.zeros((4, 4, 3))
    L = unbidden._all_samples(4, 4, 64, 5)
    m = unremarked._pixel_mode(x, spp=64, seed=5).reshape(16, 3)
    distinct = np.array([[len(np.unique(L[k, :, c])) == 64 for c in range(3)] for k in range(16)])
    np.testing.assert_allclose(m[distinct], L.min(axis=1)[distinct])
    np.testing.assert_allclose(unremarked._samples_added_at(x, spp=64, seed=5).reshape(16, 3), L.mean(axis=1))
    g = unremarked._griddata_centres(np.zeros((8, 8, 3)), spp=64, seed=5)
    assert g.shape == (8, 8, 3) and np.all(np.isfinite(g))


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    check_correct_agree(unremarked, plain)


def test_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    seen, lit = lum > 5, lum < 1

    def image(name):
        return _build(_by_name(name)).image

    # The light 20 times too dark.
    im = image("light_radiance_numba_frozen").mean(axis=2)
    assert im.mean() == pytest.approx(lum.mean() / 20, rel=0.1)
    # Grey surfaces, washed-out colours.
    im = image("materials_defaults_merged_last")
    assert np.abs(im[lit] - im[lit].mean(axis=1, keepdims=True)).mean() < 0.2 * np.abs(
        plain[lit] - plain[lit].mean(axis=1, keepdims=True)).mean()
    im = image("colours_through_sigmoid")
    assert im[lit].mean() > 1.2 * plain[lit].mean()
    # The mode: lit surfaces darker, the light kept.
    im = image("pixel_scipy_mode").mean(axis=2)
    assert np.median(im[lit]) < 0.7 * np.median(lum[lit]) and np.all(im[seen] > 19.0)
    # Half the floor and the ceiling missing: the void black.
    assert (image("floor_ceiling_quad_indices").max(axis=2) <= 0.0).sum() > 10
    # The same direct light everywhere: no dark corner left.
    im = image("light_samples_mean_over_batch").mean(axis=2)
    assert im[lit].min() > 2 * lum[lit].min()


@pytest.mark.parametrize("name", [s.name for s in unremarked.SPECS])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back."""
    check_builds(_by_name(name), tmp_path)
