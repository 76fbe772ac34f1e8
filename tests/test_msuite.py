"""Mitsuba's own render-test suite: its files read, its scenes rendered as Mitsuba renders them, its test beaten.

Scenes and references come from ``<repo>/../shared/mitsuba-tests`` (a copy of
part of Mitsuba 3's tests/scenes; CI has it beside the clone: there a missing
copy fails, elsewhere the tests that need it are skipped, saying why) and
from scenes written here.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import OpenEXR
import pytest

import mcrt  # noqa: F401  (before drjit / mitsuba)
from mcrt import imageio
from mcrt.cli import main
from mcrt.film import RenderResult
from mcrt.imageio import ImageError, read_exr, read_mitsuba_reference, read_variance_exr, write_exr

ROOT = Path(__file__).resolve().parents[1]


def _suite_dir() -> Path | None:
    """The shared copy of Mitsuba's tests: $MCRT_MITSUBA_TESTS, else ../shared/mitsuba-tests beside the clone
    (or beside the folder holding a worktree)."""
    env = os.environ.get("MCRT_MITSUBA_TESTS")
    candidates = [Path(env)] if env else []
    candidates += [ROOT.parent / "shared" / "mitsuba-tests", ROOT.parent.parent / "shared" / "mitsuba-tests"]
    return next((c for c in candidates if (c / "tests" / "scenes").is_dir()), None)


SUITE = _suite_dir()


@pytest.fixture
def suite() -> Path:
    if SUITE is None:
        where = ROOT.parent / "shared" / "mitsuba-tests"
        if os.environ.get("CI"):
            pytest.fail(f"CI: Mitsuba's test scenes are missing (looked for {where} and $MCRT_MITSUBA_TESTS)")
        pytest.skip(f"Mitsuba's test scenes are not here (no {where}; set MCRT_MITSUBA_TESTS)")
    return SUITE


def _exr(path, planes: dict, header=None):
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage, **(header or {})},
                 {k: np.ascontiguousarray(v, np.float32) for k, v in planes.items()}).write(str(path))


def _mitsuba_var_file(path, var_xyz, version="Mitsuba version 3.9.1"):
    """A variance file as Mitsuba's reference generator writes it: the XYZ variance converted like a colour."""
    rgb = var_xyz @ imageio.XYZ_TO_RGB.T
    _exr(path, {c: rgb[..., i] for i, c in enumerate("RGB")}, {"generatedBy": version})


# --------------------------------------------------------------------------
# 1. Reading what Mitsuba writes
# --------------------------------------------------------------------------


def test_mitsuba_variance_file_read_back_as_xyz(tmp_path):
    """The XYZ variance comes back exactly from its RGB-converted file, which is partly negative."""
    g = np.random.default_rng(5)
    mean_xyz = g.uniform(0.5, 1.0, (6, 7, 3))
    var_xyz = g.uniform(0.05, 0.5, (6, 7, 3)) * mean_xyz**2  # well above float32 rounding
    var_xyz[0, 0] = 0.0  # a noiseless pixel
    var_xyz[1, 1, 2] = 1e-6 * mean_xyz[1, 1, 2] ** 2  # rounding level: read as 0
    _mitsuba_var_file(tmp_path / "v.exr", var_xyz)
    mean_rgb = mean_xyz @ imageio.XYZ_TO_RGB.T
    assert np.any(var_xyz @ imageio.XYZ_TO_RGB.T < 0)  # the file itself holds negative "variances"
    v, note = read_variance_exr(tmp_path / "v.exr", mean=mean_rgb, space="xyz")
    expect = var_xyz.copy()
    expect[1, 1, 2] = 0.0
    assert np.allclose(v, expect, rtol=1e-4, atol=1e-7) and "turned back into XYZ" in note
    rgb, _ = read_variance_exr(tmp_path / "v.exr", mean=mean_rgb)
    assert np.all(rgb >= 0) and np.allclose(rgb, (np.sqrt(expect) @ np.abs(imageio.XYZ_TO_RGB).T) ** 2, rtol=1e-3)
    # Read as a plain RGB variance, the negative entries are refused in one line naming the file.
    with pytest.raises(ImageError, match=r"v\.exr: \d+ negative entries in the variance .*--variance-kind mitsuba"):
        read_variance_exr(tmp_path / "v.exr", mean=mean_rgb, kind="rgb")


