"""Image error metrics, one convention each: RMSE, relMSE, SSIM, FLIP.

Every metric compares a test image with a reference (``image_true``), both
(height, width, 3) linear RGB radiance. The convergence reports
(:mod:`mcrt.convergence`) and the grading harness (:mod:`mcrt.grade`) both
measure with these functions, so their numbers mean the same. Conventions
(also written into every report, :data:`CONVENTIONS`):

* **RMSE** = sqrt(mean((x - ref)^2)) over all pixels (or those of a
  ``mask``) and the three channels, in the image's radiance units.
* **relMSE** = mean((x - ref)^2 / (ref^2 + eps)) over pixels and channels,
  with eps = :data:`RELMSE_EPS` = 1e-2 (so dark pixels, whose squared
  radiance is below about 0.01, weigh as if their radiance were 0.1).
* **SSIM** (scikit-image ``structural_similarity``) on tone-mapped images
  (:func:`ssim_tonemap`): both are clipped to [0, 1] and sRGB-encoded
  (:func:`mcrt.image_files.srgb_oetf`; exposure 0, the same curve as the PNG
  previews, but kept as floats, not rounded to 8 bits), then compared with
  ``data_range`` = :data:`SSIM_DATA_RANGE` = 1, ``channel_axis=2`` and
  scikit-image's defaults (7 x 7 uniform window, or the largest odd size
  that fits a smaller image; K1 = 0.01, K2 = 0.03). Reports plot 1 - SSIM.
* **FLIP** (NVIDIA's flip-evaluator) in :data:`FLIP_MODE` = HDR mode on the
  linear images (NaN, infinities and negative values taken as 0): ACES tone
  mapper, 67 pixels per degree, and an exposure range (start, stop, number
  of exposures) that FLIP derives from the *reference* alone. Compute it
  once per reference (:func:`flip_parameters`) and pass it to every
  comparison with that reference, so that they all share it.
"""

from __future__ import annotations

import math

import numpy as np

#: relMSE's epsilon: mean((x - ref)^2 / (ref^2 + RELMSE_EPS)).
RELMSE_EPS = 1e-2
#: SSIM is computed on sRGB-encoded images clipped to [0, 1]: data_range 1.
SSIM_DATA_RANGE = 1.0
#: SSIM's (largest) window: scikit-image's default.
SSIM_WINDOW = 7
#: FLIP's mode and fixed settings (the exposure range comes from the reference).
FLIP_MODE = "HDR"
FLIP_TONEMAPPER = "ACES"
FLIP_PPD = 67.0

CONVENTIONS = {
    "rmse": "sqrt(mean((x - ref)^2)) over all pixels and the R, G, B channels (linear radiance)",
    "relmse": f"mean((x - ref)^2 / (ref^2 + eps)) over pixels and channels, eps = {RELMSE_EPS:g}",
    "ssim": ("skimage.metrics.structural_similarity on tone-mapped images: linear RGB clipped to [0, 1] and "
             f"sRGB-encoded (exposure 0, float, not quantised), data_range = {SSIM_DATA_RANGE:g}, channel_axis = 2, "
             f"{SSIM_WINDOW}x{SSIM_WINDOW} uniform window, K1 = 0.01, K2 = 0.03; plotted as 1 - SSIM"),
    "flip": (f"flip_evaluator.evaluate(reference, test, '{FLIP_MODE}') on linear RGB: {FLIP_TONEMAPPER} tone mapper, "
             f"{FLIP_PPD:g} pixels per degree, exposure range (start, stop, count) computed by FLIP from the reference "
             "once and reused for every comparison; the number is the mean of FLIP's per-pixel error map"),
}


def _pair(image_true, image_test, mask=None) -> tuple[np.ndarray, np.ndarray]:
    """Both images as float64 (H, W, 3), or their (N, 3) pixels where ``mask`` (H, W) is true."""
    a = np.asarray(image_true, dtype=np.float64)
    b = np.asarray(image_test, dtype=np.float64)
    if a.shape != b.shape:
        raise ValueError(f"images differ in shape: reference {a.shape}, test {b.shape}")
    if a.ndim != 3 or a.shape[2] != 3:
        raise ValueError(f"expected (height, width, 3) images, got {a.shape}")
    if mask is not None:
        m = np.asarray(mask, dtype=bool)
        if m.shape != a.shape[:2]:
            raise ValueError(f"mask has shape {m.shape}, the images {a.shape[:2]}")
        a, b = a[m], b[m]
    return a, b


def mse(image_true, image_test, *, mask=None) -> float:
    """Mean squared error over pixels (those of ``mask`` if given) and channels: mean((x - ref)^2)."""
    a, b = _pair(image_true, image_test, mask)
    return float(np.mean((b - a) ** 2))


def rmse(image_true, image_test, *, mask=None) -> float:
    """Root mean squared error: sqrt(mean((x - ref)^2)) over pixels (those of ``mask`` if given) and channels.

    Examples
    --------
    >>> rmse(np.zeros((1, 1, 3)), np.full((1, 1, 3), 2.0))
    2.0
    """
    return math.sqrt(mse(image_true, image_test, mask=mask))


