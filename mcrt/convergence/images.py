"""The report's image strip and error heat maps (PNG, drawn with Pillow).

Cells are shown at native resolution, enlarged by an integer factor (nearest
neighbour) when small; of a large image (over :data:`CELL_MAX` pixels) a
central crop is shown at native resolution, so that noise stays visible. Colours: images use
:func:`mcrt.image_files.tonemap` (exposure 0, sRGB); FLIP maps use magma on
[0, 1]; relative-error maps use viridis on log10 of the per-pixel relative
squared error (mean over channels of (x - ref)^2 / (ref^2 + eps)).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from mcrt.image_files import tonemap

#: Small images are enlarged to at least CELL_MIN pixels wide; of images wider than
#: CELL_MAX a central CROP x CROP crop is shown.
CELL_MIN, CELL_MAX, CROP = 160, 320, 256
PAD = 6
BG = (255, 255, 255)
FG = (20, 20, 20)


def cell_factor(width: int) -> tuple[int, int]:
    """(up, down): enlarge by ``up`` (nearest) or reduce by ``down`` (box); one of them is 1."""
    if width < CELL_MIN:
        return max(1, math.ceil(CELL_MIN / width)) if width * math.ceil(CELL_MIN / width) <= 2 * CELL_MAX else 1, 1
    if width > CELL_MAX:
        return 1, math.ceil(width / CELL_MAX)
    return 1, 1


def resize(a: np.ndarray, up: int, down: int) -> np.ndarray:
    """Integer nearest-neighbour enlargement or box reduction of an (H, W[, C]) array."""
    a = np.asarray(a, dtype=np.float64)
    if down > 1:
        h, w = (a.shape[0] // down) * down, (a.shape[1] // down) * down
        a = a[:h, :w]
        a = a.reshape(h // down, down, w // down, down, *a.shape[2:]).mean(axis=(1, 3))
    if up > 1:
        a = np.repeat(np.repeat(a, up, axis=0), up, axis=1)
    return a


def colorize(values: np.ndarray, cmap: str, lo: float, hi: float) -> np.ndarray:
    """(H, W) values -> (H, W, 3) uint8 through a matplotlib colormap on [lo, hi]."""
    import matplotlib

    t = np.clip((np.asarray(values, dtype=np.float64) - lo) / (hi - lo), 0.0, 1.0)
    rgba = matplotlib.colormaps[cmap](np.nan_to_num(t, nan=0.0))
    return (rgba[..., :3] * 255 + 0.5).astype(np.uint8)


def _font():
    try:
        return ImageFont.load_default(size=13)
    except TypeError:  # Pillow < 10.1
        return ImageFont.load_default()


def _text_size(draw, text, font) -> tuple[int, int]:
    b = draw.textbbox((0, 0), text, font=font)
    return b[2] - b[0], b[3] - b[1]


def colorbar(width: int, cmap: str, lo_text: str, hi_text: str, caption: str) -> np.ndarray:
    """A horizontal colour bar with its end labels and a caption, as an RGB array."""
    font = _font()
    bar_w = max(64, min(width, 360))
    grad = colorize(np.tile(np.linspace(0, 1, bar_w), (12, 1)), cmap, 0.0, 1.0)
    probe = ImageDraw.Draw(Image.new("RGB", (1, 1)))
    th = _text_size(probe, "Ag", font)[1] + 4
    img = Image.new("RGB", (max(width, bar_w + 2 * PAD), 12 + 2 * th + 2 * PAD), BG)
    d = ImageDraw.Draw(img)
    x0 = (img.width - bar_w) // 2
    img.paste(Image.fromarray(grad), (x0, PAD))
    d.text((x0, PAD + 14), lo_text, fill=FG, font=font)
    tw = _text_size(d, hi_text, font)[0]
    d.text((x0 + bar_w - tw, PAD + 14), hi_text, fill=FG, font=font)
    cw = _text_size(d, caption, font)[0]
    d.text(((img.width - cw) // 2, PAD + 14 + th), caption, fill=FG, font=font)
    return np.asarray(img)


def grid(path: str | Path, cells: list[list[np.ndarray | None]], row_labels: list[str], col_labels: list[list[str]],
         title: str = "", footer: np.ndarray | None = None, palette: bool = False) -> Path:
    """Write a PNG grid of RGB uint8 cells; each cell has its own caption above it, each row a label on the left."""
    font = _font()
    probe = ImageDraw.Draw(Image.new("RGB", (1, 1)))
    th = _text_size(probe, "Ag", font)[1] + 4
    cw = max(c.shape[1] for row in cells for c in row if c is not None)
    ch = max(c.shape[0] for row in cells for c in row if c is not None)
    lw = max([_text_size(probe, s, font)[0] for s in row_labels] + [0]) + 2 * PAD
    ncol = max(len(r) for r in cells)
    title_h = th + PAD if title else 0
    W = lw + ncol * (cw + PAD) + PAD
    if title:
        W = max(W, _text_size(probe, title, font)[0] + 2 * PAD)
    H = title_h + len(cells) * (ch + th + PAD) + PAD
    fh = 0
    if footer is not None:
        fh = footer.shape[0]
        W = max(W, footer.shape[1])
    img = Image.new("RGB", (W, H + fh), BG)
    d = ImageDraw.Draw(img)
    if title:
        d.text((PAD, PAD // 2), title, fill=FG, font=font)
    for i, row in enumerate(cells):
        y = title_h + PAD + i * (ch + th + PAD)
        d.text((PAD, y + th + ch // 2 - th // 2), row_labels[i], fill=FG, font=font)
        for j, c in enumerate(row):
            if c is None:
                continue
            x = lw + j * (cw + PAD)
            cap = col_labels[i][j]
            tw = _text_size(d, cap, font)[0]
            d.text((x + (cw - tw) // 2, y), cap, fill=FG, font=font)
            img.paste(Image.fromarray(np.ascontiguousarray(c)), (x, y + th))
    if footer is not None:
        img.paste(Image.fromarray(np.ascontiguousarray(footer)), ((W - footer.shape[1]) // 2, H))
    path = Path(path)
    if palette:  # colour-mapped heat maps hold at most the map's 256 colours (plus text): a palette PNG loses nothing visible
        img = img.quantize(colors=256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    img.save(path, format="PNG", optimize=True)
    return path


def write_strips(data, out: Path) -> dict[str, Path]:
    """images.png (renders beside the reference), flip.png and relerr.png (heat maps); returns their paths."""
    from mcrt.metrics import RELMSE_EPS

    ref = data.reference.mean
    H, W = ref.shape[:2]
    if W > CELL_MAX or H > CELL_MAX:  # large: a central crop at native resolution, where noise stays visible
        cw, ch = min(W, CROP), min(H, CROP)
        x0, y0 = (W - cw) // 2, (H - ch) // 2
        up, down = 1, 1
        scale_note = f" (central {cw}x{ch} crop of the {W}x{H} image, native resolution)"
    else:
        cw, ch, x0, y0 = W, H, 0, 0
        up, down = cell_factor(W)
        scale_note = f" (shown {up}x enlarged)" if up > 1 else ""

    def view(a: np.ndarray) -> np.ndarray:
        return resize(a[y0:y0 + ch, x0:x0 + cw], up, down)

    rungs = sorted({rung for (_, rung) in data.strip})
    labels = [s.label for s in data.specs]
    ref_cell = tonemap(view(ref))

    def cap(lab, rung):
        return f"{data.ladders[lab][rung]} spp"

    rows, caps = [], []
    for lab in labels:
        rows.append([tonemap(view(data.strip[(lab, r)].mean)) for r in rungs] + [ref_cell])
        caps.append([cap(lab, r) for r in rungs] + ["reference"])
    paths = {"images": grid(out / "images.png", rows, labels, caps, title=f"Renders (seed {data.config.seeds[0]}) beside the reference{scale_note}")}

    rows = [[colorize(view(data.strip[(lab, r)].flip_map), "magma", 0.0, 1.0) for r in rungs] for lab in labels]
    caps = [[f"{cap(lab, r)}: mean {data.strip[(lab, r)].flip:.3f}" for r in rungs] for lab in labels]
    width = len(rungs) * ref_cell.shape[1]
    paths["flip"] = grid(out / "flip.png", rows, labels, caps, title=f"HDR-FLIP error maps{scale_note}",
                         footer=colorbar(width, "magma", "0", "1", "FLIP error (0: identical)"), palette=True)

    positive = np.concatenate([v.rel_error[v.rel_error > 0].ravel() for v in data.strip.values()] + [np.array([1e-6, 1.0])])
    lo = math.floor(np.log10(np.percentile(positive, 1.0)))
    hi = math.ceil(np.log10(np.percentile(positive, 99.9)))
    if hi <= lo:
        hi = lo + 1
    floor = 10.0 ** (lo - 1)
    rows = [[colorize(np.log10(np.maximum(view(data.strip[(lab, r)].rel_error), floor)), "viridis", lo, hi) for r in rungs]
            for lab in labels]
    caps = [[cap(lab, r) for r in rungs] for lab in labels]
    paths["relerr"] = grid(out / "relerr.png", rows, labels, caps,
                           title=f"Per-pixel relative squared error{scale_note}",
                           footer=colorbar(width, "viridis", f"1e{lo}", f"1e{hi}",
                                           f"mean over RGB of (x - ref)^2 / (ref^2 + {RELMSE_EPS:g}), log scale"), palette=True)
    return paths
