"""Tests of mcrt.stats on synthetic renders with known expectations.

Synthetic renders draw actual per-sample values (exponential, gamma or
lognormal around a known mean image) and accumulate x and x^2 the way the
renderer does (mcrt.film.Moments), so means and per-sample variances carry
the real sampling noise and its correlation. Seeds are pinned so each test is
deterministic; each test states its alpha. A null test passing at a pinned
seed is a 1 - alpha event, so a failure there is worth a look, not a re-seed.
"""

from __future__ import annotations

import json
import sys
import types

import numpy as np
import pytest
from PIL import Image
from scipy import stats as sps

from mcrt.compare import compare_files, heatmap_rgb, write_heatmap, write_json
from mcrt.exitcodes import EXIT_FAILED as DIFFERENT
from mcrt.exitcodes import EXIT_OK as CONSISTENT
from mcrt.exitcodes import EXIT_UNUSABLE as UNUSABLE
from mcrt.film import Moments, RenderResult
from mcrt.pytest_plugin import assert_same_image
from mcrt.stats import (
    POLICIES,
    StatsError,
    ZeroPdfError,
    adjust_p_values,
    binomial_interval,
    chi2_gof,
    compare,
    compare_images,
    floor_variance,
    reject,
    tile_box,
    tile_counts,
    tile_means,
    tile_sums,
)

# --------------------------------------------------------------------------
# Synthetic renders
# --------------------------------------------------------------------------


def mean_image(h: int, w: int) -> np.ndarray:
    """A smooth, strictly positive expected image, different per channel."""
    y, x = np.mgrid[0:h, 0:w]
    base = 0.2 + 0.8 * (x + 0.5 * y) / (w + 0.5 * h)
    return np.stack([base, 0.7 * base[::-1], 0.4 + 0.3 * base[:, ::-1]], axis=-1)


def draw(rng: np.random.Generator, mu: np.ndarray, n: int, dist: str) -> np.ndarray:
    """n samples per pixel and channel with expectation mu: shape (h, w, 3, n)."""
    shape = mu.shape + (n,)
    mu = mu[..., None]
    if dist == "exponential":  # coefficient of variation 1, skewness 2
        return mu * rng.exponential(size=shape)
    if dist == "gamma2":  # cv 0.71
        return mu * rng.gamma(2.0, 0.5, size=shape)
    if dist == "lognormal":  # sigma 0.75: cv 0.87, skewness 3.1
        s = 0.75
        return mu * np.exp(s * rng.standard_normal(shape) - 0.5 * s * s)
    raise ValueError(dist)


def synth(seed: int, mu: np.ndarray, spp: int, dist: str = "exponential", constant: np.ndarray | None = None) -> RenderResult:
    """Render-like result: mean and per-sample variance from spp actual samples.

    ``constant`` (h, w, 3), where not NaN, replaces the samples by that
    constant (zero-variance pixels such as those seeing only the light).
    """
    rng = np.random.default_rng(seed)
    h, w, _ = mu.shape
    m = Moments.zeros(h, w)
    chunk = 256
    while m.n < spp:
        n = min(chunk, spp - m.n)
        x = draw(rng, mu, n, dist)
        if constant is not None:
            x = np.where(np.isnan(constant)[..., None], x, np.nan_to_num(constant)[..., None])
        m.add(x.sum(axis=-1), (x * x).sum(axis=-1), n)
    return RenderResult(mean=m.mean(), variance=m.variance(), spp=spp, seed=seed, max_depth=0, renderer=f"synthetic-{dist}")


# --------------------------------------------------------------------------
# compare_images
# --------------------------------------------------------------------------


def test_same_expectation_different_estimators_pass():
    # alpha = 0.01 (FWER, Holm). Two different estimators of one image:
    # exponential at 256 spp against lognormal at 1024 spp, each with its own
    # variance. Seeds 1 and 2 pinned; passing is a 99 % event.
    mu = mean_image(64, 64)
    a = synth(1, mu, 256, "exponential")
    b = synth(2, mu, 1024, "lognormal")
    c = compare_images(a, b, alpha=0.01, tile=8)
    assert c.passed, c.summary()
    assert c.n_tests == 8 * 8 * 3
    assert c.p_values.shape == (8, 8, 3)
    assert c.failing_tiles == [] and c.largest_effect is None
    assert c.summary().startswith("consistent: 0 of 192 tile tests rejected at FWER 0.01 (Holm")
    assert np.all(np.abs(c.global_rel_diff) < 0.01)


