"""Throughput of mcrt against Mitsuba on the same scene, measured in one run.

Renderers alternate within every repetition (mcrt, Mitsuba, mcrt, ...), so a
machine whose speed drifts slows both alike; the figures are medians over the
repetitions after one warm-up render each, which also takes the JIT
compilation out of the timing (reported apart, from Dr.Jit's kernel history).
Speed is paths per second (one path per pixel sample, whatever its length).

Renders too long to repeat are timed on a bounded part of themselves
(``max_paths``): the same bands of whole rows for every renderer, spread
evenly down the image (:func:`bounded_rows`), at the case's spp: mcrt's
render of those rows alone (``render_tracer(rows=...)``, the render's own
launches), Mitsuba's ``mi.render`` of films cropped to them. Each row
records the paths a timed render traced and whether it was bounded.

Where a committed Mitsuba reference of the case exists (mcrt.groundtruth), each
timed render is also scored against it: the excess MSE (the squared error
minus the reference's own noise, mean(var_ref / spp_ref)), averaged over the
repetitions, and the efficiency 1 / (MSE_excess x median time). For unbiased
renderers MSE falls as 1/spp while time grows as spp, so the efficiency does
not depend on the spp and its ratio is the ratio at equal time.

This module measures; :mod:`mcrt.bench_page` writes the report
(``mcrt bench --report DIR``) from the measurements' dictionary
(:func:`bench_data`, also the JSON file).
"""

from __future__ import annotations

import contextlib
import json
import os
import resource
import subprocess
import statistics
import sys
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np


@dataclass
class BenchCase:
    camera: str
    width: int
    height: int
    spp: int
    max_depth: int
    light_samples: int = 1


@dataclass
class BenchRow:
    case: BenchCase
    renderer: str
    times: list[float]
    compile_time: float | None
    paths_per_second: float = 0.0
    mse_excess: float | None = None  # mean over the MSE renders; None without a committed reference
    efficiency: float | None = None  # 1 / (mse_excess x median time)
    paths: int = 0  # paths one timed render traced
    bounded: bool = False  # timed on a bounded part of the render (module docstring)
    load: tuple = ()  # os.getloadavg() before the case (1, 5 and 15 minutes)


#: Paths a timed render traces at most (module docstring), unless run_bench is told otherwise.
MAX_PATHS = 1 << 22
#: Renders (distinct seeds) whose MSE against the committed reference is averaged, timed ones included.
MSE_RENDERS = 16


def _renderers(names, scene, backend, intersector, max_paths: int):
    """Callables (case, seed) -> (seconds, compile seconds or None, image or None, paths) for each renderer.

    Setup and loading are outside the clock. A case of more than
    ``max_paths`` paths is timed on the same bands of rows by every
    renderer (:func:`bounded_rows`) and returns no image.
    """
    import drjit as dr

    from mcrt.render import render
    from mcrt.tracer import render_tracer

    def mcrt_time(c, seed, **sampler):
        s = scene.settings(camera=c.camera, width=c.width, height=c.height, spp=c.spp, max_depth=c.max_depth,
                           light_samples=c.light_samples)
        rows = bounded_rows(c, max_paths)
        if rows is None:
            t0 = time.perf_counter()
            r = render(scene, s, seed=seed, backend=backend, intersector=intersector, progress=False, **sampler)
            return time.perf_counter() - t0, None, r.mean, c.width * c.height * c.spp
        t0 = time.perf_counter()
        r = render_tracer(scene, replace(s, seed=seed), backend=backend, intersector=intersector, progress=False, rows=rows,
                          **sampler)
        return time.perf_counter() - t0, None, None, int(r.extra["paths"])

    loaded = {}

    def mitsuba_time(c, seed):
        # Mitsuba's own entry point, mi.render, on scenes loaded once per case: its best case, faster
        # than the deterministic passes with variance of mcrt.render's 'mitsuba' renderer.
        import mitsuba as mi

        rows = bounded_rows(c, max_paths) or [(0, c.height)]
        key = (c.camera, c.width, c.height, c.max_depth, tuple(rows))
        if key not in loaded:
            loaded.clear()
            loaded[key] = [mi.load_dict(_cropped(scene, c, band, backend)) for band in rows]
        dr.sync_thread()
        dr.kernel_history()
        t0 = time.perf_counter()
        for band in loaded[key]:
            img = mi.render(band, spp=c.spp, seed=seed)
            dr.eval(img)
        dr.sync_thread()
        elapsed = time.perf_counter() - t0
        compile_s = sum(h.get("codegen_time", 0.0) + h.get("backend_time", 0.0) for h in dr.kernel_history()) / 1000
        image = np.asarray(img)[..., :3] if rows == [(0, c.height)] else None
        return elapsed, compile_s, image, c.width * sum(n for _, n in rows) * c.spp

    # mcrt-sobol: mcrt with the sobol pixel sampler (mcrt.samplers), to state its cost in the same run.
    table = {"mcrt": mcrt_time, "mcrt-sobol": lambda c, seed: mcrt_time(c, seed, pixel_sampler="sobol"),
             "mitsuba": mitsuba_time}
    unknown = set(names) - set(table)
    if unknown:
        raise ValueError(f"unknown renderer(s) {', '.join(sorted(unknown))} ({', '.join(table)})")
    return {n: table[n] for n in names}


