r"""Is the noise correlated between neighbours (a filter), once the image's structure is taken out?

A Monte-Carlo render's pixels are independent; a filter (a blur, a
denoiser, resampling) makes neighbours alike. A residual that still holds a
bias makes them alike too: a wrong material on one object, and the image
would be called filtered. So the test reads what is left once the structure
is accounted for:

* **two renders handed in**: their difference :math:`a - b`, which holds
  the noise of both and no bias at all, by the self-normalised lag-one
  statistic :math:`T = \sum z_i z_j / \sqrt{\sum z_i^2 z_j^2}` over
  adjacent pairs (N(0, 1) for independent pixels of mean 0);
* **one render**: second differences of neighbours along rows and
  columns, within one surface (a bias bound to an object has its step at the
  object's border, which no difference crosses). A second difference
  removes any bias that is linear over three pixels (a ramp of shading); for
  independent pixels consecutive second differences
  :math:`x_1 = (e_0 - 2 e_1 + e_2)/s_1`, :math:`x_2 = (e_1 - 2 e_2 + e_3)/s_2`
  (:math:`s_1^2 = v_0 + 4 v_1 + v_2`) have the correlation
  :math:`c = -2 (v_1 + v_2) / (s_1 s_2)` (-2/3 at equal variances), and a
  filter raises it (a Gaussian blur of 0.8 pixel, to about -0.05). The
  statistic is :math:`\sum (x_1 x_2 - c\,(x_1^2 + x_2^2)/2)`, of mean 0
  for independent pixels whatever the common scale of their variances,
  self-normalised; overlapping runs make its terms dependent, so its spread
  is that of :data:`SIMS` white-noise images of the same variances through
  the same steps (fixed seed). The effect size is the sum over
  :math:`\sum (x_1^2 + x_2^2)/2`: the correlation beyond what independent
  pixels give.

The test is one-sided (a filter raises the correlation). It is run on the
rows and columns together and on each direction alone, and the most
significant of the three counts, its p-value times three (Bonferroni): a
blur correlates both directions, while pixels that share random numbers
along one direction (every row rendered from one seed) or a filter along
one axis correlate only one, which pooling with the other would halve.
"""

from __future__ import annotations

import numpy as np
from scipy import stats as _sps

#: White-noise images that set the spread of T; their seed.
SIMS = 24
SEED = 20240
#: Fewest pairs for a verdict.
MIN_PAIRS = 16


def lag_one(z: np.ndarray, mask: np.ndarray) -> tuple[float, float]:
    """(T, lag-one correlation) over horizontally and vertically adjacent pairs of ``mask`` (NaN: too few pairs)."""
    num = den = ss = 0.0
    n = 0
    for a, b, ma, mb in ((z[:, :-1], z[:, 1:], mask[:, :-1], mask[:, 1:]), (z[:-1], z[1:], mask[:-1], mask[1:])):
        m = ma & mb
        pa, pb = a[m], b[m]
        num += float(np.sum(pa * pb))
        den += float(np.sum(pa * pa * pb * pb))
        ss += float(np.sum(0.5 * (pa * pa + pb * pb)))
        n += int(m.sum())
    if n < MIN_PAIRS or den <= 0:
        return float("nan"), float("nan")
    return num / np.sqrt(den), num / max(ss, 1e-300)


#: The directions tested: both, along rows (horizontal neighbours) and along columns (vertical neighbours).
AXES = ("", "rows", "columns")


def surface_runs(x: np.ndarray, keep: np.ndarray, labels: np.ndarray, n: int, axis: str = "") -> np.ndarray:
    """Every run of ``n`` consecutive pixels of ``keep`` within one surface (no run crosses an object's border),
    along rows then columns (``axis`` '': both; 'rows' or 'columns': one): x's values, shaped (runs, n, ...)."""
    out = []
    both = ((x, keep, labels), (x.swapaxes(0, 1), keep.T, labels.T))
    for xx, kk, ll in both if not axis else both[AXES.index(axis) - 1: AXES.index(axis)]:
        w = kk.shape[1] - n + 1
        m = kk[:, :w].copy()
        for i in range(1, n):
            m &= kk[:, i:i + w] & (ll[:, i:i + w] == ll[:, :w])
        out.append(np.stack([xx[:, i:i + w][m] for i in range(n)], axis=1))
    return np.concatenate(out)


