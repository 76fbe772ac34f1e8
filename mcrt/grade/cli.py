"""``mcrt grade``: the command line of the grading harness.

    mcrt grade SUBMISSIONS --assignment assignment.toml --out DIR [--jobs N] [--timeout S]
               [--mode image|code] [--cache DIR] [--single [--student ID]] [--prepare]

Exit codes (those of every mcrt command, mcrt.exitcodes): 0 every student
was graded (whatever their scores), 1 some students could not be graded
(their results.json says why, with score 0), 2 unusable input (a bad
assignment file, no SUBMISSIONS, a bad option).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from mcrt.exitcodes import EXIT_FAILED, EXIT_OK, EXIT_UNUSABLE


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("submissions", nargs="?", help="one student's file, a folder of students (a file or sub-folder each), "
                   "or with --single one student's folder")
    p.add_argument("--assignment", "-a", required=True, help="assignment file (see reference/assignments/course2023.toml)")
    p.add_argument("--out", "-o", default=None, help="output folder: DIR/<student>/results.json, feedback.html, DIR/grades.csv, "
                   "DIR/summary.md (required unless --prepare)")
    p.add_argument("--mode", choices=("image", "code"), default="image", help="grade images (default) or Python modules")
    p.add_argument("--jobs", "-j", type=int, default=1, help="students graded in parallel (worker processes; 0: in this "
                   "process, without timeouts)")
    p.add_argument("--timeout", type=float, default=None, help="seconds per student (default: the assignment's grading.timeout; "
                   "in code mode, per check: code.timeout)")
    p.add_argument("--memory", type=int, default=None, help="memory limit per worker or student process in MiB")
    p.add_argument("--cache", default=None, help="folder for the cached expected images (default: $MCRT_CACHE/grade or "
                   "~/.cache/mcrt/grade)")
    p.add_argument("--single", action="store_true", help="SUBMISSIONS is one student's folder (Gradescope's /autograder/submission)")
    p.add_argument("--student", default=None, help="student id with --single (default: the folder's name)")
    p.add_argument("--prepare", action="store_true", help="only render and cache the references and the bug catalogue, then "
                   "exit (for an autograder image's setup)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress lines")


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``grade`` sub-command to an ``argparse`` sub-parsers object."""
    p = subparsers.add_parser("grade", help="grade students' renders (or Python code) against the reference, Gradescope-ready",
                              description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_arguments(p)
    p.set_defaults(func=run)
    return p


def run(args) -> int:
    from mcrt.grade.assignment import AssignmentError, load_assignment

    log = (lambda s: None) if args.quiet else (lambda s: print(s, file=sys.stderr, flush=True))
    try:
        a = load_assignment(args.assignment)
    except AssignmentError as e:
        print(f"mcrt grade: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    if args.jobs < 0:
        print("mcrt grade: --jobs must be 0 or more", file=sys.stderr)
        return EXIT_UNUSABLE
    if args.timeout is not None and args.timeout <= 0:
        print("mcrt grade: --timeout must be positive", file=sys.stderr)
        return EXIT_UNUSABLE
    if args.prepare:
        return _prepare(a, args, log)
    if not args.submissions or not args.out:
        print("mcrt grade: give SUBMISSIONS and --out DIR (or --prepare)", file=sys.stderr)
        return EXIT_UNUSABLE
    if not Path(args.submissions).exists():
        print(f"mcrt grade: {args.submissions}: no such file or folder", file=sys.stderr)
        return EXIT_UNUSABLE
    try:
        if args.mode == "code":
            from mcrt.grade.codemode import grade_code_class

            if a.code is None:
                print(f"mcrt grade: {a.path}: no [code] table, so --mode code has nothing to check", file=sys.stderr)
                return EXIT_UNUSABLE
            res = grade_code_class(args.submissions, a, args.out, jobs=max(args.jobs, 1), timeout=args.timeout,
                                   memory_mb=args.memory, cache_dir=args.cache, single=args.single, student=args.student, log=log)
        else:
            from mcrt.grade.batch import DEFAULT_MEMORY_MB, grade_class

            res = grade_class(args.submissions, a, args.out, jobs=args.jobs, timeout=args.timeout, cache_dir=args.cache,
                              single=args.single, student=args.student, memory_mb=args.memory or DEFAULT_MEMORY_MB, log=log)
    except (OSError, RuntimeError, ValueError) as e:
        print(f"mcrt grade: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    s = res.summary
    if not args.quiet:
        mean = f"{s['mean']:.1f}" if s.get("mean") is not None else "-"
        print(f"graded {s['graded']} of {s['students']} students in {res.elapsed:.1f} s; mean {mean} of {s['max_score']:g}; "
              f"wrote {Path(args.out) / 'grades.csv'} and {Path(args.out) / 'summary.md'}")
    return EXIT_OK if res.all_graded else EXIT_FAILED


def _prepare(a, args, log) -> int:
    from mcrt.grade.expected import prepare_context

    try:
        ctx = prepare_context(a, args.cache, log=log)
    except (OSError, RuntimeError, ValueError) as e:
        print(f"mcrt grade: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    from mcrt.grade.diagnose import catalogue_power

    print(f"prepared {a.name}: reference {ctx.references[a.camera].source}; {len(ctx.mutants)} bugs; {ctx.prepare_time:.1f} s")
    power = catalogue_power(ctx)
    seen = [p["mutant"] for p in power if p["detectable"]]
    unseen = [f"{p['mutant']} ({'needs ' + str(p['spp_needed']) + ' spp' if p['spp_needed'] else p['limit']})"
              for p in power if not p["detectable"]]
    print(f"at {a.spp} spp the bias test sees: {', '.join(seen) or 'none'}")
    if unseen:
        print(f"below the noise at {a.spp} spp: {', '.join(unseen)}")
    return EXIT_OK


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="mcrt")
    register(ap.add_subparsers(dest="command", required=True))
    return ap


def main(argv=None) -> int:
    """Run ``mcrt grade ...`` (argv without the program name, e.g. ``['grade', 'subs', '-a', 'x.toml', '-o', 'out']``)."""
    args = build_parser().parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
