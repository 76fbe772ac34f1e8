"""The record of a grading run: ``DIR/run.json``, what each student's result was graded from, and resuming.

``run.json`` (schema :data:`SCHEMA`) says which run wrote what and whether it finished::

    {"schema": "mcrt.grade.run/1", "run": "<id>", "started": "...", "finished": null, "complete": false,
     "assignment": "course2023", "digest": {...}, "pending": ["bob", ...],
     "students": {"alice": {"key": "<sha256>", "run": "<id>", "results_sha256": "<sha256>", "row": {...}}}}

A student's ``key`` is a SHA-256 of everything their result depends on: the
bytes and names of their files (links and special files by what they are,
never opened), the assignment (its parsed form, scene included), the grader
(mcrt's version and a hash of its sources, :func:`mcrt.provenance.source_hash`),
the reference's source and the time and memory limits. A result is kept by a
later run only when its key matches and ``results.json`` still has the bytes
recorded (a run killed between moving a student's files and recording them
leaves that student to be graded again), and only when it graded the student (a timeout or a crash is tried
again). ``row`` holds what grades.csv and
the summary need, so a resumed run rewrites them without re-reading every
results.json.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import hashlib
import json
import os
import secrets
import stat
from dataclasses import dataclass, field
from pathlib import Path

from mcrt.grade.grader import StudentResult, TestResult
from mcrt.grade.outputs import write_json_atomic
from mcrt.grade.submissions import Submission, _walk, file_kind
from mcrt.groundtruth.manifest import sha256_file

SCHEMA = "mcrt.grade.run/1"
RUN_FILE = "run.json"
STAGING = ".staging"  # hidden: a student id never starts with a dot (mcrt.grade.submissions.safe_id)
LOCK_FILE = ".lock"
DEFAULT_MEMORY_MB = 4096  # per grading worker
_BLOCK = 1 << 20


@dataclass
class Plan:
    """What :func:`mcrt.grade.batch.grade_class` needs of a mode (image: :func:`mcrt.grade.batch.image_plan`; code: :func:`mcrt.grade.codemode.code_plan`).

    ``ctx`` is what a worker grades each student with (:func:`mcrt.grade._worker.grade_and_write`); ``timeout``
    and ``memory_mb`` bound one student and one worker; ``digest`` is what the results depend on besides the
    submissions and the assignment; ``finish(results)`` returns (a note for the summary, the catalogue's power
    table) once the students of this run are graded.
    """

    subs: list[Submission]
    ctx: object
    source: str
    note: str
    timeout: float
    memory_mb: int
    digest: dict = field(default_factory=dict)
    criteria: list | None = None
    image_context: object = None  # the image-mode Context (references), when the mode prepared one
    finish: object = None


def grader_digest(assignment, *, reference_source: str, timeout: float, memory_mb: int, **mode) -> dict:
    """What every student's result depends on besides their own files (``mode``: what the mode adds, e.g. the sandbox)."""
    from importlib import metadata

    from mcrt.provenance import source_hash

    try:
        version = metadata.version("mcrt")
    except metadata.PackageNotFoundError:
        version = "unknown"
    return {"assignment": hashlib.sha256(repr(assignment).encode()).hexdigest(), "mcrt": version,
            "sources": source_hash(), "reference": reference_source, "timeout": timeout, "memory_mb": memory_mb, **mode}


def _hash_file(h, path: Path) -> None:
    """Feed a regular file's bytes to ``h`` without following a link or blocking on a FIFO."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0))
    except OSError as e:
        h.update(f"unreadable: {e.strerror}".encode())
        return
    with os.fdopen(fd, "rb") as f:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            h.update(b"not a regular file")
            return
        for block in iter(lambda: f.read(_BLOCK), b""):
            h.update(block)


def submission_key(sub: Submission, digest: dict) -> str:
    """SHA-256 of a submission's files and of ``digest`` (:func:`grader_digest`): equal keys, equal results."""
    h = hashlib.sha256(json.dumps(digest, sort_keys=True).encode())
    src = Path(sub.source)
    h.update(f"\0{sub.student}\0{sub.problem}\0{sub.special}\0".encode("utf-8", "surrogateescape"))
    if sub.special:  # a link or special file where the hand-in should be: what it is, never its contents
        named = [(Path(src.name), None, sub.special)]
    elif file_kind(src) is None and src.is_dir():
        files, special, _ = _walk(src)
        named = [(p.relative_to(src), p, None) for p in files] + [(p.relative_to(src), None, k) for p, k in special]
    else:  # one file (the instructor's SUBMISSIONS may be a link to it: sub.images holds its target) and its manifest
        named = [(Path(Path(f).name), Path(f), None) for f in [*sub.images, sub.manifest_path] if f]
    for rel, path, what in sorted(named, key=lambda t: str(t[0])):
        h.update(b"\0file\0" + str(rel).encode("utf-8", "surrogateescape") + b"\0")
        if path is None:
            h.update(str(what).encode())
        else:
            _hash_file(h, path)
    return h.hexdigest()


