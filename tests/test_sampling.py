"""Chi-square goodness-of-fit tests of the samplers.

Each sampler is checked twice: by the project's own test (mcrt.stats.chi2_gof,
bins pooled below 5 expected counts) against the pdf integrated exactly over
the bins, and by Mitsuba's ChiSquareTest (a peer implementation) over the
sphere of directions. Level 0.01 per test, fixed seeds; the mutant warps must
fail the same tests, so each test is shown able to fail.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import mcrt  # noqa: F401  (libLLVM before drjit)
from mcrt.sampling import (
    cosine_about_normal,
    cosine_hemisphere_pdf,
    square_to_cosine_hemisphere,
    square_to_uniform_ball,
    square_to_uniform_hemisphere,
)
from mcrt.stats import chi2_gof

ALPHA = 0.01
N = 1_000_000


def _uniform(seed: int, n: int = N, dims: int = 2) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return [rng.random(n, dtype=np.float32) for _ in range(dims)]


def _own_hemisphere_test(x, y, z) -> float:
    """p-value of directions against the cosine pdf, binned in (cos theta, phi), 20 x 40 bins.

    Under p = cos(theta)/pi, cos(theta) has CDF z^2 and phi is uniform.
    """
    z_edges = np.linspace(0, 1, 21)
    phi_edges = np.linspace(-math.pi, math.pi, 41)
    phi = np.arctan2(y, x)
    counts, _, _ = np.histogram2d(z, phi, bins=[z_edges, phi_edges])
    p_z = np.diff(z_edges**2)
    expected = np.outer(p_z, np.diff(phi_edges) / (2 * math.pi)) * len(z)
    return chi2_gof(counts.ravel(), expected.ravel())[2]


def _warp(fn, *u):
    from drjit.llvm import Float

    out = fn(*(Float(a) for a in u))
    return [np.asarray(c.numpy() if hasattr(c, "numpy") else c, dtype=np.float64) for c in out]


def test_cosine_hemisphere_own_chi2():
    x, y, z = _warp(square_to_cosine_hemisphere, *_uniform(1))
    assert np.allclose(x * x + y * y + z * z, 1, atol=1e-5)
    assert _own_hemisphere_test(x, y, z) > ALPHA


@pytest.mark.parametrize("normal", [(0.0, 0.0, 1.0), (0.0, 0.0, -1.0), (0.48, -0.6, 0.64)])
def test_cosine_about_normal_own_chi2(normal):
    """The frame-free warp the tracer uses, in the frame of its normal (the pole and a tilted normal)."""
    u1, u2 = _uniform(6)
    n = np.array(normal)
    w = np.stack(_warp(lambda a, b: cosine_about_normal(a, b, tuple(float(c) for c in normal)), u1, u2), axis=1)
    assert np.allclose(np.linalg.norm(w, axis=1), 1, atol=1e-5)
    s = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
    s /= np.linalg.norm(s)
    t = np.cross(n, s)
    assert _own_hemisphere_test(w @ s, w @ t, w @ n) > ALPHA


def test_uniform_hemisphere_fails_the_cosine_test():
    """Mutant uniform_as_cosine: uniform directions are not cosine-distributed."""
    x, y, z = _warp(square_to_uniform_hemisphere, *_uniform(2))
    assert _own_hemisphere_test(x, y, z) < 1e-6


def test_ball_plus_normal_fails_the_cosine_test():
    """Mutant ball_plus_normal: a point inside the ball plus the normal is not cosine-distributed."""
    bx, by, bz = _warp(square_to_uniform_ball, *_uniform(3, dims=3))
    v = np.stack([bx, by, bz + 1.0], axis=1)
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    assert _own_hemisphere_test(*v.T) < 1e-6


@pytest.fixture(autouse=True)
def _in_tmp(monkeypatch, tmp_path):
    """Mitsuba's chi-square test writes chi2_data.py into the working directory when it rejects."""
    monkeypatch.chdir(tmp_path)


@pytest.fixture(scope="module")
def mi():
    import mitsuba

    mitsuba.set_variant("llvm_ad_rgb")
    return mitsuba


def _mitsuba_chi2(mi, sample, pdf, seed):
    from mitsuba.chi2 import ChiSquareTest, SphericalDomain

    test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample, pdf_func=pdf, sample_dim=2, sample_count=N, res=64, seed=seed)
    return test.run(significance_level=ALPHA, quiet=True), test


def test_cosine_hemisphere_mitsuba_chi2(mi):
    def sample(s):
        return mi.Vector3f(*square_to_cosine_hemisphere(s.x, s.y))

    def pdf(v):
        return cosine_hemisphere_pdf(v.z)

    ok, test = _mitsuba_chi2(mi, sample, pdf, seed=4)
    assert ok, test.messages


def test_cosine_about_normal_mitsuba_chi2(mi):
    n = (0.48, -0.6, 0.64)

    def sample(s):
        return mi.Vector3f(*cosine_about_normal(s.x, s.y, n))

    def pdf(v):
        return cosine_hemisphere_pdf(v.x * n[0] + v.y * n[1] + v.z * n[2])

    ok, test = _mitsuba_chi2(mi, sample, pdf, seed=7)
    assert ok, test.messages


def test_mitsuba_chi2_rejects_a_wrong_pdf(mi):
    """The peer test can fail too: uniform directions against the cosine pdf."""

    def sample(s):
        return mi.Vector3f(*square_to_uniform_hemisphere(s.x, s.y))

    def pdf(v):
        return cosine_hemisphere_pdf(v.z)

    ok, _ = _mitsuba_chi2(mi, sample, pdf, seed=5)
    assert not ok
