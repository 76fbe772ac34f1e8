"""The per-path random numbers (mcrt.rng): exactness against a NumPy twin, and their statistics.

Every statistical test here is a chi-square test at significance level
ALPHA = 1e-4 on fixed keys, so it is deterministic: it always passes or always
fails. Each has a power check: the same statistic rejects a generator with a
known defect (the Weyl sequence without its mixer: within a lane, second
differences u_k - 2 u_k+1 + u_k+2 vanish mod 1; with one increment for all
lanes, successive draws also lie on a line).
"""

import numpy as np
import pytest
from scipy import stats

import mcrt  # noqa: F401
import drjit as dr
import drjit.llvm as m

from mcrt.rng import FLOAT_ONE_BITS, SAMPLE_MULT, SampleStreams, WeylRng, mix32
from mcrt.tracer import stream_keys

ALPHA = 1e-4
LANES = 1 << 16
DRAWS = 8
KEYS = stream_keys(7, 0)  # seed 7, pass 0: any fixed keys will do


def numpy_draws(lanes, draws, key0, key1, mixer=mix32, shared_step=None):
    """The generator written again over NumPy uint32 (wrap-around arithmetic): (lanes, draws) floats.

    ``mixer`` and ``shared_step`` (one increment for every lane) build the defective variants.
    """
    i = np.arange(lanes, dtype=np.uint32)
    with np.errstate(over="ignore"):
        state = mix32(i ^ np.uint32(key0))
        step = mix32(state + np.uint32(key1)) | np.uint32(1)
        if shared_step is not None:
            step = np.full(lanes, shared_step, np.uint32)
        out = np.empty((lanes, draws), np.float32)
        for k in range(draws):
            state = state + step
            bits = (mixer(state) >> np.uint32(9)) | np.uint32(FLOAT_ONE_BITS)
            out[:, k] = bits.view(np.float32) - np.float32(1.0)
    return out


def drjit_draws(lanes, draws, key0, key1):
    rng = WeylRng.seeded(m, lanes, dr.opaque(m.UInt32, key0), dr.opaque(m.UInt32, key1))
    return np.stack([rng.next_1d().numpy() for _ in range(draws)], axis=1)


@pytest.fixture(scope="module")
def draws():
    return drjit_draws(LANES, DRAWS, *KEYS)


def chi2_uniform_p(u, bins):
    counts = np.bincount(np.minimum((u * bins).astype(np.int64), bins - 1), minlength=bins)
    return stats.chisquare(counts).pvalue


def chi2_pairs_p(a, b, bins):
    cell = np.minimum((a * bins).astype(np.int64), bins - 1) * bins + np.minimum((b * bins).astype(np.int64), bins - 1)
    return stats.chisquare(np.bincount(cell, minlength=bins * bins)).pvalue


def test_drjit_and_numpy_agree_bit_for_bit(draws):
    assert np.array_equal(draws, numpy_draws(LANES, DRAWS, *KEYS))


def test_range(draws):
    assert draws.dtype == np.float32 and draws.min() >= 0.0 and draws.max() < 1.0


def test_keys_select_different_streams():
    a = drjit_draws(1024, 2, *stream_keys(7, 0))
    b = drjit_draws(1024, 2, *stream_keys(7, 1))
    c = drjit_draws(1024, 2, *stream_keys(8, 0))
    assert np.mean(a == b) < 0.01 and np.mean(a == c) < 0.01


def test_uniform_in_every_draw(draws):
    for k in range(DRAWS):
        assert chi2_uniform_p(draws[:, k], 256) > ALPHA, f"draw {k}"


def test_successive_draws_independent(draws):
    # 32 x 32 cells of (u_k, u_k+1): draws on a line, as with one increment for all lanes, fail it.
    for k in range(DRAWS - 1):
        assert chi2_pairs_p(draws[:, k], draws[:, k + 1], 32) > ALPHA, f"draws {k}, {k + 1}"


def second_differences(u):
    """u_k - 2 u_k+1 + u_k+2 mod 1 for each k: uniform when the draws are independent uniforms."""
    return np.mod(u[:, :-2].astype(np.float64) - 2.0 * u[:, 1:-1] + u[:, 2:], 1.0)


def test_second_differences_uniform(draws):
    v = second_differences(draws)
    for k in range(v.shape[1]):
        assert chi2_uniform_p(v[:, k], 256) > ALPHA, f"draws {k} to {k + 2}"


def test_neighbouring_lanes_independent(draws):
    # Lanes i and i + 1 are two samples of one pixel: their numbers must not be related.
    for k in (0, DRAWS - 1):
        assert chi2_pairs_p(draws[:-1:2, k], draws[1::2, k], 32) > ALPHA, f"draw {k}"


def block_variance_p(u, block):
    """Two-sided chi-square p of the sums of ``block`` consecutive lanes against independent uniforms (variance block/12)."""
    sums = u.astype(np.float64).reshape(-1, block).sum(axis=1)
    statistic = np.sum((sums - block / 2) ** 2) / (block / 12)
    dof = len(sums)
    return 2 * min(stats.chi2.sf(statistic, dof), stats.chi2.cdf(statistic, dof))


def test_samples_of_one_pixel_independent(draws):
    """Consecutive lanes are the samples of one pixel: their sums must vary as independent samples' do.

    A per-pixel variance estimate assumes it. Dr.Jit's PCG32 seeded with
    consecutive stream indices (how mcrt seeded it before mcrt.rng) fails this:
    sums of 256 lanes vary more or less than independent ones' do, depending
    on the draw (the power check below).
    """
    for k in range(DRAWS):
        assert block_variance_p(draws[:, k], 256) > ALPHA, f"draw {k}"


