"""``mcrt grade`` and ``mcrt check``: the command line of the grading harness.

    mcrt grade SUBMISSIONS --assignment assignment.toml --out DIR [--jobs N] [--timeout S]
               [--mode image|code] [--cache DIR] [--single [--student ID]] [--prepare] [--fresh]
    mcrt check RENDER [--assignment NAME_OR_FILE] [--out DIR] [--cache DIR]

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
from mcrt.grade.assignment import resolve_assignment  # noqa: F401  (mcrt check's name lookup; tests import it here)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("submissions", nargs="?", help="one student's file, a folder of students (a file or sub-folder each), "
                   "or with --single one student's folder")
    p.add_argument("--assignment", "-a", required=True, help="assignment: a name of the package's assignments (course2023: 64 x 64 renders; course2023_800; "
                   "course2023_code: code mode) or an assignment file (required, no default)")
    p.add_argument("--out", "-o", default=None, help="output folder: DIR/<student>/results.json, feedback.html, DIR/grades.csv, "
                   "DIR/summary.md (default: none; required unless --prepare)")
    p.add_argument("--mode", choices=("image", "code"), default="image", help="grade images or Python modules (default: image)")
    p.add_argument("--jobs", "-j", type=int, default=1, help="students graded in parallel (worker processes; 0: in this "
                   "process, without timeouts; default: 1)")
    p.add_argument("--timeout", type=float, default=None, help="seconds per student (default: the assignment's grading.timeout; "
                   "in code mode, per check: code.timeout)")
    p.add_argument("--memory", type=int, default=None, help="memory limit per worker or student process in MiB (default: 4096 in image mode; in code "
                   "mode the assignment's code.memory_mb, else 384)")
    p.add_argument("--cache", default=None, help="folder for the cached expected images (default: $MCRT_CACHE/grade or "
                   "~/.cache/mcrt/grade)")
    p.add_argument("--single", action="store_true", help="SUBMISSIONS is one student's folder (Gradescope's /autograder/submission) "
                   "(default: off)")
    p.add_argument("--student", default=None, help="student id with --single (default: the folder's name)")
    p.add_argument("--prepare", action="store_true", help="only render and cache the references and the bug catalogue, then "
                   "exit, for an autograder image's setup (default: off)")
    p.add_argument("--allow-unisolated-code", action="store_true", help="in code mode, run student code even where "
                   "neither bubblewrap nor Landlock and seccomp can isolate it (still as an unprivileged user, with "
                   "resource limits; default: off, code mode is then refused)")
    p.add_argument("--fresh", action="store_true", help="grade every student again; by default a run into "
                   "an --out folder that holds an earlier or killed run of the same assignment keeps the results of "
                   "unchanged submissions (DIR/run.json) and grades only the missing, changed or not graded ones (default: off)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress lines (default: off)")


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``grade`` and ``check`` sub-commands to an ``argparse`` sub-parsers object; returns ``grade``'s parser."""
    p = subparsers.add_parser("grade", help="grade students' renders (or Python code) against the reference, Gradescope-ready",
                              description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_arguments(p)
    p.set_defaults(func=run)
    c = subparsers.add_parser("check", help="a student's own check: the course assignment's feedback on one render",
                              description=CHECK_DOC, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_check_arguments(c)
    c.set_defaults(func=run_check)
    from mcrt.grade.false_alarms import register as register_false_alarms

    register_false_alarms(subparsers)
    from mcrt.grade.gradescope import register as register_gradescope_zip

    register_gradescope_zip(subparsers)
    return p


# --------------------------------------------------------------------------
# mcrt check: one student, one file, the course's feedback
# --------------------------------------------------------------------------

#: The assignment ``mcrt check`` uses by default: the course's 800 x 800 hand-ins.
DEFAULT_CHECK_ASSIGNMENT = "course2023_800"

CHECK_DOC = """Grade your own render the way the course grades it, and print the feedback.

    mcrt check my_render.ppm
    mcrt check my_render.exr --assignment course2023 --out feedback/

RENDER is read at its own resolution (for the default assignment 800 x 800,
box-filtered to 100 x 100 for the comparison): OpenEXR, PFM, Radiance HDR,
PNG (8 or 16 bit), PPM (P3 or P6, 8 or 16 bit), BMP or TGA; 8- and 16-bit
files are taken as sRGB-encoded unless a manifest beside the file
(RENDER's stem + .toml, e.g. my_render.toml) says `linear = true`. The
manifest may also declare `spp = N`. JPEG is refused (lossy). The first
run renders and caches the references and the bug catalogue (a few
minutes); later checks take seconds.

Exit codes: 0 full marks, 1 fewer than full marks (the feedback says why,
also for a file that cannot be read), 2 unusable input (no such file, a bad
assignment, a bad option).
"""


def add_check_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("render", help="your render: one image file (a manifest RENDER-stem.toml beside it is read too)")
    p.add_argument("--assignment", "-a", default=DEFAULT_CHECK_ASSIGNMENT,
                   help="assignment: a name from the package's assignments (course2023_800: 800 x 800 hand-ins; "
                   "course2023: 64 x 64) or an assignment file (default: %(default)s)")
    p.add_argument("--out", "-o", default=None, help="also write results.json and feedback.html (heat maps, diagnosis) "
                   "to OUT/<name>/ (default: none, only the text on stdout)")
    p.add_argument("--cache", default=None, help="folder for the cached references and bug catalogue (default: "
                   "$MCRT_CACHE/grade or ~/.cache/mcrt/grade)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress lines on stderr (default: off)")


def run_check(args) -> int:
    from mcrt.grade.assignment import AssignmentError, load_assignment
    from mcrt.grade.submissions import discover, shown

    log = (lambda s: None) if args.quiet else (lambda s: print(s, file=sys.stderr, flush=True))
    try:
        a = load_assignment(args.assignment)
    except AssignmentError as e:
        print(f"mcrt check: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    render = Path(args.render)
    if not render.exists() and not render.is_symlink():
        print(f"mcrt check: {shown(args.render)}: no such file", file=sys.stderr)
        return EXIT_UNUSABLE
    if render.is_dir():
        print(f"mcrt check: {shown(args.render)}: is a folder; give one image file (mcrt grade --single grades a folder)",
              file=sys.stderr)
        return EXIT_UNUSABLE
    from mcrt.grade.expected import prepare_context
    from mcrt.grade.grader import grade_submission

    try:
        ctx = prepare_context(a, args.cache, log=log)
        sub = discover(render)[0]
        res = grade_submission(sub, ctx)
    except (OSError, RuntimeError, ValueError) as e:
        print(f"mcrt check: {shown(str(e))}", file=sys.stderr)
        return EXIT_UNUSABLE
    if args.out:
        from mcrt.grade.outputs import write_student

        d = write_student(res, a, Path(args.out))
        log(f"wrote {d / 'results.json'} and {d / 'feedback.html'}")
    print(format_check(res, a, render))
    return EXIT_OK if res.score >= res.max_score - 1e-9 else EXIT_FAILED


def format_check(res, a, render: Path) -> str:
    """The feedback of one result as plain text: the score, then each criterion with its points and message."""
    from mcrt.grade.submissions import shown

    lines = [f"{shown(render.name)}: {res.score:g} / {res.max_score:g} points ({a.title}; {a.width}x{a.height}, "
             f"graded at {a.grade_width}x{a.grade_height})", shown(res.summary), ""]
    for t in res.tests:
        mark = {"passed": "ok  ", "failed": "FAIL", "info": "info", "not graded": "--  "}.get(t.status, t.status)
        pts = f"{t.score:g}/{t.max_score:g}" if t.max_score else "-"
        lines.append(f"[{mark}] {t.title} ({pts})")
        lines.extend("       " + ln for ln in shown(t.output).splitlines() if ln.strip())
    if res.notes:
        lines += ["", "Notes:"] + [f"  - {shown(n)}" for n in res.notes if str(n).strip()]
    return "\n".join(lines)


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
        if args.mode == "code" and a.code is None:
            print(f"mcrt grade: {a.path}: no [code] table, so --mode code has nothing to check", file=sys.stderr)
            return EXIT_UNUSABLE
        from mcrt.grade.batch import grade_class

        # One class runner for both modes: workers, run.json, resume (--fresh), the lock on the folder.
        res = grade_class(args.submissions, a, args.out, jobs=args.jobs,
                          timeout=args.timeout, cache_dir=args.cache, single=args.single, student=args.student,
                          memory_mb=args.memory, fresh=args.fresh, mode=args.mode,
                          allow_unisolated_code=args.allow_unisolated_code, log=log)
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
    from mcrt.grade.explain.catalogue import catalogue_power

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
