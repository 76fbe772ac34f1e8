r"""Code mode: a student's Python module through the same checks, in a sandbox.

The documented interface (every function optional; the assignment's
``[code.checks.<name>]`` tables say which are graded and for how many
points). Arrays are NumPy float64; all functions must be deterministic
given their inputs (randomness comes in as ``u`` or ``seed``)::

    def sample_cosine_hemisphere(u1, u2):
        '''(N,) uniforms in [0, 1) -> (N, 3) unit directions in the local frame
        (z = the normal), distributed with pdf cos(theta) / pi.'''

    def intersect_triangle(origins, directions, v0, v1, v2):
        '''(N, 3) ray origins and unit directions, (3,) vertices -> (N,) distance
        t > 0 to the triangle (either side), or inf where the ray misses.'''

    def estimate_direct(points, normals, light, u):
        '''(N, 3) points with (N, 3) unit normals, light = {"corners": 4x3 list
        (counter-clockwise seen from the lit side), "normal": [x, y, z],
        "radiance": Le}, (N, 2) uniforms -> (N,) one-sample estimates of the
        irradiance E = integral of Le cos(theta_x) cos(theta_y) / d^2 dA over
        the light (no occluders); its mean over many u must be E.'''

    def render(scene, camera, width, height, spp, seed, max_depth):
        '''The scene file as a dict (reference/scenes/FORMAT.md), a camera name
        -> (height, width, 3) linear radiance, row 0 at the top.'''

Checks (:data:`CHECKS`), each worth its points, all or nothing except
``render`` (its share of the image rubric):

* ``sample_cosine_hemisphere``: shape, finite, unit length, above the
  horizon; chi-square goodness of fit (:func:`mcrt.stats.chi2_gof`) of
  (cos^2 theta, phi / 2 pi) on a 16 x 16 grid, which is uniform exactly for
  the cosine density; the mean of cos(theta) is reported (2/3 for cosine,
  1/2 for uniform hemisphere sampling).
* ``intersect_triangle``: 40 triangles, 500 rays each, against a float64
  Moller-Trumbore; rays within 1e-6 (barycentric) of an edge are not
  judged; 99.5 % of hits and misses must agree and distances within 1e-4
  (relative).
* ``estimate_direct``: 24 points on the floor and the walls, 4096 samples
  each, against Lambert's closed form (:func:`mcrt.closed_form.polygon_irradiance`):
  per-point z-tests, Holm at ``alpha``, penalised above 1 % effect.
* ``render``: two renders (seeds 1 and 2) at the check's size and spp,
  graded by the image pipeline (:func:`mcrt.grade.grader.grade_image`)
  against the assignment's reference; the check scores its points times the
  image rubric's share.

Every call runs in a fresh process (``python -I -B mcrt/grade/_sandbox.py``)
inside bubblewrap (``bwrap``, Debian's package ``bubblewrap``): new PID,
network, IPC and UTS namespaces (and a user namespace when the grader is not
root), so a process the student forks dies with the call and nothing leaves
the sandbox's own loopback; an unprivileged uid, one per call, even when the
grader runs as root (there bubblewrap runs privileged and the runner, given
only CAP_SETUID and CAP_SETGID, switches to it first thing); read-only binds
of only what the module may read (the Python installation and its packages
without mcrt itself, /usr and the loader's files, the call's inputs: never the
references, the grader, other students' folders or /etc); a tmpfs of
:data:`DISK_LIMIT` bytes as its only writable folder (the disk quota);
``--die-with-parent`` and ``--new-session``. The runner then sets its
resource limits (:func:`_limits`: CPU time, address space, file size,
processes, open files, no core files), installs a seccomp filter (no exec, no
new namespaces) and an audit hook, before NumPy or the student's code loads;
a wall-clock timeout kills the whole process group. The grader never opens a
path the student could have made: the student's output goes to files it
opened itself and unlinked (a link or a FIFO planted in the work folder
changes nothing), results are capped at :data:`OUTPUT_LIMIT` before they are
decoded, and a submission folder is copied without following links (a link
is skipped with a message) and capped in size.

Where bubblewrap is missing or namespaces are forbidden (a container that
refuses them: probed by running ``bwrap`` once), the grader says so on
stderr and in the class summary and falls back to the best it has: the same
rlimits, seccomp filter and audit hook, Landlock (read-only system, writable
work folder, unreadable grader files) and, as root, ``nobody`` when the
Python installation is readable by others. ``MCRT_SANDBOX=bwrap`` makes a
missing bubblewrap an error, ``MCRT_SANDBOX=fallback`` forces the fallback.
A crash, a hang, a memory blow-up or a refused operation is a graded failure
of that check, with the student's traceback.
"""

from __future__ import annotations

import io
import itertools
import json
import os
import shutil
import signal
import stat
import struct
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mcrt.grade.assignment import Assignment
from mcrt.grade.scoring import Rubric, StudentResult, code_items

RUNNER = Path(__file__).with_name("_sandbox.py")
FSIZE_LIMIT = 128 << 20  # any one file the student's process writes (its stdout included)
DISK_LIMIT = 256 << 20  # the sandbox's tmpfs: all it may write together
OUTPUT_LIMIT = 64 << 20  # the results of one check's calls together, as the grader reads them
TRAILER_LIMIT = 4 << 20  # their JSON description (tracebacks, violations)
NPROC_LIMIT = 16  # processes and threads of the sandbox's uid
NOFILE_LIMIT = 256
SUBMISSION_LIMIT = 32 << 20  # bytes of a submission folder copied into the sandbox
SUBMISSION_FILES = 2000
STDIO_TAIL = 4000
NOBODY = 65534
UID_BASE = 1_500_000_000  # one unprivileged uid per call above this (no such user on the system)
_uids = itertools.count()

CHECK_TITLES = {
    "sample_cosine_hemisphere": "sample_cosine_hemisphere: cosine-weighted directions",
    "intersect_triangle": "intersect_triangle: ray-triangle intersection",
    "estimate_direct": "estimate_direct: direct light from the area light",
    "render": "render: the whole image",
}


# --------------------------------------------------------------------------
# Running student code
# --------------------------------------------------------------------------


@dataclass
class CallResult:
    ok: bool
    outputs: list  # np.ndarray or None per call
    errors: list  # traceback text or None per call
    message: str = ""  # why nothing came back (timeout, crash, ...)
    violations: list = field(default_factory=list)
    sandbox: dict = field(default_factory=dict)
    seconds: float = 0.0
    stdout: str = ""
    notes: list = field(default_factory=list)  # what of the submission was not copied, and why


