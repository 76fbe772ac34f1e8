"""Grading a class: discover submissions, prepare once, grade in parallel, summarise.

Students are graded by a small supervised pool of worker processes
(``python -m mcrt.grade._worker``: fresh interpreters, so no Dr.Jit or thread
state is inherited, and unlike ``multiprocessing``'s spawn method the
caller's ``__main__`` is never re-imported). Each worker takes one student at
a time and writes that student's ``results.json`` and ``feedback.html``
itself; their stderr goes to ``DIR/grading.log``. The parent watches
the clock: a student whose grading exceeds the timeout gets their worker
killed and replaced, and a zero ``results.json`` saying so; a worker that
dies (a crash in a native image decoder, the memory limit) is replaced the
same way. One bad submission never stops the batch. ``concurrent.futures``
is not used because it can neither cancel a running task nor survive a dead
worker (``BrokenProcessPool`` takes every pending student with it).

Workers run with an address-space limit (``memory_mb``) and one BLAS/OpenMP
thread each, importing ``mcrt`` from where this process did (an installed
package or a checkout; never a folder named ``mcrt`` in the working folder,
such as an unpacked autograder's).
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import time
from dataclasses import dataclass, field
from multiprocessing.connection import wait
from pathlib import Path

from mcrt.grade._worker import grade_and_write, read_message, write_message
from mcrt.grade.assignment import Assignment
from mcrt.grade.expected import Context, prepare_context
from mcrt.grade.grader import STATUS_ERROR, STATUS_TIMEOUT, StudentResult, error_result
from mcrt.grade.report import write_class, write_student
from mcrt.grade.submissions import Submission, discover

DEFAULT_MEMORY_MB = 4096
STARTUP_TIMEOUT = 300.0
_THREAD_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "NUMEXPR_NUM_THREADS": "1"}


@dataclass
class ClassResult:
    results: list[StudentResult]
    summary: dict
    out: Path
    elapsed: float
    context: Context | None = None
    problems: list[str] = field(default_factory=list)

    @property
    def all_graded(self) -> bool:
        return all(r.status == "graded" for r in self.results)


def _log_stderr(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def grade_class(submissions: str | os.PathLike, assignment: Assignment, out: str | os.PathLike, *, jobs: int = 1,
                timeout: float | None = None, cache_dir=None, single: bool = False, student: str | None = None,
                context: Context | None = None, memory_mb: int = DEFAULT_MEMORY_MB, log=_log_stderr) -> ClassResult:
    """Grade every submission under ``submissions`` into ``out`` (see the module docstring).

    ``jobs`` worker processes (0: grade in this process, without timeouts);
    ``timeout`` seconds per student (default: the assignment's); ``context``
    reuses a prepared :class:`~mcrt.grade.expected.Context`.
    """
    t0 = time.perf_counter()
    out = Path(out)
    subs = discover(submissions, single=single, student=student)
    log = log or (lambda s: None)
    log(f"mcrt grade: {len(subs)} submission(s) in {submissions}")
    ctx = context or prepare_context(assignment, cache_dir, log=log)
    src = ctx.references[assignment.camera].source
    log(f"reference: {src}; catalogue of {len(ctx.mutants)} bugs ready ({ctx.prepare_time:.1f} s)")
    results = run_pool(subs, ctx, out, jobs=jobs, timeout=timeout or assignment.timeout, memory_mb=memory_mb, log=log)
    elapsed = time.perf_counter() - t0
    note = f"Reference: {src}."
    odd = [f"{s.student} ({s.special})" for s in subs if getattr(s, "special", None)]
    if odd:  # links, FIFOs, devices where a hand-in should be: never opened, graded 0, and said here
        note += " Not regular files, never followed or opened (graded 0): " + ", ".join(odd) + "."
    from mcrt.grade.explain.catalogue import catalogue_power

    try:
        power = catalogue_power(ctx)
    except Exception:  # noqa: BLE001 - a courtesy table; never stop the batch for it
        power = None
    summary = write_class(results, assignment, out, elapsed=elapsed, context_note=note, power=power)
    return ClassResult(results, summary, out, elapsed, ctx)


# --------------------------------------------------------------------------
# The pool
# --------------------------------------------------------------------------


def worker_command() -> list[str]:
    """The worker's command line: this interpreter (with ``-S`` if this one has it), and ``-P`` so that the
    working folder (which may hold a folder named ``mcrt``) never shadows the package."""
    return [sys.executable, *(["-S"] if sys.flags.no_site else []), "-P", "-m", "mcrt.grade._worker"]


def worker_env() -> dict[str, str]:
    """The environment of a worker: one thread per library, and the folder this ``mcrt`` package was imported from
    first on PYTHONPATH, so that the worker runs the same code, installed or in a checkout."""
    import mcrt

    env = dict(os.environ, **_THREAD_ENV)
    home = str(Path(mcrt.__file__).resolve().parent.parent)
    env["PYTHONPATH"] = home + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


class _Worker:
    """One ``python -m mcrt.grade._worker`` process and the student it is grading."""

    def __init__(self, ctx: Context, out: Path, memory_mb: int, log_file):
        self.proc = subprocess.Popen(worker_command(), stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=log_file,
                                     env=worker_env())
        self.task: tuple[int, Submission] | None = None
        self.started = 0.0
        write_message(self.proc.stdin, (ctx, str(out), memory_mb))
        # Wait for the worker's imports, so that they do not count against the first student's time.
        if not wait([self.proc.stdout], timeout=STARTUP_TIMEOUT) or self.receive() != "ready":
            self.kill()
            raise RuntimeError(f"a grading worker did not start within {STARTUP_TIMEOUT:g} s (see {out / 'grading.log'})")

    def give(self, idx: int, sub: Submission) -> None:
        self.task = (idx, sub)
        self.started = time.monotonic()
        write_message(self.proc.stdin, (idx, sub))

    def receive(self):
        return read_message(self.proc.stdout)

    def kill(self) -> None:
        with contextlib.suppress(Exception):
            self.proc.kill()
        with contextlib.suppress(Exception):
            self.proc.wait(5)
        for f in (self.proc.stdin, self.proc.stdout):
            with contextlib.suppress(Exception):
                f.close()

    def stop(self) -> None:
        with contextlib.suppress(Exception):
            write_message(self.proc.stdin, None)
            self.proc.stdin.close()
        try:
            self.proc.wait(5)
        except subprocess.TimeoutExpired:
            self.kill()
        with contextlib.suppress(Exception):
            self.proc.stdout.close()


def run_pool(subs: list[Submission], ctx: Context, out: Path, *, jobs: int, timeout: float, memory_mb: int = DEFAULT_MEMORY_MB,
             log=_log_stderr) -> list[StudentResult]:
    """Grade ``subs`` with ``jobs`` supervised workers; every student gets a result and a results.json."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    a = ctx.assignment
    n = len(subs)
    results: dict[int, StudentResult] = {}

    def done(idx: int, res: StudentResult) -> None:
        results[idx] = res
        log(f"  [{len(results)}/{n}] {res.student}: {res.score:g}/{res.max_score:g} ({res.status}, {res.elapsed:.1f} s)")

    if jobs <= 0:
        for i, s in enumerate(subs):
            done(i, grade_and_write(s, ctx, out))
        return [results[i] for i in range(n)]

    pending = list(enumerate(subs))[::-1]
    log_file = open(out / "grading.log", "ab")  # noqa: SIM115 - closed in the finally below
    workers: list[_Worker] = []

    def fail(w: _Worker, status: str, message: str) -> None:
        idx, sub = w.task
        res = error_result(sub.student, a, status, message)
        res.elapsed = time.monotonic() - w.started
        write_student(res, a, out)
        done(idx, res)

    try:
        workers = [_Worker(ctx, out, memory_mb, log_file) for _ in range(min(jobs, n))]
        for w in workers:
            if pending:
                w.give(*pending.pop())
        while len(results) < n:
            busy = [w for w in workers if w.task is not None]
            now = time.monotonic()
            wait_for = max(0.05, min(w.started + timeout - now for w in busy)) if busy else 0.05
            ready = wait([w.proc.stdout for w in busy], timeout=min(wait_for, 1.0))
            for i, w in enumerate(workers):
                if w.task is None:
                    continue
                replace = False
                if w.proc.stdout in ready:
                    msg = w.receive()
                    if msg is EOFError:
                        code = w.proc.wait()
                        fail(w, STATUS_ERROR, f"the grading process died while grading this submission (exit code {code}); "
                                              "the file may crash an image decoder or exceed the memory limit")
                        replace = True
                    elif time.monotonic() - w.started > timeout:  # finished, but too late: the limit is the limit
                        fail(w, STATUS_TIMEOUT, f"grading took longer than {timeout:g} s and was stopped")
                        w.task = None
                    else:
                        idx, res = msg
                        res.elapsed = time.monotonic() - w.started
                        done(idx, res)
                        w.task = None
                elif time.monotonic() - w.started > timeout:
                    fail(w, STATUS_TIMEOUT, f"grading took longer than {timeout:g} s and was stopped")
                    replace = True
                if replace:
                    w.task = None
                    w.kill()
                    workers[i] = w = _Worker(ctx, out, memory_mb, log_file)
                if w.task is None and pending:
                    w.give(*pending.pop())
    finally:
        for w in workers:
            w.stop()
        log_file.close()
    return [results[i] for i in range(n)]
