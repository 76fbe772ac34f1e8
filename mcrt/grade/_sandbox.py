"""Runs inside the student's process: lock the process down, import the module, call it.

Run as ``python -I -B _sandbox.py INDIR WORKDIR RESULT_FD`` by
:mod:`mcrt.grade.codemode`, never imported by the grader; under bubblewrap
INDIR is ``/sandbox/in`` (read-only) and WORKDIR ``/sandbox/work`` (a
size-limited tmpfs). It reads ``INDIR/input.json``::

    {"module": "student/solution.py", "function": "intersect_triangle",
     "calls": [{"args": [{"npy": "in_0_0.npy"}, 3.0, {"json": {...}}], "kwargs": {}}],
     "read_roots": ["/usr/lib/python3.11", ...], "limits": {...}, "uid": 1500000000,
     "landlock": false, "output_limit": 67108864}

and writes its answer to the file descriptor RESULT_FD, which the grader
opened (an unlinked file: nothing the student can replace by a link or a
FIFO): each result as a ``.npy`` blob (``numpy.save(allow_pickle=False)``),
then a JSON trailer (``{"results": [{"npy": [offset, length]} | {"error":
traceback}], "violations": [...], "sandbox": {...}}``), then the trailer's
length as 8 little-endian bytes. Results larger than ``output_limit`` in all
are refused here with a message (the grader also caps what it reads).

Before the student's code runs:

* resource limits (CPU time, address space, file size, processes, open
  files, no core dumps) first thing, soft = hard so that they cannot be
  raised again;
* as root (bubblewrap gives it only CAP_SETUID and CAP_SETGID): the switch
  to the unprivileged ``uid`` of this sandbox, which clears every capability;
* Landlock (only where bubblewrap is not available, Linux >= 5.13; ABI
  probed): the file system becomes read-only except WORKDIR, and readable
  only under ``read_roots`` (the Python installation, its site-packages,
  system libraries), INDIR and WORKDIR; TCP bind/connect are denied (ABI
  >= 4) and signals to processes outside the sandbox too (ABI >= 6);
* a seccomp filter (x86_64, aarch64): no exec, no new namespaces (so no
  user namespace whose tmpfs would escape the quota), no mount, ptrace, bpf,
  io_uring, keyrings, and sockets of the Unix family only;
* an audit hook (PEP 578) refuses subprocesses, exec, fork, sockets, signals
  and writes outside WORKDIR with a clear message, and records each attempt.
"""

from __future__ import annotations

import ctypes
import json
import os
import struct
import sys
import traceback

INDIR = os.path.realpath(sys.argv[1]) if len(sys.argv) > 1 else os.getcwd()
WORKDIR = os.path.realpath(sys.argv[2]) if len(sys.argv) > 2 else INDIR
RESULT_FD = int(sys.argv[3]) if len(sys.argv) > 3 else -1
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
    allow(INDIR, read)
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
# seccomp
# --------------------------------------------------------------------------

_AUDIT_ARCH = {"x86_64": 0xC000003E, "aarch64": 0xC00000B7}
#: name -> (x86_64, aarch64) system call numbers refused with EPERM.
_DENIED = {
    "execve": (59, 221), "execveat": (322, 281), "unshare": (272, 97), "setns": (308, 268),
    "mount": (165, 40), "umount2": (166, 39), "pivot_root": (155, 41), "chroot": (161, 51),
    "ptrace": (101, 117), "bpf": (321, 280), "userfaultfd": (323, 282), "perf_event_open": (298, 241),
    "keyctl": (250, 219), "add_key": (248, 217), "request_key": (249, 218), "io_uring_setup": (425, 425),
    "open_tree": (428, 428), "move_mount": (429, 429), "fsopen": (430, 430), "fsconfig": (431, 431),
    "fsmount": (432, 432), "fspick": (433, 433), "mount_setattr": (442, 442),
}
_CLONE, _CLONE3, _SOCKET = (56, 220), (435, 435), (41, 198)
_NS_FLAGS = 0x7E020080  # CLONE_NEWNS | NEWCGROUP | NEWUTS | NEWIPC | NEWUSER | NEWPID | NEWNET | NEWTIME
_EPERM, _EACCES, _ENOSYS = 1, 13, 38


