"""The sixteenth class (mcrt.grade.accuracy.unforeseen) is well formed and builds what its specs say: the same checks as
test_accuracy_unguessed's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x 16, never
graded), on this class's cases, the rays its Mitsuba renders trace and the samples its loops add up.
"""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import (H, W, build as _build, by_name, check_builds, check_held_out_rule,
                              check_not_catalogued, check_specs, image as _image, plain as _plain)
from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unforeseen, unguessed,
                                 unheard, unmet, unsaid, unseen, unsought, untold, untried)
from mcrt.image_files import read_image, srgb_eotf

_by_name = partial(by_name, unforeseen.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought, unguessed)


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


def test_specs_are_new_worded_and_in_categories():
    check_specs(unforeseen, _OTHERS, mistakes=28)
    assert all(s.truth for s in unforeseen.SPECS)
    truths = {s.truth for m in _OTHERS for s in m.SPECS}
    assert not truths & {s.truth for s in unforeseen.SPECS}
    assert {len(v) for v in unforeseen.CATEGORIES.values()} <= {3, 4}


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unforeseen)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unforeseen)
    assert sum(s.held_out for s in unforeseen.MISTAKES) == 12 and sum(s.held_out for s in unforeseen.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    assert unforeseen.NEW_CAUSES == {}
    old = set(cases.CAUSES) | set(outside.CAUSES) | {c for m in _OTHERS for c in getattr(m, "NEW_CAUSES", ())}
    assert {s.cause for s in unforeseen.MISTAKES} <= old


def test_the_command_knows_the_class():
    import importlib

    from mcrt.grade.accuracy.cli import CLASSES

    assert importlib.import_module(f"mcrt.grade.accuracy.{CLASSES['unforeseen']}").SPECS is unforeseen.SPECS


def test_correct_writers_read_back(tmp_path):
    """The ZSTD EXR, the column-major HDR and the hand-written Up-filtered PNG read back as written."""
    x = _image()
    for d in "abc":
        (tmp_path / d).mkdir()
    np.testing.assert_allclose(read_image(unforeseen._write_exr_zstd(x, tmp_path / "a")).mean, x, rtol=1e-6)
    path = unforeseen._write_hdr_columns(x, tmp_path / "b")
    assert f"+X {W} -Y {H}\n".encode() in path.read_bytes()[:80]
    from mcrt.image_files import write_hdr

    write_hdr(tmp_path / "a" / "rows.hdr", x, rle=False)  # mcrt's encoder, row by row: the same values
    np.testing.assert_array_equal(read_image(path).mean, read_image(tmp_path / "a" / "rows.hdr").mean)
    np.testing.assert_allclose(read_image(path).mean, x, atol=x.max() / 256)  # RGBE: 8 bits under the largest channel
    path = unforeseen._write_png_up_idats(x, tmp_path / "c", chunk=64)
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data.count(b"IDAT") > 1
    np.testing.assert_allclose(read_image(path).mean, srgb_eotf(blind._srgb8(x) / 255.0), atol=1e-6)


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    x = _image()
    for d in "abcd":
        (tmp_path / d).mkdir()
    # The sum buffer: 256 times the mean.
    np.testing.assert_allclose(read_image(unforeseen._write_exr_sum(x, tmp_path / "a")).mean, 256 * x, rtol=1e-6)
    # B44: half floats, lossy (not all values as the half floats written), close.
    b44 = read_image(unforeseen._write_exr_b44(x * 10, tmp_path / "b")).mean
    half = (x * 10).astype(np.float16).astype(np.float64)
    assert not np.array_equal(b44, half) and np.abs(b44 - half).mean() < 0.05 * half.mean()
    # 16-bit codes of v * 65536: white 0, the rest one code in 65536 high or so.
    y = x.copy()
    y[0, 0] = 20.0
    codes = unforeseen._codes_times_65536(y)
    assert list(codes[0, 0]) == [0, 0, 0]
    from mcrt.image_files import srgb_oetf

    exact = srgb_oetf(np.clip(y, 0.0, 1.0)) * 65535.0
    assert np.abs(codes[1:].astype(float) - exact[1:]).max() <= 1.5
    r = read_image(unforeseen._write_png16_times_65536(y, tmp_path / "c")).mean
    assert r[0, 0].max() == 0.0 and abs(r[1:].mean() / x[1:].mean() - 1) < 0.01
    # imageio's stretch: the minimum 0, the maximum 255, linear codes; as imageio itself makes them.
    s = unforeseen._imageio_stretched(y)
    assert s.min() == 0 and s.max() == 255 and s.dtype == np.uint8
    from imageio.core.util import image_as_uint

    np.testing.assert_array_equal(s, image_as_uint(y.astype(np.float32), bitdepth=8))
    np.testing.assert_allclose(read_image(unforeseen._write_png_imageio_stretched(y, tmp_path / "d")).mean,
                               srgb_eotf(s / 255.0), atol=1e-6)
    assert _by_name("manifest_spp_times_depth").declared_spp == 256 * 8


def test_post_processes_do_what_they_say():
    x = _image()
    # Chroma over 2 x 2 blocks: the luminance kept, the colour differences constant on each block.
    c = unforeseen._chroma_2x2(x)
    kept = c.min(axis=2) > 0.0  # where no channel was clipped at 0
    assert kept.mean() > 0.9 and c.min() >= 0.0
    np.testing.assert_allclose(unseen._luma(c)[kept], unseen._luma(x)[kept], atol=1e-9)
    cr = c[..., 0] - unseen._luma(c)
    both = kept[0::2, 0::2] & kept[1::2, 1::2]
    np.testing.assert_allclose(cr[0::2, 0::2][both], cr[1::2, 1::2][both], atol=1e-9)
    # The dither: at most one 8-bit step, mean nearly 0.
    dd = unforeseen._dither_linear(x, seed=1) - x
    assert np.abs(dd).max() <= 1 / 255 and abs(dd.mean()) < 1e-3
    # The Laplacian sharpening: a flat image unchanged, a peak raised by 4 times its height.
    flat = np.full((5, 5, 3), 0.3)
    np.testing.assert_allclose(unforeseen._laplacian_sharpen(flat), flat)
    peak = flat.copy()
    peak[2, 2] = 1.3
    assert unforeseen._laplacian_sharpen(peak)[2, 2, 0] == pytest.approx(0.3 + 5 * 1.0)
    # The sigmoid: 0.5 at the cutoff, 1 / (1 + e^5) at 0.
    sig = unforeseen._sigmoid(np.array([[[0.0, 0.5, 20.0]]]))
    np.testing.assert_allclose(sig[0, 0], [1 / (1 + np.exp(5)), 0.5, 1.0], atol=1e-6)


def test_scene_edits():
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    s = load_scene()
    d = scene_dict(s, "near", 4, 4, 8)  # sets Mitsuba's variant too
    import mitsuba as mi

    # Vertex colours: every corner the mean of its two walls', each vertex its corner's.
    colours = unforeseen._corner_colours(s)
    np.testing.assert_allclose(colours["B"], (np.array((0.75, 0.15, 0.15)) + (0.55, 0.15, 0.70)) / 2)
    vc = unforeseen._wall_vertex_colours("wall_AB")
    assert {tuple(np.round(v, 6)) for v in vc.reshape(-1, 3)} == {tuple(np.round(colours[k], 6)) for k in "AB"}
    walls = unforeseen._walls_vertex_coloured(d)
    assert walls["wall_CD"].has_attribute("vertex_color")
    mi.load_dict(walls)
    t = unforeseen._tetra_metallic(d)["tetrahedron"]
    assert "Principled" in str(t.bsdf())
    # The ceiling at 10, the walls with it; the light where it was.
    hi = unforeseen._ceiling_at_height(s)
    ceiling = next(sf for sf in hi.surfaces() if sf.name == "ceiling")
    assert np.all(np.asarray(ceiling.triangles)[..., 2] == 10.0) and hi.light == s.light
    # The ceiling's hole: the ceiling's area less 2.2 x 2.2, facing down, no triangle over the hole.
    tris = unforeseen._hole_tris()
    area = 0.5 * np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1)
    full = d["ceiling"].surface_area()[0]
    assert area.sum() == pytest.approx(full - 2.2 * 2.2, rel=1e-5)
    assert np.all(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])[:, 2] < 0)
    centroids = tris.mean(axis=1)
    assert not np.any((np.abs(centroids[:, 0] - 5.0) < 1.1) & (np.abs(centroids[:, 1]) < 1.1))
    assert unforeseen._ceiling_hole(d)["ceiling"].face_count() == len(tris)
    # The apex at z 2.9, the base kept.
    tv = next(o for o in unforeseen._tetra_apex_relative(s).objects if o.name == "tetrahedron").vertices
    assert tv[3] == (8.5, -2.3, 2.9) and tv[:3] == next(o for o in s.objects if o.name == "tetrahedron").vertices[:3]
    # The light's margin: 1.96 x 1.96, facing down, at the light's radiance.
    lm = unforeseen._light_margin(d)["light"]
    assert lm.surface_area()[0] == pytest.approx(1.96 ** 2, rel=1e-5) and lm.emitter() is not None
    # Correct edits: walls in four (the same area), the unnormalised camera (the same frame), the sensor matrix (the
    # look-at's), the mirror as a blend.
    four = unforeseen._walls_in_four(d)
    for w in ("wall_AB", "wall_CD"):
        assert four[w].face_count() == 4
        assert four[w].surface_area()[0] == pytest.approx(d[w].surface_area()[0], rel=1e-5)
    cam = unforeseen._unnormalised_camera(s).cameras["near"]
    assert cam.forward == (3.0, 0.0, 0.0)
    for a, b in zip(cam.frame(), s.cameras["near"].frame()):
        np.testing.assert_allclose(a, b)
    m = np.array(unforeseen._sensor_by_hand(d)["sensor"]["to_world"].matrix, np.float64)
    np.testing.assert_allclose(m, np.array(d["sensor"]["to_world"].matrix, np.float64), atol=1e-6)
    assert "BlendBSDF" in str(mi.load_dict(unforeseen._mirror_as_blend(d)["sphere"]).bsdf())


