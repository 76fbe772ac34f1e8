"""Grading a class: discover submissions, prepare once, grade in parallel, summarise.

One class runner for both modes: image mode (:func:`image_plan`) and code mode
(:func:`mcrt.grade.codemode.code_plan`) differ only in the :class:`~mcrt.grade.run.Plan` they hand
:func:`grade_class` (the submissions, what a worker grades them with, the limits, the summary's note);
everything below holds for both. In code mode a worker runs each check of a student's module in a
sandboxed process of its own (bubblewrap ``--die-with-parent``, or the fallback's runner with its own
parent-death signal), so a ``kill -9`` of ``mcrt grade`` takes the workers and with them every sandbox.
Processes rather than threads for code mode too: one supervisor that can time out, replace and outlive a
worker (a thread can be neither killed nor bounded in memory), and the chain of parent-death signals.

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

A batch survives its own death. Workers die with the parent (``PR_SET_PDEATHSIG`` on Linux, set by each worker
before it imports anything; elsewhere they stop at the end of their student, when their input pipe closes).
Each student's files are written to ``DIR/.staging/`` and moved into ``DIR/<student>/`` only once complete; then
``DIR/run.json`` (:mod:`mcrt.grade.run`) records the student, their result and the key of what was graded (a
hash of the submission's files, the assignment, the grader's sources and the limits), and grades.csv and the
summary are rewritten: every row of grades.csv always agrees with that student's results.json, and until the
batch ends ``run.json`` and the summary say it is incomplete. A later ``mcrt grade`` into the same folder
keeps every result whose key still matches and grades only the students missing, changed or not graded
(a timeout, a crash; ``fresh=True``: all of them). One ``mcrt grade`` at a time writes into a folder (a
lock on ``DIR/.lock``).

Workers run with an address-space limit (``memory_mb``) and one BLAS/OpenMP
thread each, importing ``mcrt`` from where this process did (an installed
package or a checkout; never a folder named ``mcrt`` in the working folder,
such as an unpacked autograder's).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass, field
from multiprocessing.connection import wait
from pathlib import Path

from mcrt.grade import run as run_record
from mcrt.grade.run import DEFAULT_MEMORY_MB, Plan
from mcrt.grade._worker import criteria_of, grade_and_write, read_message, write_message
from mcrt.grade.assignment import Assignment
from mcrt.grade.expected import Context, prepare_context
from mcrt.grade.grader import STATUS_ERROR, STATUS_TIMEOUT, StudentResult, error_result
from mcrt.grade.outputs import write_class, write_student
from mcrt.grade.submissions import Submission, discover
from mcrt.util.progress import log

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


def image_plan(submissions, assignment: Assignment, *, timeout, cache_dir, single, student, context, memory_mb,
               log) -> Plan:
    """Image mode: the submissions' images, the prepared references, and the catalogue's power at the end."""
    subs = discover(submissions, single=single, student=student)
    log(f"mcrt grade: {len(subs)} submission(s) in {submissions}")
    ctx = context or prepare_context(assignment, cache_dir, log=log)
    src = ctx.references[assignment.camera].source
    log(f"reference: {src}; catalogue of {len(ctx.mutants)} bugs ready ({ctx.prepare_time:.1f} s)")

    def finish(results):
        from mcrt.grade.explain.catalogue import catalogue_power

        try:
            return "", catalogue_power(ctx)
        except Exception:  # noqa: BLE001 - a courtesy table; never stop the batch for it
            return "", None

    return Plan(subs, ctx, src, f"Reference: {src}.", timeout or assignment.timeout, memory_mb or DEFAULT_MEMORY_MB,
                image_context=ctx, finish=finish)


def grade_class(submissions: str | os.PathLike, assignment: Assignment, out: str | os.PathLike, *, jobs: int = 1,
                timeout: float | None = None, cache_dir=None, single: bool = False, student: str | None = None,
                context: Context | None = None, memory_mb: int | None = None, fresh: bool = False,
                mode: str = "image", allow_unisolated_code: bool = False, log=log) -> ClassResult:
    """Grade every submission under ``submissions`` into ``out`` (see the module docstring).

    ``jobs`` worker processes (0: grade in this process, without timeouts);
    ``timeout`` seconds per student (default: the assignment's; code mode: per check, default ``code.timeout``);
    ``memory_mb`` per worker (code mode: per student process, default ``code.memory_mb``); ``context``
    reuses a prepared :class:`~mcrt.grade.expected.Context`; ``fresh`` grades everyone again instead of keeping
    the unchanged results of an earlier run into ``out``; ``mode`` "code" grades Python modules in the sandbox
    (:mod:`mcrt.grade.codemode`; ``allow_unisolated_code``: even where nothing isolates them).
    """
    t0 = time.perf_counter()
    out = Path(out)
    log = log or (lambda s: None)
    with run_record.locked(out):
        opts = dict(timeout=timeout, cache_dir=cache_dir, single=single, student=student, context=context,
                    memory_mb=memory_mb, log=log)
        if mode == "code":
            from mcrt.grade.codemode import code_plan

            plan = code_plan(submissions, assignment, allow_unisolated_code=allow_unisolated_code, **opts)
        else:
            plan = image_plan(submissions, assignment, **opts)
        subs = plan.subs
        digest = run_record.grader_digest(assignment, reference_source=plan.source, timeout=plan.timeout,
                                          memory_mb=plan.memory_mb, **plan.digest)
        keys = {s.student: run_record.submission_key(s, digest) for s in subs}
        run, kept = run_record.start(out, assignment.name, digest, keys, fresh=fresh)
        note = plan.note
        odd = [f"{s.student} ({s.special})" for s in subs if getattr(s, "special", None)]
        if odd:  # links, FIFOs, devices where a hand-in should be: never opened, graded 0, and said here
            note += " Not regular files, never followed or opened (graded 0): " + ", ".join(odd) + "."
        if kept:
            log(f"kept {len(kept)} result(s) of an earlier run of {assignment.name} in {out} (unchanged submissions; "
                f"--fresh grades them again); grading the other {len(subs) - len(kept)}")

        def summarise(*, final: bool = False, power=None, extra: str = "") -> dict:
            return write_class(run.results(), assignment, out, elapsed=time.perf_counter() - t0,
                               context_note=f"{extra}{note}", criteria=plan.criteria, power=power,
                               pending=[] if final else sorted(run.pending) or None)

        summarise()

        def done(res: StudentResult) -> None:  # the student's files are complete in the staging folder
            run_record.commit(staging, out, res.student)
            run.record(res, keys[res.student])
            summarise()

        staging = out / run_record.STAGING
        shutil.rmtree(staging, ignore_errors=True)  # what a killed run left half-written
        todo = [s for s in subs if s.student not in kept]
        graded = run_pool(todo, plan.ctx, staging, jobs=jobs, timeout=plan.timeout, memory_mb=plan.memory_mb, log=log,
                          on_done=done, log_dir=out, already=len(kept), total=len(subs))
        shutil.rmtree(staging, ignore_errors=True)
        extra, power = plan.finish(graded)
        summary = summarise(final=True, power=power, extra=extra)
        run.finished = run_record.utc_now()  # last: a run killed before this line is resumed (with nothing left to do)
        run.save()
    by_id = {r.student: r for r in run.results()}  # the kept ones: what grades.csv holds of them
    by_id.update((r.student, r) for r in graded)  # this run's: everything
    return ClassResult([by_id[s.student] for s in subs], summary, out, time.perf_counter() - t0, plan.image_context)


# --------------------------------------------------------------------------
# The pool
# --------------------------------------------------------------------------


#: What a worker runs first, before any import of mcrt: ask the kernel to kill it when this process dies
#: (``prctl(PR_SET_PDEATHSIG, SIGKILL)``; Linux only), and stop at once if that has already happened.
_WORKER_BOOT = """\
import os, sys
if sys.platform.startswith("linux"):
    import ctypes, signal
    ctypes.CDLL(None, use_errno=True).prctl(1, int(signal.SIGKILL), 0, 0, 0)  # 1: PR_SET_PDEATHSIG
if os.getppid() != int(sys.argv[1]):
    os._exit(1)
import runpy
runpy.run_module("mcrt.grade._worker", run_name="__main__", alter_sys=True)
"""


def worker_command() -> list[str]:
    """The worker's command line: this interpreter (with ``-S`` if this one has it), ``-P`` so that the working
    folder (which may hold a folder named ``mcrt``) never shadows the package, and :data:`_WORKER_BOOT`, which
    ties the worker's life to this process before it runs ``mcrt.grade._worker``."""
    return [sys.executable, *(["-S"] if sys.flags.no_site else []), "-P", "-c", _WORKER_BOOT, str(os.getpid())]


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
            raise RuntimeError(f"a grading worker did not start within {STARTUP_TIMEOUT:g} s (see grading.log)")

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
             log=log, on_done=None, log_dir: Path | None = None, already: int = 0,
             total: int | None = None) -> list[StudentResult]:
    """Grade ``subs`` with ``jobs`` supervised workers; every student gets a result and a results.json in ``out``.

    ``on_done(result)`` is called in this process as each student's files are complete; ``grading.log`` goes to
    ``log_dir`` (default: ``out``); ``already`` of ``total`` students were graded before (for the progress lines).
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    tally = _Tally(len(subs), already=already, total=total, on_done=on_done, log=log)
    if jobs <= 0:
        for i, s in enumerate(subs):
            tally.done(i, grade_and_write(s, ctx, out))
        return tally.in_order()
    with open(Path(log_dir or out) / "grading.log", "ab") as log_file:
        pool = _Pool(ctx, out, tally, timeout=timeout, memory_mb=memory_mb, log_file=log_file)
        pool.run(list(enumerate(subs))[::-1], jobs=min(jobs, len(subs)))
    return tally.in_order()


class _Tally:
    """The results so far, by index: each one is passed to ``on_done``, then logged with the time left."""

    def __init__(self, n: int, *, already: int, total: int | None, on_done, log):
        self.n, self.already, self.on_done, self.log = n, already, on_done, log
        self.total = n + already if total is None else total
        self.results: dict[int, StudentResult] = {}
        self.t_start = time.monotonic()

    @property
    def complete(self) -> bool:
        return len(self.results) >= self.n

    def done(self, idx: int, res: StudentResult) -> None:
        self.results[idx] = res
        if self.on_done is not None:
            self.on_done(res)
        k = len(self.results)
        left = (time.monotonic() - self.t_start) / k * (self.n - k)
        self.log(f"  [{k + self.already}/{self.total}] {res.student}: {res.score:g}/{res.max_score:g} ({res.status}, "
                 f"{res.elapsed:.1f} s)" + (f"; about {left:.0f} s left" if k < self.n else ""))

    def in_order(self) -> list[StudentResult]:
        return [self.results[i] for i in range(self.n)]


class _Pool:
    """Workers grading into ``out``, supervised: a student whose worker dies or overruns ``timeout`` gets a zero
    result saying so, and the worker is replaced."""

    def __init__(self, ctx: Context, out: Path, tally: _Tally, *, timeout: float, memory_mb: int, log_file):
        self.ctx, self.out, self.tally = ctx, out, tally
        self.timeout, self.memory_mb, self.log_file = timeout, memory_mb, log_file

    def spawn(self) -> _Worker:
        return _Worker(self.ctx, self.out, self.memory_mb, self.log_file)

    def run(self, pending: list[tuple[int, Submission]], *, jobs: int) -> None:
        """Grade every (index, submission) of ``pending`` (taken from its end) with ``jobs`` workers, stopped after."""
        workers: list[_Worker] = []
        try:
            workers = [self.spawn() for _ in range(jobs)]
            for w in workers:
                if pending:
                    w.give(*pending.pop())
            while not self.tally.complete:
                ready = self.wait_ready(workers)
                for i, w in enumerate(workers):
                    if w.task is None:
                        continue
                    if self.collect(w, ready):
                        w.task = None
                        w.kill()
                        workers[i] = w = self.spawn()
                    if w.task is None and pending:
                        w.give(*pending.pop())
        finally:
            for w in workers:
                w.stop()

    def wait_ready(self, workers: list[_Worker]) -> list:
        """The busy workers' readable pipes, waited for until the first deadline (at least 0.05 s, at most 1 s)."""
        busy = [w for w in workers if w.task is not None]
        now = time.monotonic()
        wait_for = max(0.05, min(w.started + self.timeout - now for w in busy)) if busy else 0.05
        return wait([w.proc.stdout for w in busy], timeout=min(wait_for, 1.0))

    def collect(self, w: _Worker, ready: list) -> bool:
        """Take the result of a busy worker that sent one, or fail its student if it died or is over time; True when
        the worker must be replaced (dead, or still grading past the limit)."""
        if w.proc.stdout in ready:
            msg = w.receive()
            if msg is EOFError:
                code = w.proc.wait()
                self.fail(w, STATUS_ERROR, f"the grading process died while grading this submission (exit code {code}); "
                                           "the file may crash an image decoder or exceed the memory limit")
                return True
            if time.monotonic() - w.started > self.timeout:  # finished, but too late: the limit is the limit
                self.fail(w, STATUS_TIMEOUT, f"grading took longer than {self.timeout:g} s and was stopped")
            else:
                idx, res = msg
                res.elapsed = time.monotonic() - w.started
                self.tally.done(idx, res)
            w.task = None
            return False
        if time.monotonic() - w.started > self.timeout:
            self.fail(w, STATUS_TIMEOUT, f"grading took longer than {self.timeout:g} s and was stopped")
            return True
        return False

    def fail(self, w: _Worker, status: str, message: str) -> None:
        """A zero result for ``w``'s student, saying why, written like any other."""
        idx, sub = w.task
        a = self.ctx.assignment
        res = error_result(sub.student, a, status, message, criteria=criteria_of(self.ctx))
        res.elapsed = time.monotonic() - w.started
        write_student(res, a, self.out)
        self.tally.done(idx, res)


def grade_code_class(submissions, a: Assignment, out, **options) -> ClassResult:
    """Grade every student's module into ``out``: :func:`grade_class` in code mode (:mod:`mcrt.grade.codemode`)."""
    return grade_class(submissions, a, out, mode="code", **options)