def second_differences(e: np.ndarray, v: np.ndarray, keep: np.ndarray, labels: np.ndarray, axis: str = ""):
    """Consecutive normalised second differences (x1, x2) along rows and columns (``axis`` '': both; 'rows' or
    'columns': one) within one surface, and the correlation c that independent pixels of variances v give them."""
    runs = surface_runs(np.stack([e, v], axis=-1), keep, labels, 4, axis)
    (e0, e1, e2, e3), (v0, v1, v2, v3) = runs[..., 0].T, runs[..., 1].T
    s1, s2 = np.sqrt(np.maximum(v0 + 4 * v1 + v2, 1e-300)), np.sqrt(np.maximum(v1 + 4 * v2 + v3, 1e-300))
    return (e0 - 2 * e1 + e2) / s1, (e1 - 2 * e2 + e3) / s2, -2 * (v1 + v2) / (s1 * s2)


def _stat(x1: np.ndarray, x2: np.ndarray, c: np.ndarray) -> tuple[float, float]:
    """(T, excess correlation) of consecutive second differences: the sum of x1 x2 - c (x1^2 + x2^2) / 2, which has
    mean 0 for independent pixels whatever their variances' common scale, self-normalised."""
    half = 0.5 * (x1 * x1 + x2 * x2)
    u = x1 * x2 - c * half
    den = float(np.sum(u * u))
    if x1.size < MIN_PAIRS or den <= 0:
        return float("nan"), float("nan")
    return float(np.sum(u)) / np.sqrt(den), float(np.sum(u)) / max(float(np.sum(half)), 1e-300)


def noise_correlation(e: np.ndarray, wt: np.ndarray, mask: np.ndarray, labels: np.ndarray | None, *,
                      pair: np.ndarray | None = None) -> tuple[float, float, float, str]:
    """(T standardised, one-sided p, excess lag-one correlation, direction) of the module docstring: the most
    significant of :data:`AXES` for one render ('' for both directions, or for two renders' difference).

    ``e`` (H, W) is the luminance residual (after any first-order fit),
    ``wt`` its weights (1 / variance; 0 where not tested); ``pair`` (H, W),
    when two renders were handed in, the luminance of their difference
    ``a - b`` (its weights are ``wt`` / 2: two renders' noise).
    """
    if pair is not None:
        z = np.where(mask, pair * np.sqrt(0.5 * wt), 0.0)
        t, c = lag_one(z, mask & (wt > 0))
        if not np.isfinite(t):
            return 0.0, 1.0, 0.0, ""
        return t, float(_sps.norm.sf(t)), c, ""
    lab = labels if labels is not None else np.zeros(e.shape, np.int16)
    keep = mask & (wt > 0)
    v = np.where(keep, 1.0 / np.where(keep, wt, 1.0), 0.0)
    sd = np.sqrt(v)
    noises = [np.random.default_rng(SEED + k).standard_normal(e.shape) * sd for k in range(SIMS)]
    tested = []
    for axis in AXES:
        t, c = _stat(*second_differences(np.where(keep, e, 0.0), v, keep, lab, axis))
        if np.isfinite(t):
            # Overlapping triples make the terms dependent: the spread of T comes from white noise through the same
            # steps.
            null = np.array([_stat(*second_differences(n, v, keep, lab, axis))[0] for n in noises])
            tested.append((t / max(float(np.sqrt(np.mean(null**2))), 1e-12), c, axis))
    if not tested:
        return 0.0, 1.0, 0.0, ""
    zt, c, axis = max(tested, key=lambda x: x[0])
    return float(zt), min(1.0, len(AXES) * float(_sps.norm.sf(zt))), float(c), axis
