"""``mcrt reference build | verify | list``: a thin command line over the package.

Exit codes (:mod:`mcrt.exitcodes`): 0 ok, 1 a reference failed its check,
2 unusable input (a bad option, an unknown camera, no manifest).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from mcrt.exitcodes import EXIT_FAILED, EXIT_OK, EXIT_UNUSABLE
from mcrt.groundtruth.build import build_reference
from mcrt.groundtruth.errors import ReferenceUnavailable
from mcrt.groundtruth.spec import (CHUNK_DIR_NAME, DEFAULT_BASE_SEED, DEFAULT_SPP, DEFAULT_WORKERS, MANIFEST_NAME, REFERENCE_DIR,
                                 STANDARD, VERIFY_BASE_SEED, VERIFY_MIN_SPP, VERIFY_PATHS, display_path, reference_key,
                                 resolve_scene, size_of, standard_spp)
from mcrt.groundtruth.text import format_table, format_verify
from mcrt.groundtruth.verify import list_references, verify_references
from mcrt.scene import Scene


def _parse_depth(text: str) -> int:
    v = int(text)
    if v < 1 and v != -1:
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
    b.add_argument("--scene", default=None, help="scene file (default: the canonical room shipped with mcrt, canonical.toml)")
    b.add_argument("--camera", nargs="+", default=None, help="camera name(s) from the scene file (default: near)")
    b.add_argument("--res", nargs="+", type=int, default=None, help="square resolution(s) N (N x N) (default: 64)")
    b.add_argument("--width", type=int, default=None, help="width, for a non-square reference (with --height) (default: none, square sizes from --res)")
    b.add_argument("--height", type=int, default=None, help="height, for a non-square reference (with --width) (default: none, square sizes from --res)")
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
                   help="Dask scheduler address (tcp://host:8786): render the chunks on that cluster "
                        "(default: none, local worker processes)")
    b.add_argument("--standard", action="store_true",
                   help="build every committed reference (canonical scene) with its committed spp; other selections are ignored "
                        "(default: off)")
    b.add_argument("--backend", choices=("llvm", "cuda"), default="llvm", help="Mitsuba variant: llvm_ad_rgb or cuda_ad_rgb (default: %(default)s)")
    b.add_argument("--dir", default=str(REFERENCE_DIR), help="reference folder (default: reference/)")
    b.add_argument("--quiet", action="store_true", help="no progress output (default: off)")
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
    v.add_argument("--checksums-only", action="store_true", help="only check files, checksums and scene hashes, no rendering (default: off)")
    v.add_argument("--backend", choices=("llvm", "cuda"), default="llvm", help="Mitsuba variant of the fresh renders (default: %(default)s)")
    v.add_argument("--dir", default=str(REFERENCE_DIR), help="reference folder (default: reference/)")
    v.add_argument("--quiet", action="store_true", help="no progress output (default: off)")
    v.set_defaults(func=cmd_verify)

    ls = sub.add_parser("list", help="table of the references in the manifest, with their status",
                        description="Summary table of reference/manifest.json: size, spp, noise, versions and status "
                                    "(ok, missing, checksum, stale, no scene). Renders nothing.")
    ls.add_argument("--dir", default=str(REFERENCE_DIR), help="reference folder (default: reference/)")
    ls.add_argument("--json", action="store_true", help="print the rows as JSON instead of a table (default: off, a table)")
    ls.set_defaults(func=cmd_list)


def _build_jobs(args) -> list[tuple[Scene, str, tuple[int, int], int, int]]:
    """(scene, camera, (w, h), max depth, spp) for every reference a build command asks for."""
    scene = resolve_scene(args.scene)
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
                jobs.append((scene, cam, size_of(size), d, args.spp or standard_spp(cam, size_of(size), d)))
    return jobs


def cmd_build(args) -> int:
    from mcrt.scene import SceneError

    try:
        jobs = _build_jobs(args)
    except (SceneError, ValueError) as e:
        print(f"mcrt reference build: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    for i, (scene, cam, size, depth, spp) in enumerate(jobs):
        if len(jobs) > 1 and not args.quiet:
            print(f"mcrt reference build: {i + 1} of {len(jobs)}: {reference_key(scene.name, cam, size, depth)}", file=sys.stderr,
                  flush=True)
        try:
            build_reference(scene, cam, size, depth, spp, chunk_spp=args.chunk_spp, base_seed=args.seed, workers=args.workers,
                            threads=args.threads, scheduler=args.scheduler, directory=args.dir, backend=args.backend,
                            progress=not args.quiet)
        except KeyboardInterrupt:
            key = reference_key(scene.name, cam, size, depth)
            folder = display_path(Path(args.dir) / CHUNK_DIR_NAME / key)
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
        print(f"mcrt reference verify: no references in {display_path(Path(args.dir) / MANIFEST_NAME)}", file=sys.stderr)
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
        print(f"no references in {display_path(Path(args.dir) / MANIFEST_NAME)}")
    else:
        print(format_table(rows))
    return EXIT_OK if all(r["status"] == "ok" for r in rows) else EXIT_FAILED
