"""README.md of a validation folder: what the studies measured and what it means, written from their JSON.

A validation folder holds one run of ``mcrt validate`` (false_alarms.json,
power.json) and, in sub-folders, further runs against other opponents (the
committed reference, with and without the variance floor). :func:`write_readme`
reads every run it finds there and writes the README: the method, explained
in fixed prose, and the analysis, every figure of which comes from the runs'
JSON, so the folder is entirely generated.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import mcrt.validate.data as data
from mcrt.validate.budget import Budget
from mcrt.validate.markdown import interval, pct, rate_cell
from mcrt.validate.power import CONTROL
from mcrt.validate.rates import false_alarm_bound

#: File name of the README in a validation folder.
README_NAME = "README.md"
#: Opponent kinds in the order the README presents them.
KIND_ORDER = ("mitsuba", "reference", "reference-floor")
#: A largest |t| at the effect-size budget below this is at noise level: no measurable change of the expected image.
NOISE_T = 4.0


@dataclass
class Run:
    """One run of ``mcrt validate`` found in a validation folder."""

    folder: str  # relative to the validation folder: '' or 'against_reference/'
    false_alarms: dict[str, Any] | None
    power: dict[str, Any] | None

    @property
    def study(self) -> dict[str, Any]:
        return self.false_alarms or self.power

    @property
    def kind(self) -> str:
        return self.study["against"]["kind"]

    @property
    def meta(self) -> dict[str, Any]:
        return self.study["meta"]


def find_runs(root: str | Path) -> list[Run]:
    """The runs in ``root`` and its immediate sub-folders, in :data:`KIND_ORDER`."""
    root = Path(root)
    runs = []
    for d in [root, *sorted(p for p in root.iterdir() if p.is_dir())] if root.is_dir() else []:
        fa, pw = data.read(d / "false_alarms.json"), data.read(d / "power.json")
        if fa or pw:
            runs.append(Run("" if d == root else f"{d.name}/", fa, pw))
    return sorted(runs, key=lambda r: (KIND_ORDER.index(r.kind) if r.kind in KIND_ORDER else len(KIND_ORDER), r.folder))


def readme_root(out: str | Path) -> Path:
    """The validation folder a run written to ``out`` belongs to: ``out``'s parent when that holds a run, else ``out``."""
    out = Path(out)
    parent = out.resolve().parent
    if any((parent / name).exists() for name in ("false_alarms.json", "power.json")):
        return out.parent
    return out


def write_readme(root: str | Path) -> Path | None:
    """Write ``root``/README.md from the runs found there (None, and nothing written, when there are none)."""
    root = Path(root)
    runs = find_runs(root)
    if not runs:
        return None
    path = root / README_NAME
    path.write_text(readme_markdown(runs), encoding="utf-8")
    return path


# --------------------------------------------------------------------------
# Words
# --------------------------------------------------------------------------


def _opponent(run: Run, long: bool = False) -> str:
    a = run.study["against"]
    if run.kind == "mitsuba":
        return "fresh Mitsuba renders at the same budget"
    text = f"the committed {a['spp']}-spp reference"
    if run.kind == "reference-floor":
        text += (", with each tested render's per-sample variance raised to the reference's where lower"
                 + (" (`mcrt.stats.floor_variance`, the rule of `mcrt reference verify`)" if long else ""))
    return text


def _alarms(k: int) -> str:
    return f"{'no' if k == 0 else k} false alarm{'' if k == 1 else 's'}"


def _tile_name(t: int | str) -> str:
    t = int(t)
    return "per-pixel tests" if t == 1 else f"{t}x{t} tiles"


def _join(items: list[str]) -> str:
    if len(items) <= 1:
        return "".join(items)
    return ", ".join(items[:-1]) + " and " + items[-1]


def _q(x: float | None, fmt: str = ".2f") -> str:
    return "n/a" if x is None else format(x, fmt)


# --------------------------------------------------------------------------
# Sections
# --------------------------------------------------------------------------


