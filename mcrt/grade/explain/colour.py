r"""The colours mixed by a 3x3 matrix: the channels reordered, colour lost to grey, a channel zeroed.

The model image is :math:`k\,M R` per pixel, M a 3x3 matrix and k a scale
fitted by weighted least squares (one parameter) within a factor :data:`GAIN`
of 1. M is one of the matrices a student's program applies by mistake
(:func:`common_matrices`): the channels in another order (BGR), one grey
value in every channel (luminance with the Rec. 709 or Rec. 601 weights, or
the mean), one channel copied to all, a channel written as 0, or a colour
space's conversion applied where none was due (the render taken for Adobe RGB,
Display P3 or Rec. 2020 and converted to sRGB, or the other way; XYZ written as
RGB, or converted from), negatives clipped to 0. Any other M is fitted per output channel
(nine parameters; each costs ln n like every fitted parameter) and worded by
its rows: a named M with one parameter wins wherever it fits as well; a
free M within :data:`NEAR` of one gain on every channel is none. In a
file clipped at 1 (an 8-bit image) the model is clipped as the file stores
it, and the clipped pixels set no parameter.
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.grade.feedback import num as _num

_RGB = ("red", "green", "blue")
#: A free matrix within this of one gain times the identity (every entry) mixes no colour: a white balance or a
#: change of primaries moves a channel by several hundredths, and a near-identity fit only bends itself to values a
#: curve or an encoding changed (dark codes a step off).
NEAR = 0.025

#: Linear RGB to CIE XYZ (D65) of each space's primaries (IEC 61966-2-1, Adobe RGB (1998), Display P3, ITU-R BT.2020).
TO_XYZ = {
    "sRGB": np.array([[0.4124564, 0.3575761, 0.1804375], [0.2126729, 0.7151522, 0.0721750],
                      [0.0193339, 0.1191920, 0.9503041]]),
    "Adobe RGB (1998)": np.array([[0.5767309, 0.1855540, 0.1881852], [0.2973769, 0.6273491, 0.0752741],
                                  [0.0270343, 0.0706872, 0.9911085]]),
    "Display P3": np.array([[0.4865709, 0.2656677, 0.1982173], [0.2289746, 0.6917385, 0.0792869],
                            [0.0, 0.0451134, 1.0439444]]),
    "Rec. 2020": np.array([[0.6369580, 0.1446169, 0.1688810], [0.2627002, 0.6779981, 0.0593017],
                           [0.0, 0.0280727, 1.0609851]]),
}


def conversions() -> dict[str, tuple[str, str, np.ndarray]]:
    """name -> (family, words, M): a colour space's conversion applied to the render where none was due."""
    srgb = TO_XYZ["sRGB"]
    out = {"XYZ written": ("colour_matrix", "the colours converted to CIE XYZ and written as RGB (XYZ for linear sRGB)",
                           srgb),
           "XYZ matrix on RGB": ("colour_matrix", "the XYZ-to-sRGB matrix applied to the render's RGB (the film taken "
                                 "for XYZ), negatives clipped to 0", np.linalg.inv(srgb))}
    for space, m in TO_XYZ.items():
        if space == "sRGB":
            continue
        out[f"{space} to sRGB"] = ("colour_matrix", f"the render taken for {space} and converted to linear sRGB (a "
                                   "colour-managed step's assumed profile), negatives clipped to 0",
                                   np.linalg.inv(srgb) @ m)
        out[f"sRGB to {space}"] = ("colour_matrix", f"the render converted from linear sRGB to {space}'s primaries "
                                   "and written as sRGB, negatives clipped to 0", np.linalg.inv(m) @ srgb)
    return out


def common_matrices() -> dict[str, tuple[str, str, np.ndarray]]:
    """name -> (family, words, M): the matrices of the module docstring."""
    out = {}
    for perm in ((0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)):
        order = "".join("RGB"[i] for i in perm)
        out[f"channels {order}"] = ("channels", f"the colour channels written in the order {order} instead of RGB",
                                    np.eye(3)[list(perm)])
    for key, w, how in (("Rec. 709", (0.2126, 0.7152, 0.0722), "luminance (Rec. 709 weights)"),
                        ("Rec. 601", (0.299, 0.587, 0.114), "luma (Rec. 601 weights)"),
                        ("mean", (1 / 3, 1 / 3, 1 / 3), "the mean of the three channels")):
        out[f"grey {key}"] = ("colour_lost", f"colour lost: {how} written to all three channels (a grey image)",
                              np.tile(np.asarray(w), (3, 1)))
    for c, name in enumerate(_RGB):
        one = np.zeros((3, 3))
        one[:, c] = 1.0
        # Under a white light, albedos taken as one number (their first, red, value) give this image exactly.
        out[f"grey {name}"] = ("colour_lost", f"colour lost: the {name} channel written to all three channels (or "
                               f"every colour taken as one number, its {name} value, for all three channels)", one)
        zero = np.eye(3)
        zero[c, c] = 0.0
        out[f"{name} zeroed"] = ("colour_lost", f"the {name} channel written as 0", zero)
    return out


