"""Where a measurement was taken: facts that every report records.

:func:`provenance` is the one dictionary every report, study and benchmark
of the project stores beside its numbers; :func:`machine`, :func:`cpu_name`
and :func:`source_hash` are its parts that other code needs alone (the
references' manifest, cache keys).
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import functools
import hashlib
import os
import platform
import subprocess
from importlib import metadata
from pathlib import Path
from typing import Any

#: The package folder: what :func:`source_hash` hashes, and where :func:`git_commit` looks for the repository.
_PACKAGE = Path(__file__).resolve().parent


def cpu_name() -> str:
    """The CPU model (from /proc/cpuinfo on Linux, else what the platform module knows)."""
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    return platform.processor() or platform.machine()


def machine() -> dict[str, Any]:
    """The machine a measurement ran on: ``cpu`` (:func:`cpu_name`), ``cores``, ``platform``."""
    return {"cpu": cpu_name(), "cores": os.cpu_count(), "platform": platform.platform()}


@functools.cache
def source_hash(root: Path | None = None) -> str:
    """A hash of the Python sources under ``root`` (default: mcrt's): part of every cache key for renders.

    The version number does not change when the renderer's output does (a new
    random number generator, a fixed estimator), the source does.
    """
    root = _PACKAGE if root is None else Path(root)
    digest = hashlib.blake2b(digest_size=8)
    for path in sorted(root.rglob("*.py")):
        digest.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def git_commit() -> str | None:
    """The checkout's commit, with ``+dirty`` when tracked files differ from it; None outside a git checkout."""
    root = str(_PACKAGE.parent)
    try:
        out = subprocess.run(["git", "-C", root, "rev-parse", "HEAD"], capture_output=True, text=True, timeout=10)
        dirty = subprocess.run(["git", "-C", root, "status", "--porcelain", "--untracked-files=no"], capture_output=True,
                               text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    if out.returncode != 0:
        return None
    return out.stdout.strip() + ("+dirty" if dirty.stdout.strip() else "")


def _version(dist: str) -> str | None:
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return None


def provenance(*, packages: tuple[str, ...] = (), **extra: Any) -> dict[str, Any]:
    """The facts that decide (or explain) a measurement's numbers, as a JSON-ready dict.

    Keys: ``date`` (now, ISO 8601 UTC, seconds), ``git_commit``
    (:func:`git_commit`), ``source_hash`` (:func:`source_hash`), ``machine``
    (``cpu``, ``cores``, ``platform``), ``versions`` (mcrt, Dr.Jit, Mitsuba,
    NumPy, Python, and the installed version, or None, of every
    distribution named in ``packages``) and ``drjit_threads``; then every
    entry of ``extra`` (``command=...``, ``backend=...``), which may also
    replace one of these.
    """
    import drjit as dr
    import mitsuba as mi
    import numpy as np

    import mcrt

    versions = {"mcrt": mcrt.__version__, "drjit": dr.__version__, "mitsuba": mi.__version__, "numpy": np.__version__,
                "python": platform.python_version()}
    versions.update({p: _version(p) for p in packages})
    return {
        "date": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "git_commit": git_commit(),
        "source_hash": source_hash(),
        "machine": machine(),
        "versions": versions,
        "drjit_threads": dr.thread_count(),
        **extra,
    }
