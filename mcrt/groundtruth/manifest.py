"""reference/manifest.json and the files beside it: checksums, atomic writes, the manifest lock.

A reference and its manifest entry are replaced together or not at all
(:func:`commit_reference`): the new EXR is written under a temporary name,
the new manifest is written as a journal (``.manifest.pending.json``, which
also records the new file's SHA-256), then the EXR is renamed into place,
then the manifest, then the journal is removed. :func:`read_manifest`
resolves a journal left by a crash without changing anything: if the file
on disk is the journal's (its checksum matches), the journal is the
manifest; otherwise the rename never happened and the old manifest still
describes the old file. The next commit, under the lock, finishes or drops
the journal (:func:`recover_pending`).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
from pathlib import Path
from typing import Any, Iterator

from mcrt.groundtruth.errors import CorruptReference
from mcrt.util import atomic
from mcrt.groundtruth.spec import CHUNK_DIR_NAME, MANIFEST_NAME, REFERENCE_DIR, SCHEMA, display_path


def sha256_file(path: str | os.PathLike) -> str:
    """SHA-256 of a file's bytes, as hex."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


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
    pending = _pending_manifest(Path(directory))
    if pending is not None:
        return pending
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
    atomic.write_text(directory / MANIFEST_NAME, json.dumps(data, indent=2) + "\n")


#: The journal of a commit in progress (see the module docstring).
PENDING_NAME = ".manifest.pending.json"


def _pending_manifest(directory: Path) -> dict[str, Any] | None:
    """The journal's manifest if the file it commits is on disk (the rename happened), else None."""
    path = directory / PENDING_NAME
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        file, digest = data["pending"]["file"], data["pending"]["sha256"]
        if data.get("schema") != SCHEMA or not isinstance(data.get("references"), dict):
            return None
    except (OSError, ValueError, KeyError, TypeError):
        return None
    try:
        if sha256_file(directory / file) != digest:
            return None
    except OSError:
        return None
    return {"schema": SCHEMA, "references": data["references"]}


def recover_pending(directory: Path) -> None:
    """Finish (the file was renamed) or drop (it was not) a commit a crash interrupted; call under :func:`manifest_lock`."""
    path = directory / PENDING_NAME
    if not path.exists():
        return
    data = _pending_manifest(directory)
    if data is not None:
        write_manifest(directory, data)
    with contextlib.suppress(OSError):
        path.unlink()


def _replace_file(src: Path, dst: Path) -> None:
    os.replace(src, dst)
    with contextlib.suppress(OSError):  # make the rename durable before the manifest names the new file
        fd = os.open(dst.parent, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def commit_reference(directory: Path, staged: Path, key: str, entry: dict[str, Any]) -> None:
    """Move ``staged`` to ``directory / entry['file']`` and record ``entry`` under ``key``: both or neither.

    ``entry['sha256']`` must be the staged file's checksum. A crash at any
    point leaves either the previous reference with the previous manifest
    or the new reference with the new manifest (see the module docstring).
    """
    directory = Path(directory)
    target = directory / entry["file"]
    with manifest_lock(directory):
        recover_pending(directory)
        data = read_manifest(directory)
        data["references"][key] = entry
        journal = {"schema": SCHEMA, "references": dict(sorted(data["references"].items())),
                   "pending": {"key": key, "file": entry["file"], "sha256": entry["sha256"]}}
        atomic.write_text(directory / PENDING_NAME, json.dumps(journal, indent=2) + "\n")
        try:
            _replace_file(staged, target)
        except BaseException:
            with contextlib.suppress(OSError):
                (directory / PENDING_NAME).unlink()
            raise
        write_manifest(directory, data)
        with contextlib.suppress(OSError):
            (directory / PENDING_NAME).unlink()



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
