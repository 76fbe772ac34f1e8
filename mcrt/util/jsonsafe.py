"""JSON-safe copies of results (what ``json.dumps(..., allow_nan=False)`` accepts) and strict JSON files of them."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path, PurePath
from typing import Any

import numpy as np

from mcrt.util import atomic


def json_safe(x: Any) -> Any:
    """A copy of ``x`` that JSON can hold.

    NaN and infinities become None (JSON has neither); tuples, lists and
    NumPy arrays become lists; NumPy scalars Python numbers; paths strings;
    dictionary keys strings; an object with a ``to_dict()`` method its
    dictionary. Anything else is returned as it is.
    """
    if isinstance(x, dict):
        return {str(k): json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [json_safe(v) for v in x]
    if isinstance(x, np.ndarray):
        return json_safe(x.tolist())
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (float, np.floating)):
        v = float(x)
        return v if math.isfinite(v) else None
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, PurePath):
        return str(x)
    if callable(getattr(x, "to_dict", None)):
        return json_safe(x.to_dict())
    return x


def write_json(path: str | os.PathLike, data: Any, *, indent: int = 1) -> Path:
    """Write :func:`json_safe` of ``data`` as strict JSON with a final newline, whole or not at all; returns the path."""
    atomic.write_text(path, json.dumps(json_safe(data), indent=indent, allow_nan=False) + "\n")
    return Path(path)
