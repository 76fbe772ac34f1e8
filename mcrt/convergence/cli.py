"""``mcrt report``: a thin command line over :func:`mcrt.convergence.build.run_report`.

Exit codes (those of every mcrt command, :mod:`mcrt.exitcodes`): 0 report
written, 2 unusable input (bad option, scene or missing reference with
``--reference committed``).
"""

from __future__ import annotations

import argparse
import shlex
import sys
import time
from dataclasses import replace
from pathlib import Path

from mcrt.exitcodes import EXIT_OK, EXIT_UNUSABLE
from mcrt.convergence.config import PRESET_HELP, PRESETS, parse_ladder, preset_config


def _positive(text: str) -> int:
    v = int(text)
    if v < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {v}")
    return v


def _depth(text: str) -> int:
    v = int(text)
    if v < 1 and v != -1:
        raise argparse.ArgumentTypeError(f"max depth must be -1 (unbounded) or >= 1, got {v}")
    return v


def _ladder(text: str) -> tuple[int, ...]:
    try:
        return parse_ladder(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--preset", default="canonical", choices=sorted(PRESETS),
                   help="named settings to start from (default canonical): " + "; ".join(f"{k}: {v}" for k, v in PRESET_HELP.items()))
    p.add_argument("--scene", default=None, help="scene file (default: the canonical room shipped with mcrt, canonical.toml)")
    p.add_argument("--camera", default=None, help="camera name from the scene file, near or far (default: the preset's; canonical: near)")
    p.add_argument("--res", type=_positive, default=None, help="square resolution N (N x N) (default: the preset's; canonical: 64)")
    p.add_argument("--spp-ladder", type=_ladder, default=None, metavar="LIST",
                   help="samples per pixel of each rung: 1,2,4,8 or 1..1024 (powers of two) or a mix (1..16,100) "
                        "(default: the preset's; canonical: 1..1024)")
    p.add_argument("--seeds", type=_positive, default=None, metavar="N", help="renders per (renderer, spp): seeds 1..N (default: the preset's; canonical: 3)")
    p.add_argument("--first-seed", type=int, default=None, metavar="S", help="first seed (seeds S..S+N-1; default 1)")
    p.add_argument("--renderers", default=None, metavar="LIST",
                   help="comma-separated: mcrt, mitsuba, plugin, each optionally with :kN shadow rays (mcrt:k30) "
                        "(default: the preset's; canonical: mcrt,mitsuba,plugin)")
    p.add_argument("--max-depth", type=_depth, default=None, help="longest path in segments (-1: unbounded; default: the preset's; canonical: 8)")
    p.add_argument("--light-samples", type=_positive, default=None, help="shadow rays per diffuse vertex (mcrt, plugin) unless :kN (default: the preset's; canonical: 1)")
    p.add_argument("--equal-time", action=argparse.BooleanOptionalAction, default=None,
                   help="the first renderer renders the ladder, the others the spp that takes them the same time "
                        "(default: the preset's; canonical: off, course2023: on)")
    p.add_argument("--baseline", default=None, help="renderer that efficiency ratios divide by (default: mitsuba, else the last)")
    p.add_argument("--reference", choices=("auto", "committed", "render"), default=None,
                   help="auto: the committed Mitsuba reference if there is one, else a cached render; committed: only that; render: always render "
                        "(default: the preset's; canonical: auto)")
    p.add_argument("--reference-renderer", default=None, help="renderer of a rendered reference (default mitsuba)")
    p.add_argument("--reference-spp", type=_positive, default=None, help="spp of a rendered reference (default 8 x the largest rung)")
    p.add_argument("--strip-spp", type=_ladder, default=None, metavar="LIST", help="rungs shown in the image strip (default: first, middle, last)")
    p.add_argument("--cache-dir", default=None, help="where rendered references are cached (default $XDG_CACHE_HOME/mcrt/report-references)")
    p.add_argument("--no-svg", action="store_true", help="write plots as PNG only (default: off, SVG and PNG)")
    p.add_argument("--backend", choices=("llvm", "cuda"), default=None,
                   help="Dr.Jit backend: llvm on the CPU, cuda on a GPU (default: the preset's; every preset: llvm)")
    p.add_argument("--name", default=None, help="report name (default: the preset's); the folder is reports/<name> unless --out")
    p.add_argument("--out", default=None, help="output folder (default reports/<name>)")
    p.add_argument("--quiet", action="store_true", help="no progress output (default: off)")


