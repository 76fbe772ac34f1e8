"""The twentieth class (mcrt.grade.accuracy.unbeknown) is well formed and builds what its specs say: the same checks
as test_accuracy_unheralded's (specs, writers read back, post-processes, scene edits, hand-ins built at 16 x 16, never
graded), on this class's cases, the rays, light samples and sample loops its Mitsuba renders are made of.
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np
import pytest

import mcrt  # noqa: F401  (before mitsuba and drjit)
from accuracy_helpers import (H, W, build as _build, by_name, check_builds, check_held_out_rule,
                              check_not_catalogued, check_specs, image as _image, plain as _plain)
from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unbeknown, unbidden,
                                 unforeseen, unguessed, unheard, unheralded, unmet, unprompted, unsaid, unseen,
                                 unsought, untold, untried)
from mcrt.image_files import read_image, srgb_eotf, srgb_oetf

_by_name = partial(by_name, unbeknown.SPECS)
_OTHERS = (cases, outside, programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked,
           unsought, unguessed, unforeseen, unprompted, unbidden, unheralded)


@pytest.fixture(scope="module")
def plain():
    """A correct Mitsuba render at W x H, 1024 spp (shared by the comparisons)."""
    return _plain(W, 1024)


def _variant():
    """Mitsuba's variant set (for mi.load_dict and the meshes), and the scene's dict."""
    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    return scene_dict(load_scene(), "near", 4, 4, 8)


def _codes(path) -> np.ndarray:
    """The 8-bit codes of a PNG as Pillow decodes them."""
    from PIL import Image

    return np.asarray(Image.open(path).convert("RGB"))


def test_specs_are_new_worded_and_in_categories():
    check_specs(unbeknown, _OTHERS, mistakes=28)
    assert len(unbeknown.MISTAKES) == 28
    assert all(s.truth for s in unbeknown.SPECS)
    truths = {s.truth for m in _OTHERS for s in m.SPECS}
    assert not truths & {s.truth for s in unbeknown.SPECS}
    assert {len(v) for v in unbeknown.CATEGORIES.values()} <= {3, 4}
    assert list(unbeknown.CATEGORIES) == list(unheralded.CATEGORIES)


def test_no_mistake_is_a_catalogued_bug_by_name():
    check_not_catalogued(unbeknown)


def test_held_out_half_follows_the_rule_in_every_category():
    check_held_out_rule(unbeknown)
    assert sum(s.held_out for s in unbeknown.MISTAKES) == 12 and sum(s.held_out for s in unbeknown.CORRECT) == 4


def test_every_cause_is_an_old_one_with_its_equivalences_fixed():
    """No new cause: every mistake's cause is a word of the other classes, so SAME_MISTAKE needed no new entry."""
    assert unbeknown.NEW_CAUSES == {}
    old = set(cases.CAUSES) | set(outside.CAUSES) | {c for m in _OTHERS for c in getattr(m, "NEW_CAUSES", ())}
    assert {s.cause for s in unbeknown.MISTAKES} <= old
    assert unbeknown._EARLIER[-1] is unheralded


def test_seeds_differ_from_the_other_classes():
    names = [s.name for s in unbeknown.SPECS]
    assert all(701000 <= unbeknown._crc(n) < 801000 for n in names)
    for m in _OTHERS:
        if hasattr(m, "_crc"):
            assert not any(701000 <= m._crc(n) < 801000 for n in names), m.__name__


def test_the_command_knows_the_class():
    import importlib

    from mcrt.grade.accuracy.cli import CLASSES

    assert importlib.import_module(f"mcrt.grade.accuracy.{CLASSES['unbeknown']}").SPECS is unbeknown.SPECS


