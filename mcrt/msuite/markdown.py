"""The suite's report as Markdown (index.md), from the JSON-ready result of :func:`mcrt.msuite.run.run_suite`."""

from __future__ import annotations

from mcrt.msuite.perturb import ISSUE, KINDS, LADDER, PERTURBATIONS, factor_name
from mcrt.msuite.run import _false_alarms, rtol_text, verdict
from mcrt.msuite.scenes import HELD_OUT


def _mark(p: dict | None, who: str) -> str:
    if p is None:
        return "n/a"
    return "caught" if p[who]["caught"] else "-"


def _ratio(a: int, b: int) -> str:
    return f"{a / b:.2g}x" if b else ("no catch by either" if not a else "Mitsuba's rule catches none")


def _summary_lines(title: str, s: dict) -> list[str]:
    if not s["scenes"]:
        return [f"- {title}: no scene."]
    i = s["issue_sizes"]
    return [f"- {title}: {s['scenes']} scene{'s' if s['scenes'] > 1 else ''}, {s['correct_renders']} correct renders "
            f"({s['suite_runs']} seeds). "
            f"Rejected: mcrt {s['mcrt_rejected_correct']} ({s['mcrt_reference_differences']} "
            f"scene{'' if s['mcrt_reference_differences'] == 1 else 's'} with a difference "
            f"of the reference, named below; false alarms {s['mcrt_false_alarms']}, failing "
            f"{s['mcrt_suite_runs_failed']} of {s['suite_runs']} suite runs), Mitsuba's rule {s['mitsuba_rejected_correct']} "
            f"(false alarms {s['mitsuba_false_alarms']}). Perturbed renders caught"
            + (f" (left out: {', '.join(s['power_left_out'])}, with a difference of the reference)" if s["power_left_out"] else "")
            + ": at the issue's four sizes mcrt "
            f"{i['mcrt']}, Mitsuba's rule {i['mitsuba']} of {i['applicable']}; over the whole ladder mcrt {s['mcrt_caught']}, "
            f"Mitsuba's rule {s['mitsuba_caught']} of {s['perturbations']} ({_ratio(s['mcrt_caught'], s['mitsuba_caught'])}). "
            f"Reference offsets accepted: {s['reference_offsets']}."]


def _calibration_line(data: dict) -> str:
    cal = data["summary"]["all"]["mcrt_calibration"]
    n, own = cal["renders"], f"{data['scene_alpha']:.3g}"
    mark = " (each scene's level)"
    parts = [f"at {a}{mark if a == own else ''}: {k} (expected at most {n * float(a):.2g})" for a, k in cal["rejected"].items()]
    return (f"- False-alarm rate measured: mcrt's rejections of the {n} correct renders of scenes without a difference "
            "of the reference, at several levels (a render whose family p-value, its smallest weighted-Holm adjusted "
            "p-value, is at or below a level is rejected at that level): " + "; ".join(parts) + ".")


def _goal_lines(data: dict) -> list[str]:
    """The issue's goals, each met or not, from the counts."""
    s = data["summary"]["all"]
    done = [c for c in data["cases"] if "error" not in c]
    clean = sum(c["correct"][0]["mcrt"]["passed"] for c in done)
    out = [f"- Goals: correct renders consistent (a reference's stated offset accepted) on {clean} of {len(done)} scenes "
           f"(first seed), {s['mcrt_reference_differences']} scenes with a difference of the reference that the seeds "
           f"confirm (named below); mcrt's false alarms: {s['mcrt_false_alarms']} of {s['correct_renders']} correct renders, "
           f"{s['mcrt_suite_runs_failed']} of {s['suite_runs']} suite runs failed at the suite's level {data['alpha']:g} "
           f"({'met' if s['mcrt_false_alarms'] == 0 else 'not met'}: no false alarm)."]
    ok = s["mcrt_caught"] >= 2 * s["mitsuba_caught"]
    twice = [name for name, b in s["by_perturbation"].items() if b["mcrt"] and b["mcrt"] >= 2 * b["mitsuba"]]
    i = s["issue_sizes"]
    out.append(f"- Power: over the whole ladder mcrt catches {s['mcrt_caught']}, Mitsuba's rule {s['mitsuba_caught']} of "
               f"{s['perturbations']} perturbed renders ({'met' if ok else 'not met'}: at least twice as many). At the "
               f"issue's four sizes {i['mcrt']} against {i['mitsuba']} of {i['applicable']}"
               + (" (twice as many is out of reach where Mitsuba's rule catches more than half)"
                  if 2 * i["mitsuba"] > i["applicable"] else "")
               + f". Twice as many or more on: {', '.join(twice) or 'none'}.")
    return out


