"""reports/tricks/: index.md (verdicts, tables, figures) and data.json (every number, the command, provenance)."""

from __future__ import annotations

import math
from dataclasses import asdict
from pathlib import Path

from mcrt.convergence.content import fmt
from mcrt.convergence.markdown import write as write_markdown
from mcrt.tricks import plots
from mcrt.tricks.study import StudyData, measurement_dicts, rung_dicts
from mcrt.tricks.variants import PLAIN, TRICKS
from mcrt.tricks.verdicts import TRICK_NAMES, WORTH, denoiser_numbers, rungs_of, variant_row, verdicts
from mcrt.util.jsonsafe import json_safe, write_json

#: Schema tag of data.json.
SCHEMA = "mcrt.tricks/1"
#: Where ``mcrt tricks`` writes by default.
REPORT_DIR = Path("reports") / "tricks"

CONVENTIONS = {
    "time": "wall time less Dr.Jit's JIT compile time, after a warm-up render of each variant; denoised renders add "
            "OIDN's time and the first-hit buffers' tracing time; adaptive renders count every launch",
    "efficiency": "1 / (MSE_excess x time), MSE_excess = MSE - the reference's noise floor mean(var_ref / spp_ref); "
                  "the ratio is a variant's over plain mcrt's at the same spp, plain mcrt timed between the variant's "
                  "renders (paired: the machine is shared); also with relMSE and its floor",
    "bias2": "MSE - variance - floor, means over the seeds; variance = mean over pixels and channels of the image's "
             "variance across seeds (can come out negative by chance: no measurable bias)",
    "flagged": "seeds for which mcrt.stats.policy.compare against the reference, policy 'reference-floor', rejects "
               "'same image' at one of the tile sizes (Welch tile test, Holm, each tile size at alpha / their number); "
               "a denoised image keeps its noisy render's variance; an adaptive one its per-pixel variance of the mean, "
               "floored at the reference's at each pixel's own count; 'biased (measured)': flagged on at least half "
               "the seeds at the top rung",
    "worth": f"a trick's best variant: unbiased, not flagged, largest smaller-of-two efficiency ratios; worth it: both "
             f"ratios (MSE, relMSE) >= {WORTH}; not worth it: both <= 1/{WORTH}; a wash: both between; mixed otherwise. "
             "MSE weighs bright pixels most, relMSE weighs each pixel's error by its brightness",
}


#: What each trick's variants are (the method; the numbers are the tables').
METHODS = {
    "roulette": "mcrt's roulette survives with q = min(max throughput, 0.95) from depth 5 and divides by q. The "
                "variants move its start depth, fix q (still dividing: unbiased, but a survivor's weight grows by 1/q "
                "per vertex), switch it off, or use the 2023 course's scheme: absorb with 0.75 at every diffuse hit, "
                "survivors times 0.8, no division (biased), from depth 1, 3 or 5.",
    "adaptive": "Both spend spp samples per pixel on average. Naive: 8 samples per pixel, then rounds that double the "
                "samples of each pixel whose own samples still estimate a relative error above the target; the "
                "estimate averages all of them (Kirk and Arvo's bias). Two-stage: a pilot of spp / 8 decides each "
                "pixel's count (proportional to the square root of its relative variance); the estimate uses only "
                "the fresh samples that follow (unbiased). Times include every launch of the per-pixel sample sets.",
    "bidirectional": "mcrt's bidirectional estimator (mcrt.bidir): light tracing for the paths eye - diffuse ... - "
                     "mirror - light that next-event estimation cannot sample, the path tracer for the rest.",
    "denoise": "Intel Open Image Denoise 2.5 (pyoidn, CPU, RT filter, HDR, quality high) on plain mcrt's render, "
               "guided by first-hit albedo and normal buffers (16 jittered rays per pixel, through mirrors; their "
               "tracing time is added) or by the colour alone.",
    "light": "Next-event estimation samples the square light uniformly in area (weight proportional to 1 / d^2); "
             "the variants sample it uniformly in the solid angle it subtends (a spherical rectangle, Urena et al. "
             "2013; weight Le cos_x Omega) or take K = 4 area samples per diffuse vertex.",
}


def _scene_path(data: StudyData) -> str:
    """The scene file relative to the working folder where it lies below it (as the command was given)."""
    p = Path(data.scene.path)
    try:
        return p.resolve().relative_to(Path.cwd().resolve()).as_posix()
    except ValueError:
        return str(p)


def _trick_list(data: StudyData) -> list[str]:
    return [t for t in TRICKS if any(v.trick == t for v in data.variants)]


