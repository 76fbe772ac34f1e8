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
    """The most paths one of mcrt's SIMD lanes traces in turn in a render of ``case`` (its first, largest pass)."""
    from mcrt.tracer import pass_layout, pass_size

    n = pass_size(case["width"], case["height"], case["spp"])
    lanes_per_pixel, _ = pass_layout(n, case["width"] * case["height"])
    return -(-n // lanes_per_pixel)


def format_table(rows) -> str:
    """The run's table: one row per case and renderer, with mcrt's speed-up and efficiency ratio beside Mitsuba's."""
    rows = _rows(rows)
    lines = ["| camera | resolution | spp | depth | K | renderer | median s | M paths/s | JIT s | speed-up | MSE excess | "
             "efficiency ratio | paths per lane |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
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
                     f"{f'{eff:.1f}x' if eff else '-'} | {lane} |")
    return "\n".join(lines)


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
    from mcrt.mitsuba import VARIANTS

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
            f"{data['intersector']} |"]


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
            f"(`mcrt.tracer.pass_layout`); where a lane has more than one, a path that ends is followed in the same loop "
            f"iteration by the lane's next (path regeneration), so a packet does not idle while its longest path finishes.")


def _efficiency(data: dict) -> list[str]:
    ratios = [(efficiency_ratio(a, b), speedup(a, b)) for a, b in pairs(data["rows"])]
    ratios = [(e, s) for e, s in ratios if e is not None]
    if not ratios:
        return []
    spread = [e / s for e, s in ratios]
    return ["", f"MSE excess: each timed render's mean squared error against the committed Mitsuba reference of its case, "
                f"less the reference's own noise (mean(var_ref / spp_ref)), averaged over the {_times(data['repeats'], 'timed render')}; "
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
             *_efficiency(data), *_spp_section(data), *_profile_section(data), *_reading(data, out_dir)]
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
