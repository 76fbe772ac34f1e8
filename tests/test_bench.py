"""The benchmark's library API on a tiny case: shapes of its results, not speeds (speed lives in reports/bench/)."""

from __future__ import annotations

import json
import statistics

from mcrt.bench import BenchCase, format_profile, format_table, kernel_profile, run_bench
from mcrt.cli import main
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
    well above zero and within a factor 3 of each other (measured: 0.92).
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
                 "--json", str(out)]) == 0
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