def _row_cells(row: dict) -> list[str]:
    return [row["label"], row["claim"], fmt(row["time"], 3), fmt(row["time_ratio"], 3), fmt(row["relmse"], 3),
            fmt(math.sqrt(row["mse"]), 3), fmt(row["efficiency_ratio"], 3), fmt(row["efficiency_ratio_relmse"], 3),
            f"{row['flagged']}/{row['seeds']}", fmt(row["detected_from"]),
            fmt(row["bias_share"], 2) if row["biased"] and row["bias_share"] > 0 else "-"]


ROW_HEADER = ["variant", "theory", "time [s]", "time / plain", "relMSE", "RMSE", "efficiency / plain",
              "efficiency / plain (relMSE)", "flagged", "detected from spp", "bias^2 / MSE"]


def _rung_table(data: StudyData, labels: list[str]) -> tuple[list[str], list[list[str]]]:
    header = ["variant", "spp", "time [s]", "plain time [s]", "relMSE", "RMSE", "variance", "bias^2", "efficiency", "flagged"]
    rows = []
    for label in labels:
        for r in rungs_of(data, label):
            rows.append([label, str(r.spp), fmt(r.time, 3), fmt(r.time_plain, 3), fmt(r.relmse, 3), fmt(r.rmse, 3), fmt(r.variance, 3),
                         fmt(r.bias2, 3), fmt(r.efficiency, 3), f"{r.flagged}/{r.seeds}"])
    return header, rows


def _light_table(rows: list[dict]) -> tuple[list[str], list[list[str]]]:
    header = ["receiver", "distance", "closed form E", "area: mean", "solid angle: mean (z)", "variance area / solid angle",
              "time per sample area / solid angle", "efficiency ratio"]
    out = []
    for r in rows:
        a, s = r["area"], r["solid_angle"]
        z = (s["mean"] - r["closed_form"]) / s["std_error"] if s["std_error"] > 0 else float("nan")
        out.append([r["receiver"], fmt(r["distance"], 3), fmt(r["closed_form"], 5), fmt(a["mean"], 5),
                    f"{fmt(s['mean'], 5)} ({z:+.1f})", fmt(r["variance_ratio"], 3),
                    fmt(a["seconds_per_sample"] / s["seconds_per_sample"], 3), fmt(r["efficiency_ratio"], 3)])
    return header, out


def _section(data: StudyData, trick: str, files: dict, line: str) -> list:
    labels = [v.label for v in data.variants if v.trick == trick]
    doc = [("h", 2, TRICK_NAMES[trick]), ("p", METHODS[trick]), ("p", f"**Verdict.** {line}")]
    doc.append(("table", ROW_HEADER, [_row_cells(variant_row(data, lab)) for lab in [PLAIN, *labels]]))
    if trick == "adaptive" and "spp_maps" in files:
        doc.append(("img", files["spp_maps"], "samples per pixel of each adaptive scheme"))
    if trick == "denoise":
        d = {lab: denoiser_numbers(data, lab) for lab in labels}
        doc.append(("table", ["variant", "relMSE plain / denoised per spp", "MSE plain / denoised per spp",
                              "bias^2 > variance from spp", "plain better (relMSE) from spp", "flagged from spp"],
                    [[lab, ", ".join(f"{k}: {fmt(v, 3)}" for k, v in n["relmse_ratio"].items()),
                      ", ".join(f"{k}: {fmt(v, 3)}" for k, v in n["mse_ratio"].items()),
                      fmt(n["bias_dominates_from"]), fmt(n["plain_better_from"]), fmt(n["detected_from"])]
                     for lab, n in d.items()]))
        doc.append(("img", files["bias"], "bias squared and variance against spp"))
    if trick == "light" and data.extra.get("light_receivers"):
        doc.append(("p", "Single receivers facing the light, direct-light estimate of one light sample (the estimator's "
                         "own light_sample, mcrt's host), both strategies with the same number of samples; z: the "
                         "solid-angle mean's distance from Lambert's closed form in standard errors."))
        doc.append(("table", *_light_table(data.extra["light_receivers"])))
        doc.append(("img", files["light_sampling"], "light sampling near and far"))
    if trick == "bidirectional" and "variance_distribution" in files:
        doc.append(("img", files["variance_distribution"], "distribution of per-pixel variance"))
    return doc


def _bidir_note(data: StudyData) -> list:
    if any(v.trick == "bidirectional" for v in data.variants):
        return []
    return [("h", 2, TRICK_NAMES["bidirectional"]),
            ("p", "Pending: the mcrt renderer has no option bidirectional=True in this checkout, so this run did not "
                  "render it; the same command includes it once the option exists.")]


