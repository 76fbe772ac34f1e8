"""``mcrt validate``: a thin command line over the false-alarm and power studies.

Exit codes (:mod:`mcrt.exitcodes`): 0 the goals are met, 1 a goal is missed,
2 unusable input (e.g. ``--against reference`` without committed references).
"""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path
from typing import Any

from mcrt.exitcodes import EXIT_FAILED, EXIT_OK, EXIT_UNUSABLE
from mcrt.mutants import MUTANTS
from mcrt.validate.budget import (DEFAULT_EFFECT_SPP, DEFAULT_EXTRA_TILES, DEFAULT_FOLLOWUPS, ESCALATION_SPP, POWER_GOAL, SUBTLE,
                                  Budget)
from mcrt.validate.markdown import interval, pct
from mcrt.validate.opponent import Opponent

#: Report folder of each opponent when ``--out`` is not given: the runs against the
#: reference go into sub-folders of the run against Mitsuba, whose README covers all three.
DEFAULT_OUT = {"mitsuba": "reports/validation", "reference": "reports/validation/against_reference",
               "reference-floor": "reports/validation/against_reference_floor"}


def _int_list(text: str) -> list[int]:
    text = text.strip()
    if text in ("", "none"):
        return []
    try:
        return [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated integers, got {text!r}") from None


def _followup(text: str) -> dict[str, Any]:
    """``max_depth=2`` or ``camera=far`` (several separated by commas) -> dict; ``none`` -> {}."""
    if text.strip() == "none":
        return {}
    out: dict[str, Any] = {}
    for part in text.split(","):
        if "=" not in part:
            raise argparse.ArgumentTypeError(f"follow-up must be KEY=VALUE (camera, res, max_depth), got {part!r}")
        k, v = (s.strip() for s in part.split("=", 1))
        k = k.replace("-", "_")
        if k not in ("camera", "res", "max_depth"):
            raise argparse.ArgumentTypeError(f"follow-up key must be camera, res or max_depth, got {k!r}")
        out[k] = v if k == "camera" else int(v)
    return out


def _followups(args) -> list[dict[str, Any]]:
    return [f for f in (args.followup if args.followup is not None else list(DEFAULT_FOLLOWUPS)) if f]


def _command_line(args) -> str:
    """The canonical command line that reproduces a run (every option explicit)."""
    parts = ["mcrt", "validate"]
    if args.scene:
        parts += ["--scene", args.scene]
    parts += ["--seeds", str(args.seeds), "--power-seeds", str(args.power_seeds), "--spp", str(args.spp), "--res", str(args.res),
              "--camera", args.camera, "--max-depth", str(args.max_depth), "--alpha", f"{args.alpha:g}", "--tile", str(args.tile),
              "--against", args.against]
    if args.pixel_sampler != "independent":
        parts += ["--pixel-sampler", args.pixel_sampler]
    if args.only:
        parts += ["--only", args.only]
    for m in args.mutant or ():
        parts += ["--mutant", m]
    parts += ["--extra-tiles", ",".join(map(str, args.extra_tiles)) or "none",
              "--escalate-spp", ",".join(map(str, args.escalate_spp)) or "none"]
    fus = _followups(args)
    if not fus:
        parts += ["--followup", "none"]
    for f in fus:
        parts += ["--followup", ",".join(f"{k}={v}" for k, v in f.items())]
    parts += ["--effect-spp", str(args.effect_spp), "--out", args.out]
    if args.backend != "llvm":
        parts += ["--backend", args.backend]
    return shlex.join(parts)


def register(subparsers) -> None:
    """Add ``validate`` to an argparse subparsers object (``mcrt validate``)."""
    p = subparsers.add_parser(
        "validate",
        help="measure the comparison's false-alarm rate and its power against the bug catalogue; write reports/validation/",
        description=(
            "Measure the image comparison (mcrt.stats.compare_images) itself. False alarms: a correct mcrt render per seed "
            "against an independent Mitsuba render (or the committed reference); the rate must not be significantly above "
            "alpha (Clopper-Pearson interval), and the pooled tile p-values should be uniform. Power: every mutant of the bug "
            f"catalogue on --power-seeds seeds at the same budget must be detected on >= {100 * POWER_GOAL:.0f} % of seeds "
            f"(the subtle {', '.join(SUBTLE)} at a larger budget found by --escalate-spp). Mutants below the goal are "
            "followed up at other configurations, larger budgets and by their effect size. Writes false_alarms.md/.json and "
            "power.md/.json with the command line and versions, and the README.md of the validation folder (--out, or its "
            "parent when that holds a run) from every run in it and its sub-folders. Exit 0 when the goals are met, 1 when "
            "not, 2 on unusable input (e.g. --against reference without committed references)."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--scene", default=None, help="scene file (default: the canonical room shipped with mcrt, canonical.toml)")
    p.add_argument("--seeds", type=int, default=200, help="false-alarm trials (independent seeds of correct renders) (default: %(default)s)")
    p.add_argument("--power-seeds", type=int, default=20, help="seeds per mutant in the power study (default: %(default)s)")
    p.add_argument("--spp", type=int, default=1024, help="samples per pixel per side, the default suite's budget (default: %(default)s)")
    p.add_argument("--res", type=int, default=64, help="square resolution N (N x N) (default: %(default)s)")
    p.add_argument("--camera", default="near", help="camera name from the scene file (default: %(default)s)")
    p.add_argument("--max-depth", type=int, default=8, help="longest path in segments (default: %(default)s)")
    p.add_argument("--alpha", type=float, default=0.01, help="family-wise error rate of one comparison (Holm) (default: %(default)s)")
    p.add_argument("--tile", type=int, default=8, help="tile size in pixels of the test under study (default: %(default)s)")
    p.add_argument("--pixel-sampler", choices=("independent", "sobol"), default="independent",
                   help="pixel sampler of the image under test (mcrt.samplers; sobol: 8 replicates, their variance with 7 df) "
                        "(default: %(default)s)")
    p.add_argument("--against", choices=Opponent.KINDS, default="mitsuba",
                   help="opponent: a fresh independent Mitsuba render per trial, the committed reference, or the committed "
                        "reference with the tested render's variance floored at the reference's (as `mcrt reference verify` tests) (default: %(default)s)")
    p.add_argument("--only", choices=("false-alarms", "power"), default=None, help="run one study only (default: %(default)s, both studies)")
    p.add_argument("--mutant", action="append", metavar="NAME", default=None,
                   help="power study for this mutant only (repeatable; default: the whole catalogue, see `mcrt mutants`)")
    p.add_argument("--extra-tiles", type=_int_list, default=list(DEFAULT_EXTRA_TILES),
                   help="other tile sizes evaluated on the same renders (comma-separated; 'none') (default: %(default)s)")
    p.add_argument("--escalate-spp", type=_int_list, default=list(ESCALATION_SPP),
                   help="larger budgets tried, in order, for mutants below the goal (comma-separated; 'none') (default: %(default)s)")
    p.add_argument("--followup", type=_followup, action="append", default=None, metavar="KEY=VALUE",
                   help="another configuration tried for mutants below the goal (repeatable; camera=, res=, max_depth=; "
                        "'none' for no follow-ups; default: max_depth=2 and camera=far)")
    p.add_argument("--effect-spp", type=int, default=DEFAULT_EFFECT_SPP,
                   help="spp of the effect-size renders of mutants below the goal (0: skip) (default: %(default)s)")
    p.add_argument("--backend", choices=("llvm", "cuda"), default="llvm",
                   help="Dr.Jit backend: llvm on the CPU, cuda on a GPU (default: %(default)s)")
    p.add_argument("--out", default=None,
                   help="report folder (default: " + "; ".join(f"{v} against {k}" for k, v in DEFAULT_OUT.items()) + ")")
    p.add_argument("--readme-only", action="store_true",
                   help="run no study: rewrite README.md of the folder --out (default reports/validation) from the JSON "
                        "reports in it and its sub-folders")
    p.add_argument("--quiet", action="store_true", help="no progress lines (default: %(default)s)")
    p.set_defaults(func=cmd_validate)


def _say(msg: str, enabled: bool) -> None:
    if enabled:
        print(msg, file=sys.stderr, flush=True)


def cmd_readme(args) -> int:
    """Rewrite the README of the validation folder ``args.out`` from its JSON reports."""
    from mcrt.validate.readme import write_readme

    out = args.out or DEFAULT_OUT["mitsuba"]
    path = write_readme(out)
    if path is None:
        print(f"mcrt validate: no false_alarms.json or power.json in {out} or its sub-folders", file=sys.stderr)
        return EXIT_UNUSABLE
    print(f"wrote {path}")
    return EXIT_OK


def cmd_validate(args) -> int:
    """Run the studies selected by ``args`` and write the reports; exit code per the goals."""
    if args.readme_only:
        return cmd_readme(args)
    from mcrt.groundtruth import ReferenceUnavailable
    from mcrt.scene import CANONICAL, SceneError, load_scene
    from mcrt.stats import StatsError
    from mcrt.validate.false_alarms import false_alarm_study
    from mcrt.validate.meta import report_meta
    from mcrt.validate.output import write_reports
    from mcrt.validate.power import power_study

    progress = not args.quiet
    args.out = args.out or DEFAULT_OUT[args.against]
    try:
        scene = load_scene(args.scene or CANONICAL)
        scene.camera(args.camera)
    except (SceneError, KeyError, ValueError) as e:
        print(f"mcrt validate: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    if args.seeds < 1 or args.power_seeds < 1 or args.spp < 2 or args.res < 1 or args.tile < 1 or not 0 < args.alpha < 1:
        print("mcrt validate: need --seeds, --power-seeds, --res, --tile >= 1, --spp >= 2 and 0 < --alpha < 1", file=sys.stderr)
        return EXIT_UNUSABLE
    for m in args.mutant or ():
        if m not in MUTANTS:
            print(f"mcrt validate: unknown mutant {m!r}; known: {', '.join(MUTANTS)}", file=sys.stderr)
            return EXIT_UNUSABLE
    command = _command_line(args)
    budget = Budget(camera=args.camera, res=args.res, spp=args.spp, max_depth=args.max_depth, alpha=args.alpha, tile=args.tile,
                    pixel_sampler=args.pixel_sampler)
    common = {"budget": budget, "extra_tiles": args.extra_tiles, "backend": args.backend, "progress": progress}
    opp = Opponent(scene, args.against, backend=args.backend)
    meta = report_meta(scene, command)
    results: dict[str, Any] = {}
    _say(f"$ {command}", progress)
    written: list[Path] = []
    try:
        if args.only in (None, "false-alarms"):
            results["false_alarms"] = false_alarm_study(scene, seeds=args.seeds, against=opp, **common)
            fa = results["false_alarms"]["primary"]
            _say(f"false alarms: {fa['k']}/{fa['n']} ({pct(fa['rate'], 2)}, 95 % interval {interval(fa['interval'])})", progress)
            written += write_reports({"meta": meta, "false_alarms": results["false_alarms"]}, args.out)
            # Only the first power-seeds Mitsuba renders are reused by the power study.
            opp.forget(lambda k: not (k[0] == "mitsuba" and k[-1] >= args.power_seeds))
        if args.only in (None, "power"):
            results["power"] = power_study(scene, mutants=args.mutant, seeds=args.power_seeds, against=opp,
                                           escalate_spp=args.escalate_spp, followups=_followups(args),
                                           effect_spp=args.effect_spp, **common)
    except (ReferenceUnavailable, StatsError, SceneError) as e:
        print(f"mcrt validate: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    if "power" in results:
        written += write_reports({"meta": report_meta(scene, command), "power": results["power"]}, args.out)
    for path in dict.fromkeys(written):
        print(f"wrote {path}")
    return _verdict(results, args.alpha)


def _verdict(results: dict[str, Any], alpha: float) -> int:
    """Print the studies' outcome; the exit code per the goals."""
    ok = True
    if "false_alarms" in results:
        fa = results["false_alarms"]["primary"]
        ok &= results["false_alarms"]["goal_met"]
        print(f"false alarms: {fa['k']}/{fa['n']} = {pct(fa['rate'], 2)}, 95 % interval {interval(fa['interval'])}, "
              f"alpha {alpha:g}: {'ok' if results['false_alarms']['goal_met'] else 'TOO MANY'}")
    if "power" in results:
        pw = results["power"]
        ok &= pw["goal_met"]
        for n, r in pw["mutants"].items():
            tag = "subtle" if r["subtle"] else ("ok" if r["goal_met"] else "BELOW GOAL")
            print(f"  {n:20s} {r['k']:3d}/{r['n']:<3d} {pct(r['rate'], 0):>6s}  {tag}")
        for n, s in pw["stated_budgets"].items():
            print(f"  {n}: " + (f"reaches the goal at {s['spp']} spp" if s["spp"] else "does not reach the goal at the budgets tried"))
        print(f"power: {'goal met' if pw['goal_met'] else 'goal NOT met'}")
    return EXIT_OK if ok else EXIT_FAILED
