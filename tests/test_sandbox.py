"""Code mode's sandbox against the attacks of issue 18, one test each.

Each attack is a student module that tries it; the test checks that it is
contained (nothing read or written outside the sandbox, no process left
behind, no batch hung, the grader's memory bounded). Every test is bounded
in time (the sandbox's own timeouts, or a subprocess with a timeout) and
removes what it made. The tests need bubblewrap (Debian's ``bubblewrap``):
without it they are skipped with a message, except under CI (``CI`` set,
as .ci/run does), where a missing bubblewrap is a failure.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import textwrap
import time
import uuid
import warnings
from pathlib import Path

import pytest

from mcrt.grade import codemode
from mcrt.grade.codemode import run_student

REPO = Path(__file__).resolve().parent.parent
BWRAP = shutil.which("bwrap")
MISSING = "bubblewrap is not installed (apt-get install bubblewrap); CI installs it (.ci/run) and runs these tests"
if BWRAP is None and not os.environ.get("CI"):
    warnings.warn(f"tests/test_sandbox.py skipped: {MISSING}", stacklevel=1)

needs_bwrap = pytest.mark.skipif(BWRAP is None and not os.environ.get("CI"), reason=MISSING)

COSINE = """
def sample_cosine_hemisphere(u1, u2):
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    return np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(0.0, 1 - u1))], axis=1)
"""


@pytest.fixture
def sandbox():
    """bubblewrap works here (or the test fails saying why, under CI)."""
    assert BWRAP, f"CI is set but {MISSING}"
    iso = codemode.isolation()
    if iso.kind != "bubblewrap":  # namespaces forbidden (a container): the fallback cannot hold all of these
        msg = f"bubblewrap is installed but unusable here: {iso.detail}"
        if os.environ.get("CI"):
            pytest.fail(msg)
        pytest.skip(msg)
    return iso


def _module(folder: Path, body: str, name: str = "solution.py") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    p = folder / name
    p.write_text("import ctypes, os, sys, time\nimport numpy as np\nlibc = ctypes.CDLL(None, use_errno=True)\n"
                 + textwrap.dedent(body))
    return p


def _run(path: Path, calls=None, *, timeout=20, memory_mb=1024, function="f", folder: Path | None = None):
    """Call the module at path (or, with ``folder``, that folder holding it) in the sandbox."""
    calls = calls if calls is not None else [{"args": [1.0]}]
    return run_student(folder or path, path.name, function, calls, {}, timeout=timeout, memory_mb=memory_mb)


def _find_comm(token: str) -> list[int]:
    """Processes whose name (PR_SET_NAME, 15 characters at most) is token."""
    pids = []
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                if Path(f"/proc/{d}/comm").read_text().strip() == token:
                    pids.append(int(d))
            except OSError:
                pass
    return pids


def _kill_all(pids) -> None:
    for pid in pids:
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass


def _token() -> str:
    return "mcrt" + uuid.uuid4().hex[:10]


# --------------------------------------------------------------------------
# Reading what the grader should not show
# --------------------------------------------------------------------------


@needs_bwrap
def test_symlink_in_place_of_the_stdout_capture_shows_nothing(sandbox, tmp_path):
    secret = tmp_path / "alice" / "solution.py"
    secret.parent.mkdir()
    token = _token()
    secret.write_text(f"# alice's work {token}\n")
    mod = _module(tmp_path / "bob", f"""
        def f(x):
            print("bob was here")
            sys.stdout.flush()
            for name in (b"stdout.txt", b"output.json"):
                libc.unlink(name)
                libc.symlink({str(secret).encode()!r}, name)
            raise RuntimeError("look at my output")
        """)
    res = _run(mod)
    shown = res.stdout + "".join(e or "" for e in res.errors) + res.message
    assert token not in shown
    assert "look at my output" in shown


@needs_bwrap
def test_reading_etc_shadow_and_the_references_fails(sandbox, tmp_path):
    mod = _module(tmp_path / "eve", f"""
        def f(x):
            found = []
            for p in ("/etc/shadow", {str(REPO / "reference")!r}, {str(REPO / "mcrt" / "grade")!r}, {str(tmp_path)!r}):
                try:
                    found.append(1.0 if (os.listdir(p) if os.path.isdir(p) else open(p, "rb").read(1)) else 0.0)
                except OSError:
                    found.append(0.0)
            return np.array(found)
        """)
    res = _run(mod)
    assert res.outputs and res.outputs[0] is not None, res
    assert res.outputs[0].tolist() == [0.0, 0.0, 0.0, 0.0]


@needs_bwrap
def test_symlinks_inside_a_submission_are_not_followed(sandbox, tmp_path):
    alice = tmp_path / "alice"
    alice.mkdir()
    token = _token()
    (alice / "solution.py").write_text(f"# {token}\n")
    bob = tmp_path / "bob"
    mod = _module(bob, """
        HERE = os.path.dirname(os.path.abspath(__file__))
        def f(x):
            out = []
            for name in ("refs", "alice", "share", "alice.py"):
                out.append(1.0 if os.path.lexists(os.path.join(HERE, name)) else 0.0)
            return np.array(out)
        """)
    (bob / "refs").symlink_to(REPO / "reference")
    (bob / "alice").symlink_to(alice)
    (bob / "share").symlink_to("/usr/share")
    (bob / "alice.py").symlink_to(alice / "solution.py")
    t0 = time.monotonic()
    res = _run(mod, folder=bob)
    assert time.monotonic() - t0 < 15  # /usr/share (hundreds of MB) is not copied
    assert res.outputs[0].tolist() == [0.0, 0.0, 0.0, 0.0], res
    notes = " ".join(getattr(res, "notes", []))
    for name in ("refs", "alice", "share", "alice.py"):
        assert f"{name}: a symbolic link" in notes, notes


def test_copy_submission_skips_links_and_fifos_without_blocking(tmp_path):
    src = tmp_path / "sub"
    src.mkdir()
    (src / "solution.py").write_text("x = 1\n")
    os.mkfifo(src / "pipe")
    (src / "link").symlink_to("/etc/passwd")
    (src / "deep").mkdir()
    (src / "deep" / "data.txt").write_text("ok")
    notes = codemode.copy_submission(src, tmp_path / "copy")
    assert sorted(p.name for p in (tmp_path / "copy").iterdir()) == ["deep", "solution.py"]
    assert (tmp_path / "copy" / "deep" / "data.txt").read_text() == "ok"
    assert any("pipe: not a regular file" in n for n in notes) and any("link: a symbolic link" in n for n in notes)


# --------------------------------------------------------------------------
# Processes
# --------------------------------------------------------------------------


@needs_bwrap
def test_fork_and_setsid_leave_no_process_behind(sandbox, tmp_path):
    token = _token()
    mod = _module(tmp_path / "eve", f"""
        def f(x):
            pid = libc.fork()
            if pid == 0:
                libc.setsid()
                libc.prctl(15, {token.encode()!r}, 0, 0, 0)
                while True:
                    libc.sleep(1)
            return np.array([float(pid)])
        """)
    try:
        res = _run(mod)
        assert res.outputs[0] is not None and res.outputs[0][0] == -1, res  # one submission is one process: fork is refused
        time.sleep(1.0)
        assert _find_comm(token) == [], "a process forked by the student outlived its call"
    finally:
        _kill_all(_find_comm(token))


@needs_bwrap
def test_fork_exec_of_a_shell_is_refused(sandbox, tmp_path):
    mod = _module(tmp_path / "eve", """
        import _posixsubprocess
        def f(x):
            r, w = os.pipe()
            er, ew = os.pipe()
            args = [[b"/bin/sh", b"-c", b"echo SHELL-RAN"], [b"/bin/sh"], True, (), None, None,
                    -1, -1, -1, w, -1, w, er, ew, True, False, -1, None, None, None, -1, None]
            try:
                try:
                    _posixsubprocess.fork_exec(*args, False)
                except TypeError:
                    _posixsubprocess.fork_exec(*args)
            except OSError:
                pass
            os.close(w)
            os.close(ew)
            time.sleep(0.5)
            os.set_blocking(r, False)
            try:
                out = os.read(r, 100)
            except OSError:
                out = b""
            os.set_blocking(er, False)
            try:
                err = os.read(er, 100)
            except OSError:
                err = b""
            return np.array([1.0 if b"SHELL-RAN" in out else 0.0, 1.0 if err else 0.0])
        """)
    res = _run(mod)
    assert res.outputs[0] is not None, res
    assert res.outputs[0][0] == 0.0, "the student's module ran /bin/sh"


@needs_bwrap
def test_two_hundred_forks_hit_the_process_limit(sandbox, tmp_path):
    token = _token()
    mod = _module(tmp_path / "eve", f"""
        def f(x):
            n = 0
            for _ in range(200):
                pid = libc.fork()
                if pid == 0:
                    libc.prctl(15, {token.encode()!r}, 0, 0, 0)
                    libc.pause()
                    os._exit(0)
                if pid > 0:
                    n += 1
            return np.array([float(n)])
        """)
    try:
        res = _run(mod)
        assert res.outputs[0] is not None, res
        n = res.outputs[0][0]
        assert n < 200 and n <= codemode.NPROC_LIMIT, f"{n:g} forks succeeded"
        time.sleep(0.5)
        assert _find_comm(token) == []
    finally:
        _kill_all(_find_comm(token))


# --------------------------------------------------------------------------
# Network
# --------------------------------------------------------------------------


@needs_bwrap
def test_udp_never_reaches_the_host(sandbox, tmp_path):
    rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        rx.bind(("127.0.0.1", 0))
        port = rx.getsockname()[1]
        mod = _module(tmp_path / "eve", f"""
            import socket, struct
            def f(x):
                sent = 0
                try:
                    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
                    s.sendmsg([b"via-sendmsg"], [], 0, ("127.0.0.1", {port}))
                    sent += 1
                except OSError:
                    pass
                fd = libc.socket(2, 2, 0)  # AF_INET, SOCK_DGRAM
                if fd >= 0:
                    addr = struct.pack("<HH4s8x", 2, socket.htons({port}), bytes([127, 0, 0, 1]))
                    msg = b"via-libc-sendto"
                    if libc.sendto(fd, msg, len(msg), 0, addr, len(addr)) > 0:
                        sent += 1
                return np.array([float(sent)])
            """)
        res = _run(mod)
        assert res.outputs[0] is not None, res
        rx.settimeout(0.5)
        got = []
        try:
            while True:
                got.append(rx.recv(100))
        except (socket.timeout, BlockingIOError):
            pass
        assert got == [], f"the host received {got}"
    finally:
        rx.close()


# --------------------------------------------------------------------------
# Resources: the grader's memory, the disk
# --------------------------------------------------------------------------


@needs_bwrap
def test_huge_return_values_do_not_grow_the_grader(sandbox, tmp_path):
    mod = _module(tmp_path / "eve", """
        def f(x):
            return np.ones(8 << 20)  # 64 MiB, on each of 40 calls
        """)
    script = textwrap.dedent(f"""
        import resource, sys
        from pathlib import Path
        from mcrt.grade.codemode import run_student
        before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        res = run_student(Path({str(mod)!r}), "solution.py", "f", [{{"args": [1.0]}}] * 40, {{}}, timeout=60, memory_mb=1024)
        after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        kept = sum(o.nbytes for o in res.outputs if o is not None)
        print((after - before) // 1024, kept >> 20, sum(e is not None and "MiB" in e for e in res.errors))
        """)
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=180, cwd=REPO)
    assert p.returncode == 0, p.stderr
    grown_mb, kept_mb, refused = (int(x) for x in p.stdout.split()[-3:])
    assert grown_mb < 500, f"the grader grew by {grown_mb} MB"
    assert kept_mb <= codemode.OUTPUT_LIMIT >> 20
    assert refused > 0  # the student is told why


@needs_bwrap
def test_writing_two_gigabytes_hits_the_quota(sandbox, tmp_path):
    mod = _module(tmp_path / "eve", """
        def f(x):
            chunk = b"x" * (1 << 20)
            total = 0
            try:
                for i in range(32):
                    with open(f"junk{i}", "wb") as out:
                        for _ in range(64):
                            out.write(chunk)
                            out.flush()
                            total += len(chunk)
            except OSError:
                pass
            return np.array([float(total)])
        """)
    res = _run(mod, timeout=60)
    assert res.outputs[0] is not None, res
    written = res.outputs[0][0]
    assert written <= codemode.DISK_LIMIT, f"{written / 2**20:.0f} MiB written"


# --------------------------------------------------------------------------
# A class: a FIFO in place of the capture, a linked submission, the fallback
# --------------------------------------------------------------------------

BATCH = """
import sys
from pathlib import Path
from mcrt.grade.assignment import assignment_from_dict
from mcrt.grade.batch import grade_code_class
a = assignment_from_dict({"name": "sbx", "title": "sandbox", "scene": {"camera": "near", "width": 32, "height": 32, "spp": 64},
                          "code": {"timeout": 20, "memory_mb": 1024, "checks": {"sample_cosine_hemisphere": {"points": 10}}}})
grade_code_class(Path(sys.argv[1]), a, Path(sys.argv[2]), jobs=2)
"""


def _batch(tmp_path: Path, env_extra: dict | None = None, timeout: float = 150):
    """Grade tmp_path/class into tmp_path/out in a subprocess (killed if it hangs); its TMPDIR is tmp_path/tmp."""
    tmpdir = tmp_path / "tmp"
    tmpdir.mkdir()
    env = {**os.environ, "TMPDIR": str(tmpdir), **(env_extra or {})}
    proc = subprocess.Popen([sys.executable, "-c", BATCH, str(tmp_path / "class"), str(tmp_path / "out")], cwd=REPO, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        pytest.fail(f"the batch hung (killed after {timeout:g} s)")
    return proc.returncode, out, err, tmpdir


@needs_bwrap
def test_a_fifo_in_place_of_the_capture_does_not_hang_the_batch(sandbox, tmp_path):
    cls = tmp_path / "class"
    _module(cls, COSINE, "good.py")
    _module(cls, COSINE.replace("def sample_cosine_hemisphere(u1, u2):\n", """def sample_cosine_hemisphere(u1, u2):
    for name in (b"stdout.txt", b"output.json"):
        libc.unlink(name)
        libc.mkfifo(name, 0o666)
"""), "fifo.py")
    (cls / "linked.py").symlink_to(cls / "good.py")
    rc, out, err, tmpdir = _batch(tmp_path)
    assert rc == 0, err
    res = tmp_path / "out"
    for sid in ("good", "fifo", "linked"):
        assert (res / sid / "results.json").is_file(), sid
    assert (res / "grades.csv").is_file() and (res / "summary.json").is_file()
    good = json.loads((res / "good" / "results.json").read_text())
    assert good["score"] == 10, good
    fifo = json.loads((res / "fifo" / "results.json").read_text())
    assert fifo["score"] == 10, fifo  # its FIFOs change nothing for the grader
    linked = json.loads((res / "linked" / "results.json").read_text())
    assert linked["score"] == 0 and "symbolic link" in json.dumps(linked)
    assert list(tmpdir.iterdir()) == [], "the batch left temporary files behind"
    assert "bubblewrap" in json.loads((res / "summary.json").read_text())["context"]


def test_the_fallback_is_announced(tmp_path):
    cls = tmp_path / "class"
    _module(cls, COSINE, "good.py")
    rc, out, err, tmpdir = _batch(tmp_path, {"MCRT_SANDBOX": "fallback"})
    assert rc == 0, err
    assert "NOT isolated" in err
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert "NOT isolated" in summary["context"]
    assert "NOT isolated" in (tmp_path / "out" / "summary.md").read_text()
    assert json.loads((tmp_path / "out" / "good" / "results.json").read_text())["score"] == 10
    assert list(tmpdir.iterdir()) == []


def test_every_python_root_is_bound_whatever_folders_share_a_parent(monkeypatch, tmp_path):
    """A root under a folder that an earlier root's bind needed as an empty parent is still bound.

    Seen in a checkout under /tmp: the dependencies (/tmp/x/.venv/...) sorted before the
    Gradescope venv (/tmp/pytest-.../venv), whose bind was skipped because /tmp had been made
    as a parent, and the module's interpreter was then missing in the sandbox.
    """
    first, second = tmp_path / "a" / "site-packages", tmp_path / "b" / "venv"
    first.mkdir(parents=True)
    second.mkdir(parents=True)
    monkeypatch.setattr(codemode, "_python_roots", lambda: [str(first), str(second)])
    argv = codemode._bwrap_argv(codemode.Isolation("bubblewrap", "", "bwrap"), tmp_path, 3, 4, None)
    binds = {argv[i + 1] for i, a in enumerate(argv) if a == "--ro-bind"}
    assert {str(first), str(second)} <= binds


def test_landlock_never_grants_a_link_to_a_folder_holding_a_hidden_package(tmp_path):
    """A venv's ``lib64 -> lib``: Landlock grants the inode a link resolves to, so granting the link would grant
    all of ``lib``, Dr.Jit included (seen in a checkout's own .venv, where student code imported drjit)."""
    venv = tmp_path / "venv"
    site = venv / "lib" / "python3.11" / "site-packages"
    (site / "drjit").mkdir(parents=True)
    (site / "numpy").mkdir()
    (venv / "lib64").symlink_to("lib")
    (site / "alias").symlink_to(site / "drjit")
    hidden = [str(site / "drjit")]
    rules = codemode._landlock_rules([str(venv)], hidden)
    granted = [os.path.realpath(p) for p, kind in rules if kind == "read"]
    assert str(site / "numpy") in granted
    assert not [g for g in granted if any(Path(h).is_relative_to(g) or Path(g).is_relative_to(h) for h in hidden)], rules


def test_packages_in_a_site_packages_off_sys_path_are_hidden_too(tmp_path):
    """Mitsuba in the base installation of the grader's venv (not on its sys.path): graded code could put that
    folder on its own sys.path, so it is hidden like the grader's own."""
    base = tmp_path / "base"
    site = base / "lib" / "python3.11" / "site-packages"
    (site / "mitsuba").mkdir(parents=True)
    (site / "numpy").mkdir()
    system = tmp_path / "usr" / "local" / "lib" / "python3.11" / "dist-packages" / "drjit"
    system.mkdir(parents=True)
    roots = [str(base), str(tmp_path / "usr")]
    hidden = codemode._hidden_paths(roots)
    assert {str(site / "mitsuba"), str(system)} <= set(hidden), hidden
    granted = [p for p, kind in codemode._landlock_rules(roots, hidden) if kind == "read"]
    assert str(site / "numpy") in granted and not [g for g in granted if "mitsuba" in g or "drjit" in g], granted
