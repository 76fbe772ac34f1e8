"""Statistical tests that decide whether two renders agree.

The main entry point is :func:`compare_images`, a two-sample Welch test of
tile means (Jung, Hanika and Dachsbacher, "Detecting Bias in Monte Carlo
Renderers using Welch's t-test", JCGT 2020): each side brings its own mean
image, its own per-sample variance and its own sample count, so two
different estimators (an NEE tracer against an MIS path tracer) are compared
honestly. Pixels are pooled into tiles so that the central limit theorem has
room to work on heavy-tailed per-pixel estimates, and the tests of all tiles
and channels are combined by a multiple-testing procedure with a stated
error rate (Holm: family-wise; Benjamini-Hochberg: false discovery rate).

Also here: :func:`chi2_gof` (chi-square goodness of fit with pooling of
low-expectation bins, for sampling routines), :func:`binomial_interval`
(Clopper-Pearson, for false-alarm-rate reports), :func:`adjust_p_values`,
:func:`compare_files` (the command-line verdict, exit codes
:data:`CONSISTENT`, :data:`DIFFERENT`, :data:`UNUSABLE`) and
:func:`assert_same_image` (for pytest).

Conventions
-----------
* Tiles are indexed ``(ty, tx)`` = (tile row, tile column); tile ``(ty, tx)``
  covers pixel rows ``ty*tile .. ty*tile + tile - 1`` and the matching
  columns. Partial tiles at the right and bottom edges are kept (they hold
  fewer pixels, so they are tested with less power but remain valid).
* Channels are ``'R', 'G', 'B'`` (``channels='rgb'``, three tests per tile) or
  ``'Y'`` (``channels='luminance'``, one test per tile).
* Signs: ``t``, ``diff`` and ``rel_diff`` are positive where image A is
  brighter than image B.
"""

from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import IO, NamedTuple

import numpy as np
from scipy import stats as _sps

from mcrt.film import RenderResult

__all__ = [
    "CONSISTENT",
    "DIFFERENT",
    "UNUSABLE",
    "LUMINANCE_WEIGHTS",
    "StatsError",
    "ZeroPdfError",
    "TileResult",
    "Comparison",
    "compare_images",
    "adjust_p_values",
    "reject",
    "chi2_gof",
    "binomial_interval",
    "compare_files",
    "report_lines",
    "assert_same_image",
]

#: Exit code of :func:`compare_files`: no tile test rejected.
CONSISTENT = 0
#: Exit code of :func:`compare_files`: at least one tile test rejected.
DIFFERENT = 1
#: Exit code of :func:`compare_files`: the inputs cannot be compared.
UNUSABLE = 2

#: Rec. 709 / sRGB luminance weights for linear RGB.
LUMINANCE_WEIGHTS = (0.2126, 0.7152, 0.0722)

#: Schema tag written by :meth:`Comparison.to_dict`.
SCHEMA = "mcrt.stats.comparison/1"

CORRECTIONS = {
    "holm": ("FWER", "Holm"),
    "bonferroni": ("FWER", "Bonferroni"),
    "bh": ("FDR", "Benjamini-Hochberg"),
}

# A pixel counts as deterministic (zero variance) when its per-sample
# standard deviation is at most this fraction of its mean. Moments kept in
# float32 (Mitsuba's 'moment' integrator, var = m2 - m1^2) leave a constant
# pixel with a relative sd of up to a few 1e-4 after cancellation instead of
# zero; real Monte Carlo noise is orders of magnitude larger.
_ZERO_SD_RTOL = 1e-3

# Saturation of the heat map's colour scale, in units of t.
_HEATMAP_T_MAX = 5.0


class StatsError(ValueError):
    """Inputs that cannot be compared (missing variance, too few samples,
    mismatched shapes, non-finite values). The CLI maps it to exit code 2."""


class ZeroPdfError(StatsError):
    """Samples landed in bins whose expected count is zero (p = 0).

    A sample drawn where the pdf is zero is a bug in the sampler, not a
    statistical fluctuation; catch this class to tell it from unusable input.
    """


class TileResult(NamedTuple):
    """One tile test: position, channel, statistic and effect.

    ``diff`` is the difference of tile means A - B; ``rel_diff`` is that
    difference relative to the average magnitude of the two tile means,
    ``(mA - mB) / ((|mA| + |mB|) / 2)`` (0 where both are 0).
    """

    ty: int
    tx: int
    channel: str
    t: float
    p: float
    diff: float
    rel_diff: float


# --------------------------------------------------------------------------
# Multiple testing
# --------------------------------------------------------------------------


