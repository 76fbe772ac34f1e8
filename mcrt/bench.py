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

This module measures; :mod:`mcrt.bench_report` writes the report
(``mcrt bench --report DIR``) from the measurements' dictionary
(:func:`bench_data`, also the JSON file).
"""

from __future__ import annotations

import contextlib
import json
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


def peak_memory_mib() -> float:
    """Peak resident memory of this process (Linux reports KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def bench_cases(cameras, resolutions, spps, depths, light_samples: int = 1, spp_sweep=()) -> list[BenchCase]:
    """Every (camera, resolution, spp, depth), then each camera's ``spp_sweep`` at the last resolution and depth.

    A sweep case that is already among the others is not timed twice.
    """
    cases = [BenchCase(cam, res, res, spp, depth, light_samples)
             for cam in cameras for res in resolutions for spp in spps for depth in depths]
    for cam in cameras:
        for spp in spp_sweep:
            case = BenchCase(cam, resolutions[-1], resolutions[-1], spp, depths[-1], light_samples)
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
               profile: list[ProfileRow] = (), profile_case: dict | None = None) -> dict:
    """The run as one JSON-ready dictionary: what ``--json`` writes and :mod:`mcrt.bench_report` reads.

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
            "kernel_profile": [asdict(r) for r in profile], "kernel_profile_case": profile_case}


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
    p.add_argument("--scene", default=None, help="scene file (default: reference/scenes/canonical.toml)")
    p.add_argument("--camera", action="append", help="camera(s), repeatable (default: near and far)")
    p.add_argument("--res", type=int, action="append", help="square resolution(s), repeatable (default 256)")
    p.add_argument("--spp", type=int, action="append", help="samples per pixel of one render, repeatable (default 16)")
    p.add_argument("--max-depth", type=int, action="append", help="max depth(s), repeatable (default 8)")
    p.add_argument("--spp-sweep", type=int, action="append", default=None, metavar="SPP",
                   help="also time these samples per pixel, repeatable, at the last --res and --max-depth of each camera "
                        "(the report's section against samples per render; default: none)")
    p.add_argument("--light-samples", type=int, default=1, help="K, shadow rays per diffuse vertex (default 1)")
    p.add_argument("--repeats", type=int, default=5,
                   help="timed repetitions per renderer and case, after one warm-up render (default 5)")
    p.add_argument("--renderers", default="mcrt,mitsuba", help="comma-separated renderers (default: mcrt,mitsuba)")
    p.add_argument("--intersector", choices=("convex", "triangles"), default="convex", help="mcrt's intersector (default: convex)")
    p.add_argument("--backend", choices=("llvm", "cuda"), default="llvm", help="Dr.Jit backend (default: llvm)")
    p.add_argument("--json", default=None, metavar="FILE",
                   help="also write the measurements to this JSON file (default: none; DIR/bench.json with --report)")
    p.add_argument("--profile", action="store_true",
                   help="also time mcrt's path kernel with one part left out at a time, at the first camera and the last "
                        "--res, --spp and --max-depth (where the time goes; default: off)")
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
    from mcrt.bench_report import format_profile, format_table, write_report
    from mcrt.scene import CANONICAL, load_scene

    if args.repeats < 1:
        raise ValueError(f"--repeats must be at least 1, got {args.repeats}")
    tried = _tried_file(args)
    scene = load_scene(args.scene or CANONICAL)
    cameras, resolutions, depths = args.camera or ["near", "far"], args.res or [256], args.max_depth or [8]
    spps = args.spp or [16]
    cases = bench_cases(cameras, resolutions, spps, depths, args.light_samples, args.spp_sweep or ())
    rows = run_bench(scene, cases, renderers=args.renderers.split(","), repeats=args.repeats, backend=args.backend,
                     intersector=args.intersector)
    profile, profile_case = [], None
    if args.profile:
        profile_case = {"camera": cameras[0], "width": resolutions[-1], "height": resolutions[-1], "spp": spps[-1],
                        "max_depth": depths[-1], "repeats": args.repeats}
        profile = kernel_profile(scene, camera=cameras[0], res=resolutions[-1], spp=spps[-1], max_depth=depths[-1],
                                 repeats=args.repeats, backend=args.backend)
    data = bench_data(rows, command=command_line(args.bench_parser, args), backend=args.backend,
                      intersector=args.intersector, repeats=args.repeats, profile=profile, profile_case=profile_case)
    prov, v = data["provenance"], data["provenance"]["versions"]
    print(f"mcrt {v['mcrt']}, Mitsuba {v['mitsuba']}, Dr.Jit {v['drjit']}, {prov['drjit_threads']} threads, "
          f"{prov['machine']['cpu']}")
    print(format_table(data["rows"]))
    print(f"peak memory of this process: {data['peak_memory_mib']:.0f} MiB")
    if profile:
        print(format_profile(data["kernel_profile"], resolutions[-1] ** 2 * spps[-1]))
    json_path = Path(args.json) if args.json else Path(args.report) / "bench.json" if args.report else None
    if json_path is not None:
        json_path.parent.mkdir(parents=True, exist_ok=True)
        json_path.write_text(json.dumps(data, indent=2))
        print(f"wrote {json_path}")
    if args.report:
        index = write_report(Path(args.report), data, json_path=json_path, tried=tried)
        print(f"wrote {index}")
    return 0
