"""Convergence plots (matplotlib, Agg backend): error against spp and time, efficiency.

Every plot is written as PNG and, when asked, SVG (text kept as text, so the
files stay small). Points are means over seeds with error bars of one
standard deviation over seeds; dashed lines are the least-squares fits whose
slopes (with 95 % confidence intervals) are in the legend; grey dotted lines
are the slopes an unbiased estimator should show (spp^-1/2 for RMSE,
spp^-1 for relMSE) and the reference's own noise level.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from mcrt.convergence.run import METRICS, ReportData
from mcrt.convergence.summary import Summary

COLORS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b")


def _plt():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    plt.rcParams.update({"svg.fonttype": "none", "font.size": 9, "axes.grid": True, "grid.alpha": 0.3,
                         "svg.hashsalt": "mcrt-report", "path.simplify": True})
    return plt


def _save(fig, out: Path, stem: str, svg: bool) -> dict[str, Path]:
    paths = {"png": out / f"{stem}.png"}
    fig.savefig(paths["png"], dpi=110, bbox_inches="tight", metadata={"Software": None})
    _palette(paths["png"])
    if svg:
        paths["svg"] = out / f"{stem}.svg"
        fig.savefig(paths["svg"], bbox_inches="tight", metadata={"Date": None, "Creator": None})
    import matplotlib.pyplot as plt

    plt.close(fig)
    return paths


def _palette(path: Path) -> None:
    """Re-save a plot PNG with a 256-colour palette: a smaller file, no visible change for line plots."""
    from PIL import Image

    with Image.open(path) as im:
        q = im.convert("RGB").quantize(colors=256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    q.save(path, format="PNG", optimize=True)


def _yerr(mean: np.ndarray, std: np.ndarray) -> np.ndarray:
    """Error bars that stay positive on a log axis."""
    lower = np.minimum(std, 0.95 * mean)
    return np.vstack([lower, std])


def _rows(summary: Summary, label: str) -> list[dict]:
    return [r for r in summary.rows if r["renderer"] == label]


def _guide(ax, x: np.ndarray, y0: float, slope: float, text: str) -> None:
    xs = np.array([x.min(), x.max()], dtype=np.float64)
    ax.plot(xs, y0 * (xs / xs[0]) ** slope, ls=":", color="0.45", lw=1.2, label=text)


def _metric_panels(data: ReportData, summary: Summary, axis: str, svg: bool, out: Path) -> dict[str, Path]:
    plt = _plt()
    fig, axes = plt.subplots(2, 2, figsize=(10.5, 8.0))
    for ax, (key, name) in zip(axes.ravel(), METRICS.items()):
        first = True
        for i, spec in enumerate(data.specs):
            rows = _rows(summary, spec.label)
            if not rows:
                continue
            c = COLORS[i % len(COLORS)]
            y = np.array([r[key] for r in rows])
            ys = np.array([r[key + "_std"] for r in rows])
            if axis == "spp":
                x = np.array([r["spp"] for r in rows], dtype=np.float64)
                xerr = None
            else:
                x = np.array([r["time"] for r in rows])
                xerr = np.array([r["time_std"] for r in rows])
                xerr = _yerr(x, xerr)
            fit = summary.fits[spec.label][key][axis]
            lab = spec.label
            if math.isfinite(fit.slope):
                ci = f" [{fit.ci_low:.2f}, {fit.ci_high:.2f}]" if math.isfinite(fit.ci_low) else ""
                lab += f": slope {fit.slope:.3f}{ci}"
            ax.errorbar(x, y, yerr=_yerr(y, ys), xerr=xerr, fmt="o", ms=3.5, color=c, capsize=2, lw=1, label=lab)
            if math.isfinite(fit.slope) and x.min() > 0:
                xs = np.geomspace(x.min(), x.max(), 50)
                ys = fit.predict(xs)
                if np.all(np.isfinite(ys)) and ys.max() < 1e3 * np.nanmax(y) and ys.min() > 1e-3 * np.nanmin(y):
                    ax.plot(xs, ys, ls="--", color=c, lw=1)
            if first and key in ("rmse", "relmse") and len(x) > 1:
                slope = -0.5 if key == "rmse" else -1.0
                _guide(ax, x, y[0] * 1.6, slope, f"slope {slope:g} ({'spp' if axis == 'spp' else 'time'}$^{{{slope:g}}}$)")
                first = False
        floor = data.floor
        if floor.get("known") and key in ("rmse", "relmse"):
            v = math.sqrt(floor["mse"]) if key == "rmse" else floor["relmse"]
            if v > 0:
                ax.axhline(v, color="0.6", ls="-.", lw=1, label="reference noise level")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("samples per pixel" if axis == "spp" else "render time [s] (wall - JIT compile)")
        ax.set_ylabel(name)
        ax.set_title(f"{name} against {'spp' if axis == 'spp' else 'render time'}")
        ax.legend(fontsize=7.5, loc="best")
    cfg = data.config
    fig.suptitle(f"{data.scene.name}, camera {cfg.camera}, {cfg.width}x{cfg.height}, max depth {cfg.max_depth}, "
                 f"{len(cfg.seeds)} seed{'s' if len(cfg.seeds) > 1 else ''} per point (mean +- 1 sd)", fontsize=10)
    fig.tight_layout()
    return _save(fig, out, f"error_vs_{axis}", svg)


def plot_efficiency(data: ReportData, summary: Summary, out: Path, svg: bool) -> dict[str, Path]:
    plt = _plt()
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10.5, 4.0))
    for i, spec in enumerate(data.specs):
        rows = _rows(summary, spec.label)
        c = COLORS[i % len(COLORS)]
        x = np.array([r["spp"] for r in rows], dtype=np.float64)
        e = np.array([r["efficiency"] for r in rows])
        summ = summary.efficiency[spec.label]["efficiency"]
        a1.plot(x, e, "o-", color=c, ms=3.5, lw=1, label=f"{spec.label}: {summ:.3g} (upper half)")
        for r in rows:
            pts = np.array(r["efficiency_seeds"])
            a1.plot(np.full(pts.shape, r["spp"]), pts, ".", color=c, alpha=0.35, ms=3)
        if math.isfinite(summ):
            a1.axhline(summ, color=c, ls="--", lw=0.8)
    a1.set_xscale("log")
    a1.set_yscale("log")
    a1.set_xlabel("samples per pixel")
    a1.set_ylabel("1 / (MSE x time)  [1/s]")
    a1.set_title("Efficiency (dots: single seeds; dashed: summary)")
    a1.legend(fontsize=7.5)
    base = summary.baseline
    for i, spec in enumerate(data.specs):
        if spec.label not in summary.ratios:
            continue
        r = summary.ratios[spec.label]
        c = COLORS[i % len(COLORS)]
        x = np.array([p["spp"] for p in r["per_rung"]], dtype=np.float64)
        y = np.array([p["ratio"] for p in r["per_rung"]])
        a2.plot(x, y, "o-", color=c, ms=3.5, lw=1, label=f"{spec.label} / {base}: {r['ratio']:.2f}")
        if math.isfinite(r["ratio"]):
            a2.axhline(r["ratio"], color=c, ls="--", lw=0.8)
    a2.axhline(1.0, color="0.4", lw=0.8)
    a2.set_xscale("log")
    a2.set_yscale("log")
    a2.set_xlabel(f"samples per pixel ({data.specs[0].label})")
    a2.set_ylabel(f"efficiency ratio to {base}")
    a2.set_title("Efficiency ratio (> 1: less time for the same MSE)")
    a2.legend(fontsize=7.5)
    fig.tight_layout()
    return _save(fig, out, "efficiency", svg)


def write_plots(data: ReportData, summary: Summary, out: Path, svg: bool = True) -> dict[str, dict[str, Path]]:
    """error_vs_spp, error_vs_time and efficiency, as PNG (and SVG)."""
    return {
        "error_vs_spp": _metric_panels(data, summary, "spp", svg, out),
        "error_vs_time": _metric_panels(data, summary, "time", svg, out),
        "efficiency": plot_efficiency(data, summary, out, svg),
    }
