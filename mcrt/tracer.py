"""The standalone tracer: camera samples, passes, moments -> RenderResult.

One pass traces ``n`` samples for every pixel in one kernel launch: each pixel
has a few consecutive lanes (:func:`pass_layout`), and each lane traces its
share of the pixel's paths one after another. Each lane has its own random
stream (mcrt.rng), keyed by a hash of (seed, pass), so a render is
reproducible from its seed and renders with different seeds are independent.
The per-pass seed and sample count enter the kernel as opaque values: a new
seed or spp does not recompile it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

import mcrt  # noqa: F401  (sets DRJIT_LIBLLVM_PATH before drjit loads)
from mcrt.camera import image_plane_basis
from mcrt.geometry import const3
from mcrt.film import Progress, RenderResult, samples_per_pass
from mcrt.llvm import require_llvm
from mcrt.mutants import check_mutants, mutate_scene
from mcrt.precision import check_precision
from mcrt.rng import WeylRng
from mcrt.scene import Scene

BACKENDS = ("llvm", "cuda")


def backend_module(backend: str):
    """The Dr.Jit array namespace of a backend, with a clear error when it is unusable."""
    import drjit as dr

    if backend == "llvm":
        require_llvm()
        if not dr.has_backend(dr.JitBackend.LLVM):
            raise RuntimeError("Dr.Jit's LLVM backend did not initialise (is DRJIT_LIBLLVM_PATH a libLLVM >= 16?)")
        import drjit.llvm as m
    elif backend == "cuda":
        if not dr.has_backend(dr.JitBackend.CUDA):
            raise RuntimeError("the CUDA backend is unavailable on this machine (no NVIDIA GPU or driver); use --backend llvm")
        import drjit.cuda as m
    else:
        raise ValueError(f"unknown backend {backend!r} (one of {', '.join(BACKENDS)})")
    return m


def _mix64(x: int) -> int:
    """SplitMix64 finaliser: decorrelates (seed, pass) before it keys the lanes' streams."""
    x &= 0xFFFFFFFFFFFFFFFF
    x = ((x ^ (x >> 30)) * 0xBF58476D1CE4E5B9) & 0xFFFFFFFFFFFFFFFF
    x = ((x ^ (x >> 27)) * 0x94D049BB133111EB) & 0xFFFFFFFFFFFFFFFF
    return x ^ (x >> 31)


def stream_keys(seed: int, pass_index: int) -> tuple[int, int]:
    """The two 32-bit keys of one pass's random streams (mcrt.rng.WeylRng.seeded)."""
    key = _mix64(seed * 0x9E3779B97F4A7C15 + pass_index)
    return key & 0xFFFFFFFF, key >> 32