def _ladder_lines(data: dict) -> list[str]:
    """Caught counts per perturbation (all scenes, held-out part) and the smallest size each test catches."""
    s, h = data["summary"]["all"], data["summary"]["held_out"]
    lines = ["", "## Power over a ladder of sizes", "",
             "The ladder was fixed before any of its results were seen: each multiplicative kind at the issue's size "
             f"and at {', '.join(f'1/{r}' for r in LADDER[1:])} of its deviation from 1; one render each, at the scene's "
             "budget and a seed of its own. mcrt accepts a relative difference within the scene's rtol by design ("
             + (rtol_text(data["margins"]["version_rtol"]) if "margins" in data else "0.0011")
             + " against a reference another Mitsuba version wrote), so where that margin applies the 1/64 rungs of the "
             "emitter and the BSDF (0.031 %) lie at or just beyond it in X and Z.", "",
             "| perturbation | applicable | mcrt | Mitsuba's rule | ratio | held out: mcrt / Mitsuba's rule |",
             "|---|---|---|---|---|---|"]
    for name, b in s["by_perturbation"].items():
        hb = h.get("by_perturbation", {}).get(name, {"applicable": 0})
        held = f"{hb['mcrt']} / {hb['mitsuba']} of {hb['applicable']}" if hb["applicable"] else "-"
        lines.append(f"| {name}{' (issue)' if name in ISSUE else ''} | {b['applicable']} | {b['mcrt']} | {b['mitsuba']} | "
                     f"{_ratio(b['mcrt'], b['mitsuba'])} | {held} |")
    done = [c for c in data["cases"] if "error" not in c]
    lines += ["", "The smallest size each test catches, per scene (mcrt / Mitsuba's rule; none: no size caught):", "",
              "| scene | " + " | ".join(KINDS) + " |", "|---|" + "---|" * len(KINDS)]
    for c in done:
        cells = []
        for kind in KINDS:
            ps = [(factor_name(kind, r), c["perturbations"].get(factor_name(kind, r))) for r in LADDER]
            if all(p is None for _, p in ps):
                cells.append("n/a")
                continue
            cells.append(" / ".join(next((n.split()[1] for n, p in reversed(ps) if p and p[who]["caught"]), "none")
                                    for who in ("mcrt", "mitsuba")))
        lines.append(f"| {_power_name(data, c)} | " + " | ".join(cells) + " |")
    lines += ["", "Over the scenes, the smallest size caught on at least half of those it applies to: "
              + "; ".join(f"{kind} " + " / ".join(_smallest_majority(s, kind, who) for who in ("mcrt", "mitsuba"))
                          for kind in KINDS) + " (mcrt / Mitsuba's rule)."]
    return lines


def _power_name(data: dict, case: dict) -> str:
    """The scene's name in the power tables, marked where its catches are left out of the counts."""
    left_out = case["name"] in data["summary"]["all"].get("power_left_out", ())
    return case["name"] + (" (a difference of the reference: not counted)" if left_out else "")


def _smallest_majority(s: dict, kind: str, who: str) -> str:
    for r in reversed(LADDER):
        b = s["by_perturbation"].get(factor_name(kind, r))
        if b and b["applicable"] and 2 * b[who] >= b["applicable"]:
            return factor_name(kind, r).split()[1]
    return "none"