def _read_roots() -> list[str]:
    """Folders the student's process may read: the Python installation and system folders.

    Never the project (references, the grader, other output) nor any folder
    holding it; inside the project only the virtual environment. Of /proc
    only cpuinfo and meminfo here; the runner adds its own /proc/<pid> (never
    the grader's, whose environment would be readable there). Used by the
    fallback (Landlock); bubblewrap binds :func:`_python_roots` and system
    folders instead.
    """
    return sorted(set(_python_roots()) | _existing({"/usr", "/lib", "/lib64", "/lib32", "/bin", "/sbin", "/etc", "/sys",
                                                    "/opt", "/proc/cpuinfo", "/proc/meminfo", "/dev/urandom", "/dev/zero"}))


def _existing(cands) -> set[str]:
    return {os.path.realpath(c) for c in cands if os.path.exists(c)}


def _python_roots() -> list[str]:
    """The Python installation, the virtual environment and the folders of sys.path, never the project."""
    repo = Path(__file__).resolve().parent.parent.parent
    venv = Path(sys.prefix).resolve()
    cands = {sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix, os.path.dirname(os.path.realpath(sys.executable))}
    cands |= {p for p in sys.path if p and os.path.isdir(p)}
    out = set()
    for c in _existing(cands):
        r = Path(c)
        if r == Path("/") or r == repo or repo.is_relative_to(r):
            continue  # an ancestor of the project would expose it
        if r.is_relative_to(repo) and not r.is_relative_to(venv):
            continue
        out.add(str(r))
    # The outermost folders only (a bind covers what is under it).
    return sorted(r for r in out if not any(r != o and Path(r).is_relative_to(o) for o in out))


def _world_traversable(path: str) -> bool:
    p = Path(path).resolve()
    for q in [p, *p.parents]:
        try:
            if not os.stat(q).st_mode & stat.S_IXOTH:
                return False
        except OSError:
            return False
    return True


def _other_readable(path: str) -> bool:
    try:
        m = os.stat(path).st_mode
    except OSError:
        return False
    return bool(m & stat.S_IROTH) and (not stat.S_ISDIR(m) or bool(m & stat.S_IXOTH))


def _can_drop_privileges() -> bool:
    if os.geteuid() != 0:
        return False
    return all(_world_traversable(x) for x in (sys.executable, sys.base_prefix, str(RUNNER)))


def _limits(cpu_s: float, memory_mb: int) -> dict:
    """Resource limits the runner sets on itself before NumPy and the student's code load."""
    cpu = int(cpu_s) + 1
    return {"RLIMIT_CPU": cpu, "RLIMIT_AS": int(memory_mb) << 20, "RLIMIT_FSIZE": FSIZE_LIMIT, "RLIMIT_CORE": 0,
            "RLIMIT_NPROC": NPROC_LIMIT, "RLIMIT_NOFILE": NOFILE_LIMIT}


# --------------------------------------------------------------------------
# Isolation: bubblewrap, or the fallback (said so, never silently)
# --------------------------------------------------------------------------


@dataclass
class Isolation:
    kind: str  # "bubblewrap" or "fallback"
    detail: str  # one line for stderr and the class summary
    bwrap: str | None = None
    options: frozenset = frozenset()  # optional bwrap options this version has


_ISOLATION: Isolation | None = None
_ISOLATION_LOCK = threading.Lock()
_NS_FLAGS = ["--unshare-pid", "--unshare-net", "--unshare-ipc", "--unshare-uts", "--unshare-cgroup-try"]


def _probe_bwrap() -> Isolation:
    exe = shutil.which("bwrap")
    if exe is None:
        return Isolation("fallback", "bubblewrap (bwrap) is not installed (apt-get install bubblewrap)")
    try:
        helptext = subprocess.run([exe, "--help"], capture_output=True, text=True, timeout=10).stdout
    except (OSError, subprocess.SubprocessError) as e:
        return Isolation("fallback", f"bwrap does not run ({e})")
    opts = frozenset(o for o in ("--size", "--perms", "--disable-userns", "--die-with-parent", "--new-session")
                     if o in helptext)
    if not {"--perms", "--die-with-parent", "--new-session"} <= opts:
        return Isolation("fallback", f"{exe} is too old (no --perms, --die-with-parent or --new-session; 0.5 or later needed)")
    # What the calls use: as root a privileged bwrap without a user namespace, else --unshare-all.
    ns = _NS_FLAGS if os.geteuid() == 0 else ["--unshare-all"]
    argv = [exe, *ns, "--die-with-parent", "--new-session", "--ro-bind", "/", "/", "--proc", "/proc", "--dev", "/dev", "true"]
    try:
        p = subprocess.run(argv, capture_output=True, text=True, timeout=30, stdin=subprocess.DEVNULL)
    except (OSError, subprocess.SubprocessError) as e:
        return Isolation("fallback", f"bwrap failed to start ({e})")
    if p.returncode != 0:
        why = (p.stderr.strip().splitlines() or [f"exit code {p.returncode}"])[-1]
        return Isolation("fallback", f"bwrap cannot create namespaces here ({why})")
    ver = subprocess.run([exe, "--version"], capture_output=True, text=True, timeout=10).stdout.strip() or "bubblewrap"
    quota = "" if "--size" in opts else "; this bwrap has no --size: no disk quota beyond the file-size limit"
    who = "an unprivileged uid"
    if os.geteuid() == 0 and not all(_other_readable(r) for r in _python_roots()):
        who = "uid 0 without capabilities (the Python installation is not readable by others, so no other uid can run it)"
    return Isolation("bubblewrap", f"{ver}: PID, network, IPC and UTS namespaces, {who}, read-only "
                                   f"system, a {DISK_LIMIT >> 20} MiB tmpfs as the only writable folder{quota}", exe, opts)


