r"""Bad pixels: a few pixels, or a block of them, black (0 in every channel) where the scene is not.

A pixel a path tracer computed is exactly 0 in every channel only where
every one of its samples found no light, which does not happen where the
reference is brighter than :data:`DARK` of the image's median luminance
(every surface of the closed room sees light; a pixel's noise, heavy-tailed,
says less about a single value than this does). A student's program writes
0 where a sample was NaN (``np.nan_to_num``), where a worker's tile was
never rendered, or where a pixel was skipped; a patch of them on one surface
is a hole in it (a face missing or cut out), which the words name too. The
model image is R with those pixels 0: it changes nothing else, so the
remainder test says whether the rest of the image is right. The pixels are
chosen by that property of the hand-in, not fitted (one parameter, the
rule); a set covering more than :data:`MOST` of the image is no longer a
few bad pixels. Pixels that are NaN or infinite are the ``finite``
criterion's (they are left out of every test, this one included).

Lines of one colour drawn over the render (a crosshair or grid drawn to
check the camera's aim, a guide line) are found the same way, by a property
no render has: a row or column whose every pixel is one value to the last
bit, far from the render's line; the model is R with those lines the
hand-in's, one parameter a line.
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.stats import LUMINANCE_WEIGHTS

_LUM = np.asarray(LUMINANCE_WEIGHTS)

#: A black pixel is bad where the reference's luminance is at least this share of the image's median.
DARK = 0.05
#: Largest share of the image's pixels the family explains as bad pixels.
MOST = 0.25
#: A line of one colour is drawn where its chi^2 against the render's line exceeds noise's by this many standard
#: deviations (sqrt(2 m) for m terms).
LINE_Z = 5.0
#: Black pixels are worded as one object's when this share of them is on it, and they cover most of its pixels
#: (not all: its edge pixels see something else too).
ONE_OBJECT = 0.9


def black_pixels(fit: Fit) -> np.ndarray:
    """(H, W) pixels 0 in every channel of the hand-in where the reference is clearly not."""
    return _zero_where_bright(fit.S, fit.R, fit.ok.all(axis=-1))


def _zero_where_bright(S: np.ndarray, R: np.ndarray, used: np.ndarray) -> np.ndarray:
    """(H, W) the ``used`` pixels of S 0 in every channel where R's luminance is at least :data:`DARK` of its median."""
    black = used & np.all(S == 0.0, axis=-1)
    lum = R @ _LUM
    return black & (lum >= DARK * float(np.median(lum[used]))) if used.any() else black


def _block(bad: np.ndarray) -> tuple[int, int, int, int] | None:
    """(top, bottom, left, right) when the bad pixels fill their bounding box of at least 2 x 2, else None."""
    rows, cols = np.nonzero(bad)
    t, b, l, r = rows.min(), rows.max(), cols.min(), cols.max()
    if b > t and r > l and bad[t:b + 1, l:r + 1].all() and int(bad.sum()) == (b - t + 1) * (r - l + 1):
        return int(t), int(b), int(l), int(r)
    return None


def bad_pixels(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The hand-in's black pixels where the scene is not, as written 0 (the module docstring), and lines of one
    colour drawn over the image (:func:`drawn_lines`)."""
    return _black(fit, inputs) + _lines(fit)


def drawn_lines(S: np.ndarray, R: np.ndarray, w: np.ndarray) -> dict[str, list[int]]:
    """{'rows': [...], 'columns': [...]}: the hand-in's rows and columns whose every pixel is one colour, to the last
    bit, neither black nor the image's largest value in every channel (an over-exposed display file's lines
    clipped at 1 are one value too) unless the four border lines are all one colour (a frame), and that colour far from the render's line (its chi^2 against it, weights
    ``w``, beyond :data:`LINE_Z` standard deviations of noise's): no render's line is one value by chance. At most
    :data:`MOST` of either."""
    out, top = {}, np.max(S, axis=(0, 1))
    # A frame drawn round the image (the four border lines one colour, the same) may be any colour, white too.
    borders = (S[0], S[-1], S[:, 0], S[:, -1])
    framed = all(np.all(b == S[0, 0]) for b in borders) and np.any(S[0, 0] != 0.0)
    for axis, word in ((0, "rows"), (1, "columns")):
        S_, R_, w_ = (np.moveaxis(x, axis, 0) for x in (S, R, w))
        one = (np.all(S_ == S_[:, :1], axis=(1, 2)) & np.any(S_[:, 0] != 0.0, axis=-1)
               & np.any(S_[:, 0] != top, axis=-1))
        one[[0, -1]] |= framed
        m = np.maximum(np.count_nonzero(w_, axis=(1, 2)), 1)
        far = np.sum((S_ - R_) ** 2 * w_, axis=(1, 2)) - m > LINE_Z * np.sqrt(2.0 * m)
        k = np.flatnonzero(one & far)
        if 0 < len(k) <= MOST * len(S_):
            out[word] = k.tolist()
    return out


def _lines(fit: Fit) -> list[Candidate]:
    """Lines of one colour drawn over the render (a crosshair or grid drawn to check the camera's aim and left in,
    a guide line, a line of one value written by an index that stays put): the model is R with those lines
    the hand-in's colour; each line is one parameter, read off the hand-in."""
    found = drawn_lines(fit.S, fit.R, fit.w)
    if not found:
        return []
    drawn = np.zeros(fit.R.shape[:2], bool)
    drawn[found.get("rows", []), :] = True
    drawn[:, found.get("columns", [])] = True
    # A file that holds no value above 1 clipped the render's too (the light's pixels at 1).
    M = np.where(drawn[..., None], fit.S, np.minimum(fit.R, 1.0) if float(np.max(fit.S)) <= 1.0 else fit.R)
    colours = {tuple(float(v) for v in fit.S[r, c]) for r, c in np.argwhere(drawn)}
    colour = ("the colour " + "(" + ", ".join(f"{v:.3g}" for v in next(iter(colours))) + ")" if len(colours) == 1
              else f"{len(colours)} colours")
    where = " and ".join(f"{word[:-1] if len(ks) == 1 else word} {', '.join(map(str, ks))}" for word, ks in found.items())
    n = sum(len(ks) for ks in found.values())
    text = (f"{'a line' if n == 1 else f'{n} lines'} of one colour drawn over the render ({colour}, along {where}): "
            "a crosshair, grid, guide or frame drawn to check the camera's aim or for a figure and left in, or a line "
            "written with one value")
    return [Candidate("bad_pixels", "lines drawn", text, fit.model(M), n, value={"lines": found}, change=M - fit.R)]


