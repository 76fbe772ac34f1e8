"""The same scene in Mitsuba 3, rendered deterministically with mean and variance.

Everything Mitsuba sees is built from a :class:`mcrt.scene.Scene` and nothing
else (scene.md, "Building it in Mitsuba 3"):

- every flat :class:`~mcrt.scene.Surface` (walls, floor, ceiling, tetrahedron,
  light) becomes an ``mi.Mesh`` filled from its triangles, so both renderers
  trace the very same triangles;
- Lambertian -> ``twosided`` around ``diffuse`` (``diffuse`` alone is
  one-sided); mirror -> ``conductor`` with material ``none``; the light's
  rectangle -> a black ``diffuse`` plus an ``area`` emitter, wound so that its
  geometric normal is ``light.normal`` (an ``area`` emitter emits only on the
  side its shape's normal points to);
- the camera -> ``perspective`` with ``fov_axis`` x, ``look_at(eye, eye +
  forward, up)``, a ``box`` reconstruction filter;
- the integrator -> ``path`` with ``max_depth``, ``rr_depth`` and
  ``hide_emitters`` false.

:func:`render_mitsuba` does not call ``mi.render``: the film accumulates
samples with atomic scatter-adds whose order varies from run to run, so its
images are not reproducible bit for bit, and it gives no variance. Instead each
pass traces a wavefront of W H n lanes laid out pixel-major (lane = pixel n +
s), with the pixel sample at film position ((i + u) / W, (j + v) / H), and
reduces it per pixel with ``dr.block_sum`` (a deterministic reduction kernel)
into the sums of x and x^2 that :func:`mcrt.film.run_passes`, the pass loop
of every renderer, turns into

    mean = S1 / n,    var = (S2 - S1^2 / n) / (n - 1).

Pass k of a render with seed s seeds Mitsuba's ``independent`` sampler with a
32-bit hash of (s, k), so passes and seeds draw independent streams.

:func:`render_with_variance` renders *any* Mitsuba scene (a dictionary, a
loaded scene, an XML file) with any of its integrators through the same
passes (:func:`_run`), recording the integrator, its max depth, the camera
(:func:`camera_id`) and the scene's hash (:func:`mitsuba_scene_hash`).
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import time
from pathlib import Path
from typing import Any

import numpy as np

import mcrt  # noqa: F401  (sets DRJIT_LIBLLVM_PATH before drjit is imported)
import drjit as dr
import mitsuba as mi

from mcrt.film import Progress, RenderResult, run_passes, samples_per_pass
from mcrt.samplers import PixelSampler, replicate_pass_size, replicate_passes, replicate_variance_scale
from mcrt.scene import Camera, Lambertian, Mirror, RenderSettings, Scene, Surface

VARIANTS = {"llvm": "llvm_ad_rgb", "cuda": "cuda_ad_rgb"}
_JIT_BACKENDS = {"llvm": dr.JitBackend.LLVM, "cuda": dr.JitBackend.CUDA}


# --------------------------------------------------------------------------
# Variant
# --------------------------------------------------------------------------


def variant_for(backend: str) -> str:
    """The Mitsuba variant for a Dr.Jit backend: 'llvm' -> 'llvm_ad_rgb', 'cuda' -> 'cuda_ad_rgb'.

    Raises ``ValueError`` for an unknown backend and a one-line
    ``RuntimeError`` when the variant cannot run here (not compiled into this
    Mitsuba, or no GPU / no libLLVM).
    """
    if backend not in VARIANTS:
        raise ValueError(f"unknown backend {backend!r} (have {', '.join(VARIANTS)})")
    variant = VARIANTS[backend]
    if variant not in mi.variants():
        raise RuntimeError(f"Mitsuba {mi.__version__} was built without the {variant} variant")
    if backend == "llvm":
        from mcrt.llvm import require_llvm

        require_llvm()
    if not dr.has_backend(_JIT_BACKENDS[backend]):
        what = "no CUDA GPU or driver found" if backend == "cuda" else "Dr.Jit could not load libLLVM"
        raise RuntimeError(f"Mitsuba variant {variant} is unavailable on this machine: {what}")
    return variant


def _use(backend: str) -> str:
    """Select the variant for ``backend`` (mi.set_variant is global and cheap when unchanged)."""
    variant = variant_for(backend)
    if mi.variant() != variant:
        mi.set_variant(variant)
    return variant


# --------------------------------------------------------------------------
# Scene description
# --------------------------------------------------------------------------


def _rgb(value) -> dict[str, Any]:
    return {"type": "rgb", "value": [float(x) for x in value]}


def _bsdf_dict(material: Lambertian | Mirror | None) -> dict[str, Any]:
    """Mitsuba BSDF for a material; None is the light's black, non-reflecting surface."""
    if material is None:
        return {"type": "diffuse", "reflectance": _rgb((0.0, 0.0, 0.0))}
    if isinstance(material, Lambertian):
        return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": _rgb(material.albedo)}}
    if isinstance(material, Mirror):
        return {"type": "conductor", "material": "none", "specular_reflectance": _rgb(material.reflectance)}
    raise TypeError(f"no Mitsuba BSDF for material {material!r}")


def _mesh(surface: Surface, bsdf: dict[str, Any], emitter: dict[str, Any] | None = None) -> "mi.Mesh":
    """An ``mi.Mesh`` with one face per triangle of ``surface`` (3 vertices each, face normals).

    The geometric normal of face (p0, p1, p2) is (p1 - p0) x (p2 - p0), the
    winding used by :meth:`Scene.surfaces`.
    """
    tris = np.asarray(surface.triangles, dtype=np.float64)
    n_faces = tris.shape[0]
    props = mi.Properties()
    props["bsdf"] = mi.load_dict(bsdf)
    if emitter is not None:
        props["emitter"] = mi.load_dict(emitter)
    mesh = mi.Mesh(surface.name, 3 * n_faces, n_faces, props)
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(tris.reshape(-1).astype(np.float32))
    params["faces"] = mi.UInt32(np.arange(3 * n_faces, dtype=np.uint32))
    params.update()  # recomputes the bounding box and the area distribution
    return mesh


