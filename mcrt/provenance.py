"""Where a measurement was taken: facts that every report records."""

from __future__ import annotations

import contextlib
import functools
import hashlib
import platform
from pathlib import Path


def cpu_name() -> str:
    """The CPU model (from /proc/cpuinfo on Linux, else what the platform module knows)."""
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    return platform.processor() or platform.machine()


@functools.cache
def source_hash(root: Path | None = None) -> str:
    """A hash of the Python sources under ``root`` (default: mcrt's): part of every cache key for renders.

    The version number does not change when the renderer's output does (a new
    random number generator, a fixed estimator), the source does.
    """
    root = Path(__file__).resolve().parent if root is None else Path(root)
    digest = hashlib.blake2b(digest_size=8)
    for path in sorted(root.rglob("*.py")):
        digest.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()
