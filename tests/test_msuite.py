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
from mcrt import image_files
from mcrt.cli import main
from mcrt.film import RenderResult
from mcrt.image_files import ImageError, read_exr, read_mitsuba_reference, read_variance_exr, write_exr

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
    rgb = var_xyz @ image_files.XYZ_TO_RGB.T
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
    mean_rgb = mean_xyz @ image_files.XYZ_TO_RGB.T
    assert np.any(var_xyz @ image_files.XYZ_TO_RGB.T < 0)  # the file itself holds negative "variances"
    v, note = read_variance_exr(tmp_path / "v.exr", mean=mean_rgb, space="xyz")
    expect = var_xyz.copy()
    expect[1, 1, 2] = 0.0
    assert np.allclose(v, expect, rtol=1e-4, atol=1e-7) and "turned back into XYZ" in note
    rgb, _ = read_variance_exr(tmp_path / "v.exr", mean=mean_rgb)
    assert np.all(rgb >= 0) and np.allclose(rgb, (np.sqrt(expect) @ np.abs(image_files.XYZ_TO_RGB).T) ** 2, rtol=1e-3)
    # Read as a plain RGB variance, the negative entries are refused in one line naming the file.
    with pytest.raises(ImageError, match=r"v\.exr: \d+ negative entries in the variance .*--variance-kind mitsuba"):
        read_variance_exr(tmp_path / "v.exr", mean=mean_rgb, kind="rgb")


def test_mitsuba_variance_beyond_rounding_or_non_finite_is_refused(tmp_path):
    mean_xyz = np.full((4, 4, 3), 0.5)
    var_xyz = np.full((4, 4, 3), 0.01)
    var_xyz[2, 3, 1] = -0.01  # 4 % of m^2: no rounding error does that
    _mitsuba_var_file(tmp_path / "neg.exr", var_xyz)
    with pytest.raises(ImageError, match=r"neg\.exr: 1 negative XYZ variances beyond float32 rounding .*row 2, column 3, channel Y"):
        read_variance_exr(tmp_path / "neg.exr", mean=mean_xyz @ image_files.XYZ_TO_RGB.T)
    var_xyz[2, 3, 1] = np.nan
    _mitsuba_var_file(tmp_path / "nan.exr", var_xyz)
    with pytest.raises(ImageError, match=r"nan\.exr: 3 non-finite values"):
        read_variance_exr(tmp_path / "nan.exr", mean=mean_xyz @ image_files.XYZ_TO_RGB.T)


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
    assert np.allclose(r.mean, m1 @ image_files.XYZ_TO_RGB.T, rtol=1e-5)
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
    from mcrt.mitsuba_scene import render_with_variance

    r = render_with_variance(suite / "tests/scenes/projector/test_projector_textured_direct.xml", spp=64, seed=1)
    assert r.renderer == "direct" and "moment" in r.extra["unwrapped"]
    assert r.extra["method"] == "batches" and r.extra["variance_dof"] == "31"
    assert r.extra["variance_method"] == "batches:32" and "GaussianFilter" in r.extra["variance_note"] and "GaussianFilter (radius 2 px)" in r.extra["film"]
    assert abs(float(r.extra["tile_variance_factor"]) - np.pi) < 0.05  # (int g)^2 / int g^2 of a gaussian of sd 1/2
    box = render_with_variance(suite / "tests/scenes/spot_light/test_spot_direct.xml", spp=16, seed=1)
    assert box.extra["method"] == "samples" and "variance_dof" not in box.extra


def test_integrator_replaced_takes_only_its_parameters_and_scene_defaults(suite, tmp_path, capsys):
    """--integrator direct on a scene that sets a depth renders (and says so); -D sets <default>s, refuses others."""
    from mcrt.mitsuba_scene import render_with_variance

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
    from mcrt.mitsuba_scene import render_with_variance
    from mcrt.stats import compare

    scene = suite / "tests/scenes/projector/test_projector_textured_direct.xml"
    a = render_with_variance(scene, spp=256, seed=1)
    b = render_with_variance(scene, spp=256, seed=2)
    for tile in (1, 4, 8):
        assert compare(a, b, tile=tile).passed, tile
    b.mean *= 1.02
    assert not compare(a, b, tile=8).passed