def isolation() -> Isolation:
    """How student code is isolated here (probed once; ``MCRT_SANDBOX``: auto, bwrap, fallback)."""
    global _ISOLATION
    with _ISOLATION_LOCK:
        if _ISOLATION is None:
            want = os.environ.get("MCRT_SANDBOX", "auto").strip().lower() or "auto"
            if want in ("fallback", "none", "off"):
                iso = Isolation("fallback", f"MCRT_SANDBOX={want} asks for no bubblewrap")
            else:
                iso = _probe_bwrap()
                if want == "bwrap" and iso.kind != "bubblewrap":
                    raise RuntimeError(f"MCRT_SANDBOX=bwrap, but {iso.detail}")
            if iso.kind == "fallback":
                who = ("a separate uid (nobody)" if _can_drop_privileges() else
                       "root: the Python installation is not readable by others" if os.geteuid() == 0 else
                       f"the grader's own uid {os.geteuid()}")
                iso.detail = (f"WARNING: student code is NOT isolated by namespaces: {iso.detail}. Falling back to "
                              f"rlimits, seccomp, Landlock and an audit hook, running as {who}; no disk quota, and "
                              "processes it forks and its network traffic are not contained by namespaces")
                print(f"mcrt grade: {iso.detail}", file=sys.stderr, flush=True)
            _ISOLATION = iso
        return _ISOLATION


def _sandbox_uid() -> int:
    return UID_BASE + (os.getpid() % 4096) * 4096 + next(_uids) % 4096


def _bwrap_argv(iso: Isolation, indir: Path, result_fd: int, uid: int | None) -> list[str]:
    """bwrap's command line: what the module sees is exactly what is bound here."""
    root = os.geteuid() == 0
    argv = [iso.bwrap, *_NS_FLAGS, "--die-with-parent", "--new-session", "--hostname", "sandbox"]
    if root:
        if uid is not None:
            argv += ["--cap-add", "CAP_SETUID", "--cap-add", "CAP_SETGID"]
    else:
        argv += ["--unshare-user", "--uid", str(NOBODY), "--gid", str(NOBODY)]
        if "--disable-userns" in iso.options:
            argv.append("--disable-userns")
    made: set[str] = set()  # folders created empty in the sandbox to hold a bind
    bound: set[str] = set()  # folders bound from outside: what lies under them is visible already

    def parents(dest: str) -> None:
        for q in reversed(Path(dest).parents):
            s = str(q)
            if s != "/" and s not in made and not any(q.is_relative_to(b) for b in bound):
                argv.extend(["--perms", "0755", "--dir", s])
                made.add(s)

    argv += ["--ro-bind", "/usr", "/usr"]
    bound.add("/usr")
    for d in ("/bin", "/sbin", "/lib", "/lib64", "/lib32"):
        if os.path.islink(d):
            argv += ["--symlink", os.readlink(d), d]
        elif os.path.isdir(d):
            argv += ["--ro-bind", d, d]
        bound.add(d)
    for f in ("/etc/ld.so.cache", "/etc/ld.so.conf", "/etc/localtime"):
        if os.path.isfile(f):
            parents(f)
            argv += ["--ro-bind", f, f]
    masks = []
    for r in _python_roots():
        if not any(Path(r).is_relative_to(b) for b in bound):
            parents(r)
            argv += ["--ro-bind", r, r]
            bound.add(r)
        for p in sys.path:
            if p and Path(p).is_relative_to(r) and os.path.isdir(os.path.join(p, "mcrt")):
                masks.append(os.path.join(p, "mcrt"))  # the grader's package (its references) stays unreadable
    for m in sorted(set(masks)):
        argv += ["--size", "4096"] if "--size" in iso.options else []
        argv += ["--tmpfs", m, "--remount-ro", m]
    parents("/sandbox/x")
    argv += ["--ro-bind", str(RUNNER), "/sandbox/runner.py", "--ro-bind", str(indir), "/sandbox/in"]
    if "--size" in iso.options:
        argv += ["--size", str(DISK_LIMIT)]
    argv += ["--perms", "1777", "--tmpfs", "/sandbox/work",
             "--proc", "/proc", "--dev", "/dev", "--chdir", "/sandbox/work", "--",
             sys.executable, "-I", "-B", "/sandbox/runner.py", "/sandbox/in", "/sandbox/work", str(result_fd)]
    return argv


# --------------------------------------------------------------------------
# Copying the submission, reading what comes back: never a link, never a special file
# --------------------------------------------------------------------------


def copy_submission(src: Path, dest: Path, *, limit: int = SUBMISSION_LIMIT, max_files: int = SUBMISSION_FILES) -> list[str]:
    """Copy a student's file or folder into ``dest`` (a new folder) without following links.

    Regular files and folders only: a symbolic link, a FIFO, a socket or a
    device is skipped, and so is what exceeds ``limit`` bytes or
    ``max_files`` files in all; returns one message per thing skipped.
    Names starting with a dot and ``__pycache__`` are left out silently.
    """
    notes: list[str] = []
    budget = {"bytes": limit, "files": max_files}
    dest.mkdir(mode=0o755)

    def skip(rel: str, why: str) -> None:
        if len(notes) < 20:
            notes.append(f"{rel}: {why}, not copied")
        elif len(notes) == 20:
            notes.append("(more files skipped)")

    def copy_file(path: Path, rel: str, out: Path) -> None:
        if budget["files"] <= 0:
            return skip(rel, f"more than {max_files} files")
        try:
            fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
        except OSError as e:
            return skip(rel, "a symbolic link (links are not followed)" if os.path.islink(path) else f"unreadable ({e.strerror})")
        try:
            st = os.fstat(fd)
            if not stat.S_ISREG(st.st_mode):
                return skip(rel, "not a regular file")
            if st.st_size > budget["bytes"]:
                return skip(rel, f"over the {limit >> 20} MiB a submission may hold")
            budget["files"] -= 1
            with os.fdopen(os.open(out, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o644), "wb") as w:
                left = st.st_size
                while left > 0:
                    chunk = os.read(fd, min(left, 1 << 20))
                    if not chunk:
                        break
                    w.write(chunk)
                    left -= len(chunk)
            budget["bytes"] -= st.st_size - left
        finally:
            os.close(fd)

    def walk(folder: Path, rel: str, out: Path, depth: int) -> None:
        try:
            entries = sorted(os.scandir(folder), key=lambda e: e.name)
        except OSError as e:
            return skip(rel or ".", f"unreadable ({e.strerror})")
        for e in entries:
            if e.name.startswith(".") or e.name == "__pycache__":
                continue
            r = f"{rel}{e.name}"
            if e.is_symlink():
                try:
                    target = os.readlink(e.path)
                except OSError:
                    target = "?"
                skip(r, f"a symbolic link (to {target}; links are not followed)")
            elif e.is_dir(follow_symlinks=False):
                if depth >= 16:
                    skip(r, "nested too deep")
                    continue
                (out / e.name).mkdir(mode=0o755)
                walk(Path(e.path), r + "/", out / e.name, depth + 1)
            elif e.is_file(follow_symlinks=False):
                copy_file(Path(e.path), r, out / e.name)
            else:
                skip(r, "not a regular file (a FIFO, socket or device)")

    st = os.lstat(src)
    if stat.S_ISLNK(st.st_mode):
        skip(src.name, "a symbolic link (links are not followed)")
    elif stat.S_ISDIR(st.st_mode):
        walk(src, "", dest, 0)
    elif stat.S_ISREG(st.st_mode):
        copy_file(src, src.name, dest / src.name)
    else:
        skip(src.name, "not a regular file")
    return notes


