r"""Early stopping (adaptive sampling): per-pixel sample counts from a budget, naive and unbiased.

Both schemes spend the same budget, ``spp`` samples per pixel on average,
and measure a pixel's error as its estimated relative variance of the mean
(the relMSE metric's weighting, :data:`mcrt.metrics.RELMSE_EPS`):

    e_i^2 = mean_c s_ic^2 / (n_i (m_ic^2 + eps)),

with m_ic and s_ic^2 the mean and per-sample variance of pixel i's samples.

``naive``
    Every pixel starts with :data:`NAIVE_FIRST` samples; each round then
    doubles the samples of the pixels whose e_i is still above the target
    tau, until the budget is spent; the estimate is the mean of all of a
    pixel's samples. tau is the error at which the first samples' estimates
    a_i predict the budget to be spent: sum_i max(n_first, a_i / tau^2) =
    spp x pixels. The samples that decide when to stop
    are the ones that estimate: a pixel whose samples so far missed its
    rare bright paths (fireflies) has a low mean *and* a low variance, and
    stops, keeping its low mean. The estimator is biased (Kirk and Arvo
    1991), darker where the integrand is heavy-tailed.

``two-stage``
    A pilot of n_0 samples per pixel decides the budget of each pixel,
    n_i proportional to sqrt(a_i), a_i = mean_c s_ic^2 / (m_ic^2 + eps) (the
    allocation that minimises sum_i a_i / n_i for a fixed sum_i n_i); the
    estimate uses only the n_i fresh samples that follow. Given the
    pilot, n_i is fixed and the fresh samples are independent of it, so
    E[mean_i | n_i] is the pixel's radiance: unbiased. The pilot's samples
    are spent, not used.

Sample s of pixel p is the same path in every call
(:meth:`mcrt.tracer.Tracer.pixel_sums`: streams keyed by (seed, p, s)), so
rounds over disjoint sample ranges are independent.

The result records the budget as its ``spp`` and, as its ``variance``,
each pixel's per-sample variance scaled to it, s_i^2 spp / n_i, so that
variance / spp is the pixel's variance of the mean, as the comparison
(:func:`mcrt.stats.policy.compare`) reads it. The comparison's variance
floor against a reference of another sample count belongs at each pixel's
own count: :func:`floor_at_counts`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from mcrt import metrics as M
from mcrt.film import RenderResult
from mcrt.scene import RenderSettings, Scene

SCHEMES = ("naive", "two-stage")
#: Samples of every pixel before the naive scheme first asks whether it has converged.
NAIVE_FIRST = 8
#: Fewest samples of a pixel's estimate (two for its variance).
MIN_SAMPLES = 2
#: Sample counts of the two-stage scheme are rounded to this geometric ladder (fewer, larger launches).
LEVEL_RATIO = 2.0


@dataclass
class Sums:
    """Per-pixel running sums (P, 3) of x and x^2, and the sample count of each pixel (P,)."""

    s1: np.ndarray
    s2: np.ndarray
    n: np.ndarray

    @classmethod
    def zeros(cls, pixels: int) -> "Sums":
        return cls(np.zeros((pixels, 3)), np.zeros((pixels, 3)), np.zeros(pixels, dtype=np.int64))

    def add(self, idx: np.ndarray, s1: np.ndarray, s2: np.ndarray, n: int) -> None:
        self.s1[idx] += s1
        self.s2[idx] += s2
        self.n[idx] += n

    def mean(self) -> np.ndarray:
        return self.s1 / np.maximum(self.n, 1)[:, None]

    def variance(self) -> np.ndarray:
        n = self.n[:, None].astype(np.float64)
        return np.maximum((self.s2 - self.s1 * self.s1 / np.maximum(n, 1)) / np.maximum(n - 1, 1), 0.0)


def relative_variance(s: Sums) -> np.ndarray:
    """a_i = mean_c s_ic^2 / (m_ic^2 + eps): a pixel's per-sample variance relative to its squared mean."""
    m = s.mean()
    return (s.variance() / (m * m + M.RELMSE_EPS)).mean(axis=1)