# --------------------------------------------------------------------------
# 3, 4. What kind of difference; more power at the same budget
# --------------------------------------------------------------------------


def _noisy_pair(seed: int, shape=(32, 32), spp: int = 256, sd: float = 0.5):
    """Two renders of one image (mean 1) with Gaussian per-sample noise: their means and per-sample variances."""
    g = np.random.default_rng(seed)
    out = []
    for _ in range(2):
        m = 1.0 + g.normal(0.0, sd / np.sqrt(spp), (*shape, 3))
        v = sd * sd * g.chisquare(spp - 1, (*shape, 3)) / (spp - 1)
        out.append(RenderResult(mean=m.astype(np.float32), variance=v.astype(np.float32), spp=spp, seed=seed,
                                max_depth=0, renderer="synthetic"))
    return out


def test_rtol_is_a_margin_for_a_known_offset_and_only_that():
    """A 0.1 % offset over a low-noise image fails exactly, passes with --rtol 0.002, and 2 % still fails (seed 7)."""
    from mcrt.stats import compare

    a, b = _noisy_pair(7, spp=100000, sd=0.05)
    b.mean *= 1.001
    assert not compare(a, b).passed
    c = compare(a, b, rtol=0.002)
    assert c.passed and c.rtol == 0.002
    b.mean *= 1.02
    assert not compare(a, b, rtol=0.002).passed


def test_rtol_per_channel_accepts_each_channels_own_offset_only():
    """An offset of 0.025 % in X and Z (an old reference's white in XYZ) passes with the per-channel margin; the
    same offset in Y fails it (exact there), though one margin of 0.0011 in every channel accepts both (seed 7)."""
    from mcrt.stats import compare, compare_multiscale
    from mcrt.stats.twosample import EXACT_RTOL

    per_channel = (0.00031, EXACT_RTOL, 0.00028)
    a, b = _noisy_pair(7, spp=1000000, sd=0.05)
    b.mean[..., [0, 2]] *= np.float32(1.00025)
    assert not compare(a, b).passed
    c = compare(a, b, rtol=per_channel)
    assert c.passed and c.rtol == per_channel
    assert compare_multiscale(a, b, rtol=per_channel).passed
    b.mean[..., 1] *= np.float32(1.00025)
    assert compare(a, b, rtol=0.0011).passed
    ms = compare_multiscale(a, b, rtol=per_channel)
    assert not ms.passed and all(not r[..., [0, 2]].any() for r in ms.rejected)
    with pytest.raises(ValueError, match="rtol must be one non-negative number or 3"):
        compare(a, b, rtol=(0.001, 0.001))


def test_rounding_floor_accepts_float32_rounding_near_zero_and_costs_no_power():
    """A reference whose dark channel holds float32 rounding at the scale of 1 (multiples of 2^-24) against a
    render of that channel near 0 with tiny noise: rejected without the absolute margin, consistent with it; a
    1e-4 relative change of the bright channels is still caught with it (seed 11)."""
    from mcrt.msuite.run import ROUNDING_ATOL
    from mcrt.stats import compare_multiscale

    g = np.random.default_rng(11)
    shape, spp = (16, 16), 100000
    mean = np.ones((*shape, 3))
    mean[..., 2] = 0.0
    var = np.full((*shape, 3), 1e-4)
    var[..., 2] = 1e-14  # rounding-level noise of a channel whose true value is 0

    def side(m):
        return RenderResult(mean=m.astype(np.float32), variance=var.astype(np.float32), spp=spp, seed=11,
                            max_depth=0, renderer="synthetic")

    render = mean + g.normal(0.0, np.sqrt(var / spp))
    ref = mean + g.normal(0.0, np.sqrt(var / spp))
    ref[..., 2] = g.integers(0, 4, shape) * 2.0**-24  # what an old reference holds there: 0 to 3 steps of 2^-24
    assert not compare_multiscale(side(render), side(ref)).passed
    ms = compare_multiscale(side(render), side(ref), atol=ROUNDING_ATOL)
    assert ms.passed and ms.atol == ROUNDING_ATOL
    brighter = render.copy()
    brighter[..., :2] *= 1.0001
    assert not compare_multiscale(side(brighter), side(ref), atol=ROUNDING_ATOL).passed


