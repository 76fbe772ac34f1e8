"""The benchmark on tiny cases: shapes of its results, not speeds (speed lives in reports/bench/), and its report.

The report (mcrt.bench_page) is checked against recorded rows whose numbers
are chosen so that every derived figure is known exactly, and end to end from
a tiny run of ``mcrt bench --report``.
"""

from __future__ import annotations

import json
import re
import statistics

from mcrt.bench import BenchCase, bench_cases, bounded_rows, kernel_profile, run_bench
from mcrt.bench_page import LOG_HEADING, format_profile, format_table, markdown, write_report
from mcrt.cli import build_parser, main
from mcrt.scene import load_scene


def test_run_bench_times_both_renderers():
    rows = run_bench(load_scene(), [BenchCase("near", 16, 16, 2, 2)], repeats=2, progress=False)
    assert [r.renderer for r in rows] == ["mcrt", "mitsuba"]
    assert all(len(r.times) == 2 and r.paths_per_second > 0 for r in rows)
    assert all(r.mse_excess is None and r.efficiency is None for r in rows)  # no committed 16x16 reference
    assert "| near | 16x16 | 2 | 2 |" in format_table(rows)


def test_run_bench_scores_against_the_committed_reference():
    """At 64x64, max depth 2 a committed reference exists: each render's excess MSE and the efficiency are reported.

    Both renderers at 4 spp (seeds 0 and 1) are unbiased, so their excess MSE is their variance over 4 spp:
    well above zero and within a factor 3 of each other.
    """
    rows = run_bench(load_scene(), [BenchCase("near", 64, 64, 4, 2)], repeats=2, progress=False)
    mcrt, mitsuba = rows
    assert mcrt.mse_excess > 0 and mitsuba.mse_excess > 0 and 1 / 3 < mcrt.mse_excess / mitsuba.mse_excess < 3
    assert mcrt.efficiency == 1 / (mcrt.mse_excess * statistics.median(mcrt.times))
    assert "x |" in format_table(rows).splitlines()[2]  # the efficiency ratio column is filled


def test_kernel_profile_names_every_part():
    rows = kernel_profile(load_scene(), res=16, spp=2, max_depth=3, repeats=1)
    labels = [r.variant for r in rows]
    assert labels[0].startswith("full kernel") and "without the tetrahedron" in labels and labels[-1].startswith("RNG")
    assert all(r.kernel_ms > 0 for r in rows)
    assert format_profile(rows, 16 * 16 * 2).count("\n") == len(rows) + 1