def adjust_p_values(p_values, method: str = "holm") -> np.ndarray:
    """Multiplicity-adjusted p-values, same shape as the input.

    A test is rejected at level alpha exactly when its adjusted p-value is
    <= alpha. With the m p-values sorted ascending, p_(1) <= ... <= p_(m):

    * Bonferroni: ``p~_i = min(1, m p_i)`` (family-wise error rate).
    * Holm (step-down): ``p~_(i) = max_{j <= i} min(1, (m - j + 1) p_(j))``,
      which rejects H_(1..k) for the largest k with
      ``p_(j) <= alpha / (m - j + 1)`` for all j <= k. Controls the
      family-wise error rate under any dependence, and is never less powerful
      than Bonferroni.
    * Benjamini-Hochberg (``'bh'``, step-up):
      ``p~_(i) = min_{j >= i} min(1, m p_(j) / j)``, which rejects H_(1..k)
      for the largest k with ``p_(k) <= k alpha / m``. Controls the false
      discovery rate for independent (or positively dependent) tests.

    Parameters
    ----------
    p_values : array_like
        Raw p-values in [0, 1], any shape.
    method : {'holm', 'bonferroni', 'bh'}

    Returns
    -------
    numpy.ndarray
        Adjusted p-values (float64), same shape as ``p_values``.
    """
    if method not in CORRECTIONS:
        raise ValueError(f"correction must be one of {sorted(CORRECTIONS)}, got {method!r}")
    p = np.asarray(p_values, dtype=np.float64)
    flat = p.ravel()
    m = flat.size
    if m == 0:
        return p.copy()
    if method == "bonferroni":
        return np.minimum(1.0, m * p)
    order = np.argsort(flat, kind="stable")
    ps = flat[order]
    rank = np.arange(1, m + 1, dtype=np.float64)
    if method == "holm":
        adj = np.maximum.accumulate(np.minimum(1.0, (m - rank + 1) * ps))
    else:  # bh
        adj = np.minimum.accumulate((m * ps / rank)[::-1])[::-1]
        adj = np.minimum(1.0, adj)
    out = np.empty(m)
    out[order] = adj
    return out.reshape(p.shape)


def reject(p_values, alpha: float, method: str = "holm") -> np.ndarray:
    """Boolean mask of the tests rejected at level ``alpha`` by ``method``.

    See :func:`adjust_p_values` for the procedures.
    """
    return adjust_p_values(p_values, method) <= alpha


# --------------------------------------------------------------------------
# Two-sample tile test
# --------------------------------------------------------------------------


@dataclass
class _Side:
    """Per-tile statistics of one image (arrays shaped (tiles_y, tiles_x, C))."""

    mean: np.ndarray  # tile mean of the pixel means
    var: np.ndarray  # variance of the tile mean, sum(var_i / n) / npix^2
    dof_term: np.ndarray  # sum over pixels of (var_i / (n npix^2))^2 / (n - 1)
    deterministic: np.ndarray  # every pixel of the tile has zero variance


def _tile_sums(x: np.ndarray, tile: int) -> np.ndarray:
    """Sums of (H, W, C) ``x`` over tile x tile blocks, partial edge tiles kept."""
    h, w = x.shape[:2]
    rows = np.arange(0, h, tile)
    cols = np.arange(0, w, tile)
    return np.add.reduceat(np.add.reduceat(x, rows, axis=0), cols, axis=1)


def _tile_pixel_counts(h: int, w: int, tile: int) -> np.ndarray:
    ny = np.minimum(tile, h - np.arange(0, h, tile))
    nx = np.minimum(tile, w - np.arange(0, w, tile))
    return np.outer(ny, nx).astype(np.float64)[:, :, None]


def _side_stats(mean: np.ndarray, var: np.ndarray, spp: int, tile: int, channels: str) -> _Side:
    mean = mean.astype(np.float64)
    var = np.maximum(var.astype(np.float64), 0.0)
    if channels == "luminance":
        w = np.asarray(LUMINANCE_WEIGHTS)
        # Per-sample sd of Y = sum_c w_c X_c is at most sum_c w_c sd_c
        # (Cauchy-Schwarz on the unknown channel covariances): conservative.
        sd_y = np.sqrt(var) @ w
        mean = (mean @ w)[:, :, None]
        var = (sd_y * sd_y)[:, :, None]
    h, w_ = mean.shape[:2]
    npix = _tile_pixel_counts(h, w_, tile)
    det_pixel = np.sqrt(var) <= _ZERO_SD_RTOL * np.abs(mean)
    s = var / spp  # variance of each pixel's mean
    tmean = _tile_sums(mean, tile) / npix
    tvar = _tile_sums(s, tile) / npix**2
    dof_term = _tile_sums(s * s, tile) / npix**4 / (spp - 1)
    det = _tile_sums((~det_pixel).astype(np.float64), tile) == 0
    return _Side(tmean, tvar, dof_term, det)


def _check_side(r: RenderResult, name: str, min_spp: int) -> None:
    if r.variance is None:
        raise StatsError(
            f"image {name} has no per-sample variance; a two-sample test needs each side's own "
            "variance (render it with mcrt, or Mitsuba's 'moment' integrator)"
        )
    if r.spp is None or r.spp < min_spp:
        raise StatsError(
            f"image {name} has spp={r.spp}, need spp >= {min_spp} "
            "(the per-sample variance needs at least 2 samples per pixel)"
        )
    if r.mean.ndim != 3 or r.mean.shape[2] != 3:
        raise StatsError(f"image {name}: mean must be (height, width, 3), got shape {r.mean.shape}")
    if r.variance.shape != r.mean.shape:
        raise StatsError(
            f"image {name}: variance shape {r.variance.shape} differs from mean shape {r.mean.shape}"
        )
    for what, arr in (("mean", r.mean), ("variance", r.variance)):
        bad = int(np.count_nonzero(~np.isfinite(arr)))
        if bad:
            raise StatsError(f"image {name}: {bad} non-finite values (NaN or inf) in its {what}")