def _files(runs: list[Run]) -> list[str]:
    lines = ["| file | what | produced by |", "|---|---|---|"]
    for r in runs:
        cmd = f"`{r.meta['command']}`"
        fa, pw = r.false_alarms, r.power
        what_fa = f"false-alarm rate: {fa['primary']['n']} correct mcrt renders against {_opponent(r, long=True)}" if fa else ""
        what_pw = (f"power: {len(pw['mutants'])} mutants x {len(pw['seeds']['mcrt'])} seeds against {_opponent(r)}"
                   + (", with follow-ups" if pw["followups"] or pw["escalation"] or pw["effects"] else "")) if pw else ""
        if not r.folder:
            if fa:
                lines.append(f"| `false_alarms.md`, `.json` | {what_fa} | {cmd} |")
            if pw:
                lines.append(f"| `power.md`, `.json` | {what_pw} | {'same run' if fa else cmd} |")
        else:
            what = "; ".join(w for w in (what_fa, what_pw) if w)
            lines.append(f"| `{r.folder}` | {what} | {cmd} |")
    return lines


def _test_under_study(runs: list[Run]) -> list[str]:
    b = runs[0].study["budget"]
    n_tests = Budget(**b).n_tests()
    default = Budget(**b) == Budget()
    which = "The default suite's comparison (`tests/test_tracer.py`)" if default else "The comparison"
    return [
        "## The test under study",
        "",
        (f"{which}: "
         f"`mcrt.stats.compare_images` with the {b['camera']} camera, {b['res']}x{b['res']} pixels, {b['spp']} spp per side, "
         f"max depth {b['max_depth']}, Welch tests on {b['tile']}x{b['tile']} tiles ({b['channels'].upper()}, {n_tests} tests), "
         f"and {b['correction'].title()} at a family-wise alpha of {b['alpha']:g}. The image under test is mcrt's; trial k of "
         "every study renders it with its own seed. The JSON files record every trial's seeds, largest |t| and smallest p, "
         "the exact command line and the mcrt, Mitsuba and Dr.Jit versions."),
        "",
        ("False alarms: each trial compares a correct render with the opponent. Against fresh Mitsuba renders every trial "
         "is independent (both sides are new), so the count of false alarms is Binomial(n, the true rate), and its "
         "Clopper-Pearson interval must contain the nominal alpha or lie below it (a conservative test). Against the "
         "committed reference the trials share the reference's noise: they are independent only given the reference. "
         "Under the null the pooled raw tile p-values are uniform on [0, 1] (Jung, Hanika and Dachsbacher 2020)."),
        "",
        ("Power: each mutant of the bug catalogue (`mcrt mutants`) is rendered on the power seeds and compared with the same "
         "opponent; the detection rate is the fraction of seeds whose comparison rejects. Mutants below the goal are "
         "followed up at other configurations of the default suite, at larger budgets, and by their effect size (one "
         "large-spp render with and one without the mutant), which tells a weak test (the expected image changes, the "
         "budget is too small to see it) from a mutant that does not change the expected image in this scene. Every "
         "study also evaluates the same renders with other tile sizes: the renders are the cost, the comparisons are free."),
        "",
    ]


