"""``mcrt hardcases``: a thin command line over the catalogue, the float32 sweep and the convergence study.

Exit codes (:mod:`mcrt.exitcodes`): 0 every case passes, 1 a case has NaN/Inf
or negative values or the renderers disagree.
"""

from __future__ import annotations

import time
from pathlib import Path

from mcrt.exitcodes import EXIT_FAILED, EXIT_OK
from mcrt.hardcases.cases import run_case
from mcrt.hardcases.catalogue import CATALOGUE, case
from mcrt.hardcases.convergence import CONVERGENCE_CASES, convergence
from mcrt.hardcases.markdown import case_table
from mcrt.hardcases.output import REPORT_DIR, write_report
from mcrt.hardcases.sweep import precision_sweep
from mcrt.util.progress import log

def register(subparsers) -> None:
    """Add ``mcrt hardcases`` to the ``mcrt`` command line."""
    p = subparsers.add_parser(
        "hardcases",
        help="render the hard-case catalogue with mcrt and Mitsuba, compare, write reports/hardcases/ (exit 1 on NaN/Inf, negatives or disagreement)",
        description="Numerical stability on hard cases: a catalogue of variants of the canonical room, each stressing one "
                    "numerical weakness, rendered by mcrt and Mitsuba and compared; optionally where float32 breaks (scenes "
                    "moved and scaled) and how fireflies slow convergence. Writes index.md, data.json and one image per case.",
    )
    p.add_argument("--case", action="append", metavar="NAME", help="run only this case (repeatable; default: all; --list shows them)")
    p.add_argument("--list", action="store_true", help="list the catalogue and exit (default: off)")
    p.add_argument("--spp", type=int, default=512, help="samples per pixel of each renderer at equal spp (default 512)")
    p.add_argument("--ref-spp", type=int, default=4096, help="samples per pixel of the Mitsuba reference (default 4096)")
    p.add_argument("--res", type=int, default=64, help="square resolution (default 64)")
    p.add_argument("--limits", choices=("auto", "yes", "no"), default="auto",
                   help="also measure float32's limits (moved/scaled scenes); auto: only when all cases run (default: auto)")
    p.add_argument("--convergence", choices=("auto", "yes", "no"), default="auto",
                   help=f"also measure convergence on the firefly cases ({', '.join(CONVERGENCE_CASES)}); auto: only when all cases run (default: auto)")
    p.add_argument("--out", default=str(REPORT_DIR), help="report folder (default reports/hardcases)")
    p.set_defaults(func=cmd_hardcases)


def cmd_hardcases(args) -> int:
    """Run the selected cases (and the sweep and convergence study), write the report; exit 1 when a case fails."""
    if args.list:
        for c in CATALOGUE:
            print(f"{c.name:18s} {c.sentence}")
        return EXIT_OK
    cases = [case(n) for n in args.case] if args.case else list(CATALOGUE)
    for name, v in (("--spp", args.spp), ("--ref-spp", args.ref_spp), ("--res", args.res)):
        if v < 2:
            raise ValueError(f"{name} must be at least 2, got {v}")

    out = Path(args.out)
    t0 = time.perf_counter()
    results = []
    for hc in cases:
        log(f"{hc.name}: {hc.sentence}")
        r = run_case(hc, res=args.res, spp=args.spp, ref_spp=args.ref_spp, images=out, log=log)
        results.append(r)
        log(f"  {hc.name}: {'pass' if r.passed else 'FAIL: ' + '; '.join(r.problems)} ({r.seconds:.0f} s)")
    sweep = None
    if args.limits == "yes" or (args.limits == "auto" and not args.case):
        log("float32 limits: moved and scaled scenes")
        sweep = precision_sweep(log=log)
    conv = None
    if args.convergence == "yes" or (args.convergence == "auto" and not args.case):
        log("fireflies and convergence")
        conv = [row for name in CONVERGENCE_CASES for row in convergence(case(name), log=log)]
    try:
        shown_out = out.resolve().relative_to(Path.cwd())
    except ValueError:
        shown_out = out
    argv = [f"--res {args.res}", f"--spp {args.spp}", f"--ref-spp {args.ref_spp}", f"--limits {args.limits}",
            f"--convergence {args.convergence}", f"--out {shown_out}",
            *(f"--case {n}" for n in args.case or ())]
    md, js = write_report(results, out, argv=argv, settings={"res": args.res, "spp": args.spp, "ref_spp": args.ref_spp},
                          sweep=sweep, conv=conv)
    print("\n".join(case_table(results)))
    failed = [r for r in results if not r.passed]
    print(f"{len(results) - len(failed)} of {len(results)} cases pass ({time.perf_counter() - t0:.0f} s); wrote {md} and {js}")
    for r in failed:
        print(f"FAIL {r.name}: {'; '.join(r.problems)}" + (" (known issue)" if r.known_issue else ""))
    return EXIT_FAILED if failed else EXIT_OK