def test_block_variance_has_power_against_consecutive_pcg32_streams():
    rng = m.PCG32(LANES, dr.opaque(m.UInt64, 0x853C49E6748FEA9B), dr.opaque(m.UInt64, 0xDA3E39CB94B95BDB))
    p = [block_variance_p(rng.next_float32().numpy(), 256) for _ in range(DRAWS)]
    assert min(p) < ALPHA


def test_statistics_have_power():
    """The tests reject the Weyl sequence without its mixer (u_k = top bits of s + k g)."""
    bare = numpy_draws(LANES, 3, *KEYS, mixer=lambda x: x)
    assert chi2_uniform_p(second_differences(bare)[:, 0], 256) < ALPHA
    shared = numpy_draws(LANES, 2, *KEYS, mixer=lambda x: x, shared_step=0x9E3779B9)
    assert chi2_pairs_p(shared[:, 0], shared[:, 1], 32) < ALPHA


# The streams the tracer draws from: one per pixel sample (mcrt.rng.SampleStreams).
PIXELS = 1 << 12
SAMPLES = 16


def numpy_sample_draws(pixel, sample, key0, key1, draws, sample_mult=SAMPLE_MULT):
    """SampleStreams written again over NumPy uint32: (lanes, draws) floats of the streams (pixel[i], sample[i])."""
    with np.errstate(over="ignore"):
        h0, h1 = mix32(pixel ^ np.uint32(key0)), mix32(pixel ^ np.uint32(key1))
        g = np.uint32(sample_mult)
        state, step = mix32(h0 + sample * g), mix32(h1 + sample * g) | np.uint32(1)
        out = np.empty((len(pixel), draws), np.float32)
        for k in range(draws):
            state = state + step
            out[:, k] = ((mix32(state) >> np.uint32(9)) | np.uint32(FLOAT_ONE_BITS)).view(np.float32) - np.float32(1.0)
    return out


def pixel_sample_grid():
    """(pixel, sample) of every lane, samples of one pixel consecutive: pixel-major, as a pixel's samples are summed."""
    pixel = np.repeat(np.arange(PIXELS, dtype=np.uint32), SAMPLES)
    sample = np.tile(np.arange(SAMPLES, dtype=np.uint32), PIXELS)
    return pixel, sample


def drjit_sample_draws(pixel, sample, key0, key1, draws):
    rng = SampleStreams.start(m.UInt32(pixel), m.UInt32(sample), dr.opaque(m.UInt32, key0), dr.opaque(m.UInt32, key1))
    return np.stack([rng.next_1d().numpy() for _ in range(draws)], axis=1)


@pytest.fixture(scope="module")
def sample_draws():
    return drjit_sample_draws(*pixel_sample_grid(), *KEYS, DRAWS)


def test_sample_streams_agree_with_numpy_bit_for_bit(sample_draws):
    assert np.array_equal(sample_draws, numpy_sample_draws(*pixel_sample_grid(), *KEYS, DRAWS))


def test_restart_is_the_next_samples_stream():
    """A lane that moves on (restart) draws what a fresh stream of (pixel, sample + 1) draws: tiling cannot matter."""
    pixel, sample = pixel_sample_grid()
    rng = SampleStreams.start(m.UInt32(pixel), m.UInt32(sample), dr.opaque(m.UInt32, KEYS[0]), dr.opaque(m.UInt32, KEYS[1]))
    rng.next_1d()
    moved = m.Bool(sample % 2 == 0)
    rng.restart(moved)
    after = np.stack([rng.next_1d().numpy() for _ in range(2)], axis=1)
    fresh = numpy_sample_draws(pixel, sample + 1, *KEYS, 2)
    stayed = numpy_sample_draws(pixel, sample, *KEYS, 3)[:, 1:]
    even = sample % 2 == 0
    assert np.array_equal(after[even], fresh[even]) and np.array_equal(after[~even], stayed[~even])


def test_sample_streams_uniform_and_successive_draws_independent(sample_draws):
    for k in range(DRAWS):
        assert chi2_uniform_p(sample_draws[:, k], 256) > ALPHA, f"draw {k}"
    for k in range(DRAWS - 1):
        assert chi2_pairs_p(sample_draws[:, k], sample_draws[:, k + 1], 32) > ALPHA, f"draws {k}, {k + 1}"


def test_samples_of_one_pixel_are_independent_streams(sample_draws):
    """Samples s and s + 1 of one pixel, and the sums of a pixel's samples, behave as independent uniforms."""
    for k in (0, DRAWS - 1):
        assert chi2_pairs_p(sample_draws[:-1:2, k], sample_draws[1::2, k], 32) > ALPHA, f"draw {k}"
        assert block_variance_p(sample_draws[:, k], SAMPLES) > ALPHA, f"draw {k}"


def test_neighbouring_pixels_are_independent_streams(sample_draws):
    """Sample s of pixel p and of pixel p + 1: neighbouring pixels must not share structure."""
    by_pixel = sample_draws.reshape(PIXELS, SAMPLES, DRAWS)
    for k in (0, DRAWS - 1):
        a, b = by_pixel[:-1:2, :, k].ravel(), by_pixel[1::2, :, k].ravel()
        assert chi2_pairs_p(a, b, 32) > ALPHA, f"draw {k}"


def test_sample_stream_statistics_have_power():
    """Without the sample's share in the increment (multiplier 0), a pixel's samples are one stream repeated: rejected."""
    same = numpy_sample_draws(*pixel_sample_grid(), *KEYS, 1, sample_mult=0)
    assert block_variance_p(same[:, 0], SAMPLES) < ALPHA
