r"""A monotone value curve: any tone map, clamp or encoding a student's program applies before saving.

The model image is :math:`f_c(R)` with :math:`f_c` monotone per channel.
Named curves come first, each with an exposure scanned before it (a
student's exposure slider): Reinhard's :math:`x/(1+x)`, the ACES filmic
curve (Narkowicz's fit), Hable's filmic curve (Uncharted 2's constants and
white point 11.2), the exponential curve :math:`1 - e^{-x}` (tutorials'
"exposure" tone map), Khronos' PBR Neutral (on each pixel's colour: its
smallest channel's offset taken off, its peak compressed and desaturated),
each alone or followed by the sRGB curve, the
smoothstep S-curve :math:`3c^2 - 2c^3` of the values clipped to [0, 1], a
clamp to [0, 1], and 8-bit rounding; Reinhard's extended curve
:math:`x (1 + x / w^2) / (1 + x)` with its white point w scanned too; and
Reinhard's curves, ACES and Hable's applied to the luminance L alone, each
pixel's colour scaled by :math:`f(L) / L` (hue and saturation kept, as
tone-mapping guides teach), and the sRGB curve so; a constant subtracted from every value,
clipped at 0 (a black level), or added; a contrast slider; a contrast stretch
between two percentiles of the image onto [0, 1]; the values normalised from
their minimum and maximum and raised to 1/gamma (OpenCV's Tonemap); and a sigmoid contrast curve
:math:`1 / (1 + e^{g (c - x)})` (scikit-image's ``adjust_sigmoid``), its cut-off and gain scanned. Any other monotone curve is fitted as an
isotonic regression of S on R per channel
(:func:`scipy.optimize.isotonic_regression`) on :data:`BINS` quantile bins
of R, each bin's level one parameter at most, and worded by the values it
maps three quantiles of R to. Such a curve is a description, not a cause
(:attr:`mcrt.grade.candidates.Candidate.describes`): a material's or the
light's mistake can make the difference a function of the value too, and a
curve no program applies is no evidence of a tone map.
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit, curve_change
from mcrt.grade.feedback import num as _num

#: Quantile bins of R per channel for the isotonic fit (each bin's fitted level is one parameter at most).
BINS = 64
#: Exposures scanned before a named tone map (a student's exposure slider; 1 is none).
EXPOSURES = (0.25, 0.35, 0.5, 0.7, 1.0, 1.4, 2.0, 2.8, 4.0)
#: White points scanned for Reinhard's extended curve (the value that maps to 1). Not 1: x (1 + x) / (1 + x) is x,
#: no tone map at all, and after an exposure it would name the image's scale a tone map.
WHITES = (2.0, 4.0, 8.0, 11.2, 16.0, 20.0, 32.0)
#: The curves also applied to the luminance alone (the image's colours kept).
ON_LUMINANCE = ("reinhard", "reinhard_ext", "aces", "hable")


def _aces(x):
    """Narkowicz's fit of the ACES filmic curve."""
    return np.clip(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0)


def _hable(x):
    """Hable's filmic curve with Uncharted 2's constants, normalised to its white point 11.2 (above it, beyond 1: the
    curve clips nothing itself, a display file does)."""
    def f(v):
        a, b, c, d, e, f_ = 0.15, 0.50, 0.10, 0.20, 0.02, 0.30
        return (v * (a * v + c * b) + d * e) / (v * (a * v + b) + d * f_) - e / f_

    return f(np.maximum(x, 0.0)) / f(11.2)


def _reinhard_ext(x, w: float):
    """Reinhard's extended curve, white point w (mapped to 1)."""
    return x * (1.0 + x / (w * w)) / (1.0 + x)


