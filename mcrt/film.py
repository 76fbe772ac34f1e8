"""Render results and the pass loop shared by every renderer.

A render is accumulated in passes of a few samples per pixel, so memory does
not grow with spp. Each pass returns per-pixel sums of the samples x and of
x^2 (float64, in Dr.Jit's memory); the totals stay on the device, and from
them the mean and the unbiased per-sample variance

    mean = S1 / n,    var = (S2 - S1^2 / n) / (n - 1)

are formed once at the end. Two loops: :func:`run_passes` (every pixel in
each pass, the Mitsuba renderers) and :func:`run_tiles` (mcrt's tracer:
every pass of one tile of pixels before the next tile, so memory does not
grow with the resolution either, beyond the output image). Passes are
independent given their seeds, so results merge exactly in any order
(:func:`merge`).
"""

from __future__ import annotations

import contextlib
import sys
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np


@dataclass
class RenderResult:
    """A rendered image with its per-pixel, per-sample variance and provenance.

    ``mean`` and ``variance`` are (height, width, 3) float32 linear RGB; the
    variance is that of one sample (divide by ``spp`` for the variance of the
    mean).
    """

    mean: np.ndarray
    variance: np.ndarray | None
    spp: int
    seed: int
    max_depth: int
    renderer: str
    scene_hash: str = ""
    camera: str = ""
    wall_time: float = 0.0
    compile_time: float | None = None
    extra: dict[str, str] = field(default_factory=dict)

    @property
    def shape(self) -> tuple[int, int]:
        return self.mean.shape[:2]


@dataclass
class Moments:
    """Running per-pixel sums of x and x^2 (float64), and the sample count."""

    s1: np.ndarray
    s2: np.ndarray
    n: int = 0

    @classmethod
    def zeros(cls, height: int, width: int, channels: int = 3) -> "Moments":
        return cls(np.zeros((height, width, channels)), np.zeros((height, width, channels)), 0)

    def add(self, s1: np.ndarray, s2: np.ndarray, n: int) -> None:
        if self.n == 0:
            # Take the first sums over (later adds update them in place; callers
            # pass fresh arrays): adding them to fresh zeros would first touch
            # every page of the zero arrays, a cost that grows with the image.
            self.s1, self.s2 = np.asarray(s1, dtype=np.float64), np.asarray(s2, dtype=np.float64)
        else:
            self.s1 += s1
            self.s2 += s2
        self.n += n

    def mean(self) -> np.ndarray:
        return (self.s1 / max(self.n, 1)).astype(np.float32)

    def variance(self) -> np.ndarray:
        if self.n < 2:
            return np.zeros(self.s1.shape, np.float32)
        var = (self.s2 - self.s1 * self.s1 / self.n) / (self.n - 1)
        return np.maximum(var, 0.0).astype(np.float32)


def merge(results: list[RenderResult]) -> RenderResult:
    """Combine independent renders of one image into one, weighting by spp.

    Means and second moments are pooled exactly: S1 = sum n_i m_i,
    S2 = sum ((n_i - 1) v_i + n_i m_i^2).
    """
    if not results:
        raise ValueError("nothing to merge")
    methods = {r.extra.get("variance_method", "samples") for r in results}
    if methods != {"samples"}:
        return _merge_replicates(results)
    m = Moments.zeros(*results[0].shape)
    for r in results:
        mean = r.mean.astype(np.float64)
        var = np.zeros_like(mean) if r.variance is None else r.variance.astype(np.float64)
        m.add(r.spp * mean, (r.spp - 1) * var + r.spp * mean * mean, r.spp)
    first = results[0]
    return RenderResult(
        mean=m.mean(),
        variance=m.variance(),
        spp=m.n,
        seed=first.seed,
        max_depth=first.max_depth,
        renderer=first.renderer,
        scene_hash=first.scene_hash,
        camera=first.camera,
        wall_time=sum(r.wall_time for r in results),
        extra=dict(first.extra, merged_seeds=",".join(str(r.seed) for r in results)),
    )


