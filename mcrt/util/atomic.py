"""Files replaced whole or not at all: written beside their target, flushed to disk, then renamed over it.

A reader sees the old file or the complete new one, never a part; with
``fsync`` (the default) so does the file system after a crash. The temporary files are hidden, ``.name.<pid>.<random>.tmp``, so a
clean-up can find those of processes that died
(:func:`mcrt.groundtruth.manifest.remove_stale_temps`).
"""

from __future__ import annotations

import contextlib
import os
import secrets
from pathlib import Path
from typing import Iterator


def temporary_path(path: str | os.PathLike) -> Path:
    """A fresh hidden name beside ``path``: ``.name.<pid>.<random>.tmp``."""
    path = Path(path)
    return path.parent / f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp"


@contextlib.contextmanager
def replacing(path: str | os.PathLike, *, fsync: bool = True) -> Iterator[str]:
    """Yield a new empty temporary file beside ``path`` to write; move it over ``path`` when the block succeeds.

    Any exception removes the temporary file and propagates (an ``OSError``
    from creating it before the block runs). ``fsync=False`` skips flushing
    the data to disk before the rename (files that a crash may lose, written
    where time counts).
    """
    tmp = os.fspath(temporary_path(path))
    os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
    try:
        yield tmp
        if fsync:
            with open(tmp, "rb+") as f:
                os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def write_text(path: str | os.PathLike, text: str, *, encoding: str = "utf-8", errors: str = "strict",
               fsync: bool = True) -> None:
    """Replace ``path`` with ``text``, whole or not at all (``fsync`` as in :func:`replacing`)."""
    with replacing(path, fsync=fsync) as tmp, open(tmp, "w", encoding=encoding, errors=errors) as f:
        f.write(text)
