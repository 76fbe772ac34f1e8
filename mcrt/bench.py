"""Throughput of mcrt against Mitsuba on the same scene, measured in one run.

Renderers alternate within every repetition (mcrt, Mitsuba, mcrt, ...), so a
machine whose speed drifts slows both alike; the figures are medians over the
repetitions after one warm-up render each, which also takes the JIT
compilation out of the timing (reported apart, from Dr.Jit's kernel history).
Speed is paths per second (one path per pixel sample, whatever its length).

Where a committed Mitsuba reference of the case exists (mcrt.reference), each
timed render is also scored against it: the excess MSE (the squared error
minus the reference's own noise, mean(var_ref / spp_ref)), averaged over the
repetitions, and the efficiency 1 / (MSE_excess x median time). For unbiased
renderers MSE falls as 1/spp while time grows as spp, so the efficiency does
not depend on the spp and its ratio is the ratio at equal time.
"""

from __future__ import annotations

import json
import platform
import resource
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
    mse_excess: float | None = None  # mean over the timed renders; None without a committed reference
    efficiency: float | None = None  # 1 / (mse_excess x median time)


def _renderers(names, scene, backend, intersector):
    """Callables (case, seed) -> seconds for each renderer; setup and loading are outside the clock."""
    import drjit as dr

    from mcrt.render import render

    def mcrt_time(c, seed):
        s = scene.settings(camera=c.camera, width=c.width, height=c.height, spp=c.spp, max_depth=c.max_depth,
                           light_samples=c.light_samples)
        t0 = time.perf_counter()
        r = render(scene, s, seed=seed, backend=backend, intersector=intersector, progress=False)
        return time.perf_counter() - t0, None, r.mean

    loaded = {}

    def mitsuba_time(c, seed):
        # Mitsuba's own entry point, mi.render, on a scene loaded once per case: its best case, faster
        # than the deterministic passes with variance of mcrt.render's 'mitsuba' renderer.
        import mitsuba as mi

        from mcrt.mitsuba import load_mitsuba_scene

        key = (c.camera, c.width, c.height, c.max_depth)
        if key not in loaded:
            loaded.clear()
            loaded[key] = load_mitsuba_scene(scene, c.camera, c.width, c.height, c.max_depth, backend=backend)
        dr.sync_thread()
        dr.kernel_history()
        t0 = time.perf_counter()
        img = mi.render(loaded[key], spp=c.spp, seed=seed)
        dr.eval(img)
        dr.sync_thread()
        elapsed = time.perf_counter() - t0
        compile_s = sum(h.get("codegen_time", 0.0) + h.get("backend_time", 0.0) for h in dr.kernel_history()) / 1000
        return elapsed, compile_s, np.asarray(img)[..., :3]

    table = {"mcrt": mcrt_time, "mitsuba": mitsuba_time}
    unknown = set(names) - set(table)
    if unknown:
        raise ValueError(f"unknown renderer(s) {', '.join(sorted(unknown))} (mcrt, mitsuba)")
    return {n: table[n] for n in names}


def run_bench(scene, cases: list[BenchCase], *, renderers=("mcrt", "mitsuba"), repeats: int = 5, backend: str = "llvm",
              intersector: str = "convex", progress: bool = True) -> list[BenchRow]:
    """Median paths per second of each renderer on each case, renderers alternating."""
    import drjit as dr

    fns = _renderers(renderers, scene, backend, intersector)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    rows = []
    for case in cases:
        ref = _committed_reference(scene, case, progress)
        times = {n: [] for n in fns}
        errors = {n: [] for n in fns}
        compile_time = {}
        for n, fn in fns.items():  # warm-up: the first call compiles the kernels
            dr.kernel_history()
            elapsed, compile_s, _ = fn(case, 1000)
            history = dr.kernel_history()
            compile_time[n] = compile_s if compile_s is not None else sum(
                h.get("codegen_time", 0.0) + h.get("backend_time", 0.0) for h in history) / 1000
        for k in range(repeats):
            for n, fn in fns.items():
                elapsed, _, image = fn(case, k)
                times[n].append(elapsed)
                if ref is not None:
                    errors[n].append(float(np.mean((image.astype(np.float64) - ref[0]) ** 2)) - ref[1])
            if progress:
                print(f"  {case.camera} {case.width}x{case.height} {case.spp} spp depth {case.max_depth}: repetition {k + 1}/{repeats}",
                      file=sys.stderr, flush=True)
        paths = case.width * case.height * case.spp
        for n in fns:
            t = statistics.median(times[n])
            mse = statistics.fmean(errors[n]) if errors[n] else None
            eff = 1.0 / (mse * t) if mse is not None and mse > 0 else None
            rows.append(BenchRow(case, n, times[n], compile_time[n], paths / t, mse, eff))
    return rows


