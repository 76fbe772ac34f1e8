"""mcrt validate-integrator on Mitsuba's own Cornell box: consistent integrators pass, wrong configurations are flagged.

32 x 32 pixels and a fraction of a second per render, so the file runs in
well under a minute on two cores. The false-alarm rate of this use is
measured in reports/integrators/ (``mcrt reports --only integrators``).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import mcrt  # noqa: F401  (before Mitsuba: libLLVM)
from mcrt.cli import main
from mcrt.mitsuba_scene import render_with_variance
from mcrt.validate_integrator import parse_integrator, validate_integrator

import mitsuba as mi  # noqa: E402

RES = 32
BUDGET = 0.3
# Every verdict here is a function of the seeds alone, the same on every machine: the renders' spp are fixed
# (seconds_per_spp given, so no calibration; --spp on the command line), never what a time budget buys on this
# machine. At equal time, a slow machine renders fewer samples and a fast one more, and the same seed then gives
# a different image (and, at FWER 0.01, now and then a rejection). ptracer alone differs between two runs of one
# seed, in the last bits (its splats are added in the threads' order); its smallest p-value here is far from Holm's
# threshold.
SPP = 512
EQUAL = (BUDGET / SPP, BUDGET / SPP)


@pytest.fixture(scope="module")
def box():
    mi.set_variant("llvm_ad_rgb")
    return mi.cornell_box()


@pytest.mark.parametrize("against", ["volpath", "prb", "ptracer"])
def test_consistent_integrators_pass(box, against):
    r = validate_integrator(box, "path", against, budget=BUDGET, seed=3, res=RES, seconds_per_spp=EQUAL)
    assert r["passed"], r["summary"]
    a, b = r["a"], r["b"]
    assert (a["seed"], b["seed"]) == (6, 7) and a["max_depth"] == b["max_depth"] == 8
    assert a["camera"] == b["camera"] and r["same_scene"]
    assert r["efficiency_ratio"] > 0 and a["spp"] == b["spp"] == SPP


# The wrong configurations render a fixed 2048 spp each (seconds_per_spp given, no calibration), so that the
# verdict does not depend on this machine's speed: at 0.25 s per render, max depth 7 against 8 is found in only
# 13 % of seeds (reports/integrators/).
FIXED = (1 / 2048, 1 / 2048)


def test_max_depth_off_by_one_is_flagged(box):
    r = validate_integrator(box, "path", parse_integrator("path:max_depth=7"), budget=1.0, seed=1, res=RES,
                            seconds_per_spp=FIXED)
    assert r["a"]["spp"] == r["b"]["spp"] == 2048
    assert not r["passed"] and r["b"]["max_depth"] == 7, r["summary"]


def test_brighter_light_is_flagged(box):
    bright = dict(box)
    light = dict(bright["light"])
    light["emitter"] = {"type": "area", "radiance": {"type": "rgb",
                                                     "value": [1.02 * v for v in box["light"]["emitter"]["radiance"]["value"]]}}
    bright["light"] = light
    r = validate_integrator(box, "path", "volpath", scene_against=bright, budget=1.0, seed=1, res=RES,
                            seconds_per_spp=FIXED)
    assert not r["passed"] and not r["same_scene"], r["summary"]
    c = r["comparison"]
    assert np.all(c.global_rel_diff < -0.01)  # A (the original light) is darker by about 2 %


def test_render_with_variance_is_reproducible_and_records_provenance(box, tmp_path):
    a = render_with_variance(box, integrator="prb", spp=16, seed=4, width=RES, height=RES)
    b = render_with_variance(box, integrator="prb", spp=16, seed=4, width=RES, height=RES)
    assert np.array_equal(a.mean, b.mean) and np.array_equal(a.variance, b.variance)
    assert (a.renderer, a.max_depth, a.spp, a.seed, a.mean.shape) == ("prb", 8, 16, 4, (RES, RES, 3))
    assert a.camera.startswith("PerspectiveCamera:") and len(a.scene_hash) == 16
    assert a.extra["rfilter"].startswith("box") and a.extra["method"] == "samples"
    c = render_with_variance(box, integrator={"type": "path", "max_depth": 3}, spp=16, seed=4, width=RES, height=RES)
    assert c.max_depth == 3 and c.scene_hash == a.scene_hash  # the integrator is not part of the scene's hash
    p = render_with_variance(box, integrator="ptracer", spp=64, seed=4, width=RES, height=RES)
    assert p.extra["method"] == "batches" and p.spp == 64 and p.extra["spp_per_pass"] == "2"
    # A loaded scene: no hash to record; the integrator is replaced all the same.
    loaded = mi.load_dict(dict(box, sensor=dict(box["sensor"], film=dict(box["sensor"]["film"], rfilter={"type": "box"}))))
    d = render_with_variance(loaded, integrator="volpath", spp=8, seed=1, width=RES, height=RES)
    assert d.scene_hash == "" and d.renderer == "volpath" and d.max_depth == 8 and d.camera == a.camera


def test_xml_scene_through_mcrt_render_and_compare(tmp_path, capsys):
    xml = tmp_path / "box.xml"
    xml.write_text("""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="4"/></integrator>
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, -4, 0" target="0, 0, 0" up="0, 0, 1"/></transform>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/>
      <rfilter type="box"/></film></sensor>
  <shape type="sphere"><bsdf type="diffuse"/></shape>
  <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