def config_from_args(args):
    """The ReportConfig that the options describe: the preset, then every option given."""
    from mcrt.scene import CANONICAL, load_scene

    scene = load_scene(args.scene or CANONICAL)
    cfg = preset_config(args.preset, scene)
    over = {}
    if args.scene:
        over["scene"] = args.scene
    if args.camera:
        over["camera"] = args.camera
    if args.res:
        over["width"] = over["height"] = args.res
    if args.spp_ladder:
        over["spp_ladder"] = args.spp_ladder
    if args.seeds or args.first_seed is not None:
        n = args.seeds or len(cfg.seeds)
        first = args.first_seed if args.first_seed is not None else (cfg.seeds[0] if cfg.seeds else 1)
        over["seeds"] = tuple(range(first, first + n))
    if args.renderers:
        over["renderers"] = tuple(r.strip() for r in args.renderers.split(",") if r.strip())
        if args.baseline is None and cfg.baseline and cfg.baseline not in over["renderers"]:
            over["baseline"] = None
    for opt, field in (("max_depth", "max_depth"), ("light_samples", "light_samples"), ("equal_time", "equal_time"),
                       ("baseline", "baseline"), ("reference", "reference"), ("reference_renderer", "reference_renderer"),
                       ("reference_spp", "reference_spp"), ("strip_spp", "strip_spp"), ("cache_dir", "cache_dir"),
                       ("backend", "backend"), ("name", "name")):
        v = getattr(args, opt)
        if v is not None:
            over[field] = v
    if args.no_svg:
        over["svg"] = False
    if "spp_ladder" in over and "strip_spp" not in over and cfg.strip_spp and not set(cfg.strip_spp) <= set(over["spp_ladder"]):
        over["strip_spp"] = None
    # The preset's sentence describes the preset's settings: once an option changes them, say so instead.
    derived = {k for k in ("strip_spp", "baseline") if getattr(args, k) is None}  # follow from other options
    changed = sorted({_OPTION_OF[k] for k, v in over.items() if k in _OPTION_OF and k not in derived and v != getattr(cfg, k)})
    if changed and cfg.preset:
        over["description"] = f"The {cfg.preset} preset with {', '.join(changed)} given on the command line (settings below)."
    return replace(cfg, **over).check()


#: ReportConfig fields that change a report's settings, and the option that sets each.
_OPTION_OF = {"scene": "--scene", "camera": "--camera", "width": "--res", "height": "--res", "spp_ladder": "--spp-ladder",
              "seeds": "--seeds", "renderers": "--renderers", "max_depth": "--max-depth", "light_samples": "--light-samples",
              "equal_time": "--equal-time", "baseline": "--baseline", "reference": "--reference",
              "reference_renderer": "--reference-renderer", "reference_spp": "--reference-spp", "strip_spp": "--strip-spp"}


def cmd_report(args) -> int:
    from mcrt.convergence.build import run_report
    from mcrt.scene import SceneError

    try:
        cfg = config_from_args(args)
    except (SceneError, ValueError) as e:
        print(f"mcrt report: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    out = Path(args.out) if args.out else Path("reports") / cfg.name
    # The same subcommand whether it came through `mcrt` or `python -m mcrt.convergence.cli`.
    command = "mcrt " + " ".join(shlex.quote(a) for a in sys.argv[1:])
    t0 = time.perf_counter()
    try:
        result = run_report(cfg, out, progress=not args.quiet, command=command)
    except (RuntimeError, ValueError) as e:
        print(f"mcrt report: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    print_summary(result, time.perf_counter() - t0)
    return EXIT_OK


def print_summary(result, elapsed: float) -> None:
    for line in result.summary.verdicts:
        print(line)
    print(f"wrote {result.folder}/ (index.html, index.md, data.json, ...) in {elapsed:.0f} s")


def register(subparsers) -> None:
    """Add ``report`` to an argparse subparsers object."""
    p = subparsers.add_parser(
        "report",
        help="convergence report: error against spp and time for every renderer, into reports/<name>/",
        description=("Render a scene with each renderer at a ladder of spp and several seeds, compare every render with the "
                     "ground truth (RMSE, relMSE, SSIM, FLIP), fit log-log slopes, measure efficiency 1/(MSE x time), and write "
                     "plots, image strips, tables, data.json, index.md and a self-contained index.html. "
                     "Options left out take the preset's value (see --preset)."),
    )
    add_arguments(p)
    p.set_defaults(func=cmd_report)


def main(argv=None) -> int:
    """``python -m mcrt.convergence.cli ...``: the report command alone."""
    ap = argparse.ArgumentParser(prog="mcrt")
    register(ap.add_subparsers(dest="command", required=True))
    args = ap.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
