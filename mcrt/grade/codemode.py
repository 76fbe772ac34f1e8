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

Every call runs in a fresh subprocess (``python -I mcrt/grade/_sandbox.py``)
in a temporary folder that holds a copy of the student's files and the
inputs, with resource limits that the runner sets on itself before NumPy or
the student's code loads (``RLIMIT_CPU`` at the timeout plus a second,
``RLIMIT_AS`` at ``memory_mb``, ``RLIMIT_FSIZE`` 256 MiB, no core files;
one BLAS thread), a wall-clock timeout that kills its whole process group
(its own session), a minimal environment (``HOME`` and ``TMPDIR`` in
the folder, no inherited secrets) and the sandbox of
:mod:`mcrt.grade._sandbox` (Landlock: read-only system, writable folder,
unreadable grader files; an audit hook refusing processes, sockets and
writes elsewhere). Running as root, it also drops to ``nobody`` when the
Python installation is readable by others. A crash, a hang, a memory blow-up
or a refused operation is a graded failure of that check, with the
student's traceback.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mcrt.grade.assignment import Assignment
from mcrt.grade.grader import StudentResult, TestResult

RUNNER = Path(__file__).with_name("_sandbox.py")
FSIZE_LIMIT = 256 << 20
OUTPUT_LIMIT = 64 << 20
STDIO_TAIL = 4000
NOBODY = 65534

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


def _read_roots() -> list[str]:
    """Folders the student's process may read: the Python installation and system folders.

    Never the project (references, the grader, other output) nor any folder
    holding it; inside the project only the virtual environment. Of /proc
    only cpuinfo and meminfo here; the runner adds its own /proc/<pid> (never
    the grader's, whose environment would be readable there).
    """
    repo = Path(__file__).resolve().parent.parent.parent
    venv = Path(sys.prefix).resolve()
    cands = {sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix,
             "/usr", "/lib", "/lib64", "/lib32", "/bin", "/sbin", "/etc", "/sys", "/opt",
             "/proc/cpuinfo", "/proc/meminfo", "/dev/urandom", "/dev/zero"}  # /proc/<pid>: added by the runner
    cands |= {p for p in sys.path if p and os.path.isdir(p)}
    out = set()
    for c in cands:
        if not os.path.exists(c):
            continue
        r = Path(os.path.realpath(c))
        if r == Path("/") or r == repo or repo.is_relative_to(r):
            continue  # an ancestor of the project would expose it
        if r.is_relative_to(repo) and not r.is_relative_to(venv):
            continue
        out.add(str(r))
    return sorted(out)


def _world_traversable(path: str) -> bool:
    p = Path(path).resolve()
    for q in [p, *p.parents]:
        try:
            if not os.stat(q).st_mode & stat.S_IXOTH:
                return False
        except OSError:
            return False
    return True


def _can_drop_privileges() -> bool:
    if os.geteuid() != 0:
        return False
    return all(_world_traversable(x) for x in (sys.executable, sys.base_prefix, str(RUNNER)))


def _limits(cpu_s: float, memory_mb: int) -> dict:
    """Resource limits the runner sets on itself before NumPy and the student's code load."""
    cpu = int(cpu_s) + 1
    return {"RLIMIT_CPU": cpu, "RLIMIT_AS": int(memory_mb) << 20, "RLIMIT_FSIZE": FSIZE_LIMIT, "RLIMIT_CORE": 0}


