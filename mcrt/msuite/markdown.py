"""The suite's report as Markdown (index.md), from the JSON-ready result of :func:`mcrt.msuite.run.run_suite`."""

from __future__ import annotations

from mcrt.msuite.perturb import PERTURBATIONS
from mcrt.msuite.run import verdict
from mcrt.msuite.scenes import HELD_OUT


def _mark(p: dict | None, who: str) -> str:
    if p is None:
        return "n/a"
    return "caught" if p[who]["caught"] else "-"


def _summary_lines(title: str, s: dict) -> list[str]:
    if not s["scenes"]:
        return [f"- {title}: no scene."]
    ratio = f"{s['mcrt_caught'] / s['mitsuba_caught']:.2g}x" if s["mitsuba_caught"] else "no catch by Mitsuba's rule"
    return [f"- {title}: {s['scenes']} scenes, {s['correct_renders']} correct renders. Rejected: mcrt "
            f"{s['mcrt_rejected_correct']} ({s['mcrt_reference_differences']} scenes with a difference of the reference: "
            f"rejected on every seed, or confirmed by the other seeds; false alarms {s['mcrt_false_alarms']}), Mitsuba's rule "
            f"{s['mitsuba_rejected_correct']} (false alarms {s['mitsuba_false_alarms']}). Perturbations caught (of "
            f"{s['perturbations']} applicable): mcrt {s['mcrt_caught']}, Mitsuba's rule {s['mitsuba_caught']} ({ratio}). "
            f"Reference offsets accepted: {s['reference_offsets']}."]


def _goal_lines(data: dict) -> list[str]:
    """The issue's goals, each met or not, from the counts."""
    s = data["summary"]["all"]
    done = [c for c in data["cases"] if "error" not in c]
    clean = sum(c["correct"][0]["mcrt"]["passed"] for c in done)
    out = [f"- Goals: correct renders consistent (a reference's stated offset accepted) on {clean} of {len(done)} scenes "
           f"(first seed), {s['mcrt_reference_differences']} scenes with a difference of the reference that the seeds "
           f"confirm (named below); mcrt's false alarms: {s['mcrt_false_alarms']} of {s['correct_renders']} correct renders "
           f"({'met' if s['mcrt_false_alarms'] == 0 else 'not met'}: no false alarm)."]
    ok = s["mcrt_caught"] >= 2 * s["mitsuba_caught"]
    why = ""
    if not ok and 2 * s["mitsuba_caught"] > s["perturbations"]:
        why = (f" Mitsuba's rule already catches {s['mitsuba_caught']} of {s['perturbations']}, so twice as many is out of "
               "reach on these perturbations: its variance floor of 1e-4 makes it sensitive in low-noise pixels.")
    out.append(f"- Power: mcrt catches {s['mcrt_caught']}, Mitsuba's rule {s['mitsuba_caught']} of {s['perturbations']} "
               f"perturbed renders ({'met' if ok else 'not met'}: at least twice as many).{why}")
    return out


