"""Ground truth: Mitsuba references that are reproducible, resumable and verifiable.

``reference/`` holds the Mitsuba 3 renders that tests, reports and grading
compare against, one OpenEXR file per (scene, camera, resolution, max depth)
with the mean and the per-sample variance, and ``reference/manifest.json``
listing every reference with its SHA-256 checksum and provenance (Mitsuba
and Dr.Jit versions, variant, scene hash, spp, chunk seeds, max depth, render
time, machine, date and the command that rebuilds it).

Chunks
------
A reference of ``spp`` samples per pixel is rendered as ``ceil(spp /
chunk_spp)`` independent chunks. Chunk ``i`` is one call of
:func:`mcrt.mitsuba.render_mitsuba` with its own seed
:func:`chunk_seed` ``(base_seed, i)`` (a hash of both, so builds with other
base seeds draw other streams) and ``min(chunk_spp, spp - i chunk_spp)``
samples per pixel. Each finished chunk is written atomically to
``reference/chunks/<key>/chunk_0007.exr`` (not committed), so an interrupted
build (Ctrl-C, a killed process, a full disk) continues where it stopped: a
chunk file that reads back with the expected seed, spp, scene hash, camera,
size, max depth, Mitsuba version and variant is reused, anything else is
rendered again. Chunks merge exactly with :func:`mcrt.film.merge`
(sample-weighted sums of x and x^2 in float64), always in chunk order, so the
reference does not depend on which worker finished first.

Chunks run in a local process pool (:data:`DEFAULT_WORKERS` workers), or on a
Dask cluster when ``scheduler`` is a ``dask.distributed`` scheduler address
(``tcp://host:8786``): workers only render and send the images back; only
the machine that runs the build writes files.

Every file is written to a temporary file in the target folder and then moved
over the target (``os.replace``), so a failed write never leaves a
half-written file where a good reference stood.

Reading references
------------------
:func:`load_reference` is what tests use. It never renders: a missing
reference, one whose checksum does not match the manifest, or one built for
another version of the scene (scene hash changed) raises a
:class:`ReferenceUnavailable` whose message names the command that rebuilds
it.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import hashlib
import json
import math
import os
import platform
import secrets
import shlex
import sys
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Iterable, Iterator, Sequence

import numpy as np

import mcrt  # noqa: F401  (sets DRJIT_LIBLLVM_PATH before drjit is imported)
from mcrt.film import Progress, RenderResult, merge
from mcrt.scene import CANONICAL, Scene, load_scene

__all__ = [
    "REFERENCE_DIR",
    "MANIFEST_NAME",
    "SCHEMA",
    "STANDARD",
    "EXIT_OK",
    "EXIT_FAILED",
    "EXIT_UNUSABLE",
    "ReferenceUnavailable",
    "MissingReference",
    "StaleReference",
    "CorruptReference",
    "ReferenceSpec",
    "BuildResult",
    "VerifyResult",
    "reference_key",
    "chunk_seed",
    "rebuild_command",
    "build_reference",
    "load_reference",
    "list_references",
    "verify_references",
    "read_manifest",
    "register",
]

REPO_ROOT = Path(__file__).resolve().parent.parent
#: Where committed references and the manifest live.
REFERENCE_DIR = REPO_ROOT / "reference"
MANIFEST_NAME = "manifest.json"
#: Sub-folder of the reference folder holding per-chunk files (git-ignored).
CHUNK_DIR_NAME = "chunks"
#: Schema tag of manifest.json.
SCHEMA = "mcrt.reference.manifest/1"

#: Exit codes of the ``mcrt reference`` commands.
EXIT_OK, EXIT_FAILED, EXIT_UNUSABLE = 0, 1, 2

#: Paths traced per chunk when ``chunk_spp`` is not given (about 10-20 s at
#: max depth 8 on two CPU cores): 4096 spp at 64x64, 1024 at 128x128.
CHUNK_PATHS = 1 << 24
#: Samples per pixel of a build when ``spp`` is not given.
DEFAULT_SPP = 16384
#: Base seed of builds; chunk seeds are hashes of (base seed, chunk index).
DEFAULT_BASE_SEED = 0
#: Base seed of the fresh renders of :func:`verify_references` (never used
#: by a build with the default base seed).
VERIFY_BASE_SEED = 1_000_003
#: Paths per reference that :func:`verify_references` renders by default
#: (at least :data:`VERIFY_MIN_SPP` samples per pixel).
VERIFY_PATHS = 1 << 22
VERIFY_MIN_SPP = 256

# Local parallelism: Dr.Jit's LLVM backend already spreads each kernel over
# every core with its own thread pool. Measured on the 2-core build machine
# (64x64, 8192 spp, max depth 8, 8 chunks, machine shared with other jobs):
# one process with two Dr.Jit threads 31 s and 46 s, two processes with one
# thread each 39 s and 46 s (process start and imports included). Two
# workers never won, so the default is one worker rendering in this process.
DEFAULT_WORKERS = 1


@dataclass(frozen=True)
class ReferenceSpec:
    """One committed reference: what ``mcrt reference build --standard`` builds."""

    camera: str
    res: int
    max_depth: int
    spp: int


#: The committed references of the canonical scene (see README, "Ground truth").
STANDARD: tuple[ReferenceSpec, ...] = (
    *(ReferenceSpec(cam, 64, 8, 32768) for cam in ("near", "far")),
    *(ReferenceSpec(cam, 64, 2, 65536) for cam in ("near", "far")),
    *(ReferenceSpec(cam, 64, 1, 65536) for cam in ("near", "far")),
    *(ReferenceSpec(cam, 64, -1, 16384) for cam in ("near", "far")),
    *(ReferenceSpec(cam, 128, 8, 8192) for cam in ("near", "far")),
    *(ReferenceSpec(cam, 128, 2, 16384) for cam in ("near", "far")),
    # The report-resolution reference: 1.07e9 paths, about 8 min on an idle 2-core machine, 1.5 MB.
    ReferenceSpec("near", 256, 8, 16384),
)


# --------------------------------------------------------------------------
# Errors
# --------------------------------------------------------------------------


class ReferenceUnavailable(RuntimeError):
    """A reference that cannot be used; the message names the command that rebuilds it."""

    def __init__(self, message: str, command: str = ""):
        super().__init__(message)
        self.command = command


class MissingReference(ReferenceUnavailable):
    """No manifest entry or no file for the requested reference."""


class StaleReference(ReferenceUnavailable):
    """The reference was built for another version of the scene (scene hash changed)."""


class CorruptReference(ReferenceUnavailable):
    """The file's checksum does not match the manifest, or it does not read."""


