"""The tricks report's figures (matplotlib through :mod:`mcrt.convergence.plots`' setup and palette-PNG writer)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mcrt.convergence.plots import COLORS, _plt, _save
from mcrt.tricks.study import StudyData
from mcrt.tricks.variants import PLAIN
from mcrt.tricks.verdicts import TRICK_NAMES, rungs_of


def _labels(data: StudyData, trick: str) -> list[str]:
    return [PLAIN] + [v.label for v in data.variants if v.trick == trick]


def error_panels(data: StudyData, tricks, out: Path, *, axis: str, svg: bool) -> dict:
    """relMSE against render time (``axis='time'``) or RMSE against samples per pixel (``axis='spp'``), a panel per trick."""
    plt = _plt()
    n = len(tricks)
    cols = 3 if n > 2 else n
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.6 * cols, 3.8 * rows), squeeze=False)
    for ax, trick in zip(axes.ravel(), tricks):
        for i, label in enumerate(_labels(data, trick)):
            rs = rungs_of(data, label)
            if axis == "time":
                x, y = [r.time for r in rs], [r.relmse for r in rs]
            else:
                x, y = [r.spp for r in rs], [r.rmse for r in rs]
            style = dict(color="k", lw=2.0) if label == PLAIN else dict(color=COLORS[(i - 1) % len(COLORS)], lw=1.1)
            ls = "--" if i > len(COLORS) else "-"
            ax.plot(x, y, "o" + ls, ms=3, label=label, **style)
        _log_axes(ax, "render time [s] (wall - JIT compile)" if axis == "time" else "samples per pixel (budget)",
                  "relMSE" if axis == "time" else "RMSE", TRICK_NAMES[trick])
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    cfg = data.config
    fig.suptitle(f"{data.scene.name}, camera {cfg.camera}, {cfg.res}x{cfg.res}, max depth {cfg.max_depth}: "
                 f"means over {cfg.seeds} seeds, against the {data.reference_spp}-spp Mitsuba reference", fontsize=9.5)
    fig.tight_layout()
    return _save(fig, out, "error_vs_time" if axis == "time" else "error_vs_spp", svg)


def bias_plot(data: StudyData, labels: list[str], out: Path, *, svg: bool) -> dict:
    """bias^2 (solid) and variance across seeds (dotted) against spp; plain mcrt's variance for scale."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7.5, 4.6))
    for i, label in enumerate([PLAIN, *labels]):
        rs = rungs_of(data, label)
        c = "k" if label == PLAIN else COLORS[(i - 1) % len(COLORS)]
        x = np.array([r.spp for r in rs], dtype=float)
        b = np.array([r.bias2 for r in rs])
        ax.plot(x, np.array([r.variance for r in rs]), ":", color=c, marker="o", ms=3, label=f"{label}: variance")
        if label != PLAIN:
            ok = b > 0
            ax.plot(x[ok], b[ok], "-", color=c, marker="s", ms=3.5, label=f"{label}: bias$^2$ (MSE - variance - floor)")
    ax.axhline(data.floor["mse"], color="0.6", ls="-.", lw=1, label="reference noise floor")
    _log_axes(ax, "samples per pixel", "squared error (mean over pixels and channels)",
              "Bias against spp: where bias$^2$ crosses the variance, more samples stop helping")
    fig.tight_layout()
    return _save(fig, out, "bias", svg)


def _log_axes(ax, xlabel: str, ylabel: str, title: str | None = None) -> None:
    """Log-log axes with their labels, title and legend."""
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title, fontsize=9)
    ax.legend(fontsize=6.5)


