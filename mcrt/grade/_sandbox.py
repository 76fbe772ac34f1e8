"""Runs inside the student's process: lock the process down, import the module, call it.

Run as ``python -I _sandbox.py WORKDIR`` by :mod:`mcrt.grade.codemode`,
never imported by the grader. It reads ``WORKDIR/input.json``::

    {"module": "student/solution.py", "function": "intersect_triangle",
     "calls": [{"args": [{"npy": "in_0_0.npy"}, 3.0, {"json": {...}}], "kwargs": {}}],
     "read_roots": ["/usr/lib/python3.11", ...]}

and writes ``WORKDIR/output.json`` (``{"results": [{"npy": "out_0.npy"} |
{"error": traceback}], "violations": [...], "sandbox": {...}}``) with each
result saved by ``numpy.save(allow_pickle=False)``.

Before the student's code runs:

* Landlock (Linux >= 5.13; ABI probed): the file system becomes read-only
  except WORKDIR, and readable only under ``read_roots`` (the Python
  installation, its site-packages, system libraries) and WORKDIR, so the
  grader's files, references and other students' work can be neither
  written nor read; TCP bind/connect are denied (ABI >= 4) and signals to
  processes outside the sandbox too (ABI >= 6). It cannot be undone.
* an audit hook (PEP 578) refuses subprocesses, exec, fork, sockets, signals
  and writes outside WORKDIR with a clear message, and records each attempt;
* resource limits (CPU time, address space, file size, no core dumps) are
  set first thing, before NumPy is imported, with soft = hard so that they
  cannot be raised again.
"""

from __future__ import annotations

import ctypes
import json
import os
import sys
import traceback

WORKDIR = os.path.realpath(sys.argv[1]) if len(sys.argv) > 1 else os.getcwd()
VIOLATIONS: list[str] = []
MAX_TRACEBACK = 6000

# --------------------------------------------------------------------------
# Landlock
# --------------------------------------------------------------------------

_SYS_CREATE, _SYS_ADD, _SYS_RESTRICT = 444, 445, 446  # x86_64 and aarch64 share these numbers
_FS_EXECUTE, _FS_WRITE_FILE, _FS_READ_FILE, _FS_READ_DIR = 1 << 0, 1 << 1, 1 << 2, 1 << 3
_FS_TRUNCATE, _FS_IOCTL_DEV = 1 << 14, 1 << 15


class _RulesetAttr(ctypes.Structure):
    _fields_ = [("handled_access_fs", ctypes.c_uint64), ("handled_access_net", ctypes.c_uint64), ("scoped", ctypes.c_uint64)]


class _PathBeneath(ctypes.Structure):
    _pack_ = 1
    _fields_ = [("allowed_access", ctypes.c_uint64), ("parent_fd", ctypes.c_int32)]


