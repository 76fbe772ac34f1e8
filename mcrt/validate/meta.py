"""Provenance of a study: the project's provenance record (:func:`mcrt.provenance.provenance`) with command and scene."""

from __future__ import annotations

import shlex
import sys
from pathlib import Path
from typing import Any

import mcrt
from mcrt.provenance import provenance
from mcrt.scene import Scene


def report_meta(scene: Scene | None, command: str | None = None) -> dict[str, Any]:
    """Provenance of a report: date, commit, versions (SciPy included), machine, command line (default: this process's), scene."""
    if scene is None:
        where = {"path": "(not recorded)", "hash": "", "name": ""}
    else:
        try:
            path = str(Path(scene.path).resolve().relative_to(Path(mcrt.__file__).resolve().parent.parent))
        except (ValueError, OSError, TypeError):
            path = str(scene.path)
        where = {"path": path, "hash": scene.content_hash(), "name": scene.name}
    return provenance(packages=("scipy",), command=command if command is not None else shlex.join(sys.argv), scene=where)