def test_correct_writers_read_back(tmp_path):
    """The PNG with a filter chosen per row reads back as its codes (and chose more than one filter); the PNG through a
    12-bit table is within a code of the exact encoding."""
    x = _image()
    x[:, : W // 2] = np.linspace(0.05, 0.9, W // 2)[None, :, None]  # smooth rows beside noisy ones
    for d in "ab":
        (tmp_path / d).mkdir()
    path = unbeknown._write_png_adaptive(x, tmp_path / "a")
    c8 = blind._srgb8(x)
    np.testing.assert_array_equal(_codes(path), c8)
    np.testing.assert_allclose(read_image(path).mean, srgb_eotf(c8 / 255.0), atol=1e-6)
    rows = np.frombuffer(unbeknown._adaptive_filtered(c8), np.uint8).reshape(H, -1)
    assert len(set(rows[:, 0].tolist())) > 1 and set(rows[:, 0].tolist()) <= {0, 1, 2, 3, 4}
    codes = _codes(unbeknown._write_png_lut12(x, tmp_path / "b"))
    assert np.abs(codes.astype(int) - c8.astype(int)).max() <= 1


def _decoded_sub(codes: np.ndarray) -> np.ndarray:
    """What a PNG decoder makes of :func:`unbeknown._sub_one_byte`'s rows: each byte plus the decoded byte 3 before."""
    rows = codes.astype(np.int64).reshape(codes.shape[0], -1)
    f = (rows - np.pad(rows[:, :-1], ((0, 0), (1, 0)))) % 256
    out = np.zeros_like(f)
    for k in range(f.shape[1]):
        out[:, k] = (f[:, k] + (out[:, k - 3] if k >= 3 else 0)) % 256
    return out.reshape(codes.shape)


def test_wrong_writers_write_what_their_specs_say(tmp_path):
    x = _image()
    x[0, 0] = 20.0  # a pixel of the light
    for d in "abcd":
        (tmp_path / d).mkdir()
    # cv2.imwrite of float sRGB values: codes rounded unscaled, 0 or 1.
    codes = _codes(unbeknown._write_png_cv2_float(x, tmp_path / "a"))
    srgb = srgb_oetf(np.clip(x, 0.0, 1.0))
    assert set(np.unique(codes)) <= {0, 1}
    np.testing.assert_array_equal(codes, np.rint(srgb))
    # The Sub filter one byte back: the decoder's reading, not the codes written (their first samples kept).
    c8 = blind._srgb8(x)
    decoded = _codes(unbeknown._write_png_sub_one_byte(x, tmp_path / "b"))
    np.testing.assert_array_equal(decoded, _decoded_sub(c8))
    np.testing.assert_array_equal(decoded[:, 0, 0], c8[:, 0, 0])
    assert np.mean(decoded != c8) > 0.5
    # RGBE mantissas scaled by 255: 255/256 of each value, within half a step of the largest channel's.
    r = read_image(unbeknown._write_hdr_mantissa_255(x, tmp_path / "c")).mean
    step = np.ldexp(1.0, np.frexp(x.max(axis=2))[1] - 8)[..., None]
    assert np.all(np.abs(r - x * 255.0 / 256.0) <= 0.5 * step + 1e-6)
    assert r[0, 0, 0] == pytest.approx(19.875) and (r / x)[1:].mean() == pytest.approx(255 / 256, abs=3e-3)
    # Codes cast to a signed byte, the negatives clipped: every code of 128 or more 0, the rest kept.
    codes = _codes(unbeknown._write_png_signed_bytes(x, tmp_path / "d"))
    np.testing.assert_array_equal(codes, np.where(c8 >= 128, 0, c8))
    assert codes[0, 0, 0] == 0 and 0 < np.mean(c8 >= 128) < 1


def test_post_processes_do_what_they_say():
    x = _image()
    # Open Image Denoise: the noise smoothed, the mean kept, nothing negative.
    d = unbeknown._oidn(x)
    assert d.shape == x.shape and d.min() >= 0.0
    assert np.abs(np.diff(d, axis=1)).mean() < 0.5 * np.abs(np.diff(x, axis=1)).mean()
    assert d.mean() == pytest.approx(x.mean(), rel=0.05)
    # Teal and orange: a mid-grey kept, the dark tinted blue, the bright orange.
    for v, tint in ((0.2, (0.94, 1.0, 1.06)), (0.5, (1.0, 1.0, 1.0)), (2.0, (1.1, 1.0, 0.9))):
        np.testing.assert_allclose(unbeknown._teal_orange(np.full((2, 2, 3), v))[0, 0], v * np.asarray(tint))
    # The unsharp mask without the image: a flat area half as bright; the dark side of an edge clipped to 0.
    np.testing.assert_allclose(unbeknown._unsharp_without_image(np.full((16, 16, 3), 0.4)), 0.2, atol=1e-9)
    edge = np.full((16, 16, 3), 0.1)
    edge[:, 8:] = 1.0
    s = unbeknown._unsharp_without_image(edge)
    assert np.all(s[:, 7] == 0.0) and np.all(s[:, 9] > 0.5) and np.all(s[:, :4] == pytest.approx(0.05))
    # The neighbourhood clamp: a spike cut to its neighbours' maximum, a ramp and the pixels within their
    # neighbours' range kept.
    spike = np.full((8, 8, 3), 0.2)
    spike[4, 4] = 5.0
    spike[3, 4] = 0.3
    c = unbeknown._neighbour_clamped(spike)
    np.testing.assert_allclose(c[4, 4], 0.3)
    keep = np.ones((8, 8), bool)
    keep[4, 4] = False
    np.testing.assert_array_equal(c[keep], spike[keep])
    ramp = np.broadcast_to(np.linspace(0.0, 1.0, 8)[None, :, None], (8, 8, 3))
    np.testing.assert_allclose(unbeknown._neighbour_clamped(ramp), ramp)


def _face_normals(mesh) -> np.ndarray:
    import mitsuba as mi

    n = mesh.face_normal(mi.UInt32(np.arange(mesh.face_count(), dtype=np.uint32)))
    return np.stack([np.array(n[c]) for c in range(3)], axis=1)


def test_scene_edits():
    import mitsuba as mi

    from mcrt.scene import load_scene

    s = load_scene()
    d = _variant()
    # The first shape in the list: the objects never met.
    e = unbeknown._objects_never_found(d)
    assert "tetrahedron" not in e and "sphere" not in e and "light" in e and "floor" in e
    # The room reoriented: every wall, the floor and the ceiling facing out of the room, one-sided.
    out = unbeknown._room_outwards(d)
    centre = np.array([5.0, 0.0, 0.0])
    for name in unbeknown._room_names():
        mesh = out[name]
        p = np.array(mesh.vertex_positions_buffer()).reshape(-1, 3)[:3].mean(axis=0)
        assert np.all(_face_normals(mesh) @ (centre - p) < 0.0), name
        assert np.all(_face_normals(d[name]) @ (centre - p) > 0.0), name
        assert "TwoSided" not in str(mesh.bsdf())
    assert len(unbeknown._room_names()) == 8
    # The tetrahedron fanned: two triangles of its vertices, (v0, v1, v2) and (v0, v2, v3).
    v = next(o for o in s.objects if o.name == "tetrahedron").vertices
    fan = unbeknown._tetra_fanned(d)["tetrahedron"]
    assert fan.face_count() == 2
    np.testing.assert_allclose(np.array(fan.vertex_positions_buffer()).reshape(-1, 3),
                               np.array([v[0], v[1], v[2], v[0], v[2], v[3]]), atol=1e-6)
    assert len(unbeknown._polygon_fan(np.zeros((6, 3)))) == 4
    # The yaw of atan2 swapped: the camera looking along +y; unswapped, the forward vector comes back.
    f = unbeknown._yaw_atan2_swapped(s).cameras["near"].forward
    np.testing.assert_allclose(f, (0.0, 1.0, 0.0), atol=1e-12)
    for g in ((1.0, 0.0, 0.0), (0.3, -0.5, 0.2), (-0.2, 0.1, -0.9)):
        np.testing.assert_allclose(unbeknown._yaw_pitch_forward(g, swapped=False), np.array(g) / np.linalg.norm(g))
    # Correct edits: the thin lens loads; the Delaunay floor and ceiling cover their faces, wound as they are.
    assert str(mi.load_dict(unbeknown._thinlens(d)["sensor"])).startswith("ThinLensCamera")
    dl = unbeknown._floor_ceiling_delaunay(d)
    for name, sign in (("floor", 1.0), ("ceiling", -1.0)):
        assert dl[name].surface_area()[0] == pytest.approx(d[name].surface_area()[0], rel=1e-5)
        assert np.all(sign * _face_normals(dl[name])[:, 2] > 0.99)
    mi.load_dict(dl)


def test_camera_and_mirror_rays_are_as_they_say():
    rng = np.random.default_rng(1)
    eye, r, u, f, k = unsaid._frame()
    # The forward component solved for unit length: forward at the centre, sideways at the image's edges, the
    # pinhole's rays near the centre.
    o, d = unbeknown._direction_z_solved(np.array([0.5, 1.0, 0.0, 0.52]), np.array([0.5, 0.5, 0.5, 0.5]))
    np.testing.assert_allclose(d[0], f, atol=1e-12)
    np.testing.assert_allclose(d[1], r, atol=1e-6)
    np.testing.assert_allclose(d[2], -r, atol=1e-6)
    assert np.linalg.norm(d[3] - unsaid._pinhole(np.array([0.52]), np.array([0.5]))[1][0]) < 1e-3
    np.testing.assert_array_equal(o, np.broadcast_to(eye, (4, 3)))
    # The reflect placeholder: rays meeting the sphere sent back from it, the rest as they were.
    fx, fy = rng.random((2, 400))
    o, d = (np.asarray(a, np.float64) for a in unsaid._pinhole(fx, fy))
    p, dr, hit = unbeknown._retroreflected(o, d)
    c, radius = unsaid._sphere()
    on = hit == 1
    assert on.any() and (~on).any()
    np.testing.assert_allclose(dr[on], -d[on])
    np.testing.assert_allclose(np.linalg.norm(p[on] - c, axis=1), radius, atol=1e-3)
    np.testing.assert_array_equal(dr[~on], d[~on])
    # The Hammersley points digitally shifted: in each pixel one offset in each of n strata along each axis.
    u, v = unbeknown._hammersley_shifted(rng, 64, w=4, pixels=6)
    assert u.shape == (6, 64) and np.all((0 < u) & (u < 1))
    for a in (u, v):
        np.testing.assert_array_equal(np.sort(np.floor(a * 64), axis=1), np.broadcast_to(np.arange(64), (6, 64)))


def test_light_samples_are_as_they_say():
    rng = np.random.default_rng(2)
    mscene = unsaid._loaded(2)
    lt = unbeknown._scene().light
    q = unbeknown._light_points(rng, 2000)
    assert np.all(np.abs(q[:, :2] - lt.center[:2]) <= 1.0) and np.all(q[:, 2] == lt.center[2])
    # The cosine at the light from the surface's normal: the same on the floor, cos_s / cos_l times on a wall.
    floor = np.tile([[5.0, 0.5, -4.999]], (2000, 1))
    up = np.tile([[0.0, 0.0, 1.0]], (2000, 1))
    np.testing.assert_allclose(unbeknown._cos_light_from_surface(floor, up, q), unbeknown._geometry(floor, up, q))
    wall = np.tile([[5.0, -5.999, 3.0]], (2000, 1))
    inward = np.tile([[0.0, 1.0, 0.0]], (2000, 1))
    wi = unsaid._unit(q - wall)
    np.testing.assert_allclose(unbeknown._cos_light_from_surface(wall, inward, q),
                               unbeknown._geometry(wall, inward, q) * wi[:, 1] / wi[:, 2])
    assert unbeknown._cos_light_from_surface(wall, inward, q).mean() > 2 * unbeknown._geometry(wall, inward, q).mean()
    # 30 shadow rays with break: in the open, the mean of the 30 samples; in a penumbra, far less; the albedo kept.
    rho = np.full((2000, 3), 0.5)
    open_ = unbeknown._light_until_blocked(mscene, np.random.default_rng(3), floor, up, rho, None)
    again = np.random.default_rng(3)
    g = np.mean([unbeknown._geometry(floor, up, unbeknown._light_points(again, 2000)) for _ in range(30)], axis=0)
    np.testing.assert_allclose(open_, 0.5 * (g * lt.area / math.pi)[:, None] * np.asarray(lt.radiance))
    side = np.tile([[8.5, 2.5, -4.999]], (2000, 1))  # in the sphere's penumbra (0.6 of the light seen)
    right = np.mean([unbeknown._light_sampled(mscene, np.random.default_rng(k), side, up, rho, None)
                     for k in range(30)], axis=0)
    cut = unbeknown._light_until_blocked(mscene, np.random.default_rng(4), side, up, rho, None)
    assert 0.0 < cut.mean() < 0.5 * right.mean()
    # The light sample without the albedo: Mitsuba's over it.
    np.testing.assert_allclose(unbeknown._without_albedo(None, None, None, None, rho, np.ones((2000, 3))), 2.0)


def test_first_vertex_with_the_right_light_sample_is_the_plain_render(plain):
    """The first vertex's light sample by hand, right, agrees with Mitsuba's path: the changes made to it are the
    mistakes'."""
    im = unheralded._first_vertex(np.zeros((H, W, 3)), spp=256, seed=3, direct=unbeknown._light_sampled)
    rel = np.abs(im - plain).mean(axis=2) / (plain.mean(axis=2) + 0.05)
    assert np.median(rel) < 0.1 and im.mean() / plain.mean() == pytest.approx(1.0, abs=0.03)


def test_samples_cut_scaled_or_traced_elsewhere_as_they_say():
    """The per-sample mistakes on rays whose first hit is known: the floor, a wall, the sphere."""
    full, two, seen = unsaid._loaded(8), unsaid._loaded(2), unsaid._loaded(1)
    eye = np.array([-1.0, 0.0, 0.0])
    d = unsaid._unit(np.array([[10.0, 0.5, -5.0], [4.0, -6.0, 0.5], [9.5, 2.0, -3.3]]) - eye)
    o = np.tile(eye, (3, 1))
    L8, L2, L1 = (unsaid._sampled(m, o, d, 7) for m in (full, two, seen))
    # The floor cut after its light sample (no bounce off it), the wall and the sphere kept.
    cut = unbeknown._horizontal_unbounced_sample(o, d, 7, full=full, direct=two)
    np.testing.assert_allclose(cut, np.vstack([L2[:1], L8[1:]]))
    # The view's cosine: the floor's and the wall's reflected light times it, the sphere's kept.
    cos = -np.einsum("ij,ij->i", unforeseen._first_normal(full, o[:2], d[:2]), d[:2])
    v = unbeknown._view_cosine_sample(o, d, 7, full=full, seen=seen)
    np.testing.assert_allclose(v[:2], L1[:2] + cos[:, None] * (L8[:2] - L1[:2]), rtol=1e-6)
    np.testing.assert_allclose(v[2], L8[2])
    assert 0.2 < cos[0] < 0.5 < cos[1] < 1.0
    # The first hit's albedo kept: the wall's sample traced where every Lambertian has wall BC's colour.
    scenes: dict = {}
    a = unbeknown._first_albedo_kept_sample(o, d, 7, full=full, scenes=scenes)
    bc = (0.55, 0.15, 0.7)
    assert set(scenes) == {(0.6, 0.6, 0.6), bc}
    np.testing.assert_allclose(a[1], unsaid._sampled(unbeknown._albedo_scene(bc), o[1:2], d[1:2], 7)[0], rtol=1e-5)
    np.testing.assert_allclose(a[2], L8[2])
    # The path left where a shadow ray is blocked: the floor under the tetrahedron's base cut, the open floor kept.
    o2 = np.array([[8.5, -2.3, -4.95], [5.0, 0.0, -4.0]])
    d2 = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, -1.0]])
    b = unbeknown._path_break_sample(o2, d2, 5, full=full, direct=two, rng=np.random.default_rng(0))
    np.testing.assert_allclose(b, np.vstack([unsaid._sampled(two, o2[:1], d2[:1], 5), unsaid._sampled(full, o2, d2, 5)[1:]]))


