"""The study reports as JSON: false_alarms.json and power.json (the study's dict, provenance under ``meta``)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from mcrt.report.data import clean


def write(path: Path, study: dict[str, Any], meta: dict[str, Any]) -> Path:
    """Write one study with its provenance as strict JSON (non-finite numbers become null)."""
    path = Path(path)
    path.write_text(json.dumps(clean({"meta": meta, **study}), indent=1, allow_nan=False) + "\n", encoding="utf-8")
    return path


def read(path: Path) -> dict[str, Any] | None:
    """A study written by :func:`write` (None when the file does not exist)."""
    path = Path(path)
    if not path.exists():
        return None
    return json.loads(path.read_text(encoding="utf-8"))