def file_sha256(path: Path) -> str | None:
    """SHA-256 of a file's bytes, None when there is no such file."""
    try:
        return sha256_file(path)
    except OSError:
        return None


def result_row(res: StudentResult) -> dict:
    """What grades.csv and the summary need of a result (see :func:`row_result`)."""
    return {"status": res.status, "score": res.score, "max_score": res.max_score, "summary": res.summary,
            "elapsed": res.elapsed, "tests": [[t.name, t.score, t.max_score] for t in res.tests],
            "diagnosis": [d.get("mutant") for d in res.diagnosis[:1]]}


def row_result(student: str, row: dict) -> StudentResult:
    """A :class:`StudentResult` with what grades.csv and the summary read, from :func:`result_row`."""
    tests = [TestResult(n, n, float(s), float(m), "", "visible", "") for n, s, m in row["tests"]]
    return StudentResult(student, row["status"], float(row["score"]), float(row["max_score"]), tests, row["summary"],
                         diagnosis=[{"mutant": m} for m in row["diagnosis"]], elapsed=float(row["elapsed"]))


def utc_now() -> str:
    return dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")


@dataclass
class Run:
    """The record of this run, written to ``DIR/run.json`` after every change."""

    out: Path
    assignment: str
    digest: dict
    students: dict[str, dict] = field(default_factory=dict)
    pending: list[str] = field(default_factory=list)
    run: str = field(default_factory=lambda: secrets.token_hex(6))
    started: str = field(default_factory=utc_now)
    finished: str | None = None

    def save(self) -> None:
        write_json_atomic(self.out / RUN_FILE, {
            "schema": SCHEMA, "run": self.run, "started": self.started, "finished": self.finished,
            "complete": self.finished is not None and not self.pending, "assignment": self.assignment,
            "digest": self.digest, "pending": sorted(self.pending), "students": self.students})

    def record(self, res: StudentResult, key: str) -> None:
        self.students[res.student] = {"key": key, "run": self.run, "status": res.status, "score": res.score,
                                      "results_sha256": file_sha256(self.out / res.student / "results.json"),
                                      "row": result_row(res)}
        if res.student in self.pending:
            self.pending.remove(res.student)
        self.save()

    def results(self) -> list[StudentResult]:
        return [row_result(s, r["row"]) for s, r in sorted(self.students.items())]


def previous(out: Path, assignment: str) -> dict:
    """The students recorded by an earlier run of ``assignment`` in ``out`` (empty when there is none)."""
    try:
        data = json.loads((out / RUN_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return {}
    if not isinstance(data, dict) or data.get("schema") != SCHEMA or data.get("assignment") != assignment:
        return {}
    students = data.get("students")
    return students if isinstance(students, dict) else {}


def start(out: Path, assignment: str, digest: dict, keys: dict[str, str], *, fresh: bool) -> tuple[Run, dict[str, dict]]:
    """A new run over the students of ``keys``: the earlier results it keeps, and the run (saved, not finished)."""
    run = Run(out, assignment, digest)
    kept = {}
    for sid, rec in ({} if fresh else previous(out, assignment)).items():
        # Only results that graded the student: a timeout or a crash may not happen again (a busy machine).
        if (sid in keys and isinstance(rec, dict) and rec.get("key") == keys[sid] and rec.get("status") == "graded"
                and isinstance(rec.get("row"), dict) and rec.get("results_sha256") == file_sha256(out / sid / "results.json")):
            kept[sid] = rec
    run.students = dict(kept)
    run.pending = [s for s in keys if s not in kept]
    run.save()
    return run, kept


def commit(staging: Path, out: Path, student: str) -> None:
    """Move a student's files, complete, from ``staging`` into ``out/<student>/`` (each by an atomic rename)."""
    src, dst = staging / student, out / student
    dst.mkdir(parents=True, exist_ok=True)
    # results.json last: it is what counts; hidden names are the temporary files of a write that was cut short.
    names = sorted((n for n in os.listdir(src) if not n.startswith(".")), key=lambda n: n == "results.json")
    for name in names:
        os.replace(src / name, dst / name)
    with contextlib.suppress(OSError):
        src.rmdir()


@contextlib.contextmanager
def locked(out: Path):
    """Hold ``out/.lock`` for the run; RuntimeError when another ``mcrt grade`` holds it (released by the OS on death)."""
    import fcntl

    out.mkdir(parents=True, exist_ok=True)
    fd = os.open(out / LOCK_FILE, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            raise RuntimeError(f"{out}: another mcrt grade is writing to this folder") from None
        yield
    finally:
        os.close(fd)