def test_mitsuba_variance_beyond_rounding_or_non_finite_is_refused(tmp_path):
    mean_xyz = np.full((4, 4, 3), 0.5)
    var_xyz = np.full((4, 4, 3), 0.01)
    var_xyz[2, 3, 1] = -0.01  # 4 % of m^2: no rounding error does that
    _mitsuba_var_file(tmp_path / "neg.exr", var_xyz)
    with pytest.raises(ImageError, match=r"neg\.exr: 1 negative XYZ variances beyond float32 rounding .*row 2, column 3, channel Y"):
        read_variance_exr(tmp_path / "neg.exr", mean=mean_xyz @ imageio.XYZ_TO_RGB.T)
    var_xyz[2, 3, 1] = np.nan
    _mitsuba_var_file(tmp_path / "nan.exr", var_xyz)
    with pytest.raises(ImageError, match=r"nan\.exr: 3 non-finite values"):
        read_variance_exr(tmp_path / "nan.exr", mean=mean_xyz @ imageio.XYZ_TO_RGB.T)


def test_negative_variance_channels_of_a_render_are_refused(tmp_path):
    r = RenderResult(mean=np.ones((3, 3, 3), np.float32), variance=np.full((3, 3, 3), 0.1, np.float32), spp=4, seed=0,
                     max_depth=0, renderer="x")
    r.variance[1, 2, 0] = -0.5
    write_exr(tmp_path / "r.exr", r)
    with pytest.raises(ImageError, match=r"r\.exr: 1 negative entries in the variance channels \(first at row 1, column 2, channel R"):
        read_exr(tmp_path / "r.exr")


def test_moment_channels_under_the_names_mitsuba_3_9_gives_an_xml_scene(tmp_path):
    """``_arg_0.X`` / ``m2__arg_0.X`` (an XML scene's nested integrator) read as ``nested.*`` are."""
    g = np.random.default_rng(1)
    m1 = g.uniform(0.1, 1.0, (5, 4, 3))
    m2 = m1 * m1 + g.uniform(0.01, 0.1, (5, 4, 3))
    planes = {}
    for i, c in enumerate("XYZ"):
        planes[f"_arg_0.{c}"], planes[f"m2__arg_0.{c}"] = m1[..., i], m2[..., i]
        planes[f"nested_other.{c}"] = m1[..., i]  # a plain AOV of that name is not a moment
    _exr(tmp_path / "m.exr", planes)
    r = read_exr(tmp_path / "m.exr", spp=16)
    assert np.allclose(r.mean, m1 @ imageio.XYZ_TO_RGB.T, rtol=1e-5)
    assert "_arg_0" in r.extra["exr.moment"] and r.variance.min() > 0
    del planes["m2__arg_0.Z"]
    _exr(tmp_path / "i.exr", planes)
    with pytest.raises(ImageError, match="incomplete moment channels, missing m2__arg_0.Z"):
        read_exr(tmp_path / "i.exr")


def test_shared_references_and_a_moment_file_of_mitsuba_read(suite):
    """Every reference pair of the shared copy reads with a finite, non-negative variance; Mitsuba 2.1's moment file too."""
    refs = sorted((suite / "tests" / "scenes").glob("*/refs/*_ref_rgb.exr"))
    assert len(refs) >= 20
    for ref in refs:
        r = read_mitsuba_reference(ref, spp=32000, space="xyz")
        assert np.all(np.isfinite(r.variance)) and r.variance.min() >= 0, ref
        assert r.extra["channels"] == "XYZ"
    m = read_exr(suite / "tests/scenes/orthographic_sensor/refs/test_orthographic.exr", spp=16)
    assert "_arg_0" in m.extra["exr.moment"] and m.mean.shape == (120, 200, 3)


def test_compare_cli_variance_file_and_rtol_for_a_noiseless_offset(tmp_path, capsys):
    """A constant 1.0 stored as 1.00108 (a reference's rounding): reported as noiseless, accepted by --rtol, said so."""
    ones = np.ones((16, 16, 3), np.float32)
    write_exr(tmp_path / "a.exr", RenderResult(mean=ones, variance=0 * ones, spp=64, seed=0, max_depth=0, renderer="x"))
    ref = ones * 1.00108
    ref[:8] = 0.5
    _exr(tmp_path / "ref.exr", {c: ref[..., i] for i, c in enumerate("RGB")}, {"generatedBy": "Mitsuba version 2.2.1"})
    var_xyz = np.zeros((16, 16, 3))
    var_xyz[:8] = (0.01, 0.001, 0.01)  # the top half noisy on the reference's side (G of its file negative)
    _mitsuba_var_file(tmp_path / "ref_var.exr", var_xyz)
    a_var = np.zeros((16, 16, 3), np.float32)
    a_var[:8] = 0.05
    write_exr(tmp_path / "a.exr", RenderResult(mean=np.where(np.arange(16)[:, None, None] < 8, 0.5, 1.0).astype(np.float32)
                                               * ones, variance=a_var, spp=64, seed=0, max_depth=0, renderer="x"))
    args = ["compare", str(tmp_path / "a.exr"), str(tmp_path / "ref.exr"), "--variance-b", str(tmp_path / "ref_var.exr"),
            "--spp-b", "32000", "--tile", "4"]
    assert main(args) == 1
    out = capsys.readouterr().out
    assert "Mitsuba's XYZ variance" in out
    assert "noiseless tests" in out and "24 of the 24 rejected tests are noiseless (0 noisy)" in out
    assert "--rtol 0.0011 accepts it" in out
    assert main(args + ["--rtol", "0.0011"]) == 0
    assert "--rtol 0.0011 accepted 24 noiseless tests" in capsys.readouterr().out
    # A variance file with negative entries read as a plain RGB variance: exit 2, one line.
    assert main(args + ["--variance-kind", "rgb"]) == 2
    err = capsys.readouterr().err.strip()
    assert "negative entries" in err and "\n" not in err