def test_region_bias_found_in_that_tile():
    # alpha = 0.01 (FWER, Holm). A 4 % brighter 8x8 region at tile (3, 5):
    # at 1024 spp each side's tile mean has a relative sd of 1/256, so the
    # bias is about 7 sd of the difference and every channel must fail there,
    # and only there.
    mu = mean_image(64, 64)
    mu_biased = mu.copy()
    mu_biased[24:32, 40:48] *= 1.04
    a = synth(11, mu_biased, 1024)
    b = synth(12, mu, 1024)
    c = compare_images(a, b, alpha=0.01, tile=8)
    assert not c.passed
    assert {(f.ty, f.tx) for f in c.failing_tiles} == {(3, 5)}
    assert {f.channel for f in c.failing_tiles} == {"R", "G", "B"}
    assert all(f.t > 0 and f.diff > 0 for f in c.failing_tiles)
    ps = [f.p for f in c.failing_tiles]
    assert ps == sorted(ps)
    e = c.largest_effect
    assert (e.ty, e.tx) == (3, 5) and 0.02 < e.rel_diff < 0.06
    assert c.tile_box(3, 5) == (24, 32, 40, 48)
    s = c.summary()
    assert s.startswith("DIFFERENT: 3 of 192") and "(3,5)" in s
    # Swapping the sides flips the sign of t, not the verdict.
    c2 = compare_images(b, a, alpha=0.01, tile=8)
    assert np.allclose(c2.t, -c.t) and np.allclose(c2.p_values, c.p_values)


def test_global_one_percent_bias_fails_at_large_spp():
    # alpha = 0.01 (FWER, Holm). 1 % brighter everywhere, 4096 spp per side,
    # 16x16 tiles: each tile's difference is about 7 sd.
    mu = mean_image(32, 32)
    a = synth(21, 1.01 * mu, 4096)
    b = synth(22, mu, 4096)
    c = compare_images(a, b, alpha=0.01, tile=16)
    assert not c.passed
    assert c.n_rejected >= 6  # of 12
    assert all(f.t > 0 for f in c.failing_tiles)
    assert np.all(np.abs(c.global_rel_diff - 0.01) < 0.003)


def test_luminance_conservative_and_still_powerful():
    # alpha = 0.01 (FWER, Holm); luminance uses the Cauchy-Schwarz variance
    # bound. Null passes; a 5 % region bias at 1024 spp is still found.
    mu = mean_image(64, 64)
    c0 = compare_images(synth(31, mu, 1024), synth(32, mu, 1024), alpha=0.01, channels="luminance")
    assert c0.passed, c0.summary()
    assert c0.n_tests == 64 and c0.channel_names == ("Y",)
    mu_b = mu.copy()
    mu_b[0:8, 0:8] *= 1.05
    c1 = compare_images(synth(33, mu_b, 1024), synth(34, mu, 1024), alpha=0.01, channels="luminance")
    assert [(f.ty, f.tx, f.channel) for f in c1.failing_tiles] == [(0, 0, "Y")]
    # The bound: var(Y) <= (sum w_c sd_c)^2 >= the variance with independent channels.
    w = np.array([0.2126, 0.7152, 0.0722])
    var = np.array([0.3, 1.0, 2.0])
    assert (w @ np.sqrt(var)) ** 2 >= w**2 @ var


def test_per_pixel_tests_with_tile_one():
    # alpha = 0.01 (FWER, Holm) over 3072 per-pixel tests at 256 spp, same
    # estimator on both sides. One pixel at twice its expectation is found.
    mu = mean_image(32, 32)
    c0 = compare_images(synth(41, mu, 256), synth(42, mu, 256), alpha=0.01, tile=1)
    assert c0.passed, c0.summary()
    assert c0.n_tests == 32 * 32 * 3
    mu_b = mu.copy()
    mu_b[7, 19] *= 2.0
    c1 = compare_images(synth(43, mu_b, 256), synth(44, mu, 256), alpha=0.01, tile=1)
    assert {(f.ty, f.tx) for f in c1.failing_tiles} == {(7, 19)}


def test_partial_edge_tiles_are_kept():
    # alpha = 0.01. 20x20 pixels in 8x8 tiles: 3x3 tiles, the last row and
    # column hold 4 pixels across.
    mu = mean_image(20, 20)
    a, b = synth(51, mu, 64), synth(52, mu, 64)
    c = compare_images(a, b, alpha=0.01, tile=8)
    assert c.t.shape == (3, 3, 3) and c.n_tests == 27
    assert np.allclose(c.mean_a[2, 2], a.mean[16:20, 16:20].astype(np.float64).mean(axis=(0, 1)))
    assert c.tile_box(2, 2) == (16, 20, 16, 20)
    # The edge tile's standard error uses its own 16 pixels.
    se = np.sqrt((a.variance[16:20, 16:20] / 64).astype(np.float64).sum(axis=(0, 1)) / 16**2
                 + (b.variance[16:20, 16:20] / 64).astype(np.float64).sum(axis=(0, 1)) / 16**2)
    assert np.allclose(c.t[2, 2], (c.mean_a[2, 2] - c.mean_b[2, 2]) / se)


