"""A batch that survives its own death (issue 29, item 3), and what a hand-in's output may not forge (item 5).

``mcrt grade`` is started on a small class in a subprocess and killed with SIGKILL mid-run: no worker may
survive it, the output folder must say it is incomplete (run.json, summary.json, summary.md), every row of
grades.csv must agree with that student's results.json, and a second ``mcrt grade`` must grade only the
students the first did not finish. A changed submission is graded again, an unchanged one is not, and
``fresh`` grades everyone, a timeout is tried again. Images are 32 x 32 PFMs of the reference scaled and
with noise added: the grading itself is not what is tested here.
"""

from __future__ import annotations

import csv
import json
import os
import shutil
import signal
import struct
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import psutil
import pytest

from mcrt.grade.assignment import load_assignment
from mcrt.grade.batch import grade_class
from mcrt.grade.expected import prepare_context
from mcrt.grade.outputs import md_text, results_json, write_class
from mcrt.grade.grader import StudentResult, grade_image
from mcrt.grade.grader import TestResult as Criterion  # not collected as a test class
from mcrt.image_files import write_pfm

ASSIGNMENT = """name = "resume32"
title = "Resume test"
scene = {camera = "near", width = 32, height = 32, spp = 64, min_spp = 16}
grading = {tiles = [8, 16, 0], diagnosis_spp = 1024, reference_spp = 1024, timeout = 120}
"""
N_STUDENTS = 8
SEED = 29  # the students' images: arbitrary, but the same every run


@pytest.fixture(scope="module")
def context(tmp_path_factory, grade_cache):
    """The assignment, prepared once here, so that the commands below find the references in the run's cache."""
    d = tmp_path_factory.mktemp("resume")
    (d / "resume32.toml").write_text(ASSIGNMENT)
    return prepare_context(load_assignment(d / "resume32.toml"), grade_cache)


@pytest.fixture(scope="module")
def workdir(context):
    return Path(context.assignment.path).parent


@pytest.fixture(scope="module")
def assignment(context):
    return context.assignment


@pytest.fixture(scope="module")
def klass(workdir, context):
    d = workdir / "class"
    d.mkdir()
    ref = context.references[context.assignment.camera].mean
    g = np.random.default_rng(SEED)
    for k in range(N_STUDENTS):
        img = ref * (1 + 0.05 * k) + g.normal(0, 0.02, ref.shape)
        write_pfm(d / f"s{k}.pfm", img.astype(np.float32))
        (d / f"s{k}.toml").write_text("spp = 64\n")
    return d


def grade_cmd(workdir: Path, klass: Path, out: Path, *extra: str, cache: Path) -> list[str]:
    return [sys.executable, "-m", "mcrt.grade.cli", "grade", str(klass), "-a", str(workdir / "resume32.toml"), "-o", str(out),
            "--cache", str(cache), *extra]


def read_run(out: Path) -> dict:
    try:
        return json.loads((out / "run.json").read_text())
    except (OSError, ValueError):
        return {}


def running(pid: int) -> bool:
    try:
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def assert_all_die(pids: set[int], *, within: float = 10.0) -> None:
    """Every process of ``pids`` ends within ``within`` seconds (the kernel's moment to deliver a parent-death signal)."""
    t = time.monotonic()
    alive = set(pids)
    while alive and time.monotonic() - t < within:
        alive = {p for p in alive if running(p)}
        time.sleep(0.05)
    assert not alive, f"still running after the batch was killed: {alive}"


