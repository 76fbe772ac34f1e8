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

from dataclasses import dataclass


import mcrt  # noqa: F401  (sets DRJIT_LIBLLVM_PATH before drjit loads)
from mcrt.camera import Pinhole
from mcrt.estimator import EstimatorOptions, PathEstimator
from mcrt.film import Progress, RenderResult, run_passes, samples_per_pass
from mcrt.imageio import encode_output
from mcrt.geometry import Geometry
from mcrt.host import McrtHost
from mcrt.light import needs_mis
from mcrt.llvm import require_llvm
from mcrt.mutants import camera_jitter, check_mutants, estimator_overrides, mutate_scene, output_encoding
from mcrt.precision import check_precision
from mcrt.rng import WeylRng
from mcrt.scene import RenderSettings, Scene
from mcrt.tricks.options import trick_options

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
    mis: bool | None = None  # None: where the scene needs it (mcrt.light.needs_mis)
    tricks: tuple = ()  # sorted (name, value) pairs of EstimatorOptions' efficiency tricks (mcrt.tricks.options)

    def __post_init__(self):
        import drjit as dr

        self.mutants = check_mutants(self.mutants)
        self.m = backend_module(self.backend)
        scene = mutate_scene(self.scene, self.mutants)
        if self.precision_guard:
            check_precision(scene)  # refuse scenes where float32 would silently give a wrong image
        self.geometry = Geometry(scene, self.m, self.intersector)
        tricks, overrides = dict(self.tricks), estimator_overrides(self.mutants)
        if set(tricks) & set(overrides):
            raise ValueError(f"option {sorted(set(tricks) & set(overrides))[0]} is set both by a trick and by a mutant")
        solid_angle = tricks.get("light_sampling") == "solid_angle"  # bounded weights: no MIS needed
        self.options = EstimatorOptions(
            max_depth=self.max_depth, light_samples=self.light_samples, rr_depth=self.rr_depth,
            mis=(needs_mis(scene) and not solid_angle) if self.mis is None else self.mis, **overrides, **tricks,
        )
        self.estimator = PathEstimator(McrtHost(self.geometry), self.options)
        self.camera_model = Pinhole(scene.camera(self.camera), self.width, self.height, jitter=camera_jitter(self.mutants))
        self._frozen_pass = dr.freeze(self._pass_kernel, limit=8, warn_after=64)  # one recording per pass size, a few kept

    def pass_sums(self, seed: int, pass_index: int, n: int):
        """Per-pixel sums of x and x^2 over ``n`` new samples per pixel: one evaluated Float64 array.

        Laid out (moment, pixel, channel): the sums of x, then those of x^2,
        pixels in row-major order. The work is :meth:`_pass_kernel`, frozen
        (``dr.freeze``): Dr.Jit traces the path kernel in Python once per
        pass size and replays the recorded kernels for every later pass,
        which then skips the Python tracing. The seed's keys
        enter as opaque arrays, so a new seed replays the same recording.
        """
        import drjit as dr

        k0, k1 = stream_keys(seed, pass_index)
        return self._frozen_pass(dr.opaque(self.m.UInt32, k0), dr.opaque(self.m.UInt32, k1), n)

    def _pass_kernel(self, key0, key1, n: int):
        """:meth:`pass_sums` for the pass keyed by the UInt32 arrays (key0, key1) (mcrt.rng.WeylRng.seeded).

        Each pixel gets consecutive lanes (:func:`pass_layout`), and each lane
        traces its share of the pixel's n paths one after another
        (mcrt.estimator.PathEstimator.path_sums), keeping the sums of its
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
        eye = m.Array3f(*self.camera_model.eye)

        def camera_ray(u, v):
            return eye, self.camera_model.direction(col, row, u, v)

        used = paths > 0  # lanes past n pad the pass to a power of two per pixel
        o, d = camera_ray(rng.next_1d(), rng.next_1d())
        sum_x, sum_x2, _ = self.estimator.path_sums(o, d, rng, paths=dr.maximum(paths, 1), camera_ray=camera_ray)

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


def render_tracer(scene: Scene, settings: RenderSettings, *, backend: str = "llvm", progress: bool = True,
                  spp_per_pass: int | None = None, mutants=(), intersector: str = "convex", mis: bool | None = None,
                  precision_guard: bool = True, bidirectional: bool = False, mirror_caustics: str = "all",
                  **tricks) -> RenderResult:
    """Render ``scene`` at ``settings`` with the standalone tracer: mean and per-sample variance.

    Called through :func:`mcrt.render.render` (renderer ``mcrt``). ``mis``
    forces multiple importance sampling on or off (default: where the scene
    needs it). ``precision_guard=False`` renders scenes that
    :func:`mcrt.precision.check_precision` would refuse (only to measure
    where float32 breaks). ``tricks`` are the estimator's efficiency tricks
    (:data:`mcrt.tricks.options.TRICK_OPTIONS`, off at their defaults).
    ``bidirectional`` adds light tracing for the paths eye D ... D S+ L
    (:func:`mcrt.bidir.render_bidirectional`); ``mirror_caustics``
    (:class:`mcrt.estimator.EstimatorOptions`) 'only' renders those paths
    alone, to check it.
    """
    import drjit as dr

    s = settings
    if bidirectional:
        from mcrt.bidir import render_bidirectional

        if mutants or mirror_caustics != "all":
            raise ValueError("bidirectional rendering takes no mutants and no mirror_caustics (it sets them itself)")
        return render_bidirectional(scene, s, backend=backend, progress=progress, spp_per_pass=spp_per_pass,
                                    intersector=intersector, mis=mis, precision_guard=precision_guard,
                                    tricks=trick_options(tricks))
    caustics = (("mirror_caustics", mirror_caustics),) if mirror_caustics != "all" else ()
    tracer = _tracer(scene, s.camera, s.width, s.height, s.max_depth, s.light_samples, s.rr_depth, backend, intersector,
                     frozenset(mutants), precision_guard, mis, tuple(sorted(trick_options(tricks) + caustics)))
    per_pass = spp_per_pass or pass_size(s.width, s.height, s.spp)
    totals = run_passes(lambda k, n: tracer.pass_sums(s.seed, k, n), width=s.width, height=s.height, spp=s.spp,
                        spp_per_pass=per_pass, progress=Progress(s.spp, label="mcrt", enabled=progress))
    mean, var = encode_output(totals.mean, totals.variance, output_encoding(tracer.mutants))
    return RenderResult(
        mean=mean,
        variance=var,
        spp=totals.spp,
        seed=s.seed,
        max_depth=s.max_depth,
        renderer="mcrt",
        scene_hash=scene.content_hash(),
        camera=s.camera,
        wall_time=totals.wall_time,
        compile_time=totals.compile_time,
        extra={
            "backend": backend,
            "intersector": intersector,
            "light_samples": str(s.light_samples),
            "mis": str(tracer.options.mis).lower(),
            "rr_depth": str(s.rr_depth),
            "mutants": ",".join(sorted(tracer.mutants)),
            **({"tricks": ",".join(f"{k}={v}" for k, v in tracer.tricks)} if tracer.tricks else {}),
            "drjit_version": dr.__version__,
            "mcrt_version": mcrt.__version__,
        },
    )
