"""``mcrt mitsuba-suite DIR``: run the suite, write reports/mitsuba_suite/ (index.md, data.json)."""

from __future__ import annotations

import json
import shlex
import sys
import time
from pathlib import Path

from mcrt.exitcodes import EXIT_FAILED, EXIT_OK, EXIT_UNUSABLE


def register(sub) -> None:
    p = sub.add_parser("mitsuba-suite",
                       help="mcrt's test on Mitsuba 3's own render-test scenes, beside Mitsuba's z-rule: verdicts, time, "
                            "power on stated perturbations, false alarms; writes a report",
                       description="For every scene of a Mitsuba-style tests/scenes folder with its reference pair: a "
                                   "correct render at Mitsuba's budget (2e6 samples per image) as Mitsuba renders it, "
                                   "mcrt's multi-scale test and Mitsuba's z-rule against the reference, and the stated "
                                   "perturbations (the issue's four, and each multiplicative one at 1/4, 1/16 and 1/64 of "
                                   "its deviation: a ladder fixed in advance, one render each). Writes index.md and "
                                   "data.json. Exit 0 when mcrt has no false alarm and catches at least twice as many "
                                   "perturbations (the whole ladder) as Mitsuba's rule, 1 otherwise, 2 on unusable input.")
    p.add_argument("folder", help="a Mitsuba-style tests/scenes folder, or the folder holding tests/scenes")
    p.add_argument("--out", default="reports/mitsuba_suite", help="report folder (index.md, data.json) (default: %(default)s)")
    p.add_argument("--spp-scale", type=float, default=1.0, help="times Mitsuba's budget of 2e6 samples per image (default: %(default)s)")
    p.add_argument("--seeds", type=int, default=1, help="correct renders per scene (false-alarm trials) (default: %(default)s)")
    p.add_argument("--alpha", type=float, default=0.01,
                   help="family-wise error rate of the whole suite run as one check: each scene is tested at alpha / "
                        "the number of scenes run (Bonferroni; 0.01 / 26 on the shared copy) (default: %(default)s)")
    p.add_argument("--ref-spp", type=int, default=32000,
                   help="the references' spp, which they do not record (default: %(default)s, what Mitsuba's generator renders)")
    p.add_argument("--version-rtol", type=float, default=None,
                   help="relative difference accepted in every channel against a reference another Mitsuba version "
                        "wrote (default: per XYZ channel, the relative offset of the white such versions store, "
                        "rounded up to two significant digits; the report states the values)")
    p.add_argument("--only", action="append", default=[], metavar="GROUP/NAME",
                   help="run this scene only, e.g. bsdf_spheres/test_constant_path (repeatable; default: all)")
    p.add_argument("--held-out", choices=("include", "exclude", "only"), default="include",
                   help="the held-out scenes: run them last, leave them out, or run them alone (default: %(default)s)")
    p.add_argument("--no-perturbations", action="store_true", help="correct renders only (default: off)")
    p.add_argument("--backend", choices=("llvm", "cuda"), default="llvm", help="Dr.Jit backend (default: %(default)s)")
    p.set_defaults(func=cmd_mitsuba_suite)


def _command(args) -> str:
    """The command line that reproduces this run (options at their defaults left out), for the report."""
    words = ["mcrt", "mitsuba-suite", args.folder]
    defaults = {"spp_scale": 1.0, "seeds": 1, "alpha": 0.01, "ref_spp": 32000, "version_rtol": None, "held_out": "include",
                "backend": "llvm", "out": "reports/mitsuba_suite"}
    for key, default in defaults.items():
        value = getattr(args, key)
        if value != default:
            words += [f"--{key.replace('_', '-')}", str(value)]
    for name in args.only:
        words += ["--only", name]
    if args.no_perturbations:
        words.append("--no-perturbations")
    return shlex.join(words)


def cmd_mitsuba_suite(args) -> int:
    from mcrt.msuite.markdown import markdown
    from mcrt.msuite.perturb import PERTURBATIONS
    from mcrt.msuite.run import run_suite
    from mcrt.provenance import provenance

    command = _command(args)
    if args.seeds < 1 or args.spp_scale <= 0 or not 0 < args.alpha < 1:
        print("mcrt mitsuba-suite: --seeds and --spp-scale must be positive, --alpha between 0 and 1", file=sys.stderr)
        return EXIT_UNUSABLE
    tiles = [2, 4, 8, 16, 32, 0]
    options = {"spp_scale": args.spp_scale, "seeds": args.seeds, "alpha": args.alpha, "tiles": tiles,
               "ref_spp": args.ref_spp, "backend": args.backend, "version_rtol": args.version_rtol,
               "perturbations": () if args.no_perturbations else tuple(PERTURBATIONS)}
    t0 = time.perf_counter()
    try:
        data = run_suite(Path(args.folder), only=tuple(args.only), held_out=args.held_out, log=sys.stderr, **options)
    except ValueError as e:
        print(f"mcrt mitsuba-suite: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    data.update(command=command, wall_time=time.perf_counter() - t0,
                options={**options, "perturbations": list(options["perturbations"]), "only": args.only,
                         "held_out": args.held_out},
                provenance=provenance())
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "data.json").write_text(json.dumps(data, indent=1))
    (out / "index.md").write_text(markdown(data))
    s = data["summary"]["all"]
    print(f"{s['scenes']} scenes: false alarms mcrt {s['mcrt_false_alarms']}, Mitsuba's rule {s['mitsuba_false_alarms']}; "
          f"perturbations caught mcrt {s['mcrt_caught']}, Mitsuba's rule {s['mitsuba_caught']} of {s['perturbations']}")
    print(f"wrote {out / 'index.md'} and data.json")
    ok = not data["errors"] and s["mcrt_false_alarms"] == 0 and s["mcrt_caught"] >= 2 * s["mitsuba_caught"]
    return EXIT_OK if ok else EXIT_FAILED