def _p_shape(u: dict[str, Any]) -> str:
    """Where the pooled p-values depart from uniform, in words."""
    counts = np.asarray(u.get("counts", []), dtype=np.float64)
    if counts.size == 0 or counts.sum() == 0:
        return ""
    frac = counts / counts.sum()
    upper = float(frac[frac.size // 2:].sum())
    dev = frac * frac.size - 1.0
    i = int(np.argmax(np.abs(dev)))
    tail = u["below"]["0.01"]
    ks = "p < 1e-300" if u["ks_p"] == 0 else f"p = {u['ks_p']:.2g}"
    text = (f"In the pooled tile p-values, the fraction at or below 0.01 is {tail:.4f} and at or below 0.001 is "
            f"{u['below']['0.001']:.5f}; Kolmogorov-Smirnov against the uniform distribution gives {ks}")
    if u["ks_p"] >= 0.01:
        return text + ", consistent with uniform."
    if upper > 0.55:
        return text + f": the p-values lean towards 1 ({100 * upper:.0f} % above 0.5), the mark of a conservative test."
    if tail <= 0.0125:
        return (text + f". The histogram's largest departure from uniform is {100 * dev[i]:+.0f} % in "
                f"[{i / frac.size:.2f}, {(i + 1) / frac.size:.2f}), but the small-p tail is not overfull, which "
                "underestimated variances would make it: the shape is that of Welch statistics of heavy-tailed tiles.")
    return text + ": the small-p tail is overfull (expected 0.01): the test's variances are too small."


def _false_alarm_item(r: Run) -> list[str]:
    fa = r.false_alarms
    p, b = fa["primary"], fa["budget"]
    alpha = b["alpha"]
    where = "inside" if p["alpha_in_interval"] else ("above" if p["conservative"] else "below")
    lines = [
        (f"- **Against {_opponent(r)}: {_alarms(p['k'])} in {p['n']}.** The rate is {pct(p['rate'], 2)}, with a "
         f"{100 * fa['level']:.0f} % Clopper-Pearson interval of {interval(p['interval'])}. The nominal {alpha:g} lies "
         f"{where} it, so the goal (a rate not significantly above alpha) is {'met' if fa['goal_met'] else '**not met**'}"
         + (": the test is conservative here." if p["conservative"] else ".")),
    ]
    q, null = p["max_abs_t"]["observed"], p["max_abs_t"]["null_independent_normal"]
    if q:
        lines.append(f"  The largest |t| per comparison has a median of {q['0.5']:.2f} and a 99th percentile of {q['0.99']:.2f}; "
                     f"for {p['n_tests']} independent normal tests these would be {null['0.5']:.2f} and {null['0.99']:.2f}.")
    shape = _p_shape(p["p_values"])
    if shape:
        if r.kind != "mitsuba":
            shape += " The trials share one reference, so the Kolmogorov-Smirnov p is only indicative."
        lines.append("  " + shape)
    diffs = [float(np.mean(np.abs(tr["global_rel_diff"]))) for tr in fa["trials"] if tr.get("global_rel_diff")]
    if diffs:
        lines.append(f"  The whole-image means of the two sides differ by a median of {100 * float(np.median(diffs)):.3f} %.")
    others = [f"{_tile_name(t)} {row['k']} of {row['n']}" for t, row in fa["extra_tiles"].items()]
    if others:
        lines.append(f"  The same renders with other tile sizes: {_join(others)}.")
    if r.kind == "reference" and not fa["goal_met"]:
        lines += [
            ("  - This is the heavy tail of the per-pixel distribution: a rare path (a diffuse bounce onto the mirror "
             "sphere and into the light, say) carries a huge weight. A modest render usually misses it, so both its tile "
             "mean and its own variance estimate come out low, and the tile test sees a darker tile with a small error. "
             "Against an equal-budget Mitsuba render both sides miss the same events, so the statistic stays honest; "
             "the reference saw them, so it does not."),
            (f"  - Consequence: a plain comparison of a {b['spp']}-spp render with the reference is not a valid test at "
             f"{alpha:g}."),
        ]
        if r.power:
            ctl = [f"{rate_cell(r.power['control'])} at {b['spp']} spp"]
            ctl += [f"{rate_cell(lvl['rows'][CONTROL])} at {lvl['spp']}" for lvl in r.power["escalation"]]
            lines.append(f"  - The control renders (correct mcrt) of its power study are rejected on {_join(ctl)}.")
    if r.kind == "reference-floor":
        lines.append(
            "  - Under \"same image\" the tested render and the reference share one per-sample variance per pixel, so the "
            "tested side takes the larger of its own estimate and the reference's: a render that missed the rare paths "
            "no longer claims a small variance. `mcrt reference verify` applies the same rule to its fresh Mitsuba render.")
    return lines


def _false_alarms(runs: list[Run]) -> list[str]:
    items = [line for r in runs if r.false_alarms for line in _false_alarm_item(r)]
    return ["## False alarms", "", *items, ""] if items else []


def _effect_words(e: dict[str, Any] | None, tile: int, spp: int) -> str:
    if not e:
        return "not measured"
    x = e["tiles"][str(tile)]
    g = float(np.mean(e["global_rel_diff"]))
    return (f"whole image {100 * g:+.2f} %, the most affected {tile}x{tile} tile {100 * x['rel_diff_at_max_t']:+.2f} % "
            f"(|t| {_q(x['max_abs_t'], '.1f')} at {e['spp']} spp); expected |t| at {spp} spp: "
            f"{_q(x['expected_max_abs_t_at_budget'], '.1f')}")


def _first_goal(pw: dict[str, Any], name: str, tile: str) -> tuple[int, dict[str, Any]] | None:
    """The smallest escalation budget at which ``tile`` (an extra tile size) detects ``name`` at the goal."""
    for lvl in pw["escalation"]:
        row = lvl["rows"].get(name)
        if row and row["extra_tiles"][tile]["rate"] >= pw["goal"]:
            return lvl["spp"], row["extra_tiles"][tile]
    return None


def _detected_at(pw: dict[str, Any], name: str) -> str:
    b, goal = pw["budget"], pw["goal"]
    found = []
    for f in pw["followups"]:
        row = f["rows"][name]
        if row["rate"] >= goal:
            found.append(f"{f['label']} at {f['budget']['spp']} spp: {rate_cell(row)}")
    s = pw["stated_budgets"].get(name, {})
    if s.get("spp"):
        found.append(f"**{s['spp']} spp per side, {b['tile']}x{b['tile']} tiles: {_escalation_cell(pw, name, s['spp'])}**"
                     + (" (the stated budget)" if name in pw["subtle"] else ""))
    else:
        tried = max((lvl["spp"] for lvl in pw["escalation"]), default=b["spp"])
        found.append(f"not with {b['tile']}x{b['tile']} tiles up to {tried} spp")
    for t in pw["tiles"][1:]:
        hit = _first_goal(pw, name, str(t))
        default_row = pw["mutants"][name]["extra_tiles"][str(t)]
        if default_row["rate"] >= goal:
            found.append(f"{_tile_name(t)} at {b['spp']} spp: {rate_cell(default_row)}")
        elif hit and (not s.get("spp") or hit[0] < s["spp"]):
            found.append(f"{_tile_name(t)} at {hit[0]} spp: {rate_cell(hit[1])}")
    return "; ".join(found)


def _escalation_cell(pw: dict[str, Any], name: str, spp: int) -> str:
    """'k/n' of ``name`` at the escalation budget ``spp``."""
    row = next(lvl["rows"][name] for lvl in pw["escalation"] if lvl["spp"] == spp)
    return rate_cell(row)


def _power(r: Run, fa: dict[str, Any] | None) -> list[str]:
    pw = r.power
    b, goal = pw["budget"], pw["goal"]
    n_seeds = len(pw["seeds"]["mcrt"])
    plain = {n: m for n, m in pw["mutants"].items() if not m["subtle"]}
    full = [n for n, m in plain.items() if m["k"] == m["n"]]
    lines = [f"## Power at the default budget (against {_opponent(r)}, {n_seeds} seeds per mutant)", ""]
    if plain:
        iv = interval(plain[full[0]]["interval"]) if full else ""
        lines.append(f"**{len(full)} of the {len(plain)} non-subtle mutants are detected on {n_seeds} of {n_seeds} seeds**"
                     + (f", with a 95 % interval of {iv}." if full else "."))
        ranked = sorted((m["median_max_abs_t"] if m["median_max_abs_t"] is not None else float("inf"), n)
                        for n, m in plain.items() if m["rate"] >= goal)
        if len(ranked) > 3:
            weak = [f"`{n}` (median largest |t| {t:.1f}, {plain[n]['median_n_rejected']:.0f} rejected tests)" for t, n in ranked[:3]]
            lines[-1] += f" The weakest are {_join(weak)}; every other has a median |t| above {math.floor(ranked[3][0])}."
        lines.append("")
    below = pw["below_goal"]
    if below:
        effects = pw["effects"]
        weak = [n for n in below if n in effects and (effects[n]["tiles"][str(b["tile"])]["max_abs_t"] or float("inf")) >= NOISE_T]
        none = [n for n in below if n in effects and n not in weak]
        text = (f"{len(below)} mutant{'s are' if len(below) > 1 else ' is'} below the {100 * goal:.0f} % goal at "
                f"{b['camera']} camera, max depth {b['max_depth']}, {b['spp']} spp.")
        if effects:
            if weak and not none:
                text += (" All of them change the expected image, as the effect sizes show: each is a weak test at this "
                         "budget, not a mutant without effect.")
            else:
                if weak:
                    text += f" {_join([f'`{n}`' for n in weak])} change the expected image (a weak test at this budget)."
                if none:
                    text += (f" {_join([f'`{n}`' for n in none])} do not measurably change it at {effects[none[0]]['spp']} spp "
                             f"(|t| below {NOISE_T:g}).")
        for f in pw["followups"]:
            if all(f["rows"][n]["rate"] >= goal for n in below):
                text += f" The follow-up at {f['label']} detects every one of them."
        lines += [text, "", "| mutant | default budget | effect | detected on >= " + f"{100 * goal:.0f} % of seeds at |",
                  "|---|---|---|---|"]
        for n in below:
            name = f"`{n}`" + (" (subtle)" if n in pw["subtle"] else "")
            lines.append(f"| {name} | {rate_cell(pw['mutants'][n])} | {_effect_words(effects.get(n), b['tile'], b['spp'])} | "
                         f"{_detected_at(pw, n)} |")
        lines.append("")
        for f in pw["followups"]:
            if not any(f["rows"][n]["rate"] >= goal for n in below):
                cells = [f"`{n}` {rate_cell(f['rows'][n])}" for n in below]
                lines.append(f"The follow-up at {f['label']} does not help any of them: {_join(cells)} "
                             f"(control {rate_cell(f['rows'][CONTROL])}).")
        lines.append("")
    helped = []
    for t in pw["tiles"][1:]:
        gains = []
        for n in below:
            row = pw["mutants"][n]["extra_tiles"][str(t)]
            hit = _first_goal(pw, n, str(t))
            if row["rate"] >= goal:
                gains.append(f"`{n}` at {b['spp']} spp ({rate_cell(row)})")
            elif hit:
                gains.append(f"`{n}` at {hit[0]} spp ({rate_cell(hit[1])})")
        if gains and t > b["tile"]:
            rate = f"; their false-alarm rate: {fa['extra_tiles'][str(t)]['k']} in {fa['extra_tiles'][str(t)]['n']}" if fa and str(t) in fa["extra_tiles"] else ""
            helped.append(f"- {_tile_name(t)} catch {_join(gains)}{rate}.")
    if helped:
        lines += ["Tile size:", "", *helped, "",
                  ("A second, coarser family of tiles would buy power against small, spread-out biases; the two families "
                   "together would need their own correction (Holm over both) to keep the family-wise level, a change to "
                   "`mcrt.stats`, which tests one family."), ""]
    return lines


def _other_power(r: Run, main: Run | None) -> list[str]:
    pw = r.power
    b = pw["budget"]
    ctl = [pw["control"], *(lvl["rows"][CONTROL] for lvl in pw["escalation"])]
    fa = r.false_alarms
    where = f"`{r.folder}power.md`"
    if fa and not fa["goal_met"]:
        return [(f"Against {_opponent(r)}, every detection rate is inflated by the {pct(fa['primary']['rate'], 1)} false-alarm "
                 f"rate: its control row rejects {rate_cell(pw['control'])} correct renders, so {where} does not measure "
                 f"power at {b['spp']} spp."), ""]
    plain = {n: m for n, m in pw["mutants"].items() if not m["subtle"]}
    full = [n for n, m in plain.items() if m["k"] == m["n"]]
    worst = max(c["k"] for c in ctl)
    text = (f"Against {_opponent(r)} ({where}) the control row rejects {f'at most {worst}' if worst else 'none'} of "
            f"{ctl[0]['n']} correct renders at any budget, and {len(full)} of {len(plain)} non-subtle mutants are detected "
            f"on every seed at {b['spp']} spp.")
    stated = []
    for n, s in pw["stated_budgets"].items():
        ref = (main.power["stated_budgets"].get(n, {}) if main and main.power else {}).get("spp")
        if s["spp"]:
            stated.append(f"`{n}` reaches the goal at {s['spp']} spp" + (f" ({ref} against {_opponent(main)})" if ref else ""))
        else:
            stated.append(f"`{n}` not up to {max((lvl['spp'] for lvl in pw['escalation']), default=b['spp'])} spp "
                          f"with {b['tile']}x{b['tile']} tiles")
    if stated:
        text += " " + _join(stated)[0].upper() + _join(stated)[1:] + "."
    for f in pw["followups"]:
        names = [n for n in f["rows"] if n != CONTROL]
        if names and all(f["rows"][n]["rate"] >= pw["goal"] for n in names):
            text += f" At {f['label']} all of them are detected on {_join([rate_cell(f['rows'][n]) for n in names])} seeds."
    return [text, ""]


def _suite(runs: list[Run]) -> list[str]:
    b = runs[0].study["budget"]
    n = 10
    k = false_alarm_bound(n, b["alpha"], 0.99)
    return [
        "## The reduced version in the default suite",
        "",
        ("`tests/test_validation.py` runs a reduced version of these studies with fixed seeds (other than the studies'), so "
         "each of its tests always passes or always fails on a given machine: a few correct renders against fresh Mitsuba "
         f"renders, whose false alarms must stay within the binomial bound (`false_alarm_bound`: with {n} renders at alpha "
         f"{b['alpha']:g}, more than {k} fails), and every mutant on two seeds where the power study detects it: at the "
         "default budget, or at the follow-up configuration or stated budget the tables above name. Its docstring lists "
         "the seeds and bounds."),
        "",
        "## Independence of the samples",
        "",
        ("A per-pixel variance estimate assumes the samples of a pixel are independent. mcrt draws them from its own "
         "generator (`mcrt.rng`, tested in `tests/test_rng.py`), and a lane that traces several of its pixel's paths one "
         "after another starts each new path from fresh numbers; correlated samples would make the tile tests' standard "
         "errors wrong, and the false-alarm rates and p-value histograms above are where that would show."),
        "",
    ]


def _time(runs: list[Run]) -> list[str]:
    lines = ["## Time", ""]
    for r in runs:
        parts = []
        if r.false_alarms:
            t = r.false_alarms["timing"]
            parts.append(f"false-alarm study {t['total_s']:.0f} s ({t['per_trial_s']:.2f} s per trial: mcrt {t['mcrt_s']:.0f} s, "
                         f"opponent {t['opponent_s']:.0f} s)")
        if r.power:
            parts.append(f"power study {r.power['timing']['total_s']:.0f} s")
        lines.append(f"- Against {_opponent(r)} ({r.meta['date']}, {r.meta['machine']['cpu']}, "
                     f"{r.meta['machine']['cores']} cores): {'; '.join(parts)}.")
    return [*lines, "", "Timings are indicative: the machine may have been shared.", ""]


def readme_markdown(runs: list[Run]) -> str:
    """The README of the validation folder holding ``runs`` (the first is the main run)."""
    main = next((r for r in runs if r.power), None)
    dates = sorted({r.meta["date"][:10] for r in runs})
    lines = [
        "# How well the image comparison works: measured error rates",
        "",
        (f"Generated by `mcrt validate` from the JSON reports in this folder and its sub-folders (runs of {_join(dates)}); "
         "do not edit by hand. `mcrt validate --readme-only --out <this folder>` rewrites it without running a study."),
        "",
        *_files(runs),
        "",
        *_test_under_study(runs),
        *_false_alarms(runs),
    ]
    if main:
        fa = main.false_alarms or next((r.false_alarms for r in runs if r.kind == main.kind and r.false_alarms), None)
        lines += _power(main, fa)
        for r in runs:
            if r.power and r is not main:
                lines += _other_power(r, main)
    lines += [*_suite(runs), *_time(runs)]
    return "\n".join(lines).rstrip() + "\n"
