"""The numbers each verdict rests on, and the one-line verdicts computed from them.

For a variant at a rung (spp):

- *efficiency ratio*: its 1 / (MSE_excess x time) over plain mcrt's at the
  same spp (> 1: it reaches a given error sooner), plain mcrt's time
  measured between the variant's renders (paired: the machine is shared);
  the same with relMSE, which weighs dark regions (the ceiling's
  fireflies) as much as bright ones;
- *flagged*: the seeds whose comparison with the reference
  (:func:`mcrt.stats.policy.compare`) rejected "same image";
- *detected from*: the smallest spp from which the comparison flags it on
  at least half the seeds at every rung;
- *bias share*: bias^2 / MSE.

A variant is *biased (measured)* when it is flagged on at least half the
seeds at the top rung. A trick's best variant is its unbiased one, not
flagged at the top rung, with the largest of the smaller of its two
efficiency ratios (by MSE, by relMSE); it is *worth it* when both reach
:data:`WORTH`, *not worth it* when both fall below 1 / WORTH, *a wash*
when both lie between, *mixed* otherwise. These thresholds are the
report's conventions, written into it.
"""

from __future__ import annotations

import math

from mcrt.tricks.study import Rung, StudyData
from mcrt.tricks.variants import PLAIN

#: Efficiency ratio above which a trick is worth it (and below whose inverse it is not).
WORTH = 1.2

TRICK_NAMES = {"roulette": "Russian roulette", "adaptive": "Early stopping (adaptive sampling)",
               "bidirectional": "Bidirectional", "denoise": "AI denoising (OIDN)", "light": "Explicit light sampling"}


def rungs_of(data: StudyData, label: str) -> list[Rung]:
    return sorted((r for r in data.rungs if r.label == label), key=lambda r: r.spp)


def ratio(data: StudyData, r: Rung, key: str = "mse", *, per_sample: bool = False) -> float:
    """Efficiency of ``r`` over plain mcrt's at the same spp: (excess_plain t_plain) / (excess t), paired times.

    ``key`` 'mse' or 'relmse'; the excess subtracts the reference's noise
    floor. ``per_sample``: at equal samples instead of equal time (the
    error ratio alone; what a trick gains before what it costs to run).
    """
    base = next(b for b in data.rungs if b.label == PLAIN and b.spp == r.spp)
    e_base, e = getattr(base, key) - data.floor[key], getattr(r, key) - data.floor[key]
    if e_base <= 0 or e <= 0:
        return float("nan")
    return e_base / e if per_sample else (e_base * r.time_plain) / (e * r.time)


def detected_from(rungs: list[Rung]) -> int | None:
    """The smallest spp from which at least half the seeds are flagged at every higher rung (None: not at the top)."""
    spp = None
    for r in reversed(rungs):
        if 2 * r.flagged < r.seeds:
            break
        spp = r.spp
    return spp


def variant_row(data: StudyData, label: str) -> dict:
    """Every number the variant's verdict uses, at the top rung unless said otherwise."""
    rs = rungs_of(data, label)
    top = rs[-1]
    v = next(x for x in data.variants if x.label == label)
    at_top = [m for m in data.measurements if m.label == label and m.spp == top.spp]
    return {
        "label": label, "trick": v.trick, "claim": v.claim, "spp": top.spp, "time": top.time, "mse": top.mse,
        "relmse": top.relmse, "efficiency_ratio": ratio(data, top), "efficiency_ratio_relmse": ratio(data, top, "relmse"),
        "time_ratio": top.time / top.time_plain, "per_sample_ratio": ratio(data, top, per_sample=True),
        "per_sample_ratio_relmse": ratio(data, top, "relmse", per_sample=True), "flagged": top.flagged, "seeds": top.seeds,
        "biased": 2 * top.flagged >= top.seeds, "detected_from": detected_from(rs),
        "rejected": sum(sum(m.rejected) for m in at_top), "rejected_darker": sum(m.rejected_darker for m in at_top),
        "whole_image": float(sum(m.whole_image for m in at_top) / len(at_top)),
        "confirm": (data.extra.get("confirm") or {}).get(label),
        "bias2": top.bias2, "bias_share": top.bias2 / top.mse if top.mse > 0 else float("nan"),
        "ratios": {r.spp: ratio(data, r) for r in rs},
    }


def _worth(row: dict) -> str:
    """Worth it when both efficiency ratios (MSE, relMSE) reach WORTH, not when both fall below 1 / WORTH."""
    a, b = row["efficiency_ratio"], row["efficiency_ratio_relmse"]
    if not (math.isfinite(a) and math.isfinite(b)):
        return "not measurable"
    if min(a, b) >= WORTH:
        return "worth it"
    if max(a, b) <= 1 / WORTH:
        return "not worth it"
    if 1 / WORTH < min(a, b) and max(a, b) < WORTH:
        return "a wash"
    return "mixed (one metric gains, the other loses)"


def _worst_case(row: dict) -> float:
    """The smaller of the two efficiency ratios (the trick's gain by the metric that favours it least)."""
    a, b = row["efficiency_ratio"], row["efficiency_ratio_relmse"]
    return min(a, b) if math.isfinite(a) and math.isfinite(b) else -1.0


def _bias_text(row: dict) -> str:
    if not row["biased"]:
        return f"no bias found ({row['flagged']}/{row['seeds']} seeds flagged at {row['spp']} spp)"
    share = row["bias_share"]
    share_text = f", bias^2 {100 * share:.0f} % of its MSE" if math.isfinite(share) and share > 0 else ""
    return f"biased: flagged from {row['detected_from']} spp ({row['flagged']}/{row['seeds']} at {row['spp']}){share_text}"