def test_rays_and_sample_loops_are_as_they_say():
    """Row strata and lattice offsets, half-circle bounces, the forward vector reflected, the bfloat16 sums."""
    rng = np.random.default_rng(0)
    u, v = unforeseen._row_strata(rng, 8, w=4, pixels=40)
    rows = np.arange(40) // 4
    assert np.all(np.floor(v * 16) == (rows % 16)[:, None]) and 0.0 <= u.min() and u.max() < 1.0
    u, v = unforeseen._lattice(rng, 64, w=4, pixels=5)
    assert u.shape == (5, 64) and np.all((0 <= u) & (u < 1)) and np.all((0 <= v) & (v < 1))
    # A lattice: each row's points, less their shift, on the grid (i / n, i g / n).
    g = unforeseen._lattice_generator(64)
    base = np.mod(v - v[:, :1], 1.0)
    np.testing.assert_allclose(np.mod(np.round(base * 64), 64), np.tile(np.arange(64) * g % 64, (5, 1)))
    # Half-circle directions: unit, above the surface, all on the frame's +b side, E[cos] = 2/3.
    n = np.tile([[0.0, 0.0, 1.0]], (100000, 1))
    dirs = unforeseen._half_circle_directions(np.random.default_rng(1), n)
    t, b = unforeseen._frame_of(n)
    np.testing.assert_allclose(np.linalg.norm(dirs, axis=1), 1.0, atol=1e-12)
    assert dirs[:, 2].min() >= 0 and np.einsum("ij,ij->i", dirs, b).min() >= -1e-12
    assert dirs[:, 2].mean() == pytest.approx(2 / 3, abs=0.005)
    # The forward vector reflected: a ray at the sphere's centre (along the view from the sphere's nearest point)
    # goes back as the ray itself would; others reflect (1, 0, 0), not their direction.
    c, r = unsaid._sphere()
    o = np.array([[-1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    d = unsaid._unit(np.array([c - o[0], c + [0.0, 0.8, 0.5] - o[0]]))
    ro, rd, hit = unforeseen._reflect_forward(o, d)
    _, rd_true, _ = unsaid._reflected(o, d)
    assert list(hit) == [1, 1]
    n2 = unsaid._unit(ro - c)
    f = np.array([1.0, 0.0, 0.0])
    np.testing.assert_allclose(rd, unsaid._unit(f - 2 * (n2 @ f)[:, None] * n2), atol=1e-6)
    assert not np.allclose(rd[1], rd_true[1], atol=1e-3)
    # bfloat16: 8 significant bits; sums of equal samples exact while representable, small samples lost on big sums.
    assert unforeseen._bfloat16(np.array([1.0 + 1 / 256]))[0] == 1.0
    assert unforeseen._bfloat16(np.array([3.0]))[0] == 3.0
    assert unforeseen._bfloat16(np.array([256.0]) + np.array([0.9]))[0] == 256.0
    x = np.zeros((4, 4, 3))
    L = np.concatenate([a for a, _, _ in unasked._samples(4, 4, 8, 5)], axis=1)
    bf = unforeseen._bfloat16_sums(x, spp=8, seed=5).reshape(16, 3)
    np.testing.assert_allclose(bf, L.mean(axis=1), rtol=0.05, atol=1e-3)
    assert not np.allclose(bf, L.mean(axis=1), rtol=1e-6)


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    for name in ("ok_lattice_offsets", "ok_walls_in_four", "ok_mcrt_unnormalised_camera", "ok_sensor_matrix_by_hand",
                 "ok_mirror_two_halves"):
        case = _build(_by_name(name))
        rel = np.abs(case.image - plain).mean(axis=2) / (plain.mean(axis=2) + 0.05)
        assert np.median(rel) < 0.15 and case.image.shape == (H, W, 3), name
        assert abs(case.image.mean() / plain.mean() - 1) < 0.1, name


def test_combined_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    seen, lit = lum > 5, lum < 1
    # The light's own pixels dimmer (by the cosine, about 0.64 for the camera), the rest right.
    cosine = _build(_by_name("light_seen_cosine_weighted")).image.mean(axis=2)
    assert cosine[seen].mean() < 0.85 * lum[seen].mean()
    assert abs(cosine[lit].mean() / lum[lit].mean() - 1) < 0.05
    # The light's samples from a smaller square: its light on surfaces a few per cent dark, the light seen right.
    margin = _build(_by_name("light_samples_margin")).image.mean(axis=2)
    assert margin[lit].mean() / lum[lit].mean() == pytest.approx(0.96, abs=0.03)
    assert margin[seen].mean() == pytest.approx(lum[seen].mean(), rel=0.02)
    # The roulette's light counted twice from 4 segments on: brighter, the light itself right.
    rr = _build(_by_name("roulette_divided_before_test")).image.mean(axis=2)
    assert rr[lit].mean() > 1.05 * lum[lit].mean()
    # Threads storing their sums: a quarter; the tiles: every tile like the top-left one.
    assert _build(_by_name("threads_store_not_add")).image.mean() / plain.mean() == pytest.approx(0.25, rel=0.1)
    tiles = _build(_by_name("tiles_origin_not_added")).image
    q = W // 4
    for r in range(4):
        for c in range(4):
            tile = tiles[r * q:(r + 1) * q, c * q:(c + 1) * q]
            assert np.abs(tile - plain[:q, :q]).mean() < 0.15 * plain[:q, :q].mean() + 0.02
    # The bfloat16 sums darker; the half-circle bounce and the uncounted mirror bounce near the truth in the mean.
    assert _build(_by_name("film_sums_bfloat16")).image.mean() < 0.98 * plain.mean()
    for name in ("bounce_azimuth_half_circle", "depth_mirror_uncounted", "mirror_reflects_forward"):
        assert abs(_build(_by_name(name)).image.mean() / plain.mean() - 1) < 0.1, name
    # The row strata: every pixel's samples in one band, the image close to the truth.
    strata = _build(_by_name("strata_row_from_pixel_row")).image
    assert np.median(np.abs(strata - plain).mean(axis=2) / (lum + 0.05)) < 0.2


@pytest.mark.parametrize("name", [s.name for s in unforeseen.SPECS])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back."""
    check_builds(_by_name(name), tmp_path)
