r"""Two-sample Welch test of tile means: do two renders have the same expected image?

:func:`compare_images` follows Jung, Hanika and Dachsbacher, "Detecting Bias
in Monte Carlo Renderers using Welch's t-test" (JCGT 2020): each side brings
its own mean image, its own per-sample variance and its own sample count, so
two different estimators (an NEE tracer against an MIS path tracer) are
compared honestly. Pixels are pooled into tiles (:mod:`mcrt.stats.tiles`) so
that the central limit theorem has room to work on heavy-tailed per-pixel
estimates, and the tests of all tiles and channels are combined by a
multiple-testing procedure with a stated error rate
(:mod:`mcrt.stats.multiple`). Which variance each side brings is the
comparison policy's business (:mod:`mcrt.stats.policy`).

Conventions
-----------
* Tiles are indexed ``(ty, tx)`` = (tile row, tile column); partial tiles at
  the right and bottom edges are kept (they hold fewer pixels, so they are
  tested with less power but remain valid).
* Channels are ``'R', 'G', 'B'`` (``channels='rgb'``, three tests per tile) or
  ``'Y'`` (``channels='luminance'``, one test per tile).
* Signs: ``t``, ``diff`` and ``rel_diff`` are positive where image A is
  brighter than image B.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from scipy import stats as _sps

from mcrt.film import RenderResult
from mcrt.stats.errors import StatsError
from mcrt.stats.multiple import CORRECTIONS, adjust_p_values, check_correction
from mcrt.stats.tiles import tile_box, tile_counts, tile_means, tile_sums

__all__ = ["LUMINANCE_WEIGHTS", "SCHEMA", "TileResult", "Comparison", "compare_images", "variance_dof"]

#: Rec. 709 / sRGB luminance weights for linear RGB.
LUMINANCE_WEIGHTS = (0.2126, 0.7152, 0.0722)

#: Schema tag written by :meth:`Comparison.to_dict`.
SCHEMA = "mcrt.stats.comparison/1"

#: The default tolerance of the equality test of noiseless tiles: float32 rounding, "exact".
EXACT_RTOL = 1e-5

# A pixel counts as deterministic (zero variance) when its per-sample
# standard deviation is at most this fraction of its mean. Moments kept in
# float32 (Mitsuba's 'moment' integrator, var = m2 - m1^2) leave a constant
# pixel with a small relative sd after cancellation instead of zero, far
# below real Monte Carlo noise.
_ZERO_SD_RTOL = 1e-3


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
    policy : str
        The comparison policy that prepared the inputs
        (:data:`mcrt.stats.policy.POLICIES`); ``'independent'`` when
        :func:`compare_images` is called directly.
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
    policy: str = "independent"
    rtol: float | tuple[float, ...] = 1e-5
    atol: float | tuple[float, ...] = 0.0

    def noiseless(self) -> dict:
        """The tests decided by equality (both sides noiseless) apart from the others.

        Returns ``{'tests', 'rejected', 'largest_rel_diff', 'accepted_by_rtol'}``:
        how many noiseless tests there are and are rejected, the largest
        |symmetric relative difference| among them, and how many differ by
        more than float32 rounding (:data:`EXACT_RTOL`) but were accepted
        because ``rtol`` is larger (a known offset the user accepted).
        """
        det = np.asarray(self.deterministic, bool)
        rel = np.abs(np.where(det, self.rel_diff, 0.0))
        accepted = det & ~self.rejected & (rel > EXACT_RTOL)
        return {"tests": int(det.sum()), "rejected": int(np.count_nonzero(det & self.rejected)),
                "largest_rel_diff": float(rel.max()) if det.any() else 0.0,
                "accepted_by_rtol": int(accepted.sum())}

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
        return tile_box(*self.shape, self.tile, ty, tx)

    def headline(self) -> str:
        """The verdict line: rejected tests of the family, level, procedure, tiles, channels (and a policy other than independent).

        Example: ``DIFFERENT: 3 of 192 tile tests rejected at FWER 0.01
        (Holm, 8x8 tiles, rgb)``.
        """
        rate, name = CORRECTIONS[self.correction]
        verdict = "consistent" if self.passed else "DIFFERENT"
        unit = "tile" if self.tile > 1 else "pixel"
        policy = "" if self.policy == "independent" else f", policy {self.policy}"
        return (
            f"{verdict}: {self.n_rejected} of {self.n_tests} {unit} tests rejected "
            f"at {rate} {self.alpha:g} ({name}, {self.tile}x{self.tile} tiles, {self.channels}{policy})"
        )

    def summary(self, max_tiles: int = 5) -> str:
        """One paragraph: verdict, failing tiles, largest effect, smallest p.

        Example: ``consistent: 0 of 192 tile tests rejected at FWER 0.01
        (Holm, 8x8 tiles, rgb); largest |t| 3.1 at tile (3,5) G``.
        """
        parts = [self.headline()]
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
        parts.append(f"whole-image (A - B) / mean(|A|, |B|): {g}")
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
            "policy": self.policy,
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


@dataclass
class _Side:
    """Per-tile statistics of one image (arrays shaped (tiles_y, tiles_x, C))."""

    mean: np.ndarray  # tile mean of the pixel means
    var: np.ndarray  # variance of the tile mean, sum(var_i / n) / npix^2
    dof_term: np.ndarray  # sum over pixels of (var_i / (n npix^2))^2 / (n - 1)
    deterministic: np.ndarray  # every pixel of the tile has zero variance
    image_mean: np.ndarray  # mean of the whole image (one tile of tile edge 0), per channel


def _to_channels(mean: np.ndarray, var: np.ndarray, channels: str) -> tuple[np.ndarray, np.ndarray]:
    """Per-pixel mean and per-sample variance (float64) in the tested channels.

    Luminance: Y = sum_c w_c X_c; its per-sample sd is at most sum_c w_c sd_c
    (Cauchy-Schwarz on the channel covariances, which a render does not
    keep), so the bound is used: conservative.
    """
    mean = mean.astype(np.float64)
    var = np.maximum(var.astype(np.float64), 0.0)
    if channels in ("rgb", "xyz"):
        return mean, var
    w = np.asarray(LUMINANCE_WEIGHTS)
    sd_y = np.sqrt(var) @ w
    return (mean @ w)[:, :, None], (sd_y * sd_y)[:, :, None]


def variance_dof(r: RenderResult) -> int:
    """Degrees of freedom of each pixel's variance estimate in ``r``: spp - 1, R - 1 for R replicates, or as stated.

    ``r.extra['variance_method']`` (the EXR attribute ``mcrt.variance_method``,
    :mod:`mcrt.samplers`) says how the variance was estimated: 'samples' (or
    absent) from independent samples, 'replicates:R' from the spread of R
    independent replicate means (randomised quasi-Monte Carlo), 'batches:P'
    from the spread of P independent batches (a film filter wider than a pixel);
    ``r.extra['variance_dof']``, where present, states it outright (a render
    made in P independent batches records P - 1). Raises
    :class:`StatsError` for a value it does not know.
    """
    extra = r.extra or {}
    if "variance_dof" in extra:  # stated outright (P independent batches: P - 1)
        return max(1, int(extra["variance_dof"]))
    method = str(extra.get("variance_method", "samples"))
    if method in ("", "samples"):
        return int(r.spp) - 1
    kind, _, count = method.partition(":")
    if kind not in ("replicates", "batches") or not count.isdigit() or int(count) < 2:
        raise StatsError(f"unknown variance_method {method!r} (expected 'samples', 'replicates:R' or 'batches:P', "
                         "R, P >= 2)")
    return int(count) - 1


def side_variance_terms(r: RenderResult, tile: int) -> tuple[int, float]:
    """The degrees of freedom of a render's variance estimate (:func:`variance_dof`) and the factor its tiles'
    variance takes.

    A render whose pixels share samples through a film filter records ``extra['tile_variance_factor']``
    (:func:`mcrt.mitsuba_scene.filter_area`), applied to tiles of more than one
    pixel, whose pixels are then not independent.
    """
    factor = float((r.extra or {}).get("tile_variance_factor", 1.0)) if tile > 1 else 1.0
    return variance_dof(r), factor


def _side_stats(mean: np.ndarray, var: np.ndarray, spp: int, tile: int, channels: str, dof: int | None = None,
                factor: float = 1.0, rtol: float | np.ndarray = EXACT_RTOL) -> _Side:
    mean, var = _to_channels(mean, var, channels)
    npix = tile_counts(*mean.shape[:2], tile)[:, :, None]
    # Noiseless: a per-sample sd at float32 rounding of the moments, and a mean whose sd is below what the
    # equality test resolves, a tenth of rtol (else a low-noise pixel at high spp would be tested for equality and
    # fail on its noise).
    sd = np.sqrt(var)
    det_pixel = (sd <= _ZERO_SD_RTOL * np.abs(mean)) & (sd / np.sqrt(spp) <= 0.1 * rtol * np.abs(mean))
    s = factor * var / spp  # variance of each pixel's mean (times the tile factor of correlated pixels)
    tvar = tile_sums(s, tile) / npix**2
    dof_term = tile_sums(s * s, tile) / npix**4 / (spp - 1 if dof is None else dof)
    det = tile_sums((~det_pixel).astype(np.float64), tile) == 0
    return _Side(tile_means(mean, tile), tvar, dof_term, det, tile_means(mean, 0)[0, 0])


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


def _per_channel(value, n: int, name: str) -> np.ndarray:
    """A tolerance given as one number or one per tested channel, as an array that broadcasts over (.., .., n)."""
    v = np.asarray(value, dtype=np.float64)
    if v.ndim == 0:
        v = np.full(n, float(v))
    if v.shape != (n,) or not np.all(np.isfinite(v)) or np.any(v < 0):
        raise ValueError(f"{name} must be one non-negative number or {n} (one per tested channel), got {value!r}")
    return v


def _as_given(value):
    """A tolerance as the Comparison records it: a float where one number was given, else a tuple per channel."""
    v = np.asarray(value, dtype=np.float64)
    return float(v) if v.ndim == 0 else tuple(float(x) for x in v)


def _relative(diff: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``diff / ((|a| + |b|) / 2)``, 0 where a and b are both 0."""
    avg = 0.5 * (np.abs(a) + np.abs(b))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(avg > 0, diff / avg, 0.0)


