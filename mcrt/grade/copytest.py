r"""Does the noise repeat: pixels apart that drew the same random numbers?

A Monte-Carlo render's pixels are independent. A generator copied into
each thread or worker (every band of rows drawn from one state), one seed
for every row, tile or pass, or seeds taken from a clock that did not tick
between pixels give pixels apart the same random numbers: the same jitter,
the same bounce directions, the same point on the light. Their noise then
repeats at a fixed offset, which no bias test sees (the mean is right), and
which the filter test (:mod:`mcrt.grade.filtertest`), looking at
neighbours through second differences, misses when the copies run along a
line (equal values have no second difference).

What is compared is the body of the noise, not its tails: the rare samples
that find a bright path differ between the copies (they see different parts
of the scene), and they dominate any product of values. Each pixel's
residual, divided by its noise's standard deviation, is replaced by its
normal score among the pixels of its surface (:math:`g`: the rank, through
the normal quantile). Copies down a column are compared through differences
along the rows, :math:`u_{x,y} = g_{x+1,y} - g_{x,y}`, copies along a row
through differences down the columns (a pair straddling an object's border
is left out): a difference removes any bias that is smooth across it, and
two differences in different rows (columns) share no pixel. For an offset
:math:`d` of :data:`MIN_OFFSET` to :data:`MAX_OFFSET` rows (columns),

.. math::

    T_d = \frac{\sum_p u_p u_{p+d}}{\sqrt{\sum_p u_p^2 u_{p+d}^2}},

which has mean 0 for independent pixels; neighbouring differences share a
pixel, which widens its spread by a factor measured on :data:`SIMS`
white-noise images through the same steps (fixed seed). The largest
standardised :math:`T` over the offsets is one-sided,
Bonferroni-corrected over them, at the level :data:`ALPHA`, and the noise
is said to repeat only where the differences' correlation there is
:data:`MIN_CORRELATION` or more: thousands of pairs make a correlation of a
few hundredths significant, which a bias below the tiles' reach can leave,
while copies of the random numbers on one surface correlate by tenths.

Copies far apart correlate little: pixels whole bands apart see different
parts of the scene, so the same random numbers take different paths (a
generator copied into four threads, each rendering a band of rows, is below
the test's reach at 64 x 64: the grading-accuracy report's
``samples_mt19937_copied_threads``). The test sees copies along a line or
within a few pixels (a seed per row, per column, or per run of pixels begun
within one clock tick).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats as _sps

#: Fewest rows (columns) apart an offset is tested from: a filter correlates neighbours, and one that the filter test
#: (:mod:`mcrt.grade.filtertest`) misses hardly reaches two pixels; copies along a line or a run reach much further.
MIN_OFFSET = 2
#: Most rows (columns) apart an offset is tested to: copies further apart see different parts of the scene and
#: correlate too little to be seen (module docstring), and each offset tested costs the others some power.
MAX_OFFSET = 8
#: Fewest pairs an offset needs to be tested.
MIN_PAIRS = 256
#: White-noise images that set the spread of T; their seed.
SIMS = 16
SEED = 20261206
#: The test's level, Bonferroni-corrected over the offsets tested. A test of independence: a strict
#: level keeps a whole class's false alarms far below one (``mcrt grade-false-alarms`` counts them).
ALPHA = 1e-3
#: The least correlation of the differences at the offset found for the noise to be said to repeat (module docstring).
MIN_CORRELATION = 0.1


@dataclass
class Repeats:
    """The test's answer: the most significant offset."""

    p: float  # one-sided, Bonferroni over the offsets (1 where nothing could be tested)
    axis: str  # 'rows' (pixels in one column, k rows apart) or 'columns' (in one row, k columns apart)
    k: int  # rows (columns) apart
    correlation: float  # the differences' correlation there (of the noise's normal scores)
    pairs: int
    tests: int

    @property
    def repeats(self) -> bool:
        return self.p <= ALPHA and self.correlation >= MIN_CORRELATION

    def to_dict(self) -> dict:
        return {"p": self.p, "axis": self.axis, "k": self.k,
                "correlation": self.correlation, "pairs": self.pairs, "tests": self.tests, "repeats": self.repeats}