def _light_surface(surface: Surface, normal) -> Surface:
    """The light's triangles wound so that every face normal is ``normal`` (the emitting side)."""
    tris = np.asarray(surface.triangles, dtype=np.float64)
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    flip = n @ np.asarray(normal, dtype=np.float64) < 0
    tris = np.where(flip[:, None, None], tris[:, [0, 2, 1]], tris)
    return Surface(surface.name, tris, surface.material)


def sensor_dict(camera: Camera, width: int, height: int, spp: int = 4, scene_size: float = 1.0) -> dict[str, Any]:
    """``perspective`` sensor with the scene.md pixel mapping (box filter, independent sampler).

    The clip planes scale with the scene (1e-6 and 1e3 times its size):
    Mitsuba's absolute defaults (0.01, 1e4) cut a scene scaled by 1e-3 or 1e3.
    """
    eye = np.asarray(camera.eye, dtype=np.float64)
    target = eye + np.asarray(camera.forward, dtype=np.float64)
    return {
        "type": "perspective",
        "fov_axis": "x",
        "fov": float(camera.fov_x_deg),
        "near_clip": 1e-6 * scene_size,
        "far_clip": 1e3 * scene_size,
        "to_world": mi.ScalarTransform4f().look_at(origin=eye.tolist(), target=target.tolist(), up=[float(x) for x in camera.up]),
        "film": {
            "type": "hdrfilm",
            "width": int(width),
            "height": int(height),
            "pixel_format": "rgb",
            "rfilter": {"type": "box"},
        },
        "sampler": {"type": "independent", "sample_count": int(spp)},
    }


def scene_dict(
    scene: Scene,
    camera_name: str | None,
    width: int,
    height: int,
    max_depth: int,
    integrator: str | dict[str, Any] = "path",
    rr_depth: int = 5,
    *,
    spp: int | None = None,
    backend: str = "llvm",
) -> dict[str, Any]:
    """A dictionary for ``mi.load_dict`` describing ``scene`` seen by one camera.

    The meshes in it are ``mi.Mesh`` objects, which exist only in a variant:
    this selects the variant of ``backend``. ``spp`` (default
    ``scene.render.spp``) only sets the sampler's sample count, used when the
    scene is given to ``mi.render``; :func:`render_mitsuba` ignores it.
    ``integrator`` is a plugin name, or a dictionary whose entries (``type``
    included) extend and override ``max_depth``, ``rr_depth`` and
    ``hide_emitters``.
    """
    _use(backend)
    camera = scene.camera(camera_name)
    spec = {"type": integrator} if isinstance(integrator, str) else dict(integrator)
    d: dict[str, Any] = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": int(max_depth), "rr_depth": int(rr_depth), "hide_emitters": False, **spec},
        "sensor": sensor_dict(camera, width, height, scene.render.spp if spp is None else spp, scene.room.size()),
    }
    light = scene.light
    for s in scene.surfaces():
        if s.name in d:
            raise ValueError(f"two surfaces named {s.name!r}")
        if s.material is None:  # the light's rectangle
            emitter = {"type": "area", "radiance": _rgb(light.radiance)}
            d[s.name] = _mesh(_light_surface(s, light.normal), _bsdf_dict(None), emitter)
        else:
            d[s.name] = _mesh(s, _bsdf_dict(s.material))
    for sph in scene.spheres():
        if sph.name in d:
            raise ValueError(f"two objects named {sph.name!r}")
        d[sph.name] = {
            "type": "sphere",
            "center": [float(x) for x in sph.center],
            "radius": float(sph.radius),
            "bsdf": _bsdf_dict(sph.material),
        }
    return d


def load_mitsuba_scene(
    scene: Scene,
    camera_name: str | None = None,
    width: int | None = None,
    height: int | None = None,
    max_depth: int | None = None,
    rr_depth: int | None = None,
    backend: str = "llvm",
    integrator: str | dict[str, Any] = "path",
) -> "mi.Scene":
    """``mi.load_dict(scene_dict(...))`` with defaults from ``scene.render``."""
    s = scene.settings(camera=camera_name, width=width, height=height, max_depth=max_depth, rr_depth=rr_depth)
    return mi.load_dict(
        scene_dict(scene, s.camera, s.width, s.height, s.max_depth, integrator, rr_depth=s.rr_depth, spp=s.spp, backend=backend)
    )


# --------------------------------------------------------------------------
# Rays and rendering
# --------------------------------------------------------------------------


def _film_positions(width: int, height: int, i, j, u, v) -> "mi.Point2f":
    """Film position ((i + u) / W, (j + v) / H) in [0, 1]^2, (0, 0) the top-left corner."""
    return mi.Point2f((mi.Float(i) + u) / width, (mi.Float(j) + v) / height)


def sensor_rays(scene: Scene, camera_name: str | None, width: int, height: int, i, j, u, v, backend: str = "llvm") -> tuple[np.ndarray, np.ndarray]:
    """The rays Mitsuba's sensor generates for pixels (i, j) with jitters (u, v).

    Returns (origins, directions), NumPy float64 arrays (N, 3). Mitsuba starts
    camera rays at the near clip plane (0.01 in front of the eye), so an
    origin is eye + t d with a small t > 0, not the eye itself.
    """
    _use(backend)
    sensor = mi.load_dict(sensor_dict(scene.camera(camera_name), width, height, scene_size=scene.room.size()))
    i, j, u, v = (a.ravel().astype(np.float32) for a in np.broadcast_arrays(i, j, u, v))
    pos = _film_positions(width, height, mi.Float(i), mi.Float(j), mi.Float(u), mi.Float(v))
    ray, _ = sensor.sample_ray(time=0.0, sample1=0.0, sample2=pos, sample3=mi.Point2f(0.5))
    o = np.array(ray.o, dtype=np.float64).T.reshape(-1, 3)
    d = np.array(ray.d, dtype=np.float64).T.reshape(-1, 3)
    return o, d