def test_welch_statistic_and_df_by_hand():
    # One 2x2 tile, constant per-pixel variances: t and the
    # Welch-Satterthwaite df from the formulas in the docstring.
    ma, mb = np.full((2, 2, 3), 1.1, np.float32), np.full((2, 2, 3), 1.0, np.float32)
    va, vb = np.full((2, 2, 3), 0.5, np.float32), np.full((2, 2, 3), 2.0, np.float32)
    a = RenderResult(ma, va, spp=10, seed=0, max_depth=0, renderer="a")
    b = RenderResult(mb, vb, spp=40, seed=0, max_depth=0, renderer="b")
    c = compare_images(a, b, alpha=0.01, tile=2)
    sa, sb = 0.5 / 10 / 4, 2.0 / 40 / 4  # variance of each tile mean
    t = (np.float32(1.1) - np.float32(1.0)) / np.sqrt(sa + sb)
    df = (sa + sb) ** 2 / (4 * (0.5 / 10 / 16) ** 2 / 9 + 4 * (2.0 / 40 / 16) ** 2 / 39)
    assert np.allclose(c.t, t, rtol=1e-6) and np.allclose(c.df, df, rtol=1e-6)
    assert np.allclose(c.p_values, 2 * sps.t.sf(t, df), rtol=1e-6)


def test_zero_variance_tiles_equal_pass_unequal_fail():
    # alpha = 0.01. Tile (0, 0) sees only the light (constant samples, zero
    # variance on both sides; float64 accumulation leaves ~1e-8 relative sd).
    mu = mean_image(32, 32)
    light = np.full(mu.shape, np.nan)
    light[0:8, 0:8] = 17.3
    a = synth(61, mu, 256, constant=light)
    b = synth(62, mu, 512, "gamma2", constant=light * (1 + 3e-7))  # rounding-level difference
    c = compare_images(a, b, alpha=0.01, tile=8)
    assert c.passed, c.summary()
    assert c.deterministic[0, 0].all() and not c.deterministic[1:].any()
    assert np.all(c.p_values[0, 0] == 1.0) and np.all(c.t[0, 0] == 0.0)
    # Moments kept in float32 (var = m2 - m1^2) leave rounding-level variance
    # on constant pixels (here a relative sd of 1e-5) and means that differ in
    # the 6th digit: still equal, although t would be about 90.
    b = synth(62, mu, 512, "gamma2", constant=light * (1 + 5e-6))
    b.variance[0:8, 0:8] = np.float32((1e-5 * 17.3) ** 2)
    c = compare_images(a, b, alpha=0.01, tile=8)
    assert c.passed, c.summary()
    assert c.deterministic[0, 0].all() and np.all(c.p_values[0, 0] == 1.0)

    b_wrong = synth(62, mu, 512, "gamma2", constant=light * 1.001)
    c = compare_images(a, b_wrong, alpha=0.01, tile=8)
    assert not c.passed
    assert [(f.ty, f.tx) for f in c.failing_tiles] == [(0, 0)] * 3
    assert np.all(c.p_values[0, 0] == 0.0) and np.all(np.isneginf(c.t[0, 0]))
    json.dumps(c.to_dict(), allow_nan=False)  # inf is written as null


