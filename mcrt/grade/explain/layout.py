r"""Values stored at the wrong places: lines out of order or all one, a row's channels one after another.

Rows (or columns) stored out of order (a pool of workers' rows kept in the
order they finished, an index off for some lines) are R with each such line
replaced by the line of R it matches (:func:`moved_lines`); each moved line
is one parameter. A file writer whose loops run channel before column
writes a row's reds, then its greens, then its blues; read as the format's
interleaved samples, pixel i of the row holds samples 3 i to 3 i + 2 of
that run. The same order over the whole image (every red first, a planar
array written as it lies in memory) is the other fixed layout. Neither has
a free parameter. Every row (or column) one and the same, the render's
row k repeated (Python's ``[[0.0] * W] * H`` holds one row H times, and
the last row written is every row), has k for its one parameter. A tiled
render whose tiles' pixel coordinates are wrong (each tile the whole view
shrunk, or each the first tile) has the tiles' count. Every pixel its row's
(column's) mean, a mean over the wrong axis, has none.
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit

#: A row (or column) matches a row of the reference up to NEAR places away better than its own by this many standard
#: deviations of its chi^2 (sqrt(2 m) for m terms): noise never does (another row holds the same noise against the
#: image's gradient between rows); a row written a few places off does wherever the image changes between rows.
LINE_Z = 5.0
#: How many places away a line may have been stored (a pool of four workers' rows, each at most three places off).
NEAR = 3
#: Lines so misplaced, at least this many and this share of them, before the image is said to hold them out of order.
LINES_MIN, LINES_SHARE = 3, 0.05


def moved_lines(S: np.ndarray, R: np.ndarray, w: np.ndarray) -> tuple[str, np.ndarray] | None:
    """('rows' or 'columns', for each line of S the line of R it shows) where lines of S match a line of R up to
    :data:`NEAR` places away better than their own, by :data:`LINE_Z` and by more than half their own excess over
    noise (``w``: each term's weight, 1 / variance; 0 where not compared), and whose line of R is so misplaced
    too (lines exchanged, not one line like its neighbour), in at least :data:`LINES_MIN` and :data:`LINES_SHARE` of
    them; else None. Against a biased image every line's chi^2 is large and another line's
    may be the smaller by chance of the gradient; it takes away little of the excess. Of rows and columns, the
    direction with the larger share: lines of one direction out of order make a few lines of the other match better
    too."""
    found = []
    for axis, word in ((0, "rows"), (1, "columns")):
        S_, R_, w_ = (np.moveaxis(x, axis, 0) for x in (S, R, w))
        n = len(S_)
        m = np.maximum(np.count_nonzero(w_, axis=(1, 2)), 1)
        own = np.sum((S_ - R_) ** 2 * w_, axis=(1, 2))
        nb, src = np.full(n, np.inf), np.arange(n)
        for d in range(-NEAR, NEAR + 1):
            r = np.clip(np.arange(n) + d, 0, n - 1)  # the line d places away, within the image
            e = np.where(r != np.arange(n), np.sum((S_ - R_[r]) ** 2 * w_, axis=(1, 2)), np.inf)
            src, nb = np.where(e < nb, r, src), np.minimum(nb, e)
        gain = own - nb
        ok = (gain > LINE_Z * np.sqrt(2.0 * m)) & (gain > 0.5 * (own - m))
        ok &= ok[src]  # lines exchanged: the line it shows is at another place too (a change on one object is not)
        k = int(np.count_nonzero(ok))
        if k >= max(LINES_MIN, LINES_SHARE * n):
            found.append((k / n, word, np.where(ok, src, np.arange(n))))
    if not found:
        return None
    _, word, src = max(found, key=lambda f: f[0])
    return word, src


def planar_rows(R: np.ndarray) -> np.ndarray:
    """R written a row at a time with the channel loop outside the column loop, read back interleaved."""
    h, w, c = R.shape
    return np.ascontiguousarray(np.swapaxes(R, 1, 2)).reshape(h, w, c)


def planar_image(R: np.ndarray) -> np.ndarray:
    """R written channel by channel over the whole image (a planar array), read back interleaved."""
    h, w, c = R.shape
    return np.ascontiguousarray(np.moveaxis(R, 2, 0)).reshape(h, w, c)


def layout(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """Lines out of order, and a row's or the image's channels written one after another (the module docstring)."""
    out = []
    lines = moved_lines(fit.S, fit.R, fit.w)
    if lines is not None:
        word, src = lines
        k = int(np.count_nonzero(src != np.arange(len(src))))
        moved = np.take(fit.R, src, axis=0 if word == "rows" else 1)
        out.append(Candidate("lines_order", f"{word} out of order", f"{word} stored out of order: {k} of the image's "
                             f"{len(src)} {word} show the render's {word[:-1]} up to {NEAR} places away (written in the "
                             f"order a pool of workers finished them, or an index off for some of them)",
                             fit.model(moved), k, value={"lines": word, "moved": k, "of": len(src)},
                             change=moved - fit.R,
                             # A shift by whole lines and lines copied onward are lines of R at other places too.
                             generalises=("pixel_offset", "resampling")))
    out += _one_line(fit)
    out += _tiles(fit)
    out += _line_means(fit)
    for name, f, text in (("planar rows", planar_rows, "each row's samples written channel by channel (the row's reds, "
                           "then its greens, then its blues: the channel loop outside the column loop) where the "
                           "format interleaves them"),
                          ("planar image", planar_image, "the image's samples written channel by channel (every red, "
                           "then every green, then every blue: a planar array written as it lies in memory) where the "
                           "format interleaves them")):
        # A file that holds no value above 1 clipped them before they were moved (the light's pixels at 1).
        M = f(np.minimum(fit.R, 1.0) if float(np.max(fit.S)) <= 1.0 else fit.R)
        out.append(Candidate("layout", name, text, fit.model(M), 0, value=name, change=M - fit.R))
    return out


#: Tiles across the image (and down it) a tiled renderer may split it into.
TILES = (2, 4, 8, 16)


def _tiles(fit: Fit) -> list[Candidate]:
    """A tiled render whose tiles' pixel coordinates are wrong, n tiles across and down (the count the choice, one
    parameter): each tile's pixels normalised by the tile's size, not the image's (every tile the whole view at 1/n of
    the size: R box-filtered down by n, repeated n x n times), or each tile's origin never added (every tile the first
    tile: R's top-left tile repeated)."""
    h, w, _ = fit.R.shape
    models = {"whole view": [], "first tile": []}
    for n in TILES:
        if h % n or w % n or h // n < 2 or w // n < 2:
            continue
        small = fit.R.reshape(h // n, n, w // n, n, 3).mean(axis=(1, 3))
        models["whole view"].append((n, np.tile(small, (n, n, 1))))
        models["first tile"].append((n, np.tile(fit.R[: h // n, : w // n], (n, n, 1))))
    words = {"whole view": "each tile's pixel coordinates divided by the tile's width and height, not the image's: "
                           "every tile the whole view at 1/{n} of the size",
             "first tile": "each tile's origin never added to its pixels' rays: every tile rendered as the top-left "
                           "one"}
    out = []
    for name, nodes in models.items():
        if not nodes:
            continue
        err, n, M = min(((fit.model(M), n, M) for n, M in nodes), key=lambda t: t[0])
        out.append(Candidate("tiles", f"tiles: {name}", f"the image rendered in {n} x {n} tiles, "
                             + words[name].format(n=n), err, 1, value={"tiles": n, "kind": name}, change=M - fit.R))
    return out


def _line_means(fit: Fit) -> list[Candidate]:
    """Each pixel its row's (column's) mean: a mean over the wrong axis of an array that holds the image's columns
    (rows) beside the samples, every row (column) flat. Worded as a smoothing, which it is, along the lines; no free
    parameter."""
    out = []
    for axis, word, across in ((1, "row", "columns"), (0, "column", "rows")):
        M = np.broadcast_to(fit.R.mean(axis=axis, keepdims=True), fit.R.shape)
        out.append(Candidate("blur", f"every {word} its mean", f"each pixel the mean of its {word} (a mean taken over "
                             f"the wrong axis, the {across} where the samples' belongs): every {word} flat, the image "
                             f"smoothed along its {word}s", fit.model(M), 0, value={"mean_over": across},
                             change=M - fit.R))
    return out


def _one_line(fit: Fit) -> list[Candidate]:
    """Every row (column) one, where the hand-in's lines are all one to the last bit (no render's lines are equal by
    chance): the model repeats its own line (its noise repeated too), and the words name the render's line k it
    matches best. No candidate otherwise: a render's line repeated fits nothing else, and would stand as the closest
    cause of images nothing explains. Nor where that line is one colour too: an image of one colour (white where the
    codes overflowed, black where nothing was written) has every row and every column the same without any line
    repeated, and the model, the hand-in itself, would explain it whatever made it."""
    out = []
    for axis, word in ((0, "row"), (1, "column")):
        n = fit.R.shape[axis]
        own = np.take(fit.S, [0], axis=axis)
        if not np.array_equal(np.broadcast_to(own, fit.S.shape), fit.S) or np.all(own == own.flat[:3]):
            continue
        errs = [fit.model(np.repeat(np.take(fit.R, [k], axis=axis), n, axis=axis)) for k in range(n)]
        k = int(np.argmin(errs))
        M = np.repeat(own, n, axis=axis)
        out.append(Candidate("lines_aliased", f"every {word} one", f"every {word} the same, the render's {word} {k} "
                             f"repeated (one {word} list referenced {n} times, as [[0.0] * W] * H makes it, or an "
                             "index that never changes)", fit.model(M), 1, value={"lines": f"{word}s", "kept": k},
                             change=M - fit.R))
    return out


layout.name = "layout"
