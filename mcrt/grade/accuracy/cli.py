"""``mcrt grade-accuracy``: grade the realistic class and write the grading-accuracy report."""

from __future__ import annotations

import datetime
import time

from mcrt.exitcodes import EXIT_OK
from mcrt.util import progress

DEFAULT_OUT = "reports/grading_accuracy"
DEFAULT_ASSIGNMENT = "course2023"
#: The classes by --class name: the module (under mcrt.grade.accuracy) holding its SPECS and CAUSES.
CLASSES = {"scene": "cases", "outside": "outside", "programs": "programs", "fresh": "fresh",
           "blind": "blind", "unseen": "unseen", "untried": "untried",
           "novel": "novel", "untold": "untold", "unmet": "unmet",
           "unheard": "unheard", "unsaid": "unsaid", "unasked": "unasked",
           "unsought": "unsought", "unguessed": "unguessed",
           "unforeseen": "unforeseen", "unprompted": "unprompted",
           "unbidden": "unbidden", "unheralded": "unheralded", "unbeknown": "unbeknown",
           "unvisited": "unvisited", "unlooked": "unlooked", "unwonted": "unwonted",
           "unremarked": "unremarked", "unremembered": "unremembered", "unnoticed": "unnoticed",
           "unrecorded": "unrecorded", "unattended": "unattended", "unattested": "unattested",
           "unconsidered": "unconsidered", "unanticipated": "unanticipated", "unexamined": "unexamined",
           "unconfirmed": "unconfirmed", "unlisted": "unlisted"}


def register(sub) -> None:
    p = sub.add_parser("grade-accuracy", help="grade a class of realistic hand-ins (Mitsuba scene edits, correct renders "
                       "of several estimators) and report scores, detection, naming and false-alarm rates",
                       description=__doc__)
    p.add_argument("--class", dest="klass", choices=tuple(CLASSES), default="scene",
                   help="the class graded: 'scene' (scene edits, mcrt.grade.accuracy.cases), 'outside' (mistakes "
                   "outside the scene file, mcrt.grade.accuracy.outside), 'programs' (mistakes of students' "
                   "programs, written apart from the grader's rules, mcrt.grade.accuracy.programs), 'fresh' (mistakes "
                   "no other class tried, tuned on since its first grading, mcrt.grade.accuracy.fresh), 'blind' "
                   "(mistakes outside the scene file no other class tried, written blind to the grader, a held-out half "
                   "fixed by category, mcrt.grade.accuracy.blind), 'unseen' (a sixth class of such mistakes, in "
                   "tracers and their output, written blind, mcrt.grade.accuracy.unseen), 'untried' (a seventh, in "
                   "tracers, scene input and output, written blind, mcrt.grade.accuracy.untried), 'novel' (an "
                   "eighth, in tracers, scene input and output, written blind, mcrt.grade.accuracy.novel), "
                   "'untold' (a ninth class of such mistakes, in tracers, scene input and output, written blind, "
                   "mcrt.grade.accuracy.untold), 'unmet' (a tenth, in tracers, scene input and output, written "
                   "blind, mcrt.grade.accuracy.unmet), 'unheard' (an eleventh, in tracers, scene input and output, "
                   "written blind, mcrt.grade.accuracy.unheard), 'unsaid' (a twelfth, in tracers, scene input and "
                   "output, written blind, mcrt.grade.accuracy.unsaid), 'unasked' (a thirteenth, in tracers, scene "
                   "input and output, written blind, mcrt.grade.accuracy.unasked), 'unsought' (a fourteenth, in "
                   "tracers, scene input and output, written blind, mcrt.grade.accuracy.unsought), 'unguessed' (a "
                   "fifteenth, in tracers, scene input and output, written blind, mcrt.grade.accuracy.unguessed), "
                   "'unforeseen' (a sixteenth, in tracers, scene input and output, written blind, "
                   "mcrt.grade.accuracy.unforeseen), 'unprompted' (a seventeenth, in tracers, scene input and "
                   "output, written blind, mcrt.grade.accuracy.unprompted), 'unbidden' (an eighteenth, in "
                   "tracers, scene input and output, written blind, mcrt.grade.accuracy.unbidden), 'unheralded' (a "
                   "nineteenth, in tracers, scene input and output, written blind, "
                   "mcrt.grade.accuracy.unheralded), 'unbeknown' (a twentieth, in tracers, scene input and output, "
                   "written blind, mcrt.grade.accuracy.unbeknown), 'unvisited' (a twenty-first, in tracers, scene "
                   "input and output, written blind, mcrt.grade.accuracy.unvisited), 'unlooked' (a twenty-second, "
                   "in tracers, scene input and output, written blind, mcrt.grade.accuracy.unlooked), 'unwonted' (a "
                   "twenty-third, in tracers, scene input and output, written blind, mcrt.grade.accuracy.unwonted), "
                   "'unremarked' (a twenty-fourth, in tracers, scene input and output, written blind, "
                   "mcrt.grade.accuracy.unremarked), 'unremembered' (a twenty-fifth, in tracers, scene input and "
                   "output, written blind, mcrt.grade.accuracy.unremembered), 'unnoticed' (a twenty-sixth, in tracers, "
                   "scene input and output, written blind, mcrt.grade.accuracy.unnoticed), 'unrecorded' (a "
                   "twenty-seventh, in tracers, scene input and output, written blind, "
                   "mcrt.grade.accuracy.unrecorded), 'unattended' (a twenty-eighth, in tracers, scene input and "
                   "output, written blind, mcrt.grade.accuracy.unattended), 'unattested' (a twenty-ninth, in array "
                   "and GPU frameworks' tracers, written blind, mcrt.grade.accuracy.unattested), 'unconsidered' (a "
                   "thirtieth, in Rust, Go, Java and C# tracers, written blind, mcrt.grade.accuracy.unconsidered), "
                   "'unanticipated' (a thirty-first, in the mathematics students derive by hand and type in, written "
                   "blind, mcrt.grade.accuracy.unanticipated), 'unexamined' (a thirty-second, in the workflow around "
                   "students' tracers, written blind, mcrt.grade.accuracy.unexamined), 'unconfirmed' (a "
                   "thirty-third, in what debugging, refactoring and version control leave in students' tracers, "
                   "written blind, mcrt.grade.accuracy.unconfirmed) or 'unlisted' (a thirty-fourth, in intersection "
                   "code, acceleration structures and floating-point robustness, written blind, "
                   "mcrt.grade.accuracy.unlisted) (default: scene)")
    p.add_argument("--held-out", choices=("all", "only", "none"), default="all",
                   help="grade all cases, only the held-out ones, or none of them (default: all)")
    p.add_argument("--out", default=None, help=f"report folder (default: {DEFAULT_OUT}, or {DEFAULT_OUT}/CLASS "
                   "for another --class)")
    p.add_argument("--assignment", default=DEFAULT_ASSIGNMENT,
                   help=f"assignment: a name of the package's assignments or a file (default: {DEFAULT_ASSIGNMENT})")
    p.add_argument("--cache", default=None, help="grading cache folder (default: $MCRT_CACHE/grade or ~/.cache/mcrt/grade)")
    p.add_argument("--only", action="append", default=[], metavar="CASE",
                   help="grade only this case (repeatable; default: the whole class)")
    p.add_argument("--gradescope", type=int, default=2, metavar="N",
                   help="time the N slowest-graded students (the slowest mistakes and the slowest correct render) in a "
                   "fresh process as Gradescope grades them (default: 2)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress lines (default: off)")
    p.set_defaults(func=cmd_grade_accuracy)


