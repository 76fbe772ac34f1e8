"""Code mode never runs student code as root and bounds a whole submission, with bubblewrap and without (issue 29).

Each test is a student module that tries one attack, run through
:func:`mcrt.grade.codemode.run_student` on both paths: bubblewrap, and the
fallback without it (Landlock, seccomp, an unprivileged uid, a new
session), chosen by ``MCRT_SANDBOX`` as the grader honours it. Here the
Python installation sits under /root (mode 0700), so the fallback's switch
to an unprivileged uid is tested where file modes would have stopped the old
one. Without bubblewrap or Landlock a path is skipped with a message, except
under CI (``CI`` set), where that is a failure.
"""

from __future__ import annotations

import json
import os
import shutil
import socket
import subprocess
import sys
import textwrap
import time
import uuid
from pathlib import Path

import numpy as np
import pytest
from test_sandbox import _find_comm  # tests/ is on sys.path (pytest's default import mode)

from mcrt.grade import codemode
from mcrt.grade.batch import grade_code_class

REPO = Path(__file__).resolve().parent.parent
MCRT = [sys.executable, "-c", "import sys; from mcrt.cli import main; sys.exit(main(sys.argv[1:]))"]


def _need(ok: bool, why: str) -> None:
    if not ok:
        if os.environ.get("CI"):
            pytest.fail(why)
        pytest.skip(why)


@pytest.fixture(params=["bubblewrap", "fallback"])
def path(request, monkeypatch):
    """The sandbox of one path, probed and self-tested afresh."""
    if request.param == "bubblewrap":
        _need(shutil.which("bwrap") is not None, "bubblewrap is not installed (apt-get install bubblewrap)")
    monkeypatch.setenv(codemode.SANDBOX_ENV, "bwrap" if request.param == "bubblewrap" else "fallback")
    monkeypatch.setattr(codemode, "_ISOLATION", None)
    try:
        iso = codemode.isolation()
    except codemode.SandboxError as e:
        _need(False, f"the {request.param} path is not available here: {e}")
    assert iso.kind == request.param
    return iso