# --------------------------------------------------------------------------
# Names, seeds, commands
# --------------------------------------------------------------------------


def _size(res: int | tuple[int, int]) -> tuple[int, int]:
    """(width, height) from N or (W, H)."""
    if isinstance(res, (tuple, list)):
        w, h = (int(x) for x in res)
    else:
        w = h = int(res)
    if w < 1 or h < 1:
        raise ValueError(f"resolution must be positive, got {w}x{h}")
    return w, h


def _depth_label(max_depth: int) -> str:
    return "inf" if max_depth == -1 else str(int(max_depth))


def reference_key(scene_name: str, camera: str, res: int | tuple[int, int], max_depth: int) -> str:
    """File stem of a reference: ``<scene>_<camera>_<W>x<H>_d<D>`` (``dinf`` for max depth -1)."""
    w, h = _size(res)
    return f"{scene_name}_{camera}_{w}x{h}_d{_depth_label(max_depth)}"


def chunk_seed(base_seed: int, index: int) -> int:
    """Seed of chunk ``index`` of a build with ``base_seed``: a 31-bit hash of both."""
    key = f"mcrt.reference/{int(base_seed)}/{int(index)}".encode()
    return int.from_bytes(hashlib.blake2b(key, digest_size=4).digest(), "little") & 0x7FFFFFFF