def _read_capped(f, limit: int) -> bytes | None:
    """All of an open regular file, or None when it is not one or is over ``limit`` bytes."""
    st = os.fstat(f.fileno())
    if not stat.S_ISREG(st.st_mode) or st.st_size > limit:
        return None
    f.seek(0)
    return f.read(limit + 1)[:limit]


def _tail_fd(f) -> str:
    try:
        st = os.fstat(f.fileno())
        if not stat.S_ISREG(st.st_mode):
            return ""
        f.seek(max(0, st.st_size - STDIO_TAIL))
        return f.read(STDIO_TAIL).decode("utf-8", "replace")
    except OSError:
        return ""


def _decode_npy(blob: bytes):
    """A float64 .npy of exactly the declared size, without pickles and without trusting its header's size."""
    from numpy.lib import format as npformat

    bio = io.BytesIO(blob)
    version = npformat.read_magic(bio)
    read = npformat.read_array_header_1_0 if version == (1, 0) else npformat.read_array_header_2_0
    shape, fortran, dtype = read(bio, max_header_size=10000)
    if dtype != np.dtype("<f8"):
        raise ValueError(f"unexpected type {dtype}")
    count = 1
    for n in shape:
        count *= int(n)
    if count * 8 != len(blob) - bio.tell():
        raise ValueError("the data does not match its declared shape")
    arr = np.frombuffer(blob, dtype="<f8", offset=bio.tell())
    return arr.reshape(shape, order="F" if fortran else "C").copy()


def _parse_results(raw: bytes | None) -> dict | None:
    """The runner's answer (see mcrt.grade._sandbox); None when it is missing or malformed."""
    if raw is None or len(raw) < 8:
        return None
    (n,) = struct.unpack("<Q", raw[-8:])
    if n > min(TRAILER_LIMIT, len(raw) - 8):
        return None
    try:
        data = json.loads(raw[len(raw) - 8 - n:len(raw) - 8])
    except ValueError:
        return None
    if not isinstance(data, dict):
        return None
    data["_blobs"] = memoryview(raw)[:len(raw) - 8 - n]
    return data


