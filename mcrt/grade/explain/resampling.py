r"""A resolution mistake: the image rendered at 1/k the resolution and enlarged.

The model image is R box-filtered to 1/k of the resolution (the expected
value of the smaller render), enlarged by repeating pixels (blocks of k x k
equal pixels, whose share in the hand-in the words give), bilinearly, or
bicubically as Pillow's ``Image.resize`` does by default on an 8-bit image
(its own kernel on the display values: sRGB-encoded, clipped to 1, then
decoded; in linear values the light's overshoot would ring into its
neighbours, which clipped display values do not), for k in :data:`FACTORS`.
A loop bound off by one renders the image at (W - 1) x (H - 1) or (W + 1) x
(H + 1) and writes it from the top-left corner: the last row and column are
black, or the render's are cut off; the model image is R box-filtered to
that size (each new pixel the area-weighted mean of the grade pixels it
covers), padded or cropped. Only every other row (or column) rendered,
each copied to the next, is R with its even rows (columns) doubled. An image rendered at a higher resolution N and
reduced by picking the nearest pixel (an image library's NEAREST, or
``img[i * N // W]``) keeps one of the render's pixels for each of its own:
pixel i shows the film from k W/N to (k + 1) W/N, k = floor((i + 1/2) N/W)
(a library's centre convention) or floor(i N/W) (an index scaled); its model
image samples the basis's finer image (:class:`mcrt.grade.explain.camera._Warp`)
over that footprint, for N in :data:`LARGER` or W times :data:`RATIOS`.
An image shifted after rendering by half a pixel (to "centre the pixels")
with bilinear interpolation, as ``scipy.ndimage.shift(order=1)`` does, is
moved and blurred at once: each pixel the mean of two (or four) of R's, the
edge filled with black (scipy's default) or its nearest pixels; its words
name the shift (a pixel offset), which a camera's offset alone (moved,
not blurred) does not fit, and a box filter of 2 pixels (each pixel the
mean of itself and its neighbour on one side), which is the same image. A
frame of another aspect ratio (:data:`ASPECTS`) rendered with the image's
view across its longer side and centred between black bars is R inside the
band, black outside. A window of the render enlarged to fill the image (a
canvas sized by a device pixel ratio and read back at the image's size, a
viewer's zoom saved, a crop resized) shows the part of the view from
:math:`(x_0, y_0)` of width and height s: pixel i samples the render at
:math:`x_0 + (i + 1/2)\,s - 1/2` by bilinear interpolation (of the display
values for a display file, as a browser's canvas smooths them); s on
:data:`WINDOW_SCALES` and the corner on a grid of the render's pixels, then
refined, three parameters. A centred window is left to the camera family:
it is the view of a narrower field of view, blurred a little.
"""

from __future__ import annotations

import itertools

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.grade.feedback import num as _num


#: Resolution factors of the resampling family.
FACTORS = (2, 4)
#: Resolutions a render reduced by nearest pixels may have had: common image sizes (the course's 100 among them),
#: and the image's own times each of RATIOS.
LARGER = (80, 96, 100, 120, 128, 150, 160, 200, 256, 300, 320, 400, 512)
RATIOS = (1.25, 1.5, 2.0, 2.5, 3.0, 4.0)


