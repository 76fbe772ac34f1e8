"""``mcrt samplers``: plain against stratified pixel samples, with and without the bidirectional estimator.

The variants (:data:`VARIANTS`) are rendered by the tricks study's engine
(:func:`mcrt.tricks.study.run_study`: a ladder of spp, several seeds, plain
mcrt timed between each variant's renders, every render compared with the
committed Mitsuba reference under the ``reference-floor`` policy) at each
resolution asked for. On top of its numbers this study measures:

* efficiency against plain mcrt at equal time, by MSE and by relMSE, two
  ways: from the error against the reference less its noise floor
  (:func:`mcrt.tricks.verdicts.ratio`), and from the error the renders
  themselves estimate (the mean of variance / spp, and its relMSE analogue
  with the reference as the scale), which the reference's noise does not
  limit: for unbiased renders both estimate the same MSE;
* the error at the light's edge: the pixels that see the emitter directly
  over part of their area (coverage between :data:`EDGE` and 1 - EDGE in a
  depth-1 render, whose pixel value is the light's radiance times the
  covered fraction), their RMSE and their share of the MSE, and the same
  for the rest of the image: where the remaining error sits.

Writes index.md, data.json and figures into ``--out``. Measured figures live
in that report, nowhere else.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from mcrt.exitcodes import EXIT_OK, EXIT_UNUSABLE
from mcrt.tricks.variants import PLAIN, Variant

#: Coverage below which (and above 1 - EDGE) a pixel does not count as on the light's edge.
EDGE = 0.02
#: Samples per pixel of the depth-1 render that measures each pixel's coverage of the light.
COVERAGE_SPP = 1024


@dataclass(frozen=True)
class _Recorded(Variant):
    """A variant that keeps, per spp, each render's mean image and its own error estimates (for the per-pixel study)."""

    sink: dict = field(default_factory=dict, compare=False, hash=False, repr=False)

    def render(self, scene, settings, seed, **kw):
        if self.options.get("pixel_sampler") == "sobol" and settings.spp % 8:
            settings = replace(settings, spp=16)  # the study's warm-up renders (2 spp) only compile: 8 replicates need 16
        r, adaptive = super().render(scene, settings, seed, **kw)
        self.sink.setdefault(settings.spp, []).append((r.mean.astype(np.float32), (r.variance / r.spp).astype(np.float32)))
        return r, adaptive


def variants() -> list[_Recorded]:
    """Plain mcrt, the sobol pixel sampler (8 replicates), bidirectional, the two together, and with the pilot's light budget."""
    return [
        _Recorded(PLAIN, "plain", "unbiased"),
        _Recorded("sobol pixels (8 replicates)", "samplers", "unbiased", {"pixel_sampler": "sobol"}),
        _Recorded("bidirectional", "samplers", "unbiased", {"bidirectional": True}),
        _Recorded("bidirectional + sobol pixels", "samplers", "unbiased", {"bidirectional": True, "pixel_sampler": "sobol"}),
        _Recorded("bidirectional + sobol, light budget from a pilot", "samplers", "unbiased",
                  {"bidirectional": True, "pixel_sampler": "sobol", "light_paths": "auto"}),
    ]


def edge_mask(scene, camera: str, res: int, max_depth: int = 1, *, backend: str = "llvm") -> tuple[np.ndarray, np.ndarray]:
    """(coverage, edge): each pixel's covered fraction of the light seen directly, and where it lies strictly inside (EDGE, 1 - EDGE)."""
    from mcrt.render import render

    s = scene.settings(camera=camera, width=res, height=res, spp=COVERAGE_SPP, max_depth=max_depth)
    r = render(scene, replace(s, seed=7), progress=False, backend=backend, pixel_sampler="sobol")
    le = float(np.max(scene.light.radiance))
    coverage = r.mean.astype(np.float64).max(axis=2) / le
    return coverage, (coverage > EDGE) & (coverage < 1 - EDGE)


def _own_errors(recs, ref_mean: np.ndarray, eps: float) -> tuple[float, float]:
    """Mean over renders of the MSE and relMSE the renders estimate themselves (variance / spp)."""
    w = 1.0 / (ref_mean.astype(np.float64) ** 2 + eps)
    return (float(np.mean([v.mean() for _, v in recs])), float(np.mean([(v * w).mean() for _, v in recs])))


