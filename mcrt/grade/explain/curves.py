"""Closed-form families on the reference: encoding curves, a blur, a 3 x 3 filter after rendering, a sharpening."""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit, curve_change, refine
from mcrt.grade.feedback import num as _num


#: A clipped power curve whose exponent is this near 1 is a clamp to [0, 1] alone (:mod:`.tonecurve`'s), no encoding.
NOT_A_POWER = 0.05


def curves(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """Encoding curves on the reference: sRGB (and its inverse, its decoding's formula inverted, a coarse table of
    it), BT.709's, HDR video's PQ and limited range, power curves; a Gaussian blur
    (over the channels too); 3 x 3 filters; an unsharp mask."""
    from scipy.ndimage import gaussian_filter

    from mcrt.image_files import srgb_eotf, srgb_oetf

    R = np.maximum(fit.R, 0.0)
    C = np.minimum(R, 1.0)  # a display file clips the encoded values; an EXR keeps them

    def curve(name: str, text: str, f, value) -> Candidate:
        """An encoding f of the render's noisy values (:func:`mcrt.grade.explain.fit.curve_change`)."""
        chi2, change, nz = curve_change(fit, f)
        return Candidate("encoding", name, text, chi2, 0, value=value, change=change, noise=nz)

    out = [curve("sRGB curve", "the values sRGB-encoded (a display curve) instead of linear", srgb_oetf, "srgb"),
           curve("sRGB curve, clipped", "the values sRGB-encoded (a display curve) instead of linear, clipped to 1 (in "
                 "an 8-bit file: the sRGB curve applied twice)", lambda x: srgb_oetf(np.minimum(x, 1.0)), "srgb-clipped"),
           curve("decoded twice", "the values decoded from sRGB once too often (linear values written to a PNG that "
                 "says sRGB, or decoded twice)", lambda x: srgb_eotf(np.minimum(x, 1.0)), "srgb-inverse"),
           # In a float file nothing clips: values above 1 (the light) go through the decoding's power law too.
           curve("decoded, float", "the values decoded from sRGB once too often (linear values taken for display "
                 "values and decoded), in a float file where values above 1 are decoded too", srgb_eotf,
                 "srgb-inverse-float"),
           # Another standard's camera curve where the file says sRGB (the reader decodes it with sRGB's).
           # The decoding's inner formula with its exponent inverted, ((v + 0.055) / 1.055)^(1/2.4), for the encoding.
           curve("sRGB's decoding inverted", "the values encoded with ((v + 0.055) / 1.055)^(1/2.4), the sRGB "
                 "decoding's formula with its exponent inverted, where the encoding 1.055 v^(1/2.4) - 0.055 belongs "
                 "(black written as code 74)",
                 lambda x: srgb_eotf(((np.minimum(x, 1.0) + 0.055) / 1.055) ** (1 / 2.4)), "srgb-decoding-inverted"),
           curve("BT.709 curve", "the values encoded with BT.709's camera curve (4.5 x below 0.018, 1.099 x^0.45 - "
                 "0.099 above) where the file's sRGB curve belongs", lambda x: srgb_eotf(bt709(np.minimum(x, 1.0))),
                 "bt709")]
    out += _per_channel(fit, R, C)
    out += _hdr_video(fit, R, srgb_eotf)
    out += _video_range(fit, C, srgb_eotf, srgb_oetf)
    exps = np.linspace(0.25, 2.5, 91)
    # A power curve, and one clipped to 1 after it (a display writer's encode-and-clamp kept in front of a float
    # file): the exponent scanned on the curve alone, then scored on the noisy values.
    for base, clip in ((R, ""), (C, ", clipped to 1 (a display file's encoding and clamp)")):
        errs = np.array([fit.model(base**p) for p in exps])
        p = refine(exps, errs, int(np.argmin(errs)))
        if clip and abs(p - 1.0) < NOT_A_POWER:
            continue  # values clipped to 1 and nothing more: the tone curves' clamp says so
        g = 1.0 / p
        what = (f"a power curve x^(1/{_num(g)}) (gamma {_num(g)} encoding)" if p < 1 else
                f"a power curve x^{_num(p)} (decoded with gamma {_num(p)} once too often)")
        chi2, change, nz = curve_change(fit, (lambda x, p=p: x**p) if not clip else (lambda x, p=p: np.minimum(x, 1.0)**p))
        out.append(Candidate("encoding", "power curve" + (", clipped" if clip else ""),
                             f"the values through {what} instead of linear{clip}", chi2, 1,
                             value=g if not clip else f"{_num(g)}-clipped", change=change, noise=nz))
    sig = np.array([0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 1.0, 1.2, 1.5, 2.0, 3.0])
    errs = np.array([fit.model(gaussian_filter(fit.R, (s, s, 0), mode="nearest")) for s in sig])
    i = int(np.argmin(errs))
    s = sig[i]
    # A pixel whose samples reach into its neighbours (a film filter wider than the box, sub-pixel offsets
    # outside 0 to 1) is a blur of the box-filtered image too, made while rendering.
    out.append(Candidate("blur", "blur", f"the image blurred, denoised or enlarged from a lower resolution, or each "
                         f"pixel's samples spread beyond its own square (a pixel filter wider than a box, or sub-pixel "
                         f"offsets outside 0 to 1): smoothed as by a Gaussian of about {_num(s)} pixel",
                         float(errs[i]), 1, value=float(s),
                         change=gaussian_filter(fit.R, (s, s, 0), mode="nearest") - fit.R))
    out.append(_blur_over_channels(fit, sig, gaussian_filter))
    out += _three_by_three(fit)
    out.append(_unsharp(fit, gaussian_filter))
    out.append(_coarse_table(fit, C, srgb_eotf, srgb_oetf))
    return out


#: Sigmas along the channel axis of a Gaussian filter given one sigma for every axis of an (H, W, 3) image (the
#: image's resolution and the grade's may differ in the pixels, never in the channels).
CHANNEL_SIGMAS = (0.5, 1.0, 2.0)


def _blur_over_channels(fit: Fit, sig: np.ndarray, gaussian_filter) -> Candidate:
    """A Gaussian blur over the channel axis too (``scipy.ndimage.gaussian_filter(img, sigma)`` with one sigma for the
    three axes of an (H, W, 3) image, its ends reflected): each channel mixed with its neighbours, the colours washed
    out; the pixels' sigma and the channels' scanned, one parameter."""
    err, s, c, M = min(((fit.model(M), s, c, M) for s in sig for c in CHANNEL_SIGMAS
                        for M in (gaussian_filter(fit.R, (s, s, c), mode=("nearest", "nearest", "reflect")),)),
                       key=lambda t: t[0])
    return Candidate("blur", "blur over the channels", f"the image blurred after rendering over its colour channels "
                     f"as well as its pixels (a Gaussian filter given one sigma for the (H, W, 3) array's three axes, "
                     f"as scipy.ndimage.gaussian_filter(img, sigma) does): about {_num(s)} pixel, and {_num(c)} across "
                     "the channels, the colours washed out", err, 1, value={"sigma": float(s), "channels": c},
                     change=M - fit.R)


def bt709(x: np.ndarray) -> np.ndarray:
    """BT.709's camera curve (its OETF) of linear values in [0, 1]."""
    return np.where(x < 0.018, 4.5 * x, 1.099 * np.power(np.maximum(x, 0.018), 0.45) - 0.099)


#: SMPTE ST 2084 (PQ): m1, m2, c1, c2, c3.
PQ = (2610.0 / 16384.0, 2523.0 / 4096.0 * 128.0, 3424.0 / 4096.0, 2413.0 / 4096.0 * 32.0, 2392.0 / 4096.0 * 32.0)
#: The luminances (cd/m^2) a value of 1 is taken for before the PQ curve: SDR's white, BT.2408's graphics white,
#: and a bright and the brightest display's.
PQ_WHITES = (100.0, 203.0, 1000.0, 10000.0)


def pq(y: np.ndarray) -> np.ndarray:
    """The PQ curve (SMPTE ST 2084's inverse EOTF) of luminances as fractions of 10000 cd/m^2, clipped to [0, 1]."""
    m1, m2, c1, c2, c3 = PQ
    p = np.power(np.clip(y, 0.0, 1.0), m1)
    return np.power((c1 + c2 * p) / (1.0 + c3 * p), m2)


def _hdr_video(fit: Fit, R: np.ndarray, srgb_eotf) -> list[Candidate]:
    """HDR video's PQ curve where the file's belongs, a value of 1 taken for one of :data:`PQ_WHITES` (one
    parameter), read back with the sRGB curve from a display file (the reader decodes what the file declares) or
    as it is from a float file. The curve ends at 1 itself (at 10000 cd/m^2)."""
    out = []
    for display, decode in ((True, srgb_eotf), (False, lambda v: v)):
        models = [decode(pq(R * w / 10000.0)) for w in PQ_WHITES]
        errs = [fit.model(m) for m in models]
        i = int(np.argmin(errs))
        where = "the file's sRGB curve belongs" if display else "the float file's linear values belong"
        out.append(Candidate("encoding", f"PQ curve{'' if display else ', float'}", "the values encoded with the PQ "
                             f"curve of HDR video (SMPTE ST 2084), a value of 1 taken as {_num(PQ_WHITES[i])} cd/m^2, "
                             f"where {where}", errs[i], 1, value=f"pq{'' if display else '-float'}",
                             change=models[i] - fit.R))
    return out


def _video_range(fit: Fit, C: np.ndarray, srgb_eotf, srgb_oetf) -> list[Candidate]:
    """8-bit video's limited range where the file's full range belongs: the codes 16 + 219 v (black at 16, white at
    235, a video library's default), or limited-range codes read as full range and stretched back, (255 v - 16) / 219
    clipped (the other way round)."""
    V = srgb_oetf(C)
    limited = srgb_eotf((16.0 + 219.0 * V) / 255.0)
    expanded = srgb_eotf(np.clip((255.0 * V - 16.0) / 219.0, 0.0, 1.0))
    return [Candidate("encoding", "video range", "the values written in video's limited range, codes 16 + 219 v of the "
                      "sRGB values (black at 16, white at 235, a video library's default) where the file's full range "
                      "0 to 255 belongs", fit.model(limited), 0, value="video-range", change=limited - fit.R),
            Candidate("encoding", "video range expanded", "the values stretched from video's limited range to the full "
                      "one once too often, (255 v - 16) / 219 of the sRGB values, clipped (blacks crushed, whites "
                      "clipped)", fit.model(expanded), 0, value="video-range-expanded", change=expanded - fit.R)]


#: What a channel can go through on its own (a loop over the wrong channels, a curve applied in one channel's code
#: path): the value right (as rendered, or clipped by a display file) or one of the encodings above.
_CHANNEL_CURVES = (("right", None), ("sRGB-encoded once too often (too bright)", "srgb"),
                   ("written linear where the file says sRGB (decoded once more: too dark)", "srgb-inverse"))
_CHANNEL_NAMES = ("red", "green", "blue")


def _per_channel(fit: Fit, R: np.ndarray, C: np.ndarray) -> list[Candidate]:
    """The sRGB curve applied to some channels and not others, or applied where it is not due on some: every
    assignment of :data:`_CHANNEL_CURVES` to the three channels that treats them unlike (the alike ones are the
    candidates above). One parameter, the choice. A channel left right is the value as rendered, clipped at 1
    where the image has no value above 1 (a display file)."""
    from itertools import product

    from mcrt.image_files import srgb_eotf, srgb_oetf

    ok = fit.ok if fit.ok.any() else np.ones(fit.S.shape, bool)
    display = float(np.max(fit.S[ok])) <= 1.0 + 1e-6
    each = {None: C if display else R, "srgb": srgb_oetf(C), "srgb-inverse": srgb_eotf(C)}
    best = None
    for combo in product(range(len(_CHANNEL_CURVES)), repeat=3):
        if len(set(combo)) == 1:
            continue
        M = np.stack([each[_CHANNEL_CURVES[k][1]][..., c] for c, k in enumerate(combo)], axis=-1)
        e = fit.model(M)
        if best is None or e < best[0]:
            best = (e, combo, M)
    e, combo, M = best
    parts = []
    for k in dict.fromkeys(combo):
        chans = [_CHANNEL_NAMES[c] for c, kc in enumerate(combo) if kc == k]
        parts.append(f"{' and '.join(chans)} {_CHANNEL_CURVES[k][0]}")
    return [Candidate("encoding", "sRGB curve per channel", "the display curve applied to some colour channels and not "
                      f"others (a loop over the wrong channels): {'; '.join(parts)}", e, 1,
                      value={"channels": [_CHANNEL_CURVES[k][1] or "right" for k in combo]}, change=M - fit.R)]


#: Kernels of 3 x 3 filters written by hand, with the sum of their weights: a filter divided by another count (a
#: binomial's 16 taken for a box's 9) scales the image by the ratio.
KERNELS = {"box": (np.ones((3, 3)), "a 3 x 3 box (mean) filter"),
           "binomial": (np.outer([1.0, 2.0, 1.0], [1.0, 2.0, 1.0]), "a 3 x 3 binomial filter (weights 1 2 1 by 1 2 1)")}


#: How a hand-written filter treats the image's border, in words: the edge pixels repeated; the opposite edge wrapped
#: round (the mean of np.roll's shifted copies); zeros taken in past it (a zero-padded convolution); the filter only
#: where it fits, the edge left black (a loop over the inner pixels writing into a zeroed image); a 'full' convolution
#: cropped at its top-left corner (the filtered image moved a pixel down and right, zeros taken in there).
BORDERS = {"nearest": "",
           "wrap": ", its border wrapped round to the opposite edge (the mean of shifted copies, as np.roll makes them)",
           "zeros": ", zeros taken in past its border (a zero-padded convolution, as torch's avg_pool2d with padding "
                    "and count_include_pad left True, or scipy.signal.convolve2d with mode 'same', makes it): the edge "
                    "rows and columns darkened; or the image resampled with zeros outside it (interpolated between "
                    "pixel centres, as torch's grid_sample does with its default padding)",
           "frame": ", only where the kernel fits inside the image, its edge pixels left at 0 (a loop over the inner "
                    "pixels writing into a zeroed image, or Java's ConvolveOp with its default EDGE_ZERO_FILL): a "
                    "black frame a pixel wide",
           "full": ", its 'full' convolution (two pixels larger, zeros outside) cropped at the top-left corner (as "
                   "MATLAB's conv2 with its default shape, then out(1:H, 1:W)): the image moved a pixel down and "
                   "right, the top row and left column taking in zeros"}


def bordered(R: np.ndarray, k: np.ndarray, border: str) -> np.ndarray:
    """R (H, W, 3) filtered by the 3 x 3 kernel k, normalised, its border treated as :data:`BORDERS` names."""
    from scipy.ndimage import convolve

    k = (k / k.sum())[..., None]
    if border in ("nearest", "wrap"):
        return convolve(R, k, mode=border)
    if border == "zeros":
        return convolve(R, k, mode="constant", cval=0.0)
    if border == "frame":
        F = convolve(R, k, mode="nearest")
        F[0], F[-1], F[:, 0], F[:, -1] = 0.0, 0.0, 0.0, 0.0
        return F
    # 'full' cropped: out[i, j] = sum over a, b of k[a, b] R[i - a, j - b], zeros where i - a or j - b < 0.
    H, W = R.shape[:2]
    P = np.pad(R, ((2, 0), (2, 0), (0, 0)))
    return sum(k[a, b] * P[2 - a:2 - a + H, 2 - b:2 - b + W] for a in range(3) for b in range(3))


#: A 3 x 3 filter's fitted gain within this of 1 is a filter that keeps the image's level (the noise moves the fit
#: by a few tenths of a per cent; weights divided by another count are off by 10 % or more).
GAIN_KEPT = 0.01

#: Counts a hand-written 3 x 3 filter may divide its weights' sum by where another belongs (a box's 9, a binomial's
#: 16, the 8 neighbours, the 4 edge neighbours), and how far from 1 its gain may be fitted freely (a filter that
#: slightly changes the level). A gain neither near 1 nor a count's ratio is a scale, which the scale's own family
#: names: with it, a filter's border (a black frame, zeros) would mimic any darkening.
COUNTS = (9.0, 16.0, 8.0, 4.0)
FREE_GAIN = 0.1


def _ratio(g: float, total: float) -> float | None:
    """The count whose ratio ``total / count`` the gain g is (within 2 %), None if none is."""
    return next((c for c in COUNTS if abs(total / c - g) < 0.02 * g), None)


def _three_by_three(fit: Fit) -> list[Candidate]:
    """3 x 3 filters after rendering: a median, a maximum and a minimum filter (each pixel the median, largest or
    smallest of its 3 x 3 neighbourhood, channel by channel: a despeckle, a dilation, an erosion), none with a free
    parameter (of R: a filter of the noisy image differs by more where the noise is large, which the remainder
    shows); and the best of :data:`KERNELS` and :data:`BORDERS` with its weights' sum fitted (1: a correct filter;
    their count where their sum belongs: the sum over it; within :data:`FREE_GAIN` of 1 or such a ratio, else 1).
    That one has two parameters, the gain and the kernel chosen: where noise
    hides the filter (a dark image), it is a constant factor with a choice more, which Occam's rule does not name
    beside the factor."""
    from scipy.ndimage import maximum_filter, median_filter, minimum_filter

    out = []
    for name, f, what in (("median", median_filter, "a median filter (each pixel the median of its 3 x 3 "
                           "neighbourhood, a despeckle)"),
                          ("maximum", maximum_filter, "a maximum filter (each pixel the largest of its 3 x 3 "
                           "neighbourhood, a dilation that fills dark speckles)"),
                          ("minimum", minimum_filter, "a minimum filter (each pixel the smallest of its 3 x 3 "
                           "neighbourhood, an erosion that removes bright speckles)")):
        M = f(fit.R, size=(3, 3, 1), mode="nearest")
        out.append(Candidate("blur", f"{name} filter", f"the image filtered after rendering by {what}", fit.model(M),
                             0, value={"filter": name, "size": 3}, change=M - fit.R))
    # The median given size=3 for an (H, W, 3) array: its channels among each value's neighbours (its ends reflected).
    M = median_filter(fit.R, size=3)
    out.append(Candidate("blur", "median filter over the channels", "the image filtered after rendering by a median "
                         "filter of size 3 over the (H, W, 3) array's three axes (scipy.ndimage.median_filter(img, "
                         "size=3)): each value the median of a 3 x 3 x 3 block, its neighbours' other channels among "
                         "them, the colours pulled towards grey", fit.model(M), 0,
                         value={"filter": "median", "size": 3, "channels": True}, change=M - fit.R))
    best = None
    for name, (k, what) in KERNELS.items():
        for mode in BORDERS:
            F = bordered(fit.R, k, mode)
            wts = fit.w * F
            g = float(np.sum(wts * fit.S) / max(float(np.sum(wts * F)), 1e-300))  # the gain by weighted least squares
            if abs(g - 1) > FREE_GAIN and _ratio(g, float(k.sum())) is None:
                g = 1.0  # no weights' sum a program writes: the filter as written
            e = fit.model(g * F)
            if best is None or e < best[0]:
                best = (e, name, what, g, g * F, float(k.sum()), mode)
    e, name, what, g, M, total, border = best
    count = _ratio(g, total)
    why = (f" (its weights divided by {count:g} where their sum {total:g} belongs)" if count and count != total
           else "")
    # Near 1, three decimals ("1.012"), none within GAIN_KEPT of 1: a filter that keeps the image's level.
    gain = f"{g:.3f}" if abs(g - 1) < 0.1 else _num(g)
    sums = "" if abs(g - 1) < GAIN_KEPT else f" whose weights sum to {gain}, not 1{why}"
    # A camera whose every ray is out of focus by the same amount (a lens's aperture left open, focused at the image
    # plane) blurs the image as a filter does; only a filter leaves a mark at the image's border.
    lens = (", or blurred as much by the camera (a lens's aperture left open where a pinhole is meant, every ray out "
            "of focus)" if border == "nearest" and not sums else "")
    return out + [Candidate("blur", f"{name} filter times {gain}", f"the image filtered after rendering by {what}"
                            f"{sums}{BORDERS[border]}{lens}", e, 2,
                            value={"filter": name, "size": 3, "gain": g, "border": border}, change=M - fit.R,
                            # A filter with a gain is a scale with a filter: where noise hides the filter it is no
                            # other cause beside the scale (a dark image left ambiguous between the two otherwise).
                            generalises=("scale",))]


#: Radii (Gaussian standard deviations, pixels) and amounts of the unsharp masks tried.
UNSHARP_SIGMAS = (0.5, 0.7, 1.0, 1.5, 2.0, 3.0)
UNSHARP_AMOUNTS = np.linspace(0.1, 2.0, 39)


def _unsharp(fit: Fit, gaussian_filter) -> Candidate:
    """An unsharp mask after rendering, R + a (R - G_s * R) with negatives clipped to 0 (an image editor's or a
    library's sharpen): the radius s and amount a, scanned."""
    best = None
    for s in UNSHARP_SIGMAS:
        detail = fit.R - gaussian_filter(fit.R, (s, s, 0), mode="nearest")
        for a in UNSHARP_AMOUNTS:
            dm = np.maximum(fit.R + a * detail, 0.0) - fit.R
            e = fit.delta(dm)
            if best is None or e < best[0]:
                best = (e, s, float(a), dm)
    e, s, a, dm = best
    return Candidate("sharpen", "unsharp mask", f"the image sharpened after rendering: an unsharp mask of radius about "
                     f"{_num(s)} pixel and amount {_num(a)}", e, 2, value={"radius": s, "amount": a}, change=dm)



#: Entries of a lookup table of the sRGB curve interpolated linearly (a shader's or a script's table).
TABLE_SIZES = (5, 9, 17, 33)


def _coarse_table(fit: Fit, C: np.ndarray, srgb_eotf, srgb_oetf) -> Candidate:
    """The sRGB curve looked up in a table of n entries by linear interpolation (its chords), n scanned (one
    parameter)."""
    err, n, M = min(((fit.model(M), n, M) for n in TABLE_SIZES
                     for M in (srgb_eotf(np.interp(C, np.linspace(0.0, 1.0, n), srgb_oetf(np.linspace(0.0, 1.0, n)))),)),
                    key=lambda t: t[0])
    return Candidate("encoding", "sRGB from a table", f"the values sRGB-encoded through a table of {n} entries "
                     "interpolated linearly (the curve's chords: the darkest values too dark)", err, 1,
                     value={"table": n}, change=M - fit.R)


curves.name = "curves"