def _merge_replicates(results: list[RenderResult]) -> RenderResult:
    """Merge renders whose variance comes from replicates (mcrt.samplers), each with spp / R samples per replicate.

    The mean is spp-weighted; each render's variance of its mean, var_i /
    spp_i, is pooled as that of the weighted mean, and reported times the
    total spp as usual: var = sum spp_i var_i / sum spp_i. Its degrees of
    freedom add up: sum (R_i - 1), recorded as 'replicates:(that + 1)'.
    """
    dofs = []
    for r in results:
        kind, _, count = r.extra.get("variance_method", "samples").partition(":")
        if kind not in ("replicates", "batches") or not count.isdigit() or r.variance is None:
            raise ValueError("cannot merge renders whose variance comes from replicates with renders whose does not")
        dofs.append(int(count) - 1)
    n = sum(r.spp for r in results)
    mean = sum(r.spp * r.mean.astype(np.float64) for r in results) / n
    var = sum(r.spp * r.variance.astype(np.float64) for r in results) / n
    first = results[0]
    return RenderResult(
        mean=mean.astype(np.float32), variance=var.astype(np.float32), spp=n, seed=first.seed,
        max_depth=first.max_depth, renderer=first.renderer, scene_hash=first.scene_hash, camera=first.camera,
        wall_time=sum(r.wall_time for r in results),
        extra=dict(first.extra, merged_seeds=",".join(str(r.seed) for r in results),
                   variance_method=f"replicates:{sum(dofs) + 1}"),
    )


class Progress:
    """Prints 'label: done/total unit (pct) elapsed, ~left' to stderr.

    On a terminal the line is rewritten in place; otherwise a line is printed
    at most every ``every`` seconds, so logs stay short.
    """

    def __init__(self, total: int, label: str = "render", unit: str = "spp", enabled: bool = True, every: float = 5.0):
        self.total, self.label, self.unit, self.enabled, self.every = total, label, unit, enabled, every
        self.start = time.perf_counter()
        self.last = -1e9
        self.tty = sys.stderr.isatty()

    def update(self, done: int, left: float | None = None) -> None:
        """Report ``done`` of the total; ``left`` (seconds) overrides the linear estimate of the time left."""
        if not self.enabled:
            return
        now = time.perf_counter()
        if done < self.total and not self.tty and now - self.last < self.every:
            return
        self.last = now
        el = now - self.start
        if left is None:
            left = el / done * (self.total - done) if done else float("nan")
        msg = f"{self.label}: {done}/{self.total} {self.unit} ({100 * done / self.total:.0f}%) {el:.1f} s, ~{left:.1f} s left"
        end = "\n" if (done >= self.total or not self.tty) else ""
        print(("\r" if self.tty else "") + msg.ljust(72), end=end, file=sys.stderr, flush=True)


def pixel_statistic(samples: np.ndarray, how: str) -> np.ndarray:
    """Each pixel's value of its samples (axis 0 of ``samples``, channel by channel) by statistic ``how`` of
    :data:`mcrt.options.PIXEL_STATISTICS`: 'median', or 'trimmed_5' / 'trimmed_10' (the mean with that percentage of
    the lowest and of the highest samples dropped, as scipy.stats.trim_mean)."""
    if how == "median":
        return np.median(samples, axis=0)
    if how.startswith("trimmed_"):
        from scipy.stats import trim_mean

        return trim_mean(samples, int(how.split("_")[1]) / 100.0, axis=0)
    raise ValueError(f"no pixel statistic {how!r}")


