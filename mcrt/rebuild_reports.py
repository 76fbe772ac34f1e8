"""``mcrt reports``: regenerate every committed report with the command that wrote it.

Each folder under reports/ is written by one ``mcrt`` command, which records
itself in the report's JSON (``command``); :data:`REPORTS` lists those
commands, and a test checks that it matches what the committed reports
record, so that this one command rebuilds all of them. Each report is built
by its own process, one after another; when one command fails or reports a
failed check (exit 1, its report written), the others go on, and the exit
code is 1.
"""

from __future__ import annotations

import argparse
import shlex
import subprocess
import sys
import time
from dataclasses import dataclass

from mcrt.exitcodes import EXIT_FAILED, EXIT_OK, EXIT_UNUSABLE


@dataclass(frozen=True)
class Report:
    """One committed report: its folder under reports/, the command that writes it, and what it shows."""

    name: str
    command: str  # the mcrt command line, without the program name
    what: str


REPORTS: tuple[Report, ...] = (
    Report("canonical", "main", "convergence of every renderer on the canonical scene at 64x64; mcrt beside Mitsuba"),
    Report("canonical_256", "report --res 256 --spp-ladder 1..256 --seeds 3 --renderers mcrt,mitsuba --reference committed "
           "--name canonical_256 --out reports/canonical_256 --quiet", "the same at 256x256"),
    Report("course2023", "report --preset course2023 --out reports/course2023 --quiet",
           "the 2023 course report's settings: 30 shadow rays against one, at equal time"),
    Report("hardcases", "hardcases --res 64 --spp 512 --ref-spp 4096 --limits auto --convergence auto --out reports/hardcases",
           "numerically hard scenes: agreement, float32 limits, fireflies"),
    Report("bench", "bench --res 64 --res 256 --res 512 --res 1024 --res 2048 --res 4096 --spp-sweep 1 --spp-sweep 4 "
           "--spp-sweep 64 --spp-sweep 256 --spp-sweep 1024 --sweep-res 256 --sweep-res 4096 --depth-sweep 2 "
           "--depth-sweep -1 --course 1 --course 30 --flatness 7 --memory --limits --profile "
           "--report reports/bench",
           "paths per second and efficiency against Mitsuba from 64x64 to 4096x4096 and 1 to 1024 spp, peak memory, "
           "where the kernel's time goes and how far it is from the machine"),
    Report("validation", "validate --seeds 200 --power-seeds 20 --spp 1024 --res 64 --camera near --max-depth 8 --alpha 0.01 "
           "--tile 8 --against mitsuba --extra-tiles 1,16,32 --escalate-spp 2048,4096,8192,16384 --followup max_depth=2 "
           "--followup camera=far --effect-spp 65536 --out reports/validation",
           "false-alarm rate and power of the comparison against fresh Mitsuba renders"),
    Report("validation/against_reference", "validate --seeds 200 --power-seeds 20 --spp 1024 --res 64 --camera near "
           "--max-depth 8 --alpha 0.01 --tile 8 --against reference --extra-tiles 1,16,32 --escalate-spp 2048,4096,8192,16384 "
           "--followup max_depth=2 --followup camera=far --effect-spp 0 --out reports/validation/against_reference",
           "the same against the committed reference"),
    Report("validation/against_reference_floor", "validate --seeds 200 --power-seeds 20 --spp 1024 --res 64 --camera near "
           "--max-depth 8 --alpha 0.01 --tile 8 --against reference-floor --extra-tiles 1,16,32 "
           "--escalate-spp 2048,4096,8192,16384 --followup max_depth=2 --followup camera=far --effect-spp 0 "
           "--out reports/validation/against_reference_floor",
           "the same against the committed reference with the variance floor"),
    Report("integrators", "validate-integrator cornell-box --integrator path --against volpath --against prb "
           "--against ptracer --wrong path:max_depth=7 --res 32 --budget 0.25 --seeds 100 --report reports/integrators",
           "mcrt validate-integrator on Mitsuba's Cornell box: false-alarm rate of path against volpath, prb, ptracer"),
    Report("tricks", "tricks --camera near --res 64 --max-depth 8 --ladder 16,64,256,1024,4096 --seeds 4 --alpha 0.01 "
           "--tiles 8,32 --light-receiver-samples 1048576 --confirm-spp 65536 --out reports/tricks",
           "the lecture's efficiency tricks beside plain mcrt: error against time and spp, bias, a verdict per trick"),
    Report("samplers", "samplers --resolutions '64:16,64,256,1024,4096;256:16,64,256,1024' --seeds 4 --camera near "
           "--max-depth 8 --out reports/samplers",
           "plain against stratified (sobol) pixel samples, with and without bidirectional: efficiency by MSE and "
           "relMSE, the error at the light's edge"),
    Report("samplers/validation_false_alarms", "validate --seeds 200 --power-seeds 20 --spp 1024 --res 32 --camera near "
           "--max-depth 8 --alpha 0.01 --tile 8 --against mitsuba --pixel-sampler sobol --only false-alarms "
           "--extra-tiles 16 --escalate-spp none --followup none --effect-spp 0 "
           "--out reports/samplers/validation_false_alarms",
           "false-alarm rate of the comparison with the sobol sampler's replicate variance against fresh Mitsuba renders"),
    Report("samplers/validation_power", "validate --seeds 200 --power-seeds 20 --spp 1024 --res 64 --camera near "
           "--max-depth 8 --alpha 0.01 --tile 8 --against mitsuba --pixel-sampler sobol --only power --extra-tiles none "
           "--escalate-spp none --followup none --effect-spp 0 --out reports/samplers/validation_power",
           "power on the bug catalogue with the sobol sampler at the suite's budget"),
    Report("samplers/bench", "bench --camera near --res 64 --res 256 --spp 64 --spp 1024 --repeats 3 --mse-renders 4 "
           "--renderers mcrt,mcrt-sobol,mitsuba --report reports/samplers/bench --tried none",
           "paths per second of mcrt with and without the sobol pixel sampler against Mitsuba, in one run"),
    Report("mitsuba_suite", "mitsuba-suite ../shared/mitsuba-tests --seeds 40",
           "Mitsuba 3's own render-test scenes (the shared copy, beside the clone): mcrt's multi-scale test beside "
           "Mitsuba's z-rule on correct renders at Mitsuba's budget, false alarms at the suite's level over 40 seeds, "
           "power on the issue's perturbations and a ladder of subtler sizes"),
    Report("grading_accuracy", "grade-accuracy --out reports/grading_accuracy",
           "grading on a class of realistic mistakes made by Mitsuba scene edits and correct renders: scores, "
           "detection, naming and false-alarm rates, one student's CPU time and memory"),
    Report("grading_accuracy/outside", "grade-accuracy --class outside --out reports/grading_accuracy/outside",
           "grading on mistakes made outside the scene file (tone maps, BGR, materials, cosine weights, a point light, "
           "enlarged renders, object sizes, claimed spp): named right, confidently wrong, partial, false alarms"),
    Report("grading_accuracy/programs", "grade-accuracy --class programs --out reports/grading_accuracy/programs",
           "grading on mistakes of students' programs written apart from the grader's rules (orientation, encodings, "
           "colour lost, direct light twice, bad pixels, a per-sample clamp, scene mistakes): named right, "
           "confidently wrong, partial, false alarms, with a held-out half fixed before grading"),
    Report("grading_accuracy/fresh", "grade-accuracy --class fresh --out reports/grading_accuracy/fresh",
           "grading on mistakes no other class tried (file writing, normals, camera models, resampling, a pair of one "
           "seed, roulette without re-weighting), written apart from the grader's rules: named right, confidently "
           "wrong, partial, false alarms"),
    Report("grading_accuracy/blind", "grade-accuracy --class blind --out reports/grading_accuracy/blind",
           "grading on mistakes outside the scene file written blind to the grader (post-processing, file writing, "
           "materials, camera and light models, resolution, claimed spp): named right, confidently wrong, partial, "
           "false alarms, with a held-out half graded once after the rules were frozen"),
    Report("grading_accuracy/unseen", "grade-accuracy --class unseen --out reports/grading_accuracy/unseen",
           "grading on a sixth class of mistakes in students' tracers and their output, written blind to the grader "
           "(post-processing, file writing, materials, camera and light models, resolution, samples per pixel): named "
           "right, confidently wrong, partial, false alarms, with a held-out half fixed before any grading"),
    Report("grading_accuracy/untried", "grade-accuracy --class untried --out reports/grading_accuracy/untried",
           "grading on a seventh class of mistakes in students' tracers, scene input and output, written blind to the "
           "grader (post-processing, file writing, materials, geometry, camera and light models, pixel sampling, "
           "samples per pixel): named right, confidently wrong, partial, false alarms, with a held-out half fixed "
           "before any grading"),
    Report("grading_accuracy/novel", "grade-accuracy --class novel --out reports/grading_accuracy/novel",
           "grading on an eighth class of mistakes in students' tracers, scene input and output, written blind to the "
           "grader (post-processing, file writing, materials, geometry, camera and light models, pixel sampling, "
           "samples per pixel): named right, confidently wrong, partial, false alarms, with a held-out half fixed "
           "before any grading"),
    Report("grading_accuracy/untold", "grade-accuracy --class untold --out reports/grading_accuracy/untold",
           "grading on a ninth class of mistakes in students' tracers, scene input and output, written blind to the "
           "grader (post-processing, file writing, materials, geometry, camera and light models, the integrator, "
           "samples and passes): named right, confidently wrong, partial, false alarms, with a held-out half fixed "
           "before any grading"),
    Report("grading_accuracy/unmet", "grade-accuracy --class unmet --out reports/grading_accuracy/unmet",
           "grading on a tenth class of mistakes in students' tracers, scene input and output, written blind to the "
           "grader (post-processing, file writing, materials, geometry, camera and light models, the integrator, "
           "samples and passes): named right, confidently wrong, partial, false alarms, with a held-out half fixed "
           "before any grading"),
    Report("grading_accuracy/unheard", "grade-accuracy --class unheard --out reports/grading_accuracy/unheard",
           "grading on an eleventh class of mistakes in students' tracers, scene input and output, written blind to "
           "the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unsaid", "grade-accuracy --class unsaid --out reports/grading_accuracy/unsaid",
           "grading on a twelfth class of mistakes in students' tracers, scene input and output, written blind to "
           "the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unasked", "grade-accuracy --class unasked --out reports/grading_accuracy/unasked",
           "grading on a thirteenth class of mistakes in students' tracers, scene input and output, written blind to "
           "the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unsought", "grade-accuracy --class unsought --out reports/grading_accuracy/unsought",
           "grading on a fourteenth class of mistakes in students' tracers, scene input and output, written blind to "
           "the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unguessed", "grade-accuracy --class unguessed --out reports/grading_accuracy/unguessed",
           "grading on a fifteenth class of mistakes in students' tracers, scene input and output, written blind to "
           "the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and tiles): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unforeseen", "grade-accuracy --class unforeseen --out reports/grading_accuracy/unforeseen",
           "grading on a sixteenth class of mistakes in students' tracers, scene input and output, written blind to "
           "the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unprompted", "grade-accuracy --class unprompted --out reports/grading_accuracy/unprompted",
           "grading on a seventeenth class of mistakes in students' tracers, scene input and output, written blind to "
           "the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unbidden", "grade-accuracy --class unbidden --out reports/grading_accuracy/unbidden",
           "grading on an eighteenth class of mistakes in students' tracers, scene input and output, written blind to "
           "the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unheralded", "grade-accuracy --class unheralded --out reports/grading_accuracy/unheralded",
           "grading on a nineteenth class of mistakes in students' tracers, scene input and output, written blind to "
           "the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unbeknown", "grade-accuracy --class unbeknown --out reports/grading_accuracy/unbeknown",
           "grading on a twentieth class of mistakes in students' tracers, scene input and output, written blind to "
           "the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unvisited", "grade-accuracy --class unvisited --out reports/grading_accuracy/unvisited",
           "grading on a twenty-first class of mistakes in students' tracers, scene input and output, written blind to "
           "the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unlooked", "grade-accuracy --class unlooked --out reports/grading_accuracy/unlooked",
           "grading on a twenty-second class of mistakes in students' tracers, scene input and output, written blind to "
           "the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unwonted", "grade-accuracy --class unwonted --out reports/grading_accuracy/unwonted",
           "grading on a twenty-third class of mistakes in students' tracers, scene input and output, written blind to "
           "the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unremarked", "grade-accuracy --class unremarked --out reports/grading_accuracy/unremarked",
           "grading on a twenty-fourth class of mistakes in students' tracers, scene input and output, written blind to "
           "the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unremembered", "grade-accuracy --class unremembered --out reports/grading_accuracy/unremembered",
           "grading on a twenty-fifth class of mistakes in students' tracers, scene input and output, written blind to "
           "the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unnoticed", "grade-accuracy --class unnoticed --out reports/grading_accuracy/unnoticed",
           "grading on a twenty-sixth class of mistakes in students' tracers, scene input and output, written blind to "
           "the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unrecorded", "grade-accuracy --class unrecorded --out reports/grading_accuracy/unrecorded",
           "grading on a twenty-seventh class of mistakes in students' tracers, scene input and output, written blind "
           "to the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unattended", "grade-accuracy --class unattended --out reports/grading_accuracy/unattended",
           "grading on a twenty-eighth class of mistakes in students' tracers, scene input and output, written blind "
           "to the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unattested", "grade-accuracy --class unattested --out reports/grading_accuracy/unattested",
           "grading on a twenty-ninth class of mistakes in students' tracers (array and GPU frameworks), written "
           "blind to the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unconsidered",
           "grade-accuracy --class unconsidered --out reports/grading_accuracy/unconsidered",
           "grading on a thirtieth class of mistakes in students' tracers (Rust, Go, Java, C# and others), written "
           "blind to the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unanticipated",
           "grade-accuracy --class unanticipated --out reports/grading_accuracy/unanticipated",
           "grading on a thirty-first class of mistakes in students' tracers (the mathematics derived by hand), "
           "written blind to the grader (post-processing, writing the file, materials, geometry, camera and light "
           "models, the integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a "
           "held-out half fixed before any grading"),
    Report("grading_accuracy/unexamined", "grade-accuracy --class unexamined --out reports/grading_accuracy/unexamined",
           "grading on a thirty-second class of mistakes in students' tracers (the workflow around them), written "
           "blind to the grader (post-processing, writing the file, materials, geometry, camera and light models, the "
           "integrator, samples and passes): named right, confidently wrong, partial, false alarms, with a held-out "
           "half fixed before any grading"),
    Report("grading_accuracy/unconfirmed",
           "grade-accuracy --class unconfirmed --out reports/grading_accuracy/unconfirmed",
           "grading on a thirty-third class of mistakes in students' tracers (what debugging, refactoring and version "
           "control leave in them), written blind to the grader (post-processing, writing the file, materials, "
           "geometry, camera and light models, the integrator, samples and passes): named right, confidently wrong, "
           "partial, false alarms, with a held-out half fixed before any grading"),
    Report("grading_accuracy/unlisted", "grade-accuracy --class unlisted --out reports/grading_accuracy/unlisted",
           "grading on a thirty-fourth class of mistakes in students' tracers (intersection code, acceleration "
           "structures and floating-point robustness), written blind to the grader (post-processing, writing the "
           "file, materials, geometry, camera and light models, the integrator, samples and passes): named right, "
           "confidently wrong, partial, false alarms, with a held-out half fixed before any grading"),
    Report("grading/false_alarms", "grade-false-alarms --out reports/grading/false_alarms",
           "grading's false alarms on correct renders: estimators, samplers, spp 16-1024, 64x64 to 800x800, PNG curves"),
)


