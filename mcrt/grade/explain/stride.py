r"""The film's samples read back with another memory layout than they were written with: a pitch, a pixel's size or
a row's length taken wrongly.

A program's film is one flat run of samples; a writer, a copy or a reader
walks it with a row pitch and a pixel size of its own. Where one of them
is wrong the image is the render's samples at other places, and which
places is plain arithmetic. Three ways:

* *Read with the wrong layout* (:func:`gathered`): the hand-in's sample
  (y, x, c) is element :math:`y P_d + 3 x + c` of the source, whose rows
  hold W pixels of :math:`C_s` samples each (3, or 4 with an alpha of 1 or a
  padding of 0 after every pixel: an RGBA or vec4 film) and are :math:`P_s`
  samples apart (packed, or padded to an alignment, as a pitched GPU
  allocation is); elements past its end were never written (0). The reader's
  pitch :math:`P_d` is the packed 3 W, or W (a stride given in pixels where
  samples or bytes are asked for).
* *Walked in another order*: a column-major H x W x 3 array (MATLAB's,
  Fortran's, R's, Julia's) written as it lies in memory, down each column
  and every red first, where the format wants interleaved rows
  (:func:`column_major`; no parameter).
* *Written to the wrong places* (:func:`scattered`): pixel (x, y) stored at
  pixel :math:`y (W \pm 1) + x` (a row's length off by one in the index),
  later rows overwriting earlier ones where they meet, the places no row
  reaches never written (0).

Each gather or scatter is one choice among a few dozen, one parameter.
Every candidate is flexible (:attr:`~mcrt.grade.candidates.Candidate.flexible`):
a layout whose zeros (padding, an alpha of 0, places never written) darken
the image takes up a share of any image darker than the render, so it is
claimed where it leaves noise and nothing else does, and never leads a
partial reading nor stands as the closest cause.
In an 8-bit file the samples were clipped at 1 before they were moved
(the light's pixels hold 1), so the model moves the clipped render.
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit

#: Alignments (in samples) a row may be padded to: a pitched allocation's 128 to 1024 bytes of 4-byte floats, or 32
#: to 256 of 8-bit codes.
ALIGNMENTS = (32, 64, 128, 256)


def source_stream(R: np.ndarray, *, channels: int, pad: float, pitch: int) -> np.ndarray:
    """R (H, W, 3) as a flat run of samples: each pixel ``channels`` samples (the fourth ``pad``), each row ``pitch``
    samples (zeros after the pixels)."""
    h, w, _ = R.shape
    px = R if channels == 3 else np.concatenate([R, np.full((h, w, 1), pad)], axis=2)
    rows = np.zeros((h, pitch))
    rows[:, : w * channels] = px.reshape(h, w * channels)
    return rows.reshape(-1)


def gathered(R: np.ndarray, *, channels: int, pad: float, pitch: int, read_pitch: int) -> np.ndarray:
    """The image read from R's stream (:func:`source_stream`) as rows ``read_pitch`` samples apart, 3 samples a pixel;
    past the stream's end, 0."""
    h, w, _ = R.shape
    src = source_stream(R, channels=channels, pad=pad, pitch=pitch)
    idx = np.arange(h)[:, None, None] * read_pitch + 3 * np.arange(w)[None, :, None] + np.arange(3)[None, None, :]
    return np.where(idx < src.size, src[np.minimum(idx, src.size - 1)], 0.0)


def column_major(R: np.ndarray) -> np.ndarray:
    """R's samples in column-major order (down each column, every red, then every green, then every blue), read back
    as interleaved rows."""
    h, w, c = R.shape
    return np.ravel(R, order="F").reshape(h, w, c)


def scattered(R: np.ndarray, *, row_length: int) -> np.ndarray:
    """R's pixel (x, y) stored at pixel y * row_length + x of an H x W film, rows in order (a later row overwrites),
    places past the film's end dropped, places never reached 0."""
    h, w, _ = R.shape
    flat = np.zeros((h * w, 3))
    for y in range(h):
        start = y * row_length
        n = max(0, min(w, h * w - start))
        flat[start:start + n] = R[y, :n]
    return flat.reshape(h, w, 3)


def layouts(w: int) -> list[tuple[dict, str]]:
    """Every gather layout this family tries (keyword arguments of :func:`gathered`) with its words; the right one,
    packed RGB read as packed RGB, left out."""
    out = []
    for channels, pad, stored in ((3, 0.0, ""),
                                  (4, 1.0, "each pixel stored as 4 samples (an RGBA or vec4 film, alpha 1) and read "
                                           "as 3"),
                                  (4, 0.0, "each pixel stored as 4 samples (a vec4 or float4 film, the fourth 0) and "
                                           "read as 3")):
        packed = channels * w
        for pitch in sorted({packed} | {-(-packed // a) * a for a in ALIGNMENTS}):
            for read_pitch in (3 * w, w):
                if channels == 3 and pitch == packed and read_pitch == 3 * w:
                    continue  # the right layout
                parts = [stored] if stored else []
                if pitch != packed:
                    parts.append(f"each row padded to {pitch} samples ({pitch - packed} after its {packed}, never "
                                 "written, as a pitched GPU allocation is) and read as if the rows were packed")
                if read_pitch == w:
                    parts.append(f"rows read {w} samples apart where they lie {pitch} apart (a row stride given in "
                                 "pixels where samples or bytes are asked for)")
                out.append(({"channels": channels, "pad": pad, "pitch": pitch, "read_pitch": read_pitch},
                            "the film read back with another memory layout than it was written with: "
                            + "; ".join(parts)))
    return out


def stride(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The best gather layout, the column-major order and the best scatter (the module docstring)."""
    h, w, _ = fit.R.shape
    # A file that holds no value above 1 clipped them before they were moved (the light's pixels at 1).
    R = np.minimum(fit.R, 1.0) if float(np.max(fit.S)) <= 1.0 else fit.R
    out = []
    err, (kw, words), M = _best(fit, (((kw, words), gathered(R, **kw)) for kw, words in layouts(w)))
    out.append(Candidate("stride", "samples read with another layout", words, err, 1,
                         value=dict(kw), change=M - fit.R, flexible=True))
    M = column_major(R)
    out.append(Candidate("stride", "column-major", "the image's samples written in column-major order (down each "
                         "column, every red, then every green, then every blue: a MATLAB, Fortran, R or Julia array "
                         "written as it lies in memory, its dimensions never permuted) where the format wants "
                         "interleaved rows", fit.model(M), 0, value="column-major", change=M - fit.R,
                         flexible=True))
    err, n, M = _best(fit, ((n, scattered(R, row_length=n)) for n in (w - 1, w + 1)))
    out.append(Candidate("stride", "pixels written with another row length",
                         f"pixel (x, y) written at y * {n} + x, the row's length taken as {n} where it is {w}: each "
                         f"row shifted {'left' if n < w else 'right'} by one pixel more than the row above, "
                         + (f"the film's last {h - 1} pixels never written (black)" if n < w else
                            "the pixels that run past the film's end dropped"),
                         err, 1, value={"row_length": n, "width": w}, change=M - fit.R, flexible=True))
    return out


def _best(fit: Fit, models):
    """(chi^2, label, model image) of the (label, model image) pairs' best fit."""
    return min(((fit.model(M), label, M) for label, M in models), key=lambda t: t[0])


stride.name = "stride"
