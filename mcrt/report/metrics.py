"""Image error metrics and the log-log slope fit of the convergence report.

Every metric compares a test image with a reference (``image_true``), both
(height, width, 3) linear RGB radiance. Conventions (also written into every
report, :data:`CONVENTIONS`):

* **RMSE** = sqrt(mean((x - ref)^2)) over all pixels and the three channels,
  in the image's radiance units.
* **relMSE** = mean((x - ref)^2 / (ref^2 + eps)) over pixels and channels,
  with eps = :data:`RELMSE_EPS` = 1e-2 (so dark pixels, whose squared
  radiance is below about 0.01, weigh as if their radiance were 0.1).
* **SSIM** (scikit-image ``structural_similarity``) on tone-mapped images:
  both are clipped to [0, 1] and sRGB-encoded (exposure 0, the same curve as
  the PNG previews, but kept as floats, not rounded to 8 bits), then compared
  with ``data_range=1``, ``channel_axis=2`` and scikit-image's defaults
  (7 x 7 uniform window, K1 = 0.01, K2 = 0.03). Plots show 1 - SSIM on a log
  axis.
* **FLIP** (NVIDIA's flip-evaluator) in HDR mode on the linear images: ACES
  tone mapper, 67 pixels per degree, and an exposure range (start, stop,
  number of exposures) that FLIP derives from the *reference* alone; the
  report computes it once (:func:`flip_parameters`) and passes the same
  range to every comparison, so all FLIP numbers of a report share it.
* **Slopes** are ordinary least squares of log(metric) against log(spp) (or
  log(time)) over every render (each seed a point), with a 95 % confidence
  interval from Student's t on n - 2 degrees of freedom. An unbiased
  estimator's RMSE falls as spp^-1/2.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

#: relMSE's epsilon: mean((x - ref)^2 / (ref^2 + RELMSE_EPS)).
RELMSE_EPS = 1e-2
#: SSIM is computed on sRGB-encoded images clipped to [0, 1]: data_range 1.
SSIM_DATA_RANGE = 1.0
#: FLIP's mode and fixed settings (the exposure range comes from the reference).
FLIP_MODE = "HDR"
FLIP_TONEMAPPER = "ACES"
FLIP_PPD = 67.0

CONVENTIONS = {
    "rmse": "sqrt(mean((x - ref)^2)) over all pixels and the R, G, B channels (linear radiance)",
    "relmse": f"mean((x - ref)^2 / (ref^2 + eps)) over pixels and channels, eps = {RELMSE_EPS:g}",
    "ssim": ("skimage.metrics.structural_similarity on tone-mapped images: linear RGB clipped to [0, 1] and "
             "sRGB-encoded (exposure 0, float, not quantised), data_range = 1, channel_axis = 2, 7x7 uniform window, "
             "K1 = 0.01, K2 = 0.03; plotted as 1 - SSIM"),
    "flip": (f"flip_evaluator.evaluate(reference, test, '{FLIP_MODE}') on linear RGB: {FLIP_TONEMAPPER} tone mapper, "
             f"{FLIP_PPD:g} pixels per degree, exposure range (start, stop, count) computed by FLIP from the reference "
             "once and reused for every comparison; the number is the mean of FLIP's per-pixel error map"),
    "mse_ref_floor": ("mean(var_ref / spp_ref): the squared error that the reference's own noise adds to every MSE "
                      "(E|x - ref|^2 = E|x - mu|^2 + E|ref - mu|^2 for independent x and ref); "
                      "'excess' MSE and efficiency subtract it"),
    "efficiency": "1 / (MSE_excess x render time), with render time = wall time - JIT compile time",
    "slope": "least squares of log(metric) on log(spp) or log(time) over every render (seeds as points), 95 % CI from Student's t, n - 2 dof",
    "error_bars": "mean over seeds +- one standard deviation over seeds",
}


def _pair(image_true, image_test) -> tuple[np.ndarray, np.ndarray]:
    a = np.asarray(image_true, dtype=np.float64)
    b = np.asarray(image_test, dtype=np.float64)
    if a.shape != b.shape:
        raise ValueError(f"images differ in shape: reference {a.shape}, test {b.shape}")
    if a.ndim != 3 or a.shape[2] != 3:
        raise ValueError(f"expected (height, width, 3) images, got {a.shape}")
    return a, b


def mse(image_true, image_test) -> float:
    """Mean squared error over pixels and channels: mean((x - ref)^2)."""
    a, b = _pair(image_true, image_test)
    return float(np.mean((b - a) ** 2))


def rmse(image_true, image_test) -> float:
    """Root mean squared error: sqrt(mean((x - ref)^2)) over pixels and channels.

    Examples
    --------
    >>> rmse(np.zeros((1, 1, 3)), np.full((1, 1, 3), 2.0))
    2.0
    """
    return math.sqrt(mse(image_true, image_test))


def relmse(image_true, image_test, *, eps: float = RELMSE_EPS) -> float:
    """Relative MSE: mean((x - ref)^2 / (ref^2 + eps)) over pixels and channels.

    ``eps`` (default :data:`RELMSE_EPS` = 1e-2) keeps black reference pixels
    from dividing by zero.
    """
    a, b = _pair(image_true, image_test)
    return float(np.mean((b - a) ** 2 / (a * a + eps)))


def ssim_tonemap(rgb) -> np.ndarray:
    """The image SSIM sees: linear RGB clipped to [0, 1], sRGB-encoded, float64 in [0, 1]."""
    from mcrt.imageio import srgb_oetf

    x = np.nan_to_num(np.asarray(rgb, dtype=np.float64), nan=0.0)
    return srgb_oetf(np.clip(x, 0.0, 1.0))


def ssim(image_true, image_test) -> float:
    """SSIM of the tone-mapped images (:func:`ssim_tonemap`), data_range 1; 1 for identical images."""
    from skimage.metrics import structural_similarity

    a, b = _pair(image_true, image_test)
    ta, tb = ssim_tonemap(a), ssim_tonemap(b)
    win = min(7, *a.shape[:2])
    win -= 1 - win % 2  # odd
    return float(structural_similarity(ta, tb, data_range=SSIM_DATA_RANGE, channel_axis=2, win_size=win))


#: Images up to this many pixels are compared by FLIP on one OpenMP thread: its
#: threads spin while they wait, and on a small, busy machine (Dr.Jit's own
#: threads, other processes) a 64x64 comparison took 0.3 to 3 s on two threads
#: against 0.07 s on one.
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
    only; computing them once lets every comparison of a report use the same.
    """
    import flip_evaluator as flip

    ref = _flip_input(image_true)
    _flip_threads(ref.shape[0] * ref.shape[1])
    _, _, params = flip.evaluate(ref, ref, FLIP_MODE, applyMagma=False, computeMeanError=False,
                                 parameters={"ppd": FLIP_PPD, "tonemapper": FLIP_TONEMAPPER})
    return {"startExposure": float(params["startExposure"]), "stopExposure": float(params["stopExposure"]),
            "numExposures": int(params["numExposures"]), "tonemapper": FLIP_TONEMAPPER, "ppd": FLIP_PPD}