def run_student(module_src: Path, module_name: str, function: str, calls: list[dict], arrays: dict[str, np.ndarray], *,
                timeout: float, memory_mb: int, first_of_tuple: bool = False) -> CallResult:
    """Call ``function`` of the student's module once per entry of ``calls`` in a sandboxed subprocess.

    ``module_src`` is the student's file or folder (copied, without following
    links, into a fresh temporary folder); ``arrays`` are saved there as
    ``.npy`` files that ``calls`` refer to with ``{"npy": name}``.
    """
    t0 = time.monotonic()
    iso = isolation()
    tmp = Path(tempfile.mkdtemp(prefix="mcrt-code-"))
    try:
        indir = tmp / "in"
        indir.mkdir(mode=0o755)
        notes = copy_submission(Path(module_src), indir / "student")
        for name, arr in arrays.items():
            np.save(indir / name, np.ascontiguousarray(arr), allow_pickle=False)
        bwrap = iso.kind == "bubblewrap"
        uid = None
        if os.geteuid() == 0 and bwrap and all(_other_readable(r) for r in _python_roots()):
            uid = _sandbox_uid()
        task = {"module": f"student/{module_name}", "function": function, "calls": calls, "first_of_tuple": first_of_tuple,
                "read_roots": [] if bwrap else _read_roots(), "limits": _limits(timeout, memory_mb), "uid": uid,
                "landlock": not bwrap, "output_limit": OUTPUT_LIMIT}
        (indir / "input.json").write_text(json.dumps(task))
        for dirpath, dirs, files in os.walk(indir):
            os.chmod(dirpath, 0o755)
            for f in files:
                os.chmod(os.path.join(dirpath, f), 0o644)
        env = {"PATH": "/usr/bin:/bin", "LANG": "C.UTF-8",
               "PYTHONDONTWRITEBYTECODE": "1", "PYTHONHASHSEED": "0", "OMP_NUM_THREADS": "1",
               "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "NUMEXPR_NUM_THREADS": "1"}
        ids: dict = {}
        with tempfile.TemporaryFile(dir=tmp) as out, tempfile.TemporaryFile(dir=tmp) as resf:
            if bwrap:
                env.update({"HOME": "/sandbox/work", "TMPDIR": "/sandbox/work"})
                argv, cwd = _bwrap_argv(iso, indir, resf.fileno(), uid), tmp
            else:
                work = tmp / "work"
                work.mkdir()
                if _can_drop_privileges():
                    os.chmod(tmp, 0o711)
                    os.chown(work, NOBODY, NOBODY)
                    ids = {"user": NOBODY, "group": NOBODY, "extra_groups": []}
                env.update({"HOME": str(work), "TMPDIR": str(work)})
                argv = [sys.executable, "-I", "-B", str(RUNNER), str(indir), str(work), str(resf.fileno())]
                cwd = work
            # No preexec_fn (unsafe with the threads that grade students in parallel): a new session for
            # killing the whole group, and the user switch, are done by Popen itself; the runner sets its
            # own resource limits before anything else.
            proc = subprocess.Popen(argv, cwd=cwd, env=env, stdin=subprocess.DEVNULL, stdout=out, stderr=subprocess.STDOUT,
                                    start_new_session=True, close_fds=True, pass_fds=(resf.fileno(),), **ids)
            try:
                code = proc.wait(timeout=timeout)
                timed_out = False
            except subprocess.TimeoutExpired:
                timed_out = True
                code = None
            finally:
                try:
                    os.killpg(proc.pid, signal.SIGKILL)  # the whole group: no orphan keeps running
                except (ProcessLookupError, PermissionError):
                    pass
                proc.wait()
            stdout = _tail_fd(out)
            raw = None if timed_out else _read_capped(resf, OUTPUT_LIMIT + TRAILER_LIMIT + 8)
            too_big = not timed_out and raw is None and os.fstat(resf.fileno()).st_size > 0
        seconds = time.monotonic() - t0
        if timed_out:
            return CallResult(False, [], [], f"stopped after {timeout:g} s (time limit): an infinite loop, or far too slow",
                              seconds=seconds, stdout=stdout, notes=notes)
        data = _parse_results(raw)
        if data is None:
            why = (f"its results exceed {OUTPUT_LIMIT >> 20} MiB" if too_big else _exit_reason(code, memory_mb))
            return CallResult(False, [], [], f"the module's process ended without returning results ({why})",
                              seconds=seconds, stdout=stdout, notes=notes)
        blobs = data.pop("_blobs")
        viol = data.get("violations", [])
        res = CallResult(True, [], [], violations=[str(v)[:300] for v in (viol if isinstance(viol, list) else [])][:20],
                         sandbox=data.get("sandbox", {}) if isinstance(data.get("sandbox"), dict) else {},
                         seconds=seconds, stdout=stdout, notes=notes)
        res.sandbox["isolation"] = iso.kind
        if "import_error" in data:
            res.ok = False
            err = str(data["import_error"])[:6000]
            if err.startswith("the module has no function"):
                res.message, res.errors = err, []
            else:
                res.message, res.errors = "importing the module failed", [err]
            return res
        results = data.get("results", [])
        for r in (results if isinstance(results, list) else [])[:len(calls)]:
            loc = r.get("npy") if isinstance(r, dict) else None
            if isinstance(loc, list) and len(loc) == 2 and all(isinstance(x, int) and x >= 0 for x in loc) \
                    and loc[0] + loc[1] <= len(blobs):
                try:
                    res.outputs.append(_decode_npy(bytes(blobs[loc[0]:loc[0] + loc[1]])))
                    res.errors.append(None)
                except (ValueError, OSError, SyntaxError) as e:
                    res.outputs.append(None)
                    res.errors.append(f"the result could not be read back as numbers ({e})")
            else:
                res.outputs.append(None)
                res.errors.append(str(r.get("error", "no result"))[:6000] if isinstance(r, dict) else "no result")
        while len(res.outputs) < len(calls):
            res.outputs.append(None)
            res.errors.append("no result")
        return res
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _exit_reason(code, memory_mb) -> str:
    if code is None:
        return "unknown"
    if code < 0:
        sig = -code
        name = signal.Signals(sig).name if sig in signal.Signals._value2member_map_ else f"signal {sig}"
        if sig == signal.SIGXCPU:
            return f"{name}: CPU time limit"
        if sig == signal.SIGSEGV:
            return f"{name}: a crash in native code, or the {memory_mb} MiB memory limit"
        if sig == signal.SIGKILL:
            return f"{name}: killed, probably the {memory_mb} MiB memory limit"
        return name
    return f"exit code {code}"


# --------------------------------------------------------------------------
# Checks
# --------------------------------------------------------------------------


@dataclass
class CheckOutcome:
    fraction: float  # of the check's points earned
    message: str
    details: dict = field(default_factory=dict)


def _failure_text(res: CallResult, i: int = 0) -> str:
    """One summary line (what went wrong), then the details (traceback, output)."""
    head, parts = [], []
    if res.violations:
        head.append("the sandbox refused: " + "; ".join(dict.fromkeys(res.violations)))
    if not res.ok and res.message:
        head.append(res.message)
    err = res.errors[i] if i < len(res.errors) else None
    if err:
        last = [ln for ln in err.strip().splitlines() if ln.strip()]
        if last and not head:
            head.append(last[-1].strip())
        if "Permission denied" in err and not res.violations:
            head.append("(the sandbox lets a module read only its own folder and the Python installation)")
        parts.append("traceback:\n" + err.strip())
    if res.stdout.strip() and not res.ok:
        parts.append("output (last lines):\n" + res.stdout.strip()[-1500:])
    return "\n".join(["; ".join(head) or "no result", *parts])


def _as(arr, shape_tail: tuple, n: int, what: str):
    if arr is None:
        return None, f"{what}: no result"
    a = np.asarray(arr, dtype=np.float64)
    want = (n, *shape_tail)
    if a.shape != want:
        return None, f"{what}: returned shape {a.shape}, expected {want}"
    return a, None


def check_sample_cosine(run, params: dict) -> CheckOutcome:
    from mcrt.stats import StatsError, chi2_gof

    n = int(params["samples"])
    rng = np.random.default_rng(12345)  # pinned: the check is a pure function of the student's code
    u = rng.random((2, n))
    res = run("sample_cosine_hemisphere", [{"args": [{"npy": "u1.npy"}, {"npy": "u2.npy"}]}], {"u1.npy": u[0], "u2.npy": u[1]})
    if not res.outputs or res.outputs[0] is None:
        return CheckOutcome(0.0, _failure_text(res))
    w, err = _as(res.outputs[0], (3,), n, "sample_cosine_hemisphere")
    if err:
        return CheckOutcome(0.0, err)
    if not np.isfinite(w).all():
        return CheckOutcome(0.0, f"{int((~np.isfinite(w)).any(axis=1).sum())} of {n} directions contain NaN or inf")
    norm = np.linalg.norm(w, axis=1)
    bad = np.abs(norm - 1) > 1e-4
    if bad.mean() > 1e-3:
        return CheckOutcome(0.0, f"{100 * bad.mean():.1f} % of the directions are not unit length (e.g. length {norm[bad][0]:.4f}); "
                                 "a Lambertian sample must lie on the unit hemisphere (a point inside the ball plus the "
                                 "normal, not normalised, is a known mistake)")
    below = w[:, 2] < -1e-9
    if below.any():
        return CheckOutcome(0.0, f"{int(below.sum())} directions are below the horizon (z < 0)")
    z = np.clip(w[:, 2], 0, 1)
    phi = (np.arctan2(w[:, 1], w[:, 0]) / (2 * np.pi)) % 1.0
    k = 16
    obs, _, _ = np.histogram2d(z * z, phi, bins=k, range=[[0, 1], [0, 1]])
    exp = np.full_like(obs, n / k**2)
    try:
        stat, dof, p = chi2_gof(obs, exp)
    except StatsError as e:
        return CheckOutcome(0.0, f"chi-square test impossible: {e}")
    mz = float(z.mean())
    d = {"chi2": stat, "dof": dof, "p": p, "mean_cos_theta": mz}
    hint = ""
    if abs(mz - 0.5) < 0.01:
        hint = "; the mean of cos(theta) is 1/2, as for uniform hemisphere sampling (cosine-weighted gives 2/3)"
    elif abs(mz - 2 / 3) > 0.01:
        hint = f"; the mean of cos(theta) is {mz:.3f} where cosine-weighted sampling gives 2/3"
    if p < params["alpha"]:
        return CheckOutcome(0.0, f"not cosine-distributed: chi-square {stat:.1f} with {dof} degrees of freedom, p = {p:.2g} "
                                 f"< {params['alpha']:g} over {n} samples in (cos^2 theta, phi) bins{hint}", d)
    return CheckOutcome(1.0, f"cosine-distributed: chi-square {stat:.1f} with {dof} degrees of freedom, p = {p:.2g}; "
                             f"mean cos(theta) {mz:.4f} (2/3 expected)", d)


def _moller_trumbore(o, d, v0, v1, v2):
    e1, e2 = v1 - v0, v2 - v0
    p = np.cross(d, e2)
    det = p @ e1
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        tv = o - v0
        u = np.einsum("ij,ij->i", tv, p) * inv
        q = np.cross(tv, e1)
        v = np.einsum("ij,ij->i", d, q) * inv
        t = (q @ e2) * inv
    hit = (np.abs(det) > 1e-12) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-9)
    margin = np.minimum(np.minimum(np.abs(u), np.abs(v)), np.abs(1 - u - v))
    return np.where(hit, t, np.inf), margin