def test_version_margin_per_xyz_channel_from_the_old_references_white(suite):
    """The margin against another version's reference is the stored white's offset in each XYZ channel, rounded
    up: X 0.00031, Y exact (the luminance row cancels it), Z 0.00028; the white is the shared reference's own."""
    from mcrt.msuite.run import STORED_WHITE_RGB, rounding_grid, rtol_text, xyz_version_rtol
    from mcrt.stats.twosample import EXACT_RTOL

    assert xyz_version_rtol() == (0.00031, EXACT_RTOL, 0.00028)
    assert rtol_text(xyz_version_rtol()) == "X 0.00031, Y exact, Z 0.00028" and rtol_text([0.0029] * 3) == "0.0029"
    white = read_exr(suite / "tests/scenes/bsdf_spheres/refs/test_constant_ref_rgb.exr").mean[0, 0]
    assert np.allclose(white, STORED_WHITE_RGB, rtol=0, atol=1e-6)
    assert rounding_grid(np.array([0.0, 3 * 2.0**-24, 2.0**-23, 1.3e-7, 0.5])) == {"dark": 3, "on_grid": 2}


def test_multiscale_sees_a_few_pixels_that_8x8_tiles_average_out():
    """A 2x2 patch 20 % brighter (a highlight moved): caught by the multi-scale family, not by 8x8 tiles (seed 3, FWER 0.01)."""
    from mcrt.stats import compare, compare_multiscale

    a, b = _noisy_pair(3)
    assert compare_multiscale(a, b).passed
    a.mean[10:12, 20:22] *= 1.2
    assert compare(a, b, tile=8).passed
    ms = compare_multiscale(a, b)
    assert not ms.passed and "2x2" in ms.by_scale() and ms.noiseless_rejected == 0
    assert ms.tiles == [2, 4, 8, 16, 0]  # 32 is the whole image: tested once


def test_multiscale_false_alarms_on_null_pairs_stay_near_alpha():
    """40 null pairs (seeds 100-139) at FWER 0.01: at most 2 rejected (P(>= 3) < 0.01 for a valid test)."""
    from mcrt.stats import compare_multiscale

    rejected = sum(not compare_multiscale(*_noisy_pair(s, shape=(24, 24))).passed for s in range(100, 140))
    assert rejected <= 2


def test_mitsuba_z_rule_as_mitsuba_applies_it():
    """Sidak level per pixel, 99.75 % of pixel-channels must pass, the variance floored at 1e-4."""
    from mcrt.msuite.zrule import z_rule

    ref = np.full((20, 20, 3), 0.5)
    var = np.full((20, 20, 3), 0.04)
    mean = ref.copy()
    assert z_rule(mean, ref, var, 100)["passed"] and z_rule(mean, ref, var, 100)["allowed"] == 3
    mean[0, :2] += 0.5  # 6 pixel-channels far off: more than the 3 allowed
    r = z_rule(mean, ref, var, 100)
    assert not r["passed"] and r["failing"] == 6


# --------------------------------------------------------------------------
# 5. The suite command
# --------------------------------------------------------------------------

_SCENE = """<scene version="3.0.0">
    <default name="spp" value="16"/>
    <integrator type="moment"><integrator type="path"><integer name="max_depth" value="3"/></integrator></integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, -3, 1.5" target="0, 0, 0" up="0, 0, 1"/></transform>
        <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/>
            <rfilter type="box"/></film>
    </sensor>
    <shape type="rectangle"><bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.5, 0.7"/></bsdf>
        <transform name="to_world"><scale value="2"/></transform></shape>
    <shape type="sphere"><point name="center" x="0" y="0" z="0.5"/><float name="radius" value="0.5"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf></shape>
    <shape type="rectangle"><emitter type="area"><rgb name="radiance" value="4"/></emitter>
        <transform name="to_world"><scale value="0.5"/><rotate x="1" angle="180"/><translate z="2.5"/></transform></shape>
</scene>
"""