def _landlock(read_roots: list[str]) -> str:
    """Apply Landlock; returns a description of what was enforced (or why not)."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.syscall.restype = ctypes.c_long
        abi = libc.syscall(_SYS_CREATE, None, ctypes.c_size_t(0), ctypes.c_uint32(1))
    except Exception as e:  # noqa: BLE001 - pragma: no cover - no libc
        return f"unavailable ({e})"
    if abi < 1:
        return "unavailable (kernel without Landlock)"
    fs_all = (1 << 13) - 1  # ABI 1: EXECUTE .. MAKE_SYM
    if abi >= 2:
        fs_all |= 1 << 13  # REFER
    if abi >= 3:
        fs_all |= _FS_TRUNCATE
    if abi >= 5:
        fs_all |= _FS_IOCTL_DEV
    attr = _RulesetAttr(fs_all, 3 if abi >= 4 else 0, 3 if abi >= 6 else 0)
    size = 8 if abi < 4 else 16 if abi < 6 else 24
    fd = libc.syscall(_SYS_CREATE, ctypes.byref(attr), ctypes.c_size_t(size), ctypes.c_uint32(0))
    if fd < 0:
        return f"unavailable (create_ruleset: errno {ctypes.get_errno()})"
    read = _FS_EXECUTE | _FS_READ_FILE | _FS_READ_DIR

    def allow(path: str, access: int) -> None:
        try:
            pfd = os.open(path, os.O_PATH | os.O_CLOEXEC)
        except OSError:
            return
        try:
            if not os.path.isdir(path):
                access &= _FS_EXECUTE | _FS_WRITE_FILE | _FS_READ_FILE | (_FS_TRUNCATE if abi >= 3 else 0) | (_FS_IOCTL_DEV if abi >= 5 else 0)
            rule = _PathBeneath(access, pfd)
            libc.syscall(_SYS_ADD, ctypes.c_int(fd), ctypes.c_int(1), ctypes.byref(rule), ctypes.c_uint32(0))
        finally:
            os.close(pfd)

    for root in read_roots:
        allow(root, read)
    allow(f"/proc/{os.getpid()}", read)  # this process only, never the grader's /proc entry
    allow(WORKDIR, fs_all)
    allow("/dev/null", _FS_READ_FILE | _FS_WRITE_FILE)
    if libc.prctl(38, 1, 0, 0, 0) != 0:  # PR_SET_NO_NEW_PRIVS
        return f"unavailable (no_new_privs: errno {ctypes.get_errno()})"
    if libc.syscall(_SYS_RESTRICT, ctypes.c_int(fd), ctypes.c_uint32(0)) != 0:
        return f"unavailable (restrict_self: errno {ctypes.get_errno()})"
    os.close(fd)
    parts = ["file system (write: the work folder only; read: Python and system folders)"]
    if abi >= 4:
        parts.append("TCP")
    if abi >= 6:
        parts.append("signals and abstract sockets outside the sandbox")
    return f"Landlock ABI {abi}: " + ", ".join(parts)


# --------------------------------------------------------------------------
# Audit hook
# --------------------------------------------------------------------------

_ALWAYS_BLOCKED = {
    "subprocess.Popen": "starting a process", "os.system": "running a shell command", "os.exec": "exec",
    "os.posix_spawn": "starting a process", "os.spawn": "starting a process", "os.fork": "fork",
    "os.forkpty": "fork", "pty.spawn": "starting a process", "socket.connect": "a network connection",
    "socket.bind": "opening a network port", "socket.sendto": "sending network data",
    "socket.getaddrinfo": "a network name lookup", "os.kill": "sending a signal", "os.killpg": "sending a signal",
    "signal.pthread_kill": "sending a signal", "winreg.OpenKey": "the registry",
}
_PATH_EVENTS = {"os.remove", "os.rmdir", "os.rename", "os.mkdir", "os.chmod", "os.chown", "os.symlink", "os.link",
                "os.truncate", "os.utime", "shutil.rmtree", "shutil.move", "shutil.copyfile", "os.mknod"}


def _inside(path) -> bool:
    try:
        p = os.path.realpath(os.fsdecode(path) if not isinstance(path, int) else "")
    except Exception:  # noqa: BLE001 - anything odd is outside
        return False
    return p == WORKDIR or p.startswith(WORKDIR + os.sep)


def _hook(event: str, args) -> None:
    if event in _ALWAYS_BLOCKED:
        VIOLATIONS.append(f"{_ALWAYS_BLOCKED[event]} ({event})")
        raise PermissionError(f"sandbox: {_ALWAYS_BLOCKED[event]} is not allowed in a graded module ({event})")
    if event == "open" and args:
        path, mode, flags = (list(args) + [None, None, None])[:3]
        if isinstance(path, int) or path is None:
            return
        writing = (isinstance(mode, str) and any(c in mode for c in "wax+")) or (
            isinstance(flags, int) and flags & (os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_TRUNC | os.O_APPEND))
        if writing and not _inside(path) and os.fsdecode(path) != "/dev/null":
            VIOLATIONS.append(f"writing {os.fsdecode(path)}")
            raise PermissionError(f"sandbox: writing {os.fsdecode(path)!r} is not allowed (only the current folder is writable)")
    elif event in _PATH_EVENTS and args:
        for p in args[:2]:
            if isinstance(p, (str, bytes, os.PathLike)) and not _inside(p):
                VIOLATIONS.append(f"{event} on {os.fsdecode(p)}")
                raise PermissionError(f"sandbox: {event} on {os.fsdecode(p)!r} is not allowed")


# --------------------------------------------------------------------------
# Running the module
# --------------------------------------------------------------------------


def _arg(a):
    import numpy as np

    if isinstance(a, dict) and "npy" in a:
        return np.load(os.path.join(WORKDIR, a["npy"]), allow_pickle=False)
    if isinstance(a, dict) and "json" in a:
        return a["json"]
    return a


def _short_tb() -> str:
    tb = traceback.format_exc()
    # Frames of this runner say nothing to the student.
    lines = [ln for ln in tb.splitlines() if "_sandbox.py" not in ln]
    text = "\n".join(lines).replace(os.path.join(WORKDIR, "student") + os.sep, "")
    return text[-MAX_TRACEBACK:]


def _rlimits(limits: dict) -> None:
    """Resource limits, set before anything else (soft = hard, so they cannot be raised again)."""
    import resource

    for name, value in limits.items():
        res = getattr(resource, name, None)
        if res is not None and value is not None:
            resource.setrlimit(res, (int(value), int(value)))


def main() -> int:
    with open(os.path.join(WORKDIR, "input.json")) as f:
        task = json.load(f)
    _rlimits(task.get("limits", {}))
    import numpy as np  # before the sandbox: its shared libraries load from the installation

    info = {"landlock": _landlock(task.get("read_roots", [])) if task.get("landlock", True) else "off"}
    sys.addaudithook(_hook)
    info["audit_hook"] = "on"
    os.chdir(WORKDIR)
    out = {"results": [], "violations": VIOLATIONS, "sandbox": info}
    module = None
    try:
        import importlib.util

        path = os.path.join(WORKDIR, task["module"])
        sys.path.insert(0, os.path.dirname(path))
        spec = importlib.util.spec_from_file_location("student_module", path)
        module = importlib.util.module_from_spec(spec)
        sys.modules["student_module"] = module
        spec.loader.exec_module(module)
    except BaseException:  # noqa: BLE001 - whatever the student's import does is reported, not raised
        out["import_error"] = _short_tb()
    if module is not None and "import_error" not in out:
        fn = getattr(module, task["function"], None)
        if fn is None or not callable(fn):
            out["import_error"] = f"the module has no function {task['function']}()"
        else:
            for i, call in enumerate(task["calls"]):
                try:
                    args = [_arg(a) for a in call.get("args", [])]
                    kwargs = {k: _arg(v) for k, v in call.get("kwargs", {}).items()}
                    res = fn(*args, **kwargs)
                    if isinstance(res, tuple) and task.get("first_of_tuple"):
                        res = res[0]
                    arr = np.asarray(res, dtype=np.float64)
                    name = f"out_{i}.npy"
                    np.save(os.path.join(WORKDIR, name), arr, allow_pickle=False)
                    out["results"].append({"npy": name})
                except BaseException:  # noqa: BLE001 - reported with its traceback
                    out["results"].append({"error": _short_tb()})
                    if isinstance(sys.exc_info()[1], (KeyboardInterrupt, SystemExit)):
                        break
    sys.stdout.flush()
    with open(os.path.join(WORKDIR, "output.json"), "w") as f:
        json.dump(out, f)
    return 0


if __name__ == "__main__":
    sys.exit(main())