def test_bench_command_writes_json(tmp_path, capsys):
    out = tmp_path / "b.json"
    assert main(["bench", "--res", "16", "--spp", "2", "--spp", "4", "--max-depth", "2", "--camera", "near", "--repeats", "1",
                 "--sampler-cost", "0", "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert {r["renderer"] for r in data["rows"]} == {"mcrt", "mitsuba"} and data["kernel_profile"] == []
    assert sorted({r["case"]["spp"] for r in data["rows"]}) == [2, 4] and len(data["rows"]) == 4


def test_bench_without_cuda_says_so_in_one_line(capsys):
    """--backend cuda on a machine without a GPU: exit 2 and one line naming the problem, prefixed once."""
    import drjit as dr
    import pytest

    if dr.has_backend(dr.JitBackend.CUDA):
        pytest.skip("this machine has the CUDA backend")
    assert main(["bench", "--backend", "cuda", "--res", "16", "--repeats", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == "mcrt: the CUDA backend is unavailable on this machine (no NVIDIA GPU or driver); use --backend llvm"


def _row(camera, res, spp, depth, renderer, seconds, mse=None):
    """A recorded row: ``seconds`` per render, so paths per second and efficiency follow exactly."""
    case = {"camera": camera, "width": res, "height": res, "spp": spp, "max_depth": depth, "light_samples": 1}
    eff = 1 / (mse * seconds) if mse else None
    return {"case": case, "renderer": renderer, "times": [seconds] * 3, "compile_time": 0.0,
            "paths_per_second": res * res * spp / seconds, "mse_excess": mse, "efficiency": eff, "median_time": seconds}


def _recorded_run() -> dict:
    """Both renderers at 64x64 (depth 2 and 8, 16 spp) and a 1/4/16-spp sweep at depth 8.

    Times are a + b x paths: mcrt 2 ms + 16 ns per path, Mitsuba 3 ms + 272 ns, so the fit recovers them exactly.
    """
    rows = []
    for spp, depth in ((16, 2), (1, 8), (4, 8), (16, 8)):
        paths = 64 * 64 * spp * depth / 8
        mse = 0.5 / spp if depth == 8 else None
        rows.append(_row("near", 64, spp, depth, "mcrt", 2e-3 + 16e-9 * paths, mse))
        rows.append(_row("near", 64, spp, depth, "mitsuba", 3e-3 + 272e-9 * paths, mse and mse * 1.1))
    profile = [{"variant": "full kernel (depth 8)", "kernel_ms": 20.0, "key": "full"},
               {"variant": "without the tetrahedron", "kernel_ms": 16.0, "key": "no_tetrahedron"},
               {"variant": "K = 4 light samples", "kernel_ms": 35.0, "key": "k4"},
               {"variant": "triangles intersector", "kernel_ms": 64.0, "key": "triangles"},
               {"variant": "RNG alone (25 draws per path)", "kernel_ms": 1.5, "key": "rng"}]
    prov = {"date": "2000-01-02T03:04:05+00:00", "git_commit": "abc", "source_hash": "def",
            "machine": {"cpu": "Test CPU", "cores": 3, "platform": "TestOS"},
            "versions": {"mcrt": "9.9", "drjit": "8.8", "mitsuba": "7.7", "numpy": "6.6", "python": "5.5"},
            "drjit_threads": 3, "libllvm": "42.0.0", "simd": "AVX-512"}
    memory = [{"width": 4096, "height": 4096, "spp": 1024, "max_depth": 2, "seconds": 100.0, "paths": 4096 * 4096 * 1024,
               "image_mib": 384.0, "peak_rss_mib": 700.0, "mean": 0.1}]
    limits = {"camera": "near", "width": 64, "height": 64, "spp": 16, "max_depth": 8, "paths": 65536, "segments": 327680,
              "shadow_rays": 262144, "segments_per_path": 5.0, "shadow_rays_per_path": 4.0, "lanes_per_pixel": 16,
              "paths_per_lane": 1, "kernel_seconds": 0.01, "kernel_bytes": 1 << 20,
              "kernel_instructions": {"instructions": 1200, "vector": 1000, "zmm": 990, "stack": 100, "branches": 9},
              "loop_instructions": {"instructions": 1000, "vector": 900, "zmm": 880, "stack": 90, "branches": 3},
              "cores": 2, "clock_mhz": 2000.0, "copy_bandwidth": 1e10, "perf": "perf is not installed"}
    return {"command": "mcrt bench --res 64 --spp-sweep 1", "provenance": prov, "backend": "llvm", "intersector": "convex",
            "repeats": 3, "warmup_renders": 1, "rows": rows, "peak_memory_mib": 123.4, "kernel_profile": profile,
            "kernel_profile_case": {"camera": "near", "width": 64, "height": 64, "spp": 16, "max_depth": 8, "repeats": 3},
            "memory_runs": memory, "limits": limits, "gpu": "No GPU run (test)."}


def _sections(page: str) -> list[str]:
    return [line for line in page.splitlines() if line.startswith("## ")]


def _table_line(page: str, case: dict, renderer: str) -> str:
    prefix = f"| {case['camera']} | {case['width']}x{case['height']} | {case['spp']} | {case['max_depth']} | 1 | {renderer} |"
    (line,) = [line for line in page.splitlines() if line.startswith(prefix)]
    return line


def test_report_from_recorded_rows(tmp_path):
    data = _recorded_run()
    tried = tmp_path / "tried.md"
    tried.write_text("### An old round\n\n- Something 11 % slower.\n")
    page = markdown(data, tmp_path, json_path=tmp_path / "bench.json", tried=tried)
    assert _sections(page) == ["## Machine", "## Method", "## Paths per second", "## Goals",
                               "## Speed-up against resolution and samples per pixel", "## Against samples per render",
                               "## Peak memory", "## Where mcrt's time goes", "## How far from the machine's limit", "## GPU",
                               "## Reading it", LOG_HEADING]
    assert (tmp_path / "speedup_spp.png").stat().st_size > 1000 and "![speedup_spp](speedup_spp.png)" in page
    assert "    mcrt bench --res 64 --spp-sweep 1\n" in page and "[bench.json](bench.json)" in page
    for fact in ("2000-01-02T03:04:05+00:00", "Test CPU, 3 cores", "16-lane packets", "| Dr.Jit threads | 3 |", "mcrt 9.9",
                 "Mitsuba 7.7", "Dr.Jit 8.8", "libLLVM 42.0.0", "abc", "Peak memory of the benchmark process: 123 MiB",
                 "medians of the 3 timed renders"):
        assert fact in page, fact
    # Every row's numbers in its table line, the speed-up and efficiency ratio from the same case.
    rows = data["rows"]
    for a, b in zip(rows[::2], rows[1::2]):
        line = _table_line(page, a["case"], "mcrt")
        assert f"| {a['median_time']:.4f} | {a['paths_per_second'] / 1e6:.2f} |" in line
        assert f"| {a['paths_per_second'] / b['paths_per_second']:.1f}x |" in line
        if a["efficiency"]:
            assert f"| {a['efficiency'] / b['efficiency']:.1f}x |" in line
        assert f"| {b['median_time']:.4f} | {b['paths_per_second'] / 1e6:.2f} |" in _table_line(page, b["case"], "mitsuba")
    # The fit recovers the times' fixed cost and cost per path.
    assert "mcrt 2 ms per render plus 16 ns per path, Mitsuba 3 ms plus 272 ns per path: 17.0x per path" in page
    # The profile's derived costs.
    assert "The tetrahedron costs 4 ms (20 % of the full kernel)" in page
    assert "(K = 4) add 75 %" in page and "3.2 times as slow" in page and "take 8 % of the full kernel" in page
    # The log comes last, verbatim, and only there does its number appear.
    body, log = page.split(LOG_HEADING)
    assert log.rstrip().endswith(tried.read_text().rstrip()) and "11 %" not in body


def test_report_goals_and_limits_from_recorded_rows(tmp_path):
    """The goals table and the limits section: each figure derived from the recorded numbers.

    The 64x64 cases' lowest speed-up is at 1 spp (the fixed costs weigh most), a goal not met;
    the kernel's 327,680 segments in 10 ms on 2 cores at 2 GHz are 2 x 2e9 /
    (3.2768e7 / 16) = 1953 cycles per packet iteration, 1000 / 1953 = 0.51
    instructions per cycle; 700 MiB is under 1 GB.
    """
    from mcrt.bench_page import goals, pairs, speedup

    data = _recorded_run()
    lowest = min(speedup(a, b) for a, b in pairs(data["rows"]))
    by_goal = {name: (met, fig) for name, met, fig in goals(data)}
    assert lowest < 10  # 1 spp: (3 ms + 272 ns x 4096) / (2 ms + 16 ns x 4096) = 2.0x
    assert by_goal["at least 10x at 1 spp and at 64x64"] == (False, f"lowest {lowest:.1f}x (near camera, 64x64, 1 spp, max depth 8) over 4 cases")
    assert by_goal["peak memory under 1 GB for a 4096x4096, 1024-spp render"][0] is True
    page = markdown(data, tmp_path)
    assert "took 1953 core cycles" in page and "about 0.51 per cycle" in page and "5.00 segments" in page
    assert "| 4096x4096 | 1024 | 2 | 100.0 | 171.8 | 384 | 700 |" in page and "No GPU run (test)." in page
    data["memory_runs"][0]["peak_rss_mib"] = 1500.0
    assert ("peak memory under 1 GB for a 4096x4096, 1024-spp render", False,
            "1500 MiB (max depth 2, the whole render, 100 s)") in goals(data)


def test_run_bench_bounds_long_renders():
    """Cases above max_paths are timed by both renderers on the same bands of rows; no MSE then."""
    rows = run_bench(load_scene(), [BenchCase("near", 600, 600, 1, 1)], repeats=1, progress=False, max_paths=2500)
    mcrt, mitsuba = rows
    assert mcrt.bounded and mitsuba.bounded and mcrt.mse_excess is None and mitsuba.mse_excess is None
    assert mcrt.paths == mitsuba.paths == 4 * 600  # 4 rows of 600 pixels at 1 spp: at most 2500 paths (one band)
    assert all(r.paths_per_second == r.paths / statistics.median(r.times) for r in rows)
    assert "(part)" in format_table(rows)


def test_bounded_rows_spread_down_the_image():
    """Up to BANDS equal bands, centred in equal parts of the image, within it; none where the case fits."""
    assert bounded_rows(BenchCase("near", 64, 64, 16, 8), 1 << 21) is None
    assert bounded_rows(BenchCase("near", 4096, 4096, 16, 8), 1 << 21) == [(508, 8), (1532, 8), (2556, 8), (3580, 8)]
    assert bounded_rows(BenchCase("near", 4096, 4096, 1024, 8), 1 << 21) == [(2048, 1)]
    assert bounded_rows(BenchCase("near", 256, 256, 256, 8), 1 << 22) == [(24, 16), (88, 16), (152, 16), (216, 16)]
    # 16 rows of 256 pixels: one band, so that mcrt's launches keep MIN_LANES lanes
    assert bounded_rows(BenchCase("near", 256, 256, 1024, 8), 1 << 22) == [(120, 16)]
    assert bounded_rows(BenchCase("near", 256, 256, 1024, 8), 1 << 21) == [(124, 8)]
    for res, spp in ((600, 7), (256, 256), (4096, 3)):
        bands = bounded_rows(BenchCase("far", res, res, spp, 8), 1 << 20)
        assert all(0 <= first and first + n <= res for first, n in bands) and len({n for _, n in bands}) == 1
        assert sum(n for _, n in bands) * res * spp <= 1 << 20


def test_report_without_log_or_sweep(tmp_path):
    data = _recorded_run()
    data["rows"] = data["rows"][:2]
    data["kernel_profile"], data["kernel_profile_case"] = [], None
    data["memory_runs"], data["limits"] = [], None
    page = (write_report(tmp_path / "r", data)).read_text()
    assert _sections(page) == ["## Machine", "## Method", "## Paths per second", "## Goals", "## GPU", "## Reading it"]
    assert "outside the last section" not in page


def test_spp_sweep_cases_are_not_timed_twice():
    cases = bench_cases(["near", "far"], [64, 256], [16], [2, 8], 1, [1, 16, 64])
    assert len(cases) == len(set(map(str, cases))) == 2 * (4 + 2)
    assert BenchCase("far", 256, 256, 64, 8) in cases and BenchCase("near", 64, 64, 64, 8) not in cases


def test_bench_command_writes_report(tmp_path, capsys):
    """A tiny run of ``mcrt bench --report``: the page, its JSON, and the table's numbers those of the JSON.

    Run twice: the second compares its speed-ups with the bench.json of the first, which it replaces.
    """
    out = tmp_path / "bench"
    tried = tmp_path / "log.md"
    tried.write_text("### Hand-kept\n\nkept 1.23x\n")
    args = ["bench", "--res", "16", "--spp", "2", "--spp-sweep", "1", "--max-depth", "3", "--camera", "near",
            "--repeats", "1", "--sampler-cost", "1", "--profile", "--report", str(out), "--tried", str(tried)]
    assert main(args) == 0
    first = json.loads((out / "bench.json").read_text())
    assert first["previous"] is None and "## Against the previous run" not in (out / "index.md").read_text()
    assert main(args) == 0
    page, data = (out / "index.md").read_text(), json.loads((out / "bench.json").read_text())
    assert data["command"] == ("mcrt bench --camera near --res 16 --spp 2 --max-depth 3 --spp-sweep 1 --sampler-cost 1 "
                               f"--repeats 1 --profile --report {out} --tried {tried}")
    assert data["previous"]["date"] == first["provenance"]["date"] and len(data["previous"]["speedups"]) == 2
    assert {"Cost of the sobol pixel sampler", "Against the previous run"} <= {s[3:] for s in _sections(page)}
    assert [(r["width"], r["spp"], len(r["times"]["sobol"])) for r in data["sampler_cost"]["rows"]] == [(64, 1024, 1), (256, 64, 1)]
    assert f"    {data['command']}\n" in page and page.rstrip().endswith("kept 1.23x")
    assert {"Where mcrt's time goes", "Against samples per render", "Machine"} <= {s[3:] for s in _sections(page)}
    assert len(data["rows"]) == 4 and data["provenance"]["versions"]["mitsuba"]
    for r in data["rows"]:
        assert f"| {r['median_time']:.4f} | {r['paths_per_second'] / 1e6:.2f} |" in _table_line(page, r["case"], r["renderer"])
    for p in data["kernel_profile"]:
        assert f"| {p['variant']} | {p['kernel_ms']:.3g} |" in page


def test_bench_refuses_a_missing_log_before_running(tmp_path, capsys):
    assert main(["bench", "--report", str(tmp_path), "--tried", str(tmp_path / "none.md")]) == 2
    assert "none.md: no such file" in capsys.readouterr().err and not (tmp_path / "index.md").exists()


def test_every_bench_option_states_its_default():
    sub = next(a for a in build_parser()._subparsers._group_actions[0].choices.items() if a[0] == "bench")[1]
    for action in sub._actions:
        if action.option_strings and action.dest != "help":
            assert re.search(r"default", action.help or ""), action.option_strings


def test_flatness_interleaves_resolutions_and_sets_the_goal():
    """--flatness: every resolution timed once per round; the 4096x4096 goal reads those medians."""
    from mcrt.bench import flatness
    from mcrt.bench_page import goals

    flat = flatness(load_scene(), cameras=["near"], resolutions=[16, 24], spp=2, max_depth=3, rounds=2, progress=False)
    assert [(r["width"], len(r["times"]), r["paths"]) for r in flat["rows"]] == [(16, 2, 16 * 16 * 2), (24, 2, 24 * 24 * 2)]
    data = _recorded_run()
    data["flatness"] = {"spp": 16, "max_depth": 8, "rounds": 5, "rows": [
        {"camera": "far", "width": w, "height": w, "paths": 1, "times": [1.0], "bounded": w > 256, "paths_per_second": v}
        for w, v in ((256, 20e6), (1024, 25e6), (4096, 21e6))]}
    got = {g[0]: g[1:] for g in goals(data) if "within 15 %" in g[0]}
    assert got == {"mcrt's throughput at 4096x4096 within 15 % of its best (far camera, depth 8, 16 spp, renders interleaved)":
                   (False, "84 % of its best: 21.0 M paths/s against 25.0 at 1024x1024 (medians of 5 interleaved rounds)")}


def test_report_states_the_sampler_cost_and_the_previous_run(tmp_path):
    """The sampler-cost table and the comparison with the previous run, each figure from recorded numbers.

    The previous run's speed-ups are this run's times 0.9, 1.0, 1.1 and 1.2 (in the order of the cases): the
    ratios this run over that are 1/0.9 .. 1/1.2, median (1/1.0 + 1/1.1) / 2.
    """
    data = _recorded_run()
    data["sampler_cost"] = {"max_depth": 8, "rounds": 3, "replicates": 8, "rows": [
        {"camera": "near", "width": 64, "height": 64, "spp": 1024, "paths": 64 * 64 * 1024,
         "times": {"independent": [0.2, 0.25, 0.3], "sobol": [0.21, 0.3, 0.33]}, "ratio": 0.3 / 0.25}]}
    from mcrt.bench_page import pairs, speedup

    now = [(a["case"], speedup(a, b)) for a, b in pairs(data["rows"])]
    data["previous"] = {"commit": "old1", "date": "1999", "speedups": [
        {"case": c, "speedup": v * f} for (c, v), f in zip(now, (0.9, 1.0, 1.1, 1.2))]}
    page = markdown(data, tmp_path)  # its plots go there, not into the checkout
    assert "| near | 64x64 | 1024 | 4,194,304 | 0.2500 | 0.3000 | 16.78 | 13.98 | 1.20 |" in page
    assert "takes 1.20 to 1.20 times the independent render's time" in page
    assert "commit old1, 1999" in page and f"median {(1 / 1.0 + 1 / 1.1) / 2:.2f}" in page
    assert f"lowest {1 / 1.2:.2f} (near camera, 64x64, 16 spp, max depth 8" in page and f"highest {1 / 0.9:.2f}" in page