def test_every_perturbation_changes_its_parameters_and_undoes_the_change(tmp_path):
    """Inside the block the parameters are scaled by the perturbation's factor; after it they are as loaded (Mitsuba
    assigns a parameter in place, so an undo from the object it returned restored nothing and every later render of
    the suite's scene stayed perturbed). The BSDF changed is the first by bounding box, not by load order."""
    import mitsuba as mi

    from mcrt import mitsuba_scene as mm
    from mcrt.msuite.perturb import DEPTH, FACTORS, PERTURBATIONS, perturbed

    xml = tmp_path / "s.xml"
    xml.write_text(_SCENE)
    mm._use("llvm")
    scene, _ = mm.load_scene_file(xml)

    def values():
        p = mi.traverse(scene)
        return {k: np.array(p[k]) for k in p.keys() if k.endswith(("x_fov", "radiance.value", "reflectance.value"))}

    before = values()
    assert len(before) == 5  # fov, radiance, three reflectances (the light's rectangle has a default BSDF)
    for name in PERTURBATIONS:
        with perturbed(mi, scene, name, 3) as change:
            if name == DEPTH:
                assert change == ("max_depth 3 -> 2", 2)
                continue
            inside = values()
            changed = [k for k in before if not np.array_equal(inside[k], before[k])]
            assert len(changed) == 1 and np.allclose(inside[changed[0]], before[changed[0]] * FACTORS[name], rtol=1e-6), name
            if name.startswith("BSDF"):  # the floor: the lowest corner of the shapes that are not lights
                assert np.allclose(before[changed[0]].ravel(), [0.2, 0.5, 0.7]) and change[0].startswith("bsdf.reflectance.value")
        after = values()
        assert all(np.array_equal(after[k], before[k]) for k in before), name


def _mitsuba_style_suite(root: Path, ref_spp: int) -> Path:
    """A one-scene tests/scenes folder laid out as Mitsuba's, with a reference pair written as Mitsuba writes it."""
    from mcrt.mitsuba_scene import render_with_variance

    group = root / "tests" / "scenes" / "made"
    (group / "refs").mkdir(parents=True)
    xml = group / "test_made_path.xml"
    xml.write_text(_SCENE)
    r = render_with_variance(xml, spp=ref_spp, seed=99, space="xyz")
    rgb = r.mean.astype(np.float64) @ image_files.XYZ_TO_RGB.T
    by = {"generatedBy": "Mitsuba version 3.9.1"}
    _exr(group / "refs" / "test_made_ref_rgb.exr", {c: rgb[..., i] for i, c in enumerate("RGB")}, by)
    _mitsuba_var_file(group / "refs" / "test_made_ref_rgb_var.exr", r.variance.astype(np.float64))
    return root


def test_suite_on_a_scene_mcrt_makes_consistent_and_perturbations_caught(tmp_path, capsys):
    import json

    root = _mitsuba_style_suite(tmp_path / "suite", ref_spp=16384)
    out = tmp_path / "report"
    rc = main(["mitsuba-suite", str(root), "--ref-spp", "16384", "--out", str(out)])
    data = json.loads((out / "data.json").read_text())
    case = data["cases"][0]
    assert case["name"] == "made/test_made_path" and case["integrator"] == "path" and case["spp"] == 2_000_000 // 256
    assert case["correct"][0]["mcrt"]["passed"] and case["correct"][0]["mitsuba"]["passed"]
    p = case["perturbations"]
    assert p["emitter x1.02"]["mcrt"]["caught"] and p["max depth - 1"]["change"] == "max_depth 3 -> 2"
    assert p["BSDF x0.98"]["mcrt"]["caught"] and p["fov x1.005"] is not None
    # The ladder: every size rendered, the issue's four apart; one scene, so its level is the suite's.
    from mcrt.msuite.perturb import ISSUE, PERTURBATIONS

    assert list(p) == list(PERTURBATIONS) and len(p) == 13 and data["scene_alpha"] == data["alpha"] == 0.01
    s = data["summary"]["all"]
    assert s["perturbations"] == 13 and sum(b["applicable"] for b in s["by_perturbation"].values()) == 13
    assert s["issue_sizes"]["applicable"] == 4 and set(ISSUE) <= set(s["by_perturbation"])
    md = (out / "index.md").read_text()
    assert "| made/test_made_path | 16x16, 7812 | path (per-sample) | consistent |" in md
    assert "## Perturbations at the issue's sizes" in md and "| scene | emitter x1.02 | fov x1.005 | max depth - 1 | BSDF x0.98 |" in md
    assert "fixed before any of its results were seen" in md and "| emitter x1.0003125 | 1 |" in md
    assert "Held-out scenes" in md and data["command"].startswith("mcrt mitsuba-suite")
    assert rc in (0, 1) and "[1/1] made/test_made_path: consistent" in capsys.readouterr().err
    assert main(["mitsuba-suite", str(tmp_path / "nowhere")]) == 2
    assert main(["mitsuba-suite", str(root), "--alpha", "1.5"]) == 2


