"""The kernel's pixel-to-ray mapping (mcrt.camera.Pinhole.direction, on Dr.Jit arrays as the tracer calls it).

Jittered pixel samples must give directions of density 1 / (A_film cos^3 theta)
over the film seen from the eye: E[A_film cos^3 theta] over the directions is
the film's solid angle (Van Oosterom and Strackee), and the directions'
film coordinates are uniform (own chi-square over 32 x 16 cells, two per pixel and axis). z- and
chi-square tests at level 0.01, 200 000 samples, NumPy seed 11. The same
tests fail for the no-jitter camera and for a film whose height is not
scaled by H / W.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import norm

import mcrt
from mcrt.camera import Pinhole, primary_directions
from mcrt.stats import chi2_gof
from test_light import solid_angle

import drjit as dr  # noqa: E402,F401  (after mcrt: it sets DRJIT_LIBLLVM_PATH)

ALPHA = 0.01
N = 200_000
W, H = 16, 8  # not square: the vertical half-size is t_x H / W


def _samples():
    rng = np.random.default_rng(11)
    u1, u2 = rng.random(N), rng.random(N)
    i, j = np.floor(u1 * W), np.floor(u2 * H)
    return i, j, u1 * W - i, u2 * H - j


def _kernel_directions(pinhole: Pinhole) -> np.ndarray:
    from drjit.llvm import Float

    d = pinhole.direction(*(Float(a.astype(np.float32)) for a in _samples()))
    return np.stack([np.asarray(c.numpy(), dtype=np.float64) for c in d], axis=1)


def _film(camera):
    """The film's true centre and half-axes (one unit in front of the eye), from the camera's definition."""
    right, up, forward = camera.frame()
    tx = math.tan(math.radians(camera.fov_x_deg) / 2)
    return forward, tx * right, tx * H / W * up


def _solid_angle_ok(camera, d) -> bool:
    center, hr, hu = _film(camera)
    cos_t = d @ center
    inv_pdf = 4 * np.linalg.norm(hr) * np.linalg.norm(hu) * cos_t**3
    omega = solid_angle(np.zeros(3), np.array([center - hr + hu, center + hr + hu, center + hr - hu, center - hr - hu]))
    return abs(inv_pdf.mean() - omega) / (inv_pdf.std(ddof=1) / math.sqrt(N)) < norm.isf(ALPHA / 2)


def _uniform_on_film(camera, d) -> bool:
    center, hr, hu = _film(camera)
    p = d / (d @ center)[:, None] - center
    sx, sy = p @ hr / (hr @ hr), p @ hu / (hu @ hu)
    # Two cells per pixel and axis: pixel-centre samples would fill only a quarter of them.
    counts, _, _ = np.histogram2d(sx, sy, bins=[2 * W, 2 * H], range=[[-1, 1], [-1, 1]])
    return chi2_gof(counts.ravel(), np.full(4 * W * H, N / (4 * W * H)))[2] > ALPHA


@pytest.fixture(scope="module")
def scene():
    return mcrt.load_scene()


@pytest.mark.parametrize("camera", ["near", "far"])
def test_kernel_directions_cover_the_film_uniformly(scene, camera):
    cam = scene.camera(camera)
    d = _kernel_directions(Pinhole(cam, W, H))
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-6)
    assert _solid_angle_ok(cam, d) and _uniform_on_film(cam, d)


def test_the_same_tests_fail_without_jitter_or_with_a_wrong_aspect(scene):
    cam = scene.camera("near")
    assert not _uniform_on_film(cam, _kernel_directions(Pinhole(cam, W, H, jitter=False)))
    square = Pinhole(cam, W, H)
    square.half_up = tuple(2.0 * c for c in square.half_up)  # t_y = t_x: the H / W factor removed
    assert not _solid_angle_ok(cam, _kernel_directions(square))


def test_scene_md_pixel_mapping(scene):
    """Pixel (i, j) + (u, v) goes through (0, 1 - 2 (i + u) / W, 1 - 2 (j + v) / H) for the near camera."""
    i, j, u, v = (a[:1000] for a in _samples())
    d = primary_directions(scene.camera("near"), W, W, i, j, u, v)  # square: the plane point is as scene.md says
    p = d / d[:, :1]  # the ray's point on the plane x = 0, one unit in front of the eye at x = -1
    assert np.allclose(p[:, 1], 1 - 2 * (i + u) / W, atol=1e-12) and np.allclose(p[:, 2], 1 - 2 * (j + v) / W, atol=1e-12)
    # The NumPy evaluation is the kernel's code: the same directions in float32.
    from drjit.llvm import Float

    k = Pinhole(scene.camera("near"), W, W).direction(*(Float(a.astype(np.float32)) for a in (i, j, u, v)))
    assert np.allclose(np.stack([c.numpy() for c in k], axis=1), d, atol=1e-6)
