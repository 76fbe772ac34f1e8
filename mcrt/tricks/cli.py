"""``mcrt tricks``: the efficiency tricks beside plain mcrt on the canonical scene, written to reports/tricks/."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from mcrt.exitcodes import EXIT_FAILED, EXIT_OK, EXIT_UNUSABLE

DESCRIPTION = """Render plain mcrt and every variant of the lecture's efficiency tricks (Russian roulette, early
stopping, bidirectional where the renderer has it, OIDN denoising, light sampling) at a ladder of spp and
several seeds; measure error against time and spp, bias with the project's comparison against the committed
Mitsuba reference, and write index.md, data.json and figures with one verdict per trick. Exit 1 when a variant
that is unbiased in theory is flagged at the top rung on half its seeds or more and again in one render at
--confirm-spp."""


def _ladder(text: str) -> tuple[int, ...]:
    try:
        values = tuple(int(x) for x in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated integers, got {text!r}") from None
    if not values or min(values) < 2 or list(values) != sorted(set(values)):
        raise argparse.ArgumentTypeError(f"expected increasing spp of at least 2, got {text!r}")
    return values


def _tiles(text: str) -> tuple[int, ...]:
    try:
        values = tuple(int(x) for x in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated integers, got {text!r}") from None
    if not values or min(values) < 1:
        raise argparse.ArgumentTypeError(f"expected positive tile sizes, got {text!r}")
    return values


def register(sub) -> None:
    p = sub.add_parser("tricks", help="the lecture's efficiency tricks measured for speed against error (reports/tricks)",
                       description=DESCRIPTION)
    p.add_argument("--scene", default=None, help="scene file with a committed reference (default: the canonical room shipped with mcrt, canonical.toml)")
    p.add_argument("--camera", default="near", help="camera (default: near)")
    p.add_argument("--res", type=int, default=64, help="square resolution; a committed reference must exist (default: 64)")
    p.add_argument("--max-depth", type=int, default=8, help="longest path in segments (default: 8)")
    p.add_argument("--ladder", type=_ladder, default=(16, 64, 256, 1024, 4096),
                   help="samples per pixel of the rungs, comma-separated (default: 16,64,256,1024,4096)")
    p.add_argument("--seeds", type=int, default=4, help="independent renders per rung, at least 2 (default: 4)")
    p.add_argument("--alpha", type=float, default=0.01, help="family-wise level of the comparison (default: 0.01)")
    p.add_argument("--tiles", type=_tiles, default=(8, 32), help="tile sizes of the comparisons, each at alpha / their number "
                                                "(default: 8,32)")
    p.add_argument("--only", action="append", default=[], metavar="TRICK",
                   choices=("roulette", "adaptive", "bidirectional", "denoise", "light"),
                   help="study only this trick, beside plain mcrt (repeatable; default: every trick)")
    p.add_argument("--light-receiver-samples", type=int, default=1 << 20,
                   help="light samples per receiver and strategy in the near/far study (default: 1048576)")
    p.add_argument("--confirm-spp", type=int, default=65536,
                   help="re-render once at this spp each variant that is unbiased in theory but flagged at the top "
                        "rung (heavy tails or bias?); 0: none (default: 65536)")
    p.add_argument("--backend", choices=("llvm", "cuda"), default="llvm", help="Dr.Jit backend (default: llvm)")
    p.add_argument("--out", default="reports/tricks", help="report folder (default: reports/tricks)")
    p.add_argument("--quiet", action="store_true", help="no progress line (default: progress on stderr)")
    p.set_defaults(func=cmd_tricks)


def _command(args) -> str:
    words = ["mcrt", "tricks"]
    if args.scene:
        words += ["--scene", args.scene]
    words += ["--camera", args.camera, "--res", str(args.res), "--max-depth", str(args.max_depth),
              "--ladder", ",".join(map(str, args.ladder)), "--seeds", str(args.seeds), "--alpha", f"{args.alpha:g}",
              "--tiles", ",".join(map(str, args.tiles))]
    for t in args.only:
        words += ["--only", t]
    words += ["--light-receiver-samples", str(args.light_receiver_samples), "--confirm-spp", str(args.confirm_spp),
              "--out", args.out]
    return " ".join(words)


def cmd_tricks(args) -> int:
    from mcrt.groundtruth import ReferenceUnavailable
    from mcrt.scene import CANONICAL, load_scene
    from mcrt.tricks.light_study import light_receiver_study
    from mcrt.tricks.report import write_report
    from mcrt.tricks.study import StudyConfig, confirm_unbiased, run_study
    from mcrt.tricks.variants import PLAIN, default_variants
    from mcrt.tricks.verdicts import variant_row

    if args.seeds < 2:
        print("mcrt tricks: --seeds must be at least 2 (the variance across seeds needs two)", file=sys.stderr)
        return EXIT_UNUSABLE
    scene = load_scene(args.scene or CANONICAL)
    variants = [v for v in default_variants() if v.trick == "plain" or not args.only or v.trick in args.only]
    cfg = StudyConfig(camera=args.camera, res=args.res, max_depth=args.max_depth, ladder=args.ladder, seeds=args.seeds,
                      alpha=args.alpha, tiles=args.tiles, backend=args.backend)
    log = (lambda *a: None) if args.quiet else (lambda *a: print(*a, file=sys.stderr))
    log(f"mcrt tricks: {len(variants)} variants x {len(cfg.ladder)} rungs x {cfg.seeds} seeds at {cfg.res}x{cfg.res}")
    try:
        data = run_study(scene, variants, cfg, progress=not args.quiet)
    except ReferenceUnavailable as e:
        print(f"mcrt tricks: {' '.join(str(e).split())}", file=sys.stderr)
        return EXIT_UNUSABLE
    if not args.only or "light" in args.only:
        log("mcrt tricks: light sampling at single receivers")
        data.extra["light_receivers"] = light_receiver_study(scene, samples=args.light_receiver_samples)
    wrong = [v.label for v in variants if v.label != PLAIN and v.claim == "unbiased" and variant_row(data, v.label)["biased"]]
    if wrong and args.confirm_spp:
        data.extra["confirm"] = confirm_unbiased(data, wrong, args.confirm_spp, backend=args.backend, log=log)
        wrong = [w for w in wrong if not data.extra["confirm"][w]["passed"]]
    files = write_report(data, Path(args.out), command=_command(args))
    print(f"mcrt tricks: wrote {Path(args.out) / 'index.md'} ({len(files)} files, {data.runtime:.0f} s)")
    if wrong:
        print(f"mcrt tricks: flagged although unbiased in theory: {', '.join(wrong)}", file=sys.stderr)
        return EXIT_FAILED
    return EXIT_OK