def _region_errors(recs, ref_mean: np.ndarray, edge: np.ndarray, floor_map: np.ndarray) -> dict:
    """Per-pixel squared error over the renders (less the reference's noise), split into the light's edge and the rest."""
    se = np.mean([((m.astype(np.float64) - ref_mean) ** 2).mean(axis=2) for m, _ in recs], axis=0) - floor_map
    own = np.mean([v.astype(np.float64).mean(axis=2) for _, v in recs], axis=0)
    total, total_own = se.sum(), own.sum()
    out = {}
    for name, mask in (("edge", edge), ("rest", ~edge)):
        measurable = mask.any() and se[mask].mean() > 0  # not below the reference's own noise
        out[name] = {"pixels": int(mask.sum()), "rmse": float(np.sqrt(se[mask].mean())) if measurable else None,
                     "mse_share": float(se[mask].sum() / total) if measurable and total > 0 else None,
                     "own_rmse": float(np.sqrt(own[mask].mean())) if mask.any() else None,
                     "own_mse_share": float(own[mask].sum() / total_own) if total_own > 0 else None}
    top = np.sort(own.ravel())[::-1]
    out["top_1pct_own_share"] = float(top[: max(1, top.size // 100)].sum() / total_own) if total_own > 0 else None
    return out, own


def analyse(data, recorded: list[_Recorded], edge: np.ndarray) -> dict:
    """The study's numbers: per (variant, spp) the errors, the efficiency ratios both ways, the regions."""
    from mcrt import metrics as M
    from mcrt.groundtruth import load_reference
    from mcrt.tricks.verdicts import ratio, rungs_of

    cfg = data.config
    ref = load_reference(data.scene, cfg.camera, (cfg.res, cfg.res), cfg.max_depth)
    ref_mean = ref.mean.astype(np.float64)
    floor_map = (np.maximum(ref.variance.astype(np.float64), 0.0) / ref.spp).mean(axis=2)
    rows, maps = [], {}
    own_plain = {}
    for v in recorded:
        for r in rungs_of(data, v.label):
            recs = v.sink.get(r.spp, [])
            own_mse, own_rel = _own_errors(recs, ref_mean, M.RELMSE_EPS)
            if v.label == PLAIN:
                own_plain[r.spp] = (own_mse, own_rel)
            regions, own_map = _region_errors(recs, ref_mean, edge, floor_map)
            if r.spp == cfg.ladder[-1]:
                maps[v.label] = own_map
            rows.append({"label": v.label, "spp": r.spp, "time": r.time, "time_plain": r.time_plain, "rmse": r.rmse,
                         "relmse": r.relmse, "mse": r.mse, "variance_across_seeds": r.variance, "bias2": r.bias2,
                         "flagged": r.flagged, "seeds": r.seeds, "renders": len(recs),
                         "eff_mse_vs_reference": ratio(data, r, "mse"), "eff_relmse_vs_reference": ratio(data, r, "relmse"),
                         "own_mse": own_mse, "own_relmse": own_rel, "regions": regions})
    for row in rows:  # equal-time efficiency from the renders' own error estimates, paired times as above
        base = own_plain[row["spp"]]
        row["eff_mse_own"] = base[0] * row["time_plain"] / (row["own_mse"] * row["time"])
        row["eff_relmse_own"] = base[1] * row["time_plain"] / (row["own_relmse"] * row["time"])
    return {"rows": rows, "maps": maps, "reference_floor": data.floor, "reference_spp": data.reference_spp}


def _fmt(x, spec=".3g") -> str:
    return "-" if x is None or (isinstance(x, float) and not np.isfinite(x)) else format(x, spec)


def _best(rows: list[dict], spp: int) -> dict | None:
    """The unbiased, unflagged variant with the largest smaller-of-two own efficiency ratios at ``spp``."""
    cands = [r for r in rows if r["spp"] == spp and r["label"] != PLAIN and 2 * r["flagged"] < r["seeds"]]
    return max(cands, key=lambda r: min(r["eff_mse_own"], r["eff_relmse_own"]), default=None)


def markdown(results: dict, *, command: str, prov: dict) -> list[str]:
    """index.md: what was run, the verdict against the issue's goal, the tables, where the error sits, the figures."""
    lines = ["# Stratified pixel samples against plain mcrt, with and without the bidirectional estimator", "",
             "Generated by `mcrt samplers`; do not edit by hand.", "",
             f"- Command: `{command}`", f"- Date: {prov['date']}; commit {prov.get('git_commit')}",
             f"- Machine: {prov['machine']['cpu']} ({prov['machine']['cores']} cores, shared with other work: "
             "times are paired with plain mcrt renders timed between each variant's)",
             f"- Versions: mcrt {prov['versions']['mcrt']}, Dr.Jit {prov['versions']['drjit']}, "
             f"Mitsuba {prov['versions']['mitsuba']}", ""]
    lines += ["How to read it: *efficiency* is 1 / (error x time); a ratio is a variant's over plain mcrt's at the same "
              "spp, with plain mcrt timed between the variant's renders (the machine is shared). Two error sources: "
              "*vs reference*, the MSE (relMSE) against the committed Mitsuba reference less the reference's own noise "
              "(it becomes unmeasurable once a render's error nears that noise); *own*, the MSE the renders estimate "
              "themselves, the mean of variance / spp (for sobol renders the replicates' variance), and for relMSE the "
              "same weighted by 1 / (ref^2 + 0.01). For unbiased renders both estimate the same expected error; "
              "*flagged* counts seeds whose comparison with the reference (8x8 and 32x32 tiles, policy "
              "reference-floor) rejected \"same image\". The light's *edge* is the pixels that see the emitter over "
              f"part of their area (coverage in ({EDGE}, {1 - EDGE}) in a depth-1 render).", ""]
    for res, block in results.items():
        rows = block["rows"]
        top = max(r["spp"] for r in rows)
        best = _best(rows, top)
        lines += [f"## {res}x{res}, camera {block['camera']}, max depth {block['max_depth']}", ""]
        if best is not None:
            goal_mse, goal_rel = best["eff_mse_own"] >= 3, best["eff_relmse_own"] >= 5
            lines += [f"**Best unbiased configuration at {top} spp: {best['label']}: {best['eff_mse_own']:.2f}x plain "
                      f"mcrt's equal-time efficiency by MSE and {best['eff_relmse_own']:.2f}x by relMSE (own error "
                      f"estimates; against the reference {_fmt(best['eff_mse_vs_reference'], '.2f')}x and "
                      f"{_fmt(best['eff_relmse_vs_reference'], '.2f')}x). Goal 3x by MSE: "
                      f"{'met' if goal_mse else 'not met'}; 5x by relMSE: {'met' if goal_rel else 'not met'}.**", ""]
        lines += [f"Reference: {block['reference']} ({block['reference_spp']} spp); its noise adds "
                  f"{block['reference_floor']['mse']:.3g} to every MSE. {block['edge_pixels']} of {res * res} pixels lie "
                  f"on the light's edge. Study time {block['runtime']:.0f} s.", ""]
        lines += ["| variant | spp | time [s] | time / plain | RMSE | relMSE | own MSE | own relMSE | eff. MSE (own) | "
                  "eff. relMSE (own) | eff. MSE (vs ref.) | eff. relMSE (vs ref.) | flagged |",
                  "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for r in rows:
            lines.append(f"| {r['label']} | {r['spp']} | {r['time']:.3g} | {r['time'] / r['time_plain']:.2f} | "
                         f"{r['rmse']:.3g} | {r['relmse']:.3g} | {r['own_mse']:.3g} | {r['own_relmse']:.3g} | "
                         f"{_fmt(r['eff_mse_own'], '.2f')} | {_fmt(r['eff_relmse_own'], '.2f')} | "
                         f"{_fmt(r['eff_mse_vs_reference'], '.2f')} | {_fmt(r['eff_relmse_vs_reference'], '.2f')} | "
                         f"{r['flagged']}/{r['seeds']} |")
        lines += ["", f"Where the error sits at {top} spp (own estimates, per pixel mean of variance / spp over the "
                  "channels; against the reference less its noise in brackets, '-' where that is below the "
                  "reference's own noise):", "",
                  "| variant | edge RMSE | edge share of MSE | rest RMSE | rest share | top 1 % of pixels' share |",
                  "|---|---|---|---|---|---|"]
        for r in (r for r in rows if r["spp"] == top):
            e, o = r["regions"]["edge"], r["regions"]["rest"]
            lines.append(f"| {r['label']} | {_fmt(e['own_rmse'])} ({_fmt(e['rmse'])}) | "
                         f"{_fmt(100 * e['own_mse_share'], '.1f')} % ({_fmt(100 * e['mse_share'] if e['mse_share'] is not None else None, '.1f')} %) | "
                         f"{_fmt(o['own_rmse'])} ({_fmt(o['rmse'])}) | {_fmt(100 * o['own_mse_share'], '.1f')} % | "
                         f"{_fmt(100 * r['regions']['top_1pct_own_share'], '.1f')} % |")
        if best is not None:
            e = best["regions"]["edge"]
            lines += ["", f"The remaining error of {best['label']} at {top} spp: {100 * e['own_mse_share']:.0f} % of its "
                      f"MSE in the {e['pixels']} pixels on the light's edge, {100 * best['regions']['top_1pct_own_share']:.0f} "
                      "% in the 1 % of pixels with the largest error; the map below shows the rest (the mirror sphere's "
                      "reflections and caustics, the ceiling)."]
        lines += ["", f"![RMSE against spp, relMSE against time](error_{res}.png)", "",
                  f"![per-pixel MSE (own estimate) at {top} spp, log scale, same scale in every panel](error_map_{res}.png)", ""]
    return lines


def plots(results: dict, out: Path) -> None:
    from mcrt.convergence.plots import COLORS, _plt, _save

    plt = _plt()
    for res, block in results.items():
        rows = block["rows"]
        labels = list(dict.fromkeys(r["label"] for r in rows))
        fig, axes = plt.subplots(1, 3, figsize=(14, 3.9))
        for i, label in enumerate(labels):
            rs = sorted((r for r in rows if r["label"] == label), key=lambda r: r["spp"])
            style = dict(color="k", lw=2.0) if label == PLAIN else dict(color=COLORS[(i - 1) % len(COLORS)], lw=1.2)
            axes[0].plot([r["spp"] for r in rs], [np.sqrt(r["own_mse"]) for r in rs], "o-", ms=3, label=label, **style)
            axes[0].plot([r["spp"] for r in rs], [r["rmse"] for r in rs], "x:", ms=4, **style)
            axes[1].plot([r["time"] for r in rs], [r["own_relmse"] for r in rs], "o-", ms=3, label=label, **style)
            axes[1].plot([r["time"] for r in rs], [r["relmse"] for r in rs], "x:", ms=4, **style)
            axes[2].plot([r["time"] for r in rs], [r["own_mse"] for r in rs], "o-", ms=3, label=label, **style)
        axes[0].axhline(np.sqrt(block["reference_floor"]["mse"]), color="0.6", ls="-.", lw=1, label="reference noise")
        for ax, (xl, yl) in zip(axes, (("samples per pixel", "RMSE"), ("render time [s]", "relMSE"),
                                       ("render time [s]", "MSE"))):
            ax.set_xscale("log"), ax.set_yscale("log"), ax.set_xlabel(xl), ax.set_ylabel(yl), ax.grid(True, which="both", lw=0.3)
        axes[0].legend(fontsize=7)
        fig.suptitle(f"{res}x{res}: solid, the renders' own error estimate; dotted, against the Mitsuba reference", fontsize=9)
        fig.tight_layout()
        _save(fig, out, f"error_{res}", False)
        maps = block.pop("maps")
        fig, axes = plt.subplots(1, len(maps), figsize=(3.3 * len(maps), 3.4), squeeze=False)
        vals = np.concatenate([m.ravel() for m in maps.values()])
        lo, hi = np.percentile(vals[vals > 0], 1), vals.max()
        from matplotlib.colors import LogNorm

        for ax, (label, m) in zip(axes[0], maps.items()):
            im = ax.imshow(np.maximum(m, lo), norm=LogNorm(lo, hi), cmap="magma")
            ax.set_title(label, fontsize=8), ax.set_xticks([]), ax.set_yticks([])
        fig.colorbar(im, ax=axes[0].tolist(), shrink=0.8)
        fig.savefig(out / f"error_map_{res}.png", dpi=110, bbox_inches="tight", metadata={"Software": None})
        plt.close(fig)  # not _save: its 256-colour palette would band a colour map


def run(*, resolutions: dict[int, tuple[int, ...]], seeds: int, camera: str = "near", max_depth: int = 8,
        backend: str = "llvm", progress: bool = True, log=print) -> dict:
    """Render and analyse every resolution's ladder; returns the JSON-ready results (maps kept for the plots)."""
    from mcrt.scene import load_scene
    from mcrt.tricks.study import StudyConfig, run_study

    scene = load_scene()
    results = {}
    for res, ladder in resolutions.items():
        t0 = time.perf_counter()
        recorded = variants()
        cfg = StudyConfig(camera=camera, res=res, max_depth=max_depth, ladder=tuple(ladder), seeds=seeds, backend=backend)
        data = run_study(scene, recorded, cfg, progress=progress, log=log)
        coverage, edge = edge_mask(scene, camera, res, backend=backend)
        block = analyse(data, recorded, edge)
        block.update(camera=camera, max_depth=max_depth, ladder=list(ladder), seeds=seeds, edge_pixels=int(edge.sum()),
                     reference=data.reference_key, runtime=time.perf_counter() - t0)
        results[res] = block
        log(f"mcrt samplers: {res}x{res} done in {block['runtime']:.0f} s")
    return results


def _resolutions(text: str) -> dict[int, tuple[int, ...]]:
    """'64:16,64,256;256:16,64' -> {64: (16, 64, 256), 256: (16, 64)}."""
    out = {}
    try:
        for part in text.split(";"):
            res, ladder = part.split(":")
            out[int(res)] = tuple(int(x) for x in ladder.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected RES:SPP,SPP,...;RES:..., got {text!r}") from None
    if any(s % 8 or s < 16 for ladder in out.values() for s in ladder):
        raise argparse.ArgumentTypeError(f"every spp must be a multiple of 8 (the sobol replicates) and >= 16, got {text!r}")
    return out


DEFAULT_RESOLUTIONS = "64:16,64,256,1024,4096;256:16,64,256,1024"


def _finite(x):
    """JSON-ready: NaN and infinities (a ratio without a measurable error) as None."""
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite(v) for v in x]
    if isinstance(x, float) and not np.isfinite(x):
        return None
    return x


def register(sub) -> None:
    p = sub.add_parser("samplers", help="plain against stratified pixel samples, with and without bidirectional (reports/samplers)",
                       description=__doc__.split("\n\n")[0] + " Measured at a ladder of spp per resolution against the "
                       "committed Mitsuba references; writes index.md, data.json and figures.")
    p.add_argument("--resolutions", type=_resolutions, default=_resolutions(DEFAULT_RESOLUTIONS), metavar="RES:SPP,...;...",
                   help=f"square resolutions and each one's spp ladder; a committed reference must exist (default: {DEFAULT_RESOLUTIONS})")
    p.add_argument("--seeds", type=int, default=4, help="independent renders per rung, at least 2 (default: 4)")
    p.add_argument("--camera", default="near", help="camera (default: near)")
    p.add_argument("--max-depth", type=int, default=8, help="longest path in segments (default: 8)")
    p.add_argument("--backend", choices=("llvm", "cuda"), default="llvm", help="Dr.Jit backend (default: llvm)")
    p.add_argument("--out", default="reports/samplers", help="report folder (default: reports/samplers)")
    p.add_argument("--quiet", action="store_true", help="no progress line (default: progress on stderr)")
    p.set_defaults(func=cmd_samplers)


def cmd_samplers(args) -> int:
    from mcrt.provenance import provenance

    if args.seeds < 2:
        print("mcrt samplers: --seeds must be at least 2 (the variance across seeds)", file=sys.stderr)
        return EXIT_UNUSABLE
    spec = ";".join(f"{r}:{','.join(map(str, ladder))}" for r, ladder in args.resolutions.items())
    command = (f"mcrt samplers --resolutions '{spec}' --seeds {args.seeds} --camera {args.camera} "
               f"--max-depth {args.max_depth} --out {args.out}")
    log = (lambda *a, **k: None) if args.quiet else (lambda *a, **k: print(*a, file=sys.stderr, **k))
    results = run(resolutions=args.resolutions, seeds=args.seeds, camera=args.camera, max_depth=args.max_depth,
                  backend=args.backend, progress=not args.quiet, log=log)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    plots(results, out)  # takes the maps out of the results
    prov = provenance(command=command, backend=args.backend)
    (out / "index.md").write_text("\n".join(markdown(results, command=command, prov=prov)) + "\n")
    doc = {"schema": "mcrt.samplers/1", "provenance": prov, "results": {str(k): v for k, v in results.items()}}
    (out / "data.json").write_text(json.dumps(_finite(doc), indent=1))
    print(f"wrote {out / 'index.md'}")
    return EXIT_OK
