"""Convergence reports: image metrics, slope fit, a tiny end-to-end report, the HTML in a real browser, and the import graph.

The end-to-end report is tiny (16x16 pixels, spp 1, 4, 16, one seed, mcrt
and Mitsuba, against a 256-spp Mitsuba reference rendered into a temporary
cache), so that the file stays quick.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import mcrt
from mcrt import metrics as M
from mcrt.convergence import REPORT_FILES, SCHEMA, preset_config, run_report
from mcrt.convergence.config import RendererSpec, parse_ladder, render_seed
from mcrt.convergence.data import MEASUREMENT_KEYS, TOP_KEYS
from mcrt.convergence.run import run_ladder
from mcrt.convergence.slopes import fit_slope

# Fixed seed: the synthetic test data are arbitrary but must be the same every run.
RNG_SEED = 20240611


def rng() -> np.random.Generator:
    return np.random.default_rng(RNG_SEED)


# --------------------------------------------------------------------------
# Metrics
# --------------------------------------------------------------------------


def test_rmse_of_known_arrays():
    ref = np.zeros((2, 2, 3))
    assert M.rmse(ref, np.full((2, 2, 3), 2.0)) == pytest.approx(2.0)
    x = ref.copy()
    x[0, 0] = 1.0  # one pixel of four off by 1 in every channel: MSE 1/4
    assert M.mse(ref, x) == pytest.approx(0.25)
    assert M.rmse(ref, x) == pytest.approx(0.5)
    assert M.rmse(x, x) == 0.0


def test_relmse_epsilon():
    assert M.RELMSE_EPS == 1e-2
    ref = np.zeros((1, 1, 3))
    x = np.full((1, 1, 3), 0.1)
    assert M.relmse(ref, x) == pytest.approx(0.01 / 1e-2)  # black reference: divided by eps alone
    ref1 = np.ones((1, 1, 3))
    assert M.relmse(ref1, ref1 + 0.5) == pytest.approx(0.25 / (1 + 1e-2))
    assert M.relmse(ref, x, eps=1.0) == pytest.approx(0.01)


def test_metrics_reject_mismatched_shapes():
    with pytest.raises(ValueError):
        M.rmse(np.zeros((2, 2, 3)), np.zeros((2, 3, 3)))
    with pytest.raises(ValueError):
        M.rmse(np.zeros((2, 2, 3)), np.zeros((2, 2, 3)), mask=np.ones((2, 3), bool))


def test_rmse_over_a_mask_and_relmse_per_pixel():
    ref = np.zeros((2, 2, 3))
    x = ref.copy()
    x[0, 0], x[1, 1] = 1.0, np.nan  # the NaN pixel is masked out
    mask = np.ones((2, 2), bool)
    mask[1, 1] = False
    assert M.rmse(ref, x, mask=mask) == pytest.approx(math.sqrt(1 / 3))
    emap = M.relmse_map(ref, np.nan_to_num(x))
    assert emap.shape == (2, 2) and emap[0, 0] == pytest.approx(1 / M.RELMSE_EPS) and emap[0, 1] == 0
    assert M.relmse(ref, np.nan_to_num(x)) == pytest.approx(emap.mean())


def test_ssim_of_identical_images_is_one():
    img = rng().lognormal(-1.0, 1.0, (24, 24, 3))
    assert M.ssim(img, img) == pytest.approx(1.0)
    noisy = img * rng().lognormal(0.0, 0.5, img.shape)
    assert M.ssim(img, noisy) < 0.99


def test_ssim_sees_the_tone_mapped_image():
    # Above 1 everything clips to white: SSIM cannot tell 2 from 5.
    a, b = np.full((16, 16, 3), 2.0), np.full((16, 16, 3), 5.0)
    assert M.ssim(a, b) == pytest.approx(1.0)
    assert M.ssim_tonemap(np.array([[[0.5, 0.0, 1.0]]]))[0, 0] == pytest.approx([0.735357, 0.0, 1.0], abs=1e-5)


def test_flip_of_identical_images_is_zero():
    img = rng().lognormal(-1.0, 1.0, (32, 32, 3)).astype(np.float32)
    params = M.flip_parameters(img)
    assert set(params) >= {"startExposure", "stopExposure", "numExposures", "tonemapper", "ppd"}
    assert params["startExposure"] <= params["stopExposure"]
    assert M.flip(img, img, params) == 0.0
    emap, mean = M.flip_map(img, img * 1.5, params)
    assert emap.shape == (32, 32) and 0 < mean <= 1
    assert mean == pytest.approx(float(emap.mean()), rel=1e-4)


def test_fit_slope_recovers_minus_one_half():
    n = np.repeat(2.0 ** np.arange(11), 3)  # 1 .. 1024 spp, three seeds each
    exact = fit_slope(n, 0.7 / np.sqrt(n))
    assert exact.slope == pytest.approx(-0.5) and exact.intercept == pytest.approx(math.log(0.7))
    assert fit_slope(n, 1.0 / n).slope == pytest.approx(-1.0)
    # Noisy 1/sqrt(n) data: every fit is close, and the 95 % interval holds -1/2
    # in about 95 % of 400 independent data sets (binomial sd 1.1 %).
    g = rng()
    fits = [fit_slope(n, 0.7 / np.sqrt(n) * g.lognormal(0.0, 0.15, n.shape)) for _ in range(400)]
    assert all(abs(f.slope + 0.5) < 0.06 and f.n == 33 and f.level == 0.95 for f in fits)
    assert all(f.ci_high - f.ci_low < 0.1 for f in fits)
    coverage = np.mean([f.contains(-0.5) for f in fits])
    assert 0.92 <= coverage <= 0.98, coverage


def test_fit_slope_with_too_few_points():
    two = fit_slope([1, 4], [1.0, 0.5])
    assert two.slope == pytest.approx(-0.5) and math.isinf(two.ci_high)
    assert math.isnan(fit_slope([1], [1.0]).slope)
    assert fit_slope([1, 2, 4, 8], [1.0, 0.0, -1.0, 0.25]).n == 2  # non-positive values dropped


# --------------------------------------------------------------------------
# Settings
# --------------------------------------------------------------------------


def test_ladder_and_renderer_parsing():
    assert parse_ladder("1..1024") == tuple(2**i for i in range(11))
    assert parse_ladder("1..16,100") == (1, 2, 4, 8, 16, 100)
    assert parse_ladder("4,1,4") == (1, 4)
    with pytest.raises(ValueError):
        parse_ladder("0,1")
    assert RendererSpec.parse("mcrt:k30") == RendererSpec("mcrt", 30)
    assert RendererSpec.parse("mcrt:k30").label == "mcrt K=30"
    assert RendererSpec.parse("Mitsuba").label == "mitsuba"
    for bad in ("mitsuba:k4", "pbrt", "mcrt:k0"):
        with pytest.raises(ValueError):
            RendererSpec.parse(bad)
    a, b = RendererSpec.parse("mcrt"), RendererSpec.parse("mitsuba")
    assert render_seed(a, 1, 4) == render_seed(a, 1, 4)
    assert len({render_seed(a, 1, 4), render_seed(a, 2, 4), render_seed(a, 1, 8), render_seed(b, 1, 4)}) == 4


def test_presets():
    scene = mcrt.load_scene(mcrt.CANONICAL)
    canonical = preset_config("canonical", scene).check()
    assert canonical.spp_ladder == tuple(2**i for i in range(11)) and len(canonical.seeds) == 3
    assert canonical.renderers == ("mcrt", "mitsuba", "plugin")
    course = preset_config("course2023", scene).check()
    assert (course.width, course.height, course.max_depth) == (800, 800, 8)
    assert course.spp_ladder[-1] == 100 and course.renderers == ("mcrt:k30", "mcrt:k1")
    assert course.equal_time and course.baseline_spec().label == "mcrt K=1"
    with pytest.raises(ValueError):
        preset_config("nope", scene)


def test_command_line_options():
    import argparse

    from mcrt.convergence.cli import config_from_args, register

    ap = argparse.ArgumentParser(prog="mcrt")
    register(ap.add_subparsers(dest="command", required=True))
    args = ap.parse_args(["report", "--preset", "course2023", "--res", "32", "--spp-ladder", "1,4", "--seeds", "2", "--no-svg"])
    cfg = config_from_args(args)
    assert (cfg.width, cfg.height, cfg.spp_ladder, cfg.seeds) == (32, 32, (1, 4), (1, 2))
    assert cfg.renderers == ("mcrt:k30", "mcrt:k1") and cfg.equal_time and not cfg.svg and cfg.strip_spp is None
    args = ap.parse_args(["report", "--renderers", "mcrt:k4,mitsuba", "--max-depth", "2", "--light-samples", "3"])
    cfg = config_from_args(args)
    assert cfg.renderers == ("mcrt:k4", "mitsuba") and cfg.max_depth == 2 and cfg.light_samples == 3
    # The preset's own sentence ("64x64, spp 1 to 1024") no longer holds: the description says what changed.
    assert cfg.description == "The canonical preset with --light-samples, --max-depth, --renderers given on the command line (settings below)."
    assert config_from_args(ap.parse_args(["report", "--name", "x"])).description.startswith("The main job: the canonical scene")
    with pytest.raises(SystemExit):
        ap.parse_args(["report", "--spp-ladder", "0"])
    help_text = ap._subparsers._group_actions[0].choices["report"].format_help()
    for opt in ("--scene", "--camera", "--res", "--spp-ladder", "--seeds", "--renderers", "--max-depth", "--light-samples",
                "--preset", "--out", "--name"):
        assert opt in help_text


# --------------------------------------------------------------------------
# A tiny report, end to end
# --------------------------------------------------------------------------


@pytest.fixture(scope="module")
def cache_dir():
    d = tempfile.mkdtemp(prefix="mcrt-report-cache-")
    yield Path(d)
    shutil.rmtree(d, ignore_errors=True)


@pytest.fixture(scope="module")
def tiny_config(cache_dir):
    cfg = preset_config("tiny")
    assert (cfg.width, cfg.spp_ladder, cfg.seeds, cfg.renderers) == (16, (1, 4, 16), (1,), ("mcrt", "mitsuba"))
    return replace(cfg, cache_dir=str(cache_dir))


@pytest.fixture(scope="module")
def tiny_report(tiny_config, tmp_path_factory):
    out = tmp_path_factory.mktemp("report") / "tiny"
    return run_report(tiny_config, out, progress=False, command="pytest tiny report")


def test_tiny_report_writes_every_file(tiny_report):
    folder = tiny_report.folder
    for name in REPORT_FILES:
        p = folder / name
        assert p.is_file() and p.stat().st_size > 0, name
    for name in ("error_vs_spp.png", "images.png", "flip.png"):
        assert (folder / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (folder / "error_vs_spp.svg").read_text().lstrip().startswith("<?xml")
    md = (folder / "index.md").read_text().replace("\\", "")  # unescape Markdown
    for text in ("Key numbers", "Metric conventions", "eps = 0.01", "data_range = 1", "HDR", "Provenance", "images.png"):
        assert text in md, text
    csv = (folder / "table.csv").read_text().splitlines()
    assert csv[0].split(",") == list(MEASUREMENT_KEYS) and len(csv) == 1 + 6


def test_tiny_report_data_json(tiny_report, tiny_config):
    d = json.loads((tiny_report.folder / "data.json").read_text())
    assert d["schema"] == SCHEMA
    assert set(TOP_KEYS) <= set(d)
    assert d["config"]["spp_ladder"] == [1, 4, 16] and d["config"]["seeds"] == [1]
    ms = d["measurements"]
    assert len(ms) == 2 * 3 * 1
    assert {(m["renderer"], m["spp"]) for m in ms} == {(r, s) for r in ("mcrt", "mitsuba") for s in (1, 4, 16)}
    for m in ms:
        assert set(m) == set(MEASUREMENT_KEYS)
        assert m["rmse"] > 0 and 0 < m["ssim"] <= 1 and 0 < m["flip"] <= 1 and m["time"] > 0
        assert m["rmse"] == pytest.approx(math.sqrt(m["mse"]))
    prov = d["provenance"]
    assert prov["command"] == "pytest tiny report" and prov["backend"] == "llvm"
    assert prov["machine"]["cpu"] and prov["machine"]["cores"] >= 1 and prov["date"] and len(prov["source_hash"]) == 16
    assert {"mcrt", "drjit", "mitsuba", "python", "scikit-image", "flip-evaluator", "matplotlib"} <= set(prov["versions"])
    ref = d["reference"]
    assert ref["source"] in ("rendered", "cached render") and ref["spp"] == 256 and ref["floor"]["known"]
    assert d["conventions"]["relmse_eps"] == M.RELMSE_EPS
    assert d["flip_parameters"]["tonemapper"] == "ACES"
    fits = d["summary"]["fits"]["mcrt"]["rmse"]
    assert set(fits) == {"spp", "time"} and fits["spp"]["n"] == 3
    assert d["summary"]["baseline"] == "mitsuba" and "mcrt" in d["summary"]["ratios"]
    assert set(d["warmup"]) == {"mcrt", "mitsuba"}
    assert "NaN" not in (tiny_report.folder / "data.json").read_text()


def test_same_seeds_give_the_same_numbers(tiny_report, tiny_config):
    again = run_ladder(tiny_config, progress=False)  # the reference now comes from the cache
    assert again.reference_info["source"] == "cached render"
    keys = ("renderer", "spp", "seed", "render_seed", "mse", "rmse", "relmse", "ssim", "flip", "mse_predicted")

    def numbers(ms):  # NaN (no variance at 1 spp) compares unequal to itself: spell it out
        return [{k: ("nan" if isinstance(v := getattr(m, k), float) and math.isnan(v) else v) for k in keys} for m in ms]

    first, second = numbers(tiny_report.data.measurements), numbers(again.measurements)
    assert first == second


def test_report_html_is_self_contained(tiny_report):
    import re

    html = (tiny_report.folder / "index.html").read_text()
    srcs = re.findall(r'src="([^"]*)"', html)
    assert len(srcs) == 6 and all(s.startswith("data:image/png;base64,") for s in srcs)
    assert "http://" not in html and "https://" not in html and "<link" not in html


def test_equal_time_mode(cache_dir, tmp_path):
    cfg = replace(preset_config("tiny"), name="eq", width=8, height=8, spp_ladder=(2, 8), renderers=("mcrt:k4", "mcrt:k1"),
                  equal_time=True, baseline="mcrt:k1", reference_renderer="mcrt:k1", reference_spp=64, cache_dir=str(cache_dir),
                  svg=False)
    out = run_report(cfg, tmp_path / "eq", progress=False)
    data = out.data
    assert set(data.calibration) == {"mcrt K=4", "mcrt K=1"}
    assert data.ladders["mcrt K=4"] == [2, 8]
    factor = data.calibration["mcrt K=1"]["spp_factor"]
    assert data.ladders["mcrt K=1"] == [max(1, round(2 * factor)), max(1, round(8 * factor))]
    assert any(v.startswith("Equal time:") for v in out.summary.verdicts)
    assert "mcrt K=4" in out.summary.ratios and out.summary.ratios["mcrt K=4"]["vs"] == "mcrt K=1"
    assert not (tmp_path / "eq" / "error_vs_spp.svg").exists()


# --------------------------------------------------------------------------
# The HTML in headless Chromium
# --------------------------------------------------------------------------

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")

#: Appended to a copy of the page: after 'load', lists every <img> that did not decode.
IMAGE_CHECK = """<script>
window.addEventListener('load', function () {
  var imgs = Array.prototype.slice.call(document.images);
  var out = {n: imgs.length, widths: imgs.map(function (i) { return i.naturalWidth; }),
             bad: imgs.filter(function (i) { return !(i.complete && i.naturalWidth > 0); }).map(function (i) { return i.alt; })};
  var el = document.createElement('pre'); el.id = 'mcrt-image-check'; el.textContent = JSON.stringify(out);
  document.body.appendChild(el);
});
</script>"""


def browser_image_check(html_path: Path, workdir: Path) -> dict:
    """Open a copy of ``html_path`` in headless Chromium; return {n, widths, bad} for its images."""
    import re
    from html import unescape

    page = workdir / "check.html"
    page.write_text(html_path.read_text(encoding="utf-8").replace("</body>", IMAGE_CHECK + "</body>"), encoding="utf-8")
    cmd = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
           f"--user-data-dir={workdir / 'profile'}", "--virtual-time-budget=10000", "--dump-dom", page.as_uri()]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    m = re.search(r'<pre id="mcrt-image-check">([^<]*)</pre>', proc.stdout)
    assert m, f"no image check in Chromium's DOM (exit {proc.returncode}): {proc.stderr[-2000:]}"
    return json.loads(unescape(m.group(1)))


needs_chromium = pytest.mark.skipif(
    CHROMIUM is None and not os.environ.get("CI"),
    reason="chromium is not installed (apt-get install chromium); CI installs it and runs this test",
)


@needs_chromium
def test_report_html_opens_in_chromium(tiny_report, tmp_path):
    assert CHROMIUM, "CI is set but chromium is not installed (see .ci/run)"
    result = browser_image_check(tiny_report.folder / "index.html", tmp_path)
    assert result["n"] == 6 and result["bad"] == [], result
    assert all(w > 0 for w in result["widths"])


@needs_chromium
def test_chromium_check_catches_a_broken_image(tmp_path):
    assert CHROMIUM, "CI is set but chromium is not installed (see .ci/run)"
    page = tmp_path / "broken.html"
    page.write_text('<!DOCTYPE html><html><body><img alt="broken" src="data:image/png;base64,AAAA">'
                    '<img alt="missing" src="nowhere.png"></body></html>')
    result = browser_image_check(page, tmp_path)
    assert result["n"] == 2 and sorted(result["bad"]) == ["broken", "missing"]


def test_cached_renders_are_keyed_by_the_source(tmp_path, monkeypatch):
    """A change to mcrt's code changes the key of cached references and grading renders (not only a version bump)."""
    import mcrt.provenance
    from mcrt.grade.expected import _cache_key, grading_settings
    from mcrt.convergence.run import _versions_key
    from mcrt.scene import load_scene

    (tmp_path / "a.py").write_text("x = 1\n")
    before = mcrt.provenance.source_hash(tmp_path)
    (tmp_path / "a.py").write_text("x = 2\n")
    assert mcrt.provenance.source_hash.__wrapped__(tmp_path) != before

    scene = load_scene()
    s = grading_settings(scene, "near", 8, 8, 8, 4, 1)
    keys = [_versions_key(), _cache_key(scene, s, "none")]
    assert _cache_key(scene, replace(s, seed=2), "none") != keys[1]  # and by every render setting
    monkeypatch.setattr(mcrt.provenance, "source_hash", lambda: "0" * 16)
    assert _versions_key() != keys[0]
    assert _cache_key(scene, s, "none") != keys[1]


# --------------------------------------------------------------------------
# The import graph
# --------------------------------------------------------------------------
