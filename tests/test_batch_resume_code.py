"""Code mode's batch survives its own death too (issue 29, item 3; issue 30: one class runner for both modes).

``mcrt grade --mode code`` is started on four tiny modules (one check, the cosine sampler), with the last
student's module sleeping inside its sandbox, and killed with SIGKILL while that sandbox runs: no worker and no
sandbox process (bubblewrap, or the fallback's runner in a session of its own) may outlive it, run.json must say
the run is incomplete, grades.csv must agree with the results.json files, and a second run must grade only the
student it did not finish and the one whose module changed since.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest
from test_batch_resume import assert_all_die, assert_consistent, graded_by, read_run  # tests/ is on sys.path

from mcrt.grade import codemode

ASSIGNMENT = """name = "coderesume"
title = "Code-mode resume test"
scene = {camera = "near", width = 32, height = 32, spp = 64}

[code]
timeout = 60
memory_mb = 1024

[code.checks.sample_cosine_hemisphere]
points = 10
samples = 20000
"""

COSINE = """import numpy as np
{extra}

def sample_cosine_hemisphere(u1, u2):
    {stall}
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    return np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(0.0, 1 - u1))], axis=1)
"""
STUDENTS = ("s0", "s1", "s2", "s3")
SLEEPER = "s3"  # graded last (-j 1): its sandbox is running when the grader is killed


def module(*, stall: bool = False, extra: str = "") -> str:
    return COSINE.format(extra="import time" + extra if stall else extra, stall="time.sleep(50)" if stall else "pass")


def sandbox_kinds():
    kinds = [pytest.param("fallback", id="fallback")]
    kinds.append(pytest.param("bwrap", id="bwrap", marks=pytest.mark.skipif(shutil.which("bwrap") is None,
                                                                            reason="bubblewrap is not installed")))
    return kinds


def grade_cmd(tmp_path: Path, out: Path) -> list[str]:
    return [sys.executable, "-m", "mcrt.grade.cli", "grade", str(tmp_path / "class"), "--mode", "code",
            "-a", str(tmp_path / "coderesume.toml"), "-o", str(out), "-j", "1"]


def sandbox_processes(pids: set[int]) -> set[int]:
    """Those of ``pids`` that run student code: bwrap, or the runner (mcrt/grade/_sandbox.py, /sandbox/runner.py)."""
    found = set()
    for pid in pids:
        try:
            cmd = " ".join(psutil.Process(pid).cmdline())
        except psutil.Error:
            continue
        if "bwrap" in cmd or "_sandbox.py" in cmd or "runner.py" in cmd:
            found.add(pid)
    return found


@pytest.mark.parametrize("kind", sandbox_kinds())
def test_a_killed_code_batch_leaves_no_sandbox_running_and_resumes(tmp_path, kind):
    (tmp_path / "coderesume.toml").write_text(ASSIGNMENT)
    klass = tmp_path / "class"
    klass.mkdir()
    for sid in STUDENTS:
        (klass / f"{sid}.py").write_text(module(stall=sid == SLEEPER))
    out = tmp_path / "out"
    env = {**os.environ, codemode.SANDBOX_ENV: kind}
    proc = subprocess.Popen(grade_cmd(tmp_path, out), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
    tree: set[int] = set()
    sandboxes: set[int] = set()
    try:
        deadline = time.monotonic() + 300
        while time.monotonic() < deadline and proc.poll() is None:
            tree |= {c.pid for c in psutil.Process(proc.pid).children(recursive=True)}
            sandboxes |= sandbox_processes(tree)
            if read_run(out).get("pending") == [SLEEPER] and sandboxes:
                break
            time.sleep(0.05)
        assert proc.poll() is None, "the batch ended before it could be killed: " + proc.stderr.read().decode()[-2000:]
        time.sleep(0.5)  # the sleeper's module is running inside its sandbox now
        tree |= {c.pid for c in psutil.Process(proc.pid).children(recursive=True)}
        sandboxes |= sandbox_processes(tree)
        proc.send_signal(signal.SIGKILL)
        proc.wait(30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert sandboxes, "no sandbox process was seen running"
    assert_all_die(tree)  # workers, bwrap and runners alike

    run = read_run(out)
    assert run["complete"] is False and run["finished"] is None and run["pending"] == [SLEEPER]
    first = run["run"]
    assert len(assert_consistent(out)) == len(STUDENTS) - 1
    assert not (out / SLEEPER / "results.json").exists()

    # The sleeper wakes up, s1 changes: a second run grades those two only.
    (klass / f"{SLEEPER}.py").write_text(module())
    (klass / "s1.py").write_text(module(extra="# resubmitted"))
    r = subprocess.run(grade_cmd(tmp_path, out), capture_output=True, text=True, timeout=300, env=env)
    assert r.returncode == 0, r.stderr[-3000:]
    run = read_run(out)
    assert run["complete"] is True and not run["pending"] and run["finished"]
    assert graded_by(run) == {"s1", SLEEPER}
    assert {s for s, rec in run["students"].items() if rec["run"] == first} == {"s0", "s2"}
    assert "kept 2 result(s) of an earlier run" in r.stderr
    rows = assert_consistent(out)
    assert len(rows) == len(STUDENTS) and all(float(row["score"]) == 10 for row in rows), rows
    assert not (out / ".staging").exists()