def spp_maps(data: StudyData, out: Path, *, svg: bool) -> dict | None:
    """Samples traced per pixel by each adaptive scheme at the top rung (seed 0), beside the reference."""
    if not data.spp_maps:
        return None
    from mcrt.image_files import srgb_oetf

    plt = _plt()
    n = len(data.spp_maps)
    fig, axes = plt.subplots(1, n + 1, figsize=(3.6 * (n + 1), 3.4))
    axes[0].imshow(srgb_oetf(np.clip(data.images["reference"], 0, 1)))
    axes[0].set_title("reference", fontsize=8)
    top = data.config.ladder[-1]
    for ax, (label, m) in zip(axes[1:], data.spp_maps.items()):
        im = ax.imshow(m, cmap="viridis", norm=_log_norm(m))
        ax.set_title(f"{label}\n{top} spp budget: {m.min():.0f} .. {m.max():.0f} per pixel", fontsize=8)
        fig.colorbar(im, ax=ax, fraction=0.046, pad=0.04)
    for ax in axes:
        ax.set_xticks([])
        ax.set_yticks([])
    fig.tight_layout()
    return _save(fig, out, "spp_maps", svg)


def _log_norm(m: np.ndarray):
    from matplotlib.colors import LogNorm

    return LogNorm(vmin=max(float(m.min()), 1.0), vmax=max(float(m.max()), 2.0))


def light_plot(rows: list[dict], out: Path, *, svg: bool) -> dict | None:
    """Per-sample variance of the direct-light estimate and the efficiency ratio against the distance to the light."""
    if not rows:
        return None
    plt = _plt()
    below = [r for r in rows if "below" in r["receiver"]]
    d = np.array([r["distance"] for r in below])
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.8))
    for strategy, c in (("area", COLORS[0]), ("solid_angle", COLORS[1])):
        a1.plot(d, [r[strategy]["variance"] / r["closed_form"] ** 2 for r in below], "o-", color=c, ms=3,
                label=strategy.replace("_", " "))
    a2.plot(d, [r["efficiency_ratio"] for r in below], "o-", color="k", ms=3, label="variance x time, area / solid angle")
    a2.axhline(1.0, color="0.5", lw=0.8)
    for ax, ylabel in ((a1, "relative per-sample variance  var / E$^2$"), (a2, "efficiency ratio (solid angle over area)")):
        _log_axes(ax, "distance below the light's centre (receiver facing it)", ylabel)
    fig.tight_layout()
    return _save(fig, out, "light_sampling", svg)


def variance_histogram(data: StudyData, labels: list[str], out: Path, *, svg: bool) -> dict | None:
    """Distribution of the per-pixel per-sample variance (top rung, seed 0): the fireflies are its right tail."""
    maps = {k: v for k, v in data.variance_maps.items() if k in labels}
    if len(maps) < 2:
        return None
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7.5, 4.0))
    allv = np.concatenate([m.ravel() for m in maps.values()])
    pos = allv[allv > 0]
    bins = np.geomspace(max(pos.min(), 1e-8), pos.max() * 1.01, 60)
    for i, (label, m) in enumerate(maps.items()):
        c = "k" if label == PLAIN else COLORS[i % len(COLORS)]
        ax.hist(m.ravel()[m.ravel() > 0], bins=bins, histtype="step", color=c, lw=1.3, label=label)
    _log_axes(ax, "per-sample variance of a pixel (mean over channels)", "pixels",
              "Per-pixel variance: the right tail is the fireflies")
    fig.tight_layout()
    return _save(fig, out, "variance_distribution", svg)


def image_strip(data: StudyData, labels: list[str], out: Path) -> dict:
    """The top-rung renders (seed 0) of ``labels`` beside the reference, sRGB, exposure 0."""
    from mcrt.image_files import srgb_oetf

    plt = _plt()
    shown = ["reference", *labels]
    cols = min(len(shown), 5)
    rows = -(-len(shown) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(2.6 * cols, 2.8 * rows), squeeze=False)
    for ax in axes.ravel():
        ax.set_axis_off()
    for ax, label in zip(axes.ravel(), shown):
        ax.imshow(srgb_oetf(np.clip(data.images[label], 0, 1)), interpolation="nearest")
        ax.set_title(label, fontsize=7)
    fig.tight_layout()
    return _save(fig, out, "images", False)