def _seccomp() -> str:
    """Install the filter (irreversible); returns what was done, or why not."""
    import platform

    machine = platform.machine()
    if machine not in _AUDIT_ARCH:
        return f"unavailable (no filter for {machine})"
    col = 0 if machine == "x86_64" else 1
    ld, jeq, jset, ret = 0x20, 0x15, 0x45, 0x06
    allow, errno = 0x7FFF0000, 0x00050000
    prog: list = []  # (code, jt, jf, k); jt/jf may be labels, resolved below

    def op(code, k, jt=0, jf=0):
        prog.append([code, jt, jf, k])

    op(ld, 4)  # seccomp_data.arch
    op(jeq, _AUDIT_ARCH[machine], 1, 0)
    op(ret, errno | _EPERM)
    op(ld, 0)  # seccomp_data.nr
    if col == 0:
        op(jset, 0x40000000, "eperm", 0)  # the x32 ABI
    for nums in _DENIED.values():
        op(jeq, nums[col], "eperm", 0)
    op(jeq, _CLONE3[col], "enosys", 0)  # glibc falls back to clone, whose flags can be checked
    op(jeq, _CLONE[col], "clone", 0)
    op(jeq, _SOCKET[col], "socket", 0)
    op(ret, allow)
    labels = {"clone": len(prog)}
    op(ld, 16)  # args[0], low half: the flags
    op(jset, _NS_FLAGS, "eperm", 0)
    op(ret, allow)
    labels["socket"] = len(prog)
    op(ld, 16)  # args[0]: the address family
    op(jeq, 1, 0, "eacces")  # AF_UNIX only
    op(ret, allow)
    labels["eperm"] = len(prog)
    op(ret, errno | _EPERM)
    labels["eacces"] = len(prog)
    op(ret, errno | _EACCES)
    labels["enosys"] = len(prog)
    op(ret, errno | _ENOSYS)
    raw = b""
    for i, (code, jt, jf, k) in enumerate(prog):
        jt = labels[jt] - i - 1 if isinstance(jt, str) else jt
        jf = labels[jf] - i - 1 if isinstance(jf, str) else jf
        raw += struct.pack("HBBI", code, jt, jf, k)
    buf = ctypes.create_string_buffer(raw, len(raw))

    class _Prog(ctypes.Structure):
        _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.c_void_p)]

    fprog = _Prog(len(prog), ctypes.cast(buf, ctypes.c_void_p))
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.prctl(38, 1, 0, 0, 0) != 0:  # PR_SET_NO_NEW_PRIVS
        return f"unavailable (no_new_privs: errno {ctypes.get_errno()})"
    if libc.prctl(22, 2, ctypes.byref(fprog), 0, 0) != 0:  # PR_SET_SECCOMP, SECCOMP_MODE_FILTER
        return f"unavailable (errno {ctypes.get_errno()})"
    return "on (no exec, namespaces, mount, ptrace, bpf, io_uring; Unix sockets only)"


def _drop_to(uid: int) -> str:
    """Root inside the sandbox (CAP_SETUID and CAP_SETGID only): become ``uid``, which clears every capability."""
    if os.geteuid() != 0:
        return f"uid {os.geteuid()}"
    os.setgroups([])
    os.setresgid(uid, uid, uid)
    os.setresuid(uid, uid, uid)
    return f"uid {os.getuid()} (unprivileged)"


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
        return np.load(os.path.join(INDIR, os.path.basename(a["npy"])), allow_pickle=False)
    if isinstance(a, dict) and "json" in a:
        return a["json"]
    return a


def _short_tb() -> str:
    tb = traceback.format_exc()
    # Frames of this runner say nothing to the student.
    lines = [ln for ln in tb.splitlines() if "_sandbox.py" not in ln and "/sandbox/runner.py" not in ln]
    text = "\n".join(lines).replace(os.path.join(INDIR, "student") + os.sep, "")
    return text[-MAX_TRACEBACK:]


def _rlimits(limits: dict) -> None:
    """Resource limits, set before anything else (soft = hard, so they cannot be raised again)."""
    import resource

    for name, value in limits.items():
        res = getattr(resource, name, None)
        if res is not None and value is not None:
            resource.setrlimit(res, (int(value), int(value)))


class _Results:
    """The answer on RESULT_FD: .npy blobs, a JSON trailer, its length (8 bytes, little-endian)."""

    def __init__(self, fd: int, limit: int):
        self.f = os.fdopen(fd, "wb", closefd=False) if fd >= 0 else open(os.path.join(WORKDIR, "output.bin"), "wb")
        self.offset, self.limit = 0, limit

    def array(self, arr) -> dict:
        import numpy as np

        if arr.nbytes > self.limit - self.offset:
            raise MemoryError(f"the result is {arr.nbytes / 2**20:.1f} MiB; the results of one check may total at most "
                              f"{self.limit / 2**20:.0f} MiB")
        start = self.f.tell() if self.f.seekable() else self.offset
        np.save(self.f, arr, allow_pickle=False)
        self.f.flush()
        end = self.f.tell() if self.f.seekable() else start
        self.offset = end
        return {"npy": [start, end - start]}

    def close(self, out: dict) -> None:
        data = json.dumps(out).encode()
        self.f.write(data)
        self.f.write(struct.pack("<Q", len(data)))
        self.f.close()


def main() -> int:
    with open(os.path.join(INDIR, "input.json")) as f:
        task = json.load(f)
    _rlimits(task.get("limits", {}))
    info = {}
    if task.get("uid") is not None:
        info["user"] = _drop_to(int(task["uid"]))
    import numpy as np  # before the sandbox: its shared libraries load from the installation

    info["landlock"] = _landlock(task.get("read_roots", [])) if task.get("landlock", True) else "off (bubblewrap)"
    info["seccomp"] = _seccomp() if task.get("seccomp", True) else "off"
    sys.addaudithook(_hook)
    info["audit_hook"] = "on"
    os.chdir(WORKDIR)
    results = _Results(RESULT_FD, int(task.get("output_limit", 64 << 20)))
    out = {"results": [], "violations": VIOLATIONS, "sandbox": info}
    module = None
    try:
        import importlib.util

        path = os.path.join(INDIR, task["module"])
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
                    arr = np.ascontiguousarray(np.asarray(res, dtype=np.float64))
                    out["results"].append(results.array(arr))
                    del res, arr
                except BaseException:  # noqa: BLE001 - reported with its traceback
                    out["results"].append({"error": _short_tb()})
                    if isinstance(sys.exc_info()[1], (KeyboardInterrupt, SystemExit)):
                        break
    sys.stdout.flush()
    results.close(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
