"""reference/manifest.json and the files beside it: checksums, atomic writes, the manifest lock."""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import secrets
from pathlib import Path
from typing import Any, Iterator

from mcrt.reference.errors import CorruptReference
from mcrt.reference.spec import CHUNK_DIR_NAME, MANIFEST_NAME, REFERENCE_DIR, SCHEMA, display_path


def sha256_file(path: str | os.PathLike) -> str:
    """SHA-256 of a file's bytes, as hex."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _atomic_write_text(path: Path, text: str) -> None:
    """Write ``text`` to a temporary file beside ``path``, fsync it, move it over ``path``."""
    tmp = path.parent / f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp"
    try:
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


@contextlib.contextmanager
def manifest_lock(directory: Path) -> Iterator[None]:
    """Serialise read-modify-write of the manifest between concurrent builds (POSIX flock)."""
    lock_dir = directory / CHUNK_DIR_NAME
    lock_dir.mkdir(parents=True, exist_ok=True)
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        yield
        return
    with open(lock_dir / ".manifest.lock", "w") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


def read_manifest(directory: str | os.PathLike = REFERENCE_DIR) -> dict[str, Any]:
    """The manifest as a dict ``{'schema': ..., 'references': {key: entry}}``.

    A missing manifest reads as an empty one; an unreadable one raises
    :class:`CorruptReference`.
    """
    path = Path(directory) / MANIFEST_NAME
    if not path.exists():
        return {"schema": SCHEMA, "references": {}}
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as e:
        raise CorruptReference(f"{display_path(path)}: unreadable manifest ({e}); restore it with `git checkout -- {display_path(path)}`") from None
    if not isinstance(data, dict) or data.get("schema") != SCHEMA or not isinstance(data.get("references"), dict):
        raise CorruptReference(f"{display_path(path)}: not a {SCHEMA} manifest")
    return data


def write_manifest(directory: Path, data: dict[str, Any]) -> None:
    data = {"schema": SCHEMA, "references": dict(sorted(data["references"].items()))}
    _atomic_write_text(directory / MANIFEST_NAME, json.dumps(data, indent=2) + "\n")



def remove_stale_temps(folder: Path) -> None:
    """Delete temporary files (``.name.<pid>.<hex>.tmp``) left by processes that died."""
    if not folder.is_dir():
        return
    for p in folder.glob(".*.tmp"):
        parts = p.name.split(".")
        try:
            pid = int(parts[-3])
        except (ValueError, IndexError):
            continue
        if pid == os.getpid():
            continue
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            with contextlib.suppress(OSError):
                p.unlink()
        except OSError:
            pass