def pass_seed(seed: int, pass_index: int) -> int:
    """The 32-bit sampler seed of pass ``pass_index`` of a render with ``seed`` (a hash of both)."""
    key = f"mcrt.mitsuba/{int(seed)}/{int(pass_index)}".encode()
    return int.from_bytes(hashlib.blake2b(key, digest_size=4).digest(), "little")


def _integrator_name(integrator) -> str:
    """The plugin name of an integrator given as a name or a dictionary (its ``type``)."""
    return integrator if isinstance(integrator, str) else str(integrator.get("type", "path"))


def _sample_function(integrator):
    """``f(scene, sampler, ray) -> L`` for an integrator that samples one camera ray at a time, else None.

    C++ sampling integrators (``path``, ``volpath``, ``direct``, ...) take
    ``sample(scene, sampler, ray, medium, active)``; Mitsuba's differentiable
    Python integrators (``prb``, ``prbvolpath``, ...) take the AD interface
    in primal mode, as their own ``render`` calls it. Adjoint (particle)
    integrators such as ``ptracer`` start at the emitters and splat onto the
    film: None.
    """
    try:
        from mitsuba.python.ad.integrators.common import ADIntegrator
    except ImportError:  # pragma: no cover - a Mitsuba built without the Python integrators
        ADIntegrator = ()
    if ADIntegrator and isinstance(integrator, ADIntegrator):
        def sample(scene, sampler, ray):
            return integrator.sample(mode=dr.ADMode.Primal, scene=scene, sampler=sampler, ray=ray, depth=mi.UInt32(0),
                                     δL=None, δaovs=None, state_in=None, active=mi.Bool(True))[0]
        return sample
    if isinstance(integrator, mi.SamplingIntegrator):
        return lambda scene, sampler, ray: integrator.sample(scene, sampler, ray, None, True)[0]
    return None


#: CIE XYZ from linear sRGB (Mitsuba's srgb_to_xyz): renders in ``space='xyz'`` (Mitsuba's own test compares in XYZ).
RGB_TO_XYZ = ((0.412453, 0.357580, 0.180423), (0.212671, 0.715160, 0.072169), (0.019334, 0.119193, 0.950227))


def _to_space(L, space: str):
    """A colour in the render's space: as is (``'rgb'``), or X, Y, Z by :data:`RGB_TO_XYZ`."""
    if space == "rgb":
        return L
    return mi.Color3f(*(m[0] * L[0] + m[1] * L[1] + m[2] * L[2] for m in RGB_TO_XYZ))


def per_sample_method(mscene, integrator) -> str | None:
    """Why the render must go in batches (a reason), or None when each pixel's samples can be summed apart.

    Samples are summed per pixel only for an integrator that samples camera
    rays, a ``box`` film filter (a sample counts for its pixel alone) and
    the ``independent`` sampler (whose streams do not depend on the number
    of samples per pass). Anything else is rendered by the integrator's own
    ``render``, as Mitsuba renders it: filter, sampler and film included.
    """
    film, sampler = mscene.sensors()[0].film(), mscene.sensors()[0].sampler()
    if _sample_function(integrator) is None:
        return f"{integrator.class_name()} splats particles onto the film"
    if film.rfilter().class_name() != "BoxFilter":
        return f"the film's {film.rfilter().class_name()} (radius {film.rfilter().radius():g} px) shares samples between pixels"
    if sampler.class_name() != "IndependentSampler":
        return f"the {sampler.class_name()} correlates a pixel's samples"
    return None


def filter_area(rfilter) -> float:
    r"""The effective area :math:`F = (\int g)^2 / \int g^2` of a film filter, in pixels (1 for a box, 3.13 for the default gaussian).

    A pixel's variance with filter g at n samples per pixel is about
    :math:`\sigma^2 / (F n)` for samples of variance :math:`\sigma^2`, while
    a tile of many pixels still averages about n samples per pixel: its
    mean's variance is about F times what its pixels' variances suggest when
    they are taken as independent. Separable filters: F is the square of the
    one-dimensional ratio, integrated numerically.
    """
    r = float(rfilter.radius())
    x = np.linspace(-r, r, 4001)
    dx = x[1] - x[0]
    g = np.asarray(rfilter.eval(mi.Float(x.astype(np.float32))), dtype=np.float64)
    a, b = g.sum() * dx, (g * g).sum() * dx
    return float((a * a / b) ** 2) if b > 0 else 1.0


def batch_image(mscene, integrator, seed: int, k: int, n: int, space: str = "rgb") -> "mi.TensorXf":
    """Batch ``k`` of a render: the integrator's own ``render`` at ``n`` spp with seed :func:`pass_seed` (seed, k).

    The scene's film, filter and sampler apply, as in ``mi.render``; the
    first three channels in ``space``, an (H, W, 3) tensor on the device.
    """
    img = integrator.render(mscene, mscene.sensors()[0], seed=pass_seed(seed, k), spp=n, develop=True)
    H, W, C = (int(v) for v in img.shape)
    idx = dr.arange(mi.UInt32, H * W)
    L = mi.Color3f(*(dr.gather(mi.Float, img.array, idx * C + c) for c in range(3)))
    L = _to_space(L, space)
    out = dr.zeros(mi.Float, 3 * H * W)
    for c in range(3):
        dr.scatter(out, L[c], idx * 3 + c)
    return mi.TensorXf(out, (H, W, 3))