def test_zero_variance_tiles_within_a_per_channel_rtol_or_an_atol():
    # alpha = 0.01. A noiseless tile 0.03 % brighter in R and B only: exact, rejected; within a per-channel rtol
    # of (0.00031, exact, 0.00031), accepted, and a 0.03 % offset in G is still rejected there. A noiseless dark
    # tile 1e-7 off (float32 rounding at the scale of 1): rejected exactly, accepted with atol 2.4e-7.
    mu = mean_image(32, 32)
    light = np.full(mu.shape, np.nan)
    light[0:8, 0:8] = 17.3
    light[8:16, 0:8] = 1e-6
    a = synth(61, mu, 256, constant=light)
    off = light.copy()
    off[0:8, 0:8] *= np.array([1.0003, 1.0, 1.0003])
    b = synth(62, mu, 512, "gamma2", constant=off)
    assert not compare_images(a, b, alpha=0.01, tile=8).passed
    c = compare_images(a, b, alpha=0.01, tile=8, rtol=(0.00031, 1e-5, 0.00031))
    assert c.passed and c.rtol == (0.00031, 1e-5, 0.00031) and c.atol == 0.0
    off[0:8, 0:8, 1] *= 1.0003
    c = compare_images(a, synth(62, mu, 512, "gamma2", constant=off), alpha=0.01, tile=8, rtol=(0.00031, 1e-5, 0.00031))
    assert [(f.ty, f.tx, f.channel) for f in c.failing_tiles] == [(0, 0, "G")]
    dark = light.copy()
    dark[8:16, 0:8] += 1e-7
    b = synth(62, mu, 512, "gamma2", constant=dark)
    assert [(f.ty, f.tx) for f in compare_images(a, b, alpha=0.01, tile=8).failing_tiles] == [(1, 0)] * 3
    c = compare_images(a, b, alpha=0.01, tile=8, atol=2.4e-7)
    assert c.passed and c.atol == 2.4e-7 and c.rtol == 1e-5  # one number given, one number recorded (mcrt compare)
    with pytest.raises(ValueError, match="atol must be"):
        compare_images(a, b, atol=-1.0)


def test_zero_variance_on_one_side_uses_the_ordinary_statistic():
    # alpha = 0.01. A is exact (constant 0.5) in tile (1, 1), B is noisy
    # around 0.5 there: an ordinary, finite test that passes.
    mu = mean_image(32, 32)
    mu[8:16, 8:16] = 0.5
    exact = np.full(mu.shape, np.nan)
    exact[8:16, 8:16] = 0.5
    c = compare_images(synth(71, mu, 256, constant=exact), synth(72, mu, 256), alpha=0.01, tile=8)
    assert c.passed, c.summary()
    assert not c.deterministic[1, 1].any()
    assert np.all(np.isfinite(c.t[1, 1])) and np.all(c.p_values[1, 1] < 1.0)


def test_unusable_inputs_raise_stats_error():
    mu = mean_image(16, 16)
    a = synth(81, mu, 16)
    b = synth(82, mean_image(16, 24), 16)
    with pytest.raises(StatsError, match=r"\(16, 16, 3\).*\(16, 24, 3\)"):
        compare_images(a, b)
    no_var = RenderResult(a.mean, None, spp=16, seed=0, max_depth=0, renderer="x")
    with pytest.raises(StatsError, match="image B has no per-sample variance"):
        compare_images(a, no_var)
    one_spp = RenderResult(a.mean, a.variance, spp=1, seed=0, max_depth=0, renderer="x")
    with pytest.raises(StatsError, match="image A has spp=1"):
        compare_images(one_spp, a)
    nan = a.mean.copy()
    nan[3, 4, 1] = np.nan
    with pytest.raises(StatsError, match="non-finite"):
        compare_images(RenderResult(nan, a.variance, 16, 0, 0, "x"), a)
    with pytest.raises(ValueError):
        compare_images(a, a, correction="sidak")


def test_calibration_false_alarm_rate_over_200_seeds():
    # alpha = 0.05 (FWER). 200 independent null comparisons: exponential
    # samples at 64 spp against 256 spp, 16x16 pixels in 4x4 tiles (48 tests).
    # The number of comparisons with any rejection must be consistent with
    # the nominal 5 %: 0.05 inside the 99.9 % Clopper-Pearson interval. Holm
    # and Benjamini-Hochberg coincide under the global null. The raw tile
    # p-values must also be uniform (Kolmogorov-Smirnov at 0.001).
    mu = mean_image(16, 16)
    n_seeds = 200
    alarms = {"holm": 0, "bh": 0}
    pooled = []
    for seed in range(n_seeds):
        a = synth(1000 + 2 * seed, mu, 64)
        b = synth(1001 + 2 * seed, mu, 256)
        c = compare_images(a, b, alpha=0.05, tile=4)
        alarms["holm"] += not c.passed
        alarms["bh"] += bool(reject(c.p_values, 0.05, "bh").any())
        pooled.append(c.p_values.ravel())
    for k in alarms.values():
        lo, hi = binomial_interval(k, n_seeds, level=0.999)
        assert lo <= 0.05 <= hi, f"{k} false alarms in {n_seeds} at alpha 0.05"
    assert sps.kstest(np.concatenate(pooled), "uniform").pvalue > 1e-3


# --------------------------------------------------------------------------
# Multiple testing
# --------------------------------------------------------------------------


