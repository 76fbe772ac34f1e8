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

Every call runs in a fresh process (``python -I -B mcrt/grade/_sandbox.py``,
see that file for the order in which it locks itself down), and student code
never runs as root, on any path: as root the grader hands the runner a
fresh unprivileged uid (one per call, no such user on the system) and the
runner switches to it by setgroups/setresgid/setresuid before anything of
the student's loads, whatever the file modes of the installation; it
refuses to go on if the switch did not take.

With bubblewrap (``bwrap``, Debian's package ``bubblewrap``): new PID,
network, IPC and UTS namespaces (and a user namespace when the grader is not
root), so nothing leaves the sandbox's own loopback; read-only binds of only
what the module may read (the Python installation, its virtual environment
and site-packages, /usr and the loader's files, the call's inputs), with
mcrt, Mitsuba and Dr.Jit hidden under empty unreadable folders wherever they
are installed (never the references, the grader, other students' folders or
/etc); a tmpfs of :data:`DISK_LIMIT` bytes and :data:`INODE_LIMIT` files as
its only writable folder; ``--die-with-parent`` and ``--new-session``; its
options passed through a pipe (``--args``), so that /proc/1/cmdline in the
sandbox does not show them.

Without bubblewrap, or where namespaces are forbidden (probed by running
``bwrap`` once), the grader says so on stderr and in the class summary and
falls back to Landlock (read-only file system, nothing made even in the
work folder, readable only the Python installation without mcrt, Mitsuba
and Dr.Jit and system folders), the same seccomp filter, rlimits, the
unprivileged uid and a new session (the runner, in a session of its own, still
dies with the process that started it: ``PR_SET_PDEATHSIG``, set after the switch
of user, which clears it); the call's folders then go where that
uid can reach them. Where neither is possible code mode is refused
(:class:`SandboxError`) unless the instructor passes
``--allow-unisolated-code`` (:func:`allow_unisolated`). ``MCRT_SANDBOX``:
``bwrap`` makes a missing bubblewrap an error, ``fallback`` forces the
fallback, ``none`` acts as if neither were possible (tests).

On both paths a submission is one process (seccomp refuses fork and memfd;
threads share one address-space limit), so the limits of :func:`_limits`
bound all of it and a wall-clock timeout kills it, whatever it does. Before
anyone is graded a correct module runs through the sandbox
(:func:`_self_test`): a sandbox that cannot import NumPy stops the batch
with the grader's problem named, instead of giving every student 0. The
runner reports each refused operation at once on a pipe the grader reads
(:class:`_Monitor`), and a runner that fails before the student's code is
reported as the grader's fault (``CallResult.grader_fault``). The grader
never opens a path the student could have made: the student's output goes
to files it opened itself and unlinked (a link or a FIFO planted in the work
folder changes nothing), results are capped at :data:`OUTPUT_LIMIT` before
they are decoded, and a submission folder is copied without following links
(a link is skipped with a message) and capped in size.

A crash, a hang, a memory blow-up or a refused operation is a graded failure
of that check, with the student's traceback.

A class is graded by image mode's class runner (:func:`mcrt.grade.batch.grade_class`, given
:func:`code_plan`): worker processes, run.json, resume; a worker grades a student by
:meth:`CodeContext.grade`. The shared-import warning (:func:`shared_import_failure`) looks at the
students graded by this run, not those kept from an earlier one.
"""

from __future__ import annotations

import glob
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
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mcrt.grade.assignment import Assignment
from mcrt.grade.scoring import Rubric, StudentResult, code_items

RUNNER = Path(__file__).with_name("_sandbox.py")
FSIZE_LIMIT = 128 << 20  # any one file the student's process writes (its stdout included)
DISK_LIMIT = 128 << 20  # the sandbox's tmpfs: all it may write together (its pages count against the container too)
INODE_LIMIT = 4096  # files and folders on that tmpfs (each costs kernel memory, outside every other bound)
OUTPUT_LIMIT = 64 << 20  # the results of one check's calls together, as the grader reads them
TRAILER_LIMIT = 4 << 20  # their JSON description (tracebacks, what the sandbox enforced)
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
    grader_fault: bool = False  # the sandbox failed before the student's code ran: not the student's doing


def _read_roots() -> list[str]:
    """Folders the student's process may read: the Python installation and system folders.

    Never the project (references, the grader, other output) nor any folder
    holding it; inside the project only the virtual environment. Of /proc
    only cpuinfo and meminfo here; the runner adds its own /proc/<pid> (never
    the grader's, whose environment would be readable there). Used by the
    fallback (Landlock, :func:`_landlock_rules`); bubblewrap binds
    :func:`_python_roots` and system folders instead.
    """
    return sorted(set(_python_roots()) | _existing({"/usr", "/lib", "/lib64", "/lib32", "/bin", "/sbin", "/etc", "/sys",
                                                    "/opt", "/proc/cpuinfo", "/proc/meminfo", "/dev/urandom", "/dev/zero"}))


def _existing(cands) -> set[str]:
    return {os.path.realpath(c) for c in cands if os.path.exists(c)}


def _project_root() -> Path | None:
    """The source checkout mcrt runs from, or None for an installed package (a wheel in site-packages)."""
    home = Path(__file__).resolve().parent.parent.parent
    return home if (home / "pyproject.toml").is_file() else None


def _python_roots() -> list[str]:
    """The Python installation, the virtual environment and the folders of sys.path, never a source checkout.

    An installed mcrt lies in site-packages with NumPy: that folder is bound
    like any other, and :func:`_hidden_paths` hides mcrt's own folder in it.
    """
    repo = _project_root()
    venv = Path(sys.prefix).resolve()
    cands = {sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix, os.path.dirname(os.path.realpath(sys.executable))}
    prefixes = [Path(p).resolve() for p in (sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix)]
    # Of sys.path only library folders: never the folder of the grader's script or the current folder (which
    # `python -m` puts first), where the instructor's solutions or the other students' files may be.
    cands |= {p for p in sys.path if p and os.path.isdir(p) and (
        Path(p).name in ("site-packages", "dist-packages") or any(Path(p).resolve().is_relative_to(x) for x in prefixes))}
    out = set()
    for c in _existing(cands):
        r = Path(c)
        if r == Path("/"):
            continue
        if repo is not None:
            if r == repo or repo.is_relative_to(r):
                continue  # an ancestor of the checkout would expose it
            if r.is_relative_to(repo) and not r.is_relative_to(venv):
                continue
        out.add(str(r))
    # The outermost folders only (a bind covers what is under it).
    return sorted(r for r in out if not any(r != o and Path(r).is_relative_to(o) for o in out))


HIDDEN_PACKAGES = ("mcrt", "mitsuba", "drjit")  # the grader (its references) and the reference renderers
# Where Pythons install packages, under a root such as /usr, /opt, an installation or a venv.
_SITE_PATTERNS = [f"{pre}lib*/python3*/{kind}-packages" for pre in ("", "local/", "*/") for kind in ("site", "dist")]


def _hidden_paths(roots) -> list[str]:
    """What must stay unreadable under ``roots``: mcrt, Mitsuba and Dr.Jit wherever Python could import them from.

    That is the grader's sys.path, and also every site-packages under a root
    (another Python's, the base installation's of a venv): graded code may
    put any readable folder on its own sys.path.
    """
    out = {str(Path(__file__).resolve().parent.parent)}
    dirs = {os.path.realpath(p) for p in sys.path if p and os.path.isdir(p)} | set(roots)
    for r in roots:
        if any(Path(r).is_relative_to(o) for o in ("/sys", "/etc", "/proc", "/dev")) or \
                any(r != o and Path(r).is_relative_to(o) for o in roots):
            continue  # no Python there (/sys alone is thousands of folders), or looked through from a root above
        for pattern in _SITE_PATTERNS:
            dirs |= {os.path.realpath(p) for p in glob.glob(os.path.join(glob.escape(r), pattern)) if os.path.isdir(p)}
    for d in dirs:
        for name in HIDDEN_PACKAGES:
            for cand in (os.path.join(d, name), os.path.join(d, name + ".libs")):
                if os.path.isdir(cand):
                    out.add(os.path.realpath(cand))
    repo = _project_root()
    if repo is not None:
        out.add(str(repo))
    return sorted(h for h in out if any(Path(h).is_relative_to(r) for r in roots))


def _landlock_rules(roots, hidden) -> list[list[str]]:
    """Landlock's allow-list: every root readable except the hidden folders, which stay listable only.

    Landlock only grants, so a root holding a hidden folder is split: the
    folders on the way to it may be listed, and each of their other entries
    is granted whole. A symbolic link among those entries is never granted:
    Landlock grants the inode the link resolves to, so a venv's ``lib64 ->
    lib`` granted whole would grant all of ``lib``, hidden folders included.
    A link's target inside a root has rules of its own; one outside every
    root stays unreadable, as it is unbound under bubblewrap.
    """
    rules: list[list[str]] = []

    def grant(path: str) -> None:
        if os.path.islink(path):
            return
        inner = [h for h in hidden if Path(h).is_relative_to(path)]
        if not inner:
            rules.append([path, "read"])
            return
        if path in inner or not os.path.isdir(path):
            return
        rules.append([path, "list"])
        try:
            names = sorted(os.listdir(path))
        except OSError:
            return
        for n in names:
            grant(os.path.join(path, n))

    for r in roots:
        grant(r)
    return rules


def _world_traversable(path: str) -> bool:
    p = Path(path).resolve()
    for q in [p, *p.parents]:
        try:
            if not os.stat(q).st_mode & stat.S_IXOTH:
                return False
        except OSError:
            return False
    return True


def _scratch_base(iso: "Isolation") -> str | None:
    """Where a call's folders go: the usual temporary folder, except that without bubblewrap the unprivileged
    uid must be able to reach them (a folder under a private parent such as /root would be out of its reach)."""
    if iso.kind == "bubblewrap":
        return None
    for cand in (tempfile.gettempdir(), "/tmp", "/var/tmp", "/dev/shm"):
        if os.path.isdir(cand) and os.access(cand, os.W_OK) and _world_traversable(cand):
            return cand
    return None


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
    kind: str  # "bubblewrap", "fallback" (Landlock + seccomp) or "none" (refused unless the instructor allows it)
    detail: str  # one line for stderr and the class summary
    bwrap: str | None = None
    options: frozenset = frozenset()  # optional bwrap options this version has


class SandboxError(RuntimeError):
    """Code mode cannot run here: no isolation, or the sandbox fails on a correct module (the grader's problem)."""


_ISOLATION: Isolation | None = None
_ISOLATION_LOCK = threading.Lock()
_ALLOW_UNISOLATED = False
_NS_FLAGS = ["--unshare-pid", "--unshare-net", "--unshare-ipc", "--unshare-uts", "--unshare-cgroup-try"]
SANDBOX_ENV = "MCRT_SANDBOX"  # auto (default), bwrap, fallback, none (as if neither were possible: tests)
REFUSAL = ("code mode refused: student code would run without isolation ({why}). Install bubblewrap "
           "(apt-get install bubblewrap) or use a Linux with Landlock (5.13 or later) and seccomp; "
           "--allow-unisolated-code runs it anyway, as an unprivileged user with resource limits only")


def allow_unisolated(flag: bool = True) -> None:
    """The instructor's choice (``mcrt grade --allow-unisolated-code``) to run student code where nothing isolates it."""
    global _ALLOW_UNISOLATED
    _ALLOW_UNISOLATED = bool(flag)


def _probe_bwrap() -> Isolation:
    exe = shutil.which("bwrap")
    if exe is None:
        return Isolation("fallback", "bubblewrap (bwrap) is not installed (apt-get install bubblewrap)")
    try:
        helptext = subprocess.run([exe, "--help"], capture_output=True, text=True, timeout=10).stdout
    except (OSError, subprocess.SubprocessError) as e:
        return Isolation("fallback", f"bwrap does not run ({e})")
    opts = frozenset(o for o in ("--size", "--perms", "--disable-userns", "--die-with-parent", "--new-session", "--args")
                     if o in helptext)
    if not {"--perms", "--die-with-parent", "--new-session", "--args"} <= opts:
        return Isolation("fallback", f"{exe} is too old (no --perms, --die-with-parent, --new-session or --args; 0.5 or later needed)")
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
    if os.geteuid() == 0:
        disk = f"a tmpfs of {DISK_LIMIT >> 20} MiB and {INODE_LIMIT} files as the only writable folder"
    else:
        disk = (f"a {DISK_LIMIT >> 20} MiB tmpfs as the only writable folder (no file-count bound: the grader is not root)"
                if "--size" in opts else "a tmpfs without a size bound (this bwrap has no --size) as the only writable folder")
    return Isolation("bubblewrap", f"{ver}: PID, network, IPC and UTS namespaces, an unprivileged uid, one process "
                                   f"(no fork), read-only system without mcrt, Mitsuba or Dr.Jit, {disk}", exe, opts)


def _landlock_abi() -> int:
    import ctypes

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.syscall.restype = ctypes.c_long
        return int(libc.syscall(444, None, ctypes.c_size_t(0), ctypes.c_uint32(1)))  # landlock_create_ruleset, VERSION
    except (OSError, AttributeError):
        return -1


def _probe_fallback(why: str) -> Isolation:
    import platform

    missing = []
    if _landlock_abi() < 1:
        missing.append("no Landlock (Linux 5.13 or later with the landlock LSM)")
    if platform.machine() not in ("x86_64", "aarch64"):
        missing.append(f"no seccomp filter for {platform.machine()}")
    if _scratch_base(Isolation("fallback", "")) is None:
        missing.append("no temporary folder that an unprivileged user can reach")
    if missing:
        return Isolation("none", f"{why}; {'; '.join(missing)}")
    who = "an unprivileged uid (switched to by the runner: the grader is root)" if os.geteuid() == 0 else \
        f"the grader's own uid {os.geteuid()}"
    private = [r for r in _python_roots() if not _world_traversable(r)]
    if os.geteuid() == 0 and private:
        who += (f"; {private[0]} is out of that user's reach (a parent folder without o+x), so graded code imports "
                "only NumPy and the common standard modules loaded before the switch (chmod o+rx its folders, or "
                "use bubblewrap, to give it the rest)")
    return Isolation("fallback", f"WARNING: student code is NOT isolated by namespaces: {why}. Falling back to Landlock "
                                 f"(read-only system without mcrt, Mitsuba or Dr.Jit), seccomp (one process, no fork, exec or "
                                 f"memfd), rlimits and a new session, running as {who}; no file can be written (no quota could bound it), and "
                                 "its network traffic is not contained by namespaces (TCP is refused by Landlock ABI 4 or later)")


CANARY = """import numpy as np
import os
def f(x):
    return np.array([float(os.getuid()), float(os.getgid()), float(np.linalg.norm(np.random.default_rng(0).random(3)) > 0)])
"""


def _self_test(iso: Isolation) -> None:
    """Run a correct module through the sandbox once; raise :class:`SandboxError` naming the problem if it fails.

    A batch in which every student's import of NumPy fails is the grader's
    installation failing, not the students: it stops here, before anyone is
    graded.
    """
    tmp = Path(tempfile.mkdtemp(prefix="mcrt-canary-"))
    try:
        (tmp / "canary.py").write_text(CANARY)
        res = _run_student(iso, tmp / "canary.py", "canary.py", "f", [{"args": [1.0]}], {}, timeout=60, memory_mb=1024)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    out = res.outputs[0] if res.outputs else None
    if out is None or out.shape != (3,):
        why = res.message or "no result"
        err = next((e for e in res.errors if e), "") or res.stdout
        last = [ln for ln in str(err).strip().splitlines() if ln.strip()]
        raise SandboxError(f"the sandbox ({iso.kind}) fails on a correct module, so every student would fail: {why}"
                           f"{': ' + last[-1].strip() if last else ''} (a problem of the grader's installation, not the students')")
    if os.geteuid() == 0 and (out[0] == 0 or out[1] == 0):
        raise SandboxError(f"the sandbox ({iso.kind}) ran a module as root (uid {out[0]:g}, gid {out[1]:g}); refusing code mode")


def isolation() -> Isolation:
    """How student code is isolated here (probed and self-tested once; ``MCRT_SANDBOX``: auto, bwrap, fallback, none).

    Raises :class:`SandboxError` when no isolation is possible (unless
    :func:`allow_unisolated`) or when the sandbox fails on a correct module.
    """
    global _ISOLATION
    with _ISOLATION_LOCK:
        if _ISOLATION is None:
            want = os.environ.get(SANDBOX_ENV, "auto").strip().lower() or "auto"
            if want not in ("auto", "bwrap", "fallback", "none"):
                raise SandboxError(f"{SANDBOX_ENV}={want}: expected auto, bwrap, fallback or none")
            if want == "none":
                iso = Isolation("none", f"{SANDBOX_ENV}=none: neither bubblewrap nor Landlock and seccomp")
            elif want == "fallback":
                iso = _probe_fallback(f"{SANDBOX_ENV}=fallback asks for no bubblewrap")
            else:
                iso = _probe_bwrap()
                if iso.kind != "bubblewrap":
                    if want == "bwrap":
                        raise SandboxError(f"{SANDBOX_ENV}=bwrap, but {iso.detail}")
                    iso = _probe_fallback(iso.detail)
            if iso.kind == "none":
                if not _ALLOW_UNISOLATED:
                    raise SandboxError(REFUSAL.format(why=iso.detail))
                iso.detail = (f"WARNING: student code is NOT isolated ({iso.detail}); the instructor allowed it "
                              "(--allow-unisolated-code): an unprivileged uid, rlimits and a new session only")
            if iso.kind != "bubblewrap":
                print(f"mcrt grade: {iso.detail}", file=sys.stderr, flush=True)
            _self_test(iso)
            _ISOLATION = iso
        return _ISOLATION


def _sandbox_uid() -> int:
    return UID_BASE + (os.getpid() % 4096) * 4096 + next(_uids) % 4096


def _bwrap_argv(iso: Isolation, indir: Path, result_fd: int, monitor_fd: int, uid: int | None) -> list[str]:
    """bwrap's command line: what the module sees is exactly what is bound here."""
    root = os.geteuid() == 0
    argv = [iso.bwrap, *_NS_FLAGS, "--die-with-parent", "--new-session", "--hostname", "sandbox"]
    if root:
        # The runner mounts its work folder (inode budget), then switches to uid, which clears these.
        argv += ["--cap-add", "CAP_SETUID", "--cap-add", "CAP_SETGID", "--cap-add", "CAP_SYS_ADMIN"]
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
    roots = _python_roots()
    for r in roots:
        if not any(Path(r).is_relative_to(b) for b in bound):
            parents(r)
            argv += ["--ro-bind", r, r]
            bound.add(r)
    for m in _hidden_paths(sorted(bound)):  # an empty folder no one may read in place of each
        argv += ["--size", "4096"] if "--size" in iso.options else []
        argv += ["--perms", "0000", "--tmpfs", m, "--remount-ro", m]
    parents("/sandbox/x")
    argv += ["--ro-bind", str(RUNNER), "/sandbox/runner.py", "--ro-bind", str(indir), "/sandbox/in"]
    if "--size" in iso.options:
        argv += ["--size", str(DISK_LIMIT)]
    argv += ["--perms", "1777", "--tmpfs", "/sandbox/work",
             "--proc", "/proc", "--dev", "/dev", "--chdir", "/sandbox/work", "--",
             sys.executable, "-I", "-B", "/sandbox/runner.py", "/sandbox/in", "/sandbox/work", str(result_fd), str(monitor_fd)]
    return argv


# --------------------------------------------------------------------------
# Copying the submission, reading what comes back: never a link, never a special file
# --------------------------------------------------------------------------


def copy_submission(src: Path, dest: Path, *, limit: int = SUBMISSION_LIMIT, max_files: int = SUBMISSION_FILES,
                    first: str | None = None) -> list[str]:
    """Copy a student's file or folder into ``dest`` (a new folder) without following links.

    Regular files and folders only: a symbolic link, a FIFO, a socket or a
    device is skipped, and so is what exceeds ``limit`` bytes or
    ``max_files`` files in all; returns one message per thing skipped.
    Names starting with a dot and ``__pycache__`` are left out silently.
    ``first`` (a name at the top of a folder: the graded module) is copied before anything else, so that many other
    files cannot push it out of the budget.
    """
    copy = _SubmissionCopy(limit=limit, max_files=max_files, first=first)
    dest.mkdir(mode=0o755)
    st = os.lstat(src)
    if stat.S_ISLNK(st.st_mode):
        copy.skip(src.name, "a symbolic link (links are not followed)")
    elif stat.S_ISDIR(st.st_mode):
        copy.walk(src, "", dest, 0)
    elif stat.S_ISREG(st.st_mode):
        copy.copy_file(src, src.name, dest / src.name)
    else:
        copy.skip(src.name, "not a regular file")
    return copy.notes


class _SubmissionCopy:
    """One :func:`copy_submission`: its budget of bytes and files left, and its messages about what was skipped."""

    def __init__(self, *, limit: int, max_files: int, first: str | None):
        self.limit, self.max_files, self.first = limit, max_files, first
        self.notes: list[str] = []
        self.budget = {"bytes": limit, "files": max_files}

    def skip(self, rel: str, why: str) -> None:
        if len(self.notes) < 20:
            self.notes.append(f"{rel}: {why}, not copied")
        elif len(self.notes) == 20:
            self.notes.append("(more files skipped)")

    def copy_file(self, path: Path, rel: str, out: Path) -> None:
        """Copy one regular file, opened without following a link (and without blocking on a FIFO), within the budget."""
        if self.budget["files"] <= 0:
            return self.skip(rel, f"more than {self.max_files} files")
        try:
            fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
        except OSError as e:
            return self.skip(rel, "a symbolic link (links are not followed)" if os.path.islink(path)
                             else f"unreadable ({e.strerror})")
        try:
            st = os.fstat(fd)
            if not stat.S_ISREG(st.st_mode):
                return self.skip(rel, "not a regular file")
            if st.st_size > self.budget["bytes"]:
                return self.skip(rel, f"over the {self.limit >> 20} MiB a submission may hold")
            self.budget["files"] -= 1
            with os.fdopen(os.open(out, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o644), "wb") as w:
                left = st.st_size
                while left > 0:
                    chunk = os.read(fd, min(left, 1 << 20))
                    if not chunk:
                        break
                    w.write(chunk)
                    left -= len(chunk)
            self.budget["bytes"] -= st.st_size - left
        finally:
            os.close(fd)

    def walk(self, folder: Path, rel: str, out: Path, depth: int) -> None:
        """Copy a folder's entries (``first`` before the others at the top), recursing into folders up to depth 16."""
        try:
            entries = sorted(os.scandir(folder), key=lambda e: (not (depth == 0 and e.name == self.first), e.name))
        except OSError as e:
            return self.skip(rel or ".", f"unreadable ({e.strerror})")
        for e in entries:
            if e.name.startswith(".") or e.name == "__pycache__":
                continue
            r = f"{rel}{e.name}"
            if e.is_symlink():
                try:
                    target = os.readlink(e.path)
                except OSError:
                    target = "?"
                self.skip(r, f"a symbolic link (to {target}; links are not followed)")
            elif e.is_dir(follow_symlinks=False):
                if depth >= 16:
                    self.skip(r, "nested too deep")
                    continue
                (out / e.name).mkdir(mode=0o755)
                self.walk(Path(e.path), r + "/", out / e.name, depth + 1)
            elif e.is_file(follow_symlinks=False):
                self.copy_file(Path(e.path), r, out / e.name)
            else:
                self.skip(r, "not a regular file (a FIFO, socket or device)")


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
    except (ValueError, RecursionError):  # a result nested thousands deep is the student's, like malformed JSON
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
    ``.npy`` files that ``calls`` refer to with ``{"npy": name}``. Raises
    :class:`SandboxError` where code mode is refused (see :func:`isolation`).
    """
    return _run_student(isolation(), module_src, module_name, function, calls, arrays, timeout=timeout,
                        memory_mb=memory_mb, first_of_tuple=first_of_tuple)


class _Monitor:
    """The grader's end of the runner's monitor pipe, read as it comes (see mcrt.grade._sandbox).

    Refused operations are recorded here, outside the student's process: what
    the runner wrote cannot be taken back by the student's code.
    """

    def __init__(self):
        self.read_fd, self.write_fd = os.pipe()
        self.violations: list[str] = []
        self.reached = False
        self._thread = threading.Thread(target=self._drain, daemon=True)

    def start(self) -> None:
        os.close(self.write_fd)  # the child holds the only write end now: EOF when it (and its sandbox) is gone
        self._thread.start()

    def _drain(self) -> None:
        buf, kept = b"", 0
        with os.fdopen(self.read_fd, "rb", buffering=0) as f:
            while chunk := f.read(65536):
                if kept > 64 << 10:
                    continue  # drained, not kept: the pipe never fills up and blocks the runner
                buf += chunk
                kept += len(chunk)
                *lines, buf = buf.split(b"\n")
                for ln in lines:
                    text = ln.decode("utf-8", "replace")
                    if text == "R":
                        self.reached = True
                    elif text.startswith("V ") and len(self.violations) < 20:
                        self.violations.append(text[2:302])

    def join(self) -> None:
        self._thread.join(timeout=5)


def _run_student(iso: Isolation, module_src: Path, module_name: str, function: str, calls: list[dict],
                 arrays: dict[str, np.ndarray], *, timeout: float, memory_mb: int, first_of_tuple: bool = False) -> CallResult:
    """:func:`run_student` under ``iso``: stage the inputs in a fresh folder, run the runner, read back its results."""
    t0 = time.monotonic()
    if iso.kind == "none" and not _ALLOW_UNISOLATED:
        raise SandboxError(REFUSAL.format(why=iso.detail))
    uid = _sandbox_uid() if os.geteuid() == 0 else None  # never root, on any path: the runner refuses to go on as root
    tmp = Path(tempfile.mkdtemp(prefix="mcrt-code-", dir=_scratch_base(iso)))
    try:
        os.chmod(tmp, 0o711)
        indir = tmp / "in"
        indir.mkdir(mode=0o755)
        notes = copy_submission(Path(module_src), indir / "student")
        for name, arr in arrays.items():
            np.save(indir / name, np.ascontiguousarray(arr), allow_pickle=False)
        task = _task(iso, module_name, function, calls, first_of_tuple=first_of_tuple, timeout=timeout,
                     memory_mb=memory_mb, uid=uid)
        (indir / "input.json").write_text(json.dumps(task))
        _readable_by_all(indir)
        ran = _launch(iso, tmp, indir, uid, timeout=timeout)
        common = dict(seconds=time.monotonic() - t0, stdout=ran.stdout, notes=notes, violations=ran.monitor.violations)
        return _call_result(iso, ran, len(calls), timeout=timeout, memory_mb=memory_mb, common=common)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _task(iso: Isolation, module_name: str, function: str, calls: list[dict], *, first_of_tuple: bool, timeout: float,
          memory_mb: int, uid: int | None) -> dict:
    """input.json: what the runner calls, and what it must enforce on itself before anything of the student's loads."""
    bwrap = iso.kind == "bubblewrap"
    landlock = None
    if iso.kind == "fallback":
        roots = _read_roots()
        landlock = _landlock_rules(roots, _hidden_paths(roots))
    return {"module": f"student/{module_name}", "function": function, "calls": calls, "first_of_tuple": first_of_tuple,
            "limits": _limits(timeout, memory_mb), "uid": uid, "landlock": landlock,
            # Without bubblewrap (whose --die-with-parent does it) the runner ties its life to this process itself.
            "parent": None if bwrap else os.getpid(),
            "mount_work": {"size": DISK_LIMIT, "nr_inodes": INODE_LIMIT} if bwrap and os.geteuid() == 0 else None,
            "require": ["landlock", "seccomp"] if iso.kind == "fallback" else ["seccomp"] if bwrap else [],
            "output_limit": OUTPUT_LIMIT}


def _readable_by_all(folder: Path) -> None:
    """Folders 0755 and files 0644 under ``folder``: the runner reads them as the unprivileged uid."""
    for dirpath, dirs, files in os.walk(folder):
        os.chmod(dirpath, 0o755)
        for f in files:
            os.chmod(os.path.join(dirpath, f), 0o644)


#: The runner's whole environment (HOME and TMPDIR added: its work folder); one thread per numeric library.
_RUNNER_ENV = {"PATH": "/usr/bin:/bin", "LANG": "C.UTF-8",
               "PYTHONDONTWRITEBYTECODE": "1", "PYTHONHASHSEED": "0", "OMP_NUM_THREADS": "1",
               "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "NUMEXPR_NUM_THREADS": "1"}


@dataclass
class _Ran:
    """How one run of the runner ended, as the grader saw it."""
    code: int | None  # exit code (negative: the signal), None after a timeout
    timed_out: bool
    stdout: str  # its tail
    raw: bytes | None  # the results file, None when missing, not a regular file or over the cap
    too_big: bool  # the results file is over the cap
    monitor: "_Monitor"  # what the runner reported on its monitor pipe: refused operations, reaching the module


def _launch(iso: Isolation, tmp: Path, indir: Path, uid: int | None, *, timeout: float) -> _Ran:
    """Run the runner on ``indir`` (under bubblewrap or directly), wait for it at most ``timeout`` s, kill its group."""
    mon = _Monitor()
    args_r = None
    with tempfile.TemporaryFile(dir=tmp) as out, tempfile.TemporaryFile(dir=tmp) as resf:
        fds = [resf.fileno(), mon.write_fd]
        if iso.kind == "bubblewrap":
            argv, args_r = _bwrap_command(iso, indir, resf.fileno(), mon.write_fd, uid)
            fds.append(args_r)
            cwd, home = tmp, "/sandbox/work"
        else:
            work = _fallback_work(tmp, uid)
            argv = [sys.executable, "-I", "-B", str(RUNNER), str(indir), str(work), str(resf.fileno()), str(mon.write_fd)]
            cwd, home = work, str(work)
        proc = _start_runner(argv, cwd, {**_RUNNER_ENV, "HOME": home, "TMPDIR": home}, out, fds, mon, args_r)
        mon.start()
        code, timed_out = _wait_then_kill_group(proc, timeout)
        mon.join()
        stdout = _tail_fd(out)
        raw = None if timed_out else _read_capped(resf, OUTPUT_LIMIT + TRAILER_LIMIT + 8)
        too_big = not timed_out and raw is None and os.fstat(resf.fileno()).st_size > 0
    return _Ran(code, timed_out, stdout, raw, too_big, mon)


def _bwrap_command(iso: Isolation, indir: Path, result_fd: int, monitor_fd: int, uid: int | None) -> tuple[list[str], int]:
    """bwrap's command line with its options written to a pipe (``--args``), and the pipe's read end to pass on.

    The sandbox's /proc/1/cmdline then shows "bwrap --args N -- python ... runner.py", not what is bound from where
    (bwrap takes the command itself only from its argv).
    """
    full = _bwrap_argv(iso, indir, result_fd, monitor_fd, uid)
    cut = full.index("--")
    packed = b"".join(os.fsencode(x) + b"\0" for x in full[1:cut])
    args_r, args_w = os.pipe()
    if len(packed) > 60000:  # a pipe holds 64 KiB: bwrap reads it only once started
        os.close(args_r)
        os.close(args_w)
        raise SandboxError(f"bwrap's command line is {len(packed)} bytes; at most 60000 fit its --args pipe")
    os.write(args_w, packed)
    os.close(args_w)
    return [full[0], "--args", str(args_r), *full[cut:]], args_r


def _fallback_work(tmp: Path, uid: int | None) -> Path:
    """The runner's work folder without bubblewrap: private, owned by the uid it switches to."""
    work = tmp / "work"
    work.mkdir(mode=0o700)
    if uid is not None:
        os.chown(work, uid, uid)
    return work


def _start_runner(argv: list[str], cwd: Path, env: dict, out, fds: list[int], mon: "_Monitor",
                  args_r: int | None) -> subprocess.Popen:
    """Start the runner in a new session, its stdout and stderr to ``out``, passing it only ``fds``."""
    # No preexec_fn (unsafe in a process with threads, such as the monitor's): a new session for
    # killing the whole group is done by Popen itself; the runner sets its own resource limits,
    # then switches to uid, before anything of the student's loads.
    try:
        return subprocess.Popen(argv, cwd=cwd, env=env, stdin=subprocess.DEVNULL, stdout=out, stderr=subprocess.STDOUT,
                                start_new_session=True, close_fds=True, pass_fds=tuple(fds))
    except BaseException:
        os.close(mon.write_fd)
        os.close(mon.read_fd)
        raise
    finally:
        if args_r is not None:
            os.close(args_r)


def _wait_then_kill_group(proc: subprocess.Popen, timeout: float) -> tuple[int | None, bool]:
    """(exit code, False), or (None, True) after ``timeout`` s; either way its whole group is killed after."""
    try:
        return proc.wait(timeout=timeout), False
    except subprocess.TimeoutExpired:
        return None, True
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)  # the whole group: no orphan keeps running
        except (ProcessLookupError, PermissionError):
            pass
        proc.wait()


def _call_result(iso: Isolation, ran: _Ran, n_calls: int, *, timeout: float, memory_mb: int, common: dict) -> CallResult:
    """What the calls returned, or why nothing did (the grader's fault when the runner never reached the module)."""
    if not ran.monitor.reached:
        last = [ln for ln in ran.stdout.strip().splitlines() if ln.strip()]
        why = "timed out" if ran.timed_out else _exit_reason(ran.code, memory_mb)
        return CallResult(False, [], [], f"the sandbox failed before the module ran ({why}"
                          f"{': ' + last[-1].strip()[:300] if last else ''}): a problem of the grader, not the module",
                          grader_fault=True, **common)
    if ran.timed_out:
        return CallResult(False, [], [], f"stopped after {timeout:g} s (time limit): an infinite loop, or far too slow",
                          **common)
    data = _parse_results(ran.raw)
    if data is None:
        why = (f"its results exceed {OUTPUT_LIMIT >> 20} MiB" if ran.too_big else _exit_reason(ran.code, memory_mb))
        return CallResult(False, [], [], f"the module's process ended without returning results ({why})", **common)
    blobs = data.pop("_blobs")
    res = CallResult(True, [], [], sandbox=data.get("sandbox", {}) if isinstance(data.get("sandbox"), dict) else {},
                     **common)
    res.sandbox["isolation"] = iso.kind
    if "import_error" in data:
        res.ok = False
        err = str(data["import_error"])[:6000]
        if err.startswith("the module has no function"):
            res.message, res.errors = err, []
        else:
            res.message, res.errors = "importing the module failed", [err]
        return res
    _read_outputs(res, data.get("results", []), blobs, n_calls)
    return res


def _read_outputs(res: CallResult, results, blobs: memoryview, n_calls: int) -> None:
    """Append each call's array (or its error) to ``res``, read only within ``blobs``; a missing call gets "no result"."""
    for r in (results if isinstance(results, list) else [])[:n_calls]:
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
    while len(res.outputs) < n_calls:
        res.outputs.append(None)
        res.errors.append("no result")


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
    with np.errstate(over="ignore", invalid="ignore"):
        m, sd = e.mean(axis=1), e.std(axis=1, ddof=1)
    if not (np.isfinite(m).all() and np.isfinite(sd).all()):  # finite estimates whose sums overflow (1e308, say)
        return CheckOutcome(0.0, f"the estimates are too large to average (largest {np.max(np.abs(e)):.3g}): their mean "
                                 "or spread overflows")
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
    bad = [i for i in imgs if i.ndim != 3 or i.shape[2] not in (3, 4) or i.shape[:2] != imgs[0].shape[:2] or 0 in i.shape]
    if bad:  # the module's doing, said as such (an empty image would otherwise fail inside the image grader)
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
        skipped = copy_submission(root, stage / "s", first=mod)
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


def shared_import_failure(results) -> str | None:
    """A module that every student's code (two or more) failed to import though the grader can: the grader's problem.

    mcrt, Mitsuba and Dr.Jit do not count: graded code is meant not to have them.
    """
    import importlib.util
    import re

    if len(results) < 2:
        return None
    common: set | None = None
    for r in results:
        text = " ".join(str(t.output) for t in r.tests)
        # Missing, or an empty shell of it (a folder Python cannot read is an empty namespace package).
        found = re.findall(r"No module named '([\w.]+)'|cannot import name '\w+' from '([\w.]+)' \(unknown location\)", text)
        names = {(a or b).partition(".")[0] for a, b in found}
        common = names if common is None else common & names
        if not common:
            return None
    found = sorted(n for n in common if n not in HIDDEN_PACKAGES and importlib.util.find_spec(n) is not None)
    return found[0] if found else None


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


@dataclass
class CodeContext:
    """What a grading worker needs to grade one student's module (pickled to it like image mode's Context).

    The isolation probed and self-tested by the parent is handed on, so a worker neither probes again nor decides
    differently (and the instructor's ``--allow-unisolated-code`` reaches it).
    """

    assignment: Assignment
    isolation: Isolation
    allow_unisolated: bool = False
    image: object = None  # the prepared image-mode Context, for the render check
    timeout: float | None = None  # per check (default: code.timeout)
    memory_mb: int | None = None  # per student process (default: code.memory_mb)

    @property
    def criteria(self) -> list[tuple[str, float, str]]:
        return [(c.name, c.points, CHECK_TITLES.get(c.name, c.name)) for c in self.assignment.code.checks]

    def grade(self, sub) -> StudentResult:
        global _ISOLATION
        with _ISOLATION_LOCK:
            if _ISOLATION is None:
                _ISOLATION = self.isolation
        allow_unisolated(self.allow_unisolated)
        return grade_code(sub.student, Path(sub.source), self.assignment, ctx=self.image, timeout=self.timeout,
                          memory_mb=self.memory_mb)


def code_submission(student: str, path: Path):
    """A code hand-in as the class runner's :class:`~mcrt.grade.submissions.Submission`: its key hashes the module
    file (or the folder's files); a link or special file is named, never opened (find_module refuses it)."""
    from mcrt.grade.submissions import Submission, file_kind

    special = file_kind(path)
    regular_file = special is None and not path.is_dir()
    return Submission(student, str(path), images=[str(path)] if regular_file else [], special=special)


def code_plan(submissions, a: Assignment, *, timeout, cache_dir, single, student, context, memory_mb, log,
              allow_unisolated_code: bool = False):
    """Code mode for :func:`mcrt.grade.batch.grade_class`: the modules, the sandbox (probed and self-tested before
    anyone is graded; :class:`SandboxError` where it cannot isolate), and the shared-import warning at the end."""
    from mcrt.grade.run import DEFAULT_MEMORY_MB, Plan

    subs = [code_submission(sid, p) for sid, p in discover_code(submissions, single=single, student=student)]
    log(f"mcrt grade (code): {len(subs)} submission(s)")
    if allow_unisolated_code:
        allow_unisolated(True)
    iso = isolation()  # a fallback is announced on stderr there; a refusal or a failed self-test raises
    log(f"sandbox: {iso.detail}")
    ctx = context
    if ctx is None and any(c.name == "render" for c in a.code.checks):
        from mcrt.grade.expected import prepare_context

        ctx = prepare_context(a, cache_dir, log=log)
    cc = CodeContext(a, iso, _ALLOW_UNISOLATED, ctx, timeout, memory_mb)
    per_check, mem = timeout or a.code.timeout, memory_mb or a.code.memory_mb
    # A backstop over the sandbox's own per-call limits: every check's time, and the render check's image grading.
    student_timeout = len(a.code.checks) * (per_check + 10) + (a.timeout if ctx is not None else 0) + 30

    def finish(results):
        shared = shared_import_failure(results)
        if not shared:
            return "", None
        warning = (f"WARNING: every student's module failed to import {shared}, which the grader itself has: the sandbox "
                   "does not show it to graded code, a problem of the grader's installation, not the students'")
        print(f"mcrt grade: {warning}", file=sys.stderr, flush=True)
        return f"{warning}. ", None

    src = ctx.references[a.camera].source if ctx is not None else "none (no render check)"
    # The worker's own limit stays above the student process's, which the runner sets below it.
    return Plan(subs, cc, src, f"Sandbox: {iso.detail}.", student_timeout, max(DEFAULT_MEMORY_MB, mem + 1024),
                digest={"mode": "code", "sandbox": iso.kind, "check_timeout": per_check, "student_memory_mb": mem},
                criteria=cc.criteria, image_context=ctx, finish=finish)