</scene>""")
    a, b = tmp_path / "a.exr", tmp_path / "b.exr"
    assert main(["render", "--mitsuba-scene", str(xml), "--spp", "64", "--seed", "1", "-o", str(a)]) == 0
    assert main(["render", "--mitsuba-scene", str(xml), "--integrator", "volpath", "--spp", "64", "--seed", "2",
                 "-o", str(b)]) == 0
    assert main(["compare", str(a), str(b)]) == 0
    c = tmp_path / "c.exr"
    assert main(["render", "--mitsuba-scene", str(xml), "--max-depth", "2", "--spp", "16", "-o", str(c)]) == 0
    capsys.readouterr()
    assert main(["compare", str(a), str(c)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"error: {a} and {c} differ in max_depth: 4 against 2") and "\n" not in err
    assert main(["render", "--mitsuba-scene", str(xml), "--camera", "near", "-o", str(c)]) == 2


def test_command_line_writes_json_and_heatmap(tmp_path, capsys):
    out = tmp_path / "v.json"
    rc = main(["validate-integrator", "cornell-box", "--integrator", "path", "--against", "volpath", "--res", str(RES),
               "--spp", str(SPP), "--seed", "2", "--json", str(out), "--heatmap", str(tmp_path / "h.png")])
    text = capsys.readouterr().out
    assert rc == 0, text
    d = json.loads(out.read_text())
    assert d["passed"] and d["a"]["seed"] == 4 and d["b"]["seed"] == 5 and d["comparison"]["policy"] == "independent"
    assert d["a"]["spp"] == d["b"]["spp"] == SPP and d["budget"] is None
    assert "efficiency 1/(MSE x time), A over B" in text and (tmp_path / "h.png").is_file()
    assert main(["validate-integrator", "cornell-box", "--seeds", "2"]) == 2  # --seeds without --report


def test_report_mode(tmp_path, capsys):
    rc = main(["validate-integrator", "cornell-box", "--against", "volpath", "--wrong", "path:max_depth=2",
               "--res", "16", "--budget", "0.1", "--seeds", "2", "--report", str(tmp_path / "rep")])
    assert rc == 0
    d = json.loads((tmp_path / "rep" / "data.json").read_text())
    assert [r["expected"] for r in d["rows"]] == ["consistent", "wrong"] and d["rows"][1]["rejected"] == 2
    assert d["command"].startswith("mcrt ") and (tmp_path / "rep" / "index.md").is_file()