def _module(folder: Path, body: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    p = folder / "solution.py"
    p.write_text("import ctypes, os, sys, time\nimport numpy as np\nlibc = ctypes.CDLL(None, use_errno=True)\n"
                 + textwrap.dedent(body))
    return p


def _run(mod: Path, *, memory_mb=1024, timeout=20):
    res = codemode.run_student(mod, mod.name, "f", [{"args": [1.0]}], {}, timeout=timeout, memory_mb=memory_mb)
    assert res.outputs and res.outputs[0] is not None, res
    return res, res.outputs[0].tolist()


# --------------------------------------------------------------------------
# Never root
# --------------------------------------------------------------------------


def test_student_code_runs_unprivileged(path, tmp_path):
    mod = _module(tmp_path / "eve", """
        def f(x):
            caps = [ln.split()[1] for ln in open("/proc/self/status") if ln.startswith(("CapEff", "CapPrm"))]
            return np.array([*os.getresuid(), *os.getresgid(), len(os.getgroups()), *(float(int(c, 16)) for c in caps)])
        """)
    res, out = _run(mod)
    assert min(out[:6]) > 0, f"uids/gids {out[:6]}"
    assert out[6:] == [0.0, 0.0, 0.0], f"groups and capabilities {out[6:]}"
    assert "unprivileged" in res.sandbox["user"] or os.geteuid() != 0


def test_etc_shadow_setuid_files_xattrs_and_the_hostname_are_refused(path, tmp_path):
    mod = _module(tmp_path / "eve", """
        def f(x):
            out = []
            fd = libc.open(b"/etc/shadow", 0)
            out.append(1.0 if fd >= 0 else 0.0)
            fd = libc.open(b"made", 0o101, 0o755)  # O_CREAT | O_WRONLY, in the work folder
            chown = libc.fchown(fd, 0, 0) if fd >= 0 else -1
            chmod = libc.fchmod(fd, 0o4755) if fd >= 0 else -1
            st = os.stat("made") if os.path.exists("made") else None
            out.append(1.0 if st is not None and st.st_uid == 0 and st.st_mode & 0o4000 else 0.0)
            out.append(float(chown))
            for name in (b"trusted.mcrt", b"security.mcrt"):
                out.append(float(libc.setxattr(b"made", name, b"x", 1, 0)))
            out.append(float(libc.sethostname(b"owned", 5)))
            return np.array(out)
        """)
    before = socket.gethostname()
    try:
        _, out = _run(mod)
    finally:
        if socket.gethostname() != before:  # a sandbox that let it through renamed this machine: undo, then fail
            subprocess.run(["hostname", before], check=False)
            pytest.fail(f"the student's module renamed the host to {socket.gethostname()!r}")
    assert out[0] == 0.0, "/etc/shadow was opened"
    assert out[1] == 0.0, "a setuid-root file was made"
    assert out[2:] == [-1.0] * 4, f"fchown, setxattr or sethostname succeeded: {out[2:]}"


def test_a_double_fork_and_setsid_does_not_outlive_the_call(path, tmp_path):
    token = "mcrt" + uuid.uuid4().hex[:10]
    mod = _module(tmp_path / "eve", f"""
        def f(x):
            pid = libc.fork()
            if pid == 0:
                libc.setsid()
                if libc.fork() != 0:
                    libc._exit(0)
                libc.prctl(15, {token.encode()!r}, 0, 0, 0)
                while True:
                    libc.sleep(1)
            return np.array([float(pid)])
        """)
    try:
        _, out = _run(mod)
        time.sleep(1.0)
        assert _find_comm(token) == [], "a process forked by the student outlived its call"
        assert out[0] == -1.0, "fork succeeded: one submission is no longer one process"
    finally:
        for pid in _find_comm(token):
            os.kill(pid, 9)


def test_memory_is_bounded_over_the_whole_submission(path, tmp_path):
    """Threads share one address-space limit; fork, memfd and System V shared memory (outside every rlimit) are refused."""
    mod = _module(tmp_path / "eve", """
        import threading
        kept = []
        def grab():
            try:
                kept.append(np.ones(25 << 20))  # 200 MiB each
            except MemoryError:
                pass
        def f(x):
            ts = [threading.Thread(target=grab) for _ in range(4)]
            for t in ts:
                t.start()
            for t in ts:
                t.join()
            memfd = libc.syscall(319 if os.uname().machine == "x86_64" else 279, b"x", 0)
            shm = libc.shmget(0, 64 << 20, 0o1600)  # IPC_PRIVATE, IPC_CREAT | 0600: would outlive the call
            if shm >= 0:
                libc.shmctl(shm, 0, None)  # IPC_RMID: leave nothing behind even when the test fails
            return np.array([len(kept) * 200.0, float(libc.fork()), float(memfd), float(shm)])
        """)
    _, out = _run(mod, memory_mb=512)
    assert out[0] < 512, f"{out[0]:g} MiB held under a 512 MiB limit"
    assert out[1:] == [-1.0] * 3, f"fork {out[1]:g}, memfd_create {out[2]:g}, shmget {out[3]:g}"


def test_the_wall_clock_limit_stops_every_thread_of_the_submission(path, tmp_path):
    token = "mcrt" + uuid.uuid4().hex[:10]
    mod = _module(tmp_path / "eve", f"""
        import threading
        def spin():
            libc.prctl(15, {token.encode()!r}, 0, 0, 0)
            while True:
                libc.sleep(1)
        def f(x):
            threading.Thread(target=spin, daemon=False).start()
            libc.setsid()
            spin()
        """)
    t0 = time.monotonic()
    try:
        res = codemode.run_student(mod, mod.name, "f", [{"args": [1.0]}], {}, timeout=3, memory_mb=1024)
        assert time.monotonic() - t0 < 15
        assert "time limit" in res.message and not res.grader_fault, res
        time.sleep(0.5)
        assert _find_comm(token) == [], "a thread of the student's process outlived the time limit"
    finally:
        for pid in _find_comm(token):
            os.kill(pid, 9)


def test_the_work_folder_bounds_the_number_of_files(path, tmp_path):
    mod = _module(tmp_path / "eve", """
        def f(x):
            n = 0
            for i in range(20000):
                fd = libc.open(f"f{i}".encode(), 0o101, 0o644)
                if fd < 0:
                    break
                libc.close(fd)
                n += 1
            return np.array([float(n)])
        """)
    _, out = _run(mod, timeout=60)
    if path.kind == "bubblewrap" and os.geteuid() == 0:
        assert 0 < out[0] <= codemode.INODE_LIMIT, f"{out[0]:g} files made"
    else:
        assert out[0] <= codemode.INODE_LIMIT, f"{out[0]:g} files made"


# --------------------------------------------------------------------------
# What the sandbox shows and records
# --------------------------------------------------------------------------


def test_mitsuba_drjit_and_mcrt_cannot_be_imported(path, tmp_path):
    """Not imported, even with the import hook removed, and no file of theirs readable by any path to it.

    The paths include those through links (a venv's ``lib64 -> lib``, which
    once granted all of ``lib`` to Landlock) from wherever the grader's
    packages are: the checkout's .venv, a venv elsewhere, site-packages.
    """
    import drjit
    import mitsuba

    import mcrt

    homes = sorted({str(Path(m.__file__).parent.parent) for m in (mcrt, drjit, mitsuba)} | {sys.prefix}
                   | {p for p in sys.path if p.endswith(("site-packages", "dist-packages"))})
    mod = _module(tmp_path / "eve", f"""
        import glob
        HOMES = {homes!r}

        def readable():
            found = []
            for home in HOMES + [sys.prefix]:
                for depth in range(4):  # home/drjit ... home/lib64/python3.11/site-packages/drjit, through links
                    for name in ("mitsuba", "drjit", "mcrt"):
                        for p in glob.glob(os.path.join(home, *["*"] * depth, name, "__init__.py")):
                            try:
                                with open(p, "rb") as fh:
                                    fh.read(1)
                                found.append(p)
                            except OSError:
                                pass
            return found

        def f(x):
            out = [float(len(readable()))]
            if out[0]:
                print("readable:", readable())
            for name in ("mitsuba", "drjit", "mcrt"):
                try:
                    __import__(name)
                    out.append(1.0)
                except Exception:
                    out.append(0.0)
            sys.meta_path[:] = [m for m in sys.meta_path if getattr(m, "__name__", "") != "_Hidden"]
            for name, attr in (("mitsuba", "set_variant"), ("drjit", "llvm"), ("mcrt", "render")):
                try:
                    out.append(1.0 if hasattr(__import__(name), attr) else 0.0)
                except Exception:
                    out.append(0.0)
            return np.array(out)
        """)
    res, out = _run(mod)
    assert out == [0.0] * 7, (out, res.stdout)
    assert any("mitsuba" in v for v in res.violations), res.violations


def test_refusals_are_recorded_outside_the_student_process(path, tmp_path):
    mod = _module(tmp_path / "eve", """
        import __main__
        def f(x):
            try:
                os.system("true")
            except PermissionError:
                pass
            for name in ("VIOLATIONS",):
                getattr(__main__, name, []).clear()
            return np.array([1.0])
        """)
    res, _ = _run(mod)
    assert any("os.system" in v for v in res.violations), res.violations


def test_bwrap_command_line_is_not_shown_at_proc_1(tmp_path, monkeypatch):
    _need(shutil.which("bwrap") is not None, "bubblewrap is not installed (apt-get install bubblewrap)")
    monkeypatch.setenv(codemode.SANDBOX_ENV, "bwrap")
    monkeypatch.setattr(codemode, "_ISOLATION", None)
    codemode.isolation()
    mod = _module(tmp_path / "eve", """
        def f(x):
            data = open("/proc/1/cmdline", "rb").read()
            return np.frombuffer(data.ljust(4096, b"\\0")[:4096], dtype=np.uint8).astype(float)
        """)
    _, out = _run(mod)
    shown = bytes(int(v) for v in out).rstrip(b"\0").split(b"\0")
    assert b"--ro-bind" not in shown and b"--tmpfs" not in shown, shown
    assert not any(str(REPO).encode() in a and b"python" not in a for a in shown), shown


def test_a_sandbox_failing_before_the_module_is_the_graders_fault(tmp_path, monkeypatch):
    """A runner that cannot start (here: no Python bound) is reported as the grader's, not the student's."""
    _need(shutil.which("bwrap") is not None, "bubblewrap is not installed (apt-get install bubblewrap)")
    monkeypatch.setenv(codemode.SANDBOX_ENV, "bwrap")
    monkeypatch.setattr(codemode, "_ISOLATION", None)
    monkeypatch.setattr(codemode, "_python_roots", lambda: [])
    with pytest.raises(codemode.SandboxError, match="grader's installation"):
        codemode.isolation()
    iso = codemode.Isolation("bubblewrap", "", shutil.which("bwrap"), frozenset({"--size", "--perms", "--args"}))
    mod = _module(tmp_path / "eve", "def f(x):\n    return np.zeros(1)\n")
    res = codemode._run_student(iso, mod, mod.name, "f", [{"args": [1.0]}], {}, timeout=20, memory_mb=1024)
    assert res.grader_fault and "grader" in res.message, res
    monkeypatch.undo()
    monkeypatch.setattr(codemode, "_ISOLATION", None)
    bad = _module(tmp_path / "bob", "import numpyy\ndef f(x):\n    return 1\n")
    res = codemode.run_student(bad, bad.name, "f", [{"args": [1.0]}], {}, timeout=20, memory_mb=1024)
    assert not res.grader_fault and "numpyy" in res.errors[0], res


# --------------------------------------------------------------------------
# No isolation: refused unless the instructor allows it, and never as root then either
# --------------------------------------------------------------------------


def test_no_isolation_refuses_code_mode_unless_allowed(tmp_path, monkeypatch):
    monkeypatch.setenv(codemode.SANDBOX_ENV, "none")
    monkeypatch.setattr(codemode, "_ISOLATION", None)
    monkeypatch.setattr(codemode, "_ALLOW_UNISOLATED", False)
    with pytest.raises(codemode.SandboxError, match="code mode refused.*--allow-unisolated-code"):
        codemode.isolation()
    mod = _module(tmp_path / "eve", "def f(x):\n    return np.array([float(os.getuid())])\n")
    with pytest.raises(codemode.SandboxError):
        codemode.run_student(mod, mod.name, "f", [{"args": [1.0]}], {}, timeout=20, memory_mb=1024)
    codemode.allow_unisolated(True)
    _, out = _run(mod)
    assert out[0] != 0.0 or os.geteuid() != 0


SMALL = """format = 1
name = "sbx"
title = "sandbox"
[scene]
camera = "near"
width = 32
height = 32
spp = 64
[code]
timeout = 20
memory_mb = 1024
[code.checks.sample_cosine_hemisphere]
points = 10
"""

NOT_AS_ROOT = """import os
import numpy as np

def sample_cosine_hemisphere(u1, u2):
    if os.getuid() == 0 or os.geteuid() == 0:
        raise RuntimeError("running as root")
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    return np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(0.0, 1 - u1))], axis=1)
"""


def test_grade_refuses_code_mode_without_isolation_unless_the_flag_allows_it(tmp_path):
    (tmp_path / "class").mkdir()
    (tmp_path / "class" / "good.py").write_text(NOT_AS_ROOT)
    (tmp_path / "small.toml").write_text(SMALL)
    env = {**os.environ, codemode.SANDBOX_ENV: "none"}
    cmd = [*MCRT, "grade", str(tmp_path / "class"), "-a", str(tmp_path / "small.toml"), "--mode", "code",
           "-o", str(tmp_path / "out"), "-q"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=120, env=env, cwd=tmp_path)
    assert p.returncode == 2, p.stderr
    assert "code mode refused" in p.stderr and "--allow-unisolated-code" in p.stderr
    assert not (tmp_path / "out" / "good" / "results.json").exists()
    p = subprocess.run([*cmd, "--allow-unisolated-code"], capture_output=True, text=True, timeout=120, env=env, cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert "NOT isolated" in p.stderr
    res = json.loads((tmp_path / "out" / "good" / "results.json").read_text())
    assert res["score"] == 10, res  # its check raises if it runs as root
    helptext = subprocess.run([*MCRT, "grade", "--help"], capture_output=True, text=True, timeout=60, cwd=tmp_path).stdout
    assert "--allow-unisolated-code" in helptext and "default: off" in " ".join(helptext.split())


# --------------------------------------------------------------------------
# Whose fault: a student's odd result is the student's
# --------------------------------------------------------------------------


def test_an_empty_render_is_the_students_error_not_the_graders():
    from mcrt.grade.assignment import assignment_from_dict

    a = assignment_from_dict({"name": "sbx", "title": "sandbox", "scene": {"camera": "near", "width": 32, "height": 32, "spp": 64},
                              "code": {"timeout": 20, "memory_mb": 1024, "checks": {"render": {"points": 10}}}})
    params = a.code.checks[0].params

    def run(function, calls, arrays, first_of_tuple=False):
        return codemode.CallResult(True, [np.zeros((0, 0, 3)) for _ in calls], [None for _ in calls])

    out, sr = codemode.check_render(run, params, a, None, {})
    assert out.fraction == 0.0 and sr is None
    assert "render returned shape (0, 0, 3), expected (32, 32, 3)" in out.message


def test_a_module_every_student_fails_to_import_is_reported_as_the_graders_problem(tmp_path, monkeypatch, capsys):
    """SciPy hidden from the sandbox (as a broken installation would): two students importing it both fail."""
    import scipy

    from mcrt.grade.assignment import assignment_from_dict

    _need(shutil.which("bwrap") is not None, "bubblewrap is not installed (apt-get install bubblewrap)")
    monkeypatch.setenv(codemode.SANDBOX_ENV, "bwrap")
    monkeypatch.setattr(codemode, "_ISOLATION", None)
    hidden = codemode._hidden_paths
    scipy_dir = str(Path(scipy.__file__).resolve().parent)
    monkeypatch.setattr(codemode, "_hidden_paths", lambda roots: sorted({*hidden(roots), scipy_dir}))
    cls = tmp_path / "class"
    cls.mkdir()
    for sid in ("ann", "bob"):
        (cls / f"{sid}.py").write_text("from scipy import stats\n\ndef sample_cosine_hemisphere(u1, u2):\n    return None\n")
    a = assignment_from_dict({"name": "sbx", "title": "sandbox", "scene": {"camera": "near", "width": 32, "height": 32, "spp": 64},
                              "code": {"timeout": 20, "memory_mb": 1024, "checks": {"sample_cosine_hemisphere": {"points": 10}}}})
    grade_code_class(cls, a, tmp_path / "out", jobs=0)  # in this process: the monkeypatches hold there
    err = capsys.readouterr().err
    assert "every student's module failed to import scipy" in err and "grader's installation" in err, err
    assert "failed to import scipy" in (tmp_path / "out" / "summary.md").read_text()
