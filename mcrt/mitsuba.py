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
"""

from __future__ import annotations

import hashlib
import time
from typing import Any

import numpy as np

import mcrt  # noqa: F401  (sets DRJIT_LIBLLVM_PATH before drjit is imported)
import drjit as dr
import mitsuba as mi

from mcrt.film import Progress, RenderResult, run_passes, samples_per_pass
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


def render_mitsuba(scene: Scene, settings: RenderSettings, *, backend: str = "llvm", progress: bool = True,
                   spp_per_pass: int | None = None, integrator: str | dict[str, Any] = "path",
                   jitter: bool = True) -> RenderResult:
    """Render ``scene`` at ``settings`` with Mitsuba's ``path`` integrator: mean and per-sample variance images.

    Called through :func:`mcrt.render.render` (renderer ``mitsuba``).
    ``integrator`` replaces ``path`` by another plugin (a name, or a
    dictionary as in :func:`scene_dict`; :func:`mcrt.plugins.render_plugin`
    uses it for mcrt's estimator); ``jitter=False`` sends every sample through
    its pixel's centre (the plugin's no-jitter mutant). The result is identical bit for bit for
    the same arguments on the same machine and backend.

    ``wall_time`` is the time of all passes (after ``dr.sync_thread()``),
    JIT compilation included; ``compile_time`` is the part of it spent
    generating and compiling kernels, from Dr.Jit's kernel history
    (codegen + backend time). Scene loading is not timed in either (it is
    in ``extra['load_time']``).
    """
    s = settings
    W, H, n_total = s.width, s.height, s.spp
    per_pass = spp_per_pass if spp_per_pass is not None else samples_per_pass(W, H, n_total)
    if W * H * per_pass >= 2**32:
        raise ValueError(f"one pass of {W}x{H}x{per_pass} samples exceeds 2^32 lanes: lower spp_per_pass")

    variant = _use(backend)
    t_load = time.perf_counter()
    mscene = mi.load_dict(scene_dict(scene, s.camera, W, H, s.max_depth, integrator, rr_depth=s.rr_depth, spp=n_total, backend=backend))
    load_time = time.perf_counter() - t_load
    sensor = mscene.sensors()[0]
    integrator_name = integrator if isinstance(integrator, str) else str(integrator.get("type", "path"))
    integrator = mscene.integrator()
    sampler = sensor.sampler().clone()

    def pass_sums(k: int, n: int):
        lanes = W * H * n
        # Opaque seed and n: one compiled kernel serves every pass and seed.
        sampler.seed(dr.opaque(mi.UInt32, pass_seed(s.seed, k)), lanes)
        idx = dr.arange(mi.UInt32, lanes)
        pixel = idx // dr.opaque(mi.UInt32, n)  # lane = pixel * n + sample
        row = pixel // W
        col = pixel - row * W
        uv = sampler.next_2d()
        if not jitter:
            uv = mi.Point2f(0.5)  # the catalogued no-jitter bug: every sample through the pixel centre
        pos = _film_positions(W, H, col, row, uv.x, uv.y)
        ray, weight = sensor.sample_ray_differential(time=0.0, sample1=0.0, sample2=pos, sample3=mi.Point2f(0.5))
        L, _, _ = integrator.sample(mscene, sampler, ray, None, True)
        L = L * weight  # the perspective sensor's weight is 1; kept for other sensors
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

    totals = run_passes(pass_sums, width=W, height=H, spp=n_total, spp_per_pass=per_pass,
                        progress=Progress(n_total, label="mitsuba", enabled=progress))
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
            "integrator": integrator_name,
            "rr_depth": str(s.rr_depth),
            "spp_per_pass": str(per_pass),
            "load_time": f"{load_time:.3f}",
        },
    )
