"""Pixel samplers (mcrt.samplers): the points, their randomisation, the replicate variance and its degrees of freedom.

Statistical tests state their level and seeds; each is a pure function of
them, so it always passes or always fails. Chi-square tests run at
ALPHA_POINTS = 1e-4 on fixed keys; image comparisons at the suite's family-wise
ALPHA = 0.01 (Holm over 8x8 tiles and RGB).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

import mcrt  # noqa: F401
import drjit as dr
import drjit.llvm as m

from mcrt.compare import compare_files
from mcrt.film import RenderResult
from mcrt.image_files import read_exr, write_exr
from mcrt.render import render
from mcrt.rng import SampleStreams, mix32
from mcrt.samplers import PixelSampler, owen_scramble, scrambled_jitter, sobol_02
from mcrt.scene import load_scene
from mcrt.tracer import pixel_jitter, render_tracer
from mcrt.stats import StatsError, compare_images, variance_dof

ALPHA = 0.01
ALPHA_POINTS = 1e-4


@pytest.fixture(scope="module")
def scene():
    return load_scene()


def _jitter(keys, samples, n):
    """scrambled_jitter on Dr.Jit arrays, as NumPy float32 (u, v)."""
    u, v = scrambled_jitter(m.UInt32(np.asarray(keys, np.uint32)), m.UInt32(np.asarray(samples, np.uint32)), n)
    return u.numpy(), v.numpy()


def _is_02_net(u, v):
    """Whether the 2^k points (u, v) put exactly one point in every elementary box 2^-a x 2^-(k-a)."""
    k = int(np.log2(len(u)))
    for a in range(k + 1):
        cells = np.floor(u * 2**a).astype(np.int64) * 2 ** (k - a) + np.floor(v * 2 ** (k - a)).astype(np.int64)
        if len(np.unique(cells)) != len(u):
            return False
    return True


@pytest.mark.parametrize("n", [16, 256])
def test_one_replicate_is_a_02_net(n):
    """A replicate's N = 2^k points of one pixel are a (0, k, 2)-net, scrambled or not, in every replicate.

    Power: N independent jitters (the stream's draws) are not a net.
    """
    for key, replicate in ((0x1234, 0), (0xBEEF, 3)):
        u, v = _jitter(np.full(n, key), replicate * n + np.arange(n), n)
        assert _is_02_net(u, v)
    plain_u, plain_v = (x.numpy().astype(np.float64) / 2**32 for x in sobol_02(m.UInt32(np.arange(n, dtype=np.uint32)), 8))
    assert _is_02_net(plain_u, plain_v)
    streams = SampleStreams.start(m.UInt32(np.full(n, 5, np.uint32)), m.UInt32(np.arange(n, dtype=np.uint32)), 1, 2)
    assert not _is_02_net(streams.next_1d().numpy(), streams.next_1d().numpy())


def test_numpy_and_drjit_agree_bit_for_bit():
    """The same functions on NumPy uint32 and Dr.Jit UInt32 (the NumPy path is the kernel's twin for these tests)."""
    rng = np.random.default_rng(3)  # any fixed values will do
    keys, samples = rng.integers(0, 2**32, 4096, dtype=np.uint32), rng.integers(0, 2**12, 4096, dtype=np.uint32)
    with np.errstate(over="ignore"):
        nu, nv = scrambled_jitter(keys, samples, 64)
        ns = owen_scramble(keys, samples * np.uint32(7) + np.uint32(1))
    du, dv = _jitter(keys, samples, 64)
    ds = owen_scramble(m.UInt32(keys), m.UInt32(samples) * 7 + 1).numpy()
    assert np.array_equal(nu, du) and np.array_equal(nv, dv) and np.array_equal(ns, ds)


def _nested(x, y, bits=12):
    """Whether y's top j bits are a function of x's top j bits alone, and a permutation of them, for j = 1, 4, 8."""
    for j in (1, 4, 8):
        top_x, top_y = x >> np.uint32(32 - j), y >> np.uint32(32 - j)
        table = {}
        for a, b in zip(top_x.tolist(), top_y.tolist()):
            if table.setdefault(a, b) != b:
                return False
        if len(set(table.values())) != 2**j:
            return False
    return True


def test_owen_scramble_keeps_leading_bits_nested():
    """Owen scrambling: a value's top j scrambled bits depend on its top j bits alone, one to one.

    Power: a plain hash of the value (mix32) does not.
    """
    with np.errstate(over="ignore"):
        x = np.arange(1 << 12, dtype=np.uint32) << np.uint32(20) | np.uint32(0x5A5A5)  # every top-12-bit value
        assert _nested(x, owen_scramble(x, np.uint32(0x9E3779B9)))
        assert not _nested(x, mix32(x))


def test_every_point_is_uniform_and_its_coordinates_independent():
    """Point i of a replicate over 65536 pixel keys: u, v uniform and (u, v) uniform on a 16x16 grid (chi-square, ALPHA_POINTS).

    Power: without the scramble (the same key for every pixel) the point is one fixed position.
    """
    keys = np.arange(1 << 16, dtype=np.uint32)
    for i in (0, 5, 63):
        u, v = _jitter(keys, np.full(keys.size, i), 64)
        for counts in (np.bincount((u * 64).astype(int), minlength=64), np.bincount((v * 64).astype(int), minlength=64),
                       np.bincount((u * 16).astype(int) * 16 + (v * 16).astype(int), minlength=256)):
            assert stats.chisquare(counts).pvalue > ALPHA_POINTS
    u, v = _jitter(np.zeros(keys.size), np.full(keys.size, 5), 64)
    assert stats.chisquare(np.bincount((u * 64).astype(int), minlength=64)).pvalue < ALPHA_POINTS


def test_replicates_and_pixels_scramble_apart():
    """Two replicates of one pixel, and one replicate of two pixels, get different points."""
    a = _jitter(np.full(16, 9), np.arange(16), 16)
    b = _jitter(np.full(16, 9), 16 + np.arange(16), 16)
    c = _jitter(np.full(16, 10), np.arange(16), 16)
    assert not np.array_equal(a[0], b[0]) and not np.array_equal(a[0], c[0])


def test_independent_jitter_is_the_streams_first_two_draws():
    """The default sampler draws exactly what the tracer always drew, so default images do not change."""
    pixel, sample = m.UInt32(np.arange(64, dtype=np.uint32)), m.UInt32(np.arange(64, dtype=np.uint32) * 3)
    s1, s2 = SampleStreams.start(pixel, sample, 11, 22), SampleStreams.start(pixel, sample, 11, 22)
    u, v = pixel_jitter(s1, PixelSampler())
    assert np.array_equal(u.numpy(), s2.next_1d().numpy()) and np.array_equal(v.numpy(), s2.next_1d().numpy())


def _settings(scene, spp=64, res=32, seed=1):
    return replace(scene.settings(camera="near", width=res, height=res, spp=spp), seed=seed)


def test_default_render_unchanged_and_unlabelled(scene):
    """pixel_sampler='independent' is the default render bit for bit, and its header names no variance method."""
    a = render(scene, _settings(scene), progress=False)
    b = render(scene, _settings(scene), progress=False, pixel_sampler="independent")
    assert np.array_equal(a.mean, b.mean) and np.array_equal(a.variance, b.variance)
    assert "variance_method" not in a.extra and variance_dof(a) == 63


def test_sobol_same_seed_same_image_and_tiling_free(scene):
    """A sobol render is a function of its seed bit for bit, whatever the tiling; another seed differs.

    Another pass size deals the samples into other float32 sums (mcrt.tracer): the same image to rounding.
    """
    a = render(scene, _settings(scene), progress=False, pixel_sampler="sobol")
    b = render_tracer(scene, _settings(scene), progress=False, pixel_sampler="sobol", tile_pixels=96, spp_per_pass=4)
    c = render(scene, _settings(scene, seed=2), progress=False, pixel_sampler="sobol")
    assert np.array_equal(a.mean, render(scene, _settings(scene), progress=False, pixel_sampler="sobol").mean)
    assert np.allclose(a.mean, b.mean, rtol=1e-5) and np.allclose(a.variance, b.variance, rtol=1e-3, atol=1e-7)
    assert not np.array_equal(a.mean, c.mean)
    assert a.extra["variance_method"] == "replicates:8" and variance_dof(a) == 7


def test_replicate_variance_is_the_variance_of_the_mean(scene):
    """Over 16 seeds (1..16) of 32x32 at 256 spp: variance / spp averaged over the image is the spread of the
    means across seeds to within 10 %, for both samplers (sobol: 8 replicates of 32).

    And the sampler is worth having: the sobol means spread less than a quarter as much (about a tenth here,
    most of it at the light's edge).
    """
    runs = {ps: [render(scene, _settings(scene, spp=256, seed=s), progress=False, pixel_sampler=ps) for s in range(1, 17)]
            for ps in ("independent", "sobol")}
    spread = {ps: np.var(np.stack([r.mean for r in rs]), axis=0, ddof=1).mean() for ps, rs in runs.items()}
    claimed = {ps: np.mean([(r.variance / r.spp).mean() for r in rs]) for ps, rs in runs.items()}
    for ps in runs:
        assert 0.9 < claimed[ps] / spread[ps] < 1.1, (ps, claimed[ps], spread[ps])
    assert spread["sobol"] < 0.25 * spread["independent"]


def test_sobol_agrees_with_mitsuba(scene):
    """64x64, 1024 spp each side, near, depth 8: sobol (8 replicates, 7 df) against Mitsuba, 8x8 tiles, Holm at ALPHA.

    Seeds: mcrt 11, Mitsuba 12 (those of tests/test_tracer.py's acceptance test).
    """
    a = render(scene, _settings(scene, spp=1024, res=64, seed=11), progress=False, pixel_sampler="sobol")
    b = render(scene, _settings(scene, spp=1024, res=64, seed=12), renderer="mitsuba", progress=False)
    c = compare_images(a, b, alpha=ALPHA, tile=8)
    assert c.passed, c.summary()


def _fake(extra, spp=64, var=1.0, shift=0.0):
    mean = np.full((8, 8, 3), 1.0 + shift, np.float32)
    return RenderResult(mean=mean, variance=np.full((8, 8, 3), var, np.float32), spp=spp, seed=0, max_depth=8,
                        renderer="mcrt", extra=extra)


def test_welch_takes_the_replicates_degrees_of_freedom():
    """The same images with variance from 2 replicates (1 df per pixel) against from 64 samples (63 df).

    Welch-Satterthwaite over the 64 pixels of a tile: one side 64 * 63 df, the other 64 * 1; fewer df, larger p.
    """
    b = _fake({}, shift=0.0)
    per_sample = compare_images(_fake({}, shift=0.05), b, tile=8)
    replicates = compare_images(_fake({"variance_method": "replicates:2"}, shift=0.05), b, tile=8)
    assert per_sample.df[0, 0, 0] == pytest.approx(2 * 64 * 63)
    assert replicates.df[0, 0, 0] == pytest.approx(4 / (1 / 64 + 1 / (64 * 63)))
    assert replicates.p_values[0, 0, 0] > per_sample.p_values[0, 0, 0]
    with pytest.raises(StatsError, match="variance_method"):
        variance_dof(_fake({"variance_method": "batches"}))


def test_exr_header_carries_the_method_and_compare_reads_it(scene, tmp_path):
    """The EXR says mcrt.variance_method = replicates:R; `mcrt compare` reads it and names it."""
    path = tmp_path / "a.exr"
    write_exr(path, render(scene, _settings(scene), progress=False, pixel_sampler="sobol", replicates=4))
    a = read_exr(path)
    assert a.extra["variance_method"] == "replicates:4" and variance_dof(a) == 3
    b = render(scene, _settings(scene, seed=9), progress=False)
    import io

    out = io.StringIO()
    assert compare_files(path, b, out=out) == 0
    assert "variance of 4 replicates, 3 df" in out.getvalue()


def test_refusals(scene):
    with pytest.raises(ValueError, match="multiple of 8"):
        render(scene, _settings(scene, spp=60), progress=False, pixel_sampler="sobol")
    with pytest.raises(ValueError, match="at least 2 replicates"):
        render(scene, _settings(scene), progress=False, pixel_sampler="sobol", replicates=1)
    with pytest.raises(ValueError, match="replicates go with"):
        render(scene, _settings(scene), progress=False, replicates=4)
    with pytest.raises(ValueError, match="unknown pixel sampler"):
        render(scene, _settings(scene), progress=False, pixel_sampler="halton")
    with pytest.raises(ValueError, match="pixel_sampler"):
        render(scene, _settings(scene), progress=False, pixel_sampler="sobol", adaptive="naive")


def test_validate_renders_the_image_under_test_with_the_sampler(scene):
    """mcrt validate --pixel-sampler: the study's image under test carries the sampler and its variance method."""
    from mcrt.validate.budget import Budget
    from mcrt.validate.opponent import render_tested

    r = render_tested(scene, Budget(res=16, spp=32, pixel_sampler="sobol"), seed=1)
    assert r.extra["variance_method"] == "replicates:8"
    assert "variance_method" not in render_tested(scene, Budget(res=16, spp=32), seed=1).extra


def test_merging_replicate_renders_pools_their_variance_and_df(scene):
    """Two sobol renders (8 replicates each) merge into one with 14 df whose variance / spp is the merged mean's.

    The merged variance of the mean is (v1 + v2) / 4 for two equal renders; per-sample merging would add the
    spread between the two means as if the samples were independent. Mixing with a per-sample render is refused.
    """
    from mcrt.film import merge

    a = render(scene, _settings(scene, seed=1), progress=False, pixel_sampler="sobol")
    b = render(scene, _settings(scene, seed=2), progress=False, pixel_sampler="sobol")
    m = merge([a, b])
    assert m.spp == 128 and variance_dof(m) == 14
    assert np.allclose(m.variance / m.spp, (a.variance / a.spp + b.variance / b.spp) / 4, rtol=1e-5)
    assert np.allclose(m.mean, (a.mean + b.mean) / 2, rtol=1e-6)
    with pytest.raises(ValueError, match="replicates"):
        merge([a, render(scene, _settings(scene), progress=False)])


def test_light_budget_from_the_pilot(scene):
    """light_paths='auto' (64x64, 256 spp, seed 5): a budget among AUTO_LIGHT_PATHS, the pilot's facts in the header,
    its time in the wall time; the image agrees with Mitsuba's committed reference (policy reference-floor, ALPHA).

    The recorded optimum is lambda* = sqrt(b t_p / (a t_l)) of the recorded pilot facts; without bidirectional the
    budget is refused.
    """
    from mcrt.bidir import AUTO_LIGHT_PATHS
    from mcrt.groundtruth import load_reference
    from mcrt.stats import compare

    r = render(scene, _settings(scene, spp=256, res=64, seed=5), progress=False, bidirectional=True, light_paths="auto",
               pixel_sampler="sobol")
    pilot = dict(kv.split("=") for kv in r.extra["light_paths_pilot"].split(","))
    assert float(pilot["seconds"]) < r.wall_time and int(pilot["spp"]) == 16
    chosen = int(r.extra["light_paths"]) / (256 * 64 * 64)
    assert min(abs(chosen / x - 1) for x in AUTO_LIGHT_PATHS) < 0.01
    a, b, t_p, t_l = (float(pilot[k]) for k in ("a", "b", "t_p", "t_l"))
    assert float(pilot["optimum"]) == pytest.approx((b * t_p / (a * t_l)) ** 0.5, rel=1e-3)
    assert compare(r, load_reference(scene, "near", 64, 8), policy="reference-floor", alpha=ALPHA).passed
    with pytest.raises(ValueError, match="needs bidirectional"):
        render(scene, _settings(scene), progress=False, light_paths="auto")


# -- the sobol sampler on the Mitsuba hosts (renderers plugin and mitsuba) ---------------------------------------


@pytest.mark.parametrize("renderer", ["plugin", "mitsuba"])
def test_mitsuba_hosts_take_the_tracers_points_and_replicate_variance(scene, renderer):
    """At max depth 1 a sample's value is a function of its camera ray, so a sobol render on a Mitsuba host at the
    standalone tracer's seed is the tracer's sobol render bit for bit, mean and replicate variance (64x64, 64 spp,
    4 replicates, seed 4): the same points in the same pixels and the same arithmetic, here in 16 passes of 4
    samples whose replicate sums are held across passes (mcrt.samplers.replicate_passes).

    Power: another seed's points differ.
    """
    s = replace(scene.settings(camera="near", width=64, height=64, spp=64, max_depth=1), seed=4)
    tracer = render(scene, s, progress=False, pixel_sampler="sobol", replicates=4)
    host = render(scene, s, renderer=renderer, progress=False, pixel_sampler="sobol", replicates=4, spp_per_pass=4)
    assert (host.variance > 0).sum() > 40  # the light's edge: pixels whose replicates differ
    assert np.array_equal(host.mean, tracer.mean) and np.array_equal(host.variance, tracer.variance)
    assert host.extra["pixel_sampler"] == "sobol" and host.extra["variance_method"] == "replicates:4"
    other = render(scene, replace(s, seed=5), renderer=renderer, progress=False, pixel_sampler="sobol", replicates=4)
    assert not np.array_equal(other.mean, tracer.mean)


def test_plugin_sobol_agrees_with_mitsuba_and_the_standalone_tracer(scene, tmp_path):
    """64x64, 1024 spp, near, depth 8, 8x8 tiles, Holm at ALPHA: the plugin's sobol render (seed 31, 8 replicates)
    against Mitsuba's path (seed 32, independent) and against the standalone tracer's sobol render (seed 33).

    The header says replicates:8 (through an EXR) and the comparison takes 7 df per pixel: against the tracer's
    sobol render, both sides 64 pixels x 7 df, a tile's Welch df is at most 2 x 64 x 7 (per-sample df would give
    up to 2 x 64 x 1023).
    """
    s = scene.settings(camera="near", width=64, height=64, spp=1024, max_depth=8)
    path = tmp_path / "plugin.exr"
    write_exr(path, render(scene, replace(s, seed=31), renderer="plugin", progress=False, pixel_sampler="sobol"))
    plugin = read_exr(path)
    assert plugin.extra["variance_method"] == "replicates:8" and variance_dof(plugin) == 7
    mitsuba = render(scene, replace(s, seed=32), renderer="mitsuba", progress=False)
    tracer = render(scene, replace(s, seed=33), progress=False, pixel_sampler="sobol")
    against_path, against_tracer = (compare_images(plugin, b, alpha=ALPHA, tile=8) for b in (mitsuba, tracer))
    assert against_path.passed, against_path.summary()
    assert against_tracer.passed, against_tracer.summary()
    assert np.nanmax(against_tracer.df) <= 2 * 64 * 7 * (1 + 1e-6)


def test_mitsuba_hosts_refuse_what_the_tracer_refuses(scene):
    with pytest.raises(ValueError, match="multiple of 8"):
        render(scene, _settings(scene, spp=60), renderer="plugin", progress=False, pixel_sampler="sobol")
    with pytest.raises(ValueError, match="at least 2 replicates"):
        render(scene, _settings(scene), renderer="mitsuba", progress=False, pixel_sampler="sobol", replicates=1)
    with pytest.raises(ValueError, match="summed apart, and here ParticleTracerIntegrator splats"):
        render(scene, _settings(scene), renderer="mitsuba", progress=False, pixel_sampler="sobol", integrator="ptracer")


def test_any_mitsuba_scene_takes_the_sampler(tmp_path, capsys):
    """Mitsuba's Cornell box (mi.cornell_box(), its path integrator), 32x32, 256 spp: sobol (seed 41, 8 replicates)
    agrees with independent samples (seed 42), 8x8 tiles, Holm at ALPHA, and says replicates:8.

    `mcrt render --mitsuba-scene` takes --pixel-sampler, and refuses it with Mitsuba's particle tracer (exit 2, one
    line saying why).
    """
    import mitsuba as mi

    from mcrt.cli import main
    from mcrt.mitsuba_scene import render_with_variance

    mi.set_variant("llvm_ad_rgb")
    kw = dict(spp=256, width=32, height=32)
    a = render_with_variance(mi.cornell_box(), seed=41, pixel_sampler="sobol", **kw)
    b = render_with_variance(mi.cornell_box(), seed=42, **kw)
    assert a.extra["variance_method"] == "replicates:8" and variance_dof(a) == 7
    c = compare_images(a, b, alpha=ALPHA, tile=8)
    assert c.passed, c.summary()
    out = tmp_path / "cb.exr"
    args = ["render", "--mitsuba-scene", "cornell-box", "--res", "16", "--spp", "16", "--pixel-sampler", "sobol", "-o", str(out)]
    assert main(args) == 0 and read_exr(out).extra["variance_method"] == "replicates:8"
    capsys.readouterr()
    assert main([*args, "--integrator", "ptracer"]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "pixel sampler 'sobol' needs each pixel's samples summed apart" in line