def _pbr_neutral(x):
    """Khronos' PBR Neutral tone map on each pixel's colour: the smallest channel's offset (x - 6.25 x^2 under 0.08,
    0.04 above) taken off every channel; a peak (the largest channel) above 0.76 compressed towards 1, the colour
    scaled with it and blended towards grey by 0.15 of the compression (glTF viewers' and three.js's Neutral)."""
    start, desaturation = 0.76, 0.15
    x = np.asarray(x, np.float64)
    m = x.min(axis=-1, keepdims=True)
    c = x - np.where(m < 0.08, m - 6.25 * m * m, 0.04)
    peak = c.max(axis=-1, keepdims=True)
    d = 1.0 - start
    new_peak = 1.0 - d * d / (np.maximum(peak, start) + d - start)
    g = 1.0 - 1.0 / (desaturation * (peak - new_peak) + 1.0)
    compressed = (1.0 - g) * c * (new_peak / np.maximum(peak, start)) + g * new_peak
    return np.where(peak < start, c, compressed)


def _smoothstep(x):
    """The S-curve 3 c^2 - 2 c^3 of c the values clipped to [0, 1] (GLSL's smoothstep(0, 1, x), a contrast curve)."""
    c = np.clip(x, 0.0, 1.0)
    return c * c * (3.0 - 2.0 * c)


def _on_luminance(f):
    """The curve f applied to each pixel's luminance (Rec. 709), the pixel's colour scaled by f(L) / L."""
    from mcrt.grade.objects import LUMINANCE

    def g(x):
        lum = (x @ LUMINANCE)[..., None]
        return x * np.where(lum > 0, f(lum) / np.maximum(lum, 1e-300), 0.0)

    return g


def _named_curves() -> dict[str, tuple[str, callable]]:
    from mcrt.image_files import srgb_oetf

    def q8(x):
        return np.floor(np.clip(x, 0.0, 1.0) * 255.0 + 0.5) / 255.0

    return {
        "reinhard": ("put through Reinhard's tone map x / (1 + x)", lambda x: x / (1.0 + x)),
        "reinhard+srgb": ("put through Reinhard's tone map x / (1 + x), then the sRGB curve", lambda x: srgb_oetf(x / (1.0 + x))),
        "aces": ("put through the ACES filmic tone map", _aces),
        "aces+srgb": ("put through the ACES filmic tone map, then the sRGB curve", lambda x: srgb_oetf(_aces(x))),
        "hable": ("put through Hable's filmic tone map (Uncharted 2)", _hable),
        "hable+srgb": ("put through Hable's filmic tone map (Uncharted 2), then the sRGB curve",
                       lambda x: srgb_oetf(_hable(x))),
        "exponential": ("put through the exponential tone map 1 - exp(-x)", lambda x: -np.expm1(-x)),
        "exponential+srgb": ("put through the exponential tone map 1 - exp(-x), then the sRGB curve",
                             lambda x: srgb_oetf(-np.expm1(-x))),
        "pbr_neutral": ("put through Khronos' PBR Neutral tone map (glTF viewers', three.js's Neutral)", _pbr_neutral),
        "pbr_neutral+srgb": ("put through Khronos' PBR Neutral tone map (glTF viewers', three.js's Neutral), then "
                             "the sRGB curve", lambda x: srgb_oetf(np.clip(_pbr_neutral(x), 0.0, None))),
        "smoothstep": ("put through the smoothstep S-curve 3 c^2 - 2 c^3 of c the values clipped to [0, 1]",
                       _smoothstep),
        "clamp": ("clamped to [0, 1]", lambda x: np.clip(x, 0.0, 1.0)),
        "quantised": ("clamped to [0, 1] and rounded to 8 bits (linear)", q8),
    }


