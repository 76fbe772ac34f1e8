"""A grading worker process: ``python -m mcrt.grade._worker`` (started by :mod:`mcrt.grade.batch`).

Protocol on stdin/stdout, each message a little-endian 8-byte length and a
pickle: first ``(context, out_dir, memory_mb)``, answered by ``"ready"`` once
the worker has imported everything; then ``(index, submission)`` per student
(``None`` to stop), each answered by ``(index, result)``.
Anything the libraries print goes to stderr, never into the channel.
"""

from __future__ import annotations

import os
import pickle
import struct
import sys


def _read(f):
    head = f.read(8)
    if len(head) < 8:
        return EOFError
    (n,) = struct.unpack("<Q", head)
    data = f.read(n)
    if len(data) < n:
        return EOFError
    return pickle.loads(data)


def _write(f, obj) -> None:
    data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    f.write(struct.pack("<Q", len(data)) + data)
    f.flush()


def main() -> int:  # pragma: no cover - runs in a child process
    chan = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    inp = sys.stdin.buffer
    setup = _read(inp)
    if setup is EOFError:
        return 0
    ctx, out, memory_mb = setup
    try:
        import resource

        limit = int(memory_mb) << 20
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    except (ImportError, ValueError, OSError):
        pass
    from pathlib import Path

    from mcrt.grade.batch import _grade_and_write

    _write(chan, "ready")  # the parent starts a student's clock only now
    while True:
        task = _read(inp)
        if task is EOFError or task is None:
            return 0
        idx, sub = task
        res = _grade_and_write(sub, ctx, Path(out))
        _write(chan, (idx, res))


if __name__ == "__main__":
    sys.exit(main())
