"""The study reports as JSON: false_alarms.json and power.json (the study's dict, provenance under ``meta``)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from mcrt.util.jsonsafe import write_json


def write(path: Path, study: dict[str, Any], meta: dict[str, Any]) -> Path:
    """Write one study with its provenance as strict JSON (non-finite numbers become null)."""
    return write_json(path, {"meta": meta, **study})


def read(path: Path) -> dict[str, Any] | None:
    """A study written by :func:`write` (None when the file does not exist)."""
    path = Path(path)
    if not path.exists():
        return None
    return json.loads(path.read_text(encoding="utf-8"))
