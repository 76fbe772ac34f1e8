"""Where an image differs, in the words a student sees: surfaces, direct or indirect light, catalogue texts.

Regions are described by the surfaces the camera sees there (the walls by
their colour, the floor, the ceiling, the sphere...) and by the share of
direct light, so that the words match what a student sees in the image.
"""

from __future__ import annotations

import numpy as np

from mcrt.stats import LUMINANCE_WEIGHTS
from mcrt.stats.tiles import tile_box, tile_sums

LUMINANCE = np.asarray(LUMINANCE_WEIGHTS)  # as an array, for ``rgb @ LUMINANCE``

_PROPER = ("Russian", "Lambertian", "Monte")


def short_text(text: str) -> str:
    """The first clause of a catalogue entry, to follow 'consistent with': 'Russian roulette without dividing by
    the survival probability', 'next-event estimation without the cosine at the light'."""
    s = text.split(": ")[0].split(". ")[0].rstrip(".")
    if len(s) > 1 and s[1].islower() and not s.startswith(_PROPER):
        s = s[0].lower() + s[1:]
    return s


def tile_means(x: np.ndarray, mask: np.ndarray, tile: int) -> np.ndarray:
    """Means of an (H, W, 3) array over the valid pixels (``mask``) of each tile (0 where a tile has none)."""
    return tile_sums(np.where(mask[..., None], x, 0.0), tile) / valid_counts(mask, tile)


def valid_counts(mask: np.ndarray, tile: int) -> np.ndarray:
    """Valid pixels per tile, at least 1, shape (tiles_y, tiles_x, 1)."""
    return np.maximum(tile_sums(mask.astype(np.float64), tile), 1.0)[..., None]



def rel_lum(d: np.ndarray, ref_t: np.ndarray) -> np.ndarray:
    """Relative luminance difference d / |ref| per tile (0 where the reference is black)."""
    dl, rl = d @ LUMINANCE, ref_t @ LUMINANCE
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.abs(rl) > 1e-12, dl / np.abs(rl), 0.0)


def _join(items: list[str]) -> str:
    if len(items) <= 1:
        return "".join(items)
    return ", ".join(items[:-1]) + " and " + items[-1]


def describe_tiles(rel: np.ndarray, chosen: np.ndarray, shape: tuple[int, int], tile: int, labels: np.ndarray,
                   names: tuple[str, ...], direct: np.ndarray) -> str:
    """Words for the tiles marked in ``chosen`` (tiles_y, tiles_x), with signed relative effects ``rel``.

    For example: 'too dark (about -38 %) on the floor, wall AB (red) and the ceiling, where
    indirect light dominates (70 % of the light there is indirect); too bright
    (about +12 %) on the mirror sphere'.
    """
    h, w = shape
    parts = []
    for sign, word in ((-1, "too dark"), (1, "too bright")):
        sel = chosen & (np.sign(rel) == sign)
        if not sel.any():
            continue
        weights = np.zeros(len(names))
        eff, npx, dsum, wsum = 0.0, 0, 0.0, 0.0
        for ty, tx in zip(*np.nonzero(sel)):
            y0, y1, x0, x1 = tile_box(h, w, tile, int(ty), int(tx))
            lab = labels[y0:y1, x0:x1].ravel()
            a = abs(float(rel[ty, tx]))
            np.add.at(weights, lab, a)
            eff += float(rel[ty, tx]) * lab.size
            npx += lab.size
            dsum += a * float(direct[y0:y1, x0:x1].sum())
            wsum += a * lab.size
        order = np.argsort(-weights)
        total = weights.sum()
        where = [names[i] for i in order[:3] if weights[i] >= 0.15 * total and names[i] != "nothing"]
        if not where:
            where = [names[order[0]]]
        pct = 100 * eff / max(npx, 1)
        text = f"{word} (about {pct:+.{0 if abs(pct) >= 10 else 1}f} %) on {_join(where)}"
        share = dsum / wsum if wsum > 0 else 1.0
        if share < 0.45:
            text += f", where indirect light dominates ({100 * (1 - share):.0f} % of the light there is indirect)"
        elif share > 0.8:
            text += ", where direct light dominates"
        parts.append(text)
    return "; ".join(parts)


def signature_region(rel: np.ndarray, shape, tile, labels, names, direct, min_effect: float) -> str:
    """Where a bug's expected signature (relative luminance per tile) is strong."""
    mx = float(np.max(np.abs(rel))) if rel.size else 0.0
    if mx < min_effect:
        return "no visible change at this resolution"
    chosen = np.abs(rel) >= max(0.3 * mx, min_effect)
    return describe_tiles(rel, chosen, shape, tile, labels, names, direct)


def change_region(delta: np.ndarray, ref: np.ndarray, mask: np.ndarray, tile: int, labels, names, direct,
                  min_effect: float) -> str:
    """Where an image change ``delta`` (H, W, 3) lies, in the words of :func:`describe_tiles`.

    Tiles are chosen by the mean *absolute* relative change in luminance
    (a shift or a blur moves light within a tile, so its signed mean can
    vanish where the change is strong) and worded with the sign of the
    signed mean; a change whose tile means all stay below ``min_effect``
    is 'no visible change at this resolution'.
    """
    d = np.asarray(delta, np.float64)
    r_t = tile_means(np.asarray(ref, np.float64), mask, tile)
    signed = rel_lum(tile_means(d, mask, tile), r_t)
    lum = np.abs(d @ LUMINANCE)[..., None] * np.ones(3)
    mag = rel_lum(tile_means(lum, mask, tile), r_t)
    mx = float(np.max(np.abs(mag))) if mag.size else 0.0
    if mx < min_effect:
        return "no visible change at this resolution"
    chosen = np.abs(mag) >= max(0.3 * mx, min_effect)
    rel = np.where(signed < 0, -np.abs(mag), np.abs(mag))
    h, w = np.asarray(ref).shape[:2]
    return describe_tiles(rel, chosen, (h, w), tile, labels, names, direct)