@dataclass
class Tracer:
    """A compiled view of one scene and camera for repeated passes."""

    scene: Scene
    camera: str
    width: int
    height: int
    max_depth: int = 8
    light_samples: int = 1
    rr_depth: int = 5
    backend: str = "llvm"
    intersector: str = "convex"
    mutants: frozenset = frozenset()
    precision_guard: bool = True
    mis: bool | None = None  # None: where the scene needs it (mcrt.integrator.needs_mis)

    def __post_init__(self):
        from mcrt.geometry import Geometry
        from mcrt.integrator import PathIntegrator, needs_mis

        self.mutants = check_mutants(self.mutants)
        self.m = backend_module(self.backend)
        scene = mutate_scene(self.scene, self.mutants)
        if self.precision_guard:
            check_precision(scene)  # refuse scenes where float32 would silently give a wrong image
        self.geometry = Geometry(scene, self.m, self.intersector)
        self.integrator = PathIntegrator(
            self.geometry, max_depth=self.max_depth, light_samples=self.light_samples, rr_depth=self.rr_depth, mutants=self.mutants,
            mis=needs_mis(scene) if self.mis is None else self.mis,
        )
        self.cam = scene.camera(self.camera)
        import drjit as dr

        self._frozen_pass = dr.freeze(self._pass_kernel, limit=8, warn_after=64)  # one recording per pass size, a few kept

    def pass_sums(self, seed: int, pass_index: int, n: int):
        """Per-pixel sums of x and x^2 over ``n`` new samples per pixel: one evaluated Float64 array.

        Laid out (moment, pixel, channel): the sums of x, then those of x^2,
        pixels in row-major order. The work is :meth:`_pass_kernel`, frozen
        (``dr.freeze``): Dr.Jit traces the path kernel in Python once per
        pass size and replays the recorded kernels for every later pass,
        which saves about a millisecond of tracing per pass. The seed's keys
        enter as opaque arrays, so a new seed replays the same recording.
        """
        import drjit as dr

        k0, k1 = stream_keys(seed, pass_index)
        return self._frozen_pass(dr.opaque(self.m.UInt32, k0), dr.opaque(self.m.UInt32, k1), n)

    def _pass_kernel(self, key0, key1, n: int):
        """:meth:`pass_sums` for the pass keyed by the UInt32 arrays (key0, key1) (mcrt.rng.WeylRng.seeded).

        Each pixel gets consecutive lanes (:func:`pass_layout`), and each lane
        traces its share of the pixel's n paths one after another
        (mcrt.integrator.PathIntegrator.path_sums), keeping the sums of its
        samples x and x^2. The lanes' sums are then added (as float64)
        into slots of up to GROUP consecutive lanes of one pixel, each packet
        first reducing its own lanes (ReduceMode.Local), so a slot receives
        one addition per packet: a pixel's sums do not depend on which thread
        adds first, and a seed gives the same image bit for bit. The slots
        of a pixel are added in a second, ordered reduction.
        """
        import drjit as dr

        m = self.m
        W, H = self.width, self.height
        stride, group = pass_layout(n, W * H)
        lanes = W * H * stride
        idx = dr.arange(m.UInt32, lanes)
        # lane // stride in float64 (exact for lanes < 2^32): an integer division by an
        # opaque value would be 16 scalar divides per packet.
        pixel = m.UInt32((m.Float64(idx) + 0.5) * dr.opaque(m.Float64, 1.0 / stride))
        lane = idx - pixel * dr.opaque(m.UInt32, stride)  # the lane's place among its pixel's lanes
        # The pixel's n paths dealt out: n // stride to every lane, one more to the first n % stride.
        paths = dr.opaque(m.UInt32, n // stride) + dr.select(lane < dr.opaque(m.UInt32, n % stride), 1, 0)
        col = m.Float(pixel % W)
        row = m.Float(pixel // W)
        rng = WeylRng.seeded(m, lanes, key0, key1)
        center, half_right, half_up = image_plane_basis(self.cam, W, H)
        center, half_right, half_up = const3(m, center), const3(m, half_right), const3(m, half_up)
        eye = const3(m, self.cam.eye)
        no_jitter = "no_jitter" in self.mutants

        def camera_ray(u, v):
            if no_jitter:
                u = v = 0.5
            sx = dr.fma(col + u, 2.0 / W, -1.0)
            sy = dr.fma(row + v, -2.0 / H, 1.0)
            return eye, dr.normalize(dr.fma(sy, half_up, dr.fma(sx, half_right, center)))

        used = paths > 0  # lanes past n pad the pass to a power of two per pixel
        sum_x, sum_x2 = self.integrator.path_sums(camera_ray, rng, dr.maximum(paths, 1))

        slots = stride // group  # per pixel
        # Layout (moment, pixel, channel, slot): the slots of one sum are one block of ``slots``.
        base = (pixel * 3) * slots + (lane >> dr.opaque(m.UInt32, group.bit_length() - 1))
        moment = 3 * W * H * slots
        acc = dr.zeros(m.Float64, 2 * moment)
        for c in range(3):
            dr.scatter_reduce(dr.ReduceOp.Add, acc, m.Float64(sum_x[c]), base + c * slots, used, mode=dr.ReduceMode.Local)
            dr.scatter_reduce(dr.ReduceOp.Add, acc, m.Float64(sum_x2[c]), base + (c * slots + moment), used, mode=dr.ReduceMode.Local)
        if slots > 1:
            dr.eval(acc)
            acc = dr.block_sum(acc, slots)
        dr.eval(acc)
        return acc

    def mean_variance(self, sums, n: int) -> tuple[np.ndarray, np.ndarray]:
        """Mean and unbiased per-sample variance (float32, H x W x 3) from :meth:`pass_sums`' layout over n samples.

        The formulas of :class:`mcrt.film.Moments`, evaluated by Dr.Jit: one
        small kernel instead of NumPy's temporaries (a few ms at 256x256).
        """
        import drjit as dr

        m = self.m
        size = 3 * self.width * self.height
        idx = dr.arange(m.UInt32, size)
        # Opaque counts: a true division (Dr.Jit turns division by a literal into
        # a product with its reciprocal), and one kernel for every spp.
        count = dr.opaque(m.Float64, n)
        s1 = dr.gather(m.Float64, sums, idx)
        mean = m.Float(s1 / count)
        if n < 2:
            var = dr.zeros(m.Float, size)
        else:
            s2 = dr.gather(m.Float64, sums, idx + size)
            var = m.Float(dr.maximum((s2 - s1 * s1 / count) / dr.opaque(m.Float64, n - 1), 0.0))
        dr.eval(mean, var)
        shape = (self.height, self.width, 3)
        return mean.numpy().reshape(shape), var.numpy().reshape(shape)


#: Lanes summed into one slot inside the kernel (a power of two no wider than a packet of 16).
GROUP = 16
#: Paths one lane traces in turn, at most: its float32 sums of x and x^2 stay exact to about a
#: millionth, and a packet's lanes, each with this many paths, end close together.
PATHS_PER_LANE = 16
#: Lanes a pass has at least, where it has the samples: Dr.Jit's LLVM backend hands out blocks
#: of 16384 lanes to its threads, and a pass of one block would keep one core busy.
MIN_LANES = 1 << 16


def pass_layout(n: int, pixels: int) -> tuple[int, int]:
    """(lanes per pixel, lanes per slot) of a pass of ``n`` samples per pixel over ``pixels`` pixels.

    Enough lanes that none traces more than PATHS_PER_LANE paths and, where
    n allows, that the pass has MIN_LANES; up to GROUP lanes per pixel, the
    next power of two (lanes past n trace nothing that is counted), beyond,
    whole groups of GROUP.
    """
    lanes = min(n, max(-(-n // PATHS_PER_LANE), -(-MIN_LANES // pixels)))
    if lanes <= GROUP:
        stride = 1 << (lanes - 1).bit_length()
        return stride, stride
    return -(-lanes // GROUP) * GROUP, GROUP


def pass_size(width: int, height: int, spp: int) -> int:
    """Samples per pixel in one pass: the film's budget, rounded down to whole groups (no padded lanes)."""
    n = samples_per_pass(width, height, spp)
    return n if n <= GROUP else n // GROUP * GROUP


_TRACERS: dict = {}


def _tracer(scene: Scene, *args) -> Tracer:
    """A Tracer for these settings, reused across renders of the same scene content (a few kept)."""
    key = (scene.content_hash(), scene.path, *args)
    tracer = _TRACERS.get(key)
    if tracer is None:
        tracer = Tracer(scene, *args)
        if len(_TRACERS) >= 8:
            _TRACERS.pop(next(iter(_TRACERS)))
        _TRACERS[key] = tracer
    return tracer


def srgb_encode(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, None)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def render(
    scene: Scene,
    camera: str | None = None,
    spp: int | None = None,
    seed: int | None = None,
    max_depth: int | None = None,
    light_samples: int | None = None,
    backend: str = "llvm",
    *,
    width: int | None = None,
    height: int | None = None,
    rr_depth: int | None = None,
    mutants=(),
    intersector: str = "convex",
    spp_per_pass: int | None = None,
    progress: bool = True,
    precision_guard: bool = True,
    mis: bool | None = None,
) -> RenderResult:
    """Render ``scene`` with the standalone tracer: mean and per-sample variance.

    Arguments left as None take the scene file's render defaults.
    ``mis`` forces multiple importance sampling on or off (default: where
    the scene needs it). ``precision_guard=False`` renders scenes that :func:`mcrt.precision.check_precision`
    would refuse (only to measure where float32 breaks).
    """
    import drjit as dr

    s = scene.settings(camera=camera, spp=spp, seed=seed, max_depth=max_depth, light_samples=light_samples, width=width, height=height, rr_depth=rr_depth)
    tracer = _tracer(scene, s.camera, s.width, s.height, s.max_depth, s.light_samples, s.rr_depth, backend, intersector,
                     frozenset(mutants), precision_guard, mis)
    per_pass = spp_per_pass or pass_size(s.width, s.height, s.spp)
    bar = Progress(s.spp, label="mcrt", enabled=progress)
    flag = dr.flag(dr.JitFlag.KernelHistory)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    dr.kernel_history()  # clear
    t0 = time.perf_counter()
    # The sums stay in Dr.Jit's memory across passes (float64, added pass by pass).
    sums, done, k = None, 0, 0
    while done < s.spp:
        n = min(per_pass, s.spp - done)
        acc = tracer.pass_sums(s.seed, k, n)
        sums = acc if sums is None else sums + acc
        dr.eval(sums)
        done, k = done + n, k + 1
        if bar.enabled:
            dr.sync_thread()  # the kernels run asynchronously: wait, so the time left is right
            bar.update(done)
    mean, var = tracer.mean_variance(sums, done)
    wall = time.perf_counter() - t0
    history = dr.kernel_history()
    dr.set_flag(dr.JitFlag.KernelHistory, flag)
    compile_ms = sum(h.get("codegen_time", 0.0) + h.get("backend_time", 0.0) for h in history if not h.get("cache_hit", False))
    if "gamma_output" in tracer.mutants:
        # The student's file holds sRGB-encoded values; the variance follows by the delta method.
        eps = 1e-4
        deriv = (srgb_encode(mean + eps) - srgb_encode(np.maximum(mean - eps, 0))) / (mean + eps - np.maximum(mean - eps, 0))
        var = (var * deriv**2).astype(np.float32)
        mean = srgb_encode(mean).astype(np.float32)

    return RenderResult(
        mean=mean,
        variance=var,
        spp=s.spp,
        seed=s.seed,
        max_depth=s.max_depth,
        renderer="mcrt",
        scene_hash=scene.content_hash(),
        camera=s.camera,
        wall_time=wall,
        compile_time=compile_ms / 1000.0,
        extra={
            "backend": backend,
            "intersector": intersector,
            "light_samples": str(s.light_samples),
            "mis": str(tracer.integrator.mis).lower(),
            "rr_depth": str(s.rr_depth),
            "mutants": ",".join(sorted(tracer.mutants)),
            "drjit_version": dr.__version__,
            "mcrt_version": mcrt.__version__,
        },
    )
