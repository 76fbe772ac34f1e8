"""The standalone tracer: camera samples, tiles, passes, moments -> RenderResult.

A render runs tile by tile (:func:`mcrt.film.run_tiles`): a tile is a run of
consecutive pixels (row-major), and each of its passes traces ``n`` samples
of every pixel of the tile in one kernel launch. A pixel has ``k``
consecutive lanes, and each lane traces up to ``b`` of the pixel's samples
one after another (path regeneration; :func:`lane_layout` picks k and b so
that a launch has enough lanes and each lane enough paths, whatever the
resolution). Memory holds the output image and one tile's sums.

Random numbers: the stream of sample s of pixel p is a function of (seed,
p, s) alone (:class:`mcrt.rng.SampleStreams`); a lane moving on to its next
sample reseeds. A tile's sums are added pass by pass in sample order, so an
image does not depend on the tiling, bit for bit; another pass size deals
the same samples into other float32 partial sums (the same image to
rounding). Seeds and sample ranges enter the kernel as opaque values: a new
seed or spp does not recompile it.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import mcrt  # noqa: F401  (sets DRJIT_LIBLLVM_PATH before drjit loads)
from mcrt.camera import Pinhole
from mcrt.estimator import PathEstimator
from mcrt.film import Progress, RenderResult, run_tiles
from mcrt.geometry import Geometry
from mcrt.host import McrtHost
from mcrt.light import needs_mis
from mcrt.llvm import require_llvm
from mcrt.mutants import camera_jitter, check_mutants, mutate_scene, mutation_values, output_encoding
from mcrt.options import Caustics, EstimatorOptions, trick_options
from mcrt.precision import check_precision
from mcrt.rng import SampleStreams
from mcrt.samplers import PixelSampler, replicate_launch, replicate_pass_size, replicate_variance_scale, scrambled_jitter
from mcrt.scene import RenderSettings, Scene
from mcrt.srgb import encode_output

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


def stream_keys(seed: int, pass_index: int = 0) -> tuple[int, int]:
    """The two 32-bit keys of a seed's random streams (mcrt.rng; the tracer's camera samples use pass_index 0)."""
    key = _mix64(seed * 0x9E3779B97F4A7C15 + pass_index)
    return key & 0xFFFFFFFF, key >> 32


def pixel_jitter(streams, sampler: PixelSampler = PixelSampler(), samples_per_replicate: int | None = None):
    """(u, v) in [0, 1)^2: where in its pixel a camera sample passes, as the pixel sampler places it.

    The one place the tracer draws a camera sample's position in its pixel;
    :meth:`mcrt.camera.Pinhole.ray` maps it to the ray. ``independent``: the
    next two numbers of the sample's stream. ``sobol``: the sample's
    Owen-scrambled Sobol point (:func:`mcrt.samplers.scrambled_jitter`),
    keyed by the stream's pixel key ``h1`` at its sample, with
    ``samples_per_replicate`` (N, a trace-time constant) points per
    replicate.
    """
    if sampler.default:
        return streams.next_1d(), streams.next_1d()
    if samples_per_replicate is None:
        raise ValueError("pixel sampler 'sobol' needs its samples per replicate")
    return scrambled_jitter(streams.h1, streams.sample, samples_per_replicate)


@dataclass
class Tracer:
    """A compiled view of one scene and camera for repeated passes.

    ``caustics`` and ``caustic_pdfs`` are the estimator's split of the paths
    eye D ... D S+ L with a light tracer (:class:`mcrt.options.Caustics`;
    :mod:`mcrt.bidir` builds them): plain path tracing by default.
    ``pixel_sampler`` places the camera samples in their pixels and decides
    how the variance is estimated (:mod:`mcrt.samplers`): a render setting,
    like the depth and the light samples.
    """

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
    tricks: tuple = ()  # sorted (name, value) pairs of the renderer's tricks (mcrt.options.TRICK_OPTIONS)
    pixel_sampler: PixelSampler = PixelSampler()  # where samples land in their pixel (mcrt.samplers)
    caustics: Caustics = field(default_factory=Caustics)
    caustic_pdfs: object = None  # the light tracer's densities, with caustics.caustic_light_paths > 0

    def __post_init__(self):
        import drjit as dr

        self.mutants = check_mutants(self.mutants)
        self.m = backend_module(self.backend)
        scene = mutate_scene(self.scene, self.mutants)
        if self.precision_guard:
            check_precision(scene)  # refuse scenes where float32 would silently give a wrong image
        self.geometry = Geometry(scene, self.m, self.intersector)
        tricks, overrides = dict(self.tricks), mutation_values(self.mutants)
        if set(tricks) & set(overrides):
            raise ValueError(f"option {sorted(set(tricks) & set(overrides))[0]} is set both by a trick and by a mutant")
        # Solid-angle samples have bounded weights, and without light samples there is nothing to weigh: no MIS.
        no_mis = tricks.get("light_sampling") in ("solid_angle", "none")
        self.options = replace(EstimatorOptions.build(
            max_depth=self.max_depth, light_samples=self.light_samples, rr_depth=self.rr_depth,
            mis=(needs_mis(scene) and not no_mis) if self.mis is None else self.mis, **overrides, **tricks,
        ), caustics=self.caustics)
        self.estimator = PathEstimator(McrtHost(self.geometry), self.options, caustic_pdfs=self.caustic_pdfs)
        self.camera_model = Pinhole(scene.camera(self.camera), self.width, self.height, jitter=camera_jitter(self.mutants))
        self._frozen_launch = dr.freeze(self._launch_kernel, limit=8, warn_after=64)  # one recording per layout, a few kept

    def layout(self, spp: int, spp_per_pass: int | None = None) -> tuple[int, int, int]:
        """(lanes per pixel, paths per lane, samples per pixel of one pass) of a render of this tracer at ``spp``."""
        k, b = lane_layout(self.width * self.height, spp_per_pass or spp, self.backend)
        return k, b, min(k * b, spp_per_pass or spp)

    def render(self, *, seed: int, spp: int, progress: bool = True, spp_per_pass: int | None = None,
               tile_pixels: int | None = None, rows: list[tuple[int, int]] | None = None,
               scene_hash: str | None = None) -> RenderResult:
        """The image of ``spp`` samples per pixel at ``seed``: mean and per-sample variance.

        ``spp_per_pass`` caps the samples per pixel of one launch (default:
        as :func:`lane_layout` deals them); ``tile_pixels`` sets the pixels
        of a tile (default TILE_LANES / lanes per pixel) and never changes
        the image. ``rows`` ((first row, count) bands) renders those rows
        alone, stacked in order as the image, like a crop (benchmarks: a
        part of a long render; ``extra['paths']`` counts the paths traced).
        With the ``sobol`` pixel sampler, spp must be a multiple of its
        replicates; no pass straddles two replicates, and the variance is
        the replicates' spread (:mod:`mcrt.samplers`).
        """
        import drjit as dr

        sampler = self.pixel_sampler
        n_rep = None if sampler.default else sampler.samples_per_replicate(spp)
        k, b, per_pass = self.layout(n_rep or spp, spp_per_pass)
        if n_rep:
            per_pass = replicate_pass_size(per_pass, n_rep)
        tile = tile_pixels or max(1, TILE_LANES // k)
        W, H = self.width, self.height
        ranges = [(first * W, count * W) for first, count in rows] if rows else [(0, W * H)]
        total = sum(-(-count // tile) for _, count in ranges) * -(-spp // per_pass)

        def launch(acc, p0, count, first, n):
            return self.launch(seed, acc, range(p0, p0 + count), first, n, k, b, samples_per_replicate=n_rep)

        if n_rep:
            launch = replicate_launch(launch, n_rep)
        totals = run_tiles(launch, width=W, height=H, spp=spp, tile_pixels=tile, spp_per_pass=per_pass,
                           progress=Progress(total, label="mcrt", unit="passes", enabled=progress), pixel_ranges=ranges)
        var = totals.variance * replicate_variance_scale(spp, sampler.replicates) if n_rep else totals.variance
        stat = dict(self.tricks).get("pixel_statistic")
        mean = totals.mean if stat is None else self._statistic(seed, spp, stat).astype(totals.mean.dtype)
        mean, var = encode_output(mean, var, output_encoding(self.mutants))
        c = self.caustics  # recorded with the tricks, where not plain path tracing
        named = sorted((*self.tricks, *((("mirror_caustics", c.mirror_caustics),) if c.mirror_caustics != "all" else ()),
                        *((("caustic_light_paths", c.caustic_light_paths),) if c.caustic_light_paths else ())))
        return RenderResult(
            mean=mean,
            variance=var,
            spp=totals.spp,
            seed=seed,
            max_depth=self.max_depth,
            renderer="mcrt",
            scene_hash=scene_hash or self.scene.content_hash(),
            camera=self.camera,
            wall_time=totals.wall_time,
            compile_time=totals.compile_time,
            extra={
                "backend": self.backend,
                "intersector": self.intersector,
                "light_samples": str(self.light_samples),
                "mis": str(self.options.settings.mis).lower(),
                "rr_depth": str(self.rr_depth),
                "mutants": ",".join(sorted(self.mutants)),
                **({"tricks": ",".join(f"{k}={v}" for k, v in named)} if named else {}),
                **({} if sampler.default else {"pixel_sampler": sampler.name, "variance_method": sampler.variance_method}),
                "paths": str(totals.paths),
                "drjit_version": dr.__version__,
                "mcrt_version": mcrt.__version__,
            },
        )

    def _statistic(self, seed: int, spp: int, how: str) -> np.ndarray:
        """The image of each pixel's ``spp`` samples at ``seed`` (the render's own paths, one sample at a time by
        :meth:`pixel_sums`) combined by :func:`mcrt.film.pixel_statistic` ``how``, (H, W, 3)."""
        import numpy as np

        from mcrt.film import pixel_statistic

        pixels = np.arange(self.width * self.height)
        samples = np.stack([self.pixel_sums(seed, pixels, s, 1)[0] for s in range(spp)])
        return pixel_statistic(samples, how).reshape(self.height, self.width, 3)

    def pixel_sums(self, seed: int, pixels, first_sample: int, n: int, *, spp_per_pass: int | None = None):
        """Sums of x and of x^2 over samples ``first_sample`` .. ``first_sample + n - 1`` of each of ``pixels``.

        ``pixels``: pixel indices (row * width + column) as a NumPy array, a
        list or a Dr.Jit UInt32: any set, any order. Returns (s1, s2),
        float64 NumPy arrays of shape (len(pixels), 3). Sample s of pixel p
        is the same path here as in every other call and in
        :func:`render_tracer` with this seed (its random stream is a function
        of (seed, p, s) alone), so calls over disjoint sample ranges are
        independent and their sums add up to those of the union: the
        primitive for adaptive sampling (per-pixel sample counts). One call's
        sums are a function of (seed, pixels, first_sample, n, spp_per_pass),
        bit for bit; the lanes are laid out by :func:`lane_layout` for
        len(pixels) pixels and ``n`` (or ``spp_per_pass``) samples, in
        launches of at most TILE_LANES lanes.
        """
        import numpy as np

        idx = np.asarray(pixels.numpy() if hasattr(pixels, "numpy") else pixels, dtype=np.int64).ravel()
        if idx.size and (idx.min() < 0 or idx.max() >= self.width * self.height):
            raise ValueError(f"pixel indices must lie in [0, {self.width * self.height}), got {idx.min()}..{idx.max()}")
        if n < 1 or first_sample < 0:
            raise ValueError(f"need n >= 1 and first_sample >= 0, got n={n}, first_sample={first_sample}")
        k, b = lane_layout(max(idx.size, 1), spp_per_pass or n, self.backend)
        per_pass = min(k * b, spp_per_pass or n)
        tile = max(1, TILE_LANES // k)
        s1, s2 = np.zeros((idx.size, 3)), np.zeros((idx.size, 3))
        for p0 in range(0, idx.size, tile):
            acc, chunk = None, self.m.UInt32(idx[p0:p0 + tile].astype(np.uint32))
            for first in range(first_sample, first_sample + n, per_pass):
                acc = self.launch(seed, acc, chunk, first, min(per_pass, first_sample + n - first), k, b)
            s1[p0:p0 + tile] = np.stack([a.numpy() for a in acc[0]], axis=1)
            s2[p0:p0 + tile] = np.stack([a.numpy() for a in acc[1]], axis=1)
        return s1, s2

    def pass_sums(self, seed: int, pass_index: int, n: int):
        """Sums of x and x^2 over ``n`` samples of every pixel, pass ``pass_index``'s: one evaluated Float64 array.

        Laid out (moment, pixel, channel), pixels in row-major order, for
        renderers that loop over passes of the whole image (mcrt.bidir).
        Pass k takes samples k PASS_SAMPLES .. k PASS_SAMPLES + n - 1, so no two
        passes share a sample.
        """
        import drjit as dr

        if not 1 <= n <= PASS_SAMPLES:
            raise ValueError(f"a pass holds 1 to {PASS_SAMPLES} samples per pixel, got {n}")
        m, P = self.m, self.width * self.height
        k, b = lane_layout(P, n, self.backend)
        tile = max(1, TILE_LANES // k)
        out = dr.zeros(m.Float64, 6 * P)
        for p0 in range(0, P, tile):
            count = min(tile, P - p0)
            acc = None
            for first in range(0, n, k * b):
                acc = self.launch(seed, acc, range(p0, p0 + count), pass_index * PASS_SAMPLES + first,
                                  min(k * b, n - first), k, b)
            pixels = pixel_range(m, p0, count)
            for moment in range(2):
                for c in range(3):
                    dr.scatter(out, acc[moment][c], (moment * P + pixels) * 3 + c)
        dr.eval(out)
        return out

    def launch(self, seed: int, acc, pixels, first_sample: int, n: int, k: int, b: int, *,
               samples_per_replicate: int | None = None):
        """``acc`` plus the sums of x and x^2 over samples first_sample .. first_sample + n - 1 of ``pixels``.

        ``pixels``: a UInt32 array of pixel indices, or a ``range`` of them
        (a tile: its start travels with the other per-launch values, and no
        index array is built). ``acc`` (None: zeros) and the result are (sums of x, sums of x^2),
        three evaluated Float64 arrays each, one entry per pixel. ``k`` lanes
        per pixel (a power of two), each tracing up to ``b`` samples, with
        n <= k b. The work is :meth:`_launch_kernel`, frozen (``dr.freeze``):
        Dr.Jit traces the path kernel in Python once per layout and array
        size, and replays the recorded kernels for every later launch. The
        seed's keys and the sample range enter as opaque arrays, so they
        replay the same recording. ``samples_per_replicate``: N of the
        ``sobol`` pixel sampler (a kernel constant; None for ``independent``).
        """
        import drjit as dr

        m = self.m
        if not 1 <= n <= k * b:
            raise ValueError(f"a launch of {k} lanes of {b} paths per pixel holds 1 to {k * b} samples, got {n}")
        tile = isinstance(pixels, range)
        count = len(pixels) if tile else dr.width(pixels)
        # One small array for the per-launch values: one copy to the device instead of several.
        params = m.UInt32([*stream_keys(seed), first_sample, n, pixels.start if tile else 0])
        # acc None and a range are recorded apart from arrays; the width keys the recording too.
        return self._frozen_launch(acc, None if tile else pixels, params, k, b, count, samples_per_replicate)

    def _launch_kernel(self, acc, pixels, params, k: int, b: int, count: int, spr: int | None = None):
        """:meth:`launch` with its per-launch values in ``params`` (UInt32 [key0, key1, first, n, first pixel]).

        ``pixels`` None: the ``count`` pixels from params' first pixel on.
        ``spr``: the pixel sampler's samples per replicate (:func:`pixel_jitter`).

        Lane i k + j (j < k) traces samples first + j b .. of pixel i, at most
        b and none from first + n on (mcrt.estimator.PathEstimator.path_sums;
        each sample from the start of its own stream, mcrt.rng.SampleStreams),
        keeping float32 sums of its samples x and x^2. A pixel's k lanes are
        then added in float64 in lane order (``dr.block_sum``, no atomics) and
        the pass's totals added to ``acc``: a pixel's sums do not depend on
        which thread or tile traced it.
        """
        import drjit as dr

        m = self.m
        key0, key1, first, n, p0 = (dr.gather(m.UInt32, params, i) for i in range(5))
        idx = dr.arange(m.UInt32, count * k)
        i = idx >> (k.bit_length() - 1) if k > 1 else idx  # the lane's pixel among the launch's
        lane = idx & (k - 1) if k > 1 else m.UInt32(0)  # the lane's place among its pixel's lanes
        pixel = p0 + i if pixels is None else (dr.gather(m.UInt32, pixels, i) if k > 1 else m.UInt32(pixels))
        start = lane * b  # the lane's first sample, counted from ``first``
        paths = dr.select(n > start, dr.minimum(n - start, b), 0)
        rng = SampleStreams.start(pixel, first + start, key0, key1)
        camera = self.camera_model
        col, row = camera.pixel_position(pixel)
        stop = first + start + paths  # one past the lane's last sample

        def new_path(ended, streams):
            restart = ended & (streams.sample + 1 < stop)
            streams.restart(restart)
            return restart, *camera.ray(col, row, *pixel_jitter(streams, self.pixel_sampler, spr))

        o, d = camera.ray(col, row, *pixel_jitter(rng, self.pixel_sampler, spr))
        # Lanes past n (paths 0) pad the launch to whole lanes of b: inactive, their sums stay 0.
        sum_x, sum_x2, _ = self.estimator.path_sums(o, d, rng, active=paths > 0, new_path=new_path)
        sums = [m.Float64(v[c]) for v in (sum_x, sum_x2) for c in range(3)]
        if k > 1:
            dr.eval(sums)  # once: a block sum of an unevaluated result would rerun the path kernel per channel
            sums = [dr.block_sum(v, k) for v in sums]
        if acc is not None:
            sums = [a + v for a, v in zip((*acc[0], *acc[1]), sums)]
        out = (tuple(sums[:3]), tuple(sums[3:]))
        dr.eval(out)
        return out


#: Paths one lane traces in turn, at most: its float32 sums of x and x^2 stay exact to about a
#: millionth, and a packet's lanes, each with this many paths, end close together.
PATHS_PER_LANE = 16
#: Lanes a launch has at least on the CPU, where it has the samples. Dr.Jit's LLVM backend splits a
#: launch of up to 2 x 16384 lanes per core into one block per core, larger ones into blocks of
#: 16384: 4096 lanes (256 packets) keep 16 cores busy with work that evens out, and leave a
#: 64x64 image its 16 paths per lane.
MIN_LANES = 1 << 12
#: The same on a GPU, which needs many more threads in flight to hide its latencies.
MIN_LANES_CUDA = 1 << 16
#: Lanes a launch has at most (a tile holds TILE_LANES / k pixels): bounds a tile's sums and
#: leaves enough launches for the progress line, whatever the resolution.
TILE_LANES = 1 << 18
#: The samples of pass k of :meth:`Tracer.pass_sums` start at k * PASS_SAMPLES (passes of at most as many).
PASS_SAMPLES = 1 << 16


def lane_layout(pixels: int, n: int, backend: str = "llvm") -> tuple[int, int]:
    """(k lanes per pixel, b paths per lane) of launches of up to ``n`` samples per pixel over ``pixels`` pixels.

    One lane per pixel where the pixels alone give MIN_LANES lanes
    (MIN_LANES_CUDA on the cuda backend); fewer pixels get more lanes each
    (a power of two, no more than n needs), so a launch keeps every core
    busy. Each lane then traces b = ceil(n / k) samples, at most
    PATHS_PER_LANE; a pass holds k b samples per pixel.
    """
    if pixels < 1 or n < 1:
        raise ValueError(f"need pixels >= 1 and n >= 1, got {pixels} and {n}")
    min_lanes = MIN_LANES_CUDA if backend == "cuda" else MIN_LANES
    k = 1
    if pixels < min_lanes:
        k = min(1 << (-(-min_lanes // pixels) - 1).bit_length(), 1 << (n - 1).bit_length())
    return k, min(PATHS_PER_LANE, -(-n // k))


def pixel_range(m, first: int, count: int):
    """Pixel indices first .. first + count - 1 as a UInt32 of backend ``m`` (the start opaque: one kernel for every tile)."""
    import drjit as dr

    return dr.opaque(m.UInt32, first) + dr.arange(m.UInt32, count)


_TRACERS: dict = {}
#: Tracers kept for reuse (a benchmark interleaving this many configurations reuses each one's kernels).
TRACERS_KEPT = 16


def _tracer(scene: Scene, *args, scene_hash: str | None = None) -> Tracer:
    """A Tracer for these settings, reused across renders of the same scene content (a few kept)."""
    key = (scene_hash or scene.content_hash(), scene.path, *args)
    tracer = _TRACERS.get(key)
    if tracer is None:
        tracer = Tracer(scene, *args)
        if len(_TRACERS) >= TRACERS_KEPT:
            _TRACERS.pop(next(iter(_TRACERS)))
        _TRACERS[key] = tracer
    return tracer


def render_tracer(scene: Scene, settings: RenderSettings, *, backend: str = "llvm", progress: bool = True,
                  spp_per_pass: int | None = None, mutants=(), intersector: str = "convex", mis: bool | None = None,
                  precision_guard: bool = True, tile_pixels: int | None = None, rows: list[tuple[int, int]] | None = None,
                  pixel_sampler: str = "independent", replicates: int | None = None, **tricks) -> RenderResult:
    """Render ``scene`` at ``settings`` with the standalone tracer: mean and per-sample variance.

    Called through :func:`mcrt.render.render` (renderer ``mcrt``). ``mis``
    forces multiple importance sampling on or off (default: where the scene
    needs it). ``precision_guard=False`` renders scenes that
    :func:`mcrt.precision.check_precision` would refuse (only to measure
    where float32 breaks). ``tricks`` are the estimator's efficiency tricks
    (:data:`mcrt.options.TRICK_OPTIONS`, off at their defaults).
    ``pixel_sampler`` and ``replicates`` choose where samples land in their
    pixel and how the variance is estimated (:mod:`mcrt.samplers`; 'sobol'
    needs spp a multiple of the replicates). The other options are
    :meth:`Tracer.render`'s. Tracers are kept for reuse across
    renders of the same scene content (their kernels are recorded once).
    """
    s = settings
    scene_hash = scene.content_hash()
    tracer = _tracer(scene, s.camera, s.width, s.height, s.max_depth, s.light_samples, s.rr_depth, backend, intersector,
                     frozenset(mutants), precision_guard, mis, trick_options(tricks),
                     PixelSampler.of(pixel_sampler, replicates), scene_hash=scene_hash)
    return tracer.render(seed=s.seed, spp=s.spp, progress=progress, spp_per_pass=spp_per_pass, tile_pixels=tile_pixels,
                         rows=rows, scene_hash=scene_hash)
