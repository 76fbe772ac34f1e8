"""data.json (every measurement and its provenance, versioned schema) and table.csv (one row per render)."""

from __future__ import annotations

import csv
from dataclasses import asdict, fields
from pathlib import Path
from typing import Any

from mcrt import metrics
from mcrt.convergence.run import Measurement, ReportData
from mcrt.convergence.summary import Summary
from mcrt.util.jsonsafe import json_safe

#: Schema tag of data.json; bump the number when a field changes meaning or goes away.
SCHEMA = "mcrt.report/1"

#: What every number of a report means: the image metrics' conventions (:mod:`mcrt.metrics`) and the report's own.
CONVENTIONS = {
    **metrics.CONVENTIONS,
    "mse_ref_floor": ("mean(var_ref / spp_ref): the squared error that the reference's own noise adds to every MSE "
                      "(E|x - ref|^2 = E|x - mu|^2 + E|ref - mu|^2 for independent x and ref); "
                      "'excess' MSE and efficiency subtract it"),
    "efficiency": "1 / (MSE_excess x render time), with render time = wall time - JIT compile time",
    "slope": "least squares of log(metric) on log(spp) or log(time) over every render (seeds as points), 95 % CI from Student's t, n - 2 dof",
    "error_bars": "mean over seeds +- one standard deviation over seeds",
}

#: Top-level keys every data.json has.
TOP_KEYS = ("schema", "name", "config", "scene", "provenance", "reference", "conventions", "flip_parameters", "warmup",
            "calibration", "ladders", "measurements", "summary", "runtime_s", "files")
MEASUREMENT_KEYS = tuple(f.name for f in fields(Measurement))


def data_dict(data: ReportData, s: Summary, files: list[str]) -> dict[str, Any]:
    cfg = data.config
    return json_safe({
        "schema": SCHEMA,
        "name": cfg.name,
        "config": cfg.to_dict(),
        "scene": {"name": data.scene.name, "path": str(data.scene.path), "hash": data.scene.content_hash()},
        "provenance": data.provenance,
        "reference": dict(data.reference_info, floor=data.floor, width=cfg.width, height=cfg.height, max_depth=cfg.max_depth),
        "conventions": dict(CONVENTIONS, relmse_eps=metrics.RELMSE_EPS),
        "flip_parameters": data.flip_params,
        "warmup": data.warmup,
        "calibration": data.calibration,
        "ladders": data.ladders,
        "measurements": [asdict(m) for m in data.measurements],
        "summary": {
            "rows": s.rows, "fits": s.fits, "efficiency": s.efficiency, "ratios": s.ratios, "baseline": s.baseline,
            "upper_rungs": s.upper_rungs, "equal_time": s.equal_time, "verdicts": s.verdicts,
        },
        "runtime_s": data.runtime,
        "files": sorted(files),
    })


def write_csv(path: Path, data: ReportData) -> Path:
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(MEASUREMENT_KEYS)
        for m in data.measurements:
            w.writerow([repr(v) if isinstance(v, float) else v for v in asdict(m).values()])
    return Path(path)
