"""Building a reference: chunks rendered locally, in a process pool or on Dask, merged, recorded in the manifest."""

from __future__ import annotations

import contextlib
import datetime as _dt
import os
import platform
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from mcrt.film import Progress, RenderResult, merge
from mcrt.groundtruth.manifest import commit_reference, remove_stale_temps, sha256_file
from mcrt.groundtruth.spec import (CHUNK_DIR_NAME, DEFAULT_BASE_SEED, DEFAULT_SPP, DEFAULT_WORKERS, REFERENCE_DIR, chunk_seed,
                                 chunk_sizes, chunk_spp_for, display_path, rebuild_command, reference_key, resolve_scene,
                                 size_of)
from mcrt.render import render
from mcrt.scene import Scene
from mcrt.util import atomic
from mcrt.util.progress import log


def machine_info() -> dict[str, Any]:
    """Where this process runs: host, and :func:`mcrt.provenance.machine` (OS, CPU model, core count), Python."""
    from mcrt.provenance import machine

    m = machine()
    return {"host": platform.node(), "platform": m["platform"], "cpu": m["cpu"], "cores": m["cores"],
            "python": platform.python_version()}



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
    s = task.scene.settings(camera=task.camera, width=task.width, height=task.height, spp=task.spp, max_depth=task.max_depth)
    r = render(task.scene, s, renderer="mitsuba", seed=task.seed, backend=task.backend, progress=False)
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


def installed_versions(backend: str) -> dict[str, str]:
    import drjit as dr
    import mitsuba as mi

    from mcrt.mitsuba_scene import variant_for

    return {"mitsuba_version": mi.__version__, "drjit_version": dr.__version__, "variant": variant_for(backend)}


def _chunk_path(folder: Path, index: int) -> Path:
    return folder / f"chunk_{index:04d}.exr"


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

    The merged reference ``<directory>/<key>.exr`` and its manifest entry are
    replaced together or not at all (:func:`mcrt.groundtruth.manifest.commit_reference`:
    a crash between the two writes leaves the previous pair or the new one). Interrupting the build (KeyboardInterrupt, a killed
    process, a write error) keeps every finished chunk; calling it again
    renders only the missing ones.
    """
    t_start = time.perf_counter()
    scene = resolve_scene(scene)
    scene.camera(camera)  # raises SceneError for an unknown camera
    w, h = size_of(res)
    s = scene.settings(camera=camera, width=w, height=h, spp=int(spp), max_depth=int(max_depth))
    spp = s.spp
    chunk_spp = int(chunk_spp) if chunk_spp else chunk_spp_for((w, h), spp)
    if chunk_spp < 2:
        raise ValueError(f"chunk_spp must be >= 2 (a chunk needs two samples for a variance), got {chunk_spp}")
    sizes = chunk_sizes(spp, chunk_spp)
    if sizes[-1] < 2:
        raise ValueError(f"spp {spp} leaves a last chunk of 1 sample with chunk_spp {chunk_spp}: choose another spp")
    directory = Path(directory)
    key = reference_key(scene.name, camera, (w, h), s.max_depth)
    folder = directory / CHUNK_DIR_NAME / key
    folder.mkdir(parents=True, exist_ok=True)
    remove_stale_temps(folder)
    remove_stale_temps(directory)
    versions = installed_versions(backend)
    scene_hash = scene.content_hash()
    tasks = [ChunkTask(scene, camera, w, h, s.max_depth, i, chunk_seed(base_seed, i), n, backend) for i, n in enumerate(sizes)]
    command = rebuild_command(scene, camera, (w, h), s.max_depth, spp, chunk_spp, base_seed)

    from mcrt.image_files import ImageError, read_exr, write_exr

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
            log(f"reference {key}: chunk {t.index} not reusable ({problem}); rendering it again", progress)
        todo.append(t)
    reused = sorted(chunks)
    log(f"reference {key}: {spp} spp in {len(tasks)} chunks of {chunk_spp} spp; "
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
    # Written under a temporary name; commit_reference renames it into place together with the manifest.
    staged = atomic.temporary_path(path)
    write_exr(staged, merged)
    wall = time.perf_counter() - t_start

    machine = machine_info()
    hosts = sorted({c.extra.get("host", machine["host"]) for c in ordered})
    entry = {
        "file": path.name,
        "sha256": sha256_file(staged),
        "bytes": staged.stat().st_size,
        "scene": scene.name,
        "scene_file": display_path(scene.path),
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
    try:
        commit_reference(directory, staged, key, entry)
    finally:
        with contextlib.suppress(OSError):
            staged.unlink()  # gone after a commit; a failed one leaves the previous reference and manifest
    if not keep_chunks:
        for t in tasks:
            with contextlib.suppress(OSError):
                _chunk_path(folder, t.index).unlink()
        with contextlib.suppress(OSError):
            folder.rmdir()
    log(f"reference {key}: wrote {display_path(path)} ({merged.spp} spp, {entry['bytes'] / 1024:.0f} KiB, "
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