def select(only=(), skip=()) -> list[Report]:
    """The reports to build: all, or those named in ``only``, less those in ``skip``; unknown names raise ValueError."""
    names = {r.name for r in REPORTS}
    for n in (*only, *skip):
        if n not in names:
            raise ValueError(f"no committed report named {n!r} (have {', '.join(sorted(names))})")
    return [r for r in REPORTS if (not only or r.name in only) and r.name not in skip]


def build(reports: list[Report], *, dry_run: bool = False) -> list[str]:
    """Run each report's command in its own process, in order; returns the names whose command did not exit 0."""
    failed = []
    t0 = time.perf_counter()
    for k, r in enumerate(reports, 1):
        argv = [sys.executable, "-m", "mcrt.cli", *shlex.split(r.command)]
        print(f"mcrt reports: [{k}/{len(reports)}] {r.name}: mcrt {r.command} ({time.perf_counter() - t0:.0f} s so far)",
              file=sys.stderr, flush=True)
        if dry_run:
            continue
        rc = subprocess.run(argv).returncode
        if rc == EXIT_FAILED:
            print(f"mcrt reports: {r.name}: written; a check it reports failed (exit {rc}: see the report)", file=sys.stderr)
            failed.append(r.name)
        elif rc != EXIT_OK:
            print(f"mcrt reports: {r.name}: the command stopped with exit {rc} (its output above says why)", file=sys.stderr)
            failed.append(r.name)
    return failed


def register(sub) -> None:
    p = sub.add_parser("reports", help="regenerate every committed report under reports/ with the command that wrote it",
                       description=__doc__.split("\n\n")[1], formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--list", action="store_true", help="print each report's folder and command, and build nothing (default: build)")
    p.add_argument("--only", action="append", default=[], metavar="NAME",
                   help="build only this report (repeatable; default: every report)")
    p.add_argument("--skip", action="append", default=[], metavar="NAME", help="do not build this report (repeatable; default: none)")
    p.add_argument("--dry-run", action="store_true", help="print the commands in the order they would run (default: run them)")
    p.set_defaults(func=cmd_reports)


def cmd_reports(args) -> int:
    try:
        reports = select(args.only, args.skip)
    except ValueError as e:
        print(f"mcrt reports: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    if args.list:
        for r in reports:
            print(f"reports/{r.name}: mcrt {r.command}\n    {r.what}")
        return EXIT_OK
    failed = build(reports, dry_run=args.dry_run)
    return EXIT_FAILED if failed else EXIT_OK