def test_holm_bonferroni_bh_on_a_hand_made_vector():
    # alpha = 0.05, m = 5. Sorted: 0.005 0.011 0.02 0.038 0.3.
    # Bonferroni (0.01 each): 1. Holm (0.01, 0.0125, 0.0167, ...): 2.
    # BH (0.01, 0.02, 0.03, 0.04, 0.05, largest k with p_(k) <= k/m alpha): 4.
    p = np.array([0.038, 0.3, 0.005, 0.02, 0.011])
    assert reject(p, 0.05, "bonferroni").tolist() == [False, False, True, False, False]
    assert reject(p, 0.05, "holm").tolist() == [False, False, True, False, True]
    assert reject(p, 0.05, "bh").tolist() == [True, False, True, True, True]
    assert np.allclose(adjust_p_values(p, "holm"), [0.076, 0.3, 0.025, 0.06, 0.044])
    assert np.allclose(adjust_p_values(p, "bh"), [0.0475, 0.3, 0.025, 0.1 / 3, 0.0275])
    assert np.allclose(adjust_p_values(p, "bonferroni"), [0.19, 1.0, 0.025, 0.1, 0.055])


# --------------------------------------------------------------------------
# Chi-square goodness of fit
# --------------------------------------------------------------------------


def exponential_bins(samples: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    edges = np.concatenate([np.linspace(0.0, 12.0, 61), [np.inf]])
    obs = np.histogram(samples, bins=edges)[0]
    exp = n * np.diff(sps.expon.cdf(edges))
    return obs, exp


def test_chi2_right_distribution_passes_wrong_fails():
    # alpha = 0.01. 50000 exponential samples in 61 bins, the tail pooled.
    rng = np.random.default_rng(91)
    n = 50000
    obs, exp = exponential_bins(rng.exponential(size=n), n)
    stat, dof, p = chi2_gof(obs, exp)
    assert p > 0.01
    assert dof < len(exp) - 1  # the sparse tail was pooled
    obs_w, _ = exponential_bins(rng.exponential(1.05, size=n), n)  # a 5 % wrong scale
    assert chi2_gof(obs_w, exp)[2] < 1e-6


def test_chi2_cosine_hemisphere_vs_uniform_hemisphere():
    # alpha = 0.01. Bins of cos(theta) x phi; the cosine-weighted pdf gives
    # E = n (u1^2 - u0^2) / n_phi. Uniform hemisphere sampling weighted as
    # cosine-weighted (mutant 7) must fail.
    rng = np.random.default_rng(92)
    n, nu, nphi = 50000, 20, 16
    ue, pe = np.linspace(0, 1, nu + 1), np.linspace(0, 2 * np.pi, nphi + 1)
    exp = n * np.outer(np.diff(ue**2), np.diff(pe) / (2 * np.pi))
    phi = 2 * np.pi * rng.random(n)
    good = np.histogram2d(np.sqrt(rng.random(n)), phi, bins=(ue, pe))[0]
    bad = np.histogram2d(rng.random(n), phi, bins=(ue, pe))[0]
    assert chi2_gof(good, exp)[2] > 0.01
    assert chi2_gof(bad, exp)[2] < 1e-9


def test_chi2_pooling_by_hand():
    # Bins with E < 5 (1, 1.5, 2: 4.5 in all) are pooled; still below 5, so
    # the smallest regular bin (E = 10) joins: bins {14.5, 10, 20}, dof 2.
    obs = np.array([12, 8, 3, 1, 0, 25])
    exp = np.array([10, 10, 1, 2, 1.5, 20])
    stat, dof, p = chi2_gof(obs, exp)
    # Sorted by E: 1(3), 1.5(0), 2(1), 10(12), 10(8), 20(25) -> pooled 4.5 + 10 (O = 16).
    want = (16 - 14.5) ** 2 / 14.5 + (8 - 10) ** 2 / 10 + (25 - 20) ** 2 / 20
    assert dof == 2 and stat == pytest.approx(want)
    assert p == pytest.approx(sps.chi2.sf(want, 2))
    # Without low bins nothing is pooled.
    assert chi2_gof([9, 11, 20], [10, 10, 20])[1] == 2


def test_chi2_zero_expected_bins():
    with pytest.raises(ZeroPdfError, match="p = 0: 1 samples fell in 1 bins"):
        chi2_gof([9, 1, 10], [10, 0, 10])
    assert issubclass(ZeroPdfError, StatsError)
    stat, dof, p = chi2_gof([10, 0, 10], [10, 0, 10])  # empty and impossible: dropped
    assert (stat, dof, p) == (0.0, 1, 1.0)
    with pytest.raises(StatsError, match="shape"):
        chi2_gof([1, 2], [1, 2, 3])


# --------------------------------------------------------------------------
# Binomial interval
# --------------------------------------------------------------------------


def test_binomial_interval_known_values():
    # Clopper-Pearson: 0/10 -> upper 1 - 0.025^(1/10); 5/10 -> (0.1871, 0.8129).
    lo, hi = binomial_interval(0, 10)
    assert lo == 0.0 and hi == pytest.approx(1 - 0.025 ** 0.1, abs=1e-12) and hi == pytest.approx(0.3085, abs=1e-4)
    lo, hi = binomial_interval(10, 10)
    assert hi == 1.0 and lo == pytest.approx(0.025 ** 0.1, abs=1e-12)
    assert binomial_interval(5, 10) == pytest.approx((0.1871, 0.8129), abs=1e-4)
    lo99, hi99 = binomial_interval(10, 200, level=0.999)
    lo95, hi95 = binomial_interval(10, 200, level=0.95)
    assert lo99 < lo95 < 0.05 < hi95 < hi99
    with pytest.raises(ValueError):
        binomial_interval(11, 10)


# --------------------------------------------------------------------------
# Reports, heat map, files, pytest helper
# --------------------------------------------------------------------------


def biased_pair(seed: int = 101) -> tuple[RenderResult, RenderResult]:
    mu = mean_image(64, 64)
    mu_b = mu.copy()
    mu_b[24:32, 40:48] *= 1.05
    return synth(seed, mu_b, 1024), synth(seed + 1, mu, 1024)


def test_heatmap_and_to_dict(tmp_path):
    # alpha = 0.01. Red where A is brighter, failing tile outlined in black.
    a, b = biased_pair()
    c = compare_images(a, b, alpha=0.01, tile=8)
    path = write_heatmap(c, tmp_path / "sub" / "heat.png", scale=2)
    img = np.asarray(Image.open(path))
    assert img.shape == (128, 128, 3)
    assert img[2 * 28, 2 * 44].tolist() == [255, 0, 0]  # saturated red inside tile (3, 5)
    assert img[2 * 24, 2 * 44].tolist() == [0, 0, 0]  # its top edge
    assert img[2 * 28, 2 * 44 - 16].max() == 255  # the neighbour is not outlined
    assert np.array_equal(img, heatmap_rgb(c, scale=2))
    d = c.to_dict()
    text = json.dumps(d, allow_nan=False)
    assert json.loads(text)["failing_tiles"][0]["box"] == [24, 32, 40, 48]
    assert d["passed"] is False and d["n_tests"] == 192 and d["error_rate"] == "FWER" and d["policy"] == "independent"
    assert json.loads(write_json(c, tmp_path / "sub" / "c.json").read_text()) == json.loads(text)


@pytest.fixture
def fake_imageio(monkeypatch):
    """Stand-in for mcrt.image_files: read_image looks paths up in a dict."""
    images: dict[str, RenderResult] = {}
    mod = types.ModuleType("mcrt.image_files")

    class ImageError(Exception):
        pass

    def read_image(path):
        try:
            r = images[str(path)]
        except KeyError:
            raise ImageError(f"{path}: no such image") from None
        return RenderResult(r.mean.copy(), None if r.variance is None else r.variance.copy(), r.spp, r.seed,
                            r.max_depth, r.renderer)

    mod.ImageError, mod.read_image = ImageError, read_image
    monkeypatch.setitem(sys.modules, "mcrt.image_files", mod)
    return images


def test_compare_files_exit_codes(fake_imageio, tmp_path, capsys):
    # alpha = 0.01.
    a, b = biased_pair()
    fake_imageio.update({"a.exr": a, "b.exr": b, "b2.exr": synth(103, mean_image(64, 64), 1024)})
    assert compare_files("b.exr", "b2.exr", alpha=0.01) == CONSISTENT
    assert "consistent: 0 of 192" in capsys.readouterr().out

    heat, report = tmp_path / "h.png", tmp_path / "r.json"
    assert compare_files("a.exr", "b.exr", alpha=0.01, heatmap=heat, json_path=report) == DIFFERENT
    out = capsys.readouterr().out
    assert "DIFFERENT" in out and "tile (3,5)" in out and "rows 24-31 cols 40-47" in out
    assert "largest effect" in out and "min p-value" in out
    assert heat.exists() and json.loads(report.read_text())["n_rejected"] >= 1

    assert compare_files("a.exr", "missing.exr") == UNUSABLE
    assert "missing.exr: no such image" in capsys.readouterr().err


def test_compare_files_missing_variance(fake_imageio, capsys):
    # alpha = 0.01. B lacks variance: exit 2 naming B, unless it borrows A's.
    mu = mean_image(32, 32)
    a = synth(111, mu, 1024)
    b = synth(112, mu, 1024)
    fake_imageio.update({"a.exr": a, "b.png": RenderResult(b.mean, None, 0, 0, 0, ""),
                         "c.png": RenderResult(b.mean, None, 0, 0, 0, "")})
    assert compare_files("a.exr", "b.png") == UNUSABLE
    err = capsys.readouterr().err
    assert "image B (b.png) has no per-sample variance" in err and "--assume-variance-from other" in err
    assert compare_files("a.exr", "b.png", assume_variance_from_other=True) == UNUSABLE
    assert "--spp-b" in capsys.readouterr().err  # spp unknown
    assert compare_files("a.exr", "b.png", assume_variance_from_other=True, spp_b=1024) == CONSISTENT
    assert "uses image A's per-sample variance" in capsys.readouterr().out
    assert compare_files("b.png", "c.png", assume_variance_from_other=True, spp_a=8, spp_b=8) == UNUSABLE
    assert "neither image" in capsys.readouterr().err


def test_compare_reference_variance_floor_from_the_command_line(fake_imageio, capsys):
    # alpha = 0.01, seeds 121 and 122. A is a 256-spp render whose variance estimate came out low (x0.05, as when it
    # misses the rare high-weight paths), B a 16384-spp reference of the same image: only the floor keeps A honest.
    from mcrt.cli import main

    mu = mean_image(32, 32)
    a = synth(121, mu, 256)
    a.variance = a.variance * 0.05
    fake_imageio.update({"a.exr": a, "ref.exr": synth(122, mu, 16384), "nospp.png": RenderResult(a.mean, None, 0, 0, 0, "")})
    assert main(["compare", "a.exr", "ref.exr"]) == DIFFERENT
    capsys.readouterr()
    assert main(["compare", "a.exr", "ref.exr", "--reference-variance-floor"]) == CONSISTENT
    assert "raised to image B's where lower" in capsys.readouterr().out
    assert main(["compare", "a.exr", "ref.exr", "--policy", "reference-floor"]) == CONSISTENT
    assert "policy reference-floor" in capsys.readouterr().out
    assert main(["compare", "a.exr", "ref.exr", "--policy", "independent"]) == DIFFERENT
    capsys.readouterr()
    # The options the error messages name exist on the command line.
    assert main(["compare", "nospp.png", "ref.exr", "--assume-variance-from", "other"]) == UNUSABLE
    assert "--spp-a" in capsys.readouterr().err
    assert main(["compare", "nospp.png", "ref.exr", "--assume-variance-from", "other", "--spp-a", "256"]) == CONSISTENT


def test_assert_same_image(tmp_path):
    # alpha = 0.01.
    a, b = biased_pair()
    mu = mean_image(64, 64)
    assert assert_same_image(b, synth(103, mu, 1024), alpha=0.01).passed
    with pytest.raises(AssertionError) as info:
        assert_same_image(a, b, alpha=0.01, save_dir=tmp_path, name="room")
    msg = str(info.value)
    assert msg.startswith("renders differ: DIFFERENT:") and "tile (3,5)" in msg and "min p-value" in msg
    assert len(msg.splitlines()) >= 4
    for f in ("room_a.npy", "room_b.npy", "room_heatmap.png", "room.json"):
        assert (tmp_path / f).exists()
    assert np.array_equal(np.load(tmp_path / "room_a.npy"), a.mean)
    # policy= passes through: a render whose variance came out low fails against a reference unless floored.
    low, ref = synth(121, mean_image(32, 32), 256), synth(122, mean_image(32, 32), 16384)
    low.variance = low.variance * 0.05
    with pytest.raises(AssertionError, match="policy reference-floor"):
        assert_same_image(mean_shift(low, 1.05), ref, policy="reference-floor")
    with pytest.raises(AssertionError):
        assert_same_image(low, ref)
    assert assert_same_image(low, ref, policy="reference-floor").policy == "reference-floor"


def test_compare_files_with_real_exr_files(tmp_path, capsys):
    # alpha = 0.01. Round trip through mcrt.image_files (EXR keeps variance and
    # spp); a file without spp gets a hint to pass it.
    imageio = pytest.importorskip("mcrt.image_files")
    mu = mean_image(32, 32)
    a, b = synth(121, mu, 512), synth(122, mu, 512, "gamma2")
    imageio.write_exr(tmp_path / "a.exr", a)
    imageio.write_exr(tmp_path / "b.exr", b)
    assert compare_files(tmp_path / "a.exr", tmp_path / "b.exr", alpha=0.01) == CONSISTENT
    b.spp = 0
    imageio.write_exr(tmp_path / "b0.exr", b)
    assert compare_files(tmp_path / "a.exr", tmp_path / "b0.exr", alpha=0.01) == UNUSABLE
    assert "--spp-b" in capsys.readouterr().err
    assert compare_files(tmp_path / "a.exr", tmp_path / "b0.exr", alpha=0.01, spp_b=512) == CONSISTENT


def test_floor_variance_raises_only_lower_variances():
    mu = mean_image(8, 8)
    small, big = synth(1, mu, 16), synth(2, mu, 4096)
    f = floor_variance(small, big)
    assert np.array_equal(f.variance, np.maximum(small.variance, big.variance)) and np.array_equal(f.mean, small.mean)
    assert (f.variance > small.variance).any() and (f.variance == small.variance).any() and f.spp == small.spp
    with pytest.raises(StatsError):
        floor_variance(small, RenderResult(mean=big.mean, variance=None, spp=1, seed=0, max_depth=0, renderer="x"))
    with pytest.raises(StatsError, match="differ in shape"):
        floor_variance(small, synth(3, mean_image(8, 16), 16))


def mean_shift(r: RenderResult, factor: float) -> RenderResult:
    return RenderResult(r.mean * np.float32(factor), r.variance, r.spp, r.seed, r.max_depth, r.renderer)


# --------------------------------------------------------------------------
# Comparison policy
# --------------------------------------------------------------------------


def test_policy_reference_floor_is_the_floored_comparison():
    # alpha = 0.01, seeds 121 and 122 (as in the command-line test above): A's variance estimate came out low (x0.05).
    mu = mean_image(32, 32)
    a, ref = synth(121, mu, 256), synth(122, mu, 16384)
    a.variance = a.variance * 0.05
    plain = compare(a, ref, alpha=0.01)
    assert plain.policy == "independent" and not plain.passed
    assert np.array_equal(plain.t, compare_images(a, ref, alpha=0.01).t)
    floored = compare(a, ref, policy="reference-floor", alpha=0.01, tile=4, correction="bh")
    by_hand = compare_images(floor_variance(a, ref), ref, alpha=0.01, tile=4, correction="bh")
    assert floored.passed and floored.policy == "reference-floor"
    assert np.array_equal(floored.t, by_hand.t) and np.array_equal(floored.p_adjusted, by_hand.p_adjusted)
    assert "policy reference-floor" in floored.summary() and floored.to_dict()["policy"] == "reference-floor"
    assert np.array_equal(a.variance, synth(121, mu, 256).variance * 0.05)  # the caller's render is not modified
    with pytest.raises(ValueError, match="policy must be one of independent, reference-floor"):
        compare(a, ref, policy="floor")


def test_command_line_policies_are_the_policies():
    from mcrt.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command").choices["compare"]
    choices = next(a for a in sub._actions if a.option_strings == ["--policy"]).choices
    assert tuple(choices) == tuple(POLICIES)


# --------------------------------------------------------------------------
# Tiles
# --------------------------------------------------------------------------


def test_tile_sums_means_counts_and_boxes_with_partial_and_whole_tiles():
    x = np.arange(5 * 7 * 2, dtype=np.float64).reshape(5, 7, 2)
    s = tile_sums(x, 3)
    assert s.shape == (2, 3, 2)
    assert np.array_equal(s[1, 2], x[3:5, 6:7].sum(axis=(0, 1)))  # the bottom-right partial tile
    assert tile_counts(5, 7, 3).tolist() == [[9, 9, 3], [6, 6, 2]]
    assert np.allclose(tile_means(x, 3)[1, 2], x[3:5, 6:7].mean(axis=(0, 1)))
    assert np.allclose(tile_means(x, 0)[0, 0], x.mean(axis=(0, 1)))  # tile 0: the whole image
    assert tile_sums(x[:, :, 0], 0).shape == (1, 1)
    assert np.allclose(tile_means(x[:4, :6], 2), x[:4, :6].reshape(2, 2, 3, 2, 2).mean(axis=(1, 3)))  # block means
    assert tile_box(5, 7, 3, 1, 2) == (3, 5, 6, 7) and tile_box(5, 7, 0, 0, 0) == (0, 5, 0, 7)
