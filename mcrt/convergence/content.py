"""The report's content as a list of format-neutral blocks, rendered by markdown.py and html.py.

Blocks are tuples:
``("h", level, text)``, ``("p", text)``, ``("ul", [text, ...])``,
``("table", header, rows)``, ``("img", file, alt)``, ``("link", file, text)``, ``("code", text)``,
``("details", summary, [blocks])``. Text is plain (each renderer escapes it);
a ``**bold**`` prefix is the only markup.
"""

from __future__ import annotations

import math
from typing import Any

from mcrt.convergence.data import CONVENTIONS
from mcrt.convergence.run import ReportData
from mcrt.convergence.summary import Summary

Block = tuple


def fmt(x: Any, sig: int = 4) -> str:
    if x is None:
        return "-"
    if isinstance(x, bool):
        return str(x)
    if isinstance(x, int):
        return str(x)
    if isinstance(x, float):
        if not math.isfinite(x):
            return "-" if math.isnan(x) else ("inf" if x > 0 else "-inf")
        if x == 0:
            return "0"
        if 1e-3 <= abs(x) < 1e5:
            return f"{x:.{sig}g}"
        return f"{x:.{sig - 1}e}"
    return str(x)


def pm(mean: float, sd: float, sig: int = 3) -> str:
    if not math.isfinite(mean):
        return "-"
    return f"{fmt(mean, sig)} ± {fmt(sd, 2)}" if sd and math.isfinite(sd) else fmt(mean, sig)


def _fit_text(f) -> str:
    if not math.isfinite(f.slope):
        return "-"
    if not math.isfinite(f.ci_low):
        return f"{f.slope:.3f}"
    return f"{f.slope:.3f} [{f.ci_low:.3f}, {f.ci_high:.3f}]"


