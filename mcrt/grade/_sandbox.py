"""Runs inside the student's process: lock the process down, import the module, call it.

Run as ``python -I -B _sandbox.py INDIR WORKDIR RESULT_FD MONITOR_FD`` by
:mod:`mcrt.grade.codemode`, never imported by the grader; under bubblewrap
INDIR is ``/sandbox/in`` (read-only) and WORKDIR ``/sandbox/work`` (a
tmpfs bounded in bytes and in files). It reads ``INDIR/input.json``::

    {"module": "student/solution.py", "function": "intersect_triangle",
     "calls": [{"args": [{"npy": "in_0_0.npy"}, 3.0, {"json": {...}}], "kwargs": {}}],
     "limits": {...}, "uid": 1500000000, "mount_work": {"size": ..., "nr_inodes": ...},
     "landlock": [["/usr", "read"], ["/venv/lib/python3.11/site-packages", "list"], ...],
     "require": ["landlock", "seccomp"], "output_limit": 67108864}

and writes its answer to the file descriptor RESULT_FD, which the grader
opened (an unlinked file: nothing the student can replace by a link or a
FIFO): each result as a ``.npy`` blob (``numpy.save(allow_pickle=False)``),
then a JSON trailer (``{"results": [{"npy": [offset, length]} | {"error":
traceback}], "sandbox": {...}}``), then the trailer's length as 8
little-endian bytes. Results larger than ``output_limit`` in all are refused
here with a message (the grader also caps what it reads).

MONITOR_FD is the write end of a pipe the grader reads as it comes: one line
per refused operation (``V what``), and ``R`` just before the student's
module is imported. What was written there is the grader's, whatever the
student's code does afterwards; a process that ends without ``R`` failed
before the student's code ran, which is the grader's problem, not the
student's.

Before the student's code runs, in this order:

* resource limits (CPU time, address space, file size, processes, open
  files, no core dumps), soft = hard so that they cannot be raised again;
* as root under bubblewrap (given CAP_SYS_ADMIN, CAP_SETUID and CAP_SETGID
  only): WORKDIR becomes a fresh tmpfs with a byte and an inode budget
  (bubblewrap's own ``--tmpfs`` cannot bound inodes);
* NumPy and common standard modules are imported, while the Python
  installation is certainly readable;
* as root (bubblewrap or not): the switch to the unprivileged ``uid`` of
  this call by setgroups/setresgid/setresuid, which clears every capability;
  whether it can read the installation does not decide whether it happens;
* Landlock (the fallback without bubblewrap; Linux >= 5.13, ABI probed): the
  file system becomes read-only, no file can be made even in WORKDIR (no
  quota could bound it there), and it is readable only along the
  grader's rules (the Python installation without mcrt, Mitsuba and Dr.Jit,
  system folders, INDIR, WORKDIR); TCP bind/connect are denied (ABI >= 4)
  and signals to processes outside the sandbox too (ABI >= 6). Written by
  hand with ctypes: no well-kept Python binding of Landlock was found in
  Debian or on PyPI, and three system calls need no more;
* a seccomp filter (x86_64, aarch64): no exec, no fork (threads only: one
  process, so the address-space limit bounds the whole submission), no
  memfd or System V/POSIX IPC object (memory outside that limit, or outliving
  the call), no new namespaces, no mount, ptrace, bpf, io_uring, keyrings, and
  sockets of the Unix family only. A hand-built BPF program: libseccomp's
  Python binding is Debian's python3-seccomp, tied to the system Python and
  not importable from the grader's virtual environment, and none was found
  on PyPI;
* an audit hook (PEP 578) refuses subprocesses, exec, fork, sockets, signals
  and writes outside WORKDIR with a clear message, and an import hook
  refuses mcrt, Mitsuba and Dr.Jit (their files are hidden as well); each
  refusal goes to MONITOR_FD.
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
MONITOR_FD = int(sys.argv[4]) if len(sys.argv) > 4 else -1
HIDDEN = ("mcrt", "mitsuba", "drjit")  # the grader and the reference renderers
# Imported before the switch of user: what graded code commonly uses stays importable where the installation
# is out of the unprivileged user's reach (about 50 ms beyond NumPy).
PRELOAD = ("numpy", "numpy.random", "numpy.linalg", "numpy.fft", "math", "cmath", "random", "itertools", "functools",
           "collections", "dataclasses", "typing", "enum", "copy", "operator", "heapq", "bisect", "statistics", "time",
           "importlib.util", "threading", "glob", "fnmatch", "re", "pathlib", "string", "textwrap", "fractions",
           "decimal", "array", "warnings", "contextlib", "csv", "struct", "json", "base64", "hashlib", "numbers",
           "weakref", "traceback")
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


def _landlock(rules: list) -> str:
    """Apply Landlock: ``rules`` are ``[path, "read" | "list"]`` (read and run files, or only list folders).

    Returns a description of what was enforced, or of why not ("unavailable ...").
    """
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

    for path, kind in rules:
        allow(path, read if kind == "read" else _FS_READ_DIR)
    allow(f"/proc/{os.getpid()}", read)  # this process only, never the grader's /proc entry
    allow(INDIR, read)
    # Writable but nothing can be made there: without a tmpfs of its own no quota could bound files made here.
    allow(WORKDIR, read | _FS_WRITE_FILE | (_FS_TRUNCATE if abi >= 3 else 0))
    allow("/dev/null", _FS_READ_FILE | _FS_WRITE_FILE)
    if libc.prctl(38, 1, 0, 0, 0) != 0:  # PR_SET_NO_NEW_PRIVS
        return f"unavailable (no_new_privs: errno {ctypes.get_errno()})"
    if libc.syscall(_SYS_RESTRICT, ctypes.c_int(fd), ctypes.c_uint32(0)) != 0:
        return f"unavailable (restrict_self: errno {ctypes.get_errno()})"
    os.close(fd)
    parts = ["file system (read-only, no file can be made; read: Python without mcrt, Mitsuba and Dr.Jit, system folders)"]
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
    # memory outside the address-space limit: an unmapped memfd's pages count against no rlimit
    "memfd_create": (319, 279), "memfd_secret": (447, 447),
    # System V and POSIX IPC objects outlive the process (without bubblewrap, in the grader's IPC namespace)
    "shmget": (29, 194), "semget": (64, 190), "msgget": (68, 186), "mq_open": (240, 180),
}
_DENIED_X86 = {"fork": 57, "vfork": 58}  # aarch64 has only clone
_CLONE, _CLONE3, _SOCKET = (56, 220), (435, 435), (41, 198)
_NS_FLAGS = 0x7E020080  # CLONE_NEWNS | NEWCGROUP | NEWUTS | NEWIPC | NEWUSER | NEWPID | NEWNET | NEWTIME
_CLONE_THREAD = 0x00010000
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
    if col == 0:
        for nr in _DENIED_X86.values():
            op(jeq, nr, "eperm", 0)
    op(jeq, _CLONE3[col], "enosys", 0)  # glibc falls back to clone, whose flags can be checked
    op(jeq, _CLONE[col], "clone", 0)
    op(jeq, _SOCKET[col], "socket", 0)
    op(ret, allow)
    labels = {"clone": len(prog)}
    op(ld, 16)  # args[0], low half: the flags
    op(jset, _NS_FLAGS, "eperm", 0)
    op(jset, _CLONE_THREAD, 0, "eperm")  # a thread (same address space), never a new process
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
    return "on (no exec, fork, memfd, IPC objects, namespaces, mount, ptrace, bpf, io_uring; Unix sockets only)"


def _drop_to(uid: int) -> str:
    """As root (in bubblewrap: CAP_SYS_ADMIN, CAP_SETUID and CAP_SETGID only): become ``uid``, clearing every capability.

    Raises when the switch did not happen completely: the module never runs as root.
    """
    if os.geteuid() != 0:
        return f"uid {os.geteuid()} (the grader's own, not root)"
    if uid <= 0:
        raise PermissionError(f"refusing to run the module as uid {uid}")
    os.setgroups([])
    os.setresgid(uid, uid, uid)
    os.setresuid(uid, uid, uid)
    if 0 in os.getresuid() or 0 in os.getresgid() or os.getgroups():
        raise PermissionError("the switch to an unprivileged user did not take")
    return f"uid {os.getuid()} (unprivileged)"


def _die_with(parent: int | None) -> None:
    """Be killed when the grader (pid ``parent``) dies: ``prctl(PR_SET_PDEATHSIG, SIGKILL)``, set after the switch
    of user, which clears it; if the grader is gone already, stop. Never left running after a ``kill -9`` of the
    grader, although the runner is in a session of its own."""
    if parent is None:
        return
    if ctypes.CDLL(None, use_errno=True).prctl(1, 9, 0, 0, 0) != 0:  # 1: PR_SET_PDEATHSIG, 9: SIGKILL
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_PDEATHSIG) failed")
    if os.getppid() != int(parent):
        os._exit(1)


def _mount_work(uid: int | None, size: int, nr_inodes: int) -> str:
    """A fresh tmpfs on WORKDIR, owned by ``uid``, of ``size`` bytes and ``nr_inodes`` files and folders at most."""
    libc = ctypes.CDLL(None, use_errno=True)
    owner = f",uid={uid},gid={uid}" if uid is not None else ""
    opts = f"size={int(size)},nr_inodes={int(nr_inodes)},mode=0700{owner}".encode()
    ms_nosuid, ms_nodev = 2, 4
    if libc.mount(b"tmpfs", WORKDIR.encode(), b"tmpfs", ctypes.c_ulong(ms_nosuid | ms_nodev), opts) != 0:
        raise OSError(ctypes.get_errno(), f"mounting the work folder's tmpfs: {os.strerror(ctypes.get_errno())}")
    return f"tmpfs of {size >> 20} MiB and {nr_inodes} files"


def _preload(names) -> None:
    """Import what graded modules commonly use while the installation is readable (it may not be after the switch)."""
    import importlib

    for name in names:
        try:
            importlib.import_module(name)
        except ImportError:
            if name == "numpy":
                raise


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


def _monitor(line: str) -> None:
    """One line to the grader's pipe (see the module's docstring); never blocks, never raises."""
    if MONITOR_FD < 0:
        return
    try:
        os.write(MONITOR_FD, (" ".join(line.split())[:300] + "\n").encode("utf-8", "replace"))
    except OSError:
        pass


def _refused(what: str) -> None:
    _monitor("V " + what)


def _hook(event: str, args) -> None:
    if event in _ALWAYS_BLOCKED:
        _refused(f"{_ALWAYS_BLOCKED[event]} ({event})")
        raise PermissionError(f"sandbox: {_ALWAYS_BLOCKED[event]} is not allowed in a graded module ({event})")
    if event == "open" and args:
        path, mode, flags = (list(args) + [None, None, None])[:3]
        if isinstance(path, int) or path is None:
            return
        writing = (isinstance(mode, str) and any(c in mode for c in "wax+")) or (
            isinstance(flags, int) and flags & (os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_TRUNC | os.O_APPEND))
        if writing and not _inside(path) and os.fsdecode(path) != "/dev/null":
            _refused(f"writing {os.fsdecode(path)}")
            raise PermissionError(f"sandbox: writing {os.fsdecode(path)!r} is not allowed (only the current folder is writable)")
    elif event in _PATH_EVENTS and args:
        for p in args[:2]:
            if isinstance(p, (str, bytes, os.PathLike)) and not _inside(p):
                _refused(f"{event} on {os.fsdecode(p)}")
                raise PermissionError(f"sandbox: {event} on {os.fsdecode(p)!r} is not allowed")


class _Hidden:
    """A meta-path finder that refuses the grader's and the reference renderers' packages with a clear message.

    Their files are hidden as well (bubblewrap masks them, Landlock leaves them
    unreadable): this only says why, to a module that tries.
    """

    @staticmethod
    def find_spec(name, path=None, target=None):
        top = name.partition(".")[0]
        if top in HIDDEN:
            _refused(f"importing {top}")
            raise ModuleNotFoundError(f"sandbox: {top} is not available to graded code (the reference renderers and "
                                      "the grader stay outside the sandbox)", name=name)
        return None


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


def _lock_down(task: dict) -> dict:
    """Everything before the student's code, in the module docstring's order; raises if a required layer fails."""
    _rlimits(task.get("limits", {}))
    info = {}
    uid = task.get("uid")
    if task.get("mount_work"):
        info["work"] = _mount_work(uid, **task["mount_work"])
    _preload(PRELOAD)
    os.chdir(WORKDIR)  # after the mount, which the current folder would otherwise hide
    if uid is not None or os.geteuid() == 0:
        info["user"] = _drop_to(int(uid) if uid is not None else -1)
    _die_with(task.get("parent"))
    require = set(task.get("require", []))
    rules = task.get("landlock")
    info["landlock"] = _landlock(rules) if rules is not None else "off (bubblewrap)"
    info["seccomp"] = _seccomp() if task.get("seccomp", True) else "off"
    for layer in ("landlock", "seccomp"):
        if layer in require and not (info[layer].startswith("Landlock") or info[layer].startswith("on")):
            raise OSError(f"{layer} is required here but {info[layer]}")
    sys.meta_path.insert(0, _Hidden)
    for name in list(sys.modules):
        if name.partition(".")[0] in HIDDEN:
            del sys.modules[name]
    sys.addaudithook(_hook)
    info["audit_hook"] = "on"
    return info


def main() -> int:
    with open(os.path.join(INDIR, "input.json")) as f:
        task = json.load(f)
    try:
        info = _lock_down(task)
    except BaseException as e:  # noqa: BLE001 - the grader's problem: said on stderr, and no "R" on the monitor
        print(f"sandbox: could not lock the process down before the module ran: {type(e).__name__}: {e}",
              file=sys.stderr, flush=True)
        return 3
    import numpy as np

    results = _Results(RESULT_FD, int(task.get("output_limit", 64 << 20)))
    out = {"results": [], "sandbox": info}
    module = None
    _monitor("R")
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