def allocate(a: np.ndarray, budget: int, *, minimum: int = MIN_SAMPLES) -> np.ndarray:
    """n_i proportional to sqrt(a_i), at least ``minimum``, on a geometric ladder of levels, summing to about ``budget``.

    Rounding to the ladder moves the sum; the proportionality constant is
    then bisected so that the rounded counts add up to ``budget`` or just
    below (the report records the samples traced).
    """
    w = np.sqrt(np.maximum(a, 0.0))
    share = np.full(a.shape, 1.0 / a.size) if w.sum() <= 0 else w / w.sum()
    levels = _levels(minimum, max(int(budget * share.max()) + 1, minimum))

    def rounded(scale):
        n = np.maximum(budget * scale * share, minimum)
        pick = np.clip(np.searchsorted(levels, n), 1, len(levels) - 1)
        lo, hi = levels[pick - 1], levels[pick]
        return np.where(n - lo <= hi - n, lo, hi).astype(np.int64)

    lo, hi = 0.0, 2.0
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if rounded(mid).sum() <= budget else (lo, mid)
    return rounded(lo)


def _levels(lo: int, hi: int) -> np.ndarray:
    out, v = [lo], float(lo)
    while out[-1] < hi:
        v *= LEVEL_RATIO
        out.append(max(int(round(v)), out[-1] + 1))
    return np.array(out, dtype=np.int64)


def _trace_levels(tracer, seed: int, sums: Sums, counts: np.ndarray, first: int) -> None:
    """Samples first .. first + counts_i - 1 of every pixel i, launched level by level (pixels with equal counts together)."""
    done = 0
    for level in np.unique(counts):
        idx = np.nonzero(counts >= level)[0]
        n = int(level) - done
        if n > 0:
            s1, s2 = tracer.pixel_sums(seed, idx, first + done, n)
            sums.add(idx, s1, s2, n)
        done = int(level)


