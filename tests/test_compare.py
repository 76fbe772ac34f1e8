"""mcrt compare's inputs: files (Mitsuba's 'moment' integrator's too), RenderResults and NumPy arrays; refused headers."""

from __future__ import annotations

import io

import numpy as np
import pytest

import mcrt  # noqa: F401  (before Mitsuba: libLLVM)
from mcrt.cli import main
from mcrt.compare import as_result, check_headers, compare_files, image
from mcrt.film import RenderResult
from mcrt.image_files import write_exr
from mcrt.stats import StatsError

import mitsuba as mi  # noqa: E402


def _synthetic(seed, spp=1024, **fields):
    g = np.random.default_rng(seed)
    mean = (0.5 + g.normal(0, 1 / np.sqrt(spp), (16, 16, 3))).astype(np.float32)
    return RenderResult(mean=mean, variance=np.ones((16, 16, 3), np.float32), spp=spp, seed=seed,
                        **{"max_depth": 8, "renderer": "synthetic", **fields})


def test_every_kind_of_input(tmp_path):
    a, b = _synthetic(1), _synthetic(2)
    write_exr(tmp_path / "b.exr", b)
    out = io.StringIO()
    assert compare_files(a, tmp_path / "b.exr", out=out) == 0
    assert compare_files(a.mean, b.mean, variance_a=a.variance, spp_a=a.spp, variance_b=b.variance, spp_b=b.spp, out=out) == 0
    assert compare_files(image(a.mean, a.variance, a.spp), b, out=out) == 0
    err = io.StringIO()
    assert compare_files(a.mean, b, err=err) == 2
    assert "image A is a bare array: give its per-sample variance and spp alongside" in err.getvalue()
    with pytest.raises(StatsError, match="expected a file path, a RenderResult or a NumPy array"):
        as_result(42)
    assert as_result(a, spp=7).spp == 7 and a.spp == 1024  # a copy: the caller's render is not changed


def test_headers_refused_with_one_line_and_the_override(tmp_path, capsys):
    for seed, (name, camera, depth, h) in enumerate((("near", "near", 8, "s1"), ("far", "far", 8, "s1"), ("d7", "near", 7, "s1"),
                                                     ("other", "near", 8, "s2"))):
        write_exr(tmp_path / f"{name}.exr", _synthetic(seed, camera=camera, max_depth=depth, scene_hash=h))
    for other, field in (("far", "camera"), ("d7", "max_depth"), ("other", "scene_hash")):
        capsys.readouterr()
        assert main(["compare", str(tmp_path / "near.exr"), str(tmp_path / f"{other}.exr")]) == 2
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and f"near.exr and {tmp_path / other}.exr differ in {field}" in err
        assert main(["compare", str(tmp_path / "near.exr"), str(tmp_path / f"{other}.exr"), "--allow-mismatch", field]) == 0
    assert main(["compare", str(tmp_path / "near.exr"), str(tmp_path / "far.exr"), "--allow-mismatch", "all"]) == 0
    small = RenderResult(np.zeros((8, 8, 3), np.float32), np.ones((8, 8, 3), np.float32), 4, 0, 8, "x")
    with pytest.raises(StatsError, match="differ in resolution: 16x16 against 8x8"):
        check_headers(_synthetic(1), small, allow=("all",))
    # Unknown fields (empty, max depth 0) are not compared.
    check_headers(_synthetic(1, camera="near"), image(np.zeros((16, 16, 3)), np.ones((16, 16, 3)), 4))


def test_relative_difference_is_labelled_symmetric(capsys):
    a, b = _synthetic(1), _synthetic(2)
    a.mean[:8, :8] *= 1.5
    assert compare_files(a, b) == 1
    out = capsys.readouterr().out
    assert "% symmetric)" in out and "symmetric relative difference (A-B)/mean(|A|,|B|)" in out
    assert "A relative to B" not in out


def test_mitsuba_moment_integrator_output_against_render_with_variance(tmp_path, capsys):
    """The 'moment' integrator's EXR (no spp in it: --spp) against the same integrator through render_with_variance."""
    from mcrt.mitsuba_scene import render_with_variance

    mi.set_variant("llvm_ad_rgb")
    d = mi.cornell_box()
    d["sensor"]["film"].update(width=16, height=16, rfilter={"type": "box"})
    d["integrator"] = {"type": "moment", "nested": {"type": "path", "max_depth": 8}}
    scene = mi.load_dict(d)
    mi.render(scene, spp=256, seed=11)
    scene.sensors()[0].film().write(str(tmp_path / "moment.exr"))
    ours = render_with_variance(mi.cornell_box(), integrator="path", spp=256, seed=3, width=16, height=16)
    write_exr(tmp_path / "ours.exr", ours)
    m, o = str(tmp_path / "moment.exr"), str(tmp_path / "ours.exr")
    assert main(["compare", m, o]) == 2
    assert "does not record its spp; give it with --spp-a N" in capsys.readouterr().err
    assert main(["compare", m, o, "--spp-a", "256"]) == 0
    assert "moment.exr (16x16, 256 spp, variance" in capsys.readouterr().out
    # A wrong light is seen through the moment file too.
    bright = mi.cornell_box()
    bright["light"]["emitter"]["radiance"]["value"] = [1.1 * v for v in bright["light"]["emitter"]["radiance"]["value"]]
    write_exr(tmp_path / "bright.exr", render_with_variance(bright, integrator="path", spp=256, seed=4, width=16, height=16))
    assert main(["compare", m, str(tmp_path / "bright.exr"), "--spp-a", "256", "--allow-mismatch", "scene_hash"]) == 1
