"""The sRGB transfer functions (IEC 61966-2-1) on NumPy arrays, and an image encoded with them.

Core-level (NumPy only): the tracer and the plugin encode a mutant's output
here without loading the image formats of :mod:`mcrt.image_files`.
"""

from __future__ import annotations

import numpy as np


def srgb_eotf(v: np.ndarray) -> np.ndarray:
    r"""sRGB decoding (IEC 61966-2-1), encoded value v to linear x; float64.

    .. math::

        x = \begin{cases} v / 12.92 & v \le 0.04045 \\
                           ((v + 0.055) / 1.055)^{2.4} & v > 0.04045 \end{cases}

    The linear segment continues below 0 (a negative value stays negative)
    and NaN stays NaN, without warnings. The inverse of :func:`srgb_oetf`.
    """
    v = np.asarray(v, dtype=np.float64)
    return np.where(v <= 0.04045, v / 12.92, ((np.maximum(v, 0.04045) + 0.055) / 1.055) ** 2.4)


def srgb_eotf_slope(v: np.ndarray) -> np.ndarray:
    """The derivative dx/dv of :func:`srgb_eotf`: 1 / 12.92 for v <= 0.04045, else (2.4 / 1.055) ((v + 0.055) / 1.055)**1.4.

    It turns a step of the encoded value (a quantisation level of an 8-bit
    PNG) into the step of linear radiance it stands for.
    """
    v = np.asarray(v, dtype=np.float64)
    return np.where(v <= 0.04045, 1 / 12.92, 2.4 / 1.055 * ((np.maximum(v, 0.04045) + 0.055) / 1.055) ** 1.4)


def srgb_oetf(x: np.ndarray) -> np.ndarray:
    r"""sRGB encoding (IEC 61966-2-1), linear x to encoded value v; float64.

    .. math::

        v = \begin{cases} 12.92\, x & x \le 0.0031308 \\
                           1.055\, x^{1/2.4} - 0.055 & x > 0.0031308 \end{cases}

    The linear segment continues below 0 and NaN stays NaN, without
    warnings. Used for PNG previews (:func:`mcrt.image_files.tonemap`) and SSIM's tone map
    (:func:`mcrt.metrics.ssim_tonemap`); the inverse of :func:`srgb_eotf`.
    """
    x = np.asarray(x, dtype=np.float64)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(np.maximum(x, 0.0031308), 1 / 2.4) - 0.055)


def encode_output(mean: np.ndarray, variance: np.ndarray, encoding: str) -> tuple[np.ndarray, np.ndarray]:
    """An image as a renderer hands it out: linear as rendered, or sRGB-encoded (the catalogued ``gamma_output`` bug).

    The encoded image's per-sample variance follows by the delta method,
    var(g(X)) ~ g'(mean)^2 var(X), with g' = 1 / :func:`srgb_eotf_slope` at
    the encoded value.
    """
    if encoding == "linear":
        return mean, variance
    if encoding != "srgb":
        raise ValueError(f"unknown output encoding {encoding!r} (linear, srgb)")
    encoded = srgb_oetf(mean)
    return encoded.astype(np.float32), (variance / srgb_eotf_slope(encoded) ** 2).astype(np.float32)