def markdown(data: dict) -> str:
    """index.md: what was run, the summary, one row per scene, the perturbations, what is left out."""
    o = data["options"]
    lines = ["# mcrt on Mitsuba 3's render-test suite", "",
             f"Written by `{data['command']}` (commit {str(data['provenance'].get('git_commit') or 'unknown')[:10]}, "
             f"Mitsuba {data['provenance']['versions'].get('mitsuba', '?')}, {data['provenance']['machine']['cores']} "
             f"cores shared with other work); {data['wall_time']:.0f} s in all.", "",
             "Each scene is rendered as Mitsuba renders it (its film, reconstruction filter, sampler and integrator; "
             "the `moment` wrapper unwrapped) at Mitsuba's budget of 2e6 samples over the image"
             + (f" times {o['spp_scale']:g}" if o["spp_scale"] != 1 else "")
             + ", in CIE XYZ (the space of Mitsuba's test, where the reference's variance is exact). "
             f"**mcrt** is the multi-scale Welch tile test (tiles {', '.join(str(t) if t else 'whole image' for t in o['tiles'])}; "
             f"weighted Holm, FWER {o['alpha']:g} per comparison; the render's variance floored at the reference's; "
             f"the reference's spp taken as {o['ref_spp']}, what Mitsuba's reference generator renders by default, "
             f"since the files do not record it; against a reference another Mitsuba version wrote, a relative "
             f"difference up to {o.get('version_rtol', 0.0011):g} is accepted in every test, the colour conversion of "
             "those versions storing a constant 1.0 as 1.00108 or 0.99971). **Mitsuba's rule** is Mitsuba's own per-pixel z-test on the same "
             "render (Sidak level per pixel from 0.01, pass when 99.75 % of pixel-channels pass). A perturbation is "
             "caught when the test rejects it on evidence the scene's first correct render does not show: for mcrt a "
             "rejected test (tile, channel, scale) the correct render does not have; for Mitsuba's rule a failure where "
             "the correct render passes, or more failing pixel-channels than the correct render's plus the rule's "
             "allowance.", "",
             "## Summary", ""]
    for key, title in (("all", "All scenes"), ("tuning", "Tuning part"), ("held_out", "Held-out part")):
        lines += _summary_lines(title, data["summary"][key])
    lines += ["", *_goal_lines(data)]
    lines += ["", "## Scenes", "",
              "| scene | size, spp | integrator (variance) | mcrt | Mitsuba's rule (failing / allowed) | time |",
              "|---|---|---|---|---|---|"]
    for c in data["cases"]:
        name = c["name"] + (" (held out)" if c.get("held_out") else "")
        if "error" in c:
            lines.append(f"| {name} | | | error: {c['error']} | | |")
            continue
        z = c["correct"][0]["mitsuba"]
        zt = f"{'passes' if z['passed'] else 'FAILS'} ({z['failing']} / {z['allowed']})"
        var = "batches" if c.get("method") == "batches" else "per-sample"
        lines.append(f"| {name} | {c['size'][0]}x{c['size'][1]}, {c['spp']} | {c['integrator']} ({var}) | {verdict(c)} | "
                     f"{zt} | {c['time']:.1f} s |")
    lines += ["", "## Perturbations", "", "Rendered at the scene's budget; mcrt / Mitsuba's rule. What each is:", ""]
    lines += [f"- **{k}**: {v}" for k, v in PERTURBATIONS.items()]
    lines += ["", "| scene | " + " | ".join(PERTURBATIONS) + " |", "|---|" + "---|" * len(PERTURBATIONS)]
    for c in data["cases"]:
        if "error" in c:
            continue
        cells = [f"{_mark(c['perturbations'].get(k), 'mcrt')} / {_mark(c['perturbations'].get(k), 'mitsuba')}"
                 for k in PERTURBATIONS]
        lines.append(f"| {c['name']} | " + " | ".join(cells) + " |")
    different = [c for c in data["cases"] if "error" not in c and not all(r["mcrt"]["passed"] for r in c["correct"])]
    if different:
        lines += ["", "## Differences mcrt finds in correct renders", "",
                  "The rejected tests of the first rejected correct render (at most 10: tile, relative difference, the tile "
                  "means of render and reference), and on how many of the scene's correct renders (independent seeds) "
                  "mcrt rejects: a difference that every seed shows is the reference's, not noise; so is one whose "
                  "rejected tests the other seeds confirm (their t on the same tests, combined by Stouffer's z, beyond "
                  "the one-sided 0.01 level, Bonferroni over the render's rejected tests: no selection bias, since "
                  "those seeds did not pick the tests). Otherwise it is a false alarm.", ""]
        for c in different:
            n_rej = sum(not r["mcrt"]["passed"] for r in c["correct"])
            conf = [r["mcrt"].get("confirm_z") for r in c["correct"] if not r["mcrt"]["passed"]]
            conf_text = "; the other seeds' t on the rejected tests, combined (Stouffer z): " + ", ".join(
                f"{z:.1f}" for z in conf if z is not None) if any(z is not None for z in conf) else ""
            lines.append(f"- {c['name']}: rejected on {n_rej} of {len(c['correct'])} seeds{conf_text}; "
                         + "; ".join(f"{f['tile']}x{f['tile'] if f['tile'] else 'whole'} rows {f['rows'][0]}-{f['rows'][1]} "
                                     f"cols {f['cols'][0]}-{f['cols'][1]} {f['channel']} {100 * f['rel_diff']:+.3g} %"
                                     + (f" ({f['mean']:.3g} against {f['reference']:.3g}, the image's peak "
                                        f"{c['correct'][0]['mcrt']['peak']:.3g})" if "mean" in f else "")
                                     + (" (noiseless)" if f["noiseless"] else "")
                                     for f in next(r for r in c["correct"] if not r["mcrt"]["passed"])["mcrt"]["failing"]))
    offsets = [c for c in data["cases"] if "reference_offset" in c]
    if offsets:
        lines += ["", "## Differences of the references", "",
                  "Noiseless pixels (no variance on either side) where the reference differs from a correct render, "
                  "and no noisy test rejected: the reference's own difference (the old references store a constant "
                  "1.0 as 1.00108 / 0.99971), accepted with the stated rtol:", ""]
        lines += [f"- {c['name']}: up to {100 * c['reference_offset']:.3g} % (rtol {c['rtol']:g})" for c in offsets]
    lines += ["", "## Held-out scenes", "",
              "Chosen before any scene was rendered and kept out of tuning, looked at last (one of each kind): "
              + ", ".join(f"`{n}`" for n in HELD_OUT) + ". Their results are in the held-out line of the summary.", "",
              "## Not covered", "",
              "The shared copy holds part of Mitsuba's `tests/scenes` (rgb references only); the rest of the upstream "
              "suite (e.g. participating media, other sensors and emitters) cannot be fetched here (no network but "
              "PyPI and Debian) and is not in this report."]
    if data["skipped"]:
        lines += ["", "Skipped (no reference pair):", ""] + [f"- {s['name']}: {s['why']}" for s in data["skipped"]]
    if o.get("only") or o.get("held_out") != "include":
        lines += ["", f"This run covers a subset: {o.get('only') or ''} held-out {o.get('held_out')}."]
    return "\n".join(lines) + "\n"