def _fake_case(name: str, p_family: list[float], alpha: float, caught=None) -> dict:
    """A scene's result as :func:`mcrt.msuite.run.run_case` gives it, without rendering: correct renders with these
    family p-values (rejected at or below ``alpha``), the issue's emitter perturbation caught as ``caught`` says."""
    correct = [{"mcrt": {"p_family": p, "passed": p > alpha, "rejected": int(p <= alpha), "confirmed": False,
                         "failing": [], "noiseless_rejected": 0, "noisy_rejected": int(p <= alpha), "by_scale": {}},
                "mitsuba": {"passed": True, "failing": 0, "allowed": 17}} for p in p_family]
    who = caught or {"mcrt": True, "mitsuba": False}
    return {"name": name, "held_out": False, "alpha": alpha, "size": [8, 8], "spp": 4, "integrator": "path",
            "method": "samples", "time": 0.0, "correct": correct,
            "perturbations": {"emitter x1.02": {who_: {"caught": c} for who_, c in who.items()}, "fov x1.005": None}}


def test_suite_level_split_over_scenes_and_false_alarms_counted_per_suite_run(monkeypatch):
    """run_suite tests each of N scenes at alpha / N; a seed with a false alarm in any scene fails that suite run, and
    the rejection rate at other levels comes from the renders' family p-values (no rendering: run_case faked)."""
    from mcrt.msuite import run as suite_run
    from mcrt.msuite.markdown import markdown

    levels = {}
    p_values = {"bsdf_spheres/test_constant_path": [0.5, 0.003, 0.3], "spot_light/test_spot_direct": [0.2, 0.9, 1e-4],
                "texture_interp/test_texture_interp_direct": [1e-6, 1e-7, 1e-6]}  # rejected on every seed

    def fake_run_case(case, *, alpha, **options):
        levels[case.name] = alpha
        return _fake_case(case.name, p_values[case.name], alpha)

    monkeypatch.setattr(suite_run, "run_case", fake_run_case)
    monkeypatch.setattr(suite_run, "find_cases", lambda folder: ([suite_run.Case(n, Path(n), Path(n), Path(n))
                                                                   for n in p_values], []))
    data = suite_run.run_suite("anywhere", alpha=0.01)
    assert levels == {n: 0.01 / 3 for n in p_values} and data["scene_alpha"] == 0.01 / 3
    s = data["summary"]["all"]
    # The texture scene, rejected on every seed, shows a difference of its reference: no false alarm, and left out of
    # the power counts (its perturbed render's rejections are not the perturbation's). Seed 2 of the spot light
    # (p 1e-4) and seed 1 of the plain one (p 0.003) are rejected at 0.01 / 3: two suite runs fail.
    assert s["mcrt_reference_differences"] == 1 and s["power_left_out"] == ["texture_interp/test_texture_interp_direct"]
    assert s["mcrt_false_alarms"] == 2 and s["mcrt_suite_runs_failed"] == 2 and s["suite_runs"] == 3
    assert s["mcrt_calibration"] == {"renders": 6, "rejected": {"0.001": 1, "0.00333": 2, "0.01": 2, "0.05": 2}}
    assert s["mcrt_caught"] == 2 and s["mitsuba_caught"] == 0 and s["issue_sizes"]["applicable"] == 2
    data.update(command="mcrt mitsuba-suite anywhere", wall_time=1.0, options={"spp_scale": 1.0, "tiles": [2, 0], "ref_spp": 32000},
                provenance={"git_commit": "x", "versions": {}, "machine": {"cores": 2}})
    md = markdown(data)
    assert "at the level 0.00333: the suite's family-wise error rate 0.01 split evenly over its 3 scenes" in md
    assert "at 0.00333 (each scene's level): 2 (expected at most 0.02)" in md and "2 of 3 suite runs failed" in md
    assert "| 1, 1, 0 of 3 |" in md  # the spot light: rejected at its level, at 0.01, by Mitsuba's rule
    assert "| 3, 3, 0 of 3 |" in md and "| texture_interp/test_texture_interp_direct (a difference of the reference: not counted) |" in md