def _margin_text(data: dict) -> str:
    """The margins of the tests against the references, and what they come from, in words."""
    m = data.get("margins")
    if m is None:  # a report written before the margins were recorded
        return (f"against a reference another Mitsuba version wrote, a relative difference up to "
                f"{data['options'].get('version_rtol') or 0.0011:g} is accepted in every test")
    white = ", ".join(str(v) for v in m["stored_white_rgb"])
    done = [c for c in data["cases"] if "error" not in c]
    grid = [c["name"] for c in done if c.get("rounding_grid", {}).get("dark", 0) >= 10
            and c["rounding_grid"]["on_grid"] == c["rounding_grid"]["dark"]]
    return (f"against a reference another Mitsuba version wrote, a relative difference up to {rtol_text(m['version_rtol'])} "
            f"is accepted, channel by channel: the relative offset in XYZ of the white those versions store (a constant "
            f"1.0 stored as RGB ({white}), bsdf_spheres/refs/test_constant_ref_rgb.exr pixel [0, 0]), rounded up to two "
            "significant digits, a rule fixed from that white alone, before this run and not from any scene's results; "
            f"and every test accepts an absolute difference up to {m['rounding_atol']:.2g} (2^-22, twice float32's spacing "
            "at 1.0): Mitsuba computes in float32 with factors of order 1, so a value near 0 carries rounding at that "
            "scale, not at its own"
            + (f" (in the dark pixels, XYZ below 1e-5, of {', '.join(grid)}, every reference value is a multiple of 2^-24)"
               if grid else ""))


def _differences_of_references(data: dict) -> list[str]:
    """The section naming each difference of a reference: noiseless offsets accepted, and, where correct renders
    are rejected on evidence the seeds confirm, where, how large, what the camera sees there, and where the same
    shapes are consistent."""
    done = [c for c in data["cases"] if "error" not in c]
    systematic, _ = _false_alarms(done, "mcrt")
    offsets = [c for c in done if "reference_offset" in c]
    named = [c for c, sy in zip(done, systematic) if sy and c.get("differences")]
    if not offsets and not named:
        return []
    lines = ["", "## Differences of the references", ""]
    if offsets:
        lines += ["Noiseless pixels (no variance on either side) where the reference differs from a correct render, "
                  "and no noisy test rejected: the reference's own offset, accepted with the stated rtol:", ""]
        lines += [f"- {c['name']}: up to {100 * c['reference_offset']:.3g} % (rtol {rtol_text(c['rtol'])})"
                  + (" on the first seed; other seeds' renders exceed it, named below" if c in named else "") for c in offsets]
        lines.append("")
    if named:
        version = data["provenance"]["versions"].get("mitsuba", "?")
        lines += ["Rejections the seeds confirm (above): where, the mean of all the scene's correct renders against the "
                  "reference there, what the camera's primary rays (4 x 4 per pixel) hit there, and the other scenes "
                  "with the same shapes and BSDFs. mcrt renders with Mitsuba's own integrators, so the render is "
                  f"Mitsuba {version}'s.", ""]
        for c in named:
            lines.append(f"- {c['name']} (reference by {c.get('written_by') or 'an unrecorded version'}, emitters "
                         f"{', '.join(c.get('emitters', [])) or 'none'}): " + "; ".join(_difference_text(d, len(c['correct']))
                                                                              for d in c["differences"])
                         + _elsewhere(c, done, systematic, version) + ".")
    return lines


def _difference_text(d: dict, seeds: int) -> str:
    rel = d["rel_diff"]
    size = ", ".join(f"{ch} {100 * v:+.3g} %" for ch, v in zip("XYZ", rel))
    same = max(rel) - min(rel) <= 0.1 * max(abs(v) for v in rel) if any(rel) else False
    seen = ", ".join(f"{what} {100 * f:.0f} %" for what, f in d["seen"])
    way = ("darker than" if max(rel) < 0 else "brighter than" if min(rel) > 0 else "different from")
    return (f"rows {d['rows'][0]}-{d['rows'][1]}, cols {d['cols'][0]}-{d['cols'][1]}: the mean of the {seeds} correct "
            f"renders is {way} the reference, {size}"
            + (" (the same in every channel: not a colour shift)" if same else "")
            + (" in noiseless pixels (no variance on either side)" if d.get("noiseless") else "")
            + f" (Y {d['mean'][1]:.5g} against {d['reference'][1]:.5g}); there the camera sees {seen}")