def _command(args) -> str:
    words = ["mcrt", "grade-accuracy"] + (["--class", args.klass] if args.klass != "scene" else []) + \
        (["--held-out", args.held_out] if args.held_out != "all" else []) + ["--out", args.out]
    if args.assignment != DEFAULT_ASSIGNMENT:
        words += ["--assignment", args.assignment]
    for c in args.only:
        words += ["--only", c]
    if args.gradescope != 2:
        words += ["--gradescope", str(args.gradescope)]
    return " ".join(words)


def cmd_grade_accuracy(args) -> int:
    from mcrt.grade.accuracy.cases import build_class
    from mcrt.grade.accuracy.markdown import write_report
    from mcrt.grade.accuracy.run import grade_cases, gradescope_figures
    from mcrt.grade.assignment import load_assignment
    from mcrt.grade.expected import default_cache_dir, prepare_context

    def log(line: str) -> None:
        progress.log(f"mcrt grade-accuracy: {line}", not args.quiet)

    import importlib

    if args.out is None:
        args.out = DEFAULT_OUT + (f"/{args.klass}" if args.klass != "scene" else "")
    t0 = time.perf_counter()
    a = load_assignment(args.assignment)
    cache = args.cache or default_cache_dir()
    log(f"preparing {a.name} (cache {cache})")
    ctx = prepare_context(a, cache, log=log)
    prep = time.perf_counter() - t0
    specs = importlib.import_module(f"mcrt.grade.accuracy.{CLASSES[args.klass]}").SPECS
    held = {"all": None, "only": True, "none": False}[args.held_out]
    cases = build_class(width=a.grade_width, height=a.grade_height, max_depth=a.max_depth,
                        names=tuple(args.only) or None, held_out=held, log=log, specs=specs)
    outcomes = grade_cases(cases, ctx, log=log)
    gs = []
    # The slowest hand-ins as graded here: Gradescope's limits are about the worst student, not the first.
    took = {o.name: o.seconds for o in outcomes}
    slowest = sorted(cases, key=lambda c: -took.get(c.name, 0.0))
    picks = [c for c in slowest if c.cause is not None][: max(args.gradescope - 1, 0)] + \
        [c for c in slowest if c.cause is None][:1]
    for c in picks[: args.gradescope]:
        log(f"timing {c.name} as Gradescope grades it")
        gs.append(gradescope_figures(c, ctx))
    meta = {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "seconds": time.perf_counter() - t0, "prepare_seconds": prep, "assignment": a.name,
            "reference": ctx.references[a.camera].source}
    path = write_report(args.out, outcomes, command=_command(args), meta=meta, gradescope=gs, klass=args.klass)
    log(f"wrote {path} ({time.perf_counter() - t0:.0f} s)")
    return EXIT_OK