def test_sample_loops_and_passes_add_up_as_they_say():
    x = np.zeros((4, 4, 3))
    L = unbidden._all_samples(4, 4, 32, 5)
    # Inverse-variance weights of 4 passes of 8 samples, from each pass's own luminance variance.
    p = L.reshape(16, 4, 8, 3)
    w = 1.0 / ((p @ programs._LUMA).var(axis=2, ddof=1) / 8 + 1e-8)
    np.testing.assert_allclose(unbeknown._passes_inverse_variance(x, passes=4, spp=32, seed=5).reshape(16, 3),
                               (w[..., None] * p.mean(axis=2)).sum(axis=1) / w.sum(axis=1)[:, None])
    # The log-space mean: a geometric mean, at most the arithmetic one.
    g = unbeknown._log_mean(x, spp=32, seed=5).reshape(16, 3)
    np.testing.assert_allclose(g, np.exp(np.log(L + 1e-3).mean(axis=1)) - 1e-3)
    assert np.all(g <= L.mean(axis=1) + 1e-12)
    # The moving average of passes, from the first.
    passes = [unseen._render(4, 4, 8, 9 + k) for k in range(3)]
    ema = 0.9 * (0.9 * passes[0] + 0.1 * passes[1]) + 0.1 * passes[2]
    np.testing.assert_allclose(unbeknown._passes_moving_average(x, passes=3, spp=8, seed=9), ema)
    # Roulette with one number: the paths of k segments weighted 1, 1, 2, 4, 8 from k = 4.
    r = {k: fresh._mitsuba(x.shape, 8, 3, max_depth=k, rr_depth=100) for k in range(4, 9)}
    want = r[4] + (r[5] - r[4]) + 2 * (r[6] - r[5]) + 4 * (r[7] - r[6]) + 8 * (r[8] - r[7])
    np.testing.assert_allclose(unbeknown._roulette_one_number(x, spp=8, seed=3), want)
    # The light seen twice: a render plus its own max-depth-1 render.
    np.testing.assert_allclose(unbeknown._light_seen_twice(x, spp=8, seed=3),
                               unseen._render(4, 4, 8, 3) + unseen._render(4, 4, 8, 3, max_depth=1))