def _elsewhere(case: dict, done: list[dict], systematic: list[bool], version: str) -> str:
    """Other scenes holding every shape seen in the case's differences: whether mcrt finds a difference of the
    reference there, and whether that difference too is where these shapes are seen."""
    shapes = {what for d in case["differences"] for what, _ in d["seen"] if what != "nothing"}
    # A shape in words includes its place and BSDF: the same object, not merely the same kind.
    others = [(c, sy) for c, sy in zip(done, systematic) if c is not case and shapes <= set(c.get("objects", []))]
    if not shapes or not others:
        return ""
    ok = [c for c, sy in others if not sy]
    bad = [c for c, sy in others if sy]
    there = [c for c in bad if shapes & {what for d in c.get("differences", []) for what, _ in d["seen"]}]

    def named(cs):
        return ", ".join(f"{c['name']} (emitters {', '.join(c.get('emitters', []))})" for c in cs)

    text = ""
    if ok:
        text += f"; the same shapes are in {named(ok)}, where mcrt finds no difference of the reference"
    if there:
        text += f"; {'and ' if ok else 'the same shapes are '}in {named(there)}, which differ{'s' if len(there) == 1 else ''} too, where these shapes are seen"
    rest = [c for c in bad if c not in there]
    if rest:
        text += f"; and in {named(rest)}, which differ{'s' if len(rest) == 1 else ''} elsewhere"
    rel = case["differences"][0]["rel_diff"]
    sign = "darker" if max(rel) < 0 else "brighter" if min(rel) > 0 else "different"
    by = case.get("written_by") or "the reference's version"
    if ok and not bad:
        text += (f": the difference comes with these shapes lit by {', '.join(case.get('emitters', []))}, which "
                 f"Mitsuba {version} renders {sign} than {by} did")
    elif there and not rest:
        text += (f": in every scene with these shapes where mcrt finds a difference of the reference, it is where "
                 f"these shapes are seen; Mitsuba {version} renders them otherwise than {by} did ({sign} here)")
    return text


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
             f"weighted Holm over them within a scene at the level {data['scene_alpha']:.3g}: the suite's family-wise "
             f"error rate {data['alpha']:g} split evenly over its {len(data['cases'])} scenes, Bonferroni, so that the "
             "suite run as one CI check fails a correct run with probability at most "
             f"{data['alpha']:g}; the render's variance floored at the reference's; "
             f"the reference's spp taken as {o['ref_spp']}, what Mitsuba's reference generator renders by default, "
             f"since the files do not record it; {_margin_text(data)}). **Mitsuba's rule** is Mitsuba's own per-pixel z-test on the same "
             "render as Mitsuba applies it, scene by scene (Sidak level per pixel from 0.01, pass when 99.75 % of "
             "pixel-channels pass; its level left as it is, though mcrt's is made stricter). A perturbation is "
             "caught when the test rejects it on evidence the scene's first correct render does not show: for mcrt a "
             "rejected test (tile, channel, scale) the correct render does not have; for Mitsuba's rule a failure where "
             "the correct render passes, or more failing pixel-channels than the correct render's plus the rule's "
             "allowance. Catches are counted on the scenes whose correct renders mcrt finds consistent: where it "
             "finds a difference of the reference, a perturbed render's rejections are not evidence of the "
             "perturbation (a rule added after a run in which such a scene was caught at every size, down to 1/64).", "",
             "## Summary", ""]
    for key, title in (("all", "All scenes"), ("tuning", "Tuning part"), ("held_out", "Held-out part")):
        lines += _summary_lines(title, data["summary"][key])
    lines += [_calibration_line(data), "", *_goal_lines(data)]
    lines += ["", "## Scenes", "",
              "mcrt's verdict and Mitsuba's rule's are those of the first seed; then how many of the correct renders "
              f"are rejected: by mcrt at the scene's level {data['scene_alpha']:.3g}, by mcrt at 0.01 (from their family "
              "p-values), by Mitsuba's rule.", "",
              "| scene | size, spp | integrator (variance) | mcrt | Mitsuba's rule (failing / allowed) | rejected: mcrt, "
              "mcrt at 0.01, Mitsuba's rule | time |",
              "|---|---|---|---|---|---|---|"]
    for c in data["cases"]:
        name = c["name"] + (" (held out)" if c.get("held_out") else "")
        if "error" in c:
            lines.append(f"| {name} | | | error: {c['error']} | | | |")
            continue
        z = c["correct"][0]["mitsuba"]
        zt = f"{'passes' if z['passed'] else 'FAILS'} ({z['failing']} / {z['allowed']})"
        var = "batches" if c.get("method") == "batches" else "per-sample"
        rc = c["correct"]
        counts = (f"{sum(not r['mcrt']['passed'] for r in rc)}, {sum(r['mcrt']['p_family'] <= 0.01 for r in rc)}, "
                  f"{sum(not r['mitsuba']['passed'] for r in rc)} of {len(rc)}")
        lines.append(f"| {name} | {c['size'][0]}x{c['size'][1]}, {c['spp']} | {c['integrator']} ({var}) | {verdict(c)} | "
                     f"{zt} | {counts} | {c['time']:.1f} s |")
    lines += ["", "## Perturbations at the issue's sizes", "",
              "Rendered at the scene's budget; mcrt / Mitsuba's rule. What each is:", ""]
    lines += [f"- **{k}**: {PERTURBATIONS[k]}" for k in ISSUE]
    lines += ["", "| scene | " + " | ".join(ISSUE) + " |", "|---|" + "---|" * len(ISSUE)]
    for c in data["cases"]:
        if "error" in c:
            continue
        cells = [f"{_mark(c['perturbations'].get(k), 'mcrt')} / {_mark(c['perturbations'].get(k), 'mitsuba')}"
                 for k in ISSUE]
        lines.append(f"| {_power_name(data, c)} | " + " | ".join(cells) + " |")
    if any(name not in ISSUE for c in data["cases"] for name in c.get("perturbations", {})):
        lines += _ladder_lines(data)
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
            zs = [f"{z:.1f}" for z in conf if z is not None]
            conf_text = ("; the other seeds' t on the rejected tests, combined (Stouffer z): " + ", ".join(zs[:5])
                         + (f" and {len(zs) - 5} more" if len(zs) > 5 else "")) if zs else ""
            lines.append(f"- {c['name']}: rejected on {n_rej} of {len(c['correct'])} seeds{conf_text}; "
                         + "; ".join(f"{f['tile']}x{f['tile'] if f['tile'] else 'whole'} rows {f['rows'][0]}-{f['rows'][1]} "
                                     f"cols {f['cols'][0]}-{f['cols'][1]} {f['channel']} {100 * f['rel_diff']:+.3g} %"
                                     + (f" ({f['mean']:.3g} against {f['reference']:.3g}, the image's peak "
                                        f"{c['correct'][0]['mcrt']['peak']:.3g})" if "mean" in f else "")
                                     + (" (noiseless)" if f["noiseless"] else "")
                                     for f in next(r for r in c["correct"] if not r["mcrt"]["passed"])["mcrt"]["failing"]))
    lines += _differences_of_references(data)
    lines += ["", "## Held-out scenes", "",
              "Chosen before any scene was rendered and kept out of tuning, looked at last (one of each kind): "
              + ", ".join(f"`{n}`" for n in HELD_OUT) + ". Their results are in the held-out line of the summary. "
              "They are no longer unseen: an earlier run's results on them were looked at, and the rounding margin "
              "(2^-22) was added after texture_interp/test_texture_interp_direct was found rejected at values near 0. "
              "The per-channel margin against other versions' references was set from the stored white alone, not "
              "from the held-out results.", "",
              "## Not covered", "",
              "The shared copy holds part of Mitsuba's `tests/scenes` (rgb references only); the rest of the upstream "
              "suite (e.g. participating media, other sensors and emitters) cannot be fetched here (no network but "
              "PyPI and Debian) and is not in this report."]
    if data["skipped"]:
        lines += ["", "Skipped (no reference pair):", ""] + [f"- {s['name']}: {s['why']}" for s in data["skipped"]]
    if o.get("only") or o.get("held_out") != "include":
        lines += ["", f"This run covers a subset: {o.get('only') or ''} held-out {o.get('held_out')}."]
    return "\n".join(lines) + "\n"
