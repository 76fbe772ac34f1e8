"""From the measurements to the report's numbers: means over seeds, slopes, efficiencies.

Efficiency is 1 / (MSE x time): the inverse of the work needed for a given
error (an unbiased estimator's MSE x time is constant once overheads are
amortised). MSE here is the excess over the reference's own noise floor
(see :data:`mcrt.convergence.data.CONVENTIONS`); time is render time (wall
minus JIT compile). A renderer's summary efficiency pools the upper half of
its ladder, where fixed costs per render matter least:

    efficiency = 1 / ( mean_r(spp_r x MSE_r) x mean_r(time_r / spp_r) )

over those rungs r (MSE_r and time_r: means over seeds), i.e. the inverse of
(per-sample variance x time per sample). Ratios divide two renderers'
summary efficiencies; "per seed" repeats the computation with one seed's
renders only, to show the spread.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mcrt.convergence.slopes import SlopeFit, fit_slope
from mcrt.convergence.run import METRICS, Measurement, ReportData

#: Metrics whose slopes are fitted (against spp and against time).
FIT_METRICS = ("rmse", "relmse", "dssim", "flip")
#: An RMSE slope this close to -1/2 is called practically right even when its
#: confidence interval (narrow with few points) excludes -1/2.
SLOPE_TOLERANCE = 0.05


@dataclass
class Summary:
    rows: list[dict[str, Any]]  # one per (renderer, rung)
    fits: dict[str, dict[str, dict[str, SlopeFit]]]  # label -> metric -> 'spp' | 'time' -> fit
    efficiency: dict[str, dict[str, Any]]  # label -> summary efficiency
    ratios: dict[str, dict[str, Any]]  # label -> efficiency ratio against the baseline
    baseline: str
    upper_rungs: list[int]
    equal_time: list[dict[str, Any]] = field(default_factory=list)  # per rung, in equal-time mode
    verdicts: list[str] = field(default_factory=list)


def _stats(values: list[float]) -> tuple[float, float]:
    a = np.asarray(values, dtype=np.float64)
    a = a[np.isfinite(a)]
    if a.size == 0:
        return float("nan"), float("nan")
    return float(a.mean()), float(a.std(ddof=1)) if a.size > 1 else 0.0


def _efficiency(ms: list[Measurement], rungs: list[int], key: str = "mse_excess") -> float:
    """1 / (mean_r(spp x MSE) x mean_r(time / spp)) over ``rungs`` (means over the seeds present)."""
    var, tps = [], []
    for r in rungs:
        sel = [m for m in ms if m.rung == r]
        if not sel:
            continue
        mse = float(np.mean([getattr(m, key) for m in sel]))
        t = float(np.mean([m.time for m in sel]))
        var.append(sel[0].spp * mse)
        tps.append(t / sel[0].spp)
    if not var:
        return float("nan")
    v, c = float(np.mean(var)), float(np.mean(tps))
    return 1.0 / (v * c) if v > 0 and c > 0 else float("nan")


def summarize(data: ReportData) -> Summary:
    cfg = data.config
    labels = [s.label for s in data.specs]
    by = {lab: [m for m in data.measurements if m.renderer == lab] for lab in labels}
    n_rungs = len(cfg.spp_ladder)
    upper = list(range(n_rungs // 2, n_rungs)) if n_rungs > 1 else [0]

    rows = []
    for lab in labels:
        for rung in range(n_rungs):
            sel = [m for m in by[lab] if m.rung == rung]
            if not sel:
                continue
            row: dict[str, Any] = {"renderer": lab, "rung": rung, "spp": sel[0].spp, "seeds": len(sel)}
            for key in ("time", "wall_time", "compile_time", "mse", "mse_excess", "mse_predicted", *METRICS, "ssim"):
                mu, sd = _stats([getattr(m, key) for m in sel])
                row[key], row[key + "_std"] = mu, sd
            mse_x = row["mse_excess"]
            row["efficiency"] = 1.0 / (mse_x * row["time"]) if mse_x > 0 and row["time"] > 0 else float("nan")
            row["efficiency_seeds"] = [1.0 / (m.mse_excess * m.time) if m.mse_excess > 0 else float("nan") for m in sel]
            rows.append(row)

    fits: dict[str, dict[str, dict[str, SlopeFit]]] = {}
    for lab in labels:
        ms = by[lab]
        fits[lab] = {}
        for key in FIT_METRICS:
            y = [getattr(m, key) for m in ms]
            fits[lab][key] = {"spp": fit_slope([m.spp for m in ms], y), "time": fit_slope([m.time for m in ms], y)}
        y = [math.sqrt(m.mse_excess) if m.mse_excess > 0 else float("nan") for m in ms]
        fits[lab]["rmse_excess"] = {"spp": fit_slope([m.spp for m in ms], y), "time": fit_slope([m.time for m in ms], y)}

    base = cfg.baseline_spec().label
    eff: dict[str, dict[str, Any]] = {}
    for lab in labels:
        ms = by[lab]
        per_seed = [_efficiency([m for m in ms if m.seed == s], upper) for s in cfg.seeds]
        eff[lab] = {
            "efficiency": _efficiency(ms, upper),
            "efficiency_predicted": _efficiency(ms, upper, "mse_predicted"),
            "per_seed": per_seed,
            "rungs": [ms_spp for ms_spp in sorted({m.spp for m in ms if m.rung in upper})],
        }
    ratios: dict[str, dict[str, Any]] = {}
    for lab in labels:
        if lab == base:
            continue
        e, b = eff[lab], eff[base]
        per_seed = [x / y if y and math.isfinite(x) and math.isfinite(y) else float("nan") for x, y in zip(e["per_seed"], b["per_seed"])]
        per_rung = []
        for rung in range(n_rungs):
            ra = next((r for r in rows if r["renderer"] == lab and r["rung"] == rung), None)
            rb = next((r for r in rows if r["renderer"] == base and r["rung"] == rung), None)
            if ra and rb:
                per_rung.append({"rung": rung, "spp": ra["spp"], "baseline_spp": rb["spp"],
                                 "ratio": ra["efficiency"] / rb["efficiency"] if rb["efficiency"] else float("nan")})
        ratios[lab] = {
            "vs": base,
            "ratio": e["efficiency"] / b["efficiency"] if b["efficiency"] else float("nan"),
            "ratio_predicted": e["efficiency_predicted"] / b["efficiency_predicted"] if b["efficiency_predicted"] else float("nan"),
            "per_seed": per_seed,
            "per_rung": per_rung,
        }

    s = Summary(rows=rows, fits=fits, efficiency=eff, ratios=ratios, baseline=base, upper_rungs=upper)
    if cfg.equal_time:
        for rung in range(n_rungs):
            entry = {"rung": rung}
            for lab in labels:
                r = next((r for r in rows if r["renderer"] == lab and r["rung"] == rung), None)
                if r:
                    entry[lab] = {k: r[k] for k in ("spp", "time", "mse", "mse_excess", "mse_predicted", "rmse", "relmse", "flip", "dssim")}
            s.equal_time.append(entry)
    s.verdicts = _verdicts(data, s)
    return s


def _verdicts(data: ReportData, s: Summary) -> list[str]:
    out = []
    for lab, per in s.fits.items():
        raw, ex = per["rmse"]["spp"], per["rmse_excess"]["spp"]
        if not math.isfinite(raw.slope):
            continue
        text = f"{lab}: RMSE falls as spp^{raw.slope:.3f} (95 % CI [{raw.ci_low:.3f}, {raw.ci_high:.3f}])"
        f = raw
        if data.floor.get("known") and data.floor["mse"] > 0 and math.isfinite(ex.slope):
            # The estimator's own convergence: the reference's noise (a floor under every MSE) removed.
            text += f", with the reference's noise removed spp^{ex.slope:.3f} ([{ex.ci_low:.3f}, {ex.ci_high:.3f}])"
            f = ex
        if f.contains(-0.5):
            out.append(text + ": consistent with the expected -1/2.")
        elif abs(f.slope + 0.5) <= SLOPE_TOLERANCE:
            out.append(text + f": within {SLOPE_TOLERANCE:g} of -1/2, though its 95 % interval excludes -1/2 "
                       "(few rungs or seeds, or an imperfect estimate of the reference's noise).")
        else:
            out.append(text + ": NOT consistent with -1/2.")
    for lab, r in s.ratios.items():
        if not math.isfinite(r["ratio"]):
            out.append(f"{lab} vs {r['vs']}: efficiency ratio not measurable (MSE not above the reference's noise).")
            continue
        seeds = [x for x in r["per_seed"] if math.isfinite(x)]
        spread = f" (per seed {min(seeds):.2f} to {max(seeds):.2f})" if len(seeds) > 1 else ""
        pred = f"; from the renders' own variance estimates {r['ratio_predicted']:.2f}" if math.isfinite(r["ratio_predicted"]) else ""
        out.append(f"efficiency {lab} / {r['vs']} = {r['ratio']:.2f}{spread}{pred}: "
                   + (f"{lab} reaches a given MSE in {1 / r['ratio']:.2f}x the time {r['vs']} needs."))
    cfg = data.config
    if cfg.equal_time and len(data.specs) >= 2:
        lead, other = data.specs[0].label, s.baseline
        if lead != other and lead in s.ratios:
            r = s.ratios[lead]
            last = s.equal_time[-1]
            a, b = last.get(lead), last.get(other)
            if a and b:
                worth = r["ratio"] > 1
                agree = (r["ratio_predicted"] > 1) == worth if math.isfinite(r["ratio_predicted"]) else True
                out.append(
                    f"Equal time: {lead} at {a['spp']} spp took {a['time']:.1f} s for MSE {a['mse_excess']:.4g}; "
                    f"{other} at {b['spp']} spp took {b['time']:.1f} s for MSE {b['mse_excess']:.4g}. "
                    + (f"Answer: yes, {lead} is worth it ({r['ratio']:.2f}x as efficient)." if worth else
                       f"Answer: no, {lead} is not worth it ({other} is {1 / r['ratio']:.2f}x as efficient).")
                    + ("" if agree else " (The renders' own variance estimates disagree: treat as a tie.)")
                )
    return out