def _black(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The hand-in's black pixels where the scene is not, as written 0."""
    bad = black_pixels(fit)
    n = int(bad.sum())
    if n == 0 or n > MOST * max(int(fit.ok.all(axis=-1).sum()), 1):
        return []
    change = np.where(bad[..., None], -fit.R, 0.0)
    box = _block(bad)
    obj = _on_one_object(bad, inputs)
    hole = _hole(bad, inputs) if not obj and box is None else ""
    shadow = n >= 2 and _in_shadow(bad, inputs)
    if shadow:
        text = (f"{n} pixels ({100 * n / bad.size:.2g} % of the image) black where the scene is not, nearly every one "
                "where the light is hidden from the surface (no direct light there): the light bounced there lost, as "
                "when the path ends where its shadow ray is blocked (an early exit meant for the shadow test, in the "
                "path's loop), no light is bounced at all, or Russian roulette stops every path that has gathered no "
                "light yet (its survival probability taken from the radiance so far)")
    elif obj:  # one object's pixels: neither a tile left out nor NaNs scattered, first of all that object
        text = (f"{n} pixels ({100 * n / bad.size:.2g} % of the image) black where the scene is not{obj}; or a NaN or "
                "infinite sample written as 0 on it (a division by a zero pdf or cosine there)")
    elif hole:
        text = (f"a patch of {n} pixels ({100 * n / bad.size:.2g} % of the image) black on {hole}, all touching: a hole "
                f"in {hole} (a face missing or cut out, the rays through it finding nothing behind), or NaN samples "
                "written as 0 there (a division by a zero pdf or cosine)")
    elif box is not None:
        t, b, l, r = box
        text = (f"a block of {b - t + 1} x {r - l + 1} pixels (rows {t} to {b}, columns {l} to {r}) left black: "
                "a tile or part of the image never rendered or never written")
    else:
        first = np.argwhere(bad)[0]
        text = (f"{n} pixels ({100 * n / bad.size:.2g} % of the image) black where the scene is not, the first at row "
                f"{int(first[0])}, column {int(first[1])}: a NaN or infinite sample written as 0, or pixels "
                "skipped; check for a division by a zero pdf or cosine")
    rows, cols = np.nonzero(bad)
    return [Candidate("bad_pixels", "black pixels", text, fit.delta(change), 1,
                      value={"pixels": n, "block": box, "first": [int(rows[0]), int(cols[0])], "in_shadow": shadow},
                      change=change)]


#: Least share of the image's pixels that are holes for them to count (a few NaN samples written 0 are no surface).
MIN_HOLES = 0.005
#: Least share of the holes with both neighbours along a row or along a column black too: holes are patches or
#: lines (rows never written), not a sparse render's zeros scattered (at a share p of zeros, about 2 p^2 of them).
HOLE_INTERIOR = 0.5
#: Least luminance off the holes, as a share of the reference's there, for the image to be lit around them: an image
#: dark throughout (the light hardly ever found) may have dark pixels 0 by chance.
LIT_AROUND = 0.25


#: The share of black pixels that may have some direct light and still be read as where the light is hidden (a
#: penumbra's or an edge's pixel the basis's few samples lit, the light seen in the mirror).
LIT_SHARE = 0.01


def directly_lit(basis) -> np.ndarray | None:
    """(H, W) the pixels the light reaches directly or the camera sees emitting: their direct light (the ``basis``'s
    paths of depth 2 less those of depth 1: next-event estimation alone lights a surface there) or the emission seen
    there (the light's own pixels get no light sample) not 0, to the last bit; None without the basis's depths. A
    shadow ray always blocked gives a pixel no sample of direct light, whatever the basis's seed."""
    depth = dict(basis.nodes.get("depth", ())) if basis is not None else {}
    if 1 not in depth or 2 not in depth:
        return None
    seen = np.asarray(depth[1], np.float64)  # the emission the camera sees: the light's own pixels
    direct = np.asarray(depth[2], np.float64) - seen
    return np.any(direct != 0.0, axis=-1) | np.any(seen != 0.0, axis=-1)


def _in_shadow(bad: np.ndarray, inputs: Inputs) -> bool:
    """Whether (all but :data:`LIT_SHARE` of) the black pixels are ones the light does not reach directly
    (:func:`directly_lit`)."""
    lit = directly_lit(inputs.basis)
    return lit is not None and int(lit[bad].sum()) <= int(LIT_SHARE * int(bad.sum()))


def _hole(bad: np.ndarray, inputs: Inputs) -> str:
    """The object's name where the black pixels are one patch of at least 2 x 2, touching one another (not NaNs
    scattered), inside one object's pixels and covering less of it than :func:`_on_one_object` words; else ''."""
    from scipy.ndimage import binary_erosion, label

    if inputs.labels is None or label(bad, structure=np.ones((3, 3)))[1] != 1 or not binary_erosion(
            bad, np.ones((2, 2))).any():
        return ""
    ks = np.unique(inputs.labels[bad])
    return inputs.label_names[int(ks[0])].split(" (")[0] if len(ks) == 1 else ""


def _on_one_object(bad: np.ndarray, inputs: Inputs) -> str:
    """Words for black pixels that are (nearly) all of one object's: which, and for a mirror what blackens it ('' when
    they are spread over several objects or cover little of one)."""
    if inputs.labels is None:
        return ""
    ks, counts = np.unique(inputs.labels[bad], return_counts=True)
    k = int(ks[np.argmax(counts)])
    seen = int(np.count_nonzero(inputs.labels == k))
    if counts.max() < ONE_OBJECT * bad.sum() or 2 * counts.max() < seen:
        return ""
    name = inputs.label_names[k].split(" (")[0]
    words = f": {name}'s pixels, most of them, {name} rendered black"
    if "mirror" in name:
        # Black where the camera sees the mirror: no path through it reaches the camera.
        words += (" (paths through the mirror to the camera never counted: a light tracer, whose paths cannot reach "
                  "the camera through a mirror, a path ended at the first specular hit, or the mirror's "
                  "reflectance 0)")
    return words


bad_pixels.name = "bad_pixels"


def black_holes(S: np.ndarray, R: np.ndarray, mask: np.ndarray, lit: np.ndarray | None) -> np.ndarray | None:
    """(H, W) the hand-in's pixels 0 in every channel where the reference is clearly not
    (:func:`black_pixels`' rule) and the light reaches directly (``lit``,
    :func:`directly_lit`), where they are at least :data:`MIN_HOLES` of the pixels; else None.

    A sample of a surface the light reaches directly is never 0 (next-event estimation finds the light), so a
    patch of such pixels 0 in every channel, in an image lit around it, says no surface is there, or a black one, or
    nothing was written: no change that leaves light there explains it, however close its chi^2
    (:func:`mcrt.grade.adequacy.holes_left`). They count as holes where at least :data:`HOLE_INTERIOR` of them are
    black with both neighbours along a row or a column (a sparse render's zeros are scattered) and the image off them keeps
    :data:`LIT_AROUND` of the reference's light. Black pixels in shadow are the bounced light lost, another reading
    (:func:`bad_pixels`)."""
    used = mask & np.isfinite(S).all(axis=-1)
    if lit is None or not used.any():
        return None
    lum = R @ _LUM
    black = _zero_where_bright(S, R, used) & lit
    if int(black.sum()) < MIN_HOLES * int(used.sum()):
        return None
    pad = np.pad(black, 1)
    inner = black & ((pad[:-2, 1:-1] & pad[2:, 1:-1]) | (pad[1:-1, :-2] & pad[1:-1, 2:]))
    off = used & ~black & (lum < 1.0)  # the light's own pixels say nothing of the room's light
    around = float(np.sum(S[off] @ _LUM)) >= LIT_AROUND * float(np.sum(lum[off]))
    return black if around and int(inner.sum()) >= HOLE_INTERIOR * int(black.sum()) else None