def mean_variance(sums, n: int, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Mean and unbiased per-sample variance (float32, H x W x 3) from device sums laid out (moment, pixel, channel).

    The formulas of :class:`Moments`, evaluated by Dr.Jit in one small kernel
    (NumPy would allocate and traverse a temporary image per operation).
    The count is opaque: a true division (Dr.Jit turns a division by a
    literal into a product with its reciprocal), and one kernel for every spp.
    """
    import drjit as dr

    Float64 = type(sums)
    Float, UInt32 = dr.float32_array_t(Float64), dr.uint32_array_t(Float64)
    size = 3 * width * height
    idx = dr.arange(UInt32, size)
    count = dr.opaque(Float64, n)
    s1 = dr.gather(Float64, sums, idx)
    mean = Float(s1 / count)
    if n < 2:
        var = dr.zeros(Float, size)
    else:
        s2 = dr.gather(Float64, sums, idx + size)
        var = Float(dr.maximum((s2 - s1 * s1 / count) / dr.opaque(Float64, n - 1), 0.0))
    dr.eval(mean, var)
    shape = (height, width, 3)
    return mean.numpy().reshape(shape), var.numpy().reshape(shape)


@dataclass
class PassTotals:
    """What :func:`run_passes` returns: the image, its sample count and where the time went."""

    mean: np.ndarray
    variance: np.ndarray
    spp: int
    wall_time: float  # every pass, JIT compilation included, after the device finished
    compile_time: float  # the part spent generating and compiling kernels (Dr.Jit's kernel history)
    paths: int = 0  # paths traced (fewer than pixels x spp where run_tiles stopped early)


def compile_seconds(history: list[dict]) -> float:
    """Seconds spent generating and compiling kernels (codegen + backend) in a Dr.Jit kernel history."""
    import drjit as dr

    return sum(float(h.get("codegen_time", 0.0)) + float(h.get("backend_time", 0.0))
               for h in history if h.get("type") == dr.KernelType.JIT) / 1000.0


PassFn = Callable[[int, int], object]


def run_passes(pass_sums: PassFn, *, width: int, height: int, spp: int, spp_per_pass: int, progress: Progress) -> PassTotals:
    """Call ``pass_sums(pass_index, n)`` until ``spp`` samples per pixel are summed: the one pass loop.

    ``pass_sums`` returns an evaluated Dr.Jit Float64 array of the sums of x
    and x^2 over its ``n`` new samples per pixel, laid out (moment, pixel,
    channel); pass ``k`` must use random numbers that no other pass uses. The
    sums are added on the device, pass by pass.
    """
    import drjit as dr

    if spp_per_pass < 1:
        raise ValueError(f"spp_per_pass must be >= 1, got {spp_per_pass}")
    with _clock() as clock:
        sums, done, k = None, 0, 0
        while done < spp:
            n = min(spp_per_pass, spp - done)
            acc = pass_sums(k, n)
            sums = acc if sums is None else sums + acc
            dr.eval(sums)
            done, k = done + n, k + 1
            if progress.enabled:
                dr.sync_thread()  # the kernels run asynchronously: wait, so the time left is right
                progress.update(done)
        mean, var = mean_variance(sums, done, width, height)
    return PassTotals(mean, var, done, clock['wall'], clock['compile'])


def tile_mean_variance(s1, s2, n: int):
    """Mean and unbiased per-sample variance of a tile from its device sums (three Float64 arrays each).

    The formulas of :class:`Moments`, with the count opaque as in
    :func:`mean_variance`, as one unevaluated float32 Dr.Jit array laid out
    (moment, pixel, channel): the tile's mean, then its variance. Its lanes
    are the entries, so writing it into the image is one kernel.
    """
    import drjit as dr

    Float64 = type(s1[0])
    Float, UInt32 = dr.float32_array_t(Float64), dr.uint32_array_t(Float64)
    size = dr.width(s1[0])
    j = dr.arange(UInt32, 6 * size)
    half = dr.opaque(UInt32, 3 * size)  # opaque: one kernel for every tile size
    second = j >= half
    k = dr.select(second, j - half, j)
    pixel, channel = k // 3, k % 3

    def gather(sums):
        out = dr.gather(Float64, sums[2], pixel)
        for c in (1, 0):
            out = dr.select(channel == c, dr.gather(Float64, sums[c], pixel), out)
        return out

    count = dr.opaque(Float64, n)
    a = gather(s1)
    if n < 2:
        return Float(dr.select(second, 0.0, a / count))
    var = dr.maximum((gather(s2) - a * a / count) / dr.opaque(Float64, n - 1), 0.0)
    return Float(dr.select(second, var, a / count))


#: launch(acc, first_pixel, pixels, first_sample, n) -> acc: the tile's running sums after n more samples per pixel.
LaunchFn = Callable[[object, int, int, int, int], object]


def run_tiles(launch: LaunchFn, *, width: int, height: int, spp: int, tile_pixels: int, spp_per_pass: int,
              progress: Progress, pixel_ranges: list[tuple[int, int]] | None = None) -> PassTotals:
    """Render tile by tile: every pass of one tile of consecutive pixels, then the next tile.

    Memory is the output image and one tile's sums, whatever the resolution
    and spp. ``launch`` adds ``n`` samples per pixel (those from
    ``first_sample`` on) to the tile's running sums ``acc`` (None before the
    first pass) and returns them, as (sums of x, sums of x^2), three evaluated
    Float64 arrays each. A tile's mean and variance are formed on the device
    and copied into the image when its last pass is done.
    ``pixel_ranges`` ((first pixel, count) pairs of whole rows, default the
    whole image) renders those pixels alone, and the image holds them alone,
    their rows stacked in order (benchmarks time bands of a long render, as
    a crop): ``PassTotals.paths`` counts the paths traced.
    """
    import drjit as dr

    if spp_per_pass < 1 or tile_pixels < 1:
        raise ValueError(f"spp_per_pass and tile_pixels must be >= 1, got {spp_per_pass} and {tile_pixels}")
    pixels = width * height
    ranges = pixel_ranges or [(0, pixels)]
    if any(first < 0 or count < 1 or first + count > pixels or first % width or count % width for first, count in ranges):
        raise ValueError(f"pixel ranges must be whole rows within the {width}x{height} image, got {ranges}")
    covered = sum(count for _, count in ranges)
    # The image on the device, laid out (moment, pixel, channel), every entry written by a tile: memory
    # the allocator recycles across renders (a fresh host copy of a large image costs its page faults).
    image = None
    with _clock() as clock:
        launches, paths, done = 0, 0, 0  # done: pixels of the image written so far
        for start, length in ranges:
            for p0 in range(start, start + length, tile_pixels):
                count, acc = min(tile_pixels, start + length - p0), None
                for first in range(0, spp, spp_per_pass):
                    n = min(spp_per_pass, spp - first)
                    acc = launch(acc, p0, count, first, n)
                    clock["drain"]()  # the history keeps every launch's kernel source: empty it as the render goes
                    launches, paths = launches + 1, paths + count * n
                    if progress.enabled:
                        dr.sync_thread()  # the kernels run asynchronously: wait, so the time left is right
                        progress.update(launches)
                tile = tile_mean_variance(*acc, spp)
                if count == covered:
                    image = tile  # one tile: its output is the image
                else:
                    if image is None:
                        image = dr.empty(type(tile), 6 * covered)
                    UInt32 = dr.uint32_array_t(type(tile))
                    j = dr.arange(UInt32, 6 * count)  # opaque offsets: one kernel for every tile
                    shift = dr.select(j >= dr.opaque(UInt32, 3 * count), dr.opaque(UInt32, 3 * (covered - count)), 0)
                    dr.scatter(image, tile, j + shift + dr.opaque(UInt32, 3 * done))
                dr.eval(image)
                done += count
    out = image.numpy().reshape(2, covered // width, width, 3)  # a view of the device's memory
    return PassTotals(out[0], out[1], spp, clock["wall"], clock["compile"], paths)


@contextlib.contextmanager
def _clock():
    """Times the block from an idle device with Dr.Jit's kernel history on: fills 'wall' and 'compile' (seconds).

    ``drain()`` adds the compile time recorded so far and empties the
    history, whose entries hold each launch's kernel source (a long render
    would otherwise grow by that much per launch).
    """
    import drjit as dr

    compiled = [0.0]

    def drain() -> None:
        compiled[0] += compile_seconds(dr.kernel_history())

    out: dict = {"drain": drain}
    was_recording = dr.flag(dr.JitFlag.KernelHistory)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        dr.kernel_history_clear()
        dr.sync_thread()
        t0 = time.perf_counter()
        yield out
        out["wall"] = time.perf_counter() - t0
        drain()
        out["compile"] = compiled[0]
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, was_recording)


def samples_per_pass(width: int, height: int, spp: int, budget: int = 1 << 22) -> int:
    """Samples per pixel in one pass so that one pass traces at most ``budget`` paths."""
    return max(1, min(spp, budget // max(width * height, 1)))