def chunk_spp_for(res: int | tuple[int, int], spp: int) -> int:
    """Default samples per pixel of one chunk: about :data:`CHUNK_PATHS` paths, a power of two."""
    w, h = _size(res)
    n = max(1, CHUNK_PATHS // (w * h))
    n = 1 << (n.bit_length() - 1)
    return max(1, min(n, int(spp)))


def _chunk_sizes(spp: int, chunk_spp: int) -> list[int]:
    n = math.ceil(spp / chunk_spp)
    return [min(chunk_spp, spp - i * chunk_spp) for i in range(n)]


def _scene_arg(scene: Scene) -> str:
    """``--scene PATH`` for a scene that is not the canonical file, else ''."""
    try:
        if Path(scene.path).resolve() == CANONICAL.resolve():
            return ""
    except (OSError, ValueError):
        pass
    return f"--scene {shlex.quote(_display_path(scene.path))} "


def rebuild_command(
    scene: Scene,
    camera: str,
    res: int | tuple[int, int],
    max_depth: int,
    spp: int | None = None,
    chunk_spp: int | None = None,
    base_seed: int = DEFAULT_BASE_SEED,
) -> str:
    """The ``mcrt reference build`` command line that (re)builds one reference."""
    w, h = _size(res)
    size = f"--res {w}" if w == h else f"--width {w} --height {h}"
    spp = int(spp) if spp else _standard_spp(camera, (w, h), max_depth)
    cmd = f"mcrt reference build {_scene_arg(scene)}--camera {camera} {size} --max-depth {max_depth} --spp {spp}"
    if chunk_spp and chunk_spp != chunk_spp_for((w, h), spp):
        cmd += f" --chunk-spp {chunk_spp}"
    if base_seed != DEFAULT_BASE_SEED:
        cmd += f" --seed {base_seed}"
    return cmd


def _standard_spp(camera: str, size: tuple[int, int], max_depth: int) -> int:
    for s in STANDARD:
        if (s.camera, (s.res, s.res), s.max_depth) == (camera, size, max_depth):
            return s.spp
    return DEFAULT_SPP


def _display_path(path: str | os.PathLike) -> str:
    """A path relative to the repository when it lies inside it."""
    p = Path(path)
    try:
        return str(p.resolve().relative_to(REPO_ROOT))
    except (ValueError, OSError):
        return str(p)


def _resolve_scene(scene: Scene | str | os.PathLike | None) -> Scene:
    if scene is None:
        return load_scene(CANONICAL)
    if isinstance(scene, Scene):
        return scene
    return load_scene(scene)


# --------------------------------------------------------------------------
# Files: checksums, atomic text, manifest
# --------------------------------------------------------------------------


def sha256_file(path: str | os.PathLike) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _atomic_write_text(path: Path, text: str) -> None:
    """Write ``text`` to a temporary file beside ``path``, fsync it, move it over ``path``."""
    tmp = path.parent / f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp"
    try:
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


@contextlib.contextmanager
def _manifest_lock(directory: Path) -> Iterator[None]:
    """Serialise read-modify-write of the manifest between concurrent builds (POSIX flock)."""
    lock_dir = directory / CHUNK_DIR_NAME
    lock_dir.mkdir(parents=True, exist_ok=True)
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        yield
        return
    with open(lock_dir / ".manifest.lock", "w") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


def read_manifest(directory: str | os.PathLike = REFERENCE_DIR) -> dict[str, Any]:
    """The manifest as a dict ``{'schema': ..., 'references': {key: entry}}``.

    A missing manifest reads as an empty one; an unreadable one raises
    :class:`CorruptReference`.
    """
    path = Path(directory) / MANIFEST_NAME
    if not path.exists():
        return {"schema": SCHEMA, "references": {}}
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as e:
        raise CorruptReference(f"{_display_path(path)}: unreadable manifest ({e}); restore it with `git checkout -- {_display_path(path)}`") from None
    if not isinstance(data, dict) or data.get("schema") != SCHEMA or not isinstance(data.get("references"), dict):
        raise CorruptReference(f"{_display_path(path)}: not a {SCHEMA} manifest")
    return data


def _write_manifest(directory: Path, data: dict[str, Any]) -> None:
    data = {"schema": SCHEMA, "references": dict(sorted(data["references"].items()))}
    _atomic_write_text(directory / MANIFEST_NAME, json.dumps(data, indent=2) + "\n")


def machine_info() -> dict[str, Any]:
    """Where this process runs: host, OS, CPU model, core count, Python."""
    from mcrt.provenance import cpu_name

    cpu = cpu_name()
    return {
        "host": platform.node(),
        "platform": platform.platform(),
        "cpu": cpu,
        "cores": os.cpu_count(),
        "python": platform.python_version(),
    }


def _remove_stale_temps(folder: Path) -> None:
    """Delete temporary files (``.name.<pid>.<hex>.tmp``) left by processes that died."""
    if not folder.is_dir():
        return
    for p in folder.glob(".*.tmp"):
        parts = p.name.split(".")
        try:
            pid = int(parts[-3])
        except (ValueError, IndexError):
            continue
        if pid == os.getpid():
            continue
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            with contextlib.suppress(OSError):
                p.unlink()
        except OSError:
            pass


# --------------------------------------------------------------------------
# Chunks
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class ChunkTask:
    """Everything a worker needs to render one chunk (picklable, sent to Dask workers)."""

    scene: Scene
    camera: str
    width: int
    height: int
    max_depth: int
    index: int
    seed: int
    spp: int
    backend: str = "llvm"


def _render_chunk(task: ChunkTask) -> tuple[int, RenderResult]:
    """Worker entry point: render one chunk with Mitsuba, return (index, result)."""
    from mcrt.mitsuba import render_mitsuba

    r = render_mitsuba(task.scene, task.camera, task.width, task.height, task.spp, task.seed, task.max_depth,
                       backend=task.backend, progress=False)
    m = machine_info()
    r.extra.update(host=str(m["host"]), cpu=str(m["cpu"]), chunk_index=str(task.index))
    return task.index, r


def _init_worker(threads: int | None) -> None:
    """ProcessPool initializer: limit Dr.Jit's thread pool so workers do not oversubscribe cores."""
    import drjit as dr

    if threads:
        dr.set_thread_count(int(threads))


def _chunk_problem(r: RenderResult, task: ChunkTask, scene_hash: str, versions: dict[str, str]) -> str | None:
    """Why a stored chunk cannot be reused for ``task`` (None: it can)."""
    want = {
        "seed": task.seed, "spp": task.spp, "max_depth": task.max_depth, "camera": task.camera,
        "scene_hash": scene_hash, "renderer": "mitsuba", "shape": (task.height, task.width),
    }
    got = {"seed": r.seed, "spp": r.spp, "max_depth": r.max_depth, "camera": r.camera,
           "scene_hash": r.scene_hash, "renderer": r.renderer, "shape": r.shape}
    for k, v in want.items():
        if got[k] != v:
            return f"{k} is {got[k]!r}, expected {v!r}"
    for k, v in versions.items():
        if r.extra.get(k) != v:
            return f"{k} is {r.extra.get(k)!r}, expected {v!r}"
    if r.variance is None:
        return "no variance channels"
    if not (np.isfinite(r.mean).all() and np.isfinite(r.variance).all()):
        return "non-finite values"
    return None


def _installed_versions(backend: str) -> dict[str, str]:
    import drjit as dr
    import mitsuba as mi

    from mcrt.mitsuba import variant_for

    return {"mitsuba_version": mi.__version__, "drjit_version": dr.__version__, "variant": variant_for(backend)}


def _chunk_path(folder: Path, index: int) -> Path:
    return folder / f"chunk_{index:04d}.exr"


def _log(msg: str, enabled: bool = True) -> None:
    if enabled:
        print(msg, file=sys.stderr, flush=True)


# --------------------------------------------------------------------------
# Build
# --------------------------------------------------------------------------


@dataclass
class BuildResult:
    """Outcome of :func:`build_reference`."""

    key: str
    path: Path
    entry: dict[str, Any]
    result: RenderResult
    rendered: list[int] = field(default_factory=list)  # chunk indices rendered by this call
    reused: list[int] = field(default_factory=list)  # chunk indices found valid on disk
    wall_time: float = 0.0


def build_reference(
    scene: Scene | str | os.PathLike | None = None,
    camera: str = "near",
    res: int | tuple[int, int] = 64,
    max_depth: int = 8,
    spp: int = DEFAULT_SPP,
    *,
    chunk_spp: int | None = None,
    base_seed: int = DEFAULT_BASE_SEED,
    workers: int | None = None,
    threads: int | None = None,
    scheduler: Any = None,
    directory: str | os.PathLike = REFERENCE_DIR,
    backend: str = "llvm",
    progress: bool = True,
    keep_chunks: bool = True,
) -> BuildResult:
    """Render (or finish rendering) one Mitsuba reference and record it in the manifest.

    Parameters
    ----------
    scene : Scene, path or None
        The scene (None: the canonical scene).
    camera, res, max_depth, spp
        What to render: ``res`` is N (N x N) or (width, height); ``spp`` is
        the total number of samples per pixel.
    chunk_spp : int, optional
        Samples per pixel of one chunk (default :func:`chunk_spp_for`: about
        2^24 paths per chunk). Chunk ``i`` renders with seed
        ``chunk_seed(base_seed, i)``.
    base_seed : int
        Base of the chunk seeds.
    workers : int, optional
        Local worker processes (default :data:`DEFAULT_WORKERS`; 1 renders in
        this process). Ignored with ``scheduler``. More than one starts
        processes with ``spawn``, so a script calling this needs the
        ``if __name__ == "__main__":`` guard.
    threads : int, optional
        Dr.Jit threads per local worker process (default: cores / workers).
    scheduler : str or distributed.Client, optional
        A Dask scheduler address (``tcp://host:8786``) or a connected
        ``distributed.Client``: chunks are submitted to the cluster instead.
    directory : path
        The reference folder (default ``reference/``); chunks go to
        ``<directory>/chunks/<key>/``.
    keep_chunks : bool
        Keep the chunk files after merging (default True: a later build with
        more spp reuses them).

    Returns
    -------
    BuildResult
        With the chunk indices rendered by this call and those reused.

    The merged reference ``<directory>/<key>.exr`` and the manifest are
    replaced atomically. Interrupting the build (KeyboardInterrupt, a killed
    process, a write error) keeps every finished chunk; calling it again
    renders only the missing ones.
    """
    t_start = time.perf_counter()
    scene = _resolve_scene(scene)
    scene.camera(camera)  # raises SceneError for an unknown camera
    w, h = _size(res)
    s = scene.settings(camera=camera, width=w, height=h, spp=int(spp), max_depth=int(max_depth))
    spp = s.spp
    chunk_spp = int(chunk_spp) if chunk_spp else chunk_spp_for((w, h), spp)
    if chunk_spp < 2:
        raise ValueError(f"chunk_spp must be >= 2 (a chunk needs two samples for a variance), got {chunk_spp}")
    sizes = _chunk_sizes(spp, chunk_spp)
    if sizes[-1] < 2:
        raise ValueError(f"spp {spp} leaves a last chunk of 1 sample with chunk_spp {chunk_spp}: choose another spp")
    directory = Path(directory)
    key = reference_key(scene.name, camera, (w, h), s.max_depth)
    folder = directory / CHUNK_DIR_NAME / key
    folder.mkdir(parents=True, exist_ok=True)
    _remove_stale_temps(folder)
    _remove_stale_temps(directory)
    versions = _installed_versions(backend)
    scene_hash = scene.content_hash()
    tasks = [ChunkTask(scene, camera, w, h, s.max_depth, i, chunk_seed(base_seed, i), n, backend) for i, n in enumerate(sizes)]
    command = rebuild_command(scene, camera, (w, h), s.max_depth, spp, chunk_spp, base_seed)

    from mcrt.imageio import ImageError, read_exr, write_exr

    # -- reuse valid chunks ------------------------------------------------
    chunks: dict[int, RenderResult] = {}
    todo: list[ChunkTask] = []
    for t in tasks:
        p = _chunk_path(folder, t.index)
        if p.exists():
            try:
                r = read_exr(p)
                problem = _chunk_problem(r, t, scene_hash, versions)
            except ImageError as e:
                problem = str(e)
            if problem is None:
                chunks[t.index] = r
                continue
            _log(f"reference {key}: chunk {t.index} not reusable ({problem}); rendering it again", progress)
        todo.append(t)
    reused = sorted(chunks)
    _log(f"reference {key}: {spp} spp in {len(tasks)} chunks of {chunk_spp} spp; "
         f"{len(reused)} done, {len(todo)} to render", progress)

    # -- render the rest ---------------------------------------------------
    bar = Progress(sum(t.spp for t in todo), label=f"reference {key}", unit="spp", enabled=progress and bool(todo))
    done = 0
    rendered: list[int] = []

    def finish(index: int, r: RenderResult) -> None:
        nonlocal done
        problem = _chunk_problem(r, tasks[index], scene_hash, versions)
        if problem is not None:  # a Dask worker with another Mitsuba, say
            host = r.extra.get("host", "?")
            raise RuntimeError(f"reference {key}: chunk {index} rendered on {host} does not match this build: {problem}")
        write_exr(_chunk_path(folder, index), r)
        chunks[index] = r
        rendered.append(index)
        done += r.spp
        bar.update(done)

    for index, r in _run_chunks(todo, workers=workers, threads=threads, scheduler=scheduler, key=key):
        finish(index, r)

    # -- merge and store ---------------------------------------------------
    ordered = [chunks[i] for i in range(len(tasks))]
    merged = merge(ordered)
    extra = {k: v for k, v in ordered[0].extra.items() if k in ("variant", "mitsuba_version", "drjit_version", "integrator", "rr_depth")}
    extra.update(
        reference_key=key,
        base_seed=str(base_seed),
        chunk_spp=str(chunk_spp),
        chunk_seeds=",".join(str(t.seed) for t in tasks),
    )
    merged = replace(
        merged,
        seed=int(base_seed),
        compile_time=float(sum(c.compile_time or 0.0 for c in ordered)),
        extra=extra,
    )
    path = directory / f"{key}.exr"
    write_exr(path, merged)
    wall = time.perf_counter() - t_start

    machine = machine_info()
    hosts = sorted({c.extra.get("host", machine["host"]) for c in ordered})
    entry = {
        "file": path.name,
        "sha256": sha256_file(path),
        "bytes": path.stat().st_size,
        "scene": scene.name,
        "scene_file": _display_path(scene.path),
        "scene_hash": scene_hash,
        "camera": camera,
        "width": w,
        "height": h,
        "max_depth": s.max_depth,
        "rr_depth": s.rr_depth,
        "spp": merged.spp,
        "chunk_spp": chunk_spp,
        "base_seed": int(base_seed),
        "chunk_seeds": [t.seed for t in tasks],
        "renderer": "mitsuba",
        "integrator": "path",
        "mitsuba_version": versions["mitsuba_version"],
        "drjit_version": versions["drjit_version"],
        "variant": versions["variant"],
        "mean_dtype": "float32",
        "render_time_s": round(float(merged.wall_time), 3),
        "compile_time_s": round(float(merged.compile_time or 0.0), 3),
        "build_wall_s": round(wall, 3),
        "median_rel_std_error": _median_rel_se(merged),
        "machine": {**machine, "hosts": hosts},
        "date": _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0).isoformat(),
        "command": command,
    }
    with _manifest_lock(directory):
        data = read_manifest(directory)
        data["references"][key] = entry
        _write_manifest(directory, data)
    if not keep_chunks:
        for t in tasks:
            with contextlib.suppress(OSError):
                _chunk_path(folder, t.index).unlink()
        with contextlib.suppress(OSError):
            folder.rmdir()
    _log(f"reference {key}: wrote {_display_path(path)} ({merged.spp} spp, {entry['bytes'] / 1024:.0f} KiB, "
         f"rendered {len(rendered)} chunks in {wall:.1f} s)", progress)
    return BuildResult(key, path, entry, merged, sorted(rendered), reused, wall)