def check_intersect(run, params: dict) -> CheckOutcome:
    rng = np.random.default_rng(2024)  # pinned
    n_tri, n = 40, max(10, int(params["rays"]) // 40)
    calls, arrays, cases = [], {}, []
    for k in range(n_tri):
        v = rng.normal(size=(3, 3)) * rng.uniform(0.5, 5)
        o = rng.normal(size=(n, 3)) * 4 + v.mean(axis=0)
        # Aim half of the rays at points in the triangle's plane near it, the rest anywhere.
        bary = rng.uniform(-0.3, 1.0, size=(n, 2))
        target = v[0] + bary[:, :1] * (v[1] - v[0]) + bary[:, 1:] * (v[2] - v[0])
        d = np.where(rng.random((n, 1)) < 0.6, target - o, rng.normal(size=(n, 3)))
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        names = [f"o{k}.npy", f"d{k}.npy", f"a{k}.npy", f"b{k}.npy", f"c{k}.npy"]
        for nm, arr in zip(names, (o, d, v[0], v[1], v[2])):
            arrays[nm] = arr
        calls.append({"args": [{"npy": nm} for nm in names]})
        cases.append((o, d, v))
    res = run("intersect_triangle", calls, arrays)
    if not res.outputs or all(x is None for x in res.outputs):
        return CheckOutcome(0.0, _failure_text(res))
    agree = total = 0
    t_err = 0.0
    wrong_examples = []
    for k, (o, d, v) in enumerate(cases):
        out = res.outputs[k] if k < len(res.outputs) else None
        if out is None:
            return CheckOutcome(0.0, f"triangle {k}: " + _failure_text(res, k))
        t, err = _as(out, (), n, "intersect_triangle")
        if err:
            return CheckOutcome(0.0, err)
        ref, margin = _moller_trumbore(o, d, v[0], v[1], v[2])
        judge = margin > 1e-6
        hit_ref = np.isfinite(ref)
        hit = np.isfinite(t) & (t > 0)
        same = hit == hit_ref
        agree += int(np.count_nonzero(same & judge))
        total += int(np.count_nonzero(judge))
        both = judge & hit & hit_ref
        if both.any():
            t_err = max(t_err, float(np.max(np.abs(t[both] - ref[both]) / np.maximum(ref[both], 1e-9))))
        for i in np.flatnonzero(judge & ~same)[:1]:
            if len(wrong_examples) < 3:
                want = f"t = {ref[i]:.4g}" if hit_ref[i] else "a miss"
                got = f"t = {t[i]:.4g}" if hit[i] else "a miss"
                wrong_examples.append(f"ray {i} of triangle {k}: expected {want}, got {got}")
    frac = agree / max(total, 1)
    d = {"agreement": frac, "max_relative_t_error": t_err, "rays": total}
    if frac < 0.995:
        return CheckOutcome(0.0, f"hits and misses agree for only {100 * frac:.1f} % of {total} rays (99.5 % needed): "
                                 + "; ".join(wrong_examples) + " (both sides of a triangle count as hits)", d)
    if t_err > 1e-4:
        return CheckOutcome(0.0, f"hits agree, but distances are off by up to {100 * t_err:.3g} % (1e-4 relative allowed)", d)
    return CheckOutcome(1.0, f"{100 * frac:.2f} % of {total} rays agree with a float64 reference; distances within "
                             f"{t_err:.1e} (relative)", d)


def _light_dict(scene) -> dict:
    lt = scene.light
    return {"corners": lt.corners().tolist(), "normal": list(lt.normal), "radiance": float(lt.radiance[0])}


def check_direct(run, params: dict, scene) -> CheckOutcome:
    from scipy import stats as sps

    from mcrt.closed_form import polygon_irradiance
    from mcrt.stats import adjust_p_values

    rng = np.random.default_rng(77)  # pinned
    npts, k = int(params["positions"]), int(params["samples"])
    room = scene.room
    pts, nrm = [], []
    for i in range(npts):
        if i % 2 == 0:  # floor
            while True:
                p = np.array([rng.uniform(-2, 12), rng.uniform(-5.5, 5.5), room.floor_z])
                if room.contains(p + [0, 0, 1e-3], 1e-3):
                    break
            pts.append(p)
            nrm.append([0.0, 0.0, 1.0])
        else:  # a wall, at a random height
            planes = room.planes()[:-2]
            j = rng.integers(len(planes))
            n_out = planes[j, :3]
            poly = room.polygon()
            a, b = poly[j], poly[(j + 1) % len(poly)]
            s = rng.uniform(0.1, 0.9)
            xy = a + s * (b - a)
            pts.append(np.array([xy[0], xy[1], rng.uniform(room.floor_z + 0.5, room.ceiling_z - 1.0)]))
            nrm.append(-n_out)
    pts, nrm = np.array(pts), np.array(nrm)
    light = _light_dict(scene)
    expected = polygon_irradiance(pts, nrm, np.array(light["corners"]), light["radiance"])
    P = np.repeat(pts, k, axis=0)
    N = np.repeat(nrm, k, axis=0)
    U = rng.random((npts * k, 2))
    res = run("estimate_direct", [{"args": [{"npy": "p.npy"}, {"npy": "n.npy"}, {"json": light}, {"npy": "u.npy"}]}],
              {"p.npy": P, "n.npy": N, "u.npy": U})
    if not res.outputs or res.outputs[0] is None:
        return CheckOutcome(0.0, _failure_text(res))
    e, err = _as(res.outputs[0], (), npts * k, "estimate_direct")
    if err:
        return CheckOutcome(0.0, err)
    if not np.isfinite(e).all():
        return CheckOutcome(0.0, f"{int((~np.isfinite(e)).sum())} estimates are NaN or inf")
    e = e.reshape(npts, k)
    m, sd = e.mean(axis=1), e.std(axis=1, ddof=1)
    se = np.sqrt(sd**2 / k + (1e-9 * expected) ** 2)
    z = (m - expected) / np.where(se > 0, se, 1e-30)
    p = 2 * sps.norm.sf(np.abs(z))
    p = np.where((se == 0) & np.isclose(m, expected, rtol=1e-6), 1.0, p)
    rel = (m - expected) / np.maximum(expected, 1e-12)
    bad = (adjust_p_values(p, "holm") <= params["alpha"]) & (np.abs(rel) >= 0.01)
    ratio = m / np.maximum(expected, 1e-12)
    d = {"expected": expected.tolist(), "mean": m.tolist(), "z": z.tolist(), "ratio": ratio.tolist()}
    if bad.any():
        i = int(np.flatnonzero(bad)[np.argmax(np.abs(z[bad]))])
        spread = float(np.std(np.log(np.maximum(ratio, 1e-12))))
        hint = ""
        if spread < 0.02:
            hint = (f"; the ratio to the right answer is the same everywhere ({float(np.median(ratio)):.3g}): a constant "
                    "factor is wrong (the light's area in the pdf, pi, the radiance)")
        else:
            hint = (f"; the ratio to the right answer varies from {ratio.min():.3g} to {ratio.max():.3g} between points: "
                    "a geometric term (a cosine or 1/d^2) is missing or wrong")
        return CheckOutcome(0.0, f"wrong at {int(bad.sum())} of {npts} points (Holm, alpha {params['alpha']:g}, over 1 % off); "
                                 f"e.g. at ({', '.join(f'{x:.2f}' for x in pts[i])}) with normal "
                                 f"({', '.join(f'{x:.0f}' for x in nrm[i])}): expected {expected[i]:.4g}, got "
                                 f"{m[i]:.4g} +- {se[i]:.2g}{hint}", d)
    return CheckOutcome(1.0, f"unbiased at all {npts} points ({k} samples each, largest |z| {np.max(np.abs(z)):.2f})", d)


def check_render(run, params: dict, a: Assignment, ctx, scene_dict: dict) -> tuple[CheckOutcome, StudentResult | None]:
    from mcrt.grade.grader import grade_image

    w, h, spp = int(params["width"]) or a.width, int(params["height"]) or a.height, int(params["spp"]) or a.spp
    calls = [{"args": [{"json": scene_dict}, a.camera, w, h, spp, seed, a.max_depth]} for seed in (1, 2)]
    res = run("render", calls, {}, first_of_tuple=True)
    imgs = [o for o in res.outputs if o is not None]
    if not imgs:
        return CheckOutcome(0.0, _failure_text(res)), None
    bad = [i for i in imgs if i.ndim != 3 or i.shape[2] not in (3, 4) or i.shape[:2] != imgs[0].shape[:2]]
    if bad:
        return CheckOutcome(0.0, f"render returned shape {bad[0].shape}, expected ({h}, {w}, 3)"), None
    imgs = [i[..., :3] for i in imgs]
    notes = []
    if len(imgs) == 2 and np.array_equal(np.nan_to_num(imgs[0]), np.nan_to_num(imgs[1])):
        notes.append("seeds 1 and 2 gave identical images: the seed is ignored")
        imgs = imgs[:1]
    sr = grade_image("render", ctx, imgs, spp=spp, notes=notes)
    frac = sr.score / sr.max_score if sr.max_score > 0 else 0.0
    lost = [f"{t.title}: {t.output}" for t in sr.tests if t.score < t.max_score]
    msg = f"graded as an image ({sr.score:g}/{sr.max_score:g} of the image rubric): {sr.summary}"
    if lost:
        msg += "\n" + "\n".join(f"- {x}" for x in lost)
    if res.violations:
        msg += "\nthe sandbox refused: " + "; ".join(dict.fromkeys(res.violations))
    return CheckOutcome(frac, msg, {"image": sr.details, "diagnosis": sr.diagnosis}), sr


# --------------------------------------------------------------------------
# One student, the class
# --------------------------------------------------------------------------


def find_module(src: Path, module: str | None) -> tuple[Path | None, str | None, str]:
    """(what to copy, module file name inside it, problem); a link is never followed."""
    try:
        st = os.lstat(src)
    except OSError:
        return None, None, "no such file or folder"
    if stat.S_ISLNK(st.st_mode):
        return None, None, f"{src.name} is a symbolic link (links are not followed: hand in the file itself)"
    if stat.S_ISREG(st.st_mode):
        if src.suffix != ".py":
            return None, None, f"{src.name} is not a Python file (.py)"
        return src, src.name, ""
    if not stat.S_ISDIR(st.st_mode):
        return None, None, f"{src.name} is not a regular file or folder"

    def regular(p: Path) -> bool:
        try:
            return stat.S_ISREG(os.lstat(p).st_mode)
        except OSError:
            return False

    if module:
        if regular(src / module):
            return src, module, ""
        if os.path.islink(src / module):
            return None, None, f"{module} is a symbolic link (links are not followed: hand in the file itself)"
        return None, None, f"the folder has no {module} (the assignment asks for that file)"
    pys = sorted(p.name for p in src.iterdir() if p.suffix == ".py" and not p.name.startswith(".") and regular(p))
    if len(pys) == 1:
        return src, pys[0], ""
    if not pys:
        return None, None, "the folder holds no Python file"
    return None, None, f"several Python files ({', '.join(pys)}); the assignment does not say which to grade"


def grade_code(student: str, src: Path, a: Assignment, *, ctx=None, timeout: float | None = None,
               memory_mb: int | None = None) -> StudentResult:
    """Run every check of ``a.code`` on one student's module."""
    t0 = time.perf_counter()
    spec = a.code
    to = timeout or spec.timeout
    mem = memory_mb or spec.memory_mb
    details: dict = {}
    notes: list[str] = []
    diagnosis: list = []
    root, mod, problem = find_module(Path(src), spec.module)
    stage = None
    if root is not None:
        # Copied once, without following links: every call then copies this copy, never the student's folder.
        stage = Path(tempfile.mkdtemp(prefix="mcrt-sub-"))
        skipped = copy_submission(root, stage / "s")
        notes += [f"submission: {n}" for n in skipped]
        root = stage / "s" / root.name if root.is_file() else stage / "s"
    try:
        return _grade_code_checks(student, a, root, mod, problem, ctx, to, mem, details, notes, diagnosis, t0)
    finally:
        if stage is not None:
            shutil.rmtree(stage, ignore_errors=True)


def _grade_code_checks(student, a, root, mod, problem, ctx, to, mem, details, notes, diagnosis, t0):
    rub = Rubric(code_items(a, CHECK_TITLES), mode="code")
    scene = None
    for chk in a.code.checks:
        if root is None:
            rub.not_graded(chk.name, f"not graded: {problem}")
            continue

        def run(function, calls, arrays, first_of_tuple=False):
            return run_student(root, mod, function, calls, arrays, timeout=to, memory_mb=mem, first_of_tuple=first_of_tuple)

        try:
            out, scene, ctx, sr = _run_check(chk, run, a, scene, ctx)
            if sr is not None:
                diagnosis = sr.diagnosis
        except Exception as e:  # noqa: BLE001 - a grader bug must not stop the class
            out = CheckOutcome(0.0, f"the grader failed on this check ({type(e).__name__}: {e})")
        details[chk.name] = out.details
        rub.credit(chk.name, out.fraction, out.message)
    if problem:
        notes.append(problem)
    details["mode"] = "code"
    details["sandbox"] = isolation().detail
    res = rub.result(student, notes=notes, diagnosis=diagnosis, details=details)
    res.elapsed = time.perf_counter() - t0
    return res


def _run_check(chk, run, a: Assignment, scene, ctx):
    """One check's outcome; the scene and the context are loaded on first use and passed on."""
    sr = None
    if chk.name == "sample_cosine_hemisphere":
        out = check_sample_cosine(run, chk.params)
    elif chk.name == "intersect_triangle":
        out = check_intersect(run, chk.params)
    elif chk.name == "estimate_direct":
        scene = scene or a.load_scene()
        out = check_direct(run, chk.params, scene)
    elif chk.name == "render":
        import tomllib

        scene = scene or a.load_scene()
        with open(scene.path, "rb") as f:
            scene_dict = tomllib.load(f)
        if ctx is None:
            from mcrt.grade.expected import prepare_context

            ctx = prepare_context(a)
        out, sr = check_render(run, chk.params, a, ctx, scene_dict)
    else:  # pragma: no cover - validated by the assignment loader
        out = CheckOutcome(0.0, f"unknown check {chk.name}")
    return out, scene, ctx, sr


def discover_code(path, *, single: bool = False, student: str | None = None) -> list[tuple[str, Path]]:
    from mcrt.grade.submissions import _unique, safe_id

    root = Path(path)
    if not root.exists():
        raise FileNotFoundError(f"{root}: no such file or folder")
    if root.is_file() or single:
        return [(safe_id(student or (root.stem if root.is_file() else root.name)), root)]
    # Links and special files stay in the list: find_module refuses each with its message (never followed, never opened).
    entries = sorted((p for p in root.iterdir() if not p.name.startswith((".", "__"))), key=lambda p: p.name)
    ids = _unique([safe_id(p.stem if p.is_file() else p.name) for p in entries])
    return list(zip(ids, entries))


def grade_code_class(submissions, a: Assignment, out, *, jobs: int = 1, timeout: float | None = None, memory_mb: int | None = None,
                     cache_dir=None, single: bool = False, student: str | None = None, context=None, log=None):
    """Grade every student's module; writes the same files as image mode.

    ``jobs`` students at a time (each check is its own sandboxed process);
    ``context`` reuses a prepared image-mode context for the ``render`` check.
    """
    from mcrt.grade.batch import ClassResult
    from mcrt.grade.grader import error_result
    from mcrt.grade.report import write_class, write_student

    t0 = time.perf_counter()
    log = log or (lambda s: None)
    out = Path(out)
    subs = discover_code(submissions, single=single, student=student)
    log(f"mcrt grade (code): {len(subs)} submission(s)")
    iso = isolation()  # a fallback is announced on stderr there
    log(f"sandbox: {iso.detail}")
    ctx = context
    if ctx is None and any(c.name == "render" for c in a.code.checks):
        from mcrt.grade.expected import prepare_context

        ctx = prepare_context(a, cache_dir, log=log)
    crit = [(c.name, c.points, CHECK_TITLES.get(c.name, c.name)) for c in a.code.checks]

    def one(item):
        sid, src = item
        try:
            r = grade_code(sid, src, a, ctx=ctx, timeout=timeout, memory_mb=memory_mb)
        except Exception as e:  # noqa: BLE001 - one student never stops the class
            from mcrt.grade.grader import format_exception

            r = error_result(sid, a, "error", f"the grader failed ({type(e).__name__}: {e})", format_exception(), criteria=crit)
        write_student(r, a, out)
        log(f"  {sid}: {r.score:g}/{r.max_score:g} ({r.elapsed:.1f} s)")
        r.figures = {}
        return r

    with ThreadPoolExecutor(max_workers=max(1, jobs)) as ex:
        results = list(ex.map(one, subs))
    elapsed = time.perf_counter() - t0
    summary = write_class(results, a, out, elapsed=elapsed, criteria=crit, context_note=f"Sandbox: {iso.detail}.")
    return ClassResult(results, summary, out, elapsed, ctx)