def compare_images(
    a: RenderResult,
    b: RenderResult,
    *,
    alpha: float = 0.01,
    tile: int = 8,
    channels: str = "rgb",
    correction: str = "holm",
    min_spp: int = 2,
    rtol: float | tuple[float, ...] = EXACT_RTOL,
    atol: float | tuple[float, ...] = 0.0,
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
    estimate on both sides (each with f_X = n_X - 1 degrees of freedom, or
    R_X - 1 where side X's variance comes from R_X replicates,
    :func:`variance_dof`):

    .. math::

        \nu = \frac{(v_A + v_B)^2}
                   {\sum_{X}\sum_{i \in T} \frac{(var_i / (n_X\, npix^2))^2}{f_X}},

    and the two-sided p-value is ``2 * t_nu.sf(|t|)`` (scipy.stats.t; for
    large spp this is the normal tail). The family of tests (all tiles times
    3 channels, or times 1 for luminance) is then corrected by ``correction``
    (see :func:`mcrt.stats.multiple.adjust_p_values`); the images are
    consistent when no test is rejected at ``alpha``.

    A side rendered in independent batches (a particle tracer, a film
    filter wider than a pixel) brings its degrees of freedom and a tile
    variance factor in its ``extra`` (:func:`side_variance_terms`): each
    pixel's term counts P - 1 degrees of freedom instead of n - 1, and a
    tile's variance is multiplied by the filter's effective area.

    This is the ``'independent'`` comparison policy: each side's own variance
    as given. Against a high-spp reference of the same estimator use
    :func:`mcrt.stats.policy.compare` with ``policy='reference-floor'``.

    Zero variance: a pixel is deterministic when its per-sample standard
    deviation is at most 1e-3 of its mean (moments stored in float32 leave
    constant pixels with a rounding-level sd after cancellation, not exactly
    0) and the standard deviation of its mean at most a tenth of ``rtol``
    of it (so that noise does not reach the equality test's tolerance). Where every pixel of a tile is deterministic on *both* sides (pixels
    that see only the light, or black ones), the tile means are compared for
    equality: ``|m_A - m_B| <= rtol * max(|m_A|, |m_B|)`` gives p = 1 and
    t = 0, otherwise p = 0 and t = +-inf. Zero variance on one side only goes
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
    channels : {'rgb', 'xyz', 'luminance'}
        ``'xyz'``: the images hold CIE X, Y, Z (a Mitsuba reference read in
        XYZ, whose per-channel variance is exact there), tested as they are.
    correction : {'holm', 'bonferroni', 'bh'}
    min_spp : int
        Smallest accepted sample count per side (>= 2).
    rtol : float
        Relative tolerance of the equality test for deterministic tiles
        (default: float32 rounding, "exact"). Above the default it is also
        a margin of the noisy tests, whose statistic then takes only the
        part of the difference beyond ``rtol max(|mA|, |mB|)``: a known
        relative offset (a reference's) is accepted everywhere. One number
        for every channel, or one per tested channel (a known offset that
        differs between channels, such as an old reference's white in XYZ).
    atol : float or tuple of float
        An absolute margin of every test, one number or one per tested
        channel (default 0): a difference of tile means within
        ``atol + rtol max(|mA|, |mB|)`` is accepted, as in numpy.isclose,
        and a noisy test's statistic takes only the part beyond it. For
        differences known to be rounding, such as the float32 resolution
        of the arithmetic that wrote a reference.

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
    if channels not in ("rgb", "xyz", "luminance"):
        raise ValueError(f"channels must be 'rgb', 'xyz' or 'luminance', got {channels!r}")
    check_correction(correction)
    min_spp = max(2, int(min_spp))
    if a.mean.shape != b.mean.shape:
        raise StatsError(f"images differ in shape: A is {a.mean.shape}, B is {b.mean.shape}")
    _check_side(a, "A", min_spp)
    _check_side(b, "B", min_spp)

    names = {"rgb": ("R", "G", "B"), "xyz": ("X", "Y", "Z")}.get(channels, ("Y",))
    rt = _per_channel(rtol, len(names), "rtol")
    at = _per_channel(atol, len(names), "atol")
    sa = _side_stats(a.mean, a.variance, a.spp, tile, channels, *side_variance_terms(a, tile), rtol=rt)
    sb = _side_stats(b.mean, b.variance, b.spp, tile, channels, *side_variance_terms(b, tile), rtol=rt)

    diff = sa.mean - sb.mean
    scale = np.maximum(np.abs(sa.mean), np.abs(sb.mean))
    rel = _relative(diff, sa.mean, sb.mean)
    with np.errstate(divide="ignore", invalid="ignore"):
        v = sa.var + sb.var
        det = (sa.deterministic & sb.deterministic) | (v <= 0)
        # A tolerance above float32 rounding is a margin on noisy tests too: H0 is |mA - mB| <= rtol max(|mA|, |mB|),
        # tested by the part of the difference beyond it (a known offset of a reference must not fail them either).
        # An atol is a margin of every test (rounding, not a difference).
        margin = np.where(rt > EXACT_RTOL, rt * scale, 0.0) + at
        beyond = np.copysign(np.maximum(np.abs(diff) - margin, 0.0), diff)
        t = np.where(det, 0.0, beyond / np.sqrt(v))
        dterm = sa.dof_term + sb.dof_term
        df = np.where(det | (dterm <= 0), np.inf, v * v / dterm)
    p = 2.0 * _sps.t.sf(np.abs(t), df)
    equal = np.abs(diff) <= rt * scale + at
    p = np.where(det, np.where(equal, 1.0, 0.0), np.minimum(p, 1.0))
    t = np.where(det & ~equal, np.copysign(np.inf, diff), t)

    p_adj = adjust_p_values(p, correction)
    rej = p_adj <= alpha

    def result(ty, tx, c) -> TileResult:
        return TileResult(int(ty), int(tx), names[c], float(t[ty, tx, c]), float(p[ty, tx, c]),
                          float(diff[ty, tx, c]), float(rel[ty, tx, c]))

    failing = sorted((result(*i) for i in np.argwhere(rej)), key=lambda r: (r.p, -abs(r.t)))
    largest = max(failing, key=lambda r: abs(r.rel_diff)) if failing else None
    max_t = result(*np.unravel_index(int(np.argmax(np.abs(t))), t.shape))

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
        global_rel_diff=_relative(sa.image_mean - sb.image_mean, sa.image_mean, sb.image_mean),
        failing_tiles=failing,
        largest_effect=largest,
        max_abs_t=max_t,
        min_p=float(p.min()),
        rtol=_as_given(rtol),
        atol=_as_given(atol),
    )
