"""Render results and the pass loop shared by every renderer.

A render is accumulated in passes of a few samples per pixel, so memory does
not grow with spp. Each pass returns per-pixel sums of the samples x and of
x^2 (float64); from the totals the mean and the unbiased per-sample variance

    mean = S1 / n,    var = (S2 - S1^2 / n) / (n - 1)

are formed once at the end. Passes are independent given their seeds, so
results merge exactly in any order (:func:`merge`).
"""

from __future__ import annotations

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

    def std_error(self) -> np.ndarray:
        """Standard error of each pixel's mean, sqrt(var / spp)."""
        if self.variance is None:
            raise ValueError("this render has no per-sample variance")
        return np.sqrt(np.maximum(self.variance, 0) / self.spp)


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
            # every page of the zero arrays, about 10 ms at 256x256.
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


PassFn = Callable[[int, int], tuple[np.ndarray, np.ndarray]]


def run_passes(render_pass: PassFn, height: int, width: int, spp: int, spp_per_pass: int, progress: Progress | None = None) -> Moments:
    """Call ``render_pass(pass_index, n)`` until ``spp`` samples per pixel are summed.

    ``render_pass`` returns the (height, width, 3) float64 sums of x and x^2
    over its ``n`` samples per pixel; pass ``k`` must use seeds that no other
    pass uses.
    """
    m = Moments.zeros(height, width)
    k = 0
    while m.n < spp:
        n = min(spp_per_pass, spp - m.n)
        s1, s2 = render_pass(k, n)
        m.add(s1, s2, n)
        k += 1
        if progress is not None:
            progress.update(m.n)
    return m


def samples_per_pass(width: int, height: int, spp: int, budget: int = 1 << 22) -> int:
    """Samples per pixel in one pass so that one pass traces at most ``budget`` paths."""
    return max(1, min(spp, budget // max(width * height, 1)))