def _committed_reference(scene, case: BenchCase, progress: bool):
    """(mean, noise floor mean(var / spp)) of the case's committed Mitsuba reference, or None where there is none."""
    from mcrt.reference import MissingReference, ReferenceUnavailable, load_reference
    from mcrt.report.run import reference_floor

    try:
        ref = load_reference(scene, case.camera, (case.width, case.height), case.max_depth)
    except MissingReference:
        return None
    except ReferenceUnavailable as e:  # stale or corrupt: say so, and time without it
        if progress:
            print(f"  no efficiency for {case.camera} {case.width}x{case.height} depth {case.max_depth}: {e}", file=sys.stderr)
        return None
    return ref.mean.astype(np.float64), reference_floor(ref)["mse"]


def format_table(rows: list[BenchRow]) -> str:
    lines = ["| camera | resolution | spp | depth | K | renderer | median s | M paths/s | JIT s | speed-up | MSE excess | efficiency ratio |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    base = {}
    for r in rows:
        if r.renderer == "mitsuba":
            base[json.dumps(asdict(r.case))] = r
    for r in rows:
        c = r.case
        b = base.get(json.dumps(asdict(c)))
        ratio = f"{r.paths_per_second / b.paths_per_second:.1f}x" if b else ""
        jit = f"{r.compile_time:.2f}" if r.compile_time is not None else "-"
        mse = f"{r.mse_excess:.3g}" if r.mse_excess is not None else "-"
        eff = f"{r.efficiency / b.efficiency:.1f}x" if b and r.efficiency and b.efficiency else "-"
        lines.append(f"| {c.camera} | {c.width}x{c.height} | {c.spp} | {c.max_depth} | {c.light_samples} | {r.renderer} | "
                     f"{statistics.median(r.times):.3f} | {r.paths_per_second / 1e6:.2f} | {jit} | {ratio} | {mse} | {eff} |")
    return "\n".join(lines)


@dataclass
class ProfileRow:
    variant: str
    kernel_ms: float  # median execution time of the path kernel (Dr.Jit kernel history)


def kernel_profile(scene, *, camera: str = "near", res: int = 256, spp: int = 16, max_depth: int = 8, repeats: int = 5,
                   backend: str = "llvm") -> list[ProfileRow]:
    """Where mcrt's kernel time goes: the path kernel of variants that each leave one part out.

    Medians of ``repeats`` passes (after one warm-up pass) of the kernel alone,
    from Dr.Jit's kernel history. A part's cost is the difference to the full
    kernel; the variants render other images (no tetrahedron, fewer bounces),
    so they time work, not correctness. The RNG row is a kernel that only
    draws a path's random numbers: five per bounce for the bounces an average
    path makes here, about 5 (a lane's later paths take their pixel jitter
    from numbers its previous path drew).
    """
    import drjit as dr

    from mcrt.rng import WeylRng
    from mcrt.tracer import Tracer

    objects = {type(o).__name__: o for o in scene.objects}
    no = {name: replace(scene, objects=tuple(o for o in scene.objects if type(o).__name__ != name)) for name in objects}
    variants = [("full kernel (depth %d)" % max_depth, scene, {}),
                ("without the tetrahedron", no.get("Tetrahedron", scene), {}),
                ("without the mirror sphere", no.get("Sphere", scene), {}),
                ("depth 2 (camera ray, one light sample, one bounce)", scene, {"max_depth": 2}),
                ("depth 1 (camera ray and its hit)", scene, {"max_depth": 1}),
                ("K = 4 light samples", scene, {"light_samples": 4}),
                ("triangles intersector", scene, {"intersector": "triangles"})]
    rows = []
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    for label, sc, kw in variants:
        args = dict(max_depth=max_depth, light_samples=1, intersector="convex") | kw
        tracer = Tracer(sc, camera, res, res, args["max_depth"], args["light_samples"], backend=backend, intersector=args["intersector"])
        times = []
        for k in range(repeats + 1):
            dr.kernel_history()
            tracer.pass_sums(1, k, spp)
            dr.sync_thread()
            times.append(max(h["execution_time"] for h in dr.kernel_history() if "execution_time" in h))
        rows.append(ProfileRow(label, statistics.median(times[1:])))
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
    rows.append(ProfileRow("RNG alone (25 draws per path)", statistics.median(times[1:])))
    return rows


def format_profile(rows: list[ProfileRow], paths: int) -> str:
    full = rows[0].kernel_ms
    lines = [f"| kernel ({paths:,} paths) | ms | share of the full kernel |", "|---|---|---|"]
    for r in rows:
        lines.append(f"| {r.variant} | {r.kernel_ms:.1f} | {100 * r.kernel_ms / full:.0f} % |")
    return "\n".join(lines)


def environment() -> dict:
    import drjit as dr
    import mitsuba as mi

    import mcrt

    from mcrt.provenance import cpu_name

    cpu = cpu_name()
    return {"mcrt": mcrt.__version__, "mitsuba": mi.__version__, "drjit": dr.__version__, "cpu": cpu,
            "threads": dr.thread_count(), "python": platform.python_version(), "date": time.strftime("%Y-%m-%d %H:%M:%S")}


def peak_memory_mib() -> float:
    """Peak resident memory of this process (Linux reports KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def register(sub) -> None:
    p = sub.add_parser("bench", help="paths per second of mcrt and Mitsuba on the same scene, in one run")
    p.add_argument("--scene", default=None)
    p.add_argument("--camera", action="append", help="camera(s) (default: near and far)")
    p.add_argument("--res", type=int, action="append", help="square resolution(s) (default 256)")
    p.add_argument("--spp", type=int, action="append", help="samples per pixel of one render (repeatable; default 16)")
    p.add_argument("--max-depth", type=int, action="append", help="max depth(s) (default 8)")
    p.add_argument("--light-samples", type=int, default=1)
    p.add_argument("--repeats", type=int, default=5, help="timed repetitions per renderer (after one warm-up)")
    p.add_argument("--renderers", default="mcrt,mitsuba")
    p.add_argument("--intersector", choices=("convex", "triangles"), default="convex")
    p.add_argument("--backend", choices=("llvm", "cuda"), default="llvm")
    p.add_argument("--json", default=None, help="also write the measurements to this JSON file")
    p.add_argument("--profile", action="store_true",
                   help="also time mcrt's path kernel with one part left out at a time (where the time goes)")
    p.set_defaults(func=cmd_bench)


def cmd_bench(args) -> int:
    from mcrt.scene import CANONICAL, load_scene

    scene = load_scene(args.scene or CANONICAL)
    spps = args.spp or [16]
    cases = [BenchCase(cam, res, res, spp, depth, args.light_samples)
             for cam in (args.camera or ["near", "far"]) for res in (args.res or [256]) for spp in spps
             for depth in (args.max_depth or [8])]
    rows = run_bench(scene, cases, renderers=args.renderers.split(","), repeats=args.repeats, backend=args.backend,
                     intersector=args.intersector)
    env = environment()
    print(f"mcrt {env['mcrt']}, Mitsuba {env['mitsuba']}, Dr.Jit {env['drjit']}, {env['threads']} threads, {env['cpu']}")
    print(format_table(rows))
    print(f"peak memory of this process: {peak_memory_mib():.0f} MiB")
    profile = []
    if args.profile:
        res, cam = (args.res or [256])[-1], (args.camera or ["near"])[0]
        profile = kernel_profile(scene, camera=cam, res=res, spp=spps[-1], max_depth=(args.max_depth or [8])[-1],
                                 repeats=args.repeats, backend=args.backend)
        print(format_profile(profile, res * res * spps[-1]))
    if args.json:
        out = {"command": " ".join(sys.argv), "environment": env, "backend": args.backend, "intersector": args.intersector,
               "rows": [dict(asdict(r), median_time=statistics.median(r.times)) for r in rows], "peak_memory_mib": peak_memory_mib(),
               "kernel_profile": [asdict(r) for r in profile]}
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(out, indent=2))
        print(f"wrote {args.json}")
    return 0
