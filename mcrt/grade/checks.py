"""Checks before scoring: can the file be read, and is it the image that was asked for?

Each function looks at one way a hand-in goes wrong before any physics is
judged, and returns what it found with a message a student can act on.
Where a mistake can be undone exactly (a flip, the other camera, a gamma
curve, a constant exposure factor, a resolution that is an integer multiple)
it is detected and undone, so that the rest of the grading still says
whether the tracer itself is right; the check's own points are lost.
Nothing here raises on bad student data.
"""

from __future__ import annotations

import itertools
import os
import stat
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy import stats as _sps

from mcrt.grade.score import LUMINANCE
from mcrt.image_files import ImageError, read_image, srgb_eotf, srgb_oetf
from mcrt.stats.tiles import block_means, tile_sums

MAX_FILE_BYTES = 1 << 30


# --------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------


@dataclass
class Loaded:
    """The renders of one hand-in at their own resolution (float64, (H, W, 3))."""

    images: list[np.ndarray]
    files: list[str]  # as shown to the student: valid UTF-8 (a byte that is not becomes U+FFFD)
    fmt: str  # float, half, rgbe, png8, png16 (+ '-linear' for PNGs declared linear)
    spp_file: int | None = None  # from our EXR attributes
    camera_file: str | None = None
    notes: list[str] = field(default_factory=list)


def _shown(text: str) -> str:
    """``text`` as valid UTF-8: surrogate-escaped bytes of a file name become U+FFFD."""
    return str(text).encode("utf-8", "surrogateescape").decode("utf-8", "replace")


def _short(msg: str, path: str) -> str:
    """An ImageError message with the file's folder removed (students see their file name), valid UTF-8."""
    return _shown(msg.replace(os.fspath(path), Path(path).name))


def _format(path: str, img: np.ndarray, linear_png: bool, extra: dict | None = None) -> str:
    """The quantisation of the file: float, half, rgbe, png8 or png16 (+ '-linear').

    8- and 16-bit display formats other than PNG (PPM, BMP, TGA) quantise
    like a PNG of the same depth, so they get the same names (the noise
    model, clipping and encoding checks treat them alike).
    """
    ext = Path(path).suffix.lower()
    bits = (extra or {}).get("file.bits")
    if bits in ("8", "16"):
        return f"png{bits}" + ("-linear" if linear_png else "")
    if ext == ".exr":
        finite = np.isfinite(img)
        x = img[finite]
        return "half" if x.size and np.array_equal(x.astype(np.float16).astype(np.float32), x) else "float"
    if ext == ".pfm":
        return "float"
    if ext in (".hdr", ".pic", ".rgbe"):
        return "rgbe"
    if ext == ".png":
        try:
            with open(path, "rb") as f:
                head = f.read(25)
            depth = head[24] if len(head) >= 25 else 8
        except OSError:
            depth = 8
        return ("png16" if depth == 16 else "png8") + ("-linear" if linear_png else "")
    return "float"


def _read_one(p: str, linear_png: bool):
    """(the render, None) or (None, why the file cannot be used)."""
    name = _shown(Path(p).name)
    try:
        st = os.lstat(p)
    except OSError as e:
        return None, f"{name}: cannot read ({_shown(e.strerror or e)})"
    if not stat.S_ISREG(st.st_mode):  # links and special files are never followed or opened
        kind = "a symbolic link" if stat.S_ISLNK(st.st_mode) else "a FIFO (named pipe)" if stat.S_ISFIFO(st.st_mode) \
            else "a folder" if stat.S_ISDIR(st.st_mode) else "a special file"
        return None, f"{name}: is {kind}, not a regular file; hand in the image file itself"
    size = st.st_size
    if size > MAX_FILE_BYTES:
        return None, f"{name}: {size / 2**20:.0f} MiB is larger than the {MAX_FILE_BYTES >> 20} MiB limit"
    if size == 0:
        return None, f"{name}: the file is empty"
    try:
        if _shown(p) != p:  # a name that is not UTF-8: some decoders cannot open it, so read a copy
            return _read_copy(p, name, linear_png)
        return read_image(p, linear_png=linear_png), None
    except ImageError as e:
        return None, _short(str(e), p)
    except (OSError, ValueError, MemoryError, RecursionError) as e:
        return None, f"{name}: cannot be read ({_shown(' '.join(str(e).split())[:160])})"