def relmse_map(image_true, image_test, *, eps: float = RELMSE_EPS) -> np.ndarray:
    """Per-pixel relative squared error (H, W): the mean over channels of (x - ref)^2 / (ref^2 + eps)."""
    a, b = _pair(image_true, image_test)
    return ((b - a) ** 2 / (a * a + eps)).mean(axis=2)


def relmse(image_true, image_test, *, eps: float = RELMSE_EPS) -> float:
    """Relative MSE: mean((x - ref)^2 / (ref^2 + eps)) over pixels and channels.

    ``eps`` (default :data:`RELMSE_EPS` = 1e-2) keeps black reference pixels
    from dividing by zero.
    """
    return float(relmse_map(image_true, image_test, eps=eps).mean())


def ssim_tonemap(rgb) -> np.ndarray:
    """The image SSIM sees: linear RGB clipped to [0, 1] (NaN as 0), sRGB-encoded, float64 in [0, 1]."""
    from mcrt.image_files import srgb_oetf

    x = np.nan_to_num(np.asarray(rgb, dtype=np.float64), nan=0.0)
    return srgb_oetf(np.clip(x, 0.0, 1.0))


def ssim(image_true, image_test) -> float:
    """SSIM of the tone-mapped images (:func:`ssim_tonemap`), data_range 1; 1 for identical images."""
    from skimage.metrics import structural_similarity

    a, b = _pair(image_true, image_test)
    win = min(SSIM_WINDOW, *a.shape[:2])
    win -= 1 - win % 2  # odd
    return float(structural_similarity(ssim_tonemap(a), ssim_tonemap(b), data_range=SSIM_DATA_RANGE, channel_axis=2,
                                       win_size=win))


#: Images up to this many pixels are compared by FLIP on one OpenMP thread:
#: FLIP's threads spin while they wait, so on a small, busy machine (Dr.Jit's
#: own threads, other processes) a small comparison runs many times faster
#: on one thread than on several.
FLIP_SINGLE_THREAD_PIXELS = 256 * 256
_omp = []


def _flip_threads(n_pixels: int) -> None:
    """Set the thread count of the OpenMP runtime bundled with flip_evaluator (when it can be found)."""
    import ctypes
    import glob
    import os

    import flip_evaluator

    if not _omp:
        libs = glob.glob(os.path.join(os.path.dirname(os.path.dirname(flip_evaluator.__file__)), "flip_evaluator.libs", "libgomp*.so*"))
        try:
            _omp.append(ctypes.CDLL(libs[0]) if libs else None)
        except OSError:
            _omp.append(None)
    lib = _omp[0]
    if lib is not None:
        lib.omp_set_num_threads(1 if n_pixels <= FLIP_SINGLE_THREAD_PIXELS else (os.cpu_count() or 1))


def _flip_input(x) -> np.ndarray:
    a = np.nan_to_num(np.asarray(x, dtype=np.float32), nan=0.0, posinf=0.0)
    return np.ascontiguousarray(np.maximum(a, 0.0))


def flip_parameters(image_true) -> dict:
    """FLIP's HDR settings for this reference: exposure range as FLIP computes it, tone mapper, ppd.

    FLIP derives start and stop exposure (and their count) from the reference
    only; computing them once lets every comparison with it use the same.
    """
    import flip_evaluator as flip

    ref = _flip_input(image_true)
    _flip_threads(ref.shape[0] * ref.shape[1])
    _, _, params = flip.evaluate(ref, ref, FLIP_MODE, applyMagma=False, computeMeanError=False,
                                 parameters={"ppd": FLIP_PPD, "tonemapper": FLIP_TONEMAPPER})
    return {"startExposure": float(params["startExposure"]), "stopExposure": float(params["stopExposure"]),
            "numExposures": int(params["numExposures"]), "tonemapper": FLIP_TONEMAPPER, "ppd": FLIP_PPD}


def flip_map(image_true, image_test, parameters: dict | None = None, *, magma: bool = False) -> tuple[np.ndarray, float]:
    """FLIP's per-pixel error map (H, W) in [0, 1] (or (H, W, 3) magma colours in [0, 1]) and its mean.

    ``parameters`` (default: :func:`flip_parameters` of ``image_true``) fix the exposure range.
    """
    import flip_evaluator as flip

    a, b = _pair(image_true, image_test)
    params = dict(parameters) if parameters else flip_parameters(a)
    _flip_threads(a.shape[0] * a.shape[1])
    emap, mean, _ = flip.evaluate(_flip_input(a), _flip_input(b), FLIP_MODE, applyMagma=magma, computeMeanError=True,
                                  parameters=params)
    emap = np.asarray(emap)
    if not magma:
        emap = emap[..., 0]
    return emap, float(mean)


def flip(image_true, image_test, parameters: dict | None = None) -> float:
    """Mean HDR-FLIP error of ``image_test`` against ``image_true``; 0 for identical images."""
    return flip_map(image_true, image_test, parameters)[1]