def normal_scores(z: np.ndarray, keep: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Each kept value's normal score among the kept values of its surface (0 elsewhere)."""
    g = np.zeros(z.shape)
    for k in np.unique(labels[keep]):
        m = keep & (labels == k)
        r = _sps.rankdata(z[m])
        g[m] = _sps.norm.ppf(r / (r.size + 1.0))
    return g


def differences(g: np.ndarray, keep: np.ndarray, labels: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """{'rows': (u, kept) of differences along each row, 'columns': down each column}, pixels on one surface."""
    out = {}
    for axis, (a, b) in (("rows", (np.s_[:, 1:], np.s_[:, :-1])), ("columns", (np.s_[1:, :], np.s_[:-1, :]))):
        ok = keep[a] & keep[b] & (labels[a] == labels[b])
        out[axis] = (np.where(ok, g[a] - g[b], 0.0), ok)
    return out


def _sums(u: np.ndarray, ok: np.ndarray, axis: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(num, den, ss, pairs) at each offset k = 1 .. MAX_OFFSET (0 at k = 0) along the axis the copies would run
    (rows apart for 'rows', whose differences lie along the rows; columns apart for 'columns')."""
    if axis == "columns":
        u, ok = u.T, ok.T
    n = min(u.shape[0], MAX_OFFSET + 1)
    num, den, ss, pairs = (np.zeros(n) for _ in range(4))
    for k in range(1, n):
        m = ok[:-k] & ok[k:]
        a, b = u[:-k][m], u[k:][m]
        num[k], den[k], ss[k], pairs[k] = np.sum(a * b), np.sum(a * a * b * b), 0.5 * np.sum(a * a + b * b), m.sum()
    return num, den, ss, pairs


def _tests(sums) -> list[tuple[int, float, float, int]]:
    """(k, T, correlation, pairs) for each offset with MIN_PAIRS pairs."""
    num, den, ss, pairs = sums
    return [(k, num[k] / np.sqrt(den[k]), num[k] / max(ss[k], 1e-300), int(pairs[k]))
            for k in range(MIN_OFFSET, len(num)) if pairs[k] >= MIN_PAIRS and den[k] > 0]


def repeats(e: np.ndarray, var: np.ndarray, mask: np.ndarray, labels: np.ndarray) -> Repeats:
    """The test of the module docstring on the luminance residual ``e`` (H, W) of variance ``var`` (H, W) on the
    pixels of ``mask``, within the surfaces of ``labels``."""
    keep = mask & (var > 0) & np.isfinite(e)
    z = np.where(keep, e / np.sqrt(np.where(keep, var, 1.0)), 0.0)
    rng = np.random.default_rng(SEED)
    sims = [differences(normal_scores(rng.standard_normal(e.shape), keep, labels), keep, labels) for _ in range(SIMS)]
    best, tests = None, 0
    for axis, (u, ok) in differences(normal_scores(z, keep, labels), keep, labels).items():
        found = _tests(_sums(u, ok, axis))
        if not found:
            continue
        # The spread of T for independent pixels, over every offset of this direction.
        null = np.concatenate([[t[1] for t in _tests(_sums(*s[axis], axis))] for s in sims])
        kappa = max(float(np.sqrt(np.mean(null**2))), 1e-12)
        tests += len(found)
        k, t, c, pp = max(found, key=lambda f: f[1])
        if best is None or t / kappa > best[0]:
            best = (t / kappa, axis, k, c, pp)
    if best is None:
        return Repeats(1.0, "", 0, 0.0, 0, 0)
    zt, axis, k, c, pp = best
    return Repeats(min(1.0, tests * float(_sps.norm.sf(zt))), axis, k, float(c), pp, tests)