#: Bands of rows a bounded measurement spreads over, evenly down the image (module docstring).
BANDS = 4


def bounded_rows(c: BenchCase, max_paths: int) -> list[tuple[int, int]] | None:
    """The (first row, count) bands every renderer times of a case of more than ``max_paths`` paths; None: the whole image.

    As many whole rows as ``max_paths`` allows at the case's spp (at least
    one), in up to BANDS equal bands centred in equal parts of the image:
    the top of an image (the ceiling and the light) costs less per path than
    its middle, so a band at the top alone would misstate both renderers.
    Fewer bands where a band would hold fewer pixels than mcrt's launches
    have lanes (mcrt.tracer.MIN_LANES): a launch that small is not the
    render's.
    """
    from mcrt.tracer import MIN_LANES

    if c.width * c.height * c.spp <= max_paths:
        return None
    rows = max(1, min(c.height, max_paths // (c.width * c.spp)))
    parts = max(1, min(BANDS, rows, rows * c.width // MIN_LANES))
    per = rows // parts
    return [(min(c.height - per, max(0, round((i + 0.5) * c.height / parts - per / 2))), per) for i in range(parts)]


def _cropped(scene, c: BenchCase, band: tuple[int, int], backend: str) -> dict:
    """Mitsuba's scene dictionary of the case, its film cropped to the rows of ``band`` (first row, count)."""
    from mcrt.mitsuba_scene import scene_dict

    s = scene.settings(camera=c.camera, width=c.width, height=c.height, max_depth=c.max_depth)
    d = scene_dict(scene, s.camera, s.width, s.height, s.max_depth, "path", rr_depth=s.rr_depth, spp=c.spp, backend=backend)
    first, count = band
    if count < c.height:
        film = next(v["film"] for v in d.values() if isinstance(v, dict) and "film" in v)
        film.update(crop_offset_x=0, crop_offset_y=first, crop_width=c.width, crop_height=count)
    return d


def run_bench(scene, cases: list[BenchCase], *, renderers=("mcrt", "mitsuba"), repeats: int = 5, backend: str = "llvm",
              intersector: str = "convex", progress: bool = True, max_paths: int = MAX_PATHS,
              mse_renders: int = MSE_RENDERS) -> list[BenchRow]:
    """Median paths per second of each renderer on each case, renderers alternating.

    ``max_paths``: the paths above which a case is timed on bands of its
    rows, the same for every renderer (:func:`bounded_rows`). Where the case
    has a committed reference, the MSE is averaged over ``mse_renders``
    renders of distinct seeds (the timed ones and untimed others).
    """
    import drjit as dr

    fns = _renderers(renderers, scene, backend, intersector, max_paths)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    rows = []
    for case in cases:
        ref = _committed_reference(scene, case, progress)
        load = tuple(round(x, 2) for x in os.getloadavg())
        paths = {}
        times = {n: [] for n in fns}
        errors = {n: [] for n in fns}
        compile_time = {}
        for n, fn in fns.items():  # warm-up: the first call compiles the kernels
            dr.kernel_history()
            elapsed, compile_s, _, _ = fn(case, 1000)
            history = dr.kernel_history()
            compile_time[n] = compile_s if compile_s is not None else sum(
                h.get("codegen_time", 0.0) + h.get("backend_time", 0.0) for h in history) / 1000
        for k in range(repeats):
            for n, fn in fns.items():
                elapsed, _, image, paths[n] = fn(case, k)
                times[n].append(elapsed)
                if ref is not None and image is not None:
                    errors[n].append(float(np.mean((image.astype(np.float64) - ref[0]) ** 2)) - ref[1])
            if progress:
                print(f"  {case.camera} {case.width}x{case.height} {case.spp} spp depth {case.max_depth}: repetition {k + 1}/{repeats}",
                      file=sys.stderr, flush=True)
        for n, fn in fns.items():  # more seeds for a steadier MSE: a few renders' MSE swings with rare bright paths
            for seed in range(repeats, mse_renders if errors[n] else 0):
                image = fn(case, seed)[2]
                errors[n].append(float(np.mean((image.astype(np.float64) - ref[0]) ** 2)) - ref[1])
        full = case.width * case.height * case.spp
        for n in fns:
            t = statistics.median(times[n])
            mse = statistics.fmean(errors[n]) if errors[n] else None
            eff = 1.0 / (mse * t) if mse is not None and mse > 0 else None
            rows.append(BenchRow(case, n, times[n], compile_time[n], paths[n] / t, mse, eff, paths[n], paths[n] < full, load))
    return rows


def _committed_reference(scene, case: BenchCase, progress: bool):
    """(mean, noise floor mean(var / spp)) of the case's committed Mitsuba reference, or None where there is none."""
    from mcrt.groundtruth import MissingReference, ReferenceUnavailable, load_reference
    from mcrt.convergence.run import reference_floor

    try:
        ref = load_reference(scene, case.camera, (case.width, case.height), case.max_depth)
    except MissingReference:
        return None
    except ReferenceUnavailable as e:  # stale or corrupt: say so, and time without it
        if progress:
            print(f"  no efficiency for {case.camera} {case.width}x{case.height} depth {case.max_depth}: {e}", file=sys.stderr)
        return None
    return ref.mean.astype(np.float64), reference_floor(ref)["mse"]


@dataclass
class ProfileRow:
    variant: str
    kernel_ms: float  # median execution time of the path kernel (Dr.Jit kernel history)
    key: str = ""  # what the variant changes: 'full', 'no_tetrahedron', 'no_sphere', 'depth2', 'depth1', 'k4', 'triangles', 'rng'


def kernel_profile(scene, *, camera: str = "near", res: int = 256, spp: int = 16, max_depth: int = 8, repeats: int = 5,
                   backend: str = "llvm") -> list[ProfileRow]:
    """Where mcrt's kernel time goes: the path kernel of variants that each leave one part out.

    Medians of ``repeats`` passes (after one warm-up pass) of the kernel alone,
    from Dr.Jit's kernel history. A part's cost is the difference to the full
    kernel; the variants render other images (no tetrahedron, fewer bounces),
    so they time work, not correctness. The RNG row is a kernel that only
    draws random numbers: five per bounce for five bounces, the order of an
    average path's length in the canonical scene (a lane's later paths take
    their pixel jitter from numbers its previous path drew, so a path draws
    no more than five per bounce).
    """
    import drjit as dr

    from mcrt.rng import WeylRng
    from mcrt.tracer import Tracer

    objects = {type(o).__name__: o for o in scene.objects}
    no = {name: replace(scene, objects=tuple(o for o in scene.objects if type(o).__name__ != name)) for name in objects}
    variants = [("full", "full kernel (depth %d)" % max_depth, scene, {}),
                ("no_tetrahedron", "without the tetrahedron", no.get("Tetrahedron", scene), {}),
                ("no_sphere", "without the mirror sphere", no.get("Sphere", scene), {}),
                ("depth2", "depth 2 (camera ray, one light sample, one bounce)", scene, {"max_depth": 2}),
                ("depth1", "depth 1 (camera ray and its hit)", scene, {"max_depth": 1}),
                ("k4", "K = 4 light samples", scene, {"light_samples": 4}),
                ("triangles", "triangles intersector", scene, {"intersector": "triangles"})]
    rows = []
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    for key, label, sc, kw in variants:
        args = dict(max_depth=max_depth, light_samples=1, intersector="convex") | kw
        tracer = Tracer(sc, camera, res, res, args["max_depth"], args["light_samples"], backend=backend, intersector=args["intersector"])
        times = []
        for k in range(repeats + 1):
            dr.kernel_history()
            tracer.pass_sums(1, k, spp)
            dr.sync_thread()
            times.append(max(h["execution_time"] for h in dr.kernel_history() if "execution_time" in h))
        rows.append(ProfileRow(label, statistics.median(times[1:]), key))
    m = Tracer(scene, camera, res, res, max_depth, backend=backend).m
    times = []
    for k in range(repeats + 1):
        rng = WeylRng.seeded(m, res * res * spp, dr.opaque(m.UInt32, k), dr.opaque(m.UInt32, 7))
        acc = m.Float(0.0)
        for _ in range(5 * 5):
            acc += rng.next_1d()
        dr.kernel_history()
        dr.eval(acc)
        dr.sync_thread()
        times.append(max(h["execution_time"] for h in dr.kernel_history() if "execution_time" in h))
    rows.append(ProfileRow("RNG alone (25 draws per path)", statistics.median(times[1:]), "rng"))
    return rows


#: The renders whose peak memory ``--memory`` measures, each in a fresh process: (resolution, spp, max depth).
MEMORY_RUNS = ((256, 16, 8), (4096, 16, 8), (4096, 1024, 1))

_MEMORY_SCRIPT = """
import json, sys, time
import mcrt
from mcrt.scene import load_scene
from mcrt.tracer import render_tracer
res, spp, depth = map(int, sys.argv[1:4])
scene = load_scene()
t0 = time.perf_counter()
r = render_tracer(scene, scene.settings(camera="near", width=res, height=res, spp=spp, max_depth=depth), progress=False)
seconds = time.perf_counter() - t0
# VmHWM: this process's own peak (ru_maxrss would carry the parent's peak across fork and exec).
hwm_kib = next(int(l.split()[1]) for l in open("/proc/self/status") if l.startswith("VmHWM:"))
print(json.dumps({"seconds": seconds, "paths": int(r.extra["paths"]), "image_mib": (r.mean.nbytes + r.variance.nbytes) / 2**20,
                  "peak_rss_mib": hwm_kib / 1024.0, "mean": float(r.mean.mean())}))
"""


def memory_runs(runs=MEMORY_RUNS, *, progress: bool = True) -> list[dict]:
    """Peak resident memory (VmHWM) of whole mcrt renders (near camera), each in a fresh Python process.

    The output image itself (mean and variance, float32) is part of the
    peak; everything else is bounded by the tile, not by resolution or spp.
    """
    out = []
    for res, spp, depth in runs:
        if progress:
            print(f"  memory: {res}x{res}, {spp} spp, depth {depth} ...", file=sys.stderr, flush=True)
        done = subprocess.run([sys.executable, "-c", _MEMORY_SCRIPT, str(res), str(spp), str(depth)], check=True,
                              capture_output=True, text=True)
        out.append({"width": res, "height": res, "spp": spp, "max_depth": depth,
                    **json.loads(done.stdout.strip().splitlines()[-1])})
    return out


def flatness(scene, *, cameras, resolutions, spp: int = 16, max_depth: int = 8, rounds: int = 9,
             max_paths: int = MAX_PATHS, backend: str = "llvm", intersector: str = "convex",
             progress: bool = True) -> dict:
    """mcrt's paths per second at each resolution, renders interleaved: one per resolution per round, in turn.

    Cases timed minutes apart see a shared machine at different speeds;
    here every resolution is timed in every round, so drift slows them
    alike and the medians compare resolutions. Renders over ``max_paths``
    paths are timed on bands of rows (:func:`bounded_rows`); one warm-up
    render each first.
    """
    from mcrt.tracer import TRACERS_KEPT, render_tracer

    cases = [BenchCase(cam, r, r, spp, max_depth) for cam in cameras for r in resolutions]
    if len(cases) > TRACERS_KEPT:  # more would rebuild a tracer (and trace its kernel again) every round
        raise ValueError(f"--flatness interleaves at most {TRACERS_KEPT} cameras x resolutions, got {len(cases)}")
    times: dict[int, list[float]] = {i: [] for i in range(len(cases))}
    paths: dict[int, int] = {}

    def one(i: int, seed: int) -> float:
        c = cases[i]
        s = replace(scene.settings(camera=c.camera, width=c.width, height=c.height, spp=c.spp, max_depth=c.max_depth),
                    seed=seed)
        t0 = time.perf_counter()
        r = render_tracer(scene, s, backend=backend, intersector=intersector, progress=False,
                          rows=bounded_rows(c, max_paths))
        paths[i] = int(r.extra["paths"])
        return time.perf_counter() - t0

    for i in range(len(cases)):
        one(i, 1000)
    for k in range(rounds):
        for i in range(len(cases)):
            times[i].append(one(i, k))
        if progress:
            print(f"  interleaved throughput: round {k + 1}/{rounds}", file=sys.stderr, flush=True)
    rows = [{"camera": c.camera, "width": c.width, "height": c.height, "paths": paths[i], "times": times[i],
             "bounded": bounded_rows(c, max_paths) is not None,
             "paths_per_second": paths[i] / statistics.median(times[i])} for i, c in enumerate(cases)]
    return {"spp": spp, "max_depth": max_depth, "rounds": rounds, "rows": rows}


#: The cases ``--sampler-cost`` times, (camera, resolution, spp) at depth 8: spp multiples of the replicates.
SAMPLER_COST_CASES = (("near", 64, 1024), ("near", 256, 64))


def sampler_cost(scene, *, cases=SAMPLER_COST_CASES, max_depth: int = 8, rounds: int = 5, backend: str = "llvm",
                 intersector: str = "convex", progress: bool = True) -> dict:
    """mcrt's time with the ``sobol`` pixel sampler (mcrt.samplers, its default replicates) against ``independent``.

    Per case one warm-up render each, then ``rounds`` rounds that render
    independent then sobol (seed = round), so drift slows both alike; the
    cost is the ratio of the medians. Whole renders, replicate sums and
    variance included.
    """
    from mcrt.render import render
    from mcrt.samplers import DEFAULT_REPLICATES

    rows = []
    for camera, res, spp in cases:
        s = scene.settings(camera=camera, width=res, height=res, spp=spp, max_depth=max_depth)
        times = {"independent": [], "sobol": []}

        def one(sampler: str, seed: int) -> float:
            t0 = time.perf_counter()
            render(scene, replace(s, seed=seed), backend=backend, intersector=intersector, progress=False,
                   pixel_sampler=sampler)
            return time.perf_counter() - t0

        for sampler in times:
            one(sampler, 1000)
        for k in range(rounds):
            for sampler in times:
                times[sampler].append(one(sampler, k))
        if progress:
            print(f"  sampler cost: {camera} {res}x{res} {spp} spp done", file=sys.stderr, flush=True)
        med = {k: statistics.median(v) for k, v in times.items()}
        rows.append({"camera": camera, "width": res, "height": res, "spp": spp, "paths": res * res * spp, "times": times,
                     "ratio": med["sobol"] / med["independent"]})
    return {"max_depth": max_depth, "rounds": rounds, "replicates": DEFAULT_REPLICATES, "rows": rows}


def previous_run(json_path: Path | None) -> dict | None:
    """The speed-ups of the run whose JSON this run replaces (its commit, date and each case's), or None."""
    from mcrt.bench_page import pairs, speedup

    if json_path is None or not json_path.is_file():
        return None
    try:
        old = json.loads(json_path.read_text())
        prov = old["provenance"]
        return {"commit": prov.get("git_commit"), "date": prov.get("date"),
                "speedups": [{"case": a["case"], "speedup": speedup(a, b)} for a, b in pairs(old["rows"])]}
    except (ValueError, KeyError, TypeError):
        return None  # unreadable or another format: nothing to compare with, the run goes on


def peak_memory_mib() -> float:
    """Peak resident memory of this process (Linux reports KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


#: The course's hand-in (reference/assignments/course2023_800.toml): near camera, 800x800, 100 spp, max depth 8.
COURSE = {"camera": "near", "width": 800, "height": 800, "spp": 100, "max_depth": 8}


def bench_cases(cameras, resolutions, spps, depths, light_samples: int = 1, spp_sweep=(), *, sweep_res=None,
                depth_sweep=(), course_light_samples=()) -> list[BenchCase]:
    """Every (camera, resolution, spp, depth), then the sweeps, then the course's hand-in.

    Each camera's ``spp_sweep`` runs at every ``sweep_res`` (default: the
    last resolution) and the last depth; its ``depth_sweep`` at every
    ``sweep_res`` and the first spp. ``course_light_samples``: the course's
    800x800, 100-spp render (COURSE) with each of these K. A case already
    listed is not timed twice.
    """
    cases = [BenchCase(cam, res, res, spp, depth, light_samples)
             for cam in cameras for res in resolutions for spp in spps for depth in depths]
    extra = []
    for cam in cameras:
        for res in sweep_res or resolutions[-1:]:
            extra += [BenchCase(cam, res, res, spp, depths[-1], light_samples) for spp in spp_sweep]
            extra += [BenchCase(cam, res, res, spps[0], depth, light_samples) for depth in depth_sweep]
    extra += [BenchCase(light_samples=k, **COURSE) for k in course_light_samples]
    for case in extra:
        if case not in cases:
            cases.append(case)
    return cases


def simd_extension() -> str | None:
    """The widest x86 vector extension the CPU reports (/proc/cpuinfo flags), which sets Dr.Jit's LLVM packet width."""
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("flags"):
                flags = set(line.split(":", 1)[1].split())
                for flag, name in (("avx512f", "AVX-512"), ("avx2", "AVX2"), ("avx", "AVX"), ("sse4_2", "SSE4.2")):
                    if flag in flags:
                        return name
    return None


def bench_data(rows: list[BenchRow], *, command: str, backend: str, intersector: str, repeats: int,
               profile: list[ProfileRow] = (), profile_case: dict | None = None, memory: list[dict] = (),
               limits: dict | None = None, max_paths: int = MAX_PATHS, mse_renders: int = MSE_RENDERS,
               flat: dict | None = None, seconds: float | None = None, sampler: dict | None = None,
               previous: dict | None = None) -> dict:
    """The run as one JSON-ready dictionary: what ``--json`` writes and :mod:`mcrt.bench_page` reads.

    Machine and versions come from :func:`mcrt.provenance.provenance`, with
    the backend, the intersector, the libLLVM version and the CPU's vector
    extension added.
    """
    import drjit as dr

    from mcrt.provenance import provenance

    llvm = ".".join(map(str, dr.detail.llvm_version())) if backend == "llvm" else None
    return {"command": command,
            "provenance": provenance(command=command, backend=backend, intersector=intersector, libllvm=llvm,
                                     simd=simd_extension()),
            "backend": backend, "intersector": intersector, "repeats": repeats, "warmup_renders": 1,
            "rows": [dict(asdict(r), median_time=statistics.median(r.times)) for r in rows],
            "peak_memory_mib": peak_memory_mib(),
            "kernel_profile": [asdict(r) for r in profile], "kernel_profile_case": profile_case,
            "max_paths": max_paths, "bands": BANDS, "mse_renders": mse_renders, "flatness": flat,
            "sampler_cost": sampler, "previous": previous,
            "memory_runs": list(memory), "limits": limits,
            "load_end": list(os.getloadavg()), "seconds": seconds, "gpu": gpu_note(backend)}


def gpu_note(backend: str) -> str:
    """Whether this run used a GPU, in words for the report."""
    import drjit as dr

    if backend == "cuda":
        return "This run used Dr.Jit's CUDA backend (mcrt) and Mitsuba's cuda_ad_rgb."
    have = "has a" if dr.has_backend(dr.JitBackend.CUDA) else "has no"
    return (f"No GPU run: this machine {have} usable CUDA backend, and no GPU machine was lent to the task that "
            f"wrote this report; every figure here is the LLVM (CPU) backend's.")


def command_line(parser, args) -> str:
    """The ``mcrt bench`` command that repeats this run: every option that differs from its default."""
    import shlex

    words = ["mcrt", "bench"]
    for action in parser._actions:
        if not action.option_strings or action.dest in ("help",):
            continue
        value, flag = getattr(args, action.dest), action.option_strings[0]
        if value is None or value == action.default:
            continue
        if action.const is True:  # store_true
            words.append(flag)
        else:
            for v in value if isinstance(value, list) else [value]:
                words += [flag, str(v)]
    return " ".join(shlex.quote(w) for w in words)


def register(sub) -> None:
    p = sub.add_parser("bench", help="paths per second of mcrt and Mitsuba on the same scene, in one run")
    p.add_argument("--scene", default=None, help="scene file (default: the canonical room shipped with mcrt, canonical.toml)")
    p.add_argument("--camera", action="append", help="camera(s), repeatable (default: near and far)")
    p.add_argument("--res", type=int, action="append", help="square resolution(s), repeatable (default 256)")
    p.add_argument("--spp", type=int, action="append", help="samples per pixel of one render, repeatable (default 16)")
    p.add_argument("--max-depth", type=int, action="append", help="max depth(s), repeatable (default 8)")
    p.add_argument("--spp-sweep", type=int, action="append", default=None, metavar="SPP",
                   help="also time these samples per pixel, repeatable, at the last --res and --max-depth of each camera "
                        "(the report's section against samples per render; default: none)")
    p.add_argument("--sweep-res", type=int, action="append", default=None, metavar="RES",
                   help="resolution(s) of --spp-sweep and --depth-sweep, repeatable (default: the last --res)")
    p.add_argument("--depth-sweep", type=int, action="append", default=None, metavar="DEPTH",
                   help="also time these max depths, repeatable, at each --sweep-res and the first --spp (default: none)")
    p.add_argument("--course", type=int, action="append", default=None, metavar="K",
                   help="also time the course's hand-in (near, 800x800, 100 spp, depth 8) with K shadow rays, "
                        "repeatable (default: none)")
    p.add_argument("--max-paths", type=int, default=MAX_PATHS,
                   help=f"time renders of more paths on up to {BANDS} bands of their rows, the same for every renderer "
                        f"(default {MAX_PATHS})")
    p.add_argument("--flatness", type=int, default=0, metavar="ROUNDS",
                   help="also time mcrt alone at every --res and camera (the first --spp, the last --max-depth) in "
                        "ROUNDS interleaved rounds, one render per resolution each: its throughput against "
                        "resolution without the machine's drift between cases (default: 0, off)")
    p.add_argument("--sampler-cost", type=int, default=5, metavar="ROUNDS",
                   help="also time mcrt with the sobol pixel sampler against independent samples, alternating, in "
                        "ROUNDS rounds (near camera, 64x64 at 1024 spp and 256x256 at 64 spp, depth 8; 0: off; default: 5)")
    p.add_argument("--memory", action="store_true",
                   help="also measure the peak memory of whole mcrt renders up to 4096x4096 at 1024 spp, each in a fresh "
                        "process (default: off)")
    p.add_argument("--limits", action="store_true",
                   help="also compile the path kernel cold and count its instructions, segments and shadow rays per path "
                        "against the machine (default: off)")
    p.add_argument("--light-samples", type=int, default=1, help="K, shadow rays per diffuse vertex (default 1)")
    p.add_argument("--repeats", type=int, default=5,
                   help="timed repetitions per renderer and case, after one warm-up render (default 5)")
    p.add_argument("--mse-renders", type=int, default=MSE_RENDERS,
                   help="renders of distinct seeds whose MSE against a committed reference is averaged, the timed ones "
                        f"included (default {MSE_RENDERS})")
    p.add_argument("--renderers", default="mcrt,mitsuba", help="comma-separated renderers: mcrt, mcrt-sobol (the sobol pixel sampler), mitsuba (default: mcrt,mitsuba)")
    p.add_argument("--intersector", choices=("convex", "triangles"), default="convex", help="mcrt's intersector (default: convex)")
    p.add_argument("--backend", choices=("llvm", "cuda"), default="llvm", help="Dr.Jit backend (default: llvm)")
    p.add_argument("--json", default=None, metavar="FILE",
                   help="also write the measurements to this JSON file (default: none; DIR/bench.json with --report)")
    p.add_argument("--profile", action="store_true",
                   help="also time mcrt's path kernel with one part left out at a time, at the first camera, --profile-res "
                        "and the last --spp and --max-depth (where the time goes; default: off)")
    p.add_argument("--profile-res", type=int, default=256,
                   help="square resolution of --profile and --limits (default 256)")
    p.add_argument("--report", default=None, metavar="DIR",
                   help="write the report DIR/index.md, every number in it from this run, and the measurements "
                        "(DIR/bench.json unless --json names another file; default: none)")
    p.add_argument("--tried", default=None, metavar="FILE",
                   help="hand-kept log that the report copies verbatim as its last, labelled section "
                        "(default: DIR/tried.md when that file exists; 'none': no log)")
    p.set_defaults(func=cmd_bench, bench_parser=p)


def _tried_file(args) -> Path | None:
    """The hand-kept log to include: --tried, else DIR/tried.md where it exists; checked before the run."""
    if args.tried == "none" or not args.report:
        return None
    if args.tried is None:
        default = Path(args.report) / "tried.md"
        return default if default.is_file() else None
    if not Path(args.tried).is_file():
        raise ValueError(f"{args.tried}: no such file (--tried names the hand-kept log the report includes)")
    return Path(args.tried)


def cmd_bench(args) -> int:
    from mcrt.bench_page import format_profile, format_table, write_report
    from mcrt.scene import CANONICAL, load_scene

    if args.repeats < 1:
        raise ValueError(f"--repeats must be at least 1, got {args.repeats}")
    tried = _tried_file(args)
    scene = load_scene(args.scene or CANONICAL)
    cameras, resolutions, depths = args.camera or ["near", "far"], args.res or [256], args.max_depth or [8]
    spps = args.spp or [16]
    cases = bench_cases(cameras, resolutions, spps, depths, args.light_samples, args.spp_sweep or (),
                        sweep_res=args.sweep_res, depth_sweep=args.depth_sweep or (), course_light_samples=args.course or ())
    max_paths = args.max_paths
    json_path = Path(args.json) if args.json else Path(args.report) / "bench.json" if args.report else None
    previous = previous_run(json_path)  # read before this run overwrites it
    t0 = time.perf_counter()
    rows = run_bench(scene, cases, renderers=args.renderers.split(","), repeats=args.repeats, backend=args.backend,
                     intersector=args.intersector, max_paths=max_paths, mse_renders=args.mse_renders)
    profile, profile_case = [], None
    if args.profile:
        profile_case = {"camera": cameras[0], "width": args.profile_res, "height": args.profile_res, "spp": spps[-1],
                        "max_depth": depths[-1], "repeats": args.repeats}
        profile = kernel_profile(scene, camera=cameras[0], res=args.profile_res, spp=spps[-1], max_depth=depths[-1],
                                 repeats=args.repeats, backend=args.backend)
    limits = None
    if args.limits:
        from mcrt.bench_limits import kernel_limits

        limits = kernel_limits(scene, camera=cameras[0], res=args.profile_res, spp=spps[-1], max_depth=depths[-1],
                               backend=args.backend)
    flat = None
    if args.flatness:
        flat = flatness(scene, cameras=cameras, resolutions=resolutions, spp=spps[0], max_depth=depths[-1],
                        rounds=args.flatness, max_paths=max_paths, backend=args.backend, intersector=args.intersector)
    sampler = sampler_cost(scene, rounds=args.sampler_cost, backend=args.backend,
                           intersector=args.intersector) if args.sampler_cost > 0 else None
    memory = memory_runs() if args.memory else []
    data = bench_data(rows, command=command_line(args.bench_parser, args), backend=args.backend,
                      intersector=args.intersector, repeats=args.repeats, profile=profile, profile_case=profile_case,
                      memory=memory, limits=limits, max_paths=max_paths, mse_renders=args.mse_renders, flat=flat,
                      seconds=time.perf_counter() - t0, sampler=sampler, previous=previous)
    prov, v = data["provenance"], data["provenance"]["versions"]
    print(f"mcrt {v['mcrt']}, Mitsuba {v['mitsuba']}, Dr.Jit {v['drjit']}, {prov['drjit_threads']} threads, "
          f"{prov['machine']['cpu']}")
    print(format_table(data["rows"]))
    print(f"peak memory of this process: {data['peak_memory_mib']:.0f} MiB")
    if profile:
        print(format_profile(data["kernel_profile"], args.profile_res ** 2 * spps[-1]))
    if json_path is not None:
        json_path.parent.mkdir(parents=True, exist_ok=True)
        json_path.write_text(json.dumps(data, indent=2))
        print(f"wrote {json_path}")
    if args.report:
        index = write_report(Path(args.report), data, json_path=json_path, tried=tried)
        print(f"wrote {index}")
    return 0
