"""The estimator's own light sample, on both hosts, against closed forms.

:meth:`mcrt.estimator.PathEstimator.light_sample` returns Le V G / p_A for a
point y sampled on the light, G = cos_x cos_y / d^2. Its expectation is known
in closed form where nothing blocks the light:

- with the receiver's cosine left out (option ``nee_cos_surface=False``),
  E[Le cos_y / (d^2 p_A)] = Le Omega, Omega the light's solid angle seen from
  x (Van Oosterom and Strackee): this checks the area-to-solid-angle Jacobian
  d^2 / (A cos_y) of :mod:`mcrt.light` and of Mitsuba's emitter sampling;
- with every factor, E = Le times Lambert's polygon irradiance factor
  (:func:`mcrt.closed_form.polygon_irradiance`).

The same tests run the kernel's code with one factor removed (the
catalogued bugs' options) and must fail. z-tests at level 0.01 on 200 000
samples, fixed seeds (mcrt: Weyl streams keyed (9, 7); Mitsuba: its
independent sampler seeded 9).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import norm

import mcrt
from mcrt.closed_form import polygon_irradiance
from mcrt.estimator import PathEstimator
from mcrt.options import EstimatorOptions
from mcrt.sampling import balance_heuristic

import drjit as dr  # noqa: E402  (after mcrt: it sets DRJIT_LIBLLVM_PATH)

ALPHA = 0.01
N = 200_000
# Receivers (point, unit normal) that see the whole light with nothing in between.
RECEIVERS = [((5.0, 0.0, -5.0), (0.0, 0.0, 1.0)), ((1.0, 5.0, 2.0), (0.0, -0.6, 0.8)), ((6.5, 0.3, 4.0), (-0.6, 0.0, 0.8))]


def solid_angle(x: np.ndarray, polygon: np.ndarray) -> float:
    """Solid angle of a convex polygon seen from x: a fan of triangles (Van Oosterom and Strackee 1983)."""
    total = 0.0
    r = polygon - x
    for i in range(1, len(r) - 1):
        a, b, c = r[0], r[i], r[i + 1]
        la, lb, lc = np.linalg.norm(a), np.linalg.norm(b), np.linalg.norm(c)
        num = abs(a @ np.cross(b, c))
        den = la * lb * lc + (a @ b) * lc + (a @ c) * lb + (b @ c) * la
        total += 2.0 * math.atan2(num, den)
    return total


@pytest.fixture(scope="module")
def scene():
    return mcrt.load_scene()


def _mcrt_host(scene):
    import drjit.llvm as m

    from mcrt.geometry import Geometry
    from mcrt.host import McrtHost
    from mcrt.rng import WeylRng

    return McrtHost(Geometry(scene, m, "convex")), WeylRng.seeded(m, N, m.UInt32(9), m.UInt32(7))


def _mitsuba_host(scene):
    import mitsuba as mi

    from mcrt.mitsuba_scene import load_mitsuba_scene
    from mcrt.plugins import MitsubaHost

    host = MitsubaHost(load_mitsuba_scene(scene, "near", 8, 8))
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(9, N)
    return host, sampler


HOSTS = {"mcrt": _mcrt_host, "mitsuba": _mitsuba_host}


def light_sample_mean(scene, host_name, x, n, **options):
    """Mean and standard error of N light samples at x with normal n, green channel, on one host."""
    host, sampler = HOSTS[host_name](scene)
    est = PathEstimator(host, EstimatorOptions.build(**options))
    origin = host.Vector3f(*(dr.full(host.Float, c, N) for c in x))
    value = est.light_sample(origin, host.Vector3f(*n), sampler, host.Bool(True))
    g = np.asarray(value[1].numpy(), dtype=np.float64)
    return g.mean(), g.std(ddof=1) / math.sqrt(N)


def _z_ok(mean, se, expected):
    return abs(mean - expected) / se < norm.isf(ALPHA / 2)


@pytest.mark.parametrize("host", HOSTS)
@pytest.mark.parametrize("x, n", RECEIVERS)
def test_light_sample_integrates_to_the_solid_angle(scene, host, x, n):
    """Without the receiver's cosine the sample's mean is Le Omega: the Jacobian d^2 / (A cos_y) is right."""
    le = scene.light.radiance[1]
    mean, se = light_sample_mean(scene, host, x, n, nee_cos_surface=False)
    omega = solid_angle(np.asarray(x), scene.light.corners())
    assert _z_ok(mean, se, le * omega), (mean, le * omega)


@pytest.mark.parametrize("host", HOSTS)
@pytest.mark.parametrize("x, n", RECEIVERS)
def test_light_sample_integrates_to_lamberts_irradiance(scene, host, x, n):
    """With every factor the mean is the irradiance Le Phi(x, n) of Lambert's polygon formula."""
    mean, se = light_sample_mean(scene, host, x, n)
    expected = polygon_irradiance(np.array([x]), np.array([n]), scene.light.corners(), scene.light.radiance[1])[0]
    assert _z_ok(mean, se, expected), (mean, expected)


@pytest.mark.parametrize("host", HOSTS)
@pytest.mark.parametrize("removed", [{"nee_cos_light": False}, {"nee_inv_dist2": False}, {"nee_pdf_area": False}],
                         ids=["cos_y", "inv_dist2", "pdf_area"])
def test_the_same_test_fails_with_a_factor_removed(scene, host, removed):
    """The kernel's light sample with cos_y, 1/d^2 or the pdf's area taken out misses the solid angle (x = (1, 5, 2))."""
    x, n = RECEIVERS[1]
    le = scene.light.radiance[1]
    mean, se = light_sample_mean(scene, host, x, n, nee_cos_surface=False, **removed)
    assert not _z_ok(mean, se, le * solid_angle(np.asarray(x), scene.light.corners()))


def test_balance_heuristic_weights_add_up_to_one():
    from drjit.llvm import Float

    p_a, p_b = Float(0.1, 2.0, 5.0, 0.0), Float(0.3, 0.0, 5.0, 1.0)
    w = balance_heuristic(4, p_a, 1, p_b) + balance_heuristic(1, p_b, 4, p_a)
    assert np.allclose(w.numpy(), 1.0)
    assert np.allclose(balance_heuristic(4, p_a, 1, p_b).numpy(), [0.4 / 0.7, 1.0, 0.8, 0.0])