def two_stage(tracer, seed: int, pixels: int, spp: int) -> tuple[Sums, int]:
    """The unbiased scheme: (the fresh samples' sums, the pilot's samples per pixel)."""
    pilot_n = max(4, spp // 8)
    pilot = Sums.zeros(pixels)
    everyone = np.arange(pixels)
    pilot.add(everyone, *tracer.pixel_sums(seed, everyone, 0, pilot_n), pilot_n)
    counts = allocate(relative_variance(pilot), (spp - pilot_n) * pixels)
    fresh = Sums.zeros(pixels)
    _trace_levels(tracer, seed, fresh, counts, pilot_n)
    return fresh, pilot_n


def error_target(a: np.ndarray, first: int, budget: int) -> float:
    """The tau whose predicted sample counts max(first, a_i / tau^2) add up to ``budget`` (bisection in log tau)."""
    def spent(tau):
        return np.maximum(first, a / (tau * tau)).sum()

    lo, hi = 1e-8, 1e4
    for _ in range(100):
        mid = np.sqrt(lo * hi)
        lo, hi = (mid, hi) if spent(mid) > budget else (lo, mid)
    return float(hi)


def naive(tracer, seed: int, pixels: int, spp: int) -> Sums:
    """The biased scheme: rounds that double the samples of every pixel whose own samples say it has not converged."""
    n = min(NAIVE_FIRST, spp)
    sums = Sums.zeros(pixels)
    active = np.arange(pixels)
    sums.add(active, *tracer.pixel_sums(seed, active, 0, n), n)
    tau = error_target(relative_variance(sums), n, spp * pixels)
    left = (spp - n) * pixels
    while left >= n:
        error = np.sqrt(relative_variance(sums) / sums.n)
        active = active[error[active] > tau]  # a pixel that stopped keeps its samples, and so its error: it stays stopped
        if active.size == 0:
            break
        if active.size * n > left:  # the last round: the pixels with the largest errors
            active = active[np.argsort(error[active])[::-1][: left // n]]
        sums.add(active, *tracer.pixel_sums(seed, active, n, n), n)  # every active pixel has n samples: one launch
        left -= active.size * n
        n *= 2
    return sums


_TRACERS: dict = {}


def adaptive_tracer(scene: Scene, settings: RenderSettings, backend: str):
    """A tracer of these settings (kept: its kernels are compiled once)."""
    from mcrt.tracer import Tracer

    s = settings
    key = (scene.content_hash(), s.camera, s.width, s.height, s.max_depth, s.light_samples, s.rr_depth, backend)
    if key not in _TRACERS:
        _TRACERS[key] = Tracer(scene=scene, camera=s.camera, width=s.width, height=s.height, max_depth=s.max_depth,
                               light_samples=s.light_samples, rr_depth=s.rr_depth, backend=backend)
    return _TRACERS[key]


@dataclass
class AdaptiveRender:
    """An adaptive render: the image, and the samples each pixel's estimate used and traced."""

    result: RenderResult
    used: np.ndarray  # (H, W) samples in each pixel's estimate
    traced: np.ndarray  # (H, W) samples traced for each pixel (the two-stage pilot included)


def render_adaptive(scene: Scene, settings: RenderSettings, *, scheme: str = "two-stage", backend: str = "llvm") -> AdaptiveRender:
    """Render with an average of ``settings.spp`` samples per pixel distributed by ``scheme`` (:data:`SCHEMES`)."""
    import drjit as dr

    from mcrt.film import compile_seconds

    if scheme not in SCHEMES:
        raise ValueError(f"adaptive scheme must be one of {', '.join(SCHEMES)}, got {scheme!r}")
    s = settings
    tracer = adaptive_tracer(scene, s, backend)
    pixels = s.width * s.height
    was, level = dr.flag(dr.JitFlag.KernelHistory), dr.log_level()
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    # Launches over changing pixel sets re-record the tracer's frozen kernel, which Dr.Jit warns of
    # after a few dozen recordings: expected here, so not printed.
    dr.set_log_level(dr.LogLevel.Error)
    try:
        dr.kernel_history_clear()
        t0 = time.perf_counter()
        if scheme == "two-stage":
            sums, pilot = two_stage(tracer, s.seed, pixels, s.spp)
        else:
            sums, pilot = naive(tracer, s.seed, pixels, s.spp), 0
        wall = time.perf_counter() - t0
        compile_s = compile_seconds(dr.kernel_history())
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, was)
        dr.set_log_level(level)
    shape = (s.height, s.width, 3)
    var = sums.variance() * (s.spp / np.maximum(sums.n, 1))[:, None]
    result = RenderResult(
        mean=sums.mean().reshape(shape).astype(np.float32), variance=var.reshape(shape).astype(np.float32),
        spp=s.spp, seed=s.seed, max_depth=s.max_depth, renderer="mcrt", scene_hash=scene.content_hash(),
        camera=s.camera, wall_time=wall, compile_time=compile_s,
        extra={"adaptive": scheme, "budget_spp": str(s.spp), "samples_per_pixel": f"{(sums.n.mean() + pilot):.6g}"},
    )
    return AdaptiveRender(result, sums.n.reshape(shape[:2]), (sums.n + pilot).reshape(shape[:2]))



def floor_at_counts(a: AdaptiveRender, reference: RenderResult) -> RenderResult:
    r"""``a``'s render with the reference-floor rule applied at each pixel's own sample count.

    :func:`mcrt.stats.policy.floor_variance` raises a render's per-sample
    variance to the reference's, s_i^2 <- max(s_i^2, s_ref,i^2), where both
    are per-sample variances of the same estimator. An adaptive render's
    variance is s_i^2 spp / n_i, so the floor is taken on s_i^2 before the
    scaling: max(s_i^2, s_ref,i^2) spp / n_i. Compare the result with policy
    ``'independent'``.
    """
    from dataclasses import replace

    r = a.result
    per_sample = r.variance.astype(np.float64) * (a.used / r.spp)[..., None]
    floored = np.maximum(per_sample, reference.variance.astype(np.float64)) * (r.spp / a.used)[..., None]
    return replace(r, variance=floored.astype(np.float32))
