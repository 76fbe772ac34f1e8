"""A report folder: run the ladder, then write every file of ``reports/<name>/``.

:func:`run_report` renders and measures (:func:`mcrt.convergence.run.run_ladder`)
and :func:`write_report` writes the plots, image strips, tables, data.json,
index.md and index.html from the measurements; :func:`main_report` is the
project's main job (the ``canonical`` preset).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

from mcrt.convergence.config import ReportConfig, preset_config

#: Files a report folder holds (SVGs only when asked for).
REPORT_FILES = ("index.html", "index.md", "data.json", "table.csv", "error_vs_spp.png", "error_vs_time.png",
                "efficiency.png", "images.png", "flip.png", "relerr.png", "error_vs_spp.svg", "error_vs_time.svg",
                "efficiency.svg")


@dataclass
class ReportOutput:
    folder: Path
    data: "object"  # mcrt.convergence.run.ReportData
    summary: "object"  # mcrt.convergence.summary.Summary
    files: list[Path]


def write_report(data, out: str | Path, *, clean: bool = True) -> ReportOutput:
    """Write every file of a report for measured ``data`` into ``out``."""
    from mcrt.convergence.content import build_document
    from mcrt.convergence.data import data_dict, write_csv
    from mcrt.util.jsonsafe import write_json
    from mcrt.convergence.html import write as write_html
    from mcrt.convergence.images import write_strips
    from mcrt.convergence.markdown import write as write_markdown
    from mcrt.convergence.plots import write_plots
    from mcrt.convergence.summary import summarize

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    if clean:  # drop the files of an earlier report (an SVG no longer asked for), nothing else
        for name in REPORT_FILES:
            (out / name).unlink(missing_ok=True)
    s = summarize(data)
    plots = write_plots(data, s, out, svg=data.config.svg)
    images = write_strips(data, out)
    names = sorted({p.name for d in plots.values() for p in d.values()} | {p.name for p in images.values()}
                   | {"index.html", "index.md", "data.json", "table.csv"})
    files = {"plots": plots, "images": images, "all": names}
    doc = build_document(data, s, files)
    write_csv(out / "table.csv", data)
    write_json(out / "data.json", data_dict(data, s, names))
    write_markdown(out / "index.md", doc)
    write_html(out / "index.html", doc)
    return ReportOutput(out, data, s, [out / n for n in names])


def run_report(cfg: ReportConfig, out: str | Path | None = None, *, progress: bool = True, command: str | None = None) -> ReportOutput:
    """Render the ladder of ``cfg``, then write the report to ``out`` (default reports/<name>)."""
    from mcrt.convergence.run import run_ladder

    data = run_ladder(cfg, progress=progress, command=command)
    return write_report(data, out if out is not None else Path("reports") / cfg.name)


def main_report(out: str | Path = "reports/canonical", *, progress: bool = True, command: str | None = None, **overrides) -> ReportOutput:
    """The project's main job: the ``canonical`` preset (overridable field by field), written to ``out``.

    Near camera, 64x64, spp 1, 2, 4, ..., 1024, seeds 1, 2, 3, max depth 8,
    one shadow ray, renderers mcrt, Mitsuba and the plugin, against the
    committed Mitsuba reference.
    """
    cfg = replace(preset_config("canonical"), **overrides)
    return run_report(cfg, out, progress=progress, command=command or "mcrt main")
