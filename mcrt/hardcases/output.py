"""Writing the hard-case report: index.md and data.json from one run's results."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import mcrt.hardcases.data as data
import mcrt.hardcases.markdown as markdown
from mcrt.hardcases.cases import CaseResult
from mcrt.hardcases.convergence import ConvergenceRow
from mcrt.hardcases.sweep import SweepRow
from mcrt.provenance import provenance

#: Where ``mcrt hardcases`` writes by default.
REPORT_DIR = Path("reports") / "hardcases"  # the default --out, relative to the working folder like every report's


def write_report(results: list[CaseResult], out: Path, *, argv: Sequence[str], settings: dict[str, Any],
                 sweep: list[SweepRow] | None = None, conv: list[ConvergenceRow] | None = None) -> tuple[Path, Path]:
    """reports/hardcases/index.md (tables) and data.json (every number, schema :data:`mcrt.hardcases.data.SCHEMA`)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    command = " ".join(["mcrt", "hardcases", *argv])
    parts = {"command": command, "prov": provenance(command=command), "settings": settings, "sweep": sweep, "conv": conv}
    json_path = data.write(out / "data.json", data.report_data(results, **parts))
    md_path = markdown.write(out / "index.md", markdown.report_markdown(results, **parts))
    return md_path, json_path
