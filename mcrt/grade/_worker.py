"""A grading worker process: ``python -m mcrt.grade._worker`` (started by :mod:`mcrt.grade.batch`).

Protocol on stdin/stdout, each message a little-endian 8-byte length and a
pickle (:func:`write_message`, :func:`read_message`): first
``(context, out_dir, memory_mb)``, answered by ``"ready"`` once the worker
has imported everything; then ``(index, submission)`` per student (``None``
to stop), each answered by ``(index, result)``, the result of
:func:`grade_and_write`. Anything the libraries print goes to stderr, never
into the channel.
"""

from __future__ import annotations

import os
import pickle
import struct
import sys
from pathlib import Path

from mcrt.grade.expected import Context
from mcrt.grade.grader import STATUS_ERROR, StudentResult, error_result, format_exception, grade_submission
from mcrt.grade.outputs import write_student
from mcrt.grade.submissions import Submission


def read_message(f):
    """The next message from ``f``, or the class EOFError when the stream ends first."""
    head = f.read(8)
    if len(head) < 8:
        return EOFError
    (n,) = struct.unpack("<Q", head)
    data = f.read(n)
    if len(data) < n:
        return EOFError
    return pickle.loads(data)


def write_message(f, obj) -> None:
    data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    f.write(struct.pack("<Q", len(data)) + data)
    f.flush()


def criteria_of(ctx) -> list | None:
    """The rubric's criteria for a failure's zero result: the image rubric (None) or the code checks."""
    return None if isinstance(ctx, Context) else ctx.criteria


def grade_and_write(sub: Submission, ctx, out: Path) -> StudentResult:
    """Grade one student and write their results.json and feedback.html; a crash of the grader is a graded failure.

    ``ctx``: a :class:`~mcrt.grade.expected.Context` grades images, a :class:`~mcrt.grade.codemode.CodeContext`
    a module (the one class runner serves both modes).
    """
    try:
        if isinstance(ctx, Context):
            res = grade_submission(sub, ctx)
            res.details.setdefault("reference_source", ctx.references[res.details.get("orientation", {}).get("camera", ctx.assignment.camera)].source)
        else:
            res = ctx.grade(sub)
    except Exception as e:  # noqa: BLE001 - a bug in the grader: graded failure, never a crash of the batch
        res = error_result(sub.student, ctx.assignment, STATUS_ERROR,
                           f"the grader failed on this submission ({type(e).__name__}: {' '.join(str(e).split())[:200]})",
                           format_exception(), criteria=criteria_of(ctx))
    try:
        write_student(res, ctx.assignment, out)
    except Exception as e:  # noqa: BLE001 - the result still reaches grades.csv
        res.notes.append(f"could not write feedback: {e}")
    res.figures = {}
    return res


def main() -> int:  # pragma: no cover - runs in a child process
    chan = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    inp = sys.stdin.buffer
    setup = read_message(inp)
    if setup is EOFError:
        return 0
    ctx, out, memory_mb = setup
    try:
        import resource

        limit = int(memory_mb) << 20
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    except (ImportError, ValueError, OSError):
        pass
    write_message(chan, "ready")  # the parent starts a student's clock only now
    while True:
        task = read_message(inp)
        if task is EOFError or task is None:
            return 0
        idx, sub = task
        write_message(chan, (idx, grade_and_write(sub, ctx, Path(out))))


if __name__ == "__main__":
    sys.exit(main())