def _sobol_jitter(seed: int, pixel, sample, samples_per_replicate: int):
    """The ``sobol`` pixel sampler's jitter (u, v) of ``sample`` of film pixel ``pixel`` (row-major), as mi.Float.

    The standalone tracer's points (:func:`mcrt.tracer.pixel_jitter`): keyed
    by the pixel's stream key under ``seed``, so a render at the same seed
    puts its camera samples where the tracer's sobol render does.
    """
    from mcrt.rng import mix32
    from mcrt.samplers import scrambled_jitter
    from mcrt.tracer import stream_keys

    key = mix32(pixel ^ dr.opaque(mi.UInt32, stream_keys(seed)[1]))  # SampleStreams' h1
    return scrambled_jitter(key, sample, samples_per_replicate)


def _pass_function(mscene, integrator, seed: int, *, jitter: bool = True, space: str = "rgb",
                   samples_per_replicate: int | None = None):
    """The pass of :func:`mcrt.film.run_passes` for ``integrator`` on a loaded Mitsuba scene (its first sensor).

    Returns ``(pass_sums, width, height, method)``. ``method`` is
    ``'samples'`` where :func:`per_sample_method` allows it: pass k traces
    W H n lanes, lane = pixel n + s, film position ((i + u) / W, (j + v) / H)
    (a box pixel), the sampler seeded with :func:`pass_seed` (seed, k), and
    reduces each pixel's n samples with ``dr.block_sum`` into sums of x and
    x^2; with ``samples_per_replicate`` (N) the jitter is the ``sobol`` pixel
    sampler's (:func:`_sobol_jitter`, pass k of n samples holding samples
    k n .. k n + n - 1) instead of the sampler's first two numbers.
    ``method`` is ``'batches'`` otherwise (an adjoint integrator such
    as ``ptracer``, a filter wider than a pixel, a sampler other than
    ``independent``): pass k is :func:`batch_image` (k, n), and the image of
    the pass counts as one sample of weight n (sums n x and n x^2; see
    :func:`_run`). ``space`` is ``'rgb'`` or ``'xyz'`` (:func:`_to_space`).
    """
    sensor = mscene.sensors()[0]
    film = sensor.film()
    W, H = (int(v) for v in film.crop_size())
    ox, oy = (int(v) for v in film.crop_offset())
    FW, FH = (int(v) for v in film.size())
    sample = _sample_function(integrator)
    if per_sample_method(mscene, integrator) is not None:
        if sample is None and not isinstance(integrator, mi.AdjointIntegrator):
            raise ValueError(f"integrator {integrator.class_name()} neither samples camera rays nor traces particles")

        def pass_sums(k: int, n: int):
            x = mi.Float64(batch_image(mscene, integrator, seed, k, n, space).array)
            sums = dr.zeros(mi.Float64, 6 * W * H)
            idx = dr.arange(mi.UInt32, 3 * W * H)
            dr.scatter(sums, x * n, idx)
            dr.scatter(sums, x * x * n, idx + 3 * W * H)
            dr.eval(sums)
            return sums

        return pass_sums, W, H, "batches"

    sampler = sensor.sampler().clone()
    aperture = sensor.needs_aperture_sample()

    def pass_sums(k: int, n: int):
        lanes = W * H * n
        # Opaque seed and n: one compiled kernel serves every pass and seed.
        sampler.seed(dr.opaque(mi.UInt32, pass_seed(seed, k)), lanes)
        idx = dr.arange(mi.UInt32, lanes)
        pixel = idx // dr.opaque(mi.UInt32, n)  # lane = pixel * n + sample
        row = pixel // W
        col = pixel - row * W
        if ox or oy:
            col, row = col + ox, row + oy
        if samples_per_replicate is None:
            uv = sampler.next_2d()
        else:
            nth = dr.opaque(mi.UInt32, k * n) + (idx - pixel * dr.opaque(mi.UInt32, n))  # the pixel's sample
            uv = mi.Point2f(*_sobol_jitter(seed, row * FW + col, nth, samples_per_replicate))
        if not jitter:
            uv = mi.Point2f(0.5)  # the catalogued no-jitter bug: every sample through the pixel centre
        pos = _film_positions(FW, FH, col, row, uv.x, uv.y)
        lens = sampler.next_2d() if aperture else mi.Point2f(0.5)
        ray, weight = sensor.sample_ray_differential(time=0.0, sample1=0.0, sample2=pos, sample3=lens)
        L = sample(mscene, sampler, ray)
        L = _to_space(L * weight, space)  # the perspective sensor's weight is 1; kept for other sensors
        dr.eval(L)  # trace once; reducing an unevaluated L re-runs the path kernel per channel
        # Per-pixel sums by block_sum (a deterministic reduction), laid out (moment, pixel, channel).
        sums = dr.zeros(mi.Float64, 6 * W * H)
        slot = dr.arange(mi.UInt32, W * H) * 3
        for c in range(3):
            x = mi.Float64(L[c])
            dr.scatter(sums, dr.block_sum(x, n, mode="evaluated"), slot + c)
            dr.scatter(sums, dr.block_sum(x * x, n, mode="evaluated"), slot + (3 * W * H + c))
        dr.eval(sums)
        return sums

    return pass_sums, W, H, "samples"


