"""Convergence reports: error against samples and against time, for every renderer.

``mcrt report`` (and :func:`main_report`, the project's main job) renders a
scene with each renderer at a ladder of samples per pixel and several seeds,
compares every render with the ground truth (RMSE, relMSE, SSIM, FLIP, with
the conventions of :mod:`mcrt.metrics`), fits the log-log slopes, measures
efficiency 1 / (MSE x time), and writes ``reports/<name>/``:

* ``error_vs_spp.png|svg``, ``error_vs_time.png|svg``, ``efficiency.png|svg``;
* ``images.png`` (renders beside the reference), ``flip.png`` and
  ``relerr.png`` (error heat maps);
* ``table.csv`` (one row per render), ``data.json`` (everything, with
  provenance; schema :data:`SCHEMA`);
* ``index.md`` and ``index.html`` (self-contained: images embedded).

Modules: :mod:`.config` (settings, presets), :mod:`.run` (the ladder),
:mod:`.summary` (means, slopes, efficiencies) with :mod:`.slopes` (the
slope fit), :mod:`.build` (the report folder), :mod:`.plots`,
:mod:`.images`, :mod:`.content` with :mod:`.markdown` and :mod:`.html` (one
module per format), :mod:`.data` (JSON, CSV, the conventions), :mod:`.cli`.

The names below are imported lazily (no module of the package imports the
package itself), so ``mcrt --help`` stays fast.
"""

from __future__ import annotations

import importlib

_API = {
    "PRESETS": "config", "RendererSpec": "config", "ReportConfig": "config", "preset_config": "config",
    "SCHEMA": "data",
    "REPORT_FILES": "build", "ReportOutput": "build", "run_report": "build", "write_report": "build", "main_report": "build",
    "register": "cli",
}

__all__ = ["SCHEMA", "PRESETS", "ReportConfig", "RendererSpec", "ReportOutput", "REPORT_FILES", "preset_config",  # noqa: RUF022
           "run_report", "write_report", "main_report", "register"]


def __getattr__(name: str):
    if name in _API:
        return getattr(importlib.import_module(f"mcrt.convergence.{_API[name]}"), name)
    raise AttributeError(f"module 'mcrt.convergence' has no attribute {name!r}")
