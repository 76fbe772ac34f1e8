"""The hard-case report as JSON: reports/hardcases/data.json (every number, with its provenance)."""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path
from typing import Any

from mcrt.hardcases.cases import ALPHA, SEEDS, TILE, CaseResult
from mcrt.hardcases.convergence import ConvergenceRow
from mcrt.hardcases.sweep import SweepRow, sweep_limits
from mcrt.util.jsonsafe import json_safe, write_json

#: Schema number of data.json (2: the run's provenance under ``provenance``, :func:`mcrt.provenance.provenance`).
SCHEMA = 2


def report_data(results: list[CaseResult], *, command: str, prov: dict[str, Any], settings: dict[str, Any],
                sweep: list[SweepRow] | None = None, conv: list[ConvergenceRow] | None = None) -> dict[str, Any]:
    """Everything the run measured, JSON-ready (non-finite numbers as null)."""
    return json_safe({
        "schema": SCHEMA, "command": command, "provenance": prov, "settings": settings, "seeds": SEEDS,
        "alpha": ALPHA, "tile": TILE, "correction": "holm",
        "cases": [asdict(r) | {"passed": r.passed, "problems": r.problems} for r in results],
        "sweep": [asdict(r) for r in sweep] if sweep else None,
        "limits": sweep_limits(sweep) if sweep else None,
        "convergence": [asdict(r) for r in conv] if conv else None,
    })


def write(path: Path, data: dict[str, Any]) -> Path:
    return write_json(path, data, indent=2)