def _read_copy(p: str, name: str, linear_png: bool):
    """Read a file whose name is not valid UTF-8 through a copy with a plain name (same extension); messages name the original."""
    import shutil
    import tempfile

    ext = "".join(ch for ch in Path(_shown(p)).suffix if ch.isascii() and (ch.isalnum() or ch == "."))
    with tempfile.TemporaryDirectory(prefix="mcrt-grade-") as d:
        tmp = os.path.join(d, "render" + ext)
        with open(p, "rb") as src, open(tmp, "wb") as dst:
            shutil.copyfileobj(src, dst)
        try:
            return read_image(tmp, linear_png=linear_png), None
        except ImageError as e:
            return None, _shown(str(e).replace(tmp, name))


def read_renders(paths: list[str], linear_png: bool) -> tuple[Loaded | None, str | None]:
    """Read one or two renders; (None, message) when the first cannot be used."""
    images, files, notes = [], [], []
    fmt, spp, cam = "float", None, None
    for k, p in enumerate(paths[:2]):
        name = Path(p).name
        r, msg = _read_one(p, linear_png)
        if msg is not None:
            if k == 0:
                return None, msg
            notes.append(f"second render {msg}; graded the first alone")
            continue
        img = np.asarray(r.mean, dtype=np.float64)
        if k == 0:
            fmt = _format(p, r.mean, linear_png, r.extra)
            if r.spp < 0:
                notes.append(f"{_shown(name)}: the file's spp attribute must be a positive integer, got {r.spp}; ignored")
            spp = r.spp if r.spp > 0 else None
            cam = r.camera or None
        elif img.shape != images[0].shape:
            notes.append(f"second render {name} is {img.shape[1]}x{img.shape[0]}, the first "
                         f"{images[0].shape[1]}x{images[0].shape[0]}; graded the first alone")
            continue
        # A second render identical to the first (one seed) is kept: the noise stage names it and grades the
        # first alone (mcrt.grade.stages.noise.same_pair).
        images.append(img)
        files.append(_shown(p))
    return Loaded(images, files, fmt, spp, cam, notes), None


# --------------------------------------------------------------------------
# Resolution
# --------------------------------------------------------------------------


@dataclass
class ResolutionPlan:
    ok: bool  # the asked-for resolution
    gradeable: bool
    down: int = 1  # box-filter the hand-in by this factor
    coarsen: int = 1  # box-filter the expected images by this factor
    message: str = ""