def build_document(data: ReportData, s: Summary, files: dict[str, Any]) -> list[Block]:
    cfg = data.config
    ref = data.reference_info
    doc: list[Block] = [("h", 1, f"Convergence report: {cfg.name}")]
    if cfg.description:
        doc.append(("p", cfg.description))
    doc.append(("p", (
        f"Scene {data.scene.name} (hash {data.scene.content_hash()}), camera {cfg.camera}, {cfg.width}x{cfg.height} pixels, "
        f"max depth {cfg.max_depth}, renderers {', '.join(sp.label for sp in data.specs)}"
        + (f" (mcrt/plugin shadow rays K = {cfg.light_samples} unless given)" if any(sp.kind != 'mitsuba' and sp.light_samples is None for sp in data.specs) else "")
        + f", spp ladder {', '.join(map(str, cfg.spp_ladder))}, seeds {', '.join(map(str, cfg.seeds))}, backend {cfg.backend}. "
        f"Rendering and measuring took {data.runtime:.0f} s on {data.provenance['machine']['cpu']} "
        f"({data.provenance['machine']['cores']} cores)."
    )))
    what = {"mcrt": "the standalone Dr.Jit tracer (next-event estimation with K shadow rays per diffuse vertex)",
            "mitsuba": "Mitsuba 3's path integrator (MIS between light and BSDF sampling, one light sample per vertex)",
            "plugin": "mcrt's estimator as a Mitsuba integrator plugin (Mitsuba's scene, sensor and sampler)"}
    kinds = list(dict.fromkeys(sp.kind for sp in data.specs))
    doc.append(("p", "Renderers: " + "; ".join(", ".join(sp.label for sp in data.specs if sp.kind == k) + f": {what[k]}" for k in kinds) + "."))
    committed = ref["source"] == "committed"
    doc.append(("p", ("Reference: " if committed else "**Reference (not the committed ground truth)**: ") + ref["description"]
                + (f". Its own noise adds {fmt(data.floor['mse'])} to every MSE (RMSE {fmt(math.sqrt(data.floor['mse']))}); "
                   "the efficiency figures subtract it." if data.floor.get("known") else ".")))
    if cfg.equal_time:
        lead = data.specs[0].label
        cal = "; ".join(f"{k}: {v['time_per_spp'] * 1000:.1f} ms per spp" for k, v in data.calibration.items())
        doc.append(("p", f"Equal-time mode: {lead} renders the ladder; every other renderer renders, at each rung, the spp that "
                         f"takes it the same time, from a calibration render of {cfg.probe_spp()} spp each ({cal})."))

    doc.append(("h", 2, "Key numbers"))
    doc.append(("ul", s.verdicts))
    header = ["renderer", "RMSE vs spp", "RMSE (ref. noise removed) vs spp", "relMSE vs spp", "1 - SSIM vs spp", "FLIP vs spp", "RMSE vs time"]
    rows = []
    for sp in data.specs:
        f = s.fits[sp.label]
        rows.append([sp.label, _fit_text(f["rmse"]["spp"]), _fit_text(f["rmse_excess"]["spp"]), _fit_text(f["relmse"]["spp"]),
                     _fit_text(f["dssim"]["spp"]), _fit_text(f["flip"]["spp"]), _fit_text(f["rmse"]["time"])])
    doc.append(("p", "Fitted log-log slopes with 95 % confidence intervals (every render a point). "
                     "An unbiased estimator has RMSE slope -1/2 and relMSE slope -1 against spp."))
    doc.append(("table", header, rows))
    header = ["renderer", "efficiency 1/(MSE x s)", "from own variance", f"ratio to {s.baseline}", "ratio per seed", "rungs used (spp)"]
    rows = []
    for sp in data.specs:
        e = s.efficiency[sp.label]
        r = s.ratios.get(sp.label)
        rows.append([sp.label, fmt(e["efficiency"]), fmt(e["efficiency_predicted"]), fmt(r["ratio"], 3) if r else "1 (baseline)",
                     ", ".join(fmt(x, 3) for x in r["per_seed"]) if r else "-", ", ".join(map(str, e["rungs"]))])
    doc.append(("p", "Efficiency = 1 / (MSE x render time), pooled over the upper half of the ladder (see conventions); "
                     "'from own variance' uses each render's estimate of its expected MSE, mean(per-sample variance) / spp, "
                     "instead of its error against the reference."))
    doc.append(("table", header, rows))

    if s.equal_time:
        labels = [sp.label for sp in data.specs]
        header = ["rung"] + [f"{lab}: {what}" for lab in labels for what in ("spp", "time [s]", "MSE (excess)", "FLIP")]
        rows = []
        for e in s.equal_time:
            row = [str(e["rung"])]
            for lab in labels:
                v = e.get(lab)
                row += [str(v["spp"]), fmt(v["time"], 3), fmt(v["mse_excess"]), fmt(v["flip"], 3)] if v else ["-"] * 4
            rows.append(row)
        doc.append(("h", 2, "Equal time"))
        doc.append(("table", header, rows))

    doc.append(("h", 2, "Error against samples and against time"))
    for key, alt in (("error_vs_spp", "RMSE, relMSE, 1 - SSIM and FLIP against samples per pixel"),
                     ("error_vs_time", "RMSE, relMSE, 1 - SSIM and FLIP against render time"),
                     ("efficiency", "efficiency 1/(MSE x time) and ratio between renderers")):
        doc.append(("img", files["plots"][key]["png"].name, alt))
        if "svg" in files["plots"][key]:
            doc.append(("link", files["plots"][key]["svg"].name, "vector version (SVG)"))

    doc.append(("h", 2, "Images"))
    doc.append(("img", files["images"]["images"].name, "renders at a few spp beside the reference"))
    doc.append(("img", files["images"]["flip"].name, "HDR-FLIP error maps"))
    doc.append(("img", files["images"]["relerr"].name, "per-pixel relative squared error maps"))

    doc.append(("h", 2, "Per rung (mean ± sd over seeds)"))
    header = ["renderer", "spp", "seeds", "time [s]", "RMSE", "relMSE", "SSIM", "FLIP", "MSE excess", "MSE from own variance", "efficiency"]
    rows = [[r["renderer"], str(r["spp"]), str(r["seeds"]), pm(r["time"], r["time_std"]), pm(r["rmse"], r["rmse_std"]),
             pm(r["relmse"], r["relmse_std"]), pm(r["ssim"], r["ssim_std"], 4), pm(r["flip"], r["flip_std"]),
             fmt(r["mse_excess"], 3), fmt(r["mse_predicted"], 3), fmt(r["efficiency"], 3)] for r in s.rows]
    doc.append(("table", header, rows))

    doc.append(("h", 2, "Metric conventions"))
    fp = data.flip_params
    conv = [f"{k}: {v}" for k, v in CONVENTIONS.items()]
    conv.append(f"FLIP settings used here: HDR mode, tone mapper {fp['tonemapper']}, {fp['ppd']:g} pixels per degree, "
                f"exposures {fp['startExposure']:.4f} to {fp['stopExposure']:.4f} stops in {fp['numExposures']} steps (from the reference).")
    conv.append("Image previews: linear RGB x 2^0, clipped to [0, 1], sRGB-encoded, 8 bits (mcrt.image_files.tonemap).")
    conv.append(f"Reference noise floor: MSE {fmt(data.floor['mse'])}, relMSE {fmt(data.floor['relmse'])}"
                + ("" if data.floor.get("known") else " (unknown: the reference has no variance; taken as 0)") + ".")
    conv.append("Render seeds: each (renderer, seed, spp) renders with its own seed, a hash of the three (column render_seed "
                "of table.csv), so rungs are independent renders, and the same seeds give the same numbers.")
    conv.append("Timing: one warm-up render per renderer (1 spp) compiles the kernels first; each render's JIT compile time "
                "(Dr.Jit kernel history) is recorded and subtracted from its wall time; renders synchronise before the clock stops.")
    doc.append(("ul", conv))

    doc.append(("h", 2, "Provenance"))
    p = data.provenance
    prov = [f"command: {p['command']}", f"date: {p['date']}", f"git commit: {p['git_commit']}, source hash {p['source_hash']}",
            f"machine: {p['machine']['cpu']}, {p['machine']['cores']} cores, {p['machine']['platform']}",
            f"backend: {p['backend']}, {p['drjit_threads']} Dr.Jit threads",
            "versions: " + ", ".join(f"{k} {v}" for k, v in p["versions"].items()),
            "warm-up (JIT compile): " + "; ".join(f"{k}: {v['wall_time']:.2f} s wall, {v['compile_time']:.2f} s compile" for k, v in data.warmup.items()),
            f"reference: {ref['description']}" + (f", sha256 {ref['sha256']}" if ref.get("sha256") else "")]
    doc.append(("ul", prov))

    header = ["renderer", "spp", "seed", "render seed", "wall [s]", "compile [s]", "time [s]", "RMSE", "relMSE", "SSIM", "FLIP", "MSE excess", "MSE own var."]
    rows = [[m.renderer, str(m.spp), str(m.seed), str(m.render_seed), fmt(m.wall_time), fmt(m.compile_time, 3), fmt(m.time),
             fmt(m.rmse), fmt(m.relmse), fmt(m.ssim, 5), fmt(m.flip), fmt(m.mse_excess), fmt(m.mse_predicted)] for m in data.measurements]
    doc.append(("details", f"Every render ({len(rows)}; also in table.csv and data.json)", [("table", header, rows)]))
    doc.append(("p", "Files: " + ", ".join(sorted(files["all"]))))
    return doc
