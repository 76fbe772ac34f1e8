"""``mcrt validate-integrator``: is a Mitsuba integrator right on a Mitsuba scene? One command.

:func:`validate_integrator` renders one scene with integrator A and with
integrator B (:func:`mcrt.mitsuba_scene.render_with_variance`: mean and per-sample
variance, reproducible from recorded seeds) *at equal time*, compares them
with the Welch tile test under the ``independent`` policy (two different
estimators: each keeps its own variance) and reports the verdict, the heat
map of t and the efficiency ratio.

Equal time: each integrator renders a short calibration run
(``calibration_spp``); its time per spp is (wall time - JIT compilation
time) / spp. Each then gets spp = budget / (time per spp) (at least 16;
``ptracer`` rounds to whole batches), and the final renders' times are
reported beside the budget.

Efficiency: 1 / (MSE x time), with the MSE of an unbiased renderer taken as
its per-pixel variance of the mean, mean(per-sample variance) / spp (over
pixels and channels), and time = wall time - JIT compilation of the final
render. The ratio eff_A / eff_B > 1 means A reaches a given noise sooner.
It presumes both are unbiased, which is what the verdict tests; for a
renderer the verdict rejects, the number means nothing.

ptracer (Mitsuba's particle tracer) starts paths at the light and connects
each vertex to the camera: it cannot render what the camera sees through a
delta (mirror, glass) surface, and it ignores ``hide_emitters``; on a scene
with such surfaces it differs from ``path`` for that reason alone, which
this command does not detect or excuse. Its per-pixel samples are not
separable, so it is rendered in batches (:func:`mcrt.mitsuba_scene._run`) and the
tile test ignores the correlation one particle path creates between pixels
of a tile; the false-alarm report (``--seeds N --report DIR``) measures
what that costs.

``--seeds N --report DIR`` repeats the validation of every ``--against``
with N seed pairs (calibrating once) and writes the rejection rates with
Clopper-Pearson intervals: the false-alarm rate of this use where the
integrators agree, the detection rate for the ``--wrong`` configurations.
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from mcrt.exitcodes import EXIT_FAILED, EXIT_OK, EXIT_UNUSABLE

#: Scene names the command knows besides XML files.
BUILTIN_SCENES = ("cornell-box",)

MIN_SPP = 16


def load_scene_arg(text: str):
    """``'cornell-box'`` -> ``mitsuba.cornell_box()`` (a dictionary); anything else is an XML file path."""
    if text.replace("_", "-") == "cornell-box":
        import mcrt.mitsuba_scene  # noqa: F401  (selects nothing; imports Mitsuba after mcrt)
        import mitsuba as mi

        if not mi.variant():
            mi.set_variant("llvm_ad_rgb")
        return mi.cornell_box()
    path = Path(text)
    if not path.is_file():
        raise ValueError(f"{text}: no such Mitsuba scene file (or one of {', '.join(BUILTIN_SCENES)})")
    return str(path)


def parse_integrator(text: str) -> str | dict[str, Any]:
    """``'path'`` -> ``'path'``; ``'path:max_depth=7,rr_depth=100'`` -> ``{'type': 'path', 'max_depth': 7, 'rr_depth': 100}``.

    Values are read as int, then float, then true/false, else kept as text.
    """
    name, _, rest = text.partition(":")
    if not name:
        raise ValueError(f"integrator {text!r}: no plugin name")
    if not rest:
        return name
    spec: dict[str, Any] = {"type": name}
    for item in rest.split(","):
        key, eq, value = item.partition("=")
        if not eq or not key:
            raise ValueError(f"integrator {text!r}: expected key=value, got {item!r}")
        spec[key.strip()] = _value(value.strip())
    return spec


def parse_defines(items) -> dict[str, str]:
    """``['spp=16', 'integrator=direct']`` (``-D KEY=VALUE`` options) -> ``{'spp': '16', 'integrator': 'direct'}``."""
    out = {}
    for item in items or ():
        key, eq, value = item.partition("=")
        if not eq or not key.strip():
            raise ValueError(f"-D {item!r}: expected KEY=VALUE")
        out[key.strip()] = value.strip()
    return out


def _value(v: str):
    for cast in (int, float):
        try:
            return cast(v)
        except ValueError:
            pass
    return {"true": True, "false": False}.get(v.lower(), v)


def _label(spec) -> str:
    if isinstance(spec, str):
        return spec
    rest = ",".join(f"{k}={v}" for k, v in spec.items() if k != "type")
    return f"{spec['type']}:{rest}" if rest else str(spec["type"])


def _render(scene, spec, spp: int, seed: int, res: int | None, backend: str, defaults=None):
    from mcrt.mitsuba_scene import render_with_variance

    return render_with_variance(scene, integrator=spec, spp=spp, seed=seed, width=res, height=res, backend=backend,
                                defaults=defaults)


def calibrate(scene, spec, *, spp: int = 32, res: int | None = None, backend: str = "llvm", seed: int = 999,
              defaults=None) -> float:
    """Seconds per spp of ``spec`` on ``scene``: (wall - compile) / spp of a short render (run twice: the second is timed)."""
    times = []
    for k in range(2):
        r = _render(scene, spec, spp, seed + k, res, backend, defaults)
        times.append(max(r.wall_time - (r.compile_time or 0.0), 1e-6) / max(r.spp, 1))
    return times[-1]


def spp_for(budget: float, seconds_per_spp: float, spec) -> int:
    """Samples per pixel that fit ``budget`` seconds (at least MIN_SPP; ptracer: whole batches of 32)."""
    n = max(MIN_SPP, int(budget / max(seconds_per_spp, 1e-9)))
    name = spec if isinstance(spec, str) else spec.get("type")
    if name == "ptracer":
        n = max(32, n // 32 * 32)
    return n


def efficiency(r) -> dict[str, float]:
    """MSE (variance of the mean, averaged over pixels and channels), time (wall - compile) and 1 / (MSE x time)."""
    mse = float(np.mean(r.variance.astype(np.float64)) / r.spp)
    t = max(r.wall_time - (r.compile_time or 0.0), 1e-9)
    return {"mse": mse, "time": t, "efficiency": 1.0 / max(mse * t, 1e-300)}


def _describe(r, spec) -> dict[str, Any]:
    e = efficiency(r)
    return {"integrator": _label(spec), "renderer": r.renderer, "spp": r.spp, "seed": r.seed, "max_depth": r.max_depth,
            "camera": r.camera, "scene_hash": r.scene_hash, "wall_time": r.wall_time, "compile_time": r.compile_time,
            "method": r.extra.get("method"), "mse": e["mse"], "time": e["time"], "efficiency": e["efficiency"]}


def validate_integrator(scene, integrator, against, *, budget: float = 2.0, seed: int = 1, res: int | None = None,
                        scene_against=None, alpha: float = 0.01, tile: int = 8, backend: str = "llvm",
                        seconds_per_spp: tuple[float, float] | None = None, calibration_spp: int = 32,
                        spp: int | None = None, defaults: dict[str, str] | None = None) -> dict[str, Any]:
    """Render ``scene`` with ``integrator`` (A) and ``against`` (B) at equal time (or equal ``spp``) and compare them.

    ``scene`` is a Mitsuba scene dictionary, XML path or loaded scene
    (``scene_against``, default ``scene``, is B's: a deliberately changed
    scene); ``integrator``/``against`` are names or dictionaries. Seeds:
    A renders with 2 seed, B with 2 seed + 1 (recorded). ``budget`` is each
    render's time in seconds; ``seconds_per_spp`` skips the calibration.
    ``spp`` renders both at that many samples per pixel instead (equal
    samples, no calibration): the verdict is then a function of the seeds
    alone, the same on every machine. ``defaults`` set an XML scene's
    ``<default>`` parameters (``-D key=value``).
    Returns a JSON-ready dictionary: ``passed``, ``summary``, ``a``, ``b``
    (spp, seed, times, MSE, efficiency), ``efficiency_ratio`` (A over B),
    ``seconds_per_spp`` and the :class:`mcrt.stats.Comparison` under
    ``comparison`` (not JSON: popped by the command line).
    """
    from mcrt.stats import compare

    scene_b = scene if scene_against is None else scene_against
    if spp is not None:
        spp_a = spp_b = spp
        seconds_per_spp = None
    else:
        if seconds_per_spp is None:
            seconds_per_spp = (calibrate(scene, integrator, spp=calibration_spp, res=res, backend=backend, defaults=defaults),
                               calibrate(scene_b, against, spp=calibration_spp, res=res, backend=backend,
                                         defaults=defaults))
        spp_a, spp_b = spp_for(budget, seconds_per_spp[0], integrator), spp_for(budget, seconds_per_spp[1], against)
    a = _render(scene, integrator, spp_a, 2 * seed, res, backend, defaults)
    b = _render(scene_b, against, spp_b, 2 * seed + 1, res, backend, defaults)
    c = compare(a, b, policy="independent", alpha=alpha, tile=tile)
    da, db = _describe(a, integrator), _describe(b, against)
    return {
        "passed": bool(c.passed),
        "summary": c.summary(),
        "policy": "independent",
        "budget": None if spp is not None else budget,
        "seconds_per_spp": list(seconds_per_spp) if seconds_per_spp else None,
        "a": da,
        "b": db,
        "efficiency_ratio": da["efficiency"] / db["efficiency"],
        "same_scene": a.scene_hash == b.scene_hash,
        "comparison": c,
        "images": (a, b),
    }


def _study(scene, integrator, againsts, wrongs, *, seeds: int, budget: float, res, alpha, tile, backend, out: Path,
           command: str, log) -> dict[str, Any]:
    """Every --against and --wrong validated with ``seeds`` seed pairs; rejection rates with 95 % intervals."""
    from mcrt.compare import write_heatmap
    from mcrt.provenance import provenance
    from mcrt.stats import binomial_interval

    t0 = time.perf_counter()
    cal_a = calibrate(scene, integrator, res=res, backend=backend)
    rows = []
    for spec, kind in [(s, "consistent") for s in againsts] + [(s, "wrong") for s in wrongs]:
        cal_b = calibrate(scene, spec, res=res, backend=backend)
        rejected, ratios, first = 0, [], None
        for s in range(1, seeds + 1):
            r = validate_integrator(scene, integrator, spec, budget=budget, seed=s, res=res, alpha=alpha, tile=tile,
                                    backend=backend, seconds_per_spp=(cal_a, cal_b))
            rejected += not r["passed"]
            ratios.append(r["efficiency_ratio"])
            if first is None:
                first = r
                write_heatmap(r["comparison"], out / f"heatmap_{_label(spec).replace(':', '_').replace(',', '_')}.png",
                              scale=max(1, 256 // r["comparison"].shape[1]))
        lo, hi = binomial_interval(rejected, seeds)
        row = {"against": _label(spec), "expected": kind, "seeds": seeds, "rejected": rejected, "rate": rejected / seeds,
               "interval_95": [lo, hi], "spp_a": first["a"]["spp"], "spp_b": first["b"]["spp"],
               "efficiency_ratio_median": float(np.median(ratios)), "seconds_per_spp": [cal_a, cal_b]}
        rows.append(row)
        print(f"{_label(integrator)} against {row['against']} ({kind}): {rejected} of {seeds} rejected "
              f"({100 * row['rate']:.1f} %, 95 % CI {100 * lo:.1f}-{100 * hi:.1f} %), "
              f"{row['spp_a']} against {row['spp_b']} spp, efficiency ratio {row['efficiency_ratio_median']:.3g}", file=log)
    data = {"schema": "mcrt.validate_integrator.report/1", "command": command,
            "provenance": provenance(command=command), "integrator": _label(integrator), "alpha": alpha, "tile": tile,
            "budget_seconds": budget, "resolution": res, "seeds": seeds, "rows": rows,
            "elapsed_seconds": time.perf_counter() - t0}
    out.mkdir(parents=True, exist_ok=True)
    (out / "data.json").write_text(json.dumps(data, indent=1))
    (out / "index.md").write_text(_markdown(data))
    return data


def _markdown(d: dict[str, Any]) -> str:
    res = f"{d['resolution']}x{d['resolution']}" if d["resolution"] else "the scene's resolution"
    lines = [
        f"# Validating Mitsuba integrators against `{d['integrator']}`: false alarms and detection",
        "",
        f"Written by `{d['command']}` ({d['provenance']['date']}, {d['provenance']['machine']['cpu']}, "
        f"Mitsuba {d['provenance']['versions']['mitsuba']}).",
        "",
        f"Each row validates `{d['integrator']}` (A) against another integrator (B) on Mitsuba's Cornell box "
        f"(`mitsuba.cornell_box()`, {res}, box pixel filter) with {d['seeds']} seed pairs, each render given "
        f"{d['budget_seconds']:g} s (equal time, calibrated once per integrator), compared with the Welch tile test "
        f"({d['tile']}x{d['tile']} tiles, rgb, Holm at FWER {d['alpha']:g}, policy independent). "
        "Where both integrators are correct every rejection is a false alarm: the rate should be at most "
        f"{d['alpha']:g}. Rows marked *wrong* are deliberately wrong configurations: there the rate is the power.",
        "",
        "| B | expected | spp A / B | rejected | rate | 95 % interval | efficiency A / B (median) |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in d["rows"]:
        lo, hi = r["interval_95"]
        lines.append(f"| `{r['against']}` | {r['expected']} | {r['spp_a']} / {r['spp_b']} | {r['rejected']} of {r['seeds']} "
                     f"| {100 * r['rate']:.1f} % | {100 * lo:.1f}-{100 * hi:.1f} % | {r['efficiency_ratio_median']:.3g} |")
    lines += [
        "",
        "Efficiency is 1 / (MSE x time) with the MSE of an unbiased renderer, mean(per-sample variance) / spp, and the "
        "render's time without JIT compilation. ptracer is rendered in 32 batches whose spread gives its variance; "
        "the tile test ignores the correlation between pixels that one particle path creates, and ptracer cannot see "
        "delta surfaces through the camera (the Cornell box has none). Heat maps of the first seed: `heatmap_*.png`.",
        "",
        f"Run time: {d['elapsed_seconds']:.0f} s.",
        "",
    ]
    return "\n".join(lines)


def register(sub) -> None:
    p = sub.add_parser("validate-integrator",
                       help="render a Mitsuba scene with two integrators at equal time and test that they agree "
                            "(exit 0 consistent, 1 different, 2 unusable)",
                       description=__doc__.split("\n\n")[1], formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", help="a Mitsuba XML scene file, or cornell-box (mitsuba.cornell_box())")
    p.add_argument("--integrator", default="path",
                   help="integrator A, the one under test: a plugin name, or NAME:key=value,... (default: path)")
    p.add_argument("--against", action="append", default=None,
                   help="integrator B, as --integrator (repeatable with --seeds; default: volpath)")
    p.add_argument("--wrong", action="append", default=[],
                   help="with --report: a configuration known to differ from A (e.g. path:max_depth=7), reported as "
                        "detection rate (repeatable; default: none)")
    p.add_argument("--budget", type=float, default=2.0, help="seconds per render, for equal time (default: 2.0)")
    p.add_argument("--spp", type=int, default=None,
                   help="render both at this many samples per pixel instead of at equal time: the verdict is then "
                        "a function of the seeds alone (one run, not with --seeds; default: equal time)")
    p.add_argument("--res", type=int, default=None, help="square resolution N x N (default: the scene's film)")
    p.add_argument("--seed", type=int, default=1, help="A renders with seed 2 SEED, B with 2 SEED + 1 (default: 1)")
    p.add_argument("--alpha", type=float, default=0.01, help="family-wise error rate of the tile tests, Holm (default: 0.01)")
    p.add_argument("--tile", type=int, default=8, help="tile edge in pixels (default: 8)")
    p.add_argument("--backend", choices=("llvm", "cuda"), default="llvm", help="Dr.Jit backend (default: llvm)")
    p.add_argument("-D", dest="define", action="append", default=[], metavar="KEY=VALUE",
                   help="set a <default> parameter of the XML scene (repeatable; default: the file's values)")
    p.add_argument("--heatmap", default=None, help="write the heat map of t (PNG) here (default: none)")
    p.add_argument("--json", default=None, help="write the result (seeds, spp, times, verdict, efficiency) as JSON here "
                                                "(default: none)")
    p.add_argument("--seeds", type=int, default=0,
                   help="with --report: validate with this many seed pairs and report rejection rates (default: 0, one run)")
    p.add_argument("--report", default=None, help="with --seeds: write data.json, index.md and heat maps to this folder "
                                                  "(default: none)")
    p.set_defaults(func=cmd_validate_integrator)


def cmd_validate_integrator(args) -> int:
    from mcrt.compare import report_lines, write_heatmap

    argv = getattr(args, "argv", None)
    command = "mcrt " + shlex.join(argv if argv is not None else sys.argv[1:])
    try:
        scene = load_scene_arg(args.scene)
        integrator = parse_integrator(args.integrator)
        againsts = [parse_integrator(a) for a in (args.against or ["volpath"])]
        wrongs = [parse_integrator(a) for a in args.wrong]
        if (args.seeds > 0) != (args.report is not None):
            raise ValueError("--seeds N and --report DIR go together")
        if args.seeds == 0 and (len(againsts) > 1 or wrongs):
            raise ValueError("several --against or a --wrong need --seeds N --report DIR")
        if args.define and args.seeds:
            raise ValueError("-D applies to a single run (not with --seeds)")
        if args.spp is not None and (args.seeds or args.spp < 1):
            raise ValueError("--spp needs a positive count and a single run (no --seeds)")
    except ValueError as e:
        print(f"mcrt validate-integrator: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    if args.seeds:
        data = _study(scene, integrator, againsts, wrongs, seeds=args.seeds, budget=args.budget, res=args.res,
                      alpha=args.alpha, tile=args.tile, backend=args.backend, out=Path(args.report), command=command,
                      log=sys.stdout)
        print(f"wrote {args.report}/index.md and data.json")
        return EXIT_OK
    try:
        r = validate_integrator(scene, integrator, againsts[0], budget=args.budget, seed=args.seed, res=args.res,
                                alpha=args.alpha, tile=args.tile, backend=args.backend, spp=args.spp,
                                defaults=parse_defines(args.define))
    except (ValueError, RuntimeError) as e:
        print(f"mcrt validate-integrator: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    c = r.pop("comparison")
    r.pop("images")
    for side in ("a", "b"):
        d = r[side]
        print(f"{side.upper()}: {d['integrator']}: {d['spp']} spp, seed {d['seed']}, max depth {d['max_depth']}, "
              f"{d['time']:.2f} s (+ {d['compile_time'] or 0:.2f} s compilation), MSE {d['mse']:.3g}")
    for line in report_lines(c):
        print(line)
    print(f"efficiency 1/(MSE x time), A over B: {r['efficiency_ratio']:.3g} (MSE = per-pixel variance / spp, "
          "valid for unbiased renderers)")
    r["command"] = command
    r["comparison"] = c.to_dict()
    if args.heatmap:
        print(f"heat map: {write_heatmap(c, args.heatmap, scale=max(1, 256 // c.shape[1]))}")
    if args.json:
        path = Path(args.json)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(r, indent=1))
        print(f"report: {path}")
    return EXIT_OK if r["passed"] else EXIT_FAILED
