"""The benchmark's page: ``index.md`` of ``mcrt bench --report DIR``, written from one run's measurements.

Every number on the page comes from the run's dictionary
(:func:`mcrt.bench.bench_data`, the JSON file written beside the page); the
prose says how the numbers were measured and how to read them. A hand-kept
log of earlier experiments (``tried.md``: what was tried, changed and
dropped, with the timings of its own runs) may follow as the last section,
copied verbatim under a heading that says its numbers are not this run's.

The tables are also what ``mcrt bench`` prints (:func:`format_table`,
:func:`format_profile`). This module only formats: it measures nothing.
"""

from __future__ import annotations

import os
import statistics
from dataclasses import asdict, is_dataclass
from pathlib import Path

import numpy as np

#: The section that holds the hand-kept log, the only one whose numbers do not come from the run.
LOG_HEADING = "## Hand-kept log (not from this run)"

#: Packet width of Dr.Jit's LLVM backend for the widest vector extension it finds.
_PACKET_LANES = {"AVX-512": 16, "AVX2": 8, "AVX": 8, "SSE4.2": 4}

#: What each kernel-profile variant leaves out or changes (mcrt.bench.kernel_profile's keys).
_PROFILE_TEXT = {
    "no_tetrahedron": "The tetrahedron costs {cost:.3g} ms ({share:.0f} % of the full kernel): a closest-hit test of its "
                      "four faces at every bounce, and the shadow test in packets where a segment meets its enclosing ball.",
    "no_sphere": "The mirror sphere costs {cost:.3g} ms ({share:.0f} %): its closest hit, its shadow test and the longer "
                 "paths through it.",
    "depth2": "The path beyond its first vertex costs {cost:.3g} ms ({share:.0f} %): the full kernel less the depth-2 one.",
    "depth1": "A camera ray and its hit alone take {ms:.3g} ms ({ratio_pct:.0f} % of the full kernel).",
    "k4": "Three more shadow rays per diffuse vertex (K = 4) add {extra_pct:.0f} % to the kernel.",
    "triangles": "The brute-force watertight triangle intersector (`--intersector triangles`: every flat surface as "
                 "triangles, instead of slabs and the tetrahedron's four planes) makes the kernel {ratio:.1f} times as slow.",
    "rng": "Random numbers alone (25 draws per path from mcrt.rng's 32-bit generator) take {ratio_pct:.0f} % of the full "
           "kernel.",
}


def _rows(rows) -> list[dict]:
    """Rows as dictionaries (mcrt.bench's dataclasses or their JSON form)."""
    return [asdict(r) if is_dataclass(r) else r for r in rows]


def _key(case: dict) -> tuple:
    return (case["camera"], case["width"], case["height"], case["spp"], case["max_depth"], case.get("light_samples", 1))


def _median(row: dict) -> float:
    return row["median_time"] if "median_time" in row else statistics.median(row["times"])


def pairs(rows) -> list[tuple[dict, dict]]:
    """(mcrt row, Mitsuba row) of every case that has both, in the order of the run."""
    by_case: dict[tuple, dict[str, dict]] = {}
    for r in _rows(rows):
        by_case.setdefault(_key(r["case"]), {})[r["renderer"]] = r
    return [(d["mcrt"], d["mitsuba"]) for d in by_case.values() if "mcrt" in d and "mitsuba" in d]


def speedup(mcrt: dict, mitsuba: dict) -> float:
    """mcrt's paths per second over Mitsuba's, in the same case of the same run."""
    return mcrt["paths_per_second"] / mitsuba["paths_per_second"]


def efficiency_ratio(mcrt: dict, mitsuba: dict) -> float | None:
    """mcrt's efficiency 1 / (MSE excess x time) over Mitsuba's; None without a committed reference."""
    if mcrt.get("efficiency") and mitsuba.get("efficiency"):
        return mcrt["efficiency"] / mitsuba["efficiency"]
    return None


def paths_per_lane(case: dict) -> int:
    """The most paths one of mcrt's SIMD lanes traces in turn in a render of ``case`` (mcrt.tracer.lane_layout)."""
    from mcrt.tracer import lane_layout

    return lane_layout(case["width"] * case["height"], case["spp"])[1]