def document(data: StudyData, command: str, prov: dict, lines: list[str], files: dict) -> list:
    cfg = data.config
    doc = [("h", 1, "The lecture's efficiency tricks, measured for speed against error"),
           ("p", "Generated by `mcrt tricks`; do not edit by hand."),
           ("ul", [f"Command: `{command}`", f"Date: {prov['date']}",
                   f"Versions: " + ", ".join(f"{k} {v}" for k, v in prov["versions"].items() if v),
                   f"Machine: {prov['machine']['cpu']} ({prov['machine']['cores']} cores), {prov['machine']['platform']}",
                   f"Commit: {prov['git_commit']}",
                   f"Scene: `{_scene_path(data)}` (hash {data.scene.content_hash()}), camera {cfg.camera}, "
                   f"{cfg.res}x{cfg.res}, max depth {cfg.max_depth}",
                   f"Reference: the committed Mitsuba reference {data.reference_key} ({data.reference_spp} spp); its "
                   f"noise floor {fmt(data.floor['mse'], 3)} is subtracted from every MSE in efficiencies",
                   f"Ladder: {', '.join(map(str, cfg.ladder))} spp, {cfg.seeds} seeds per rung, every render its own seed",
                   f"Comparison: mcrt.stats.policy.compare, policy reference-floor (adaptive renders: floored at each pixel's "
                   f"count), tiles {', '.join(map(str, cfg.tiles))}, each at alpha = {cfg.alpha} / {len(cfg.tiles)}",
                   f"Run time: {data.runtime:.0f} s"])]
    doc += [("h", 2, "Verdicts"), ("ul", lines)]
    doc += [("h", 2, "Conventions"), ("ul", [f"**{k}**: {v}" for k, v in CONVENTIONS.items()])]
    doc += [("h", 2, "Error against time and against samples"),
            ("img", files["error_vs_time"], "relMSE against render time"),
            ("img", files["error_vs_spp"], "RMSE against samples per pixel")]
    by_trick = dict(zip(_trick_list(data), lines))
    for trick in TRICKS:
        if trick in by_trick:
            doc += _section(data, trick, files, by_trick[trick])
        elif trick == "bidirectional":
            doc += _bidir_note(data)
    doc += [("h", 2, "Renders at the top rung (seed 0)"), ("img", files["images"], "renders")]
    doc.append(("details", "Every rung of every variant",
                [("table", *_rung_table(data, [v.label for v in data.variants]))]))
    return doc


def write_report(data: StudyData, out: Path, *, command: str, svg: bool = False) -> dict:
    """Write the figures, index.md and data.json into ``out``; returns {name: path}."""
    from mcrt.provenance import provenance

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    tricks = _trick_list(data)
    lines = verdicts(data, tricks)
    figs = {
        "error_vs_time": plots.error_panels(data, tricks, out, axis="time", svg=svg),
        "error_vs_spp": plots.error_panels(data, tricks, out, axis="spp", svg=svg),
        "bias": plots.bias_plot(data, [v.label for v in data.variants if v.claim == "biased"], out, svg=svg),
        "spp_maps": plots.spp_maps(data, out, svg=svg),
        "light_sampling": plots.light_plot(data.extra.get("light_receivers") or [], out, svg=svg),
        "variance_distribution": plots.variance_histogram(
            data, [PLAIN] + [v.label for v in data.variants if v.trick in ("bidirectional", "light")], out, svg=svg),
        "images": plots.image_strip(data, [v.label for v in data.variants], out),
    }
    files = {k: v["png"].name for k, v in figs.items() if v}
    prov = provenance(command=command, packages=("pyoidn",))
    write_markdown(out / "index.md", document(data, command, prov, lines, files))
    names = sorted([*files.values(), "index.md", "data.json"])
    write_json(out / "data.json", json_safe({
        "schema": SCHEMA, "command": command, "provenance": prov, "config": asdict(data.config),
        "scene": {"name": data.scene.name, "path": _scene_path(data), "hash": data.scene.content_hash()},
        "reference": {"key": data.reference_key, "spp": data.reference_spp, "floor": data.floor},
        "conventions": CONVENTIONS,
        "variants": [{"label": v.label, "trick": v.trick, "claim": v.claim, "options": v.options,
                      "light_samples": v.light_samples, "adaptive": v.adaptive, "denoise": v.denoise} for v in data.variants],
        "verdicts": lines, "rows": [variant_row(data, v.label) for v in data.variants],
        "denoiser": {v.label: denoiser_numbers(data, v.label) for v in data.variants if v.trick == "denoise"},
        "light_receivers": data.extra.get("light_receivers"), "aov_time_s": data.extra.get("aov_time"),
        "bidirectional_present": "bidirectional" in tricks,
        "rungs": rung_dicts(data), "measurements": measurement_dicts(data), "runtime_s": data.runtime, "files": names,
    }))
    return {n: out / n for n in names}
