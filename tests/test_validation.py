"""The comparison's error rates, reduced: false alarms within a binomial bound, every mutant detected.

The full measurement is ``mcrt validate`` (the package mcrt/validate/), whose
reports, with its README interpreting them, are in reports/validation/: many
independent seeds for the false-alarm rate, many seeds per mutant for the
power. This file is its reduced version for the default suite, at the default
suite's budget: near camera, 64x64, 1024 spp on both sides, 8x8 tiles, Welch,
Holm at family-wise ALPHA = 0.01, mcrt against fresh Mitsuba renders (the
configuration whose false-alarm rate the study measures).

Seeds are fixed (and the mcrt seeds differ from the study's), so each test
always passes or always fails on a given machine. Mitsuba renders use the
study's seeds (500000 + i) and are shared by the tests of this module.

* False alarms: 10 correct renders (mcrt seeds 20000..20009). For a test at
  its nominal level the count K is Binomial(10, 0.01); P(K >= 2) = 0.43 %,
  so more than FA_BOUND = 1 false alarm fails the test.
* The same comparison against the committed high-spp reference instead of
  an equal-budget Mitsuba render false-alarms far more often than ALPHA
  (reports/validation/against_reference/), unless the tested render's
  variance is floored at the reference's
  (reports/validation/against_reference_floor/). Ten seeds cannot pin the
  first rate either way, so it is not tested here.
* Power: each mutant on two seeds (mcrt 20100, 20101) must be rejected on
  both. Where the power study finds a mutant below the 95 % goal at the
  default configuration, it is tested where the study detects it
  (reports/validation/power.md and README.md there): ``depth_off_by_one``
  and ``light_two_sided`` at max depth 2 (one of the default suite's
  configurations, tests/test_tracer.py), and the subtle ``albedo_1pct`` at
  a larger budget: ALBEDO_SPP = 4096 spp against the committed reference
  with the variance floor, which saves the Mitsuba renders
  (reports/validation/against_reference_floor/power.md).
* The report writers: the command on a tiny study writes both reports and the
  README; the README is also written from the committed JSON reports.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pytest
from scipy import stats as sps

from mcrt import validate
from mcrt.exitcodes import EXIT_FAILED, EXIT_OK, EXIT_UNUSABLE
from mcrt.mutants import MUTANTS
from mcrt.groundtruth import load_reference
from mcrt.render import render
from mcrt.scene import load_scene
from mcrt.stats import compare, compare_images
from mcrt.validate import readme as validation_readme
from mcrt.validate.markdown import interval

ALPHA = 0.01  # family-wise error rate of each comparison (Holm over 8x8 tiles and RGB)
SPP = 1024  # the default suite's budget, both sides
RES = 64
FA_SEEDS = list(range(20_000, 20_010))
FA_BOUND = 1  # largest count consistent with ALPHA: P(K >= 2) = 0.43 % for K ~ Binomial(10, 0.01)
DETECT_SEEDS = (20_100, 20_101)  # mcrt; Mitsuba renders 0 and 1 of the module (seeds 500000, 500001)
# Mutants below the goal at the default configuration (near, max depth 8), tested where the study detects them.
AT_DEPTH_2 = ("depth_off_by_one", "light_two_sided")
ALBEDO_SPP = 4096  # against the committed reference with the variance floor (as against Mitsuba, reports/validation/power.md)


@pytest.fixture(scope="module")
def scene():
    return load_scene()


@pytest.fixture(scope="module")
def mitsuba(scene):
    """Fresh Mitsuba renders, cached for the module: ``mitsuba.get(budget, i)`` has seed 500000 + i."""
    return validate.Opponent(scene, "mitsuba")


def _budget(**kw):
    return validate.Budget(**{"camera": "near", "res": RES, "spp": SPP, "max_depth": 8, "alpha": ALPHA, "tile": 8, **kw})


def _fa(scene, against, seeds=FA_SEEDS):
    return validate.false_alarm_study(scene, seeds=seeds, against=against, budget=_budget(), extra_tiles=(), progress=False)


def test_false_alarm_bound_is_the_binomial_one():
    assert validate.false_alarm_bound(len(FA_SEEDS), ALPHA, 0.99) == FA_BOUND
    assert sps.binom.sf(FA_BOUND, len(FA_SEEDS), ALPHA) == pytest.approx(0.0043, abs=1e-4)
    assert validate.false_alarm_bound(200, ALPHA, 0.99) == 6


def test_false_alarms_within_their_bound(scene, mitsuba):
    """10 correct renders against 10 independent Mitsuba renders: at most FA_BOUND rejections."""
    fa = _fa(scene, mitsuba)
    p = fa["primary"]
    assert p["n"] == len(FA_SEEDS)
    failed = [t["summary"] for t in fa["trials"] if t["rejected"]]
    assert p["k"] <= FA_BOUND, f"{p['k']} false alarms in {p['n']} correct renders (bound {FA_BOUND}):\n" + "\n".join(failed)


def test_reference_floor_opponent_floors_the_tested_variance(scene):
    """Against 'reference-floor' each tested render takes the reference's per-sample variance where its own is lower.

    The same two renders (seeds fixed, 64 spp) against the plain reference:
    the floored statistic is never larger, and smaller on every render (a
    64-spp render underestimates the variance of some of its pixels).
    """
    plain = validate.false_alarm_study(scene, seeds=2, against="reference", budget=_budget(spp=64), extra_tiles=(), progress=False)
    floor = validate.false_alarm_study(scene, seeds=2, against="reference-floor", budget=_budget(spp=64), extra_tiles=(),
                                       progress=False)
    assert floor["against"]["kind"] == "reference-floor" and "floor_variance" in floor["against_label"]
    for p, f in zip(plain["trials"], floor["trials"]):
        assert p["seed"] == f["seed"] and f["max_abs_t"] < p["max_abs_t"]


def _mutant(scene, mutant, seed, spp, max_depth):
    s = scene.settings(camera="near", width=RES, height=RES, spp=spp, max_depth=max_depth)
    return render(scene, s, seed=seed, progress=False, mutants=(mutant,))


def _comparison(scene, other, mutant, seed, spp, max_depth):
    a = _mutant(scene, mutant, seed, spp, max_depth)
    return compare_images(a, other, alpha=ALPHA, tile=8)


@pytest.mark.parametrize("mutant", [m for m in MUTANTS if m not in AT_DEPTH_2 and m not in validate.SUBTLE])
def test_mutant_detected_at_the_default_budget(scene, mitsuba, mutant):
    for i, seed in enumerate(DETECT_SEEDS):
        c = _comparison(scene, mitsuba.get(_budget(), i), mutant, seed, SPP, 8)
        assert not c.passed, f"mutant {mutant} not detected (seed {seed}, {SPP} spp, max depth 8): {c.summary()}"


@pytest.mark.parametrize("mutant", AT_DEPTH_2)
def test_mutant_detected_at_max_depth_2(scene, mitsuba, mutant):
    for i, seed in enumerate(DETECT_SEEDS):
        c = _comparison(scene, mitsuba.get(_budget(max_depth=2), i), mutant, seed, SPP, 2)
        assert not c.passed, f"mutant {mutant} not detected (seed {seed}, {SPP} spp, max depth 2): {c.summary()}"


def test_subtle_mutant_detected_at_its_stated_budget(scene):
    ref = load_reference(scene, "near", RES, 8)
    for seed in DETECT_SEEDS:
        a = _mutant(scene, "albedo_1pct", seed, ALBEDO_SPP, 8)
        c = compare(a, ref, policy="reference-floor", alpha=ALPHA, tile=8)
        assert not c.passed, f"albedo_1pct not detected (seed {seed}, {ALBEDO_SPP} spp): {c.summary()}"
        assert c.largest_effect.rel_diff < 0  # the wall is darker, not brighter


def test_every_mutant_is_covered():
    covered = {m for m in MUTANTS if m not in AT_DEPTH_2 and m not in validate.SUBTLE} | set(AT_DEPTH_2) | set(validate.SUBTLE)
    assert covered == set(MUTANTS)


# --------------------------------------------------------------------------
# The command: reports and exit codes (tiny budgets, fresh Mitsuba renders)
# --------------------------------------------------------------------------


def _run(argv):
    ap = argparse.ArgumentParser(prog="mcrt")
    validate.register(ap.add_subparsers(dest="command", required=True))
    args = ap.parse_args(["validate", *argv])
    return args.func(args)


TINY = ["--seeds", "3", "--power-seeds", "2", "--res", "16", "--spp", "64", "--extra-tiles", "1", "--followup", "none",
        "--effect-spp", "0", "--quiet"]


def test_validate_writes_both_reports_with_their_provenance(tmp_path, capsys):
    rc = _run([*TINY, "--mutant", "gamma_output", "--mutant", "nee_no_area", "--escalate-spp", "none", "--out", str(tmp_path)])
    assert rc == EXIT_OK, capsys.readouterr().out
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["README.md", "false_alarms.json", "false_alarms.md", "power.json", "power.md"]
    for stem in ("false_alarms", "power"):
        data = json.loads((tmp_path / f"{stem}.json").read_text())
        md = (tmp_path / f"{stem}.md").read_text()
        cmd = data["meta"]["command"]
        assert cmd.startswith("mcrt validate --seeds 3 --power-seeds 2 --spp 64 --res 16") and f"`{cmd}`" in md
        assert {"mcrt", "mitsuba", "drjit"} <= set(data["meta"]["versions"]) and data["meta"]["date"]
        assert data["budget"] == {"camera": "near", "res": 16, "spp": 64, "max_depth": 8, "alpha": 0.01, "tile": 8,
                                  "correction": "holm", "channels": "rgb", "pixel_sampler": "independent"}
    fa = json.loads((tmp_path / "false_alarms.json").read_text())
    assert fa["primary"]["n"] == 3 and len(fa["trials"]) == 3 and fa["seeds"]["opponent"] == [500_000, 500_001, 500_002]
    assert sum(fa["primary"]["p_values"]["counts"]) == fa["primary"]["p_values"]["n"] == 3 * 12
    pw = json.loads((tmp_path / "power.json").read_text())
    assert pw["mutants"]["gamma_output"]["rate"] == 1.0 and pw["goal_met"]
    assert "| `gamma_output` | 2/2 | 100 % |" in (tmp_path / "power.md").read_text()
    readme = (tmp_path / "README.md").read_text()
    assert readme.startswith("# How well the image comparison works") and "do not edit by hand" in readme
    assert f"{fa['primary']['k'] or 'no'} false alarm" in readme and f"in {fa['primary']['n']}.**" in readme
    assert "2 of the 2 non-subtle mutants are detected on 2 of 2 seeds" in readme


def test_validate_exits_1_when_a_mutant_goes_undetected(tmp_path):
    # A 1 % albedo error cannot be seen at 64 spp and 16x16 pixels, and no larger budget is allowed.
    rc = _run([*TINY, "--only", "power", "--mutant", "albedo_1pct", "--escalate-spp", "none", "--out", str(tmp_path)])
    assert rc == EXIT_FAILED
    pw = json.loads((tmp_path / "power.json").read_text())
    assert pw["below_goal"] == ["albedo_1pct"] and pw["stated_budgets"]["albedo_1pct"]["spp"] is None
    assert not (tmp_path / "false_alarms.json").exists()


def test_validate_rejects_unusable_input(tmp_path, capsys):
    assert _run([*TINY, "--mutant", "no_such_bug", "--out", str(tmp_path)]) == EXIT_UNUSABLE
    assert "unknown mutant 'no_such_bug'" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        _run(["--against", "nowhere"])


def test_readme_is_written_from_the_committed_reports(tmp_path, capsys):
    """The README of reports/validation/, rewritten from its committed JSON: every figure comes from the studies."""
    src = Path(__file__).resolve().parent.parent / "reports" / "validation"
    for path in src.rglob("*.json"):
        (tmp_path / path.relative_to(src)).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / path.relative_to(src)).write_bytes(path.read_bytes())
    assert _run(["--readme-only", "--out", str(tmp_path)]) == EXIT_OK
    readme = (tmp_path / "README.md").read_text()
    runs = validation_readme.find_runs(tmp_path)
    assert [r.kind for r in runs] == ["mitsuba", "reference", "reference-floor"]
    for r in runs:
        p = r.false_alarms["primary"]
        assert f"{p['k'] or 'no'} false alarm" in readme and r.meta["command"] in readme
        assert interval(p["interval"]) in readme
    main = runs[0].power
    for name in main["below_goal"]:
        assert f"| `{name}`" in readme
    assert "## Time" in readme and "Generated by `mcrt validate`" in readme
    # A run written into a sub-folder of a validation folder rewrites that folder's README.
    assert validation_readme.readme_root(tmp_path / "against_reference") == tmp_path
    assert validation_readme.readme_root(tmp_path / "elsewhere" / "x") == tmp_path / "elsewhere" / "x"
    # An empty folder has no README to write.
    assert _run(["--readme-only", "--out", str(tmp_path / "empty")]) == EXIT_UNUSABLE
    assert "no false_alarms.json" in capsys.readouterr().err
