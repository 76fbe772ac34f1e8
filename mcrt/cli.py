"""The ``mcrt`` command line: a thin layer over the library.

Exit codes: 0 ok (or images consistent), 1 a check failed (images differ),
2 unusable input (a bad scene file, an unreadable image, a bad option).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from mcrt.exitcodes import EXIT_FAILED, EXIT_OK, EXIT_UNUSABLE


def _finite_float(text: str) -> float:
    """A float argument that must be finite (``nan`` and ``inf`` parse as floats, but no option means them)."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text!r}")
    return v


def _add_render_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--scene", default=None, help="scene file (default: the canonical room shipped with mcrt, canonical.toml)")
    p.add_argument("--camera", default=None, help="camera name from the scene file, e.g. near or far (default: the file's)")
    p.add_argument("--res", type=int, default=None, help="square resolution N (N x N) (default: the scene file's)")
    p.add_argument("--width", type=int, default=None, help="image width, overrides --res (default: the scene file's)")
    p.add_argument("--height", type=int, default=None, help="image height, overrides --res (default: the scene file's)")
    p.add_argument("--spp", type=int, default=None, help="samples per pixel (default: the scene file's)")
    p.add_argument("--seed", type=int, default=None, help="random seed; equal seeds give equal images bit for bit (default: the scene file's)")
    p.add_argument("--max-depth", type=int, default=None,
                   help="longest path in segments (1: emitters only, 2: direct light, -1: unbounded; default: the scene file's)")
    p.add_argument("--preset", default=None, help="named settings from the scene file, e.g. course2023 (default: none)")
    p.add_argument("--backend", choices=("llvm", "cuda"), default="llvm", help="Dr.Jit backend: llvm on the CPU, cuda on a GPU (default: llvm)")


def _settings(args, scene):
    w = args.width or args.res
    h = args.height or args.res
    return scene.settings(
        args.preset,
        camera=args.camera,
        width=w,
        height=h,
        spp=args.spp,
        seed=args.seed,
        max_depth=args.max_depth,
        light_samples=getattr(args, "light_samples", None),
    )


def _load(args):
    from mcrt.scene import CANONICAL, load_scene

    return load_scene(args.scene or CANONICAL)


def render_to_files(result, out: Path, exposure: float = 0.0) -> tuple[Path, Path]:
    """Write ``out`` (EXR with mean and variance) and the PNG preview beside it."""
    from mcrt.image_files import write_exr, write_png

    out = Path(out)
    if out.suffix.lower() != ".exr":
        out = out.with_suffix(".exr")
    out.parent.mkdir(parents=True, exist_ok=True)
    write_exr(out, result)
    png = out.with_suffix(".png")
    write_png(png, result.mean, exposure=exposure)
    return out, png


def _render_mitsuba_scene(args) -> int:
    """``mcrt render --mitsuba-scene FILE.xml``: any Mitsuba scene, any integrator, through render_with_variance."""
    from mcrt.mitsuba_scene import render_with_variance
    from mcrt.validate_integrator import load_scene_arg, parse_defines, parse_integrator

    refused = [o for o, v in (("--scene", args.scene), ("--camera", args.camera), ("--preset", args.preset),
                              ("--mutant", args.mutant), ("--light-samples", args.light_samples))
               if v is not None] + (["--renderer"] if args.renderer != "mcrt" else [])
    if refused:
        print(f"mcrt render: {refused[0]} does not apply to --mitsuba-scene (the scene file holds it)", file=sys.stderr)
        return EXIT_UNUSABLE
    try:
        scene = load_scene_arg(args.mitsuba_scene)
        spec = parse_integrator(args.integrator) if args.integrator else None
        result = render_with_variance(scene, integrator=spec, spp=args.spp, seed=args.seed or 0,
                                      width=args.width or args.res, height=args.height or args.res,
                                      max_depth=args.max_depth, backend=args.backend, progress=True,
                                      defaults=parse_defines(args.define), pixel_sampler=args.pixel_sampler,
                                      replicates=args.replicates)
    except (ValueError, RuntimeError) as e:
        msg = " ".join(str(e).split())
        where = "" if msg.startswith(str(args.mitsuba_scene)) else f"{args.mitsuba_scene}: "
        print(f"mcrt render: {where}{msg}", file=sys.stderr)
        return EXIT_UNUSABLE
    exr, png = render_to_files(result, Path(args.output), args.exposure)
    h, w = result.mean.shape[:2]
    print(f"{result.renderer}: {w}x{h}, {result.spp} spp, seed {result.seed}, max depth {result.max_depth}, "
          f"camera {result.camera}, scene hash {result.scene_hash}: {result.wall_time:.2f} s")
    print(f"wrote {exr} and {png}")
    return EXIT_OK