#: Robust (capped) least-squares steps of every fit here, from k = 1 and M = I.
STEPS = 3
#: Largest factor (either way) of a matrix's scale, or of the free matrix's gain on white per channel: beyond it the
#: brightness is the mistake, not the colours (a nearly black image is any matrix times almost 0).
GAIN = 2.0


def stored_top(fit: Fit) -> float:
    """The largest value the hand-in's file could hold: 1 where it is clipped there (an 8-bit image: two or more
    pixels at exactly 1 in every channel, none above), else infinity."""
    S = np.where(fit.ok, fit.S, -np.inf)
    at_one = np.all(S == 1.0, axis=-1)
    return 1.0 if np.count_nonzero(at_one) >= 2 and float(S.max()) <= 1.0 else np.inf


def _used(fit: Fit, top: float, model) -> np.ndarray:
    """Weights of a capped least-squares step at the model ``model``; none on pixels clipped at ``top``."""
    return np.where(fit.ok & (fit.S < top), fit.irls(np.minimum(model, top) - fit.R), 0.0)


def _scaled(fit: Fit, model: np.ndarray, top: float) -> tuple[float, np.ndarray]:
    """The scale k of ``model`` that fits the hand-in in capped weighted least squares, and k * model as the file
    stores it (clipped at ``top``): a few clipped pixels (the light in an 8-bit image) do not set the scale."""
    k = 1.0
    for _ in range(STEPS):
        w = _used(fit, top, k * model)
        den = float(np.sum(model * model * w))
        k = float(np.sum(fit.S * model * w)) / den if den > 0 else 1.0
    return k, np.minimum(k * model, top)


def _free_matrix(fit: Fit, top: float) -> np.ndarray:
    """M fitted per output channel in capped weighted least squares on the pixels used (none clipped)."""
    R, S = fit.R.reshape(-1, 3), fit.S.reshape(-1, 3)
    M = np.eye(3)
    for _ in range(STEPS):
        w = _used(fit, top, fit.R @ M.T).reshape(-1, 3)
        for c in range(3):
            A = (R * w[:, c:c + 1]).T @ R
            if np.linalg.cond(A) > 1e12:
                return np.eye(3)
            M[c] = np.linalg.solve(A, (R * w[:, c:c + 1]).T @ np.where(w[:, c] > 0, S[:, c], 0.0))
    return M


def _terms(row: np.ndarray) -> str:
    """One row of a colour matrix in words: '0.08 R - 0.01 G + 0.93 B'."""
    out = ""
    for j, m in enumerate(row):
        sign = ("-" if m < 0 else "") if not out else (" - " if m < 0 else " + ")
        out += f"{sign}{_num(abs(float(m)))} {'RGB'[j]}"
    return out


def colour(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The common colour matrices, each with a fitted scale, and the best free 3x3 matrix."""
    R, top = fit.R, stored_top(fit)
    out = []
    for name, (family, words, M) in {**common_matrices(), **conversions()}.items():
        k, model = _scaled(fit, np.maximum(R @ M.T, 0.0), top)
        if not 1 / GAIN <= k <= GAIN:
            continue
        scale = f" (and scaled by {_num(k)})" if abs(k - 1.0) > 0.02 else ""
        out.append(Candidate(family, name, words + scale, fit.model(model), 1,
                             value={"matrix": name, "scale": k}, change=model - R))
    M = _free_matrix(fit, top)
    if not np.all((M.sum(axis=1) >= 1 / GAIN) & (M.sum(axis=1) <= GAIN)):
        return out
    if np.abs(M - np.mean(np.diag(M)) * np.eye(3)).max() < NEAR:
        return out  # one gain on every channel, give or take a few thousandths: no colour changed
    model = np.minimum(R @ M.T, top)
    rows = "; ".join(f"{_RGB[c]} = " + _terms(M[c]) for c in range(3))
    out.append(Candidate("colour_matrix", "colour matrix", f"the colours mixed by a 3x3 matrix ({rows}): a change of colour "
                         "space or primaries, a white balance or chromatic adaptation, or a saturation change after "
                         "rendering",
                         fit.model(model), 9, value={"matrix": M.round(4).tolist()}, change=model - R))
    return out


colour.name = "colour"