def test_splat_about_the_corner_weighs_as_it_says():
    """The top-left pixel holds only its own samples, weighted (1 - u)(1 - v); the image half a pixel down and right of
    a plain one (the light's pixels moved)."""
    from mcrt.grade.accuracy import unsought

    x = np.zeros((4, 4, 3))
    im = unbeknown._splat_about_corner(x, spp=16, seed=2)
    L, u, v = next(unsought._film_samples(4, 4, 16, 2, partial(unsought._independent, pixels=16)))
    wt = (1.0 - u[0]) * (1.0 - v[0])
    np.testing.assert_allclose(im[0, 0], (L[0] * wt[:, None]).sum(axis=0) / wt.sum())


def test_normal_view_shows_the_faces_directions():
    n = unbeknown._normal_view(np.zeros((H, W, 3)), spp=4, seed=1)
    np.testing.assert_allclose(n[-1, W // 2], (0.5, 0.5, 1.0), atol=1e-6)
    np.testing.assert_allclose(n[0, W // 4], (0.5, 0.5, 0.0), atol=1e-6)
    np.testing.assert_allclose(n[H // 2, 0], (0.5, 0.0, 0.5), atol=1e-6)
    assert n.min() >= 0.0 and n.max() <= 1.0


def test_correct_hand_ins_agree_with_a_plain_render(plain):
    for s in unbeknown.CORRECT:
        case = _build(s)
        rel = np.abs(case.image - plain).mean(axis=2) / (plain.mean(axis=2) + 0.05)
        assert np.median(rel) < 0.15 and case.image.shape == (H, W, 3), s.name
        assert abs(case.image.mean() / plain.mean() - 1) < 0.1, s.name


def test_mistakes_differ_from_the_plain_render_as_they_say(plain):
    lum = plain.mean(axis=2)
    seen, lit = lum > 5, lum < 1

    def image(name):
        return _build(_by_name(name)).image.mean(axis=2)

    # Brighter lit surfaces, the light seen right.
    for name, low in (("cos_light_from_surface_normal", 1.1), ("light_sample_without_albedo", 1.25),
                      ("albedo_of_first_hit_kept", 1.25), ("roulette_one_number", 1.08)):
        im = image(name)
        assert im[lit].mean() > low * lum[lit].mean(), name
        assert im[seen].mean() == pytest.approx(lum[seen].mean(), rel=0.03), name
    # Darker lit surfaces.
    for name, high in (("lambert_view_cosine", 0.8), ("frame_nan_on_floor_ceiling", 0.85), ("samples_log_mean", 0.95),
                       ("pp_unsharp_without_image", 0.6)):
        assert image(name)[lit].mean() < high * lum[lit].mean(), name
    # The ceiling (the top row, beside the light) black without its bounce.
    assert image("frame_nan_on_floor_ceiling")[0, :3].mean() < 0.2 * lum[0, :3].mean()
    # The light seen twice as bright, the rest right.
    im = image("light_seen_counted_twice")
    whole = lum > 15
    assert im[whole].mean() == pytest.approx(2 * lum[whole].mean(), rel=0.02)
    assert im[lit].mean() == pytest.approx(lum[lit].mean(), rel=0.05)
    # The whole room black (reoriented), the camera turned away from the light.
    assert image("room_reoriented_outwards")[lit].mean() < 0.05 * lum[lit].mean()
    assert image("yaw_atan2_swapped").max() < 5.0


@pytest.mark.parametrize("name", [s.name for s in unbeknown.SPECS])
def test_hand_ins_build(name, tmp_path):
    """Every hand-in of the class builds at 16 x 16 and is written as a student's folder that reads back."""
    check_builds(_by_name(name), tmp_path)