def cmd_render(args) -> int:
    if args.mitsuba_scene is not None:
        return _render_mitsuba_scene(args)
    if args.integrator is not None:
        print("mcrt render: --integrator needs --mitsuba-scene (the canonical scene's renderers: --renderer)", file=sys.stderr)
        return EXIT_UNUSABLE
    scene = _load(args)
    s = _settings(args, scene)
    from mcrt.render import render

    options = {"mutants": tuple(args.mutant)} if args.mutant else {}
    if args.intersector != "convex":
        options["intersector"] = args.intersector
    options.update(_trick_flags(args))
    if getattr(args, "bidirectional", False):
        options["bidirectional"] = True
    if args.light_paths is not None:
        options["light_paths"] = args.light_paths
    if args.pixel_sampler != "independent" or args.replicates is not None:
        options.update(pixel_sampler=args.pixel_sampler, replicates=args.replicates)
    result = render(scene, s, renderer=args.renderer, backend=args.backend, **options)
    exr, png = render_to_files(result, Path(args.output), args.exposure)
    compile_note = f", of which JIT compilation {result.compile_time:.2f} s" if result.compile_time else ""
    paths = s.width * s.height * s.spp
    print(f"{args.renderer}: {s.width}x{s.height}, {s.spp} spp, camera {s.camera}, max depth {s.max_depth}: "
          f"{result.wall_time:.2f} s{compile_note}; {paths / max(result.wall_time, 1e-9) / 1e6:.2f} M paths/s")
    print(f"wrote {exr} and {png}")
    return EXIT_OK


def _light_paths(text: str):
    """--light-paths: a positive number, or 'auto'."""
    if text == "auto":
        return text
    try:
        value = float(text)
    except ValueError:
        value = 0.0
    if not value > 0:
        raise argparse.ArgumentTypeError(f"expected a positive number or 'auto', got {text!r}")
    return value


def _trick_flags(args) -> dict:
    """The efficiency tricks given on the command line (mcrt.options.TRICK_OPTIONS and mcrt.render.RENDER_TRICKS), as renderer options."""
    names = ("roulette", "roulette_survival", "roulette_start", "light_sampling", "adaptive", "denoise")
    return {n: getattr(args, n) for n in names if getattr(args, n, None) not in (None, False)}