def assert_consistent(out: Path) -> list[dict]:
    """Every row of grades.csv agrees with that student's results.json and with run.json; returns the rows.

    A student is committed in order: results.json, then run.json, then grades.csv (rewritten from run.json). A kill
    can fall between the last two, so grades.csv may lack the one student being recorded, never hold one more.
    """
    with open(out / "grades.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    run = read_run(out)
    for row in rows:
        res = json.loads((out / row["student"] / "results.json").read_text())
        assert float(row["score"]) == pytest.approx(res["score"]), row["student"]
        assert row["status"] == res["extra_data"]["status"]
        assert run["students"][row["student"]]["score"] == pytest.approx(res["score"])
    listed, recorded = {r["student"] for r in rows}, set(run["students"])
    assert listed <= recorded and len(recorded - listed) <= 1, (listed, recorded)
    return rows


def test_a_killed_batch_stops_its_workers_says_it_is_incomplete_and_resumes(workdir, klass, context, grade_cache):
    out = workdir / "killed"
    proc = subprocess.Popen(grade_cmd(workdir, klass, out, "-j", "2", cache=grade_cache), stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE)
    workers: set[int] = set()
    try:
        deadline = time.monotonic() + 600
        while time.monotonic() < deadline and proc.poll() is None:
            workers |= {c.pid for c in psutil.Process(proc.pid).children(recursive=True)}
            run = read_run(out)
            if run.get("students") and run.get("pending"):
                break
            time.sleep(0.02)
        assert proc.poll() is None, "the batch ended before it could be killed: " + proc.stderr.read().decode()[-2000:]
        workers |= {c.pid for c in psutil.Process(proc.pid).children(recursive=True)}
        proc.send_signal(signal.SIGKILL)
        proc.wait(30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert len(workers) >= 2
    # No worker outlives the batch (PR_SET_PDEATHSIG).
    assert_all_die(workers)

    run = read_run(out)
    assert run["complete"] is False and run["finished"] is None and run["pending"]
    first_run, graded_first = run["run"], set(run["students"])
    summary = json.loads((out / "summary.json").read_text())
    assert summary["complete"] is False and summary["pending"]
    assert (out / "summary.md").read_text().splitlines()[2].startswith("**Incomplete:**")
    rows = assert_consistent(out)
    assert 1 <= len(rows) < N_STUDENTS

    # A second run grades only the students the first did not finish.
    r = subprocess.run(grade_cmd(workdir, klass, out, "-j", "2", cache=grade_cache), capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    run = read_run(out)
    assert run["complete"] is True and not run["pending"] and run["finished"]
    assert {s for s, rec in run["students"].items() if rec["run"] == first_run} == graded_first
    assert {s for s, rec in run["students"].items() if rec["run"] == run["run"]} == {f"s{k}" for k in range(N_STUDENTS)} - graded_first
    assert f"kept {len(graded_first)} result(s) of an earlier run" in r.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["complete"] is True and summary["students"] == N_STUDENTS
    assert "Incomplete" not in (out / "summary.md").read_text()
    assert len(assert_consistent(out)) == N_STUDENTS
    assert not (out / ".staging").exists()


@pytest.fixture
def small(klass, tmp_path):
    """Three of the students, in a folder of the test's own (in-process runs below: no start-up to wait for)."""
    d = tmp_path / "small"
    d.mkdir()
    for k in range(3):
        for ext in (".pfm", ".toml"):
            shutil.copy2(klass / f"s{k}{ext}", d / f"s{k}{ext}")
    return d


def graded_by(run: dict) -> set[str]:
    """The students the run of ``run`` graded itself (not kept from an earlier one)."""
    return {s for s, rec in run["students"].items() if rec["run"] == run["run"]}


_PARENT = """\
import subprocess, sys, time
from mcrt.grade.batch import worker_command, worker_env
w = subprocess.Popen(worker_command(), stdin=int(sys.argv[1]), stdout=subprocess.DEVNULL, env=worker_env())
print(w.pid, flush=True)
time.sleep(600)
"""


def test_a_worker_dies_with_its_parent_even_with_its_input_open():
    """Its input pipe's other end is held here, so only the kernel's parent-death signal can end the worker."""
    r, w = os.pipe()
    parent = subprocess.Popen([sys.executable, "-c", _PARENT, str(r)], pass_fds=(r,), stdout=subprocess.PIPE)
    os.close(r)
    worker = None
    try:
        worker = int(parent.stdout.readline())
        assert running(worker)
        parent.kill()
        parent.wait(30)
        t = time.monotonic()
        while running(worker) and time.monotonic() - t < 10:
            time.sleep(0.05)
        assert not running(worker), "the worker outlived its parent"
    finally:
        os.close(w)
        parent.kill()
        if worker is not None and running(worker):
            os.kill(worker, signal.SIGKILL)


def test_only_changed_submissions_are_graded_again_and_fresh_grades_all(small, context, tmp_path):
    out = tmp_path / "out"
    grade_class(small, context.assignment, out, jobs=0, context=context, log=None)
    first = read_run(out)
    # s1's render changes; s2's manifest changes: both are graded again, s0 is not.
    img = (small / "s1.pfm").read_bytes()
    (small / "s1.pfm").write_bytes(img[:-4] + struct.pack("<f", 0.5))
    (small / "s2.toml").write_text("spp = 32\n")
    grade_class(small, context.assignment, out, jobs=0, context=context, log=None)
    second = read_run(out)
    assert graded_by(second) == {"s1", "s2"}
    assert second["students"]["s0"]["run"] == first["run"]
    assert_consistent(out)
    # fresh (--fresh): everyone.
    grade_class(small, context.assignment, out, jobs=0, context=context, log=None, fresh=True)
    assert graded_by(read_run(out)) == {"s0", "s1", "s2"}
    assert_consistent(out)


def test_students_not_graded_are_tried_again(small, context, tmp_path):
    """A timeout may come from a busy machine: a later run grades those students again, whatever their key."""
    out = tmp_path / "out"
    for f in [*small.glob("s1.*"), *small.glob("s2.*")]:  # one student: each timeout costs a worker's start-up
        f.unlink()
    for _ in range(2):
        res = grade_class(small, context.assignment, out, jobs=1, timeout=0.001, context=context, log=None)
        assert [r.status for r in res.results] == ["timeout"]
        run = read_run(out)
        assert graded_by(run) == {"s0"} and run["complete"]
        assert_consistent(out)


def test_a_results_json_not_as_recorded_is_graded_again(small, context, tmp_path):
    """A run killed between moving a student's files and recording them leaves a results.json run.json does not
    vouch for: that student is graded again."""
    out = tmp_path / "out"
    grade_class(small, context.assignment, out, jobs=0, context=context, log=None)
    first = read_run(out)
    p = out / "s2" / "results.json"
    p.write_text(p.read_text().replace('"score"', '"score" ', 1))
    grade_class(small, context.assignment, out, jobs=0, context=context, log=None)
    second = read_run(out)
    assert graded_by(second) == {"s2"}
    assert second["students"]["s1"]["run"] == first["run"]
    assert_consistent(out)


def test_two_runs_into_one_folder_are_refused(workdir, klass, context, grade_cache):
    import fcntl

    out = workdir / "locked"
    out.mkdir()
    fd = os.open(out / ".lock", os.O_RDWR | os.O_CREAT)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        r = subprocess.run(grade_cmd(workdir, klass, out, "-q", cache=grade_cache), capture_output=True, text=True, timeout=600)
    finally:
        os.close(fd)
    assert r.returncode == 2
    assert "another mcrt grade is writing to this folder" in r.stderr


# -- what a student's text may not do to the Markdown around it ------------------

HOSTILE = ("fine\n~~~~\n# Live heading\n[a link](http://evil.example)\n![remote](http://evil.example/x.png)\n"
           "```\n<script>alert(1)</script>\n````\n")


def _outside_fences(md: str) -> list[str]:
    """The lines of ``md`` outside fenced code blocks, by CommonMark's rules for fences."""
    lines, fence, outside = md.split("\n"), None, []
    for ln in lines:
        s = ln.lstrip(" ")
        indent = len(ln) - len(s)
        if fence is None:
            if indent <= 3 and (s.startswith("```") or s.startswith("~~~")):
                ch = s[0]
                fence = (ch, len(s) - len(s.lstrip(ch)))
                continue
            outside.append(ln)
        elif indent <= 3 and s.rstrip() and set(s.rstrip()) == {fence[0]} and len(s.rstrip()) >= fence[1]:
            fence = None
    return outside


def assert_inert(md: str) -> None:
    for ln in _outside_fences(md):
        assert not ln.lstrip().startswith("#"), ln
        assert "](" not in ln.replace("\\]", ""), ln
        assert "<script" not in ln.replace("\\<", ""), ln


def test_student_text_cannot_break_out_of_the_markdown_fence(assignment):
    t = Criterion("readable", "File readable", 0.0, 5.0, HOSTILE, "visible", "failed")
    res = StudentResult("mallory", "graded", 0.0, 5.0, [t], "Graded: " + HOSTILE.replace("\n", " "),
                        notes=[HOSTILE, "one line # [x](http://evil.example) ![i](http://e/i.png) <b>bold</b> &amp;"])
    data = results_json(res, assignment)
    assert_inert(data["output"])
    for test in data["tests"]:
        assert_inert(test["output"])
    assert "# Live heading" in data["output"]  # still shown, as text in the block


def test_md_text_fences_any_backtick_run():
    for text in (HOSTILE, "a\n`````\n# h", "a\r~~~~\r# h\r[x](http://e)"):
        assert_inert(md_text(text))


def test_summary_md_escapes_the_reasons(assignment, tmp_path):
    res = StudentResult("mallory", "error", 0.0, 5.0, [], "# Pwned [x](http://evil.example)\n![i](http://e/i.png)")
    write_class([res], assignment, tmp_path)
    line = [ln for ln in (tmp_path / "summary.md").read_text().splitlines() if "mallory" in ln]
    assert len(line) == 1  # one line, whatever the reason holds
    assert_inert(line[0])


def test_an_empty_image_is_the_hand_ins_problem_not_the_graders(context):
    for shape in [(0, 0, 3), (32, 0, 3), (0, 32, 3), (32, 32)]:
        r = grade_image("s", context, [np.zeros(shape)], spp=64)
        assert r.status == "graded" and r.score == 0
        readable = next(t for t in r.tests if t.name == "readable")
        assert readable.status == "failed" and f"shape {shape}" in readable.output