def _tails_text(row: dict) -> str:
    text = (f"{row['rejected_darker']} of its {row['rejected']} rejected tiles at {row['spp']} spp darker than the "
            f"reference, the whole image {100 * row['whole_image']:+.3f} % off")
    c = row["confirm"]
    if c:
        text += (f"; at {c['spp']} spp {'consistent' if c['passed'] else 'still flagged'} "
                 f"({sum(c['rejected'])} tiles rejected)")
    return text


def trick_verdict(data: StudyData, trick: str) -> str | None:
    """One line for one trick: its best unbiased variant's efficiency, what bias the comparison finds."""
    rows = [variant_row(data, v.label) for v in data.variants if v.trick == trick]
    if not rows:
        return None
    clean = [r for r in rows if not r["biased"] and r["claim"] == "unbiased"]
    biased = [r for r in rows if r["biased"] and r["claim"] == "biased"]
    parts = []
    if clean:
        best = max(clean, key=_worst_case)
        parts.append(f"best unbiased variant '{best['label']}': {best['efficiency_ratio']:.2f}x plain mcrt's efficiency "
                     f"by MSE and {best['efficiency_ratio_relmse']:.2f}x by relMSE at {best['spp']} spp (time "
                     f"{best['time_ratio']:.2f}x), {_worth(best)}")
    else:
        parts.append("no variant passes the comparison at the top rung")
    for r in biased:
        parts.append(f"'{r['label']}' {_bias_text(r)}")
    for r in rows:
        if r["claim"] == "unbiased" and r["biased"]:
            parts.append(f"'{r['label']}' flagged although unbiased in theory: {_tails_text(r)}")
    missed = [r["label"] for r in rows if r["claim"] == "biased" and not r["biased"]]
    if missed:
        parts.append(f"biased in theory but not flagged at {rows[0]['spp']} spp: {', '.join(missed)}")
    return f"{TRICK_NAMES[trick]}: " + "; ".join(parts) + "."


def denoiser_numbers(data: StudyData, label: str) -> dict:
    """Where the denoiser's bias dominates (bias^2 > variance), and from which spp plain mcrt has the lower relMSE."""
    rs = rungs_of(data, label)
    plain = {r.spp: r for r in rungs_of(data, PLAIN)}
    dominates = next((r.spp for r in rs if r.bias2 > r.variance), None)
    overtaken = next((r.spp for r in rs if plain[r.spp].relmse < r.relmse), None)
    return {"bias_dominates_from": dominates, "plain_better_from": overtaken,
            "mse_ratio": {r.spp: plain[r.spp].mse / r.mse for r in rs},
            "relmse_ratio": {r.spp: plain[r.spp].relmse / r.relmse for r in rs}, "detected_from": detected_from(rs)}


def _denoise_tail(data: StudyData) -> str:
    labels = [v.label for v in data.variants if v.trick == "denoise"]
    if not labels:
        return ""
    d = denoiser_numbers(data, labels[0])
    low = min(d["mse_ratio"])
    none = "no rung up to the top"
    return (f" '{labels[0]}': relMSE of plain mcrt over the denoised {d['relmse_ratio'][low]:.3g} at {low} spp (MSE "
            f"{d['mse_ratio'][low]:.3g}); its bias^2 exceeds its variance from {d['bias_dominates_from'] or none} spp on; "
            f"plain mcrt has the lower relMSE from {d['plain_better_from'] or none} spp on; the comparison tells from "
            f"{d['detected_from'] or none} spp.")


def _light_tail(data: StudyData) -> str:
    rows = data.extra.get("light_receivers") or []
    if not rows:
        return ""
    near, far = rows[0], rows[-1]
    text = (f" At single receivers, solid-angle sampling is {near['efficiency_ratio']:.3g}x as efficient {near['receiver']} "
            f"and {far['efficiency_ratio']:.3g}x at the {far['receiver']}")
    solid = [v.label for v in data.variants if v.options.get("light_sampling") == "solid_angle"]
    if solid:
        r = variant_row(data, solid[0])
        text += (f"; on the image '{solid[0]}' is {r['efficiency_ratio']:.2f}x by MSE, {r['efficiency_ratio_relmse']:.2f}x "
                 f"by relMSE (time {r['time_ratio']:.2f}x)")
    return text + "."


def _adaptive_tail(data: StudyData) -> str:
    rows = [variant_row(data, v.label) for v in data.variants if v.trick == "adaptive"]
    return " At equal samples (launch overhead aside): " + "; ".join(
        f"'{r['label']}' {r['per_sample_ratio']:.2f}x plain mcrt's efficiency by MSE, {r['per_sample_ratio_relmse']:.2f}x "
        f"by relMSE" for r in rows) + "." if rows else ""


def _bidir_tail(data: StudyData, goal: float = 3.0) -> str:
    labels = [v.label for v in data.variants if v.trick == "bidirectional"]
    if not labels:
        return ""
    row = variant_row(data, labels[0])
    a, b = row["efficiency_ratio"], row["efficiency_ratio_relmse"]
    return (f" Goal {goal:g}x at equal time: by MSE {'met' if a >= goal else 'not met'} ({a:.2f}x), by relMSE "
            f"{'met' if b >= goal else 'not met'} ({b:.2f}x).")


def verdicts(data: StudyData, tricks) -> list[str]:
    """One line per trick present in the study."""
    tails = {"denoise": _denoise_tail, "light": _light_tail, "bidirectional": _bidir_tail, "adaptive": _adaptive_tail}
    out = []
    for t in tricks:
        line = trick_verdict(data, t)
        if line:
            out.append(line + (tails[t](data) if t in tails else ""))
    return out
