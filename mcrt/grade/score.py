"""The noise estimate and the error metrics of a hand-in; its bias test is
:func:`mcrt.stats.onesample.multiscale_test`."""

from __future__ import annotations

import numpy as np

from mcrt import metrics as image_metrics
from mcrt.image_files import srgb_eotf_slope, srgb_oetf
from mcrt.stats import LUMINANCE_WEIGHTS
from mcrt.stats.tiles import tile_expand, tile_sums

LUMINANCE = np.asarray(LUMINANCE_WEIGHTS)  # as an array, for ``rgb @ LUMINANCE``


# --------------------------------------------------------------------------
# Noise level
# --------------------------------------------------------------------------


def noise_ratio(resid: np.ndarray, ref: np.ndarray, mask: np.ndarray, model_var_per_sample: np.ndarray,
                ref_noise: np.ndarray, tile: int, pair: np.ndarray | None = None) -> float:
    """Mean over tiles and channels of the student's relative noise over mcrt's per sample.

    The measured variance is that of the graded image's pixel means: the
    pair estimate ``(a - b)^2 / 4`` (two renders) or the spread of the
    residuals in each tile less the reference's share. Both sides are taken
    relative to their brightness (measured / mean(S)^2 against model /
    mean(R)^2), so an image that is too bright or too dark is not called
    noisy for it. The result is 1/spp_eff: mcrt with spp samples per pixel
    has a ratio of 1/spp. A mean, not a median: per-pixel noise here is
    heavy-tailed (rare bright paths), so the median tile of a correct
    render looks far less noisy than the render is. NaN when no tile has
    noise.
    """
    m = mask[..., None].astype(np.float64)
    n = tile_sums(mask.astype(np.float64), tile)[..., None]
    safe = np.maximum(n, 1.0)
    r = np.where(m > 0, resid, 0.0)
    d = tile_sums(r, tile) / safe
    rm = tile_sums(np.where(m > 0, ref, 0.0), tile) / safe
    sm = rm + d
    if pair is not None:
        meas = tile_sums(pair * m, tile) / safe
    else:
        # Residuals against the reference scaled to the tile's own brightness, so that an image
        # brighter by a constant (or smoothly varying) factor keeps only its noise in the spread.
        with np.errstate(divide="ignore", invalid="ignore"):
            k = np.where(rm > 0, sm / np.where(rm > 0, rm, 1.0), 1.0)
        h, w = resid.shape[:2]
        kp = tile_expand(k, h, w, tile)
        rr = np.where(m > 0, resid + ref - kp * ref, 0.0)
        dd = tile_sums(rr, tile) / safe
        meas = np.maximum(tile_sums(rr * rr, tile) - safe * dd * dd, 0.0) / np.maximum(n - 2, 1)
        meas = np.maximum(meas - tile_sums(ref_noise * kp * kp * m, tile) / safe, 0.0)
    model = tile_sums(model_var_per_sample * m, tile) / safe
    ok = (n >= 4) & (model > 0) & (rm > 0) & (sm > 0.2 * rm)
    if not ok.any():
        return float("nan")
    return float(np.mean((meas[ok] / sm[ok] ** 2) / (model[ok] / rm[ok] ** 2)))


def quantisation_variance(image: np.ndarray, fmt: str) -> np.ndarray:
    """Per-pixel variance q^2/12 of the rounding a file format applies (linear units)."""
    x = np.abs(np.nan_to_num(image.astype(np.float64), nan=0.0, posinf=0.0, neginf=0.0))
    if fmt == "half":
        e = np.floor(np.log2(np.maximum(x, 2.0**-14)))
        q = 2.0 ** (e - 10)
    elif fmt == "rgbe":
        mx = np.max(x, axis=-1, keepdims=True)
        e = np.floor(np.log2(np.maximum(mx, 1e-30))) + 1
        q = np.broadcast_to(2.0 ** (e - 8), x.shape)
    elif fmt in ("png8", "png16", "png8-linear", "png16-linear"):
        levels = 255.0 if fmt.startswith("png8") else 65535.0
        if fmt.endswith("linear"):
            q = np.full_like(x, 1.0 / levels)
        else:
            q = srgb_eotf_slope(srgb_oetf(np.clip(x, 0.0, 1.0))) / levels
    else:  # float32
        q = x * 2.0**-23
    return q * q / 12.0


# --------------------------------------------------------------------------
# Error metrics
# --------------------------------------------------------------------------


def metrics(image: np.ndarray, ref: np.ndarray, mask: np.ndarray, expected_noise_var: np.ndarray) -> dict:
    """RMSE over the valid pixels (absolute, and relative to the mean reference), the RMSE noise alone would give, SSIM and FLIP.

    RMSE, SSIM and FLIP follow the conventions of :mod:`mcrt.metrics` (the
    convergence reports' too); non-finite pixels count as 0 in SSIM and
    FLIP. FLIP's error map comes back as magma colours under ``_flip_map``
    for the feedback page. All grow with noise, so they are reported, not
    graded.
    """
    out: dict = {}
    img = np.nan_to_num(image.astype(np.float64), nan=0.0, posinf=0.0, neginf=0.0)
    mref = float(np.mean(np.abs(ref[mask]))) if mask.any() else 1.0
    out["rmse"] = image_metrics.rmse(ref, img, mask=mask) if mask.any() else float("nan")
    out["relative_rmse"] = out["rmse"] / max(mref, 1e-12)
    out["noise_rmse"] = float(np.sqrt(np.mean(expected_noise_var[mask]))) if mask.any() else float("nan")
    try:
        out["ssim"] = image_metrics.ssim(ref, img)
    except Exception as e:  # noqa: BLE001 - pragma: no cover - a metric library's trouble is not the student's
        out["ssim"] = None
        out["ssim_error"] = str(e)[:200]
    try:
        out["_flip_map"], out["flip"] = image_metrics.flip_map(ref, img, magma=True)
    except Exception as e:  # noqa: BLE001 - pragma: no cover - a metric library's trouble is not the student's
        out["flip"] = None
        out["flip_error"] = str(e)[:200]
    return out