def _median_rel_se(r: RenderResult) -> float:
    """Median over pixel channels (mean > 0) of the relative standard error sqrt(var / spp) / mean."""
    m = r.mean.astype(np.float64)
    ok = m > 0
    if not ok.any() or r.variance is None:
        return 0.0
    rel = np.sqrt(np.maximum(r.variance.astype(np.float64), 0) / r.spp)[ok] / m[ok]
    return float(f"{np.median(rel):.4g}")


def _run_chunks(todo: list[ChunkTask], *, workers, threads, scheduler, key: str) -> Iterator[tuple[int, RenderResult]]:
    """Render chunks in this process, a local process pool, or on a Dask cluster; yield as they finish."""
    if not todo:
        return
    if scheduler is not None:
        yield from _run_dask(todo, scheduler, key)
        return
    workers = DEFAULT_WORKERS if workers is None else int(workers)
    if workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    workers = min(workers, len(todo))
    if workers == 1:
        if threads:
            _init_worker(threads)
        for t in todo:
            yield _render_chunk(t)
        return
    threads = threads or max(1, (os.cpu_count() or 1) // workers)
    import multiprocessing as mp

    # spawn: a forked child would inherit this process's Dr.Jit thread pool state.
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn"), initializer=_init_worker, initargs=(threads,))
    pending = {pool.submit(_render_chunk, t) for t in todo}
    try:
        while pending:
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for f in sorted(finished, key=lambda f: f.result()[0]):
                yield f.result()
    finally:
        pool.shutdown(wait=not pending, cancel_futures=True)


def _run_dask(todo: list[ChunkTask], scheduler: Any, key: str) -> Iterator[tuple[int, RenderResult]]:
    try:
        from distributed import Client, as_completed
    except ImportError:  # pragma: no cover - dask is a dependency
        raise RuntimeError("--scheduler needs dask.distributed: pip install 'dask[distributed]'") from None
    own = not isinstance(scheduler, Client)
    client = Client(scheduler) if own else scheduler
    try:
        futures = [client.submit(_render_chunk, t, key=f"mcrt-reference-{key}-{t.index}-{t.seed}-{t.spp}", pure=False) for t in todo]
        try:
            for _, out in as_completed(futures, with_results=True):
                yield out
        finally:
            client.cancel(futures)
    finally:
        if own:
            client.close()


# --------------------------------------------------------------------------
# Load
# --------------------------------------------------------------------------


def load_reference(
    scene: Scene | str | os.PathLike | None,
    camera: str,
    res: int | tuple[int, int],
    max_depth: int,
    *,
    directory: str | os.PathLike = REFERENCE_DIR,
    check_checksum: bool = True,
) -> RenderResult:
    """The committed reference for (scene, camera, res, max depth); never renders.

    Raises
    ------
    MissingReference
        No manifest entry or no file.
    CorruptReference
        The file's SHA-256 differs from the manifest's, or it does not read.
    StaleReference
        The reference was rendered for another version of the scene (its
        scene hash is not ``scene.content_hash()``).

    Every message names the ``mcrt reference build`` command that rebuilds
    the reference.
    """
    from mcrt.imageio import ImageError, read_exr

    scene = _resolve_scene(scene)
    w, h = _size(res)
    directory = Path(directory)
    key = reference_key(scene.name, camera, (w, h), max_depth)
    data = read_manifest(directory)
    entry = data["references"].get(key)
    cmd = rebuild_command(scene, camera, (w, h), max_depth, *((entry["spp"], entry.get("chunk_spp"), entry.get("base_seed", 0)) if entry else ()))
    where = _display_path(directory)
    if entry is None:
        raise MissingReference(f"no reference {key} in {where}/{MANIFEST_NAME}; build it with: {cmd}", cmd)
    path = directory / entry["file"]
    if not path.exists():
        raise MissingReference(f"reference file {_display_path(path)} is missing; rebuild it with: {cmd} "
                               f"(or restore it with `git checkout -- {_display_path(path)}`)", cmd)
    if check_checksum:
        digest = sha256_file(path)
        if digest != entry["sha256"]:
            raise CorruptReference(f"{_display_path(path)}: SHA-256 {digest[:12]}... does not match the manifest's "
                                   f"{entry['sha256'][:12]}... (modified or corrupt); rebuild it with: {cmd}", cmd)
    want = scene.content_hash()
    if entry["scene_hash"] != want:
        raise StaleReference(f"reference {key} is stale: built for scene hash {entry['scene_hash']}, the scene "
                             f"{_display_path(scene.path)} now hashes to {want}; rebuild it with: {cmd}", cmd)
    try:
        r = read_exr(path)
    except ImageError as e:
        raise CorruptReference(f"{e}; rebuild it with: {cmd}", cmd) from None
    if r.scene_hash != want or r.shape != (h, w) or r.max_depth != max_depth or r.camera != camera:
        raise StaleReference(f"{_display_path(path)} does not hold {key} for scene hash {want} "
                             f"(it has {r.camera} {r.shape[1]}x{r.shape[0]} d{r.max_depth}, scene hash {r.scene_hash}); "
                             f"rebuild it with: {cmd}", cmd)
    return r


# --------------------------------------------------------------------------
# List and verify
# --------------------------------------------------------------------------


def _entry_scene(entry: dict[str, Any]) -> Scene:
    p = Path(entry["scene_file"])
    return load_scene(p if p.is_absolute() else REPO_ROOT / p)


def _entry_status(directory: Path, key: str, entry: dict[str, Any]) -> tuple[str, str]:
    """(status, detail) of one manifest entry without rendering: ok, missing, checksum, stale, no scene."""
    from mcrt.scene import SceneError

    try:
        scene = _entry_scene(entry)
        cmd = rebuild_command(scene, entry["camera"], (entry["width"], entry["height"]), entry["max_depth"],
                              entry["spp"], entry.get("chunk_spp"), entry.get("base_seed", 0))
    except SceneError as e:
        return "no scene", str(e)
    path = directory / entry["file"]
    if not path.exists():
        return "missing", f"{_display_path(path)} is missing; rebuild it with: {cmd}"
    digest = sha256_file(path)
    if digest != entry["sha256"]:
        return "checksum", (f"{_display_path(path)}: SHA-256 {digest[:12]}... does not match the manifest's "
                            f"{entry['sha256'][:12]}...; rebuild it with: {cmd}")
    if scene.content_hash() != entry["scene_hash"]:
        return "stale", (f"built for scene hash {entry['scene_hash']}, {entry['scene_file']} now hashes to "
                         f"{scene.content_hash()}; rebuild it with: {cmd}")
    return "ok", ""


def list_references(directory: str | os.PathLike = REFERENCE_DIR) -> list[dict[str, Any]]:
    """One row per manifest entry: its fields plus ``key``, ``status`` and ``detail`` (no rendering).

    ``status`` is ``ok``, ``missing`` (no file), ``checksum`` (file differs
    from the manifest), ``stale`` (scene hash changed) or ``no scene`` (the
    scene file does not load).
    """
    directory = Path(directory)
    rows = []
    for key, entry in read_manifest(directory)["references"].items():
        status, detail = _entry_status(directory, key, entry)
        rows.append({"key": key, **entry, "status": status, "detail": detail})
    return rows


def format_table(rows: list[dict[str, Any]]) -> str:
    """The ``mcrt reference list`` table."""
    head = ("reference", "camera", "size", "depth", "spp", "KiB", "rel.s.e.", "mitsuba", "variant", "render s", "built", "status")
    lines = [head]
    for r in rows:
        lines.append((
            r["key"], r["camera"], f"{r['width']}x{r['height']}", _depth_label(r["max_depth"]), str(r["spp"]),
            f"{r.get('bytes', 0) / 1024:.0f}", f"{r.get('median_rel_std_error', float('nan')):.2%}",
            r["mitsuba_version"], r["variant"], f"{r.get('render_time_s', 0):.0f}", r.get("date", "")[:10], r["status"],
        ))
    widths = [max(len(str(line[i])) for line in lines) for i in range(len(head))]
    right = {4, 5, 6, 9}
    out = ["  ".join(str(c).rjust(wd) if i in right else str(c).ljust(wd) for i, (c, wd) in enumerate(zip(line, widths))).rstrip() for line in lines]
    out.insert(1, "  ".join("-" * wd for wd in widths))
    total = sum(r.get("bytes", 0) for r in rows)
    size = f"{total / 2**20:.1f} MiB" if total >= 2**20 else f"{total / 1024:.0f} KiB"
    out.append(f"{len(rows)} references, {size}; rel.s.e. = median relative standard error of a pixel's mean")
    for r in rows:
        if r["status"] != "ok":
            out.append(f"{r['key']}: {r['status']}: {r['detail']}")
    return "\n".join(out)


@dataclass
class VerifyResult:
    """Verdict on one stored reference."""

    key: str
    status: str  # 'ok', 'failed' or 'unusable'
    checks: list[str] = field(default_factory=list)  # one line per check, in order
    comparison: Any = None  # mcrt.stats.Comparison of the fresh render against the reference
    fresh_spp: int = 0
    fresh_seed: int = 0
    wall_time: float = 0.0

    @property
    def passed(self) -> bool:
        return self.status == "ok"


def verify_references(
    keys: Sequence[str] | None = None,
    *,
    directory: str | os.PathLike = REFERENCE_DIR,
    spp: int | None = None,
    seed: int = VERIFY_BASE_SEED,
    alpha: float = 0.01,
    tile: int = 8,
    render: bool = True,
    backend: str = "llvm",
    progress: bool = True,
) -> list[VerifyResult]:
    """Check every reference (or those in ``keys``) against its checksum and the installed Mitsuba.

    For each reference: the file exists and its SHA-256 matches the manifest;
    the scene file still hashes to the reference's scene hash; and, with
    ``render``, a fresh Mitsuba render at a small budget (``spp``, default
    :data:`VERIFY_PATHS` paths per reference, at least
    :data:`VERIFY_MIN_SPP`) with a seed no build uses agrees with the stored
    mean by :func:`mcrt.stats.compare_images` (Welch tile test, each side
    with its own per-sample variance, Holm at ``alpha``). A failure there
    means the installed Mitsuba (or Dr.Jit, or mcrt's scene translation)
    renders a different image than the one that built the reference.

    Variance: the fresh render and the reference come from the same
    estimator, so if they agree they share one per-sample variance per pixel,
    and the fresh side is tested with the larger of its own estimate and the
    reference's (``max(var_fresh, var_ref)``). With its own variance alone a
    small fresh render false-alarms: per-pixel variance here is dominated by
    rare caustic paths (light, mirror sphere, diffuse surface) that a
    1024-spp render usually misses, so its mean and its variance estimate are
    both low together. Measured on 32 correct runs (64x64, near and far,
    max depth 8 and -1, 1024 fresh spp against the 32768- and 16384-spp
    references, tile 8, Holm 0.01): with its own variance 10 of 32 were
    rejected, every time with the fresh side darker (largest |t| 4.1 to
    5.1); with the larger variance none was (largest |t| 1.6 to 3.0), while
    the same renders made 2 % brighter were caught in 31 of 32 and 5 %
    brighter in 32 of 32.

    The fresh render's seed is ``chunk_seed(seed, 0)``; with the default
    ``seed`` the verdict is reproducible, and a failing reference can be
    re-checked with other seeds.
    """
    from mcrt.imageio import ImageError, read_exr
    from mcrt.scene import SceneError

    directory = Path(directory)
    entries = read_manifest(directory)["references"]
    if keys:
        unknown = [k for k in keys if k not in entries]
        if unknown:
            raise MissingReference(f"no reference {', '.join(unknown)} in {_display_path(directory)}/{MANIFEST_NAME} (have {', '.join(entries) or 'none'})")
        entries = {k: entries[k] for k in keys}
    results = []
    versions = None
    for key, entry in entries.items():
        t0 = time.perf_counter()
        res = VerifyResult(key, "ok")
        results.append(res)
        status, detail = _entry_status(directory, key, entry)
        if status == "no scene":
            res.status = "unusable"
            res.checks.append(f"scene: {detail}")
            continue
        if status in ("missing", "checksum"):
            res.status = "failed"
            res.checks.append(f"checksum: {detail}")
            continue
        res.checks.append(f"checksum: ok (sha256 {entry['sha256'][:12]}...)")
        if status == "stale":
            res.status = "failed"
            res.checks.append(f"scene: stale: {detail}")
            continue
        res.checks.append(f"scene: ok (hash {entry['scene_hash']})")
        if not render:
            continue
        try:
            ref = read_exr(directory / entry["file"])
        except ImageError as e:
            res.status = "failed"
            res.checks.append(f"read: {e}")
            continue
        if versions is None:
            versions = _installed_versions(backend)
        drift = [f"{k.split('_')[0]} {entry[k]} -> {versions[k]}" for k in ("mitsuba_version", "drjit_version") if entry.get(k) != versions[k]]
        res.checks.append("versions: " + (f"built with Mitsuba {entry['mitsuba_version']}, Dr.Jit {entry['drjit_version']}, {entry['variant']}; "
                                          + ("installed: same" if not drift else "installed differs: " + ", ".join(drift))))
        w, h = entry["width"], entry["height"]
        n = int(spp) if spp else max(VERIFY_MIN_SPP, VERIFY_PATHS // (w * h))
        fresh_seed = chunk_seed(seed, 0)
        if fresh_seed in entry.get("chunk_seeds", []):
            fresh_seed = chunk_seed(seed, 1)
        res.fresh_spp, res.fresh_seed = n, fresh_seed
        from mcrt.mitsuba import render_mitsuba
        from mcrt.stats import compare_images, floor_variance

        _log(f"verify {key}: rendering {w}x{h} at {n} spp (seed {fresh_seed})", progress)
        try:
            scene = _entry_scene(entry)
            fresh = render_mitsuba(scene, entry["camera"], w, h, n, fresh_seed, entry["max_depth"], backend=backend, progress=progress)
        except (SceneError, RuntimeError, ValueError) as e:
            res.status = "unusable"
            res.checks.append(f"render: {e}")
            continue
        # Both sides are the same estimator, so under "same image" they share one per-sample
        # variance per pixel; the fresh side takes the larger of the two estimates (see docstring).
        tested = floor_variance(fresh, ref)
        cmp = compare_images(tested, ref, alpha=alpha, tile=tile)
        res.comparison = cmp
        res.checks.append(f"agreement: {n} fresh spp vs {entry['spp']} reference spp: {cmp.summary()}")
        if not cmp.passed:
            res.status = "failed"
        res.wall_time = time.perf_counter() - t0
    return results


def format_verify(results: list[VerifyResult]) -> str:
    """The ``mcrt reference verify`` report: one block per reference, then a verdict line."""
    out = []
    for r in results:
        word = {"ok": "OK", "failed": "FAILED", "unusable": "UNUSABLE"}[r.status]
        out.append(f"{word:8s} {r.key}" + (f"  ({r.wall_time:.1f} s)" if r.wall_time else ""))
        out.extend(f"         {c}" for c in r.checks)
    n_ok = sum(r.passed for r in results)
    bad = [r.key for r in results if not r.passed]
    out.append(f"{n_ok} of {len(results)} references verified" + (f"; not verified: {', '.join(bad)}" if bad else ""))
    return "\n".join(out)


# --------------------------------------------------------------------------
# Command line: mcrt reference build | verify | list
# --------------------------------------------------------------------------


def _parse_depth(text: str) -> int:
    v = int(text)
    if v < 1 and v != -1:
        import argparse

        raise argparse.ArgumentTypeError(f"max depth must be -1 (unbounded) or >= 1, got {v}")
    return v


def register(subparsers) -> None:
    """Add ``reference`` with ``build``, ``verify`` and ``list`` to an argparse subparsers object."""
    p = subparsers.add_parser(
        "reference",
        help="build, verify and list the Mitsuba ground-truth references in reference/",
        description="Mitsuba ground truth: build references (resumable, in chunks, locally or on a Dask cluster), "
                    "verify them against their checksums and the installed Mitsuba, list them.",
    )
    sub = p.add_subparsers(dest="reference_command", required=True)

    b = sub.add_parser(
        "build",
        help="render references with Mitsuba into reference/ (resumable)",
        description="Render references with Mitsuba (mean + per-sample variance) in chunks of one seed each. "
                    "Finished chunks are kept in reference/chunks/, so an interrupted build continues where it stopped. "
                    "Every combination of --camera, --res and --max-depth is built.",
    )
    b.add_argument("--scene", default=None, help="scene file (default: reference/scenes/canonical.toml)")
    b.add_argument("--camera", nargs="+", default=None, help="camera name(s) from the scene file (default: near)")
    b.add_argument("--res", nargs="+", type=int, default=None, help="square resolution(s) N (N x N) (default: 64)")
    b.add_argument("--width", type=int, default=None, help="width, for a non-square reference (with --height)")
    b.add_argument("--height", type=int, default=None, help="height, for a non-square reference (with --width)")
    b.add_argument("--max-depth", nargs="+", type=_parse_depth, default=None,
                   help="longest path(s) in segments: 1 emitters only, 2 direct light, -1 unbounded (default: 8)")
    b.add_argument("--spp", type=int, default=None,
                   help=f"samples per pixel in total (default: the committed reference's spp, else {DEFAULT_SPP})")
    b.add_argument("--chunk-spp", type=int, default=None, help="samples per pixel of one chunk (default: about 2^24 paths per chunk)")
    b.add_argument("--seed", type=int, default=DEFAULT_BASE_SEED, help="base seed; chunk i uses a hash of (seed, i) (default: %(default)s)")
    b.add_argument("--workers", type=int, default=None,
                   help=f"local worker processes (default {DEFAULT_WORKERS}: Dr.Jit already uses every core in one process)")
    b.add_argument("--threads", type=int, default=None, help="Dr.Jit threads per local worker (default: cores / workers)")
    b.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="Dask scheduler address (tcp://host:8786): render the chunks on that cluster")
    b.add_argument("--standard", action="store_true",
                   help="build every committed reference (canonical scene) with its committed spp; other selections are ignored")
    b.add_argument("--backend", choices=("llvm", "cuda"), default="llvm", help="Mitsuba variant: llvm_ad_rgb or cuda_ad_rgb (default: %(default)s)")
    b.add_argument("--dir", default=str(REFERENCE_DIR), help="reference folder (default: reference/)")
    b.add_argument("--quiet", action="store_true", help="no progress output")
    b.set_defaults(func=cmd_build)

    v = sub.add_parser(
        "verify",
        help="check checksums and agreement with the installed Mitsuba (exit 0 ok, 1 failed, 2 unusable)",
        description="For each reference: check its SHA-256 against the manifest and its scene hash against the scene file, "
                    "then render a small fresh budget with new seeds and test it against the stored mean "
                    "(Welch tile test, Holm), which catches a Mitsuba or Dr.Jit version that renders differently.",
    )
    v.add_argument("keys", nargs="*", help="references to verify (default: all in the manifest), e.g. canonical_near_64x64_d8")
    v.add_argument("--spp", type=int, default=None,
                   help=f"fresh samples per pixel (default: 2^{VERIFY_PATHS.bit_length() - 1} paths per reference, at least {VERIFY_MIN_SPP} spp)")
    v.add_argument("--seed", type=int, default=VERIFY_BASE_SEED, help="base seed of the fresh renders (default: %(default)s)")
    v.add_argument("--alpha", type=float, default=0.01, help="family-wise error rate per reference (Holm) (default: %(default)s)")
    v.add_argument("--tile", type=int, default=8, help="tile size in pixels (default: %(default)s)")
    v.add_argument("--checksums-only", action="store_true", help="only check files, checksums and scene hashes (no rendering)")
    v.add_argument("--backend", choices=("llvm", "cuda"), default="llvm", help="Mitsuba variant of the fresh renders (default: %(default)s)")
    v.add_argument("--dir", default=str(REFERENCE_DIR), help="reference folder (default: reference/)")
    v.add_argument("--quiet", action="store_true", help="no progress output")
    v.set_defaults(func=cmd_verify)

    ls = sub.add_parser("list", help="table of the references in the manifest, with their status",
                        description="Summary table of reference/manifest.json: size, spp, noise, versions and status "
                                    "(ok, missing, checksum, stale, no scene). Renders nothing.")
    ls.add_argument("--dir", default=str(REFERENCE_DIR), help="reference folder (default: reference/)")
    ls.add_argument("--json", action="store_true", help="print the rows as JSON instead of a table")
    ls.set_defaults(func=cmd_list)


def _build_jobs(args) -> list[tuple[Scene, str, tuple[int, int], int, int]]:
    """(scene, camera, (w, h), max depth, spp) for every reference a build command asks for."""
    scene = _resolve_scene(args.scene)
    if args.standard:
        return [(scene, s.camera, (s.res, s.res), s.max_depth, args.spp or s.spp) for s in STANDARD]
    if (args.width is None) != (args.height is None):
        raise ValueError("--width and --height go together")
    sizes = [(args.width, args.height)] if args.width else [(n, n) for n in (args.res or [64])]
    jobs = []
    for cam in args.camera or ["near"]:
        scene.camera(cam)
        for size in sizes:
            for d in args.max_depth or [8]:
                jobs.append((scene, cam, _size(size), d, args.spp or _standard_spp(cam, _size(size), d)))
    return jobs


def cmd_build(args) -> int:
    from mcrt.scene import SceneError

    try:
        jobs = _build_jobs(args)
    except (SceneError, ValueError) as e:
        print(f"mcrt reference build: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    for i, (scene, cam, size, depth, spp) in enumerate(jobs):
        if len(jobs) > 1:
            _log(f"mcrt reference build: {i + 1} of {len(jobs)}: {reference_key(scene.name, cam, size, depth)}", not args.quiet)
        try:
            build_reference(scene, cam, size, depth, spp, chunk_spp=args.chunk_spp, base_seed=args.seed, workers=args.workers,
                            threads=args.threads, scheduler=args.scheduler, directory=args.dir, backend=args.backend,
                            progress=not args.quiet)
        except KeyboardInterrupt:
            key = reference_key(scene.name, cam, size, depth)
            folder = _display_path(Path(args.dir) / CHUNK_DIR_NAME / key)
            print(f"\nmcrt reference build: interrupted; finished chunks are kept in {folder}/: "
                  f"run the same command again to continue", file=sys.stderr)
            raise
    return EXIT_OK


def cmd_verify(args) -> int:
    try:
        results = verify_references(args.keys or None, directory=args.dir, spp=args.spp, seed=args.seed, alpha=args.alpha,
                                    tile=args.tile, render=not args.checksums_only, backend=args.backend, progress=not args.quiet)
    except ReferenceUnavailable as e:
        print(f"mcrt reference verify: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    if not results:
        print(f"mcrt reference verify: no references in {_display_path(Path(args.dir) / MANIFEST_NAME)}", file=sys.stderr)
        return EXIT_UNUSABLE
    print(format_verify(results))
    if any(r.status == "failed" for r in results):
        return EXIT_FAILED
    return EXIT_UNUSABLE if any(r.status == "unusable" for r in results) else EXIT_OK


def cmd_list(args) -> int:
    try:
        rows = list_references(args.dir)
    except ReferenceUnavailable as e:
        print(f"mcrt reference list: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    if args.json:
        print(json.dumps(rows, indent=2))
    elif not rows:
        print(f"no references in {_display_path(Path(args.dir) / MANIFEST_NAME)}")
    else:
        print(format_table(rows))
    return EXIT_OK if all(r["status"] == "ok" for r in rows) else EXIT_FAILED


def main(argv: Iterable[str] | None = None) -> int:
    """``python -m mcrt.reference build|verify|list ...``: ``mcrt reference ...`` without the rest of the CLI."""
    import argparse

    ap = argparse.ArgumentParser(prog="mcrt")
    register(ap.add_subparsers(dest="command", required=True))
    args = ap.parse_args(["reference", *(sys.argv[1:] if argv is None else argv)])
    try:
        return args.func(args)
    except (ValueError, RuntimeError, OSError) as e:  # SceneError, ImageError, ReferenceUnavailable included
        print(f"mcrt: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