def tone_curve(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """Named tone maps (an exposure scanned before each), and any monotone curve per channel (isotonic)."""
    R = np.maximum(fit.R, 0.0)
    out = []
    for key, (words, f) in _named_curves().items():
        scan = EXPOSURES if key not in ("clamp", "quantised") else (1.0,)
        errs = [fit.model(f(k * R)) for k in scan]
        i = int(np.argmin(errs))
        k = scan[i]
        exp = f" after an exposure of {_num(k)}" if k != 1.0 else ""
        chi2, change, nz = curve_change(fit, lambda x, f=f, k=k: f(k * x))  # on the noisy values, its exposure scanned on R
        out.append(Candidate("tone_curve", f"tone map {key}", f"the values {words}{exp} before saving",
                              chi2, 1 if len(scan) > 1 else 0, value={"curve": key, "exposure": k}, change=change,
                              noise=nz))
    out += _reinhard_extended(fit, R)
    out += _offset(fit, R)
    out += _contrast(fit, R)
    out += _stretch(fit, R)
    out.append(_normalised_gamma(fit, R))
    out.append(_sigmoid(fit, R))
    out.append(_isotonic(fit))
    return out


def _offset(fit: Fit, R: np.ndarray) -> list[Candidate]:
    """A constant b subtracted from every value and clipped at 0 (a black level), or added (b < 0): b fitted within
    half the image's median value, one parameter; none where b is below 1 % of that bound."""
    from scipy.optimize import minimize_scalar

    bound = 0.5 * float(np.median(R[fit.ok])) if fit.ok.any() else 0.0
    if bound <= 0:
        return []
    b = float(minimize_scalar(lambda b: fit.model(np.maximum(R - b, 0.0)), bounds=(-bound, bound),
                              method="bounded", options={"xatol": 1e-3 * bound}).x)
    if abs(b) < 0.01 * bound:  # below 0.5 % of the median value: no offset a program applies, and no change to name
        return []
    words = (f"a black level of {_num(b)} subtracted from every value (clipped at 0)" if b >= 0 else
             f"a constant {_num(-b)} added to every value")
    change = np.maximum(R - b, 0.0) - fit.R
    return [Candidate("tone_curve", "offset", f"the values with {words} before saving", fit.delta(change), 1,
                      value={"curve": "offset", "offset": -b}, change=change)]


def _contrast(fit: Fit, R: np.ndarray) -> list[Candidate]:
    """A contrast control: every value v saved as c (v - p) + p, clipped at 0 (an image editor's or a tutorial's
    contrast slider, about the pivot p), two parameters fitted from no change; none where c is within 2 % of 1
    (the offset and the scale say that), nor outside what a slider sets (c between 1/2 and 2, p in [0, 1]): a
    near-constant image (c of 0.05) fits an image whose pixels are scrambled, and is no contrast anyone chose; nor
    where the pivot lies below a tenth of the median value (below nearly every value: the scale, with a black level
    too small to name)."""
    from scipy.optimize import minimize

    def model(ab):
        return np.maximum(ab[0] * R + ab[1], 0.0)

    a, b = (float(v) for v in minimize(lambda ab: fit.model(model(ab)), x0=(1.0, 0.0), method="Nelder-Mead",
                                       options={"xatol": 1e-4, "fatol": 1e-3}).x)
    pivot = b / (1.0 - a) if a != 1.0 else 0.0
    if abs(a - 1.0) < 0.02 or not (0.5 <= a <= 2.0 and 0.0 <= pivot <= 1.0):
        return []
    if fit.ok.any() and pivot < 0.1 * float(np.median(R[fit.ok])):
        return []
    change = model((a, b)) - fit.R
    return [Candidate("tone_curve", "contrast", f"the values through a contrast control before saving: each value v "
                      f"saved as {_num(a)} (v - {_num(pivot)}) + {_num(pivot)}, clipped at 0", fit.delta(change), 2,
                      value={"curve": "contrast", "contrast": a, "pivot": pivot}, change=change)]


#: The percentile pairs a contrast stretch maps onto [0, 1] (scikit-image's example takes 2 and 98; a min-max
#: normalisation 0 and 100).
STRETCH_PERCENTILES = ((0.0, 100.0), (0.5, 99.5), (1.0, 99.0), (2.0, 98.0), (5.0, 95.0))


def _stretch(fit: Fit, R: np.ndarray) -> list[Candidate]:
    """A contrast stretch: the values between two percentiles of the image (over every value, as
    ``skimage.exposure.rescale_intensity(img, in_range=(p_lo, p_hi))`` takes them) mapped linearly onto [0, 1]
    and clipped: on the linear values, on their sRGB encoding (a stretch of the display image), or on the linear
    values then saved as they are in a display file (an image library's float-to-byte conversion, which the reader
    decodes as sRGB); the pair and the space the choice, one parameter. The student's percentiles are their own
    image's, the reference's within noise."""
    from mcrt.image_files import srgb_eotf, srgb_oetf

    spaces = {"": (lambda v: v, lambda v: v),
              ", on the sRGB-encoded image": (lambda v: srgb_oetf(np.minimum(v, 1.0)), srgb_eotf),
              ", linear values saved as they are in a display file (decoded as sRGB)": (lambda v: v, srgb_eotf)}
    best = None
    for space, (encode, decode) in spaces.items():
        V = encode(R)
        for lo, hi in STRETCH_PERCENTILES:
            a, b = (float(v) for v in np.percentile(V, (lo, hi)))
            if b <= a:
                continue
            M = decode(np.clip((V - a) / (b - a), 0.0, 1.0))
            err = fit.model(M)
            if best is None or err < best[0]:
                best = (err, space, lo, hi, M)
    if best is None:  # a constant image: nothing to stretch
        return []
    err, space, lo, hi, M = best
    what = ("from their minimum to their maximum" if (lo, hi) == (0.0, 100.0) else
            f"between their {_num(lo)} and {_num(hi)} percentiles")
    return [Candidate("tone_curve", "contrast stretch", f"the values stretched {what} onto [0, 1] and clipped before "
                      f"saving (a contrast stretch, as scikit-image's rescale_intensity with in_range does{space})",
                      err, 1, value={"curve": "stretch", "percentiles": (lo, hi), "space": space.strip(" ,")},
                      change=M - fit.R)]


#: The gammas of a normalise-then-gamma tone map (OpenCV's Tonemap(gamma) takes 1 by default; 2.2 the usual).
GAMMAS = (1.8, 2.0, 2.2, 2.4, 2.6)


def _normalised_gamma(fit: Fit, R: np.ndarray) -> Candidate:
    """The values mapped linearly from the image's minimum and maximum to [0, 1], then raised to 1 / gamma (OpenCV's
    ``cv2.createTonemap(gamma).process``), gamma scanned (one parameter)."""
    lo, hi = float(R.min()), float(R.max())
    V = (R - lo) / max(hi - lo, 1e-300)
    err, g, M = min(((fit.model(M), g, M) for g in GAMMAS for M in (V ** (1.0 / g),)), key=lambda t: t[0])
    return Candidate("tone_curve", "normalised and gamma", "the values mapped from their minimum and maximum to "
                     f"[0, 1] and raised to 1/{_num(g)} before saving (OpenCV's Tonemap with gamma {_num(g)})", err, 1,
                     value={"curve": "normalised gamma", "gamma": g}, change=M - fit.R)


#: Cut-offs and gains scanned for a sigmoid contrast curve (scikit-image's adjust_sigmoid defaults: 0.5 and 10).
SIGMOID_CUTOFFS = (0.25, 0.5, 0.75)
SIGMOID_GAINS = (3.0, 5.0, 7.0, 10.0, 15.0, 20.0)


def _sigmoid(fit: Fit, R: np.ndarray) -> Candidate:
    """A sigmoid contrast curve 1 / (1 + exp(g (c - v))) of every value (``skimage.exposure.adjust_sigmoid``, an
    S-curve for contrast): its cut-off c and gain g scanned (two parameters)."""
    best = min(((fit.model(1.0 / (1.0 + np.exp(g * (c - R)))), c, g) for c in SIGMOID_CUTOFFS for g in SIGMOID_GAINS),
               key=lambda t: t[0])
    err, c, g = best
    return Candidate("tone_curve", "sigmoid", f"the values through a sigmoid contrast curve 1 / (1 + exp({_num(g)} "
                     f"({_num(c)} - v))) before saving (an S-curve for contrast, as scikit-image's adjust_sigmoid "
                     "applies)", err, 2, value={"curve": "sigmoid", "cutoff": c, "gain": g},
                     change=1.0 / (1.0 + np.exp(g * (c - R))) - fit.R)


def _reinhard_extended(fit: Fit, R: np.ndarray) -> list[Candidate]:
    """Reinhard's extended curve per channel and on the luminance, and the other curves of :data:`ON_LUMINANCE` on
    the luminance: an exposure (and a white point) scanned for each."""
    from mcrt.image_files import srgb_oetf

    named = _named_curves()
    curves = [("reinhard_ext", "put through Reinhard's extended tone map x (1 + x / w^2) / (1 + x)", w,
               lambda x, w=w: _reinhard_ext(x, w)) for w in WHITES]
    curves += [(f"{key} on luminance", f"{named[key][0]} applied to the luminance (colours kept)", None,
                _on_luminance(named[key][1])) for key in ON_LUMINANCE if key in named]
    curves += [("reinhard_ext on luminance", "put through Reinhard's extended tone map x (1 + x / w^2) / (1 + x) "
                "applied to the luminance (colours kept)", w, _on_luminance(lambda x, w=w: _reinhard_ext(x, w)))
               for w in WHITES]
    # The display curve on the luminance, each colour scaled along (to keep the hue): an encoding, not a tone map.
    curves.append(("srgb on luminance", "through the sRGB curve applied to the luminance (colours kept)", None,
                   _on_luminance(srgb_oetf)))
    best = {}
    for key, words, w, f in curves:
        for k in EXPOSURES:
            err = fit.model(f(k * R))
            if key not in best or err < best[key][0]:
                best[key] = (err, words, w, k, f)
    out = []
    for key, (err, words, w, k, f) in best.items():
        white = f" with white point {_num(w)}" if w is not None else ""
        exp = f" after an exposure of {_num(k)}" if k != 1.0 else ""
        chi2, change, nz = curve_change(fit, lambda x, f=f, k=k: f(k * x))
        out.append(Candidate("tone_curve", f"tone map {key}", f"the values {words}{white}{exp} before saving", chi2,
                             1 + (w is not None), value={"curve": key, "exposure": k, "white": w}, change=change,
                             noise=nz))
    return out


def _isotonic(fit: Fit) -> Candidate:
    from scipy.optimize import isotonic_regression

    M = np.array(fit.R, np.float64)
    params, knots = 0, []
    for c in range(3):
        ok = fit.ok[..., c]
        x, y, w = fit.R[..., c][ok], fit.S[..., c][ok], fit.w[..., c][ok]
        if x.size < BINS:
            continue
        order = np.argsort(x, kind="stable")
        groups = np.array_split(order, BINS)
        wx = np.array([max(float(w[g].sum()), 1e-300) for g in groups])
        xm = np.array([float(np.sum(w[g] * x[g])) for g in groups]) / wx
        ym = np.array([float(np.sum(w[g] * y[g])) for g in groups]) / wx
        res = isotonic_regression(ym, weights=wx, increasing=True)
        levels = res.x
        params += len(res.blocks) - 1
        M[..., c] = np.interp(fit.R[..., c], xm, levels)
        knots.append((xm, levels))
    change = M - fit.R
    probe = [float(v) for v in np.quantile(fit.R[fit.ok], [0.1, 0.5, 0.99])] if fit.ok.any() else []
    lum = [float(np.mean([np.interp(p, xm, lv) for xm, lv in knots])) for p in probe] if knots else []
    says = ", ".join(f"{p:.3g} to {q:.3g}" for p, q in zip(probe, lum))
    text = (f"the values through a monotone curve (a tone map, clamp or encoding) that maps {says}" if says
            else "the values through a monotone curve")
    return Candidate("tone_curve", "monotone curve", text, fit.delta(change), params,
                      value={"curve": "monotone", "maps": [[p, q] for p, q in zip(probe, lum)]}, change=change,
                      describes=True)


tone_curve.name = "tone_curve"