def plan_resolution(h: int, w: int, height: int, width: int, gh: int, gw: int) -> ResolutionPlan:
    """How an image of (h, w) pixels is compared at the grade resolution (gh, gw)."""
    if (h, w) == (height, width):
        return ResolutionPlan(True, True, height // gh, 1, f"{w}x{h} as asked")
    asked = f"the assignment asks for {width}x{height}"
    if h % gh == 0 and w % gw == 0 and h // gh == w // gw:
        k = h // gh
        return ResolutionPlan(False, True, k, 1, f"the image is {w}x{h}, {asked}; it was box-filtered to "
                              f"{gw}x{gh} for grading, which is exact for a box pixel filter")
    if gh % h == 0 and gw % w == 0 and gh // h == gw // w:
        k = gh // h
        return ResolutionPlan(False, True, 1, k, f"the image is {w}x{h}, {asked}; it was graded at {w}x{h} against "
                              f"the reference box-filtered by {k}")
    if (h, w) == (width, height):
        return ResolutionPlan(False, False, message=f"the image is {w}x{h}, {asked}: width and height are swapped")
    return ResolutionPlan(False, False, message=f"the image is {w}x{h}, {asked}; it cannot be compared "
                          "(not an integer multiple or divisor of the grading resolution)")


def box_down(x: np.ndarray, k: int) -> np.ndarray:
    """Block means over k x k (NaN or inf in a block makes the block non-finite)."""
    with np.errstate(invalid="ignore", over="ignore"):
        return block_means(x, k)


# --------------------------------------------------------------------------
# Values
# --------------------------------------------------------------------------


def _where(idx) -> str:
    return f"row {int(idx[0])}, column {int(idx[1])}"


def check_finite(img: np.ndarray) -> tuple[int, float, str]:
    """(count of pixels with a NaN or infinite channel, their share, a message)."""
    bad = ~np.isfinite(img).all(axis=2)
    n = int(np.count_nonzero(bad))
    if not n:
        return 0, 0.0, "every value is finite"
    frac = n / bad.size
    nan = int(np.count_nonzero(np.isnan(img).any(axis=2)))
    first = np.argwhere(bad)[0]
    kinds = "NaN" if nan == n else "infinite" if nan == 0 else "NaN or infinite"
    share = "all" if n == bad.size else f"{100 * frac:.2g} %" if frac < 0.1 else f"{100 * frac:.0f} %"
    return n, frac, (f"{n} pixels ({share}) are {kinds}, the first at {_where(first)}; typical causes: "
                     "0/0 in a pdf, sqrt or acos of a value just outside its domain, normalising a zero vector")


def check_negative(img: np.ndarray, tolerance: float) -> tuple[int, str]:
    """(count of values below -tolerance, message)."""
    x = np.where(np.isfinite(img), img, 0.0)
    neg = x < -tolerance
    n = int(np.count_nonzero(neg))
    if not n:
        return 0, "no negative values"
    i = np.unravel_index(int(np.argmin(x)), x.shape)
    return n, (f"{n} values are negative (the smallest, {x[i]:.4g}, at {_where(i)}); radiance cannot be negative: "
               "look for a cosine that is not clamped at 0 or a direction sampled below the surface")


# --------------------------------------------------------------------------
# Orientation and camera
# --------------------------------------------------------------------------

# name -> (applied to the reference, undoes it on the submission); all square-only ones last.
TRANSFORMS = {
    "identity": (lambda x: x, lambda x: x),
    "flipped vertically (upside down)": (lambda x: x[::-1], lambda x: x[::-1]),
    "mirrored horizontally (left and right swapped)": (lambda x: x[:, ::-1], lambda x: x[:, ::-1]),
    "rotated by 180 degrees": (lambda x: x[::-1, ::-1], lambda x: x[::-1, ::-1]),
    "transposed (rows and columns swapped)": (lambda x: x.swapaxes(0, 1), lambda x: x.swapaxes(0, 1)),
    "rotated 90 degrees clockwise": (lambda x: np.rot90(x, -1), lambda x: np.rot90(x, 1)),
    "rotated 90 degrees counter-clockwise": (lambda x: np.rot90(x, 1), lambda x: np.rot90(x, -1)),
    "transposed across the anti-diagonal": (lambda x: x[::-1, ::-1].swapaxes(0, 1), lambda x: x[::-1, ::-1].swapaxes(0, 1)),
}
SQUARE_ONLY = 4  # the first four work for any shape


@dataclass
class Orientation:
    camera: str
    transform: str
    correlations: dict  # "camera/transform" -> (luminance, chromaticity) rank correlations
    resembles: bool  # the best luminance correlation is high enough to say anything
    edges: dict = field(default_factory=dict)  # "camera/transform" -> rank correlation of the edges' strength


def _ranks(x: np.ndarray) -> np.ndarray:
    r = _sps.rankdata(x.ravel()).reshape(x.shape)
    return (r - r.mean()) / max(r.std(), 1e-12)


def _features(img: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Ranks of luminance and of two chromaticities (r and g over r + g + b)."""
    x = np.maximum(np.nan_to_num(img, nan=0.0, posinf=0.0, neginf=0.0), 0.0)
    s = x.sum(axis=2) + 1e-6 * max(float(x.mean()), 1e-12)
    return _ranks(x @ LUMINANCE), _ranks(x[..., 0] / s), _ranks(x[..., 1] / s)


#: Luminance rank correlation with a view that an image must reach for its flip, rotation or camera to be claimed: a
#: correct render reaches about 0.98, and a tone curve or a colour mistake keeps the ranks of luminance.
RESEMBLES = 0.8


#: How much lower than as handed in a candidate's edge correlation may be (noise moves it by about a hundredth).
EDGE_SLACK = 0.02


def _edges(lum_ranks: np.ndarray) -> np.ndarray:
    """Ranks of the gradient's length of the luminance's ranks: where the edges are, whatever the colours (0 for an
    image of one row or column, which has none)."""
    if min(lum_ranks.shape) < 2:
        return np.zeros_like(lum_ranks)
    gy, gx = np.gradient(lum_ranks)
    return _ranks(np.hypot(gx, gy))


def resemblance(img: np.ndarray, ref: np.ndarray) -> float:
    """Luminance rank correlation (Spearman) of an image with a reference of its shape."""
    return float(np.mean(_features(img)[0] * _features(ref)[0]))


def detect_orientation(img: np.ndarray, refs: dict[str, np.ndarray], camera: str, margin: float) -> Orientation:
    """Which camera, and which flip or rotation of it, the image shows.

    Two rank correlations (Spearman) with every candidate (each camera's
    reference under each flip, rotation or transposition): of luminance, and
    of chromaticity (the mean over r/(r+g+b) and g/(r+g+b)). Ranks are blind
    to exposure and to any monotone tone curve, so the other checks do not
    disturb this one. Luminance sees the light at the top and the objects at
    the bottom; chromaticity sees which coloured wall is where, and does not
    change when a bug moves brightness around (a BRDF pi times too bright
    makes the floor brighter than the ceiling, which luminance alone takes
    for an upside-down image). Both change when surfaces' colours are given to
    the wrong surfaces: the walls' colours permuted can make a mirrored view
    the closer in luminance and in colour. Where the edges are (the ranks of
    the gradient's length of the luminance's ranks) does not depend on the
    colours: the objects' outlines, which no flip of the room keeps in place.
    A candidate replaces (assigned camera, as
    handed in) only when its luminance correlation is higher by ``margin``,
    its chromaticity correlation is not lower, its edges' correlation is not
    lower by more than :data:`EDGE_SLACK`, and its luminance correlation
    reaches :data:`RESEMBLES`; the best such candidate (sum of the first two) wins.
    Each candidate is compared with the image's channels in the order that
    matches it best (channels written in another order are a colour
    mistake, which the explanation names; they must not read as a flip).
    An image that resembles no view that well (a file read with the wrong
    layout, noise) keeps the assigned camera as handed in: a flip that
    raises a correlation from 0.2 to 0.4 is no evidence of a flip.
    """
    # The image's channels in each order: channels written in another order change which wall is bright, and a
    # mirrored view can then match the luminance better than the view itself; each candidate is judged with the
    # order that suits it best.
    feats = [_features(img[..., list(order)]) for order in itertools.permutations(range(3))]
    square = img.shape[0] == img.shape[1]
    names = list(TRANSFORMS)[: len(TRANSFORMS) if square else SQUARE_ONLY]
    lum, chroma, edge = {}, {}, {}
    img_edges = _edges(feats[0][0])  # the channels' order does not move the edges
    for cam, ref in refs.items():
        rl, rr, rg = _features(ref)
        re = _edges(rl)
        for name in names:
            t = TRANSFORMS[name][0]
            tl, tr, tg = t(rl), t(rr), t(rg)
            fl, fr, fg = max(feats, key=lambda f: float(np.mean(f[0] * tl)))
            lum[(cam, name)] = float(np.mean(fl * tl))
            chroma[(cam, name)] = 0.5 * float(np.mean(fr * tr) + np.mean(fg * tg))
            edge[(cam, name)] = float(np.mean(img_edges * t(re)))
    ident = (camera, "identity")
    table = {f"{c}/{t}": (round(lum[(c, t)], 4), round(chroma[(c, t)], 4)) for (c, t) in lum}
    edges = {f"{c}/{t}": round(v, 4) for (c, t), v in edge.items()}
    eligible = [k for k in lum if k != ident and lum[k] >= lum[ident] + margin and chroma[k] >= chroma[ident]
                and edge[k] >= edge[ident] - EDGE_SLACK and lum[k] >= RESEMBLES]
    if eligible:
        best = max(eligible, key=lambda k: lum[k] + chroma[k])
        return Orientation(best[0], best[1], table, True, edges)
    return Orientation(camera, "identity", table, max(lum.values()) > 0.3, edges)


# --------------------------------------------------------------------------
# Encoding and exposure
# --------------------------------------------------------------------------


#: name -> (decoder applied to the submission, description)
ENCODINGS = {
    "linear": (lambda x: x, "linear"),
    "srgb": (srgb_eotf, "sRGB-encoded"),
    "gamma2.2": (lambda x: np.maximum(x, 0.0) ** 2.2, "gamma-encoded (x^(1/2.2))"),
}


def _log_ratios(img: np.ndarray, ref: np.ndarray, mask: np.ndarray, tile: int) -> np.ndarray:
    m = mask.astype(np.float64)
    n = tile_sums(m, tile)
    with np.errstate(invalid="ignore", divide="ignore"):
        s = tile_sums(np.where(mask, np.nan_to_num(img @ LUMINANCE), 0.0), tile) / np.maximum(n, 1)
        r = tile_sums(np.where(mask, ref @ LUMINANCE, 0.0), tile) / np.maximum(n, 1)
        ok = (n >= 2) & (r > 1e-3 * max(float(r.max()), 1e-12)) & (s > 0)
        return np.log(s[ok] / r[ok])


def _spread(lr: np.ndarray) -> float:
    if lr.size < 3:
        return float("inf")
    return float(np.median(np.abs(lr - np.median(lr))))


@dataclass
class Encoding:
    kind: str  # key of ENCODINGS
    spreads: dict
    message: str


#: A decoding is the file's encoding only where it leaves at most this share of the linear reading's spread: decoding
#: an encoded render leaves its noise alone (a tenth or less of the spread at 16 spp or more), while every albedo
#: brightened by a gamma, which brightens the dark surfaces most as an encoding does, keeps about half of it.
DECODED_SPREAD = 0.25


def detect_encoding(img: np.ndarray, ref: np.ndarray, mask: np.ndarray, fmt: str, tile: int) -> Encoding:
    """Linear, or gamma-encoded data given as linear? (HDR files; display images: :func:`detect_png_curve`.)

    For each hypothesis the image is decoded and its tile luminances compared
    with the reference's in log space; the spread (median absolute deviation
    of the log ratios) is small for the right decoding, whatever the
    exposure. Another decoding wins only if it cuts the spread to
    :data:`DECODED_SPREAD` of the linear reading's and brings it below 0.15
    (15 %).
    """
    spreads = {k: _spread(_log_ratios(ENCODINGS[k][0](img), ref, mask, tile)) for k in ENCODINGS}
    best = min(spreads, key=spreads.get)
    lin = spreads["linear"]
    if best != "linear" and spreads[best] < DECODED_SPREAD * lin and spreads[best] < 0.15:
        msg = (f"the values look {ENCODINGS[best][1]}: decoded, they follow the reference's brightness "
               f"(spread {100 * spreads[best]:.0f} % instead of {100 * lin:.0f} %); HDR files (EXR, PFM, HDR) must "
               "hold linear radiance: write the values before any gamma or sRGB encoding")
        return Encoding(best, spreads, msg)
    return Encoding("linear", spreads, "linear radiance")


def estimate_scale(img: np.ndarray, ref: np.ndarray, mask: np.ndarray, tile: int) -> float:
    """Overall brightness ratio image / reference: median over tiles of the luminance ratio."""
    lr = _log_ratios(img, ref, mask, tile)
    return float(np.exp(np.median(lr))) if lr.size else 1.0


def nice_scale(k: float) -> float:
    """k snapped to a power of two when within 0.1 stops of one (an exposure setting), else k."""
    if not np.isfinite(k) or k <= 0:
        return 1.0
    e = np.log2(k)
    return float(2.0 ** round(e)) if abs(e - round(e)) < 0.1 else float(k)


# --------------------------------------------------------------------------
# Display images (PNG and the other 8/16-bit formats): which transfer curve
# --------------------------------------------------------------------------

#: curve -> (code value in [0, 1] -> linear radiance, how the feedback names it)
PNG_CURVES = {
    "srgb": (srgb_eotf, "the sRGB curve"),
    "gamma2.2": (lambda c: c**2.2, "a gamma of 2.2 (x^(1/2.2))"),
    "gamma2": (lambda c: c * c, "a gamma of 2 (a square root)"),
    # sRGB's exponent without its linear segment and offset (x^(1/2.4)), as a program that copies the exponent alone.
    "gamma2.4": (lambda c: c**2.4, "a gamma of 2.4 (x^(1/2.4): the sRGB curve's exponent without its linear segment "
                 "and offset)"),
    "linear": (lambda c: c, "no curve (linear values)"),
    # The gamma applied the wrong way round (x^2.2 for x^(1/2.2)), as a program that raises to the display's gamma.
    "inverted2.2": (lambda c: c ** (1 / 2.2), "the gamma applied the wrong way round (x^2.2 where x^(1/2.2) "
                    "belongs: the image darkened where the curve should brighten it)"),
}


def png_codes(img: np.ndarray, fmt: str) -> np.ndarray:
    """The code values (in [0, 1]) a display image was read from, undoing the decoding the reader applied."""
    levels = 65535.0 if fmt.startswith("png16") else 255.0
    x = np.clip(np.nan_to_num(img, nan=0.0), 0.0, 1.0)
    c = x if fmt.endswith("linear") else srgb_oetf(x)
    return np.round(c * levels) / levels


def curve_quantisation_variance(codes: np.ndarray, curve: str, fmt: str) -> np.ndarray:
    """Per-pixel variance q^2/12 of the rounding to code values, q the step of ``curve`` at each code (linear units)."""
    levels = 65535.0 if fmt.startswith("png16") else 255.0
    dec = PNG_CURVES[curve][0]
    q = dec(np.minimum(codes + 0.5 / levels, 1.0)) - dec(np.maximum(codes - 0.5 / levels, 0.0))
    return q * q / 12.0


EXPOSURE_SCALE = 0.1  # ln k: an exposure factor of 10 % costs as much as a tile mean one sd off

@dataclass
class PngEncoding:
    curve: str  # key of PNG_CURVES
    declared: str  # "srgb" (the reader's default) or "linear" (the manifest says so)
    chi2: dict  # curve -> weighted squared mismatch of the tile means


def detect_png_curve(candidates: dict[str, np.ndarray], ref: np.ndarray, mask: np.ndarray, tile: int,
                     declared: str) -> PngEncoding:
    r"""Which transfer curve a display image was written with, from its decodings at the grade resolution.

    For each curve's decoding S (box-filtered after decoding: the curve
    applies per hand-in pixel), the tile means s_t are compared with the
    reference's r_t allowing an overall factor k (exposure is judged
    elsewhere):

    .. math::

        \chi^2 = \sum_t \frac{(s_t - k r_t)^2}{S^2_t / n_t + (10^{-3} r_t)^2}
                  + N \Big(\frac{\ln k}{0.1}\Big)^2,

    with k fitted by least squares, S_t^2 the spread of the decoded pixels
    about k r within the tile (the noise, whatever its source) and N the
    number of tile means. The last term makes a curve that needs an exposure
    factor lose to one that does not: between sRGB and a square root the
    difference is mostly such a factor (about 0.83), and only the dark tiles
    tell the shapes apart. Another curve replaces the declared one only when
    it lowers chi^2 to 80 % of the declared curve's and by more than 25.
    """
    m = mask.astype(np.float64)[..., None]
    n = tile_sums(mask.astype(np.float64), tile)[..., None]
    safe = np.maximum(n, 1.0)
    r_t = tile_sums(np.where(m > 0, ref, 0.0), tile) / safe
    chi2 = {}
    for name, img in candidates.items():
        x = np.where(m > 0, np.nan_to_num(img), 0.0)
        s_t = tile_sums(x, tile) / safe
        ok = (n >= 4) & (r_t > 0)
        k = float(np.sum(s_t[ok] * r_t[ok]) / max(np.sum(r_t[ok] ** 2), 1e-300)) if ok.any() else 1.0
        dev = np.where(m > 0, x - k * ref, 0.0)
        d_t = tile_sums(dev, tile) / safe
        s2 = np.maximum(tile_sums(dev * dev, tile) - safe * d_t**2, 0.0) / np.maximum(n - 1, 1)
        v = s2 / safe + (1e-3 * r_t) ** 2
        fit = float(np.sum(((s_t - k * r_t) ** 2 / np.maximum(v, 1e-300))[ok])) if ok.any() else 0.0
        chi2[name] = fit + int(np.count_nonzero(ok)) * (np.log(max(k, 1e-12)) / EXPOSURE_SCALE) ** 2
    best = min(chi2, key=chi2.get)
    c0 = chi2.get(declared, np.inf)
    if best != declared and chi2[best] < 0.8 * c0 and c0 - chi2[best] > 25.0:
        return PngEncoding(best, declared, chi2)
    return PngEncoding(declared, declared, chi2)
