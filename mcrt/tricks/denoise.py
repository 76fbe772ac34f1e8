"""AI denoising: Intel Open Image Denoise (OIDN 2.5, CPU device, via PyPI's pyoidn) on mcrt's renders.

OIDN's ``RT`` filter takes the noisy HDR colour and, as guides, the
first-hit albedo and normal buffers (:mod:`mcrt.tricks.aov`), marked as
noise-free (``clean_aux``: they are averages of 16 or more rays that carry
no lighting noise). The output has far lower variance than the input, but
it is a smoothed image: its expectation is not the pixel's radiance, so a
denoised render is biased (the report measures by how much, and
:func:`mcrt.stats.policy.compare` is expected to say so).

pyoidn is an optional dependency (``pip install 'mcrt[denoise]'``).
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from mcrt.film import RenderResult
from mcrt.tricks.aov import Buffers


def require_denoiser():
    """pyoidn, or a RuntimeError saying how to install it."""
    try:
        import pyoidn
    except ImportError:
        raise RuntimeError("denoising needs pyoidn (Intel Open Image Denoise): pip install 'mcrt[denoise]'") from None
    return pyoidn


def denoise_image(color: np.ndarray, buffers: Buffers | None, *, quality: str = "high") -> np.ndarray:
    """OIDN's RT filter on HDR ``color`` (H, W, 3), guided by ``buffers`` (None: colour alone)."""
    pyoidn = require_denoiser()
    c = np.ascontiguousarray(np.maximum(np.nan_to_num(color, nan=0.0, posinf=0.0), 0.0), dtype=np.float32)
    if buffers is None:
        return pyoidn.denoise(c, hdr=True, quality=quality)
    return pyoidn.denoise(c, np.ascontiguousarray(buffers.albedo), np.ascontiguousarray(buffers.normal),
                          hdr=True, clean_aux=True, quality=quality)


def denoise_result(result: RenderResult, buffers: Buffers | None, *, quality: str = "high") -> RenderResult:
    """``result`` with its mean denoised; the time OIDN took is added to its wall time.

    The per-sample variance is kept as the noisy render's: the denoised
    image has no per-sample variance of its own, and the noisy one is an
    upper bound of what the statistical comparison could credit it with
    (a comparison that still flags the denoised image is conservative).
    """
    t0 = time.perf_counter()
    mean = denoise_image(result.mean, buffers, quality=quality)
    took = time.perf_counter() - t0
    return replace(result, mean=mean, wall_time=result.wall_time + took,
                   extra=dict(result.extra, denoiser=f"oidn {quality}", denoise_s=f"{took:.4f}"))