@dataclass(repr=False)
class Comparison:
    """Outcome of :func:`compare_images`.

    Arrays are shaped (tiles_y, tiles_x, channels). Tiles are indexed
    (ty, tx) = (tile row, tile column); see :meth:`tile_box`.

    Attributes
    ----------
    passed : bool
        True when no tile test is rejected.
    alpha : float
        Level of the multiple-testing procedure (FWER for Holm and Bonferroni,
        FDR for Benjamini-Hochberg).
    correction : str
        ``'holm'``, ``'bonferroni'`` or ``'bh'``.
    tile : int
        Tile edge length in pixels.
    channels : str
        ``'rgb'`` or ``'luminance'``.
    channel_names : tuple of str
        ``('R', 'G', 'B')`` or ``('Y',)``.
    shape : tuple of int
        Image (height, width).
    spp_a, spp_b : int
        Sample counts used for the two sides.
    n_tests : int
        Size of the multiple-testing family (tiles x channels).
    t : ndarray
        Welch statistic; 0 for equal deterministic tiles, +-inf for unequal.
    df : ndarray
        Welch-Satterthwaite degrees of freedom (inf where not applicable).
    p_values, p_adjusted : ndarray
        Raw two-sided and multiplicity-adjusted p-values.
    rejected : ndarray of bool
        Tests rejected at ``alpha``.
    deterministic : ndarray of bool
        Tests decided by equality because both sides have zero variance.
    mean_a, mean_b, diff, rel_diff : ndarray
        Tile means, their difference A - B and its relative size
        ``(mA - mB) / ((|mA| + |mB|) / 2)``.
    global_rel_diff : ndarray
        Relative difference of whole-image means, per channel.
    failing_tiles : list of TileResult
        Rejected tests, sorted by ascending p (then descending |t|).
    largest_effect : TileResult or None
        Rejected test with the largest |rel_diff|; None when none is rejected.
    max_abs_t : TileResult
        Test with the largest |t| (rejected or not).
    min_p : float
        Smallest raw p-value.
    """

    passed: bool
    alpha: float
    correction: str
    tile: int
    channels: str
    channel_names: tuple[str, ...]
    shape: tuple[int, int]
    spp_a: int
    spp_b: int
    n_tests: int
    t: np.ndarray
    df: np.ndarray
    p_values: np.ndarray
    p_adjusted: np.ndarray
    rejected: np.ndarray
    deterministic: np.ndarray
    mean_a: np.ndarray
    mean_b: np.ndarray
    diff: np.ndarray
    rel_diff: np.ndarray
    global_rel_diff: np.ndarray
    failing_tiles: list[TileResult] = field(default_factory=list)
    largest_effect: TileResult | None = None
    max_abs_t: TileResult | None = None
    min_p: float = 1.0

    def __repr__(self) -> str:
        return f"Comparison({self.summary()!r})"

    @property
    def n_rejected(self) -> int:
        return int(np.count_nonzero(self.rejected))

    @property
    def error_rate(self) -> str:
        """``'FWER'`` or ``'FDR'``: what ``alpha`` bounds."""
        return CORRECTIONS[self.correction][0]

    def tile_box(self, ty: int, tx: int) -> tuple[int, int, int, int]:
        """Pixel bounds ``(y0, y1, x0, x1)`` (end exclusive) of tile (ty, tx)."""
        h, w = self.shape
        return ty * self.tile, min(h, (ty + 1) * self.tile), tx * self.tile, min(w, (tx + 1) * self.tile)

    def _header(self) -> str:
        rate, name = CORRECTIONS[self.correction]
        verdict = "consistent" if self.passed else "DIFFERENT"
        unit = "tile" if self.tile > 1 else "pixel"
        return (
            f"{verdict}: {self.n_rejected} of {self.n_tests} {unit} tests rejected "
            f"at {rate} {self.alpha:g} ({name}, {self.tile}x{self.tile} tiles, {self.channels})"
        )

    def summary(self, max_tiles: int = 5) -> str:
        """One paragraph: verdict, failing tiles, largest effect, smallest p.

        Example: ``consistent: 0 of 192 tile tests rejected at FWER 0.01
        (Holm, 8x8 tiles, rgb); largest |t| 3.1 at tile (3,5) G``.
        """
        parts = [self._header()]
        if self.passed:
            m = self.max_abs_t
            if m is not None:
                parts.append(f"largest |t| {abs(m.t):.2f} at tile ({m.ty},{m.tx}) {m.channel}; min p {self.min_p:.3g}")
        else:
            shown = ", ".join(
                f"({f.ty},{f.tx}) {f.channel} t={f.t:+.2f} p={f.p:.2g} {100 * f.rel_diff:+.2f} %"
                for f in self.failing_tiles[:max_tiles]
            )
            more = len(self.failing_tiles) - max_tiles
            if more > 0:
                shown += f", and {more} more"
            parts.append(f"failing (tile row, col): {shown}")
            e = self.largest_effect
            parts.append(f"largest effect {100 * e.rel_diff:+.2f} % at tile ({e.ty},{e.tx}) {e.channel}")
            parts.append(f"min p {self.min_p:.3g}")
        g = ", ".join(f"{c} {100 * v:+.3f} %" for c, v in zip(self.channel_names, self.global_rel_diff))
        parts.append(f"whole-image A vs B: {g}")
        return "; ".join(parts)

    def to_dict(self) -> dict:
        """JSON-friendly dictionary (schema ``mcrt.stats.comparison/1``).

        Arrays become nested lists indexed [ty][tx][channel]; non-finite
        numbers (t of an unequal deterministic tile) become ``None``.
        """

        def num(x):
            x = float(x)
            return x if math.isfinite(x) else None

        def arr(a):
            a = np.asarray(a)
            if a.dtype == bool:
                return a.tolist()
            return [[[num(v) for v in px] for px in row] for row in a]

        def tile(r: TileResult | None):
            if r is None:
                return None
            return {"ty": r.ty, "tx": r.tx, "channel": r.channel, "t": num(r.t), "p": num(r.p),
                    "diff": num(r.diff), "rel_diff": num(r.rel_diff), "box": list(self.tile_box(r.ty, r.tx))}

        return {
            "schema": SCHEMA,
            "passed": bool(self.passed),
            "summary": self.summary(),
            "alpha": self.alpha,
            "error_rate": self.error_rate,
            "correction": self.correction,
            "tile": self.tile,
            "channels": self.channels,
            "channel_names": list(self.channel_names),
            "shape": list(self.shape),
            "spp_a": int(self.spp_a),
            "spp_b": int(self.spp_b),
            "n_tests": int(self.n_tests),
            "n_rejected": self.n_rejected,
            "min_p": num(self.min_p),
            "failing_tiles": [tile(f) for f in self.failing_tiles],
            "largest_effect": tile(self.largest_effect),
            "max_abs_t": tile(self.max_abs_t),
            "global_rel_diff": [num(v) for v in self.global_rel_diff],
            "t": arr(self.t),
            "df": arr(self.df),
            "p_values": arr(self.p_values),
            "p_adjusted": arr(self.p_adjusted),
            "rejected": arr(self.rejected),
            "deterministic": arr(self.deterministic),
            "rel_diff": arr(self.rel_diff),
        }

    def heatmap_rgb(self, scale: int = 1) -> np.ndarray:
        """The heat map as an (H*scale, W*scale, 3) uint8 array.

        Each tile shows its signed t (the channel with the largest |t|): white
        at 0, red where A is brighter, blue where A is darker, saturating at
        |t| = 5. Rejected tiles are outlined in black.
        """
        scale = max(1, int(scale))
        t = np.nan_to_num(self.t, nan=0.0, posinf=1e9, neginf=-1e9)
        idx = np.argmax(np.abs(t), axis=2)
        tmap = np.take_along_axis(t, idx[:, :, None], axis=2)[:, :, 0]
        s = np.clip(tmap / _HEATMAP_T_MAX, -1.0, 1.0)
        pos, neg = np.maximum(s, 0), np.maximum(-s, 0)
        rgb = np.stack([1 - neg, 1 - pos - neg, 1 - pos], axis=-1)
        tiles = np.round(255 * rgb).astype(np.uint8)
        px = self.tile * scale
        h, w = self.shape[0] * scale, self.shape[1] * scale
        img = np.repeat(np.repeat(tiles, px, axis=0), px, axis=1)[:h, :w].copy()
        bw = max(1, scale // 2)
        for ty, tx in zip(*np.nonzero(self.rejected.any(axis=2))):
            y0, y1, x0, x1 = (v * scale for v in self.tile_box(int(ty), int(tx)))
            img[y0:y1, x0:x0 + bw] = 0
            img[y0:y1, x1 - bw:x1] = 0
            img[y0:y0 + bw, x0:x1] = 0
            img[y1 - bw:y1, x0:x1] = 0
        return img

    def heatmap(self, path, scale: int = 1) -> Path:
        """Write :meth:`heatmap_rgb` as a PNG to ``path``; returns the path."""
        from PIL import Image

        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        Image.fromarray(self.heatmap_rgb(scale)).save(path)
        return path


def floor_variance(tested: RenderResult, reference: RenderResult) -> RenderResult:
    """``tested`` with each pixel's per-sample variance raised to the reference's where it is lower.

    For comparing a modest render with a high-spp reference of the same
    estimator: under "same image" both share one per-sample variance per
    pixel, and a small render that missed the rare high-weight paths
    underestimates it together with its mean (mcrt.reference.verify_references
    explains; reports/validation/against_reference_floor/ measures the
    false-alarm rate and power of the comparison with this floor).
    """
    if tested.variance is None or reference.variance is None:
        raise StatsError("a variance floor needs both renders' per-sample variance")
    if tested.variance.shape != reference.variance.shape:
        raise StatsError(f"images differ in shape: tested {tested.variance.shape}, reference {reference.variance.shape}")
    return replace(tested, variance=np.maximum(tested.variance, reference.variance))


def compare_images(
    a: RenderResult,
    b: RenderResult,
    *,
    alpha: float = 0.01,
    tile: int = 8,
    channels: str = "rgb",
    correction: str = "holm",
    min_spp: int = 2,
    rtol: float = 1e-5,
) -> Comparison:
    r"""Two-sample Welch test of tile means, corrected for multiple testing.

    For each tile T (``npix`` pixels, partial tiles at the image edges kept)
    and channel, each side X in {A, B} gives the tile mean of its pixel means
    and that mean's variance, using the side's own per-sample variance
    ``var_i`` and sample count ``n_X`` (pixels are independent):

    .. math::

        m_X = \frac{1}{npix} \sum_{i \in T} \bar x_i, \qquad
        v_X = \frac{1}{npix^2} \sum_{i \in T} \frac{var_i}{n_X},

    and the statistic is :math:`t = (m_A - m_B) / \sqrt{v_A + v_B}`. Its
    degrees of freedom follow Welch-Satterthwaite over every pixel's variance
    estimate on both sides (each with n_X - 1 degrees of freedom):

    .. math::

        \nu = \frac{(v_A + v_B)^2}
                   {\sum_{X}\sum_{i \in T} \frac{(var_i / (n_X\, npix^2))^2}{n_X - 1}},

    and the two-sided p-value is ``2 * t_nu.sf(|t|)`` (scipy.stats.t; for
    large spp this is the normal tail). The family of tests (all tiles times
    3 channels, or times 1 for luminance) is then corrected by ``correction``
    (see :func:`adjust_p_values`); the images are consistent when no test is
    rejected at ``alpha``.

    Zero variance: a pixel is deterministic when its per-sample standard
    deviation is at most 1e-3 of its mean (moments stored in float32 leave
    constant pixels at a relative sd of up to a few 1e-4 after cancellation,
    not exactly 0). Where every pixel of a tile is
    deterministic on *both* sides (pixels that see only the light, or black
    ones), the tile means are compared for equality:
    ``|m_A - m_B| <= rtol * max(|m_A|, |m_B|)`` gives p = 1 and t = 0,
    otherwise p = 0 and t = +-inf. Zero variance on one side only goes
    through the ordinary statistic.

    Luminance: with ``channels='luminance'`` one test per tile runs on
    Y = 0.2126 R + 0.7152 G + 0.0722 B. Its per-sample variance needs the
    channel covariances, which a render does not keep; the Cauchy-Schwarz
    bound ``var(Y) <= (sum_c w_c sd_c)^2`` is used, so the luminance test is
    conservative (fewer false alarms than nominal, less power than exact).

    Parameters
    ----------
    a, b : RenderResult
        The two renders; both need ``variance`` (per sample) and
        ``spp >= min_spp``. ``a`` is the image under test by convention:
        positive t and differences mean A is brighter.
    alpha : float
        Family-wise error rate (Holm, Bonferroni) or false discovery rate
        (``'bh'``).
    tile : int
        Tile edge in pixels; ``tile=1`` gives per-pixel tests.
    channels : {'rgb', 'luminance'}
    correction : {'holm', 'bonferroni', 'bh'}
    min_spp : int
        Smallest accepted sample count per side (>= 2).
    rtol : float
        Relative tolerance of the equality test for deterministic tiles.

    Returns
    -------
    Comparison

    Raises
    ------
    StatsError
        Missing variance, too few samples, mismatched shapes or non-finite
        values.
    """
    if not 0 < alpha < 1:
        raise ValueError(f"alpha must be in (0, 1), got {alpha}")
    if int(tile) != tile or tile < 1:
        raise ValueError(f"tile must be a positive integer, got {tile}")
    tile = int(tile)
    if channels not in ("rgb", "luminance"):
        raise ValueError(f"channels must be 'rgb' or 'luminance', got {channels!r}")
    if correction not in CORRECTIONS:
        raise ValueError(f"correction must be one of {sorted(CORRECTIONS)}, got {correction!r}")
    min_spp = max(2, int(min_spp))
    if a.mean.shape != b.mean.shape:
        raise StatsError(f"images differ in shape: A is {a.mean.shape}, B is {b.mean.shape}")
    _check_side(a, "A", min_spp)
    _check_side(b, "B", min_spp)

    sa = _side_stats(a.mean, a.variance, a.spp, tile, channels)
    sb = _side_stats(b.mean, b.variance, b.spp, tile, channels)
    names = ("R", "G", "B") if channels == "rgb" else ("Y",)

    diff = sa.mean - sb.mean
    scale = np.maximum(np.abs(sa.mean), np.abs(sb.mean))
    avg = 0.5 * (np.abs(sa.mean) + np.abs(sb.mean))
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(avg > 0, diff / avg, 0.0)
        v = sa.var + sb.var
        det = (sa.deterministic & sb.deterministic) | (v <= 0)
        t = np.where(det, 0.0, diff / np.sqrt(v))
        dterm = sa.dof_term + sb.dof_term
        df = np.where(det | (dterm <= 0), np.inf, v * v / dterm)
    p = 2.0 * _sps.t.sf(np.abs(t), df)
    equal = np.abs(diff) <= rtol * scale
    p = np.where(det, np.where(equal, 1.0, 0.0), np.minimum(p, 1.0))
    t = np.where(det & ~equal, np.copysign(np.inf, diff), t)

    p_adj = adjust_p_values(p, correction)
    rej = p_adj <= alpha

    def result(ty, tx, c) -> TileResult:
        return TileResult(int(ty), int(tx), names[c], float(t[ty, tx, c]), float(p[ty, tx, c]),
                          float(diff[ty, tx, c]), float(rel[ty, tx, c]))

    idx = np.argwhere(rej)
    failing = sorted((result(*i) for i in idx), key=lambda r: (r.p, -abs(r.t)))
    largest = max(failing, key=lambda r: abs(r.rel_diff)) if failing else None
    abs_t = np.abs(t)
    max_t = result(*np.unravel_index(int(np.argmax(abs_t)), t.shape))

    ga = _global_mean(a.mean, channels)
    gb = _global_mean(b.mean, channels)
    gavg = 0.5 * (np.abs(ga) + np.abs(gb))
    with np.errstate(divide="ignore", invalid="ignore"):
        grel = np.where(gavg > 0, (ga - gb) / gavg, 0.0)

    return Comparison(
        passed=not failing,
        alpha=float(alpha),
        correction=correction,
        tile=tile,
        channels=channels,
        channel_names=names,
        shape=tuple(int(s) for s in a.mean.shape[:2]),
        spp_a=int(a.spp),
        spp_b=int(b.spp),
        n_tests=int(p.size),
        t=t,
        df=df,
        p_values=p,
        p_adjusted=p_adj,
        rejected=rej,
        deterministic=det,
        mean_a=sa.mean,
        mean_b=sb.mean,
        diff=diff,
        rel_diff=rel,
        global_rel_diff=grel,
        failing_tiles=failing,
        largest_effect=largest,
        max_abs_t=max_t,
        min_p=float(p.min()),
    )


def _global_mean(mean: np.ndarray, channels: str) -> np.ndarray:
    m = mean.astype(np.float64).reshape(-1, 3).mean(axis=0)
    return m if channels == "rgb" else np.array([m @ np.asarray(LUMINANCE_WEIGHTS)])


# --------------------------------------------------------------------------
# Chi-square goodness of fit, binomial interval
# --------------------------------------------------------------------------


def chi2_gof(observed_counts, expected_counts, *, min_expected: float = 5.0) -> tuple[float, int, float]:
    r"""Pearson chi-square goodness-of-fit test of binned samples against a pdf.

    .. math::

        X^2 = \sum_k \frac{(O_k - E_k)^2}{E_k}, \qquad
        p = P(\chi^2_{dof} \ge X^2),

    over the bins left after pooling. Bins whose expected count is below
    ``min_expected`` are merged into one pooled bin (the chi-square
    approximation needs E_k of at least about 5, as in Mitsuba's
    ``ChiSquareTest``); if the pooled bin's expectation is still below
    ``min_expected``, the regular bins with the smallest expectations are
    added to it until it reaches that level. Bins with E_k = 0 and O_k = 0
    carry no information and are dropped. ``dof`` = number of bins after
    pooling - 1. The expected counts are not rescaled: a pdf that does not
    integrate to one (sum E != sum O) is part of what the test detects.

    Parameters
    ----------
    observed_counts, expected_counts : array_like
        Counts per bin, same shape (any); expected counts are
        ``n_samples * integral of the pdf over the bin``.
    min_expected : float
        Pooling threshold.

    Returns
    -------
    statistic : float
    dof : int
    p_value : float

    Raises
    ------
    ZeroPdfError
        Some samples landed in bins with zero expected count (p = 0: a
        sample where the pdf is zero is a bug).
    StatsError
        Shapes differ, negative or non-finite counts, or fewer than two bins
        remain after pooling.
    """
    obs = np.asarray(observed_counts, dtype=np.float64)
    exp = np.asarray(expected_counts, dtype=np.float64)
    if obs.shape != exp.shape:
        raise StatsError(f"observed counts have shape {obs.shape}, expected counts {exp.shape}")
    obs, exp = obs.ravel(), exp.ravel()
    if not (np.all(np.isfinite(obs)) and np.all(np.isfinite(exp))):
        raise StatsError("counts must be finite")
    if np.any(obs < 0) or np.any(exp < 0):
        raise StatsError("counts must be non-negative")
    zero_hit = (exp == 0) & (obs > 0)
    if np.any(zero_hit):
        where = np.flatnonzero(zero_hit)
        shown = ", ".join(str(int(i)) for i in where[:10]) + (", ..." if where.size > 10 else "")
        raise ZeroPdfError(
            f"p = 0: {obs[zero_hit].sum():g} samples fell in {where.size} bins of zero expected count "
            f"(flat bin indices {shown}); a sample where the pdf is 0 is a bug"
        )
    keep = exp > 0
    obs, exp = obs[keep], exp[keep]
    order = np.argsort(exp, kind="stable")
    obs, exp = obs[order], exp[order]
    # Ascending expectations: the low bins form a prefix; extend it until the
    # pooled expectation reaches min_expected.
    n_low = int(np.searchsorted(exp, min_expected, side="left"))
    if n_low > 0:
        csum = np.cumsum(exp)
        n_pool = max(n_low, int(np.searchsorted(csum, min_expected, side="left")) + 1)
        n_pool = min(n_pool, exp.size)
        pooled_o, pooled_e = obs[:n_pool].sum(), exp[:n_pool].sum()
        obs = np.concatenate([[pooled_o], obs[n_pool:]])
        exp = np.concatenate([[pooled_e], exp[n_pool:]])
    if exp.size < 2:
        raise StatsError(f"only {exp.size} bin left after pooling at min_expected={min_expected:g}; use more samples")
    stat = float(np.sum((obs - exp) ** 2 / exp))
    dof = int(exp.size - 1)
    return stat, dof, float(_sps.chi2.sf(stat, dof))


def binomial_interval(k: int, n: int, level: float = 0.95) -> tuple[float, float]:
    r"""Clopper-Pearson (exact) confidence interval for a binomial proportion.

    With a = 1 - level:

    .. math::

        lo = B^{-1}(a/2;\ k,\ n - k + 1), \qquad
        hi = B^{-1}(1 - a/2;\ k + 1,\ n - k),

    where B^{-1} is the beta quantile (scipy.stats.beta.ppf), lo = 0 for
    k = 0 and hi = 1 for k = n. Example: k = 0, n = 10 gives
    (0, 0.3085) at 95 %.

    Parameters
    ----------
    k : int
        Number of successes (for example false alarms), 0 <= k <= n.
    n : int
        Number of trials, n >= 1.
    level : float
        Confidence level in (0, 1).
    """
    if n < 1 or not 0 <= k <= n:
        raise ValueError(f"need 0 <= k <= n and n >= 1, got k={k}, n={n}")
    if not 0 < level < 1:
        raise ValueError(f"level must be in (0, 1), got {level}")
    a = 1.0 - level
    lo = 0.0 if k == 0 else float(_sps.beta.ppf(a / 2, k, n - k + 1))
    hi = 1.0 if k == n else float(_sps.beta.ppf(1 - a / 2, k + 1, n - k))
    return lo, hi


# --------------------------------------------------------------------------
# Files and pytest
# --------------------------------------------------------------------------


def _describe(r: RenderResult, path) -> str:
    h, w = r.mean.shape[:2]
    var = "variance" if r.variance is not None else "NO variance"
    spp = f"{r.spp} spp" if r.spp else "spp unknown"
    who = f", {r.renderer}" if r.renderer else ""
    return f"{path} ({w}x{h}, {spp}, {var}{who})"


def _failing_lines(c: Comparison, limit: int = 20) -> list[str]:
    lines = []
    for f in c.failing_tiles[:limit]:
        y0, y1, x0, x1 = c.tile_box(f.ty, f.tx)
        lines.append(
            f"  tile ({f.ty},{f.tx}) {f.channel}  rows {y0}-{y1 - 1} cols {x0}-{x1 - 1}  "
            f"t={f.t:+.2f}  p={f.p:.3g}  A-B={f.diff:+.4g} ({100 * f.rel_diff:+.2f} %)"
        )
    if len(c.failing_tiles) > limit:
        lines.append(f"  ... and {len(c.failing_tiles) - limit} more")
    return lines


def report_lines(c: Comparison) -> list[str]:
    """Multi-line, human-readable report of a comparison (used by the CLI and
    :func:`assert_same_image`)."""
    lines = [c._header()]
    if not c.passed:
        lines.append("failing tests (tile row, col; pixel rows/cols inclusive), smallest p first:")
        lines += _failing_lines(c)
        e = c.largest_effect
        lines.append(f"largest effect: {100 * e.rel_diff:+.2f} % at tile ({e.ty},{e.tx}) {e.channel}")
    m = c.max_abs_t
    lines.append(f"largest |t|: {abs(m.t):.2f} at tile ({m.ty},{m.tx}) {m.channel}; min p-value: {c.min_p:.3g}")
    g = ", ".join(f"{ch} {100 * v:+.3f} %" for ch, v in zip(c.channel_names, c.global_rel_diff))
    lines.append(f"whole-image mean, A relative to B: {g}")
    n_det = int(np.count_nonzero(c.deterministic))
    if n_det:
        lines.append(f"{n_det} tests had zero variance on both sides and were compared for equality")
    return lines


def compare_files(
    path_a,
    path_b,
    *,
    alpha: float = 0.01,
    tile: int = 8,
    channels: str = "rgb",
    correction: str = "holm",
    min_spp: int = 2,
    heatmap=None,
    heatmap_scale: int = 1,
    json_path=None,
    assume_variance_from_other: bool = False,
    floor_variance_from_b: bool = False,
    spp_a: int | None = None,
    spp_b: int | None = None,
    out: IO[str] | None = None,
    err: IO[str] | None = None,
) -> int:
    """Compare two image files, print the verdict, return an exit code.

    Reads both files with :func:`mcrt.imageio.read_image`, runs
    :func:`compare_images`, and prints the inputs, the verdict, the failing
    tiles with their pixel ranges, the largest effect and the smallest
    p-value to ``out`` (stdout). Optionally writes the heat map (PNG) and the
    :meth:`Comparison.to_dict` report (JSON).

    Missing variance or sample count: the test needs each side's own
    per-sample variance and spp. ``spp_a`` / ``spp_b`` override the sample
    counts read from the files. If one side lacks variance, the comparison
    is refused (exit 2) with a message naming that side, unless
    ``assume_variance_from_other`` is set: then that side borrows the other
    image's per-sample variance (its spp must be known or given). This is an
    approximation: two estimators of the same image generally differ in
    variance, and with heavy-tailed per-pixel estimates the borrowed variance
    can make the test false-alarm (see the design notes); rendering the image
    again with variance is the remedy.

    ``floor_variance_from_b``: B is a high-spp reference of the same
    estimator, and A takes B's per-sample variance where its own is lower
    (:func:`floor_variance`). Without it a modest render compared with a
    high-spp reference false-alarms on about a third of correct renders;
    with it on none of 200 (reports/validation/against_reference_floor/).

    Returns
    -------
    int
        :data:`CONSISTENT` (0), :data:`DIFFERENT` (1) or :data:`UNUSABLE` (2).
    """
    out = sys.stdout if out is None else out
    err = sys.stderr if err is None else err
    try:
        from mcrt.imageio import ImageError, read_image
    except ImportError as e:  # pragma: no cover - imageio is part of the package
        print(f"error: cannot import mcrt.imageio: {e}", file=err)
        return UNUSABLE
    try:
        a = read_image(path_a)
        b = read_image(path_b)
    except ImageError as e:
        print(f"error: {e}", file=err)
        return UNUSABLE
    except OSError as e:
        print(f"error: {e}", file=err)
        return UNUSABLE

    sides = {"A": [a, path_a, spp_a], "B": [b, path_b, spp_b]}
    for name, (r, _, override) in sides.items():
        if override is not None:
            r.spp = int(override)
    try:
        missing = [n for n, (r, _, _) in sides.items() if r.variance is None]
        if missing:
            if len(missing) == 2:
                raise StatsError(
                    f"neither image has a per-sample variance ({path_a}, {path_b}); "
                    "render them with mcrt (or Mitsuba's 'moment' integrator) so that each keeps its variance"
                )
            lack = missing[0]
            other = "B" if lack == "A" else "A"
            r, path, _ = sides[lack]
            donor = sides[other][0]
            if not assume_variance_from_other:
                raise StatsError(
                    f"image {lack} ({path}) has no per-sample variance; render it again with mcrt, or "
                    f"pass --assume-variance-from other (with --spp-{lack.lower()} N if its spp is unknown) "
                    f"to borrow image {other}'s variance"
                )
            if donor.variance.shape != r.mean.shape:
                raise StatsError(f"images differ in shape: A is {a.mean.shape}, B is {b.mean.shape}")
            if not r.spp or r.spp < max(2, min_spp):
                raise StatsError(
                    f"image {lack} ({path}) has no usable spp ({r.spp}); give it with --spp-{lack.lower()} N"
                )
            r.variance = donor.variance.copy()
            print(f"note: image {lack} uses image {other}'s per-sample variance (approximation)", file=out)
        for name, (r, path, _) in sides.items():
            if not r.spp:
                raise StatsError(f"image {name} ({path}) does not record its spp; give it with --spp-{name.lower()} N")
        if floor_variance_from_b:
            a = floor_variance(a, b)
            print("note: image A's per-sample variance is raised to image B's where lower (B taken as a reference)", file=out)
        c = compare_images(a, b, alpha=alpha, tile=tile, channels=channels, correction=correction, min_spp=min_spp)
    except StatsError as e:
        print(f"error: {e}", file=err)
        return UNUSABLE

    print(f"A: {_describe(a, path_a)}", file=out)
    print(f"B: {_describe(b, path_b)}", file=out)
    for line in report_lines(c):
        print(line, file=out)
    if heatmap is not None:
        print(f"heat map: {c.heatmap(heatmap, scale=heatmap_scale)}", file=out)
    if json_path is not None:
        jp = Path(json_path)
        jp.parent.mkdir(parents=True, exist_ok=True)
        jp.write_text(json.dumps(c.to_dict(), indent=1))
        print(f"report: {jp}", file=out)
    return CONSISTENT if c.passed else DIFFERENT


def assert_same_image(
    a: RenderResult,
    b: RenderResult,
    *,
    alpha: float = 0.01,
    tile: int = 8,
    channels: str = "rgb",
    correction: str = "holm",
    save_dir=None,
    name: str = "compare",
) -> Comparison:
    """Assert that two renders agree under :func:`compare_images`.

    Returns the :class:`Comparison` when they agree. Otherwise raises
    ``AssertionError`` with a multi-line message (how many tile tests failed,
    where, how large, smallest p-value). With ``save_dir`` the two means are
    saved there as ``{name}_a.npy`` / ``{name}_b.npy`` with the heat map
    ``{name}_heatmap.png`` and the report ``{name}.json`` (on failure only).
    :class:`StatsError` (unusable inputs) propagates unchanged.
    """
    c = compare_images(a, b, alpha=alpha, tile=tile, channels=channels, correction=correction)
    if c.passed:
        return c
    lines = ["renders differ: " + report_lines(c)[0]] + report_lines(c)[1:]
    if save_dir is not None:
        d = Path(save_dir)
        d.mkdir(parents=True, exist_ok=True)
        np.save(d / f"{name}_a.npy", a.mean)
        np.save(d / f"{name}_b.npy", b.mean)
        c.heatmap(d / f"{name}_heatmap.png", scale=max(1, 256 // max(c.shape[1], 1)))
        (d / f"{name}.json").write_text(json.dumps(c.to_dict(), indent=1))
        lines.append(f"saved means, heat map and report to {d}/{name}_*")
    raise AssertionError("\n".join(lines))