def _add_trick_flags(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("efficiency tricks (renderer mcrt; measured by `mcrt tricks`)")
    g.add_argument("--roulette", choices=("unbiased", "course2023"), default=None,
                   help="unbiased: survive with q and divide by it; course2023: absorb with 0.75, survivors times 0.8 "
                        "(biased) (default: unbiased)")
    g.add_argument("--roulette-survival", type=float, default=None, metavar="Q",
                   help="fixed survival probability (default: the scheme's, min(max throughput, 0.95) or 0.25)")
    g.add_argument("--roulette-start", type=int, default=None, metavar="DEPTH",
                   help="first depth roulette runs at (default: the scheme's, the scene's rr_depth or 1)")
    g.add_argument("--light-sampling", choices=("area", "solid_angle", "none"), default=None,
                   help="points on the light uniform in area, or uniform in its solid angle (spherical rectangle), or "
                        "none: no next-event estimation, the light found by bounces alone (unbiased, far noisier) "
                        "(default: area)")
    g.add_argument("--adaptive", choices=("naive", "two-stage"), default=None,
                   help="per-pixel sample counts, spp on average: naive stops a pixel by its own samples (biased), "
                        "two-stage budgets from a pilot and estimates from fresh samples (default: off)")
    g.add_argument("--denoise", choices=("albedo+normal", "color"), default=None,
                   help="Intel Open Image Denoise on the render, guided by first-hit buffers or the colour alone "
                        "(biased; needs pyoidn, the denoise extra) (default: off)")
    g.add_argument("--bidirectional", action="store_true",
                   help="light tracing for the paths eye-diffuse-...-mirror-light (the caustics next-event estimation "
                        "cannot sample), the path tracer for the rest (mcrt.bidir; default: off)")


def cmd_compare(args) -> int:
    from mcrt.compare import compare_files

    return compare_files(args.a, args.b, policy=args.policy, alpha=args.alpha, tile=args.tile, heatmap=args.heatmap,
                         json_path=args.json, assume_variance_from_other=args.assume_variance_from == "other",
                         spp_a=args.spp_a, spp_b=args.spp_b, allow_mismatch=tuple(args.allow_mismatch),
                         variance_a=args.variance_a, variance_b=args.variance_b, variance_kind=args.variance_kind,
                         rtol=args.rtol)


def cmd_scene(args) -> int:
    scene = _load(args)
    print(f"{scene.path}: valid; scene hash {scene.content_hash()}")
    print(f"  {len(scene.room.walls)} walls, {len(scene.objects)} objects ({', '.join(o.name for o in scene.objects)}), "
          f"light {scene.light.size[0]:g} x {scene.light.size[1]:g} at {scene.light.center}, cameras {', '.join(scene.cameras)}")
    print(f"  render defaults: {scene.render}")
    return EXIT_OK


def cmd_mutants(args) -> int:
    from mcrt.mutants import MUTANTS

    for name, text in MUTANTS.items():
        print(f"{name:20s} {text}")
    return EXIT_OK


def cmd_main(args) -> int:
    """The main job: the convergence report of the canonical scene, and mcrt beside Mitsuba."""
    from mcrt.compare import write_heatmap
    from mcrt.image_files import side_by_side
    from mcrt.convergence import main_report
    from mcrt.stats import compare_images

    out = Path(args.out)
    report = main_report(out, command="mcrt main")
    print(f"convergence report: {report.folder / 'index.md'} and index.html")
    scene = _load(args)
    s = scene.settings(camera=args.camera, width=args.res, height=args.res, spp=args.spp, seed=args.seed)
    from mcrt.render import render

    results = {name: render(scene, s, renderer=name, backend=args.backend) for name in ("mcrt", "mitsuba")}
    cmp = compare_images(results["mcrt"], results["mitsuba"], alpha=args.alpha)
    side_by_side(out / f"side_by_side_{s.camera}.png", [results["mcrt"].mean, results["mitsuba"].mean], ["mcrt", "Mitsuba 3 (path)"])
    write_heatmap(cmp, out / f"difference_{s.camera}.png")
    for name, r in results.items():
        print(f"{name}: {s.width}x{s.height}, {s.spp} spp: {r.wall_time:.2f} s, {s.width * s.height * s.spp / r.wall_time / 1e6:.2f} M paths/s")
    print(f"mcrt against Mitsuba: {cmp.summary()}")
    print(f"wrote {out}/")
    return EXIT_OK if cmp.passed else EXIT_FAILED


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="mcrt", description="Monte-Carlo path tracer for the hexagonal room, validated against Mitsuba 3.")
    sub = ap.add_subparsers(dest="command", required=True)

    p = sub.add_parser("render", help="render a scene to EXR (mean + per-sample variance) and a PNG preview")
    _add_render_options(p)
    p.add_argument("--renderer", choices=("mcrt", "plugin", "mitsuba"), default="mcrt",
                   help="mcrt: the standalone tracer; mitsuba: Mitsuba's path integrator; plugin: mcrt's estimator inside Mitsuba (default: mcrt)")
    p.add_argument("--light-samples", type=int, default=None, help="shadow rays per diffuse vertex (mcrt, plugin; default: the scene file's)")
    p.add_argument("--mutant", action="append", metavar="NAME", help="switch on a catalogued bug (mcrt, plugin; repeatable; see `mcrt mutants`; default: none)")
    p.add_argument("--intersector", choices=("convex", "triangles"), default="convex", help="mcrt's intersection code (triangles: brute-force cross-check; default: convex)")
    _add_trick_flags(p)
    p.add_argument("--pixel-sampler", choices=("independent", "sobol"), default="independent",
                   help="where samples land in their pixel (every renderer; not with --adaptive): independent jitter, or Owen-scrambled "
                        "Sobol points in --replicates independent replicates whose spread is the variance "
                        "(mcrt.samplers; default: independent)")
    p.add_argument("--replicates", type=int, default=None, metavar="R",
                   help="replicates of --pixel-sampler sobol; spp must be a multiple (default: 8)")
    p.add_argument("--light-paths", type=_light_paths, default=None, metavar="N|auto",
                   help="with --bidirectional: light subpaths per camera sample, or 'auto' to choose them from a pilot "
                        "render by the caustic paths' share of the variance (mcrt.bidir.choose_light_paths; default: 0.05)")
    p.add_argument("--exposure", type=_finite_float, default=0.0, help="PNG preview exposure in stops (default: 0)")
    p.add_argument("-o", "--output", default="out.exr", help="output EXR; the PNG preview goes beside it (default: out.exr)")
    # Any Mitsuba scene (mcrt.mitsuba_scene.render_with_variance); --res/--width/--height, --spp, --seed, --max-depth apply.
    mitsuba_help = {
        "--mitsuba-scene": ("FILE", "render this Mitsuba XML scene (or cornell-box) with its own or --integrator's "
                                    "integrator, variance from per-sample moments (default: none, the mcrt scene)"),
        "--integrator": ("NAME", "with --mitsuba-scene: the integrator replacing the scene's, a plugin name (keeps the "
                                 "scene's max depth) or NAME:key=value,... (default: the scene's)"),
    }
    for flag, (metavar, text) in mitsuba_help.items():
        p.add_argument(flag, default=None, metavar=metavar, help=text)
    p.add_argument("-D", dest="define", action="append", default=[], metavar="KEY=VALUE",
                   help="with --mitsuba-scene: set a <default> parameter of the XML scene, e.g. -D integrator=direct "
                        "(repeatable; default: the file's values)")
    p.set_defaults(func=cmd_render)

    p = sub.add_parser("compare", help="two-sample test of two renders (exit 0 consistent, 1 different, 2 unusable)")
    p.add_argument("a", help="image A: the render under test (EXR with variance, PFM, HDR, PNG, ...)")
    p.add_argument("b", help="image B: the other render, or the reference with --policy reference-floor")
    p.add_argument("--alpha", type=float, default=0.01, help="family-wise error rate (Holm; default: 0.01)")
    p.add_argument("--tile", type=int, default=8, help="tile size in pixels (default: 8)")
    p.add_argument("--heatmap", default=None, help="write a PNG of the per-tile statistic here (default: none)")
    p.add_argument("--json", default=None, help="write the comparison (every tile's statistic) as JSON here (default: none)")
    # The names of mcrt.stats.policy.POLICIES (not imported here: mcrt.stats loads SciPy; tests/test_stats.py checks them).
    p.add_argument("--policy", choices=("independent", "reference-floor"), default="independent",
                   help="independent: two independent renders, each with its own variance; reference-floor: B is a "
                        "high-spp reference of the same estimator and A's per-sample variance is raised to B's where lower "
                        "(default: independent)")
    p.add_argument("--reference-variance-floor", dest="policy", action="store_const", const="reference-floor",
                   help="the same as --policy reference-floor (default: off)")
    p.add_argument("--assume-variance-from", choices=("other",), default=None,
                   help="an image without per-sample variance borrows the other's, an approximation (default: refuse, exit 2)")
    p.add_argument("--spp-a", type=int, default=None, help="spp of image A, where its file does not record it "
                                                           "(a Mitsuba 'moment' EXR needs it; default: the file's)")
    p.add_argument("--spp-b", type=int, default=None, help="spp of image B, as --spp-a (default: the file's)")
    p.add_argument("--variance-a", default=None, metavar="FILE",
                   help="EXR holding image A's per-sample variance, where A's own file has none (default: A's file)")
    p.add_argument("--variance-b", default=None, metavar="FILE",
                   help="EXR holding image B's per-sample variance, e.g. a Mitsuba reference's <name>_ref_rgb_var.exr "
                        "(default: B's file)")
    p.add_argument("--variance-kind", choices=("auto", "rgb", "mitsuba"), default="auto",
                   help="how --variance-a/-b files are read: rgb, a per-sample RGB variance (negative entries refused); "
                        "mitsuba, Mitsuba's reference variance (an XYZ variance written through the XYZ-to-RGB matrix: "
                        "turned back into XYZ, rounding repaired, bounded in RGB); auto, mitsuba where the file says "
                        "Mitsuba wrote it (default: auto)")
    p.add_argument("--rtol", type=float, default=1e-5,
                   help="relative difference accepted between noiseless tiles (zero variance on both sides), e.g. "
                        "0.002 for a reference storing 1.0 as 1.00108; the verdict says when it accepted one "
                        "(default: 1e-5, exact to float32 rounding)")
    p.add_argument("--allow-mismatch", action="append", default=[], metavar="FIELD",
                   choices=("camera", "scene_hash", "max_depth", "all"),
                   help="compare even though the files record a different camera, scene_hash or max_depth "
                        "(repeatable; all: every one; default: refuse, exit 2)")
    p.set_defaults(func=cmd_compare)

    p = sub.add_parser("main", help="the main job: the convergence report of the canonical scene, and mcrt beside Mitsuba")
    p.add_argument("--scene", default=None, help="scene file of the side-by-side renders (default: the canonical room shipped with mcrt, canonical.toml)")
    p.add_argument("--camera", default="near", help="camera of the side-by-side renders (default: near)")
    p.add_argument("--res", type=int, default=128, help="their square resolution (default: 128)")
    p.add_argument("--spp", type=int, default=256, help="their samples per pixel (default: 256)")
    p.add_argument("--seed", type=int, default=1, help="their seed (default: 1)")
    p.add_argument("--alpha", type=float, default=0.01, help="family-wise error rate of their comparison (default: 0.01)")
    p.add_argument("--backend", choices=("llvm", "cuda"), default="llvm", help="Dr.Jit backend (default: llvm)")
    p.add_argument("--out", default="reports/canonical", help="report folder (default: reports/canonical)")
    p.set_defaults(func=cmd_main)

    p = sub.add_parser("scene", help="validate a scene file and print its hash")
    p.add_argument("scene", nargs="?", default=None, help="scene file (default: the canonical room shipped with mcrt, canonical.toml)")
    p.set_defaults(func=cmd_scene)

    p = sub.add_parser("mutants", help="list the bug catalogue")
    p.set_defaults(func=cmd_mutants)

    from mcrt import bench, convergence, groundtruth, hardcases, rebuild_reports, threeway, validate, validate_integrator
    from mcrt.grade.cli import register as register_grade

    convergence.register(sub)
    groundtruth.register(sub)
    validate.register(sub)
    register_grade(sub)
    hardcases.register(sub)
    bench.register(sub)
    threeway.register(sub)
    rebuild_reports.register(sub)
    validate_integrator.register(sub)
    from mcrt.tricks.cli import register as register_tricks

    register_tricks(sub)
    from mcrt.sampler_study import register as register_samplers

    register_samplers(sub)
    from mcrt.grade.accuracy.cli import register as register_accuracy

    register_accuracy(sub)
    from mcrt.msuite import register as register_msuite

    register_msuite(sub)
    return ap


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    from mcrt.scene import SceneError

    try:
        return args.func(args)
    except SceneError as e:
        print(f"mcrt: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    except (ValueError, RuntimeError, OSError) as e:
        print(f"mcrt: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    except KeyboardInterrupt:
        print("mcrt: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