def _run(mscene, integrator, *, seed: int, spp: int, spp_per_pass: int | None, progress: bool, label: str,
         jitter: bool = True, batches: int = 32, space: str = "rgb", pixel_sampler: PixelSampler = PixelSampler()):
    """Render a loaded Mitsuba scene with ``integrator`` in passes: the pass loop of every Mitsuba render here.

    Returns ``(totals, spp_per_pass, method, notes)`` (:class:`mcrt.film.PassTotals`;
    ``notes``: header entries saying how the variance was estimated).
    Where each pixel's samples are summed apart (``'samples'``,
    :func:`per_sample_method`) the totals are exact per-sample moments.
    Otherwise (``'batches'``: a particle tracer, a filter wider than a
    pixel, a correlated sampler) the samples of one pixel are not separable,
    so the spp are split into ``batches`` equal passes of spp_per_pass =
    spp // batches (spp rounded down to a multiple), each pass image one
    batch mean, independent of the others (its own seed); the per-sample
    variance is the variance between batch means times the batch size,

        var = n (sum x_k^2 - (sum x_k)^2 / P) / (P - 1),

    which :func:`mcrt.film.run_passes`'s formula gives after scaling by
    (nP - 1) / (P - 1). It has P - 1 degrees of freedom, not nP - 1 (keep
    P >= 16): recorded as ``variance_dof``, which :func:`mcrt.stats.compare`
    uses. Pixels that share samples (a filter of effective area F > 1 px,
    :func:`filter_area`) are correlated: ``tile_variance_factor`` = F
    records by how much a tile's variance exceeds the sum of its pixels'
    (for tiles of many pixels), which :func:`mcrt.stats.compare` applies to
    tiles larger than one pixel. A particle path's vertices in several
    pixels are a correlation it does not bound.

    ``pixel_sampler`` ``sobol`` (:mod:`mcrt.samplers`) needs per-sample
    passes: the jitter is its Owen-scrambled Sobol points in R replicates of
    N = spp / R, no pass straddles two replicates, and the variance is the
    replicates' spread (``variance_method`` 'replicates:R', R - 1 df), as
    in the standalone tracer.
    """
    why = per_sample_method(mscene, integrator)
    n_rep = None if pixel_sampler.default else pixel_sampler.samples_per_replicate(spp)
    if n_rep and why is not None:
        raise ValueError(f"pixel sampler {pixel_sampler.name!r} needs each pixel's samples summed apart, "
                         f"and here {why}")
    pass_sums, W, H, method = _pass_function(mscene, integrator, seed, jitter=jitter, space=space,
                                             samples_per_replicate=n_rep)
    if method == "batches":
        if spp_per_pass is None:
            spp_per_pass = max(1, spp // max(1, min(batches, spp)))
        spp = max(2, spp // spp_per_pass) * spp_per_pass
    per_pass = spp_per_pass if spp_per_pass is not None else samples_per_pass(W, H, spp)
    if n_rep:
        per_pass = replicate_pass_size(per_pass, n_rep)
        pass_sums = replicate_passes(pass_sums, n_rep)
    if method == "samples" and W * H * per_pass >= 2**32:
        raise ValueError(f"one pass of {W}x{H}x{per_pass} samples exceeds 2^32 lanes: lower spp_per_pass")
    totals = run_passes(pass_sums, width=W, height=H, spp=spp, spp_per_pass=per_pass,
                        progress=Progress(spp, label=label, enabled=progress))
    notes = {"variance_method": "samples", "variance_note": "per-sample moments of each pixel's own samples"}
    if n_rep:
        R = pixel_sampler.replicates
        totals.variance = (totals.variance.astype(np.float64) * replicate_variance_scale(spp, R)).astype(np.float32)
        notes = {"pixel_sampler": pixel_sampler.name, "variance_method": pixel_sampler.variance_method,
                 "variance_note": f"spp times the variance of the mean from {R} independently scrambled replicates"}
    if method == "batches":
        P = totals.spp // per_pass
        totals.variance = (totals.variance.astype(np.float64) * (totals.spp - 1) / (P - 1)).astype(np.float32)
        F = filter_area(mscene.sensors()[0].film().rfilter())
        notes = {"variance_method": f"batches:{P}", "variance_dof": str(P - 1),
                 "variance_note": f"n times the variance between {P} independent batches of {per_pass} spp ({why})"}
        if F > 1.0001:
            notes["tile_variance_factor"] = f"{F:.4f}"
    return totals, per_pass, method, notes


def render_mitsuba(scene: Scene, settings: RenderSettings, *, backend: str = "llvm", progress: bool = True,
                   spp_per_pass: int | None = None, integrator: str | dict[str, Any] = "path",
                   jitter: bool = True, pixel_sampler: str = "independent", replicates: int | None = None) -> RenderResult:
    """Render ``scene`` at ``settings`` with Mitsuba's ``path`` integrator: mean and per-sample variance images.

    Called through :func:`mcrt.render.render` (renderer ``mitsuba``).
    ``integrator`` replaces ``path`` by another plugin (a name, or a
    dictionary as in :func:`scene_dict`; :func:`mcrt.plugins.render_plugin`
    uses it for mcrt's estimator); ``jitter=False`` sends every sample through
    its pixel's centre (the plugin's no-jitter mutant); ``pixel_sampler``
    and ``replicates`` place the camera samples as in
    :func:`mcrt.tracer.render_tracer` (:mod:`mcrt.samplers`; ``sobol``: the
    tracer's points, variance from the replicates). The result is identical bit for bit for
    the same arguments on the same machine and backend. The passes are
    :func:`_run`'s, shared with :func:`render_with_variance`.

    ``wall_time`` is the time of all passes (after ``dr.sync_thread()``),
    JIT compilation included; ``compile_time`` is the part of it spent
    generating and compiling kernels, from Dr.Jit's kernel history
    (codegen + backend time). Scene loading is not timed in either (it is
    in ``extra['load_time']``).
    """
    s = settings
    variant = _use(backend)
    t_load = time.perf_counter()
    mscene = mi.load_dict(scene_dict(scene, s.camera, s.width, s.height, s.max_depth, integrator, rr_depth=s.rr_depth,
                                     spp=s.spp, backend=backend))
    load_time = time.perf_counter() - t_load
    sampler = PixelSampler.of(pixel_sampler, replicates)
    totals, per_pass, _, notes = _run(mscene, mscene.integrator(), seed=s.seed, spp=s.spp, spp_per_pass=spp_per_pass,
                                      progress=progress, label="mitsuba", jitter=jitter, pixel_sampler=sampler)
    return RenderResult(
        mean=totals.mean,
        variance=totals.variance,
        spp=totals.spp,
        seed=s.seed,
        max_depth=s.max_depth,
        renderer="mitsuba",
        scene_hash=scene.content_hash(),
        camera=s.camera,
        wall_time=totals.wall_time,
        compile_time=totals.compile_time,
        extra={
            "variant": variant,
            "mitsuba_version": mi.__version__,
            "drjit_version": dr.__version__,
            "integrator": _integrator_name(integrator),
            "rr_depth": str(s.rr_depth),
            "spp_per_pass": str(per_pass),
            "load_time": f"{load_time:.3f}",
            **({} if sampler.default else {k: notes[k] for k in ("pixel_sampler", "variance_method")}),
        },
    )


# --------------------------------------------------------------------------
# Any Mitsuba scene, any integrator
# --------------------------------------------------------------------------


def _canonical(value) -> Any:
    """A JSON-ready, order-independent form of a scene dictionary (Mitsuba objects by their text)."""
    if isinstance(value, dict):
        return {str(k): _canonical(v) for k, v in sorted(value.items(), key=lambda kv: str(kv[0]))}
    if isinstance(value, (list, tuple)):
        return [_canonical(v) for v in value]
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    return f"{type(value).__name__}:{value}"


def mitsuba_scene_hash(scene: dict[str, Any] | str | os.PathLike) -> str:
    """A content hash of a Mitsuba scene dictionary or XML file, the same for every integrator and sample count.

    A dictionary is hashed without its ``integrator`` and without its
    sensor's ``sampler`` and ``film`` (resolution and sample count are
    recorded apart); key order does not matter. A file is hashed byte for
    byte (its integrator included, not the files it references). 16 hex
    digits, like :meth:`mcrt.scene.Scene.content_hash`.
    """
    if isinstance(scene, dict):
        d = {k: v for k, v in scene.items() if k != "integrator"}
        for k, v in d.items():
            if isinstance(v, dict) and str(v.get("type", "")) in _SENSOR_TYPES:
                d[k] = {kk: vv for kk, vv in v.items() if kk not in ("sampler", "film")}
        data = json.dumps(_canonical(d), sort_keys=True, separators=(",", ":")).encode()
    else:
        data = Path(scene).read_bytes()
    return hashlib.sha256(data).hexdigest()[:16]


_SENSOR_TYPES = ("perspective", "thinlens", "orthographic", "telecentric", "radiancemeter", "irradiancemeter",
                 "batch", "distant")


def camera_id(sensor) -> str:
    """``'<sensor plugin>:<hash>'``: which camera a sensor is, from its pose, field of view and clip planes.

    The hash covers the sensor's traversable parameters other than its film
    and shutter (``to_world``, ``x_fov``, ``near_clip``, ...), so two loads of
    one camera at any resolution or sample count agree and two cameras
    differ.
    """
    params = mi.traverse(sensor)
    text = ";".join(f"{k}={params[k]}" for k in sorted(params.keys())
                    if not k.startswith("film.") and not k.startswith("shutter"))
    return f"{sensor.class_name()}:{hashlib.sha256(text.encode()).hexdigest()[:8]}"


def integrator_max_depth(integrator) -> int:
    """The integrator's ``max_depth`` (-1 unbounded), read from the object; -1 too where it has none (``direct``, ``aov``).

    Python integrators (``prb``) keep it as an attribute; C++ ones print it
    (``max_depth = 8``; an unbounded depth prints as 2^32 - 1).
    """
    v = getattr(integrator, "max_depth", None)
    if v is None:
        m = re.search(r"max_depth\s*=\s*(-?\d+)", str(integrator))
        if m is None:
            return -1
        v = int(m.group(1))
    v = int(v)
    return -1 if v < 0 or v >= 2**31 else v


def _integrator_spec(integrator: str | dict[str, Any] | None, max_depth: int | None, current: str
                     ) -> tuple[dict[str, Any] | None, tuple[str, ...]]:
    """The integrator dictionary that replaces the scene's (None: keep it), and the keys it took from the scene.

    A dictionary replaces it as given. A name replaces the plugin and keeps
    the scene integrator's ``max_depth`` and ``rr_depth`` (``current`` is its
    description), so that ``path`` and ``prb`` (default depths -1 and 6)
    render the same light paths; :func:`load_integrator` drops those the new
    plugin does not take (``direct`` has no depth). ``max_depth`` overrides
    the depth.
    """
    inherited: tuple[str, ...] = ()
    if integrator is None:
        if max_depth is None:
            return None, ()
        integrator = _INTEGRATOR_CLASSES.get(current.split("[", 1)[0].strip(), None)
        if integrator is None:
            raise ValueError(f"cannot set max_depth of the scene's integrator {current.split('[', 1)[0]}: name the integrator")
    if isinstance(integrator, dict):
        spec = dict(integrator)
    else:
        spec = {"type": str(integrator)}
        for key in ("max_depth", "rr_depth"):
            m = re.search(rf"{key}\s*=\s*(-?\d+)", current)
            if m is not None:
                v = int(m.group(1))
                spec[key] = -1 if v >= 2**31 else v
                inherited += (key,)
    if max_depth is not None:
        spec["max_depth"] = int(max_depth)
        inherited = tuple(k for k in inherited if k != "max_depth")
    return spec, inherited


def load_integrator(spec: dict[str, Any], inherited: tuple[str, ...] = ()) -> "mi.Integrator":
    """``mi.load_dict(spec)``, less the ``inherited`` parameters the plugin does not take.

    Mitsuba refuses a parameter no plugin reads ("unreferenced property");
    one the caller named is a mistake and raised as such, one copied from
    the scene's integrator (its depth, for ``direct``, which has none) is
    dropped.
    """
    spec = dict(spec)
    while True:
        try:
            return mi.load_dict(spec)
        except RuntimeError as e:
            unused = [k for k in inherited if k in spec and re.search(rf'"{k}"', str(e)) and "unreferenced" in str(e)]
            if not unused:
                raise ValueError(f"integrator {spec.get('type')}: {' '.join(str(e).split())}") from None
            for k in unused:
                del spec[k]


#: Top-level XML integrators that wrap the one that renders: the wrapped one is rendered in their place.
_WRAPPERS = ("moment",)


def _scene_defaults(root) -> dict[str, str]:
    """The ``<default name=... value=...>`` parameters of a parsed scene (its includes inlined)."""
    return {d.get("name"): d.get("value") for d in root.iter("default")}


def _inline(path: Path, root, depth: int = 0):
    """``root`` (parsed from ``path``) with ``<path>`` entries made absolute and ``<include>`` files inlined.

    An included file is looked for beside the file that includes it (as
    Mitsuba's parser does); its own ``<path>`` and ``<include>`` entries are
    relative to itself.
    """
    import xml.etree.ElementTree as ET

    if depth > 16:
        raise ValueError(f"{path}: includes nested more than 16 deep")
    for el in root.iter("path"):
        v = el.get("value")
        if v and not os.path.isabs(v):
            el.set("value", str((path.parent / v).resolve()))
    for parent in list(root.iter()):
        for i, el in enumerate(list(parent)):
            if el.tag != "include":
                continue
            name = el.get("filename", "")
            target = path.parent / name
            if not target.is_file():
                raise ValueError(f"{path}: included file {name} not found beside it")
            try:
                sub = _inline(target, ET.parse(target).getroot(), depth + 1)
            except ET.ParseError as e:
                raise ValueError(f"{target}: not a readable XML scene ({e})") from None
            parent.remove(el)
            for j, child in enumerate(list(sub)):
                parent.insert(i + j, child)
    return root


def load_scene_file(path: str | os.PathLike, defaults: dict[str, Any] | None = None) -> tuple["mi.Scene", dict[str, str]]:
    """Load a Mitsuba XML scene as Mitsuba's render tests do; returns the scene and notes for the render's header.

    * ``defaults`` set the file's ``<default>`` parameters (``-D key=value``;
      a name the file does not declare is refused, naming those it has);
    * a top-level ``moment`` integrator (Mitsuba's test scenes wrap theirs in
      one to write moments) is replaced by the integrator it wraps, which is
      what renders the image;
    * the scene's folder, and a ``common`` folder beside any folder above it
      (Mitsuba's tests add ``common`` to the file resolver), are searched for
      the files it names; ``<path>`` entries are made absolute and
      ``<include>`` files inlined (:func:`_inline`).
    """
    import xml.etree.ElementTree as ET

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: no such Mitsuba scene file")
    try:
        root = _inline(path, ET.parse(path).getroot())
    except ET.ParseError as e:
        raise ValueError(f"{path}: not a readable XML scene ({e})") from None
    notes: dict[str, str] = {}
    declared = _scene_defaults(root)
    given = {str(k): str(v) for k, v in (defaults or {}).items()}
    for k in given:
        if k not in declared:
            have = ", ".join(f"{n}={v}" for n, v in declared.items()) or "none"
            raise ValueError(f"{path}: the scene declares no parameter {k!r} (its defaults: {have})")
    if given:
        notes["parameters"] = ",".join(f"{k}={v}" for k, v in sorted(given.items()))
    for i, el in enumerate(list(root)):
        if el.tag == "integrator" and el.get("type") in _WRAPPERS:
            inner = el.find("integrator")
            if inner is not None:
                root.remove(el)
                root.insert(i, inner)
                notes["unwrapped"] = f"the scene's {el.get('type')} integrator, rendering the integrator it wraps"
    resolver = mi.file_resolver()
    old = list(resolver)
    try:
        resolver.prepend(str(path.parent.resolve()))
        for up in path.resolve().parents:
            if (up / "common").is_dir():
                resolver.append(str(up / "common"))
                break
        text = ET.tostring(root, encoding="unicode")
        scene = mi.load_string(text, **given)
    except RuntimeError as e:
        hint = ("; to change the integrator, name it with --integrator (integrator=...), which passes only the "
                "parameters it takes" if "unreferenced" in str(e) and "integrator" in given else "")
        raise ValueError(f"{path}: {' '.join(str(e).split())}{hint}") from None
    finally:
        resolver.clear()
        for p in old:
            resolver.append(p)
    return scene, notes


#: Mitsuba's class names of its integrators -> their plugin names (the rest: the class name, lower case).
_INTEGRATOR_CLASSES = {
    "PathIntegrator": "path", "VolumetricPathIntegrator": "volpath", "VolumetricMisPathIntegrator": "volpathmis",
    "PRBIntegrator": "prb", "PRBBasicIntegrator": "prb_basic", "PRBVolpathIntegrator": "prbvolpath",
    "ParticleTracerIntegrator": "ptracer", "DirectIntegrator": "direct", "AOVIntegrator": "aov",
    "MomentIntegrator": "moment", "DirectProjectiveIntegrator": "direct_projective",
    "PRBProjectiveIntegrator": "prb_projective",
}


def render_with_variance(scene: "dict[str, Any] | mi.Scene | str | os.PathLike", *, integrator: str | dict[str, Any] | None = None,
                         spp: int | None = None, seed: int = 0, width: int | None = None, height: int | None = None,
                         max_depth: int | None = None, backend: str = "llvm", progress: bool = False,
                         spp_per_pass: int | None = None, batches: int = 32, defaults: dict[str, Any] | None = None,
                         space: str = "rgb", pixel_sampler: str = "independent",
                         replicates: int | None = None) -> RenderResult:
    """Render any Mitsuba scene with any of its integrators: mean and per-sample variance, reproducible from ``seed``.

    ``scene`` is a scene dictionary (``mi.cornell_box()``), a loaded
    ``mi.Scene`` or the path of an XML file. ``integrator`` (a plugin name
    or a dictionary with ``type``) replaces the scene's; ``max_depth`` sets
    its ``max_depth``; ``width``/``height`` change the film's resolution;
    ``spp`` defaults to the scene sampler's sample count. The passes are
    those of :func:`render_mitsuba` (:func:`_run`): for integrators that
    sample camera rays (``path``, ``volpath``, ``prb``, ``direct``, ...) each
    pixel's samples are summed per pass, so the variance comes from
    per-sample second moments and the same seed gives the same image bit for
    bit; adjoint integrators (``ptracer``) are rendered in ``batches`` passes
    whose images give the variance (see :func:`_run`; their film adds splats
    atomically, so the image is reproducible only up to rounding).

    A dictionary's film filter is set to ``box`` (noted in
    ``extra['rfilter']`` when it was another), so that each sample counts
    for its own pixel and ``mi.render`` with that scene converges to the
    same image. A file (:func:`load_scene_file`: ``defaults`` are its
    ``<default>`` parameters, a ``moment`` wrapper is unwrapped) or a loaded
    scene is rendered as Mitsuba renders it: its film, reconstruction filter
    (Mitsuba's default is a gaussian), sampler and integrator parameters.
    Where a filter wider than a pixel, a sampler other than ``independent``
    or a particle tracer keeps a pixel's samples from being summed apart,
    the render goes in independent batches (:func:`_run`) and the header
    says how the variance was estimated (``variance_method``), its degrees
    of freedom (``variance_dof``) and the tile variance factor of the
    filter (``tile_variance_factor``). ``space='xyz'`` renders CIE X, Y, Z
    instead of linear RGB (``extra['channels'] = 'XYZ'``). ``pixel_sampler``
    ``sobol`` (and ``replicates``) places the camera samples at
    :mod:`mcrt.samplers`' points, variance from the replicates; it needs the
    per-sample passes (a box filter, the ``independent`` sampler, an
    integrator that samples camera rays) and says so otherwise.

    The result records ``renderer`` = the integrator's plugin name,
    ``max_depth`` = :func:`integrator_max_depth` (-1 unbounded or none),
    ``camera`` = :func:`camera_id`, ``scene_hash`` =
    :func:`mitsuba_scene_hash` of the dictionary or file ("" for a loaded
    scene: nothing to hash), and in ``extra`` the integrator's description,
    the variant, the versions, the method (``samples`` or ``batches``), the
    spp per pass and the scene's source.
    """
    variant = _use(backend)
    t_load = time.perf_counter()
    extra: dict[str, str] = {}
    if isinstance(scene, dict):
        d = dict(scene)
        scene_hash, source = mitsuba_scene_hash(d), "dict"
        for k, v in d.items():
            if isinstance(v, dict) and str(v.get("type", "")) in _SENSOR_TYPES and isinstance(v.get("film"), dict):
                film = dict(v["film"])
                old = film.get("rfilter", {"type": "gaussian"})
                old_type = old.get("type", "?") if isinstance(old, dict) else str(old)
                if old_type != "box":
                    extra["rfilter"] = f"box (the scene's film had {old_type})"
                film["rfilter"] = {"type": "box"}
                d[k] = dict(v, film=film)
                break
        mscene = mi.load_dict(d)
    elif isinstance(scene, mi.Scene):
        mscene, scene_hash, source = scene, "", "mi.Scene"
    else:
        path = Path(scene)
        if not path.is_file():
            raise ValueError(f"{path}: no such Mitsuba scene file")
        mscene, notes = load_scene_file(path, defaults)
        scene_hash, source = mitsuba_scene_hash(path), str(path)
        extra.update(notes)
    if defaults and not isinstance(scene, (str, os.PathLike)):
        raise ValueError("scene parameters (-D key=value) apply to an XML scene file only")
    spec, inherited = _integrator_spec(integrator, max_depth, str(mscene.integrator()))
    integ = mscene.integrator() if spec is None else load_integrator(spec, inherited)
    if width is not None or height is not None:
        params = mi.traverse(mscene.sensors()[0])
        fw, fh = (int(v) for v in mscene.sensors()[0].film().size())
        size = mi.ScalarVector2u(int(width or fw), int(height or fh))
        params["film.size"] = size
        params["film.crop_size"] = size
        params["film.crop_offset"] = mi.ScalarPoint2u(0, 0)
        params.update()
    load_time = time.perf_counter() - t_load
    sensor = mscene.sensors()[0]
    if spp is None:
        spp = int(sensor.sampler().sample_count())
    name = _integrator_name_of(integ)
    totals, per_pass, method, notes = _run(mscene, integ, seed=seed, spp=int(spp), spp_per_pass=spp_per_pass,
                                           progress=progress, label=name, batches=batches, space=space,
                                           pixel_sampler=PixelSampler.of(pixel_sampler, replicates))
    film = sensor.film()
    extra.update(notes)
    extra.update({
        "film": f"{film.class_name()} {int(film.size()[0])}x{int(film.size()[1])}, filter {film.rfilter().class_name()} "
                f"(radius {film.rfilter().radius():g} px), sampler {sensor.sampler().class_name()}",
        "variant": variant,
        "mitsuba_version": mi.__version__,
        "drjit_version": dr.__version__,
        "integrator": " ".join(str(integ).split()),
        "method": method,
        "spp_per_pass": str(per_pass),
        "source": source,
        "load_time": f"{load_time:.3f}",
    })
    if space == "xyz":
        extra["channels"] = "XYZ"
    return RenderResult(
        mean=totals.mean,
        variance=totals.variance,
        spp=totals.spp,
        seed=int(seed),
        max_depth=integrator_max_depth(integ),
        renderer=name,
        scene_hash=scene_hash,
        camera=camera_id(sensor),
        wall_time=totals.wall_time,
        compile_time=totals.compile_time,
        extra=extra,
    )


def _integrator_name_of(integrator) -> str:
    """The plugin name of a loaded integrator (``path`` for PathIntegrator, ``prb`` for PRBIntegrator, ...)."""
    cls = type(integrator).__name__
    if cls in ("MonteCarloIntegrator", "SamplingIntegrator", "AdjointIntegrator", "Integrator"):
        cls = integrator.class_name()  # a C++ plugin: its own class name
    return _INTEGRATOR_CLASSES.get(cls, cls.lower())