# --------------------------------------------------------------------------
# 2. Rendering a Mitsuba scene as Mitsuba renders it
# --------------------------------------------------------------------------


def test_scene_file_rendered_with_its_filter_in_batches_and_its_wrapped_integrator(suite):
    """A gaussian-filtered scene goes in independent batches (dof, tile factor in the header); moment is unwrapped."""
    from mcrt.mitsuba import render_with_variance

    r = render_with_variance(suite / "tests/scenes/projector/test_projector_textured_direct.xml", spp=64, seed=1)
    assert r.renderer == "direct" and "moment" in r.extra["unwrapped"]
    assert r.extra["method"] == "batches" and r.extra["variance_dof"] == "31"
    assert "GaussianFilter" in r.extra["variance_method"] and "GaussianFilter (radius 2 px)" in r.extra["film"]
    assert abs(float(r.extra["tile_variance_factor"]) - np.pi) < 0.05  # (int g)^2 / int g^2 of a gaussian of sd 1/2
    box = render_with_variance(suite / "tests/scenes/spot_light/test_spot_direct.xml", spp=16, seed=1)
    assert box.extra["method"] == "samples" and "variance_dof" not in box.extra


def test_integrator_replaced_takes_only_its_parameters_and_scene_defaults(suite, tmp_path, capsys):
    """--integrator direct on a scene that sets a depth renders (and says so); -D sets <default>s, refuses others."""
    from mcrt.mitsuba import render_with_variance

    scene = suite / "tests/scenes/bsdf_spheres/test_arealight_path.xml"  # its path integrator has max_depth 2
    r = render_with_variance(scene, integrator="direct", spp=4, defaults={"spp": "4"})
    assert r.renderer == "direct" and r.max_depth == -1 and r.extra["parameters"] == "spp=4"
    assert render_with_variance(scene, spp=4).renderer == "path"
    with pytest.raises(ValueError, match="unreferenced"):  # a parameter the user names is not dropped
        render_with_variance(scene, integrator={"type": "direct", "max_depth": 3}, spp=4)
    out = tmp_path / "d.exr"
    spot = suite / "tests/scenes/spot_light/test_spot_direct.xml"
    assert main(["render", "--mitsuba-scene", str(spot), "-D", "integrator=path", "--spp", "4", "-o", str(out)]) == 0
    assert read_exr(out).renderer == "path"
    # The file's own XML gives its integrator a depth: -D integrator=direct fails in Mitsuba itself; the error says what works.
    assert main(["render", "--mitsuba-scene", str(scene), "-D", "integrator=direct", "--spp", "4", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "unreferenced property" in err and "name it with --integrator" in err
    assert main(["render", "--mitsuba-scene", str(scene), "--integrator", "direct", "--spp", "4", "-o", str(out)]) == 0
    assert read_exr(out).renderer == "direct"
    assert main(["render", "--mitsuba-scene", str(scene), "-D", "nosuch=1", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("test_arealight_path.xml") == 1 and "declares no parameter 'nosuch' (its defaults: spp=128, integrator=path)" in err


def test_gaussian_filtered_renders_of_two_seeds_agree_and_a_brighter_one_does_not(suite):
    """The batch variance with its degrees of freedom and tile factor keeps a false alarm away and still detects."""
    from mcrt.mitsuba import render_with_variance
    from mcrt.stats import compare

    scene = suite / "tests/scenes/projector/test_projector_textured_direct.xml"
    a = render_with_variance(scene, spp=256, seed=1)
    b = render_with_variance(scene, spp=256, seed=2)
    for tile in (1, 4, 8):
        assert compare(a, b, tile=tile).passed, tile
    b.mean *= 1.02
    assert not compare(a, b, tile=8).passed