def flip_map(image_true, image_test, parameters: dict | None = None, *, magma: bool = False) -> tuple[np.ndarray, float]:
    """FLIP's per-pixel error map (H, W) in [0, 1] (or (H, W, 3) magma colours) and its mean."""
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


@dataclass(frozen=True)
class SlopeFit:
    """log(y) = intercept + slope log(x), with the slope's 95 % confidence interval."""

    slope: float
    intercept: float
    stderr: float
    ci_low: float
    ci_high: float
    n: int
    level: float = 0.95

    def contains(self, value: float) -> bool:
        return self.ci_low <= value <= self.ci_high

    def predict(self, x) -> np.ndarray:
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            return np.exp(self.intercept + self.slope * np.log(np.asarray(x, dtype=np.float64)))

    def to_dict(self) -> dict:
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in asdict(self).items()}

    def __str__(self) -> str:
        return f"{self.slope:.3f} [{self.ci_low:.3f}, {self.ci_high:.3f}]"


def fit_slope(x, y, *, level: float = 0.95) -> SlopeFit:
    """Least-squares line through (log x, log y), with a ``level`` confidence interval on its slope.

    Points with non-positive or non-finite x or y are dropped. With fewer than
    three points left the interval is infinite (n - 2 = 0 degrees of freedom
    leave no estimate of the scatter); with fewer than two the fit is NaN.
    """
    from scipy import stats

    x = np.asarray(x, dtype=np.float64).ravel()
    y = np.asarray(y, dtype=np.float64).ravel()
    if x.shape != y.shape:
        raise ValueError(f"fit_slope: x has {x.size} values, y has {y.size}")
    ok = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0)
    lx, ly = np.log(x[ok]), np.log(y[ok])
    n = int(lx.size)
    nan = float("nan")
    if n < 2 or np.ptp(lx) == 0:
        return SlopeFit(nan, nan, nan, nan, nan, n, level)
    xm, ym = lx.mean(), ly.mean()
    sxx = float(np.sum((lx - xm) ** 2))
    slope = float(np.sum((lx - xm) * (ly - ym)) / sxx)
    intercept = float(ym - slope * xm)
    if n < 3:
        return SlopeFit(slope, intercept, float("inf"), -float("inf"), float("inf"), n, level)
    resid = ly - (intercept + slope * lx)
    s2 = float(np.sum(resid**2)) / (n - 2)
    se = math.sqrt(s2 / sxx)
    t = float(stats.t.ppf(0.5 + level / 2, n - 2))
    return SlopeFit(slope, intercept, se, slope - t * se, slope + t * se, n, level)