def _blocks_equal(S: np.ndarray, k: int) -> float:
    """Share of k x k blocks whose pixels are all equal (the trace of nearest-neighbour enlarging)."""
    h, w = S.shape[:2]
    if h % k or w % k:
        return 0.0
    b = S.reshape(h // k, k, w // k, k, -1)
    return float(np.mean(np.all(b == b[:, :1, :, :1], axis=(1, 3, 4))))


def resampling(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The image rendered at 1/k the resolution and enlarged (nearest, bilinear, bicubic), or at one pixel more or less."""
    from scipy.ndimage import zoom

    from mcrt.stats.tiles import block_means

    h, w = fit.R.shape[:2]
    out = []
    for k in FACTORS:
        if h % k or w % k:
            continue
        low = block_means(fit.R, k)
        near = np.repeat(np.repeat(low, k, axis=0), k, axis=1)
        lin = zoom(low, (k, k, 1), order=1, mode="nearest", grid_mode=True)
        eq = _blocks_equal(fit.S, k)
        blocks = f" ({100 * eq:.0f} % of its {k} x {k} blocks are one colour)" if eq > 0.5 else ""
        out.append(Candidate("resampling", f"enlarged {k}x (nearest)", f"the image rendered at {w // k} x {h // k} "
                              f"pixels and enlarged {k} times by repeating pixels{blocks}", fit.model(near), 1,
                              value={"factor": k, "method": "nearest", "equal_blocks": eq}, change=near - fit.R))
        out.append(Candidate("resampling", f"enlarged {k}x (bilinear)", f"the image rendered at {w // k} x {h // k} "
                              f"pixels and enlarged {k} times by bilinear interpolation", fit.model(lin), 1,
                              value={"factor": k, "method": "bilinear"}, change=lin - fit.R))
        cub = _bicubic(low, w, h)
        out.append(Candidate("resampling", f"enlarged {k}x (bicubic)", f"the image rendered at {w // k} x {h // k} "
                              f"pixels and enlarged {k} times by bicubic interpolation of its display values (an image library's default)",
                              fit.model(cub), 1, value={"factor": k, "method": "bicubic"}, change=cub - fit.R))
    for d in (-1, 1):
        off = _off_by_one(fit.R, d)
        what = "the last row and column left black" if d < 0 else "its last row and column cut off"
        out.append(Candidate("resampling", f"rendered {w + d} x {h + d}", f"the image rendered at {w + d} x {h + d} "
                              f"pixels (a loop bound off by one) and written from the top-left corner, {what}",
                              fit.model(off), 1, value={"size": [w + d, h + d], "method": "off by one"},
                              change=off - fit.R))
    for axis, what in ((0, "row"), (1, "column")):  # a loop stepping by 2 that copies what it rendered onward
        dup = np.repeat(np.take(fit.R, np.arange(0, fit.R.shape[axis], 2), axis=axis), 2, axis=axis)
        dup = np.take(dup, np.arange(fit.R.shape[axis]), axis=axis)
        out.append(Candidate("resampling", f"every other {what} copied", f"only every other {what} rendered, each "
                             f"copied to the next {what} (a loop stepping by 2, or {what}s written twice)",
                             fit.model(dup), 0, value={"copied": f"{what}s", "method": "every other"},
                             change=dup - fit.R))
    out += _boxed(fit)
    out.append(_shifted(fit))
    out += _window(fit)
    if inputs.basis is not None and getattr(inputs.basis, "fine", None) is not None:
        out.append(_nearest_from_larger(fit, inputs))
    return out


#: The share of the view's width (and height) a window enlarged to the whole image may keep: a device pixel ratio of
#: 1.25 keeps 0.8, a zoom of 2 keeps 0.5.
WINDOW_SCALES = np.arange(0.5, 0.976, 0.025)
#: The corners tried on each axis at each scale before refining: this many, evenly from the first pixel to the last
#: place the window fits.
WINDOW_CORNERS = 5
#: How many of the grid's best the simplex method refines, and its evaluations from each.
WINDOW_STARTS = 3
WINDOW_EVALS = 200
#: How far (in pixels, on each axis) a window's centre must lie from the image's for it to be read as a window: a
#: centred one is a narrower field of view (:func:`_window`).
CENTRED = 0.5

#: Width-to-height ratios of a frame rendered inside the image with black bars (video's 16:9, cinema's 1.85 and 2.39,
#: a 16:10 screen, television's 4:3), and their inverses (bars at the sides).
ASPECTS = {"16:9": 16 / 9, "1.85:1": 1.85, "2.39:1": 2.39, "16:10": 1.6, "4:3": 4 / 3}


def _band(n: int, kept: float, whole: bool) -> np.ndarray:
    """How much of each of n pixels a centred band ``kept`` pixels wide covers (0 to 1); ``whole``: the band rounded
    to whole pixels and its start to the pixel before the middle, as a program at this size places it."""
    if whole:
        kept = float(round(kept))
        lo = float((n - int(kept)) // 2)
    else:
        lo = (n - kept) / 2.0
    edges = np.arange(n + 1, dtype=np.float64)
    return np.clip(np.minimum(edges[1:], lo + kept) - np.maximum(edges[:-1], lo), 0.0, 1.0)


def _boxed(fit: Fit) -> list[Candidate]:
    """A frame of another aspect ratio rendered with the image's horizontal (or vertical) view and put in the middle
    of the image, black bars above and below (letterboxed) or at the sides (pillarboxed): R inside the band, black
    outside it, the pixels on its edges covered in part (or the band in whole pixels). The ratio and the rounding the
    choice, one parameter."""
    h, w = fit.R.shape[:2]
    best = None
    ratios = [(name, a) for name, a in ASPECTS.items()]
    ratios += [(":".join(name.split(":")[::-1]), 1.0 / a) for name, a in ASPECTS.items()]  # upright: 9:16
    for (name, a), whole in itertools.product(ratios, (True, False)):
        if a > w / h:  # wider than the image: its rows are fewer
            cover, where = _band(h, w / a, whole)[:, None, None], "above and below (letterboxed)"
        elif a < w / h:
            cover, where = _band(w, h * a, whole)[None, :, None], "at the sides (pillarboxed)"
        else:
            continue
        M = fit.R * cover
        err = fit.model(M)
        if best is None or err < best[0]:
            best = (err, name, where, M)
    if best is None:
        return []
    err, name, where, M = best
    return [Candidate("resampling", f"{name} frame with bars", f"the image rendered in a {name} frame (the same view "
                      f"across its longer side) and put in the middle of the image, black bars {where}", err, 1,
                      value={"aspect": name, "method": "bars"}, change=M - fit.R)]


#: The shifts (x, y) in pixels of an image moved after rendering (half a pixel along x, y or both, either way).
HALF_SHIFTS = tuple((dx, dy) for dx in (-0.5, 0.0, 0.5) for dy in (-0.5, 0.0, 0.5) if dx or dy)


def _shifted(fit: Fit) -> Candidate:
    """The best of R shifted by :data:`HALF_SHIFTS` with bilinear interpolation, the edge black or the nearest pixels
    (module docstring)."""
    from scipy.ndimage import shift

    chi, (dx, dy), mode, moved = min(((fit.model(m), d, mode, m) for d in HALF_SHIFTS for mode in ("constant", "nearest")
                                      for m in (shift(fit.R, (d[1], d[0], 0.0), order=1, mode=mode),)),
                                     key=lambda t: t[0])
    edge = "black" if mode == "constant" else "with its nearest pixels"
    box = f"{1 + (dx != 0)} x {1 + (dy != 0)}"
    return Candidate("pixel_offset", "image shifted after rendering", f"the image shifted by ({dx:+.2f}, {dy:+.2f}) "
                     "pixel (x right, y down) after rendering, by bilinear interpolation (scipy.ndimage.shift with "
                     f"order 1, or an image library's translate), its edge filled {edge}: moved and slightly blurred, "
                     "as when the pixels are 'centred' after rendering; or, the same image, a box filter of "
                     f"{box} pixels (scipy.ndimage.uniform_filter with a size of 2), each pixel the mean of itself and "
                     "its neighbours on one side", chi, 1,
                     value={"dx": dx, "dy": dy, "method": "bilinear", "edge": mode}, change=moved - fit.R)


def _nearest_from_larger(fit: Fit, inputs: Inputs) -> Candidate:
    """The best of the image rendered at N x N' (N in LARGER) and reduced by nearest pixels (module docstring)."""
    from mcrt.grade.explain.basis import SUB
    from mcrt.grade.explain.camera import _Warp

    wp = _Warp(inputs.basis)
    h, w = fit.R.shape[:2]
    sub = (np.arange(SUB) + 0.5) / SUB
    best = None
    for n in sorted({n for n in LARGER if n > w} | {round(r * w) for r in RATIOS}):
        m = max(round(n * h / w), 1)
        for centre in (True, False):
            kx = np.floor((np.arange(w) + 0.5 * centre) * n / w)
            ky = np.floor((np.arange(h) + 0.5 * centre) * m / h)
            u = ((kx[:, None] + sub[None, :]) * w / n).ravel()
            v = ((ky[:, None] + sub[None, :]) * h / m).ravel()
            change = wp.at(u[None, :], v[:, None]) - wp.identity
            chi = fit.delta(change)
            if best is None or chi < best[0]:
                best = (chi, n, m, centre, change)
    chi, n, m, centre, change = best
    how = "an image library's nearest-pixel resize" if centre else "pixel i taken from the render's i N / W"
    return Candidate("resampling", f"reduced from {n} x {m} (nearest)", f"the image rendered at {n} x {m} pixels and "
                     f"reduced to {w} x {h} by keeping the nearest pixel ({how}): each pixel one of the render's, not "
                     "the mean of those it covers (as every sample of a pixel through one fixed point of it: the "
                     "sub-pixel jitter constant or missing)", chi, 1,
                     value={"size": [n, m], "method": "nearest", "centre": centre}, change=change,
                     # Kept pixels of a larger render are pixels moved by a fraction of a pixel, with a smaller
                     # footprint: the camera's families read such a misregistration too (the pixel offset's words
                     # name an image resampled with an offset), so they are one reading of the image with this.
                     generalises=("fov", "aspect", "pixel_offset", "rotation"))


def _area_matrix(n: int, m: int) -> np.ndarray:
    """(m, n): pixel j of m across the extent of n pixels, as the area-weighted mean of the n pixels it covers."""
    edges = np.arange(m + 1) * n / m
    A = np.zeros((m, n))
    for j in range(m):
        for i in range(int(np.floor(edges[j])), min(n, int(np.ceil(edges[j + 1])))):
            A[j, i] = min(edges[j + 1], i + 1) - max(edges[j], i)
    return A / A.sum(axis=1, keepdims=True)


def _off_by_one(R: np.ndarray, d: int) -> np.ndarray:
    """R as rendered at (W + d) x (H + d) and written into W x H from the top-left corner (black where unwritten)."""
    h, w = R.shape[:2]
    Ay, Ax = _area_matrix(h, h + d), _area_matrix(w, w + d)
    small = np.einsum("yi,ijc,xj->yxc", Ay, R, Ax)
    out = np.zeros_like(R)
    hh, ww = min(h, h + d), min(w, w + d)
    out[:hh, :ww] = small[:hh, :ww]
    return out


def _bilinear_rows(n: int, scale: float, start: float) -> np.ndarray:
    """(n, n) weights of bilinear interpolation: output pixel i samples the input at start + (i + 1/2) scale - 1/2
    (pixel centres at k, the edge pixels repeated beyond the ends)."""
    x = np.clip(start + (np.arange(n) + 0.5) * scale - 0.5, 0.0, n - 1.0)
    lo = np.minimum(np.floor(x).astype(int), n - 2)
    f = x - lo
    A = np.zeros((n, n))
    A[np.arange(n), lo] = 1.0 - f
    A[np.arange(n), lo + 1] += f
    return A


def _window(fit: Fit) -> list[Candidate]:
    """A window of the render enlarged to the whole image (module docstring): the scale and the corner fitted; none
    where the window is centred (within :data:`CENTRED` of a pixel on each axis), which is the same view as a narrower
    field of view, up to the interpolation's blur: the camera family's reading, whose words name a larger render
    cropped, and a camera model that bends the view's edges fits it as well."""
    from scipy.optimize import minimize

    from mcrt.image_files import srgb_eotf, srgb_oetf

    h, w = fit.R.shape[:2]
    display = float(np.nanmax(np.where(fit.ok, fit.S, 0.0))) <= 1.0  # a display file: its codes interpolated
    src = srgb_oetf(np.clip(fit.R, 0.0, 1.0)) if display else fit.R

    def image(p):
        scale, x0, y0 = p
        rows = np.tensordot(_bilinear_rows(h, scale, y0), src, axes=(1, 0))  # (h, w, c): the rows resampled
        M = np.einsum("ikc,lk->ilc", rows, _bilinear_rows(w, scale, x0), optimize=True)
        return srgb_eotf(np.clip(M, 0.0, 1.0)) if display else M

    def err(p):
        return fit.model(image(p))

    grid = [(sc, x0, y0) for sc in WINDOW_SCALES for x0 in np.linspace(0.0, (1 - sc) * w, WINDOW_CORNERS)
            for y0 in np.linspace(0.0, (1 - sc) * h, WINDOW_CORNERS)]
    # Refined from the best few by the simplex method, over the scale and the window's centre (which a change of
    # scale leaves in place: the corner's and the scale's errors trade off along a narrow valley).
    def corner(q):
        return q[0], q[1] - q[0] * w / 2, q[2] - q[0] * h / 2

    tried = sorted((err(p), p) for p in grid)
    best_err, best = tried[0]
    for _, (sc, x0, y0) in tried[:WINDOW_STARTS]:
        q0 = np.array([sc, x0 + sc * w / 2, y0 + sc * h / 2])
        # At a scale of 1 the window is the render shifted, which the pixel offsets' families say as a shift.
        r = minimize(lambda q: err(corner(q)) if WINDOW_SCALES[0] <= q[0] <= WINDOW_SCALES[-1] else np.inf, q0,
                     method="Nelder-Mead",
                     options={"initial_simplex": q0 + np.vstack([np.zeros(3), np.diag([0.02, 1.0, 1.0])]),
                              "xatol": 1e-3, "fatol": 1e-3, "maxfev": WINDOW_EVALS})
        if r.fun < best_err:
            best_err, best = r.fun, corner(r.x)
    scale, x0, y0 = best
    if abs(x0 - (1 - scale) * w / 2) < CENTRED and abs(y0 - (1 - scale) * h / 2) < CENTRED:
        return []
    M = image(best)
    span = lambda lo, n: f"{100 * max(lo, 0.0) / n:.0f} % to {100 * min(lo + scale * n, n) / n:.0f} %"  # noqa: E731
    part = f"the view's part from {span(x0, w)} across and {span(y0, h)} down"
    how = "its display values" if display else "its values"
    return [Candidate("resampling", "window enlarged", f"the image a window of the render enlarged to fill it: {part}, "
                      f"{_num(round(1 / scale, 2))} times larger, by bilinear interpolation of {how} (a "
                      f"canvas sized by a device pixel ratio of {_num(round(1 / scale, 2))} and read back at the "
                      "image's size, a viewer's zoom saved, or a crop resized)", fit.model(M), 3,
                      value={"scale": round(float(scale), 3), "corner": [round(float(x0), 2), round(float(y0), 2)],
                             "method": "window"}, change=M - fit.R)]


def _bicubic(low: np.ndarray, w: int, h: int) -> np.ndarray:
    """``low`` enlarged to w x h with Pillow's bicubic filter on its display values (module docstring), channel by
    channel in mode F (no rounding)."""
    from PIL import Image

    from mcrt.image_files import srgb_eotf, srgb_oetf

    disp = srgb_oetf(np.clip(low, 0.0, 1.0))
    up = np.stack([np.asarray(Image.fromarray(np.ascontiguousarray(disp[..., c], np.float32), "F")
                              .resize((w, h), Image.Resampling.BICUBIC), np.float64) for c in range(low.shape[2])],
                  axis=-1)
    return srgb_eotf(np.clip(up, 0.0, 1.0))


resampling.name = "resampling"