def format_table(rows) -> str:
    """The run's table: one row per case and renderer, with mcrt's speed-up and efficiency ratio beside Mitsuba's."""
    rows = _rows(rows)
    lines = ["| camera | resolution | spp | depth | K | renderer | median s | M paths/s | JIT s | speed-up | MSE excess | "
             "efficiency ratio | paths per lane | paths timed |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    base = {_key(r["case"]): r for r in rows if r["renderer"] == "mitsuba"}
    for r in rows:
        c = r["case"]
        b = base.get(_key(c))
        ratio = f"{r['paths_per_second'] / b['paths_per_second']:.1f}x" if b else ""
        jit = f"{r['compile_time']:.2f}" if r.get("compile_time") is not None else "-"
        mse = f"{r['mse_excess']:.3g}" if r.get("mse_excess") is not None else "-"
        eff = efficiency_ratio(r, b) if b else None
        lane = str(paths_per_lane(c)) if r["renderer"] == "mcrt" else "-"
        lines.append(f"| {c['camera']} | {c['width']}x{c['height']} | {c['spp']} | {c['max_depth']} | {c.get('light_samples', 1)} "
                     f"| {r['renderer']} | {_median(r):.4f} | {r['paths_per_second'] / 1e6:.2f} | {jit} | {ratio} | {mse} | "
                     f"{f'{eff:.1f}x' if eff else '-'} | {lane} | {_timed(r)} |")
    return "\n".join(lines)


def _timed(row: dict) -> str:
    """Paths of one timed render, marked where that was a bounded part of the case."""
    paths = row.get("paths") or row["case"]["width"] * row["case"]["height"] * row["case"]["spp"]
    return f"{paths:,}" + (" (part)" if row.get("bounded") else "")


def format_profile(rows, paths: int) -> str:
    """The kernel profile: each variant's median kernel time and its share of the full kernel's."""
    rows = _rows(rows)
    full = rows[0]["kernel_ms"]
    lines = [f"| kernel ({paths:,} paths) | ms | share of the full kernel |", "|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['variant']} | {r['kernel_ms']:.3g} | {100 * r['kernel_ms'] / full:.0f} % |")
    return "\n".join(lines)


def spp_groups(rows) -> list[list[tuple[dict, dict]]]:
    """Pairs of cases that differ only in spp, where there are at least two spp: each group sorted by spp."""
    groups: dict[tuple, list] = {}
    for a, b in pairs(rows):
        c = a["case"]
        groups.setdefault((c["camera"], c["width"], c["height"], c["max_depth"], c.get("light_samples", 1)), []).append((a, b))
    return [sorted(g, key=lambda p: p[0]["case"]["spp"]) for g in groups.values() if len({p[0]["case"]["spp"] for p in g}) > 1]


def time_fit(group: list[tuple[dict, dict]], side: int) -> tuple[float, float]:
    """Least-squares line of median render time against paths: (seconds per render, seconds per path)."""
    paths = [p[side]["case"]["width"] * p[side]["case"]["height"] * p[side]["case"]["spp"] for p in group]
    slope, intercept = np.polyfit(np.asarray(paths, dtype=float), [_median(p[side]) for p in group], 1)
    return float(intercept), float(slope)


def _times(n: int, word: str) -> str:
    return f"{n} {word}" + ("" if n == 1 else "es" if word.endswith("s") else "s")


def _case_text(c: dict, skip: str = "") -> str:
    parts = {"camera": f"{c['camera']} camera", "resolution": f"{c['width']}x{c['height']}", "spp": f"{c['spp']} spp",
             "max_depth": f"max depth {c['max_depth']}"}
    return ", ".join(v for k, v in parts.items() if k != skip)


def _machine(data: dict) -> list[str]:
    from mcrt.mitsuba_scene import VARIANTS

    p = data["provenance"]
    m, v = p["machine"], p["versions"]
    simd = p.get("simd")
    lanes = _PACKET_LANES.get(simd) if data["backend"] == "llvm" else None
    vector = f"; widest vector extension {simd}" + (f" (Dr.Jit's LLVM backend runs {lanes}-lane packets)" if lanes else "") \
        if simd else ""
    versions = ", ".join(f"{name} {v[key]}" for key, name in (("mcrt", "mcrt"), ("mitsuba", "Mitsuba"), ("drjit", "Dr.Jit"),
                                                              ("numpy", "NumPy"), ("python", "Python")) if v.get(key))
    if p.get("libllvm"):
        versions += f", libLLVM {p['libllvm']}"
    return ["| | |", "|---|---|",
            f"| date | {p['date']} |",
            f"| CPU | {m['cpu']}, {m['cores']} cores{vector} |",
            f"| Dr.Jit threads | {p['drjit_threads']} |",
            f"| platform | {m['platform']} |",
            f"| versions | {versions} |",
            f"| git commit | {p.get('git_commit') or '-'} (source hash {p.get('source_hash', '-')}) |",
            f"| backend | {data['backend']} (Mitsuba variant {VARIANTS.get(data['backend'], '-')}); mcrt's intersector "
            f"{data['intersector']} |", *_load_rows(data)]


def _method(data: dict) -> str:
    n = data["repeats"]
    return (f"Each case is rendered by both renderers in turn: one untimed warm-up render each (it compiles the kernels), "
            f"then {_times(n, 'repetition')} in which the renderers alternate (mcrt, Mitsuba, mcrt, ...), so a machine "
            f"whose speed drifts slows both alike; the table gives the medians of the {_times(n, 'timed render')}. Mitsuba is `mi.render` "
            f"(its `path` integrator) on a scene loaded once per case; mcrt is `mcrt.render.render`, renderer `mcrt` "
            f"(intersector {data['intersector']}). JIT compile time is the warm-up render's, from Dr.Jit's kernel history "
            f"(0: the on-disk kernel cache already held the kernels). Paths per second count one path per pixel sample, "
            f"whatever its length; the speed-up is mcrt's paths per second over Mitsuba's in the same case of this run. "
            f"Paths per lane: the most paths one of mcrt's SIMD lanes traces in turn in that render "
            f"(`mcrt.tracer.lane_layout`); where a lane has more than one, a path that ends is followed in the same loop "
            f"iteration by the lane's next (path regeneration), so a packet does not idle while its longest path finishes. "
            f"K is mcrt's shadow rays per diffuse vertex; Mitsuba's path integrator samples one emitter point per vertex "
            f"whatever K, so its rows with K > 1 time the same integrator as K = 1."
            + _bounded_text(data))


def _bounded_text(data: dict) -> str:
    cap = data.get("max_paths")
    if not cap:
        return ""
    n = sum(1 for r in data["rows"] if r.get("bounded"))
    return (f" Bounded measurements ('(part)' under paths timed; {n} rows): a render of more than {cap:,} paths is "
            f"too long to repeat, so each timed render covers the same bands of it for both renderers: as many whole "
            f"rows as {cap:,} paths allow at the case's spp (at least one), in up to {data.get('bands', 4)} equal bands "
            f"centred in equal parts of the image (the top rows, ceiling and light, cost less per path than the "
            f"middle ones), mcrt rendering those rows alone with its own launches and Mitsuba `mi.render` of films "
            f"cropped to them. Paths per second are the paths of those rows over their time; the MSE needs the "
            f"whole image, so bounded rows have none.")


def _efficiency(data: dict) -> list[str]:
    ratios = [(efficiency_ratio(a, b), speedup(a, b)) for a, b in pairs(data["rows"])]
    ratios = [(e, s) for e, s in ratios if e is not None]
    if not ratios:
        return []
    spread = [e / s for e, s in ratios]
    renders = data.get("mse_renders", data["repeats"])
    return ["", f"MSE excess: a render's mean squared error against the committed Mitsuba reference of its case, "
                f"less the reference's own noise (mean(var_ref / spp_ref)), averaged over {_times(max(renders, data['repeats']), 'render')} "
                f"of distinct seeds (the {_times(data['repeats'], 'timed render')} and untimed others); "
                f"efficiency ratio: 1 / (MSE excess x median time), mcrt's over Mitsuba's ('-': no committed reference of "
                f"that case). At few samples per pixel a single render's MSE swings with the rare bright paths, so the "
                f"efficiency ratio scatters around the speed-up: in this run it lies between {min(spread):.2f} and "
                f"{max(spread):.2f} times the speed-up of its case."]


def _spp_section(data: dict) -> list[str]:
    groups = spp_groups(data["rows"])
    if not groups:
        return []
    out = ["", "## Against samples per render", "",
           "| camera | resolution | depth | spp | paths per lane | mcrt median s | Mitsuba median s | mcrt M paths/s | "
           "Mitsuba M paths/s | speed-up |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for g in groups:
        for a, b in g:
            c = a["case"]
            out.append(f"| {c['camera']} | {c['width']}x{c['height']} | {c['max_depth']} | {c['spp']} | {paths_per_lane(c)} | "
                       f"{_median(a):.4f} | {_median(b):.4f} | {a['paths_per_second'] / 1e6:.2f} | "
                       f"{b['paths_per_second'] / 1e6:.2f} | {speedup(a, b):.1f}x |")
    out += ["", "A straight line of median time against paths through each camera's renders (least squares) splits a "
                "render's time into a fixed cost and a cost per path:", ""]
    for g in groups:
        (m0, m1), (w0, w1) = time_fit(g, 0), time_fit(g, 1)
        c = g[0][0]["case"]
        if m1 <= 0 or w1 <= 0:
            out.append(f"- {_case_text(c, 'spp')}: the renders are too short to tell a cost per path from the fixed cost.")
            continue
        out.append(f"- {_case_text(c, 'spp')}: mcrt {1e3 * m0:.2g} ms per render plus {1e9 * m1:.3g} ns per path, "
                   f"Mitsuba {1e3 * w0:.2g} ms plus {1e9 * w1:.3g} ns per path: {w1 / m1:.1f}x per path.")
    out += ["", "The fixed costs weigh most in the shortest renders; and where a lane traces one path (paths per lane 1), "
                "path regeneration has nothing to regenerate."]
    return out


def _profile_section(data: dict) -> list[str]:
    prof = data.get("kernel_profile") or []
    if not prof:
        return []
    pc = data["kernel_profile_case"]
    paths = pc["width"] * pc["height"] * pc["spp"]
    full = prof[0]["kernel_ms"]
    out = ["", "## Where mcrt's time goes", "",
           f"Execution time of mcrt's path kernel alone (Dr.Jit's kernel history), median of {_times(pc['repeats'], 'pass')} after "
           f"one warm-up pass: {pc['camera']} camera, {pc['width']}x{pc['height']} x {pc['spp']} spp = {paths:,} paths, "
           f"max depth {pc['max_depth']} (`--profile`). Each variant leaves one part out or changes one setting; a part's "
           f"cost is the difference to the full kernel. The variants render other images, so they time work, not "
           f"correctness.", "", format_profile(prof, paths), ""]
    for r in prof[1:]:
        text = _PROFILE_TEXT.get(r.get("key", ""))
        if text:
            ms = r["kernel_ms"]
            out.append("- " + text.format(cost=full - ms, share=100 * (full - ms) / full, ms=ms, ratio=ms / full,
                                          ratio_pct=100 * ms / full, extra_pct=100 * (ms - full) / full))
    return out


def _load_rows(data: dict) -> list[str]:
    loads = [r["load"][0] for r in _rows(data["rows"]) if r.get("load")]
    if not loads:
        return []
    end = data.get("load_end") or [float("nan")]
    took = f"; the run took {data['seconds'] / 60:.1f} min" if data.get("seconds") else ""
    return [f"| load average | {min(loads):.2f} to {max(loads):.2f} (1 minute, before each case; {end[0]:.2f} at the end; "
            f"other work shared the machine, which the alternation evens out{took}) |"]


def _goal_pairs(data, pred):
    return [(a, b) for a, b in pairs(data["rows"]) if pred(a["case"])]


def goals(data: dict) -> list[tuple[str, bool | None, str]]:
    """(goal, met or None where unmeasured, the measured figure) for the issue's goals, from this run alone."""
    out = []

    def worst(ps):
        a, b = min(ps, key=lambda p: speedup(*p))
        return speedup(a, b), _case_text(a["case"])

    big = _goal_pairs(data, lambda c: c["max_depth"] == 8 and c.get("light_samples", 1) == 1 and 256 <= c["width"] <= 4096
                      and c["spp"] >= 16 and c["width"] != 800)
    if big:
        v, where = worst(big)
        out.append(("at least 15x Mitsuba's paths/s at depth 8, 256x256 to 4096x4096, 16 spp and more", v >= 15,
                    f"lowest {v:.1f}x ({where}) over {len(big)} cases"))
    small = _goal_pairs(data, lambda c: c["spp"] == 1 or c["width"] == 64)
    if small:
        v, where = worst(small)
        out.append(("at least 10x at 1 spp and at 64x64", v >= 10, f"lowest {v:.1f}x ({where}) over {len(small)} cases"))
    flat = data.get("flatness")
    for cam in sorted({r["camera"] for r in flat["rows"]} if flat else ()):
        mine = [r for r in flat["rows"] if r["camera"] == cam]
        at = [r for r in mine if r["width"] == 4096]
        if at:
            best = max(mine, key=lambda r: r["paths_per_second"])
            ratio = at[0]["paths_per_second"] / best["paths_per_second"]
            out.append((f"mcrt's throughput at 4096x4096 within 15 % of its best ({cam} camera, depth {flat['max_depth']}, "
                        f"{flat['spp']} spp, renders interleaved)", ratio >= 0.85,
                        f"{ratio * 100:.0f} % of its best: {at[0]['paths_per_second'] / 1e6:.1f} M paths/s against "
                        f"{best['paths_per_second'] / 1e6:.1f} at {best['width']}x{best['height']} (medians of "
                        f"{flat['rounds']} interleaved rounds)"))
    for cam in sorted({r["case"]["camera"] for r in _rows(data["rows"])} if not flat else ()):
        mine = [r for r in _rows(data["rows"]) if r["renderer"] == "mcrt" and r["case"]["camera"] == cam
                and r["case"]["max_depth"] == 8 and r["case"].get("light_samples", 1) == 1 and r["case"]["spp"] >= 16]
        at = [r for r in mine if r["case"]["width"] == 4096]
        if mine and at:
            best = max(mine, key=lambda r: r["paths_per_second"])
            worst4k = min(at, key=lambda r: r["paths_per_second"])
            ratio = worst4k["paths_per_second"] / best["paths_per_second"]
            out.append((f"mcrt's throughput at 4096x4096 within 15 % of its best ({cam} camera, depth 8, 16 spp and more)",
                        ratio >= 0.85, f"{ratio * 100:.0f} % of its best: {worst4k['paths_per_second'] / 1e6:.1f} M paths/s "
                        f"({_case_text(worst4k['case'])}) against {best['paths_per_second'] / 1e6:.1f} "
                        f"({_case_text(best['case'])})"))
    mem = [m for m in data.get("memory_runs") or [] if m["width"] == 4096 and m["spp"] == 1024]
    if mem:
        m = mem[0]
        out.append(("peak memory under 1 GB for a 4096x4096, 1024-spp render", m["peak_rss_mib"] < 1024,
                    f"{m['peak_rss_mib']:.0f} MiB (max depth {m['max_depth']}, the whole render, {m['seconds']:.0f} s)"))
    eff = [(efficiency_ratio(a, b), speedup(a, b), a["case"]) for a, b in pairs(data["rows"]) if efficiency_ratio(a, b)]
    if eff:
        lo = min(eff, key=lambda e: e[0] / e[1])
        out.append(("equal-time efficiency keeps pace with the speed-up", lo[0] / lo[1] >= 0.85,
                    f"efficiency ratio {lo[0]:.1f}x against a speed-up of {lo[1]:.1f}x at the furthest case "
                    f"({_case_text(lo[2])}; {len(eff)} cases with a committed reference)"))
    return out


def _flatness_section(data: dict) -> list[str]:
    flat = data.get("flatness")
    if not flat:
        return []
    out = ["", "## Throughput against resolution, renders interleaved", "",
           f"mcrt alone, {flat['spp']} spp, max depth {flat['max_depth']}: {flat['rounds']} rounds, each rendering every "
           f"resolution once in turn after one warm-up render each (`--flatness`), so a machine whose speed drifts "
           f"slows every resolution alike; medians of the rounds. Renders over {data.get('max_paths', 0):,} paths "
           f"are timed on the bands of rows of the table above.", "",
           "| camera | resolution | paths per render | median s | M paths/s | share of the camera's best |",
           "|---|---|---|---|---|---|"]
    for cam in sorted({r["camera"] for r in flat["rows"]}):
        mine = [r for r in flat["rows"] if r["camera"] == cam]
        best = max(r["paths_per_second"] for r in mine)
        for r in mine:
            part = " (part)" if r["bounded"] else ""
            out.append(f"| {cam} | {r['width']}x{r['height']} | {r['paths']:,}{part} | {statistics.median(r['times']):.4f} | "
                       f"{r['paths_per_second'] / 1e6:.2f} | {100 * r['paths_per_second'] / best:.0f} % |")
    return out


def _sampler_section(data: dict) -> list[str]:
    cost = data.get("sampler_cost")
    if not cost:
        return []
    ratios = [r["ratio"] for r in cost["rows"]]
    out = ["", "## Cost of the sobol pixel sampler", "",
           f"mcrt with `--pixel-sampler sobol` ({cost['replicates']} replicates; mcrt.samplers) against independent "
           f"samples, whole renders at max depth {cost['max_depth']}: {cost['rounds']} rounds, each rendering "
           f"independent then sobol after one warm-up render each (`--sampler-cost`); medians of the rounds. The sobol "
           f"render takes {min(ratios):.2f} to {max(ratios):.2f} times the independent render's time.", "",
           "| camera | resolution | spp | paths | independent s | sobol s | independent M paths/s | sobol M paths/s | "
           "time ratio |", "|---|---|---|---|---|---|---|---|---|"]
    for r in cost["rows"]:
        t_i, t_s = (statistics.median(r["times"][k]) for k in ("independent", "sobol"))
        out.append(f"| {r['camera']} | {r['width']}x{r['height']} | {r['spp']} | {r['paths']:,} | {t_i:.4f} | {t_s:.4f} | "
                   f"{r['paths'] / t_i / 1e6:.2f} | {r['paths'] / t_s / 1e6:.2f} | {r['ratio']:.2f} |")
    return out


def _previous_section(data: dict) -> list[str]:
    prev = data.get("previous")
    if not prev:
        return []
    old = {_key(p["case"]): p["speedup"] for p in prev["speedups"]}
    both = [(a["case"], old[_key(a["case"])], speedup(a, b)) for a, b in pairs(data["rows"]) if _key(a["case"]) in old]
    if not both:
        return []
    ratios = [new / was for _, was, new in both]
    q1, med, q3 = (float(np.quantile(ratios, q)) for q in (0.25, 0.5, 0.75))
    lo, hi = min(range(len(both)), key=ratios.__getitem__), max(range(len(both)), key=ratios.__getitem__)
    return ["", "## Against the previous run", "",
            f"The speed-up over Mitsuba of the {len(both)} cases this run shares with the run whose bench.json it "
            f"replaced (commit {prev.get('commit') or '-'}, {prev.get('date') or '-'}), this run's over that run's: "
            f"median {med:.2f}, quartiles {q1:.2f} and {q3:.2f}, lowest {ratios[lo]:.2f} ({_case_text(both[lo][0])}: "
            f"{both[lo][1]:.1f}x then, {both[lo][2]:.1f}x now), highest {ratios[hi]:.2f} ({_case_text(both[hi][0])}: "
            f"{both[hi][1]:.1f}x then, {both[hi][2]:.1f}x now). Both runs share the machine with other work "
            f"(load averages above and in that run's page)."]


def _goals_section(data: dict) -> list[str]:
    g = goals(data)
    if not g:
        return []
    out = ["", "## Goals", "", "| goal | met | measured in this run |", "|---|---|---|"]
    out += [f"| {name} | {'yes' if met else 'no'} | {fig} |" for name, met, fig in g]
    return out


def plot_speedups(data: dict, out_dir: Path) -> list[str]:
    """speedup_resolution.png and speedup_spp.png in ``out_dir`` (speed-up and both renderers' paths/s); their names."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    written = []
    for name, dim, label in (("speedup_resolution.png", "width", "resolution (pixels per side)"),
                             ("speedup_spp.png", "spp", "samples per pixel")):
        groups: dict[tuple, list] = {}
        for a, b in pairs(data["rows"]):
            c = a["case"]
            rest = tuple(v for k, v in sorted(c.items()) if k not in (dim, "height") and not (dim == "width" and k == "width"))
            groups.setdefault(rest, []).append((a, b))
        groups = {k: sorted(g, key=lambda p: p[0]["case"][dim]) for k, g in groups.items() if len(g) >= 3}
        if not groups:
            continue
        fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11, 4))
        for g in groups.values():
            c = g[0][0]["case"]
            tag = f"{c['camera']}, depth {c['max_depth']}" + (f", {c['spp']} spp" if dim == "width" else f", {c['width']}x{c['height']}")
            xs = [p[0]["case"][dim] for p in g]
            line, = ax.plot(xs, [speedup(*p) for p in g], "o-", label=tag)
            ax2.plot(xs, [p[0]["paths_per_second"] / 1e6 for p in g], "o-", color=line.get_color(), label=f"mcrt, {tag}")
            ax2.plot(xs, [p[1]["paths_per_second"] / 1e6 for p in g], "s--", color=line.get_color(), label=f"Mitsuba, {tag}")
        for a in (ax, ax2):
            a.set_xscale("log", base=2)
            a.set_xlabel(label)
            a.grid(True, alpha=0.3)
        ax.axhline(15, color="grey", lw=0.8, ls=":")
        ax.set_ylabel("mcrt paths/s over Mitsuba's")
        ax.set_ylim(bottom=0)
        ax2.set_yscale("log")
        ax2.set_ylabel("M paths/s")
        ax.legend(fontsize=7)
        ax2.legend(fontsize=6)
        fig.tight_layout()
        fig.savefig(Path(out_dir) / name, dpi=90)
        plt.close(fig)
        written.append(name)
    return written


def _plots_section(data: dict, out_dir: Path) -> list[str]:
    names = plot_speedups(data, out_dir)
    if not names:
        return []
    return ["", "## Speed-up against resolution and samples per pixel", "",
            "Left: mcrt's paths per second over Mitsuba's (dotted: 15x); right: both renderers' paths per second "
            "(solid mcrt, dashed Mitsuba). From the table above.", ""] + [f"![{n[:-4]}]({n})" for n in names]


def _memory_section(data: dict) -> list[str]:
    runs = data.get("memory_runs") or []
    if not runs:
        return []
    out = ["", "## Peak memory", "",
           "Whole mcrt renders (near camera), each in a fresh Python process (`mcrt.bench.memory_runs`); peak resident "
           "memory is the process's own high-water mark (VmHWM in /proc/self/status), which includes the interpreter, Dr.Jit, LLVM and the output image "
           "(mean and variance, float32). A tile's memory does not depend on the depth, so the 1024-spp 4096x4096 render "
           "(every pixel, every sample: the whole image) runs at max depth 1, camera rays only, which makes it short "
           "enough for this run; the 16-spp one at depth 8 shows the same memory with whole paths.", "",
           "| resolution | spp | depth | seconds | M paths/s | output image MiB | peak RSS MiB |", "|---|---|---|---|---|---|---|"]
    for m in runs:
        out.append(f"| {m['width']}x{m['height']} | {m['spp']} | {m['max_depth']} | {m['seconds']:.1f} | "
                   f"{m['paths'] / m['seconds'] / 1e6:.1f} | {m['image_mib']:.0f} | {m['peak_rss_mib']:.0f} |")
    return out


def _limits_section(data: dict) -> list[str]:
    lim = data.get("limits")
    if not lim:
        return []
    seg_s = lim["segments"] / lim["kernel_seconds"]
    out = ["", "## How far from the machine's limit", "",
           f"One launch of the path kernel, {lim['camera']} camera, {lim['width']}x{lim['height']} x {lim['spp']} spp = "
           f"{lim['paths']:,} paths, max depth {lim['max_depth']} ({lim['lanes_per_pixel']} lane(s) per pixel, "
           f"{lim['paths_per_lane']} paths per lane), `mcrt.bench_limits`:", "",
           f"- Work: {lim['segments_per_path']:.2f} segments (closest-hit rays) and {lim['shadow_rays_per_path']:.2f} shadow "
           f"rays per path, counted by a host that counts the estimator's calls.",
           f"- Time: {1e3 * lim['kernel_seconds']:.1f} ms (median kernel execution time), {seg_s / 1e6:.0f} M segments/s, "
           f"{1e9 / seg_s:.2f} ns per segment on {lim['cores']} cores."]
    loop, whole = lim.get("loop_instructions"), lim.get("kernel_instructions")
    if lim.get("kernel_cpu_seconds"):
        out.append(f"- CPU time: {lim['kernel_cpu_seconds'] * 1e3:.1f} ms of both threads per launch (process time, which "
                   f"a loaded machine inflates less than the clock), {1e9 * lim['kernel_cpu_seconds'] / lim['segments']:.2f} "
                   f"core-ns per segment.")
    if loop and lim.get("clock_mhz"):
        hz = lim["clock_mhz"] * 1e6
        # Core cycles per 16 segments (one packet iteration if packets are full), from CPU time where measured.
        cyc = (lim["kernel_cpu_seconds"] * hz if lim.get("kernel_cpu_seconds") else lim["cores"] * hz * lim["kernel_seconds"]) \
            / (lim["segments"] / 16)
        out += [f"- Machine code (the kernel compiled cold, disassembled by Dr.Jit): {whole['instructions']} instructions, "
                f"the path loop {loop['instructions']} per iteration of a 16-lane packet, {loop['zmm']} of them on 512-bit zmm "
                f"registers (16 float32 lanes), {loop['stack']} stack accesses (loop state and constants that do not fit "
                f"the 32 vector registers), {loop['branches']} branches.",
                f"- Against the machine: {lim['cores']} cores x 16 lanes x {lim['clock_mhz'] / 1e3:.1f} GHz (the clock "
                f"/proc/cpuinfo reports) = {lim['cores'] * 16 * hz / 1e9:.0f} G lane-cycles/s. A packet iteration (16 "
                f"segments where every lane is busy) took {cyc:.0f} core cycles, so the loop's {loop['instructions']} "
                f"instructions ran at about {loop['instructions'] / cyc:.2f} per cycle if every iteration ran the whole body "
                f"with full packets; lanes idle in partly finished packets and branches that skip code move that figure "
                f"in opposite directions, and without hardware counters ({lim['perf']}) neither is measured.",
                f"- Memory: the launch moves about {lim['kernel_bytes'] / 2**20:.1f} MiB through memory (pixel indices and "
                f"the tile's float64 sums), {lim['kernel_bytes'] / lim['segments']:.1f} bytes per segment, "
                f"{lim['kernel_bytes'] / lim['kernel_seconds'] / 1e9:.2f} GB/s against the {lim['copy_bandwidth'] / 1e9:.1f} GB/s "
                f"a NumPy copy moves here. Everything else (rays, hits, throughput, random state) stays in registers "
                f"and the stack (L1).",
                "- What bounds it: the instruction stream. The kernel is not memory bound (the line above), and its "
                "vector width is the machine's (16 lanes of AVX-512); what is left is the number of instructions per "
                "segment (intersection with every object, a shadow ray, sampling, the loop state's spills) and how many "
                "of those a core retires per cycle."]
    return out


def _gpu_section(data: dict) -> list[str]:
    return ["", "## GPU", "", data.get("gpu") or "No GPU run."]


def _trends(data: dict) -> list[str]:
    """One line per camera and dimension (spp, max depth, resolution) the run varies, the other settings fixed."""
    dims = {"spp": ("samples per render", lambda c: c["spp"], lambda c: f"{c['spp']} spp"),
            "max_depth": ("max depth", lambda c: c["max_depth"], lambda c: f"depth {c['max_depth']}"),
            "resolution": ("resolution", lambda c: c["width"] * c["height"], lambda c: f"{c['width']}x{c['height']}")}
    fields = {"spp": ("spp",), "max_depth": ("max_depth",), "resolution": ("width", "height")}
    out = []
    for dim, (name, order, label) in dims.items():
        groups: dict[tuple, list] = {}
        for a, b in pairs(data["rows"]):
            c = a["case"]
            rest = tuple(v for k, v in sorted(c.items()) if k not in fields[dim])
            groups.setdefault(rest, []).append((a, b))
        for g in groups.values():
            if len(g) < 2:
                continue
            g.sort(key=lambda p: order(p[0]["case"]))
            steps = ", ".join(f"{speedup(a, b):.1f}x at {label(a['case'])}" for a, b in g)
            out.append(f"- Against {name} ({_case_text(g[0][0]['case'], dim)}): {steps}.")
    return out


def _reading(data: dict, out_dir: Path) -> list[str]:
    ps = pairs(data["rows"])
    if not ps:
        return []
    ranked = sorted(ps, key=lambda p: speedup(*p))
    lo, hi = ranked[0], ranked[-1]
    out = ["", "## Reading it", "",
           f"- mcrt traces {speedup(*lo):.1f} ({_case_text(lo[0]['case'])}) to {speedup(*hi):.1f} "
           f"({_case_text(hi[0]['case'])}) times as many paths per second as Mitsuba in this run's cases."]
    eff = [(efficiency_ratio(*p), p) for p in ps if efficiency_ratio(*p) is not None]
    if eff:
        e_lo, e_hi = min(eff, key=lambda e: e[0]), max(eff, key=lambda e: e[0])
        out.append(f"- Efficiency at equal time, against the committed references: {e_lo[0]:.1f} "
                   f"({_case_text(e_lo[1][0]['case'])}) to {e_hi[0]:.1f} ({_case_text(e_hi[1][0]['case'])}) times "
                   f"Mitsuba's, from single renders.")
    out += _trends(data)
    from mcrt.tracer import PATHS_PER_LANE

    out += ["", f"Two things in mcrt's design make short renders relatively slower: a render's fixed cost, and the lane "
                f"layout, in which a lane traces up to {PATHS_PER_LANE} paths in turn only where a pass has more samples "
                f"per pixel than the lanes it needs (small images keep more lanes per pixel to fill Dr.Jit's thread blocks). "
                f"A single run scatters with the machine's load; compare runs, not digits."]
    links = _convergence_links(out_dir)
    if links:
        out += ["", "Efficiency at equal time over whole spp ladders and several seeds, with the reference's own noise "
                    "subtracted, is measured by the convergence reports (`mcrt report`): " + ", ".join(links) + "."]
    return out


def _convergence_links(out_dir: Path) -> list[str]:
    """The canonical convergence reports: links where the page lies in this checkout, else their paths."""
    root = Path(__file__).resolve().parent.parent
    inside = out_dir.resolve().is_relative_to(root)
    found = [name for name in ("canonical", "canonical_256") if (root / "reports" / name / "index.md").is_file()]
    if not inside:
        return [f"`reports/{name}/`" for name in found]
    return [f"[reports/{name}/]({os.path.relpath(root / 'reports' / name / 'index.md', out_dir.resolve())})" for name in found]


def _log_section(tried: Path, out_dir: Path) -> list[str]:
    link = os.path.relpath(tried.resolve(), out_dir.resolve())
    return ["", LOG_HEADING, "",
            f"Copied verbatim from [{tried.name}]({link}), which is kept by hand: what earlier rounds changed, tried and "
            f"dropped, with the timings of their own runs. Its numbers are not this run's.", "",
            tried.read_text().rstrip()]


def markdown(data: dict, out_dir: Path, *, json_path: Path | None = None, tried: Path | None = None) -> str:
    """The page for one run's dictionary, as written into ``out_dir``."""
    out_dir = Path(out_dir)
    data_link = ""
    if json_path is not None:
        data_link = f" (data: [{Path(json_path).name}]({os.path.relpath(Path(json_path).resolve(), out_dir.resolve())}))"
    log_note = f' outside the last section, "{LOG_HEADING[3:]}",' if tried else ""
    lines = ["# Throughput: mcrt against Mitsuba 3", "",
             f"Written by `mcrt bench --report`: every number on this page{log_note} comes from one run of", "",
             f"    {data['command']}", "", f"on the machine below{data_link}.", "",
             "## Machine", "", *_machine(data), "",
             "## Method", "", _method(data), "",
             "## Paths per second", "", format_table(data["rows"]), "",
             f"Peak memory of the benchmark process: {data['peak_memory_mib']:.0f} MiB.",
             *_efficiency(data), *_goals_section(data), *_plots_section(data, out_dir), *_spp_section(data),
             *_flatness_section(data), *_sampler_section(data), *_previous_section(data), *_memory_section(data), *_profile_section(data), *_limits_section(data), *_gpu_section(data),
             *_reading(data, out_dir)]
    if tried:
        lines += _log_section(Path(tried), out_dir)
    return "\n".join(lines) + "\n"


def write_report(out_dir: Path, data: dict, *, json_path: Path | None = None, tried: Path | None = None) -> Path:
    """Write ``out_dir/index.md`` for one run's dictionary; returns its path."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    index = out_dir / "index.md"
    index.write_text(markdown(data, out_dir, json_path=json_path, tried=tried))
    return index