def test_suite_on_a_shared_scene_names_the_references_offset(suite, tmp_path):
    """The projector's reference (Mitsuba 3.0.1) is 0.05 % off in noiseless pixels: beyond the per-channel margin
    of the old versions' white, that offset is found, accepted as the scene's rtol and named; with one margin of
    0.0011 in every channel (--version-rtol) it is consistent within it, and says so."""
    import json

    out = tmp_path / "r"
    args = ["mitsuba-suite", str(suite), "--only", "projector/test_projector_constant_direct", "--no-perturbations"]
    main(args + ["--out", str(out)])
    data = json.loads((out / "data.json").read_text())
    case = data["cases"][0]
    assert case["integrator"] == "direct" and case["method"] == "batches"  # its film has Mitsuba's default gaussian
    assert case["version_rtol"] == [0.00031, 1e-5, 0.00028] == data["margins"]["version_rtol"]
    assert case["correct"][0]["mcrt"]["passed"] and 0.00031 < case["reference_offset"] < 0.0011
    assert min(case["rtol"]) >= case["reference_offset"]
    text = (out / "index.md").read_text()
    assert "reference's offset in noiseless pixels" in text and "X 0.00031, Y exact, Z 0.00028" in text
    main(args + ["--version-rtol", "0.0011", "--out", str(out)])
    case = json.loads((out / "data.json").read_text())["cases"][0]
    m = case["correct"][0]["mcrt"]
    assert m["passed"] and case["rtol"] == [0.0011] * 3 and 0 < m["largest_noiseless_difference"] < 0.0011
    assert "rtol 0.0011: a reference of Mitsuba version 3.0.1" in (out / "index.md").read_text()


def test_what_the_camera_sees_in_a_pixel_box_of_a_shared_scene(suite):
    """The lower right 16x16 tile of the bsdf_spheres grid sees the two masked leaves (Mask BSDFs, leaf_mask.png)
    and, mostly, nothing; the upper left one sees spheres, no leaf."""
    from mcrt import mitsuba_scene as mm
    from mcrt.msuite.run import scene_objects, seen_in

    mm._use("llvm")
    scene, _ = mm.load_scene_file(suite / "tests/scenes/bsdf_spheres/test_pointlight_path.xml")
    seen = dict(seen_in(scene, (32, 48, 32, 48)))
    leaves = [w for w in seen if w.startswith("rectangle.obj") and "Mask" in w and "leaf_mask.png" in w]
    assert len(leaves) == 2 and len(seen) == 3 and 0.6 < seen["nothing"] < 0.9
    assert set(leaves) <= set(scene_objects(scene)) and abs(sum(seen.values()) - 1) < 1e-9
    assert not any("leaf_mask" in w for w in dict(seen_in(scene, (0, 16, 0, 16))))


def test_a_rejection_the_other_seeds_confirm_is_a_difference_not_a_false_alarm():
    """Stouffer's z of the other seeds' t on the rejected test decides; their own rejections are not needed."""
    from mcrt.msuite.run import confirm, summarize

    def seed_result(t_value, rejected):
        t = np.zeros((4, 4, 3))
        t[1, 2, 0] = t_value
        m = np.zeros((4, 4, 3), bool)
        m[1, 2, 0] = rejected
        return {"mcrt": {"passed": not rejected, "p_family": 1e-5 if rejected else 0.5}, "mitsuba": {"passed": True}}, [m], [t]

    for others, expect in ((-2.5, True), (0.3, False)):
        runs = [seed_result(-4.6, True)] + [seed_result(others, False) for _ in range(4)]
        correct = [r[0] for r in runs]
        confirm(correct, [r[1] for r in runs], [r[2] for r in runs])
        assert correct[0]["mcrt"]["confirmed"] is expect and correct[1]["mcrt"]["confirmed"] is None
        s = summarize([{"name": "x", "alpha": 0.01, "correct": correct, "perturbations": {}}])
        assert s["mcrt_false_alarms"] == (0 if expect else 1) and s["mcrt_reference_differences"] == int(expect)