def run_student(module_src: Path, module_name: str, function: str, calls: list[dict], arrays: dict[str, np.ndarray], *,
                timeout: float, memory_mb: int, first_of_tuple: bool = False) -> CallResult:
    """Call ``function`` of the student's module once per entry of ``calls`` in a sandboxed subprocess.

    ``module_src`` is the student's file or folder (copied into a fresh
    temporary folder); ``arrays`` are saved there as ``.npy`` files that
    ``calls`` refer to with ``{"npy": name}``.
    """
    t0 = time.monotonic()
    work = Path(tempfile.mkdtemp(prefix="mcrt-code-"))
    drop = _can_drop_privileges()
    try:
        dest = work / "student"
        if module_src.is_dir():
            shutil.copytree(module_src, dest, symlinks=False, ignore=shutil.ignore_patterns("__pycache__", ".*"))
        else:
            dest.mkdir()
            shutil.copy2(module_src, dest / module_src.name)
        for name, arr in arrays.items():
            np.save(work / name, np.ascontiguousarray(arr), allow_pickle=False)
        task = {"module": f"student/{module_name}", "function": function, "calls": calls,
                "read_roots": _read_roots(), "first_of_tuple": first_of_tuple, "limits": _limits(timeout, memory_mb)}
        (work / "input.json").write_text(json.dumps(task))
        if drop:
            for root, dirs, files in os.walk(work):
                for n in [root, *(os.path.join(root, d) for d in dirs), *(os.path.join(root, f) for f in files)]:
                    os.chown(n, NOBODY, NOBODY)
        env = {"PATH": "/usr/bin:/bin", "HOME": str(work), "TMPDIR": str(work), "LANG": "C.UTF-8",
               "PYTHONDONTWRITEBYTECODE": "1", "PYTHONHASHSEED": "0", "OMP_NUM_THREADS": "1",
               "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "NUMEXPR_NUM_THREADS": "1"}
        ids = {"user": NOBODY, "group": NOBODY, "extra_groups": []} if drop else {}
        # No preexec_fn (unsafe with the threads that grade students in parallel): a new session for
        # killing the whole group, and the user switch, are done by Popen itself; the runner sets its
        # own resource limits before anything else.
        with open(work / "stdout.txt", "wb") as out:
            proc = subprocess.Popen([sys.executable, "-I", str(RUNNER), str(work)], cwd=work, env=env, stdin=subprocess.DEVNULL,
                                    stdout=out, stderr=subprocess.STDOUT, start_new_session=True, close_fds=True, **ids)
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
        stdout = _tail(work / "stdout.txt")
        seconds = time.monotonic() - t0
        if timed_out:
            return CallResult(False, [], [], f"stopped after {timeout:g} s (time limit): an infinite loop, or far too slow",
                              seconds=seconds, stdout=stdout)
        outp = work / "output.json"
        if not outp.is_file() or outp.stat().st_size > OUTPUT_LIMIT:
            why = _exit_reason(code, memory_mb)
            return CallResult(False, [], [], f"the module's process ended without returning results ({why})",
                              seconds=seconds, stdout=stdout)
        try:
            data = json.loads(outp.read_text())
        except (ValueError, OSError):
            return CallResult(False, [], [], "the module's process left unreadable results", seconds=seconds, stdout=stdout)
        res = CallResult(True, [], [], violations=[str(v)[:300] for v in data.get("violations", [])][:20],
                         sandbox=data.get("sandbox", {}), seconds=seconds, stdout=stdout)
        if "import_error" in data:
            res.ok = False
            err = str(data["import_error"])
            if err.startswith("the module has no function"):
                res.message, res.errors = err, []
            else:
                res.message, res.errors = "importing the module failed", [err]
            return res
        for r in data.get("results", []):
            if isinstance(r, dict) and "npy" in r and isinstance(r["npy"], str) and "/" not in r["npy"]:
                try:
                    res.outputs.append(np.load(work / r["npy"], allow_pickle=False))
                    res.errors.append(None)
                except (ValueError, OSError) as e:
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
        shutil.rmtree(work, ignore_errors=True)


def _tail(p: Path) -> str:
    try:
        with open(p, "rb") as f:
            f.seek(max(0, p.stat().st_size - STDIO_TAIL))
            return f.read().decode("utf-8", "replace")
    except OSError:
        return ""


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
    """(what to copy, module file name inside it, problem)."""
    if src.is_file():
        if src.suffix != ".py":
            return None, None, f"{src.name} is not a Python file (.py)"
        return src, src.name, ""
    if not src.is_dir():
        return None, None, "no such file or folder"
    if module:
        if (src / module).is_file():
            return src, module, ""
        return None, None, f"the folder has no {module} (the assignment asks for that file)"
    pys = sorted(p.name for p in src.iterdir() if p.suffix == ".py" and not p.name.startswith("."))
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
    tests: list[TestResult] = []
    details: dict = {}
    notes: list[str] = []
    diagnosis: list = []
    root, mod, problem = find_module(Path(src), spec.module)
    scene = None
    for chk in spec.checks:
        title = CHECK_TITLES.get(chk.name, chk.name)
        if root is None:
            tests.append(TestResult(chk.name, title, 0.0, chk.points, f"not graded: {problem}", chk.visibility, "not graded"))
            continue

        def run(function, calls, arrays, first_of_tuple=False):
            return run_student(root, mod, function, calls, arrays, timeout=to, memory_mb=mem, first_of_tuple=first_of_tuple)

        try:
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
                if sr is not None:
                    diagnosis = sr.diagnosis
            else:  # pragma: no cover - validated by the assignment loader
                out = CheckOutcome(0.0, f"unknown check {chk.name}")
        except Exception as e:  # noqa: BLE001 - a grader bug must not stop the class
            out = CheckOutcome(0.0, f"the grader failed on this check ({type(e).__name__}: {e})")
        details[chk.name] = out.details
        score = round(chk.points * max(0.0, min(1.0, out.fraction)), 4)
        status = "passed" if out.fraction >= 1.0 else "failed"
        tests.append(TestResult(chk.name, title, score, chk.points, out.message, chk.visibility, status))
    if problem:
        notes.append(problem)
    score = round(sum(t.score for t in tests), 4)
    maxs = sum(t.max_score for t in tests)
    failed = [t for t in tests if t.score < t.max_score]
    shown = f"{score:.2f}".rstrip("0").rstrip(".")
    summary = (f"Full marks: {shown}/{maxs:g}." if not failed else
               f"{shown}/{maxs:g}. " + "; ".join(f"{t.name}: {t.output.splitlines()[0][:160]}" for t in failed[:2]))
    details["mode"] = "code"
    res = StudentResult(student, "graded", score, maxs, tests, summary, notes, diagnosis, details)
    res.elapsed = time.perf_counter() - t0
    return res


def discover_code(path, *, single: bool = False, student: str | None = None) -> list[tuple[str, Path]]:
    from mcrt.grade.submissions import _unique, safe_id

    root = Path(path)
    if not root.exists():
        raise FileNotFoundError(f"{root}: no such file or folder")
    if root.is_file() or single:
        return [(safe_id(student or (root.stem if root.is_file() else root.name)), root)]
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
    summary = write_class(results, a, out, elapsed=elapsed, criteria=crit)
    return ClassResult(results, summary, out, elapsed, ctx)
