"""First-hit buffers for the denoiser: the albedo and the normal each pixel sees.

Open Image Denoise guides its filter by the albedo and the shading normal
of the surface a pixel sees first. Through a mirror it asks for the surface
seen in the mirror (the mirror's own flat albedo would hide the reflected
edges), so primary rays follow mirrors, up to :data:`MIRROR_BOUNCES`, with
the albedo multiplied by the mirror's reflectance; the light is white
(its emission clamped to 1). Each pixel averages ``spp`` jittered rays, the
same box filter as the render, so edges in the buffers match edges in the
image. The buffers are traced with mcrt's own geometry and host
(:class:`mcrt.host.McrtHost`): the same surfaces the render sees.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import mcrt  # noqa: F401  (sets DRJIT_LIBLLVM_PATH before drjit loads)
from mcrt.camera import Pinhole
from mcrt.geometry import Geometry
from mcrt.host import McrtHost
from mcrt.rng import WeylRng
from mcrt.scene import Scene

#: Mirror reflections followed before the surface behind them is taken.
MIRROR_BOUNCES = 4


@dataclass(frozen=True)
class Buffers:
    """(height, width, 3) float32: albedo in [0, 1], unit normals (world space) in [-1, 1]."""

    albedo: np.ndarray
    normal: np.ndarray


def first_hit_buffers(scene: Scene, camera: str, width: int, height: int, *, spp: int = 16, seed: int = 0,
                      backend: str = "llvm") -> Buffers:
    """The albedo and normal buffers of ``scene`` seen from ``camera``, ``spp`` jittered rays per pixel."""
    import drjit as dr

    from mcrt.tracer import backend_module, stream_keys

    m = backend_module(backend)
    host = McrtHost(Geometry(scene, m, "convex"))
    cam = Pinhole(scene.camera(camera), width, height)
    lanes = width * height * spp
    idx = dr.arange(m.UInt32, lanes)
    pixel = idx // spp
    rng = WeylRng.seeded(m, lanes, *(m.UInt32(k) for k in stream_keys(seed, 0)))
    d = cam.direction(m.Float(pixel % width), m.Float(pixel // width), rng.next_1d(), rng.next_1d())
    o = m.Array3f(*cam.eye)
    weight = m.Array3f(1.0)
    hit = host.intersect(o, d)
    for _ in range(MIRROR_BOUNCES):
        mirror = hit.mirror
        weight = dr.select(mirror, weight * hit.color, weight)
        d = dr.select(mirror, d - 2.0 * dr.dot(d, hit.n) * hit.n, d)
        o = dr.select(mirror, host.spawn_origin(hit), o)
        nxt = host.intersect(o, d)
        hit = _select_hit(m, mirror, nxt, hit)
    albedo = weight * dr.select(hit.light, m.Array3f(1.0), hit.color)
    dr.eval(albedo, hit.n)
    return Buffers(_pixel_mean(albedo, width, height, spp), _pixel_normal(hit.n, width, height, spp))


def _select_hit(m, mask, a, b):
    """The fields the buffers use, from hit ``a`` where ``mask``, else from ``b``."""
    import drjit as dr

    b.n = dr.select(mask, a.n, b.n)
    b.p = dr.select(mask, a.p, b.p)
    b.color = dr.select(mask, a.color, b.color)
    b.mirror = dr.select(mask, a.mirror, m.Bool(False))
    b.light = dr.select(mask, a.light, b.light)
    return b


def _numpy(v, width, height, spp) -> np.ndarray:
    return np.stack([np.asarray(v[c].numpy(), dtype=np.float64) for c in range(3)], axis=-1).reshape(height, width, spp, 3)


def _pixel_mean(v, width, height, spp) -> np.ndarray:
    return np.clip(_numpy(v, width, height, spp).mean(axis=2), 0.0, 1.0).astype(np.float32)


def _pixel_normal(n, width, height, spp) -> np.ndarray:
    """The mean normal of a pixel's rays, renormalised (an edge pixel's normal lies between its surfaces')."""
    mean = _numpy(n, width, height, spp).mean(axis=2)
    norm = np.linalg.norm(mean, axis=-1, keepdims=True)
    return np.where(norm > 1e-6, mean / np.maximum(norm, 1e-6), 0.0).astype(np.float32)
