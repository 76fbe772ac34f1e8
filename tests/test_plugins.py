"""The Mitsuba integrator 'mcrt' (mcrt.plugins): loading, scene checks, and the three-way comparison.

The three renderers of the canonical scene must agree by the project's test
(mcrt.stats.compare_images, Welch tile test, Holm FWER alpha = 0.01, 8x8
tiles): the plugin against Mitsuba's path integrator (same geometry,
different estimators) and against the standalone tracer (same estimator,
different geometry). Seeds are fixed, so every outcome is reproducible; with
a correct estimator each comparison fails with probability at most alpha.
Renders are 32 x 32 with 512 spp per side.
"""

from __future__ import annotations

import numpy as np
import pytest

import mcrt
import mcrt.plugins as plugins
from mcrt.mitsuba_scene import load_mitsuba_scene, scene_dict, variant_for
from mcrt.mutants import MUTANTS
from mcrt.plugins import check_scene
from mcrt.render import render
from mcrt.stats import compare_images

import drjit as dr  # noqa: E402,F401  (after mcrt: it sets DRJIT_LIBLLVM_PATH)
import mitsuba as mi  # noqa: E402

ALPHA = 0.01  # family-wise error rate of each image comparison (Holm)
TILE = 8
W = H = 32
SPP = 512
# Fixed, distinct seeds per renderer: the sides of a comparison are independent.
SEED_PLUGIN, SEED_PATH, SEED_TRACER = 101, 202, 303


@pytest.fixture(autouse=True)
def llvm_variant():
    """Every test runs in llvm_ad_rgb (other test files may have left another variant)."""
    variant = variant_for("llvm")
    if mi.variant() != variant:
        mi.set_variant(variant)  # the variant callback registers 'mcrt'


@pytest.fixture(scope="module")
def scene():
    return mcrt.load_scene(mcrt.CANONICAL)


def _compare(a, b):
    return compare_images(a, b, alpha=ALPHA, tile=TILE)


# --------------------------------------------------------------------------
# Registration and loading
# --------------------------------------------------------------------------

SMALL_XML = """<scene version="3.0.0">
    <integrator type="mcrt">
        <integer name="max_depth" value="4"/>
        <integer name="light_samples" value="2"/>
        <string name="mutant" value=""/>
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, -6, 0" target="0, 0, 0" up="0, 0, 1"/></transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/><rfilter type="box"/></film>
    </sensor>
    <shape type="sphere"><bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.5, 0.2"/></bsdf></shape>
    <shape type="rectangle">
        <transform name="to_world"><rotate x="1" angle="180"/><translate value="0, 0, 3"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
        <emitter type="area"><rgb name="radiance" value="10"/></emitter>
    </shape>
</scene>"""


def test_registered_and_loaded_from_a_dict():
    plugins.register()  # idempotent; import already registered it
    integ = mi.load_dict({"type": "mcrt", "max_depth": 3, "light_samples": 4, "rr_depth": 2, "mutant": "nee_no_area,rr_no_divide"})
    assert isinstance(integ, plugins.McrtIntegrator) and isinstance(integ, mi.SamplingIntegrator)
    o = integ.options
    assert (o.settings.max_depth, o.settings.light_samples, o.settings.rr_depth) == (3, 4, 2)
    assert integ.mutants == {"nee_no_area", "rr_no_divide"}
    assert not o.mutations.nee_pdf_area and o.mutations.roulette == "course2023"
    assert "light_samples=4" in integ.to_string()
    assert mi.load_dict({"type": "mcrt", "max_depth": -1}).options.depth_limit == 2**32 - 1  # unbounded
    default = mi.load_dict({"type": "mcrt"}).options.settings
    assert (default.max_depth, default.light_samples, default.rr_depth, default.mis) == (8, 1, 5, False)
    assert mi.load_dict({"type": "mcrt", "mis": True}).options.settings.mis


def test_loaded_from_xml_and_rendered_by_mi_render():
    ms = mi.load_string(SMALL_XML)
    integ = ms.integrator()
    assert isinstance(integ, plugins.McrtIntegrator) and integ.options.settings.light_samples == 2 and integ.options.settings.max_depth == 4
    img = np.asarray(mi.render(ms, spp=8, seed=1))
    assert img.shape == (16, 16, 3) and np.all(np.isfinite(img)) and np.all(img >= 0)
    # The lit top of the orange sphere, black background; the light is out of view.
    assert img.max() > 0.1 and img[0, 0].max() == 0.0
    centre = img[4:8, 6:10].mean(axis=(0, 1))
    assert centre[0] > centre[1] > centre[2] > 0


def test_registered_again_after_a_variant_change():
    before = mi.variant()
    try:
        mi.set_variant("scalar_rgb")
        integ = mi.load_dict({"type": "mcrt", "max_depth": 2})
        assert type(integ).__name__ == "McrtIntegrator" and isinstance(integ, mi.SamplingIntegrator)
    finally:
        mi.set_variant(before)
    assert isinstance(mi.load_dict({"type": "mcrt"}), plugins.McrtIntegrator)


@pytest.mark.parametrize(
    "mutant, message",
    [("bogus", "unknown mutant 'bogus'"), ("no_jitter", "'no_jitter' changes the camera"), ("gamma_output", "not the estimator")],
)
def test_refuses_unknown_and_unsupported_mutants(mutant, message):
    with pytest.raises(ValueError, match=message):
        plugins.parse_mutants(mutant)
    with pytest.raises(RuntimeError, match=message):
        mi.load_dict({"type": "mcrt", "mutant": mutant})


def test_refuses_bad_parameters():
    with pytest.raises(RuntimeError, match="light_samples must be >= 1"):
        mi.load_dict({"type": "mcrt", "light_samples": 0})
    with pytest.raises(RuntimeError, match="max_depth must be"):
        mi.load_dict({"type": "mcrt", "max_depth": -2})
    with pytest.raises(RuntimeError, match="unreferenced property"):
        mi.load_dict({"type": "mcrt", "spp_typo": 3})


# --------------------------------------------------------------------------
# Scene check
# --------------------------------------------------------------------------


def _small_scene(bsdf=None, emitter=None):
    scene = {
        "type": "scene",
        "integrator": {"type": "mcrt"},
        "ball": {"type": "sphere", "bsdf": bsdf or {"type": "diffuse"}},
        "lamp": {
            "type": "rectangle",
            "to_world": mi.ScalarTransform4f().translate([0, 0, 3]) @ mi.ScalarTransform4f().rotate([1, 0, 0], 180),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 10.0}},
        },
        "sensor": {"type": "perspective", "film": {"type": "hdrfilm", "width": 4, "height": 4}},
    }
    if emitter is not None:
        scene["extra_light"] = emitter
    return mi.load_dict(scene)


def test_accepts_the_canonical_scene_and_mirrors(scene):
    check_scene(load_mitsuba_scene(scene, "near", 8, 8, integrator={"type": "mcrt"}))
    check_scene(_small_scene({"type": "conductor", "material": "none"}))
    check_scene(_small_scene({"type": "twosided", "bsdf": {"type": "conductor"}}))
    check_scene(_small_scene({"type": "twosided", "bsdf": {"type": "diffuse"}}))


@pytest.mark.parametrize(
    "bsdf, plugin",
    [
        ({"type": "roughconductor"}, "'roughconductor'"),
        ({"type": "dielectric"}, "'dielectric'"),
        ({"type": "plastic"}, "'plastic'"),
        ({"type": "twosided", "bsdf": {"type": "roughconductor"}}, "'twosided'"),
        ({"type": "conductor", "material": "Au"}, "not a perfect mirror"),
    ],
)
def test_refuses_other_bsdfs(bsdf, plugin):
    ms = _small_scene(bsdf)
    with pytest.raises(ValueError, match=plugin) as e:
        check_scene(ms)
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith("mcrt integrator:") and "shape 'ball'" in msg


@pytest.mark.parametrize(
    "emitter, plugin",
    [
        ({"type": "point", "position": [0, 0, 2]}, "'point'"),
        ({"type": "constant"}, "'constant'"),
        ({"type": "directional", "direction": [0, 0, -1]}, "'directional'"),
    ],
)
def test_refuses_other_emitters(emitter, plugin):
    ms = _small_scene(emitter=emitter)
    with pytest.raises(ValueError, match=plugin) as e:
        check_scene(ms)
    msg = str(e.value)
    assert "\n" not in msg and "only 'area' emitters" in msg and "extra_light" in msg


def test_the_integrator_itself_refuses_a_roughconductor_scene(scene):
    """The check runs inside sample(): under mi.render the ValueError is the cause of Mitsuba's error."""
    d = scene_dict(scene, "near", 8, 8, 4, integrator={"type": "mcrt"})
    sphere = scene.spheres()[0].name
    d[sphere] = dict(d[sphere], bsdf={"type": "roughconductor", "alpha": 0.2})
    ms = mi.load_dict(d)
    with pytest.raises(Exception) as e:
        mi.render(ms, spp=1)
    chain, err = [], e.value
    while err is not None:
        chain.append(err)
        err = err.__cause__ or err.__context__
    assert any(isinstance(x, ValueError) and "'roughconductor'" in str(x) and f"shape '{sphere}'" in str(x) for x in chain), chain


def test_the_integrator_itself_refuses_a_point_light(scene):
    d = scene_dict(scene, "near", 8, 8, 4, integrator={"type": "mcrt"})
    d["bulb"] = {"type": "point", "position": [5.0, 0.0, 0.0], "intensity": {"type": "rgb", "value": 1.0}}
    ms = mi.load_dict(d)
    with pytest.raises(ValueError, match="emitter 'bulb' is of type 'point'"):
        ms.integrator().sample(ms, ms.sensors()[0].sampler(), mi.RayDifferential3f(mi.Ray3f([0, 0, 0], [1, 0, 0])), None, True)


# --------------------------------------------------------------------------
# Renders: the three-way comparison on the canonical scene
# --------------------------------------------------------------------------


def _render(scene, renderer, seed, *, camera=None, width=W, height=H, spp=SPP, max_depth=8, light_samples=1, **options):
    s = scene.settings(camera=camera, width=width, height=height, spp=spp, max_depth=max_depth, light_samples=light_samples)
    return render(scene, s, renderer=renderer, seed=seed, progress=False, **options)


def test_render_plugin_result(scene):
    kw = dict(width=16, height=16, spp=8, max_depth=4, light_samples=3)
    r = _render(scene, "plugin", 5, **kw)
    assert r.renderer == "mitsuba-mcrt" and r.camera == "near" and r.spp == 8 and r.max_depth == 4
    assert r.mean.shape == r.variance.shape == (16, 16, 3) and r.mean.dtype == np.float32
    assert np.all(np.isfinite(r.mean)) and np.all(r.mean >= 0) and np.any(r.variance > 0)
    assert r.extra["integrator"] == "mcrt" and r.extra["light_samples"] == "3" and r.extra["variant"] == "llvm_ad_rgb"
    assert r.scene_hash == scene.content_hash()
    again = _render(scene, "plugin", 5, **kw)
    assert np.array_equal(r.mean, again.mean) and np.array_equal(r.variance, again.variance)


@pytest.mark.parametrize("camera", ["near", "far"])
def test_max_depth_1_equals_path_bit_for_bit(scene, camera):
    """With max_depth 1 both integrators return the emission at the first hit of the same camera rays."""
    kw = dict(camera=camera, width=16, height=16, spp=8, max_depth=1)
    a, b = _render(scene, "plugin", 7, **kw), _render(scene, "mitsuba", 7, **kw)
    assert np.array_equal(a.mean, b.mean) and np.array_equal(a.variance, b.variance)


_renders: dict = {}


def _three(scene, camera, max_depth):
    """(plugin, path, tracer) renders of one configuration, cached for the two comparisons."""
    key = (camera, max_depth)
    if key not in _renders:
        kw = dict(camera=camera, max_depth=max_depth)
        _renders[key] = (_render(scene, "plugin", SEED_PLUGIN, **kw), _render(scene, "mitsuba", SEED_PATH, **kw),
                         _render(scene, "mcrt", SEED_TRACER, **kw))
    return _renders[key]


CONFIGS = [("near", 2), ("near", 8), ("far", 2), ("far", 8)]


@pytest.mark.parametrize("camera, max_depth", CONFIGS)
def test_plugin_agrees_with_mitsuba_path(scene, camera, max_depth):
    plugin, path, _ = _three(scene, camera, max_depth)
    c = _compare(plugin, path)
    assert c.passed, c.summary()


@pytest.mark.parametrize("camera, max_depth", CONFIGS)
def test_plugin_agrees_with_standalone_tracer(scene, camera, max_depth):
    plugin, _, tracer = _three(scene, camera, max_depth)
    c = _compare(plugin, tracer)
    assert c.passed, c.summary()


def test_plugin_with_four_light_samples_agrees_with_mitsuba_path(scene):
    plugin = _render(scene, "plugin", SEED_PLUGIN + 1, light_samples=4)
    _, path, _ = _three(scene, "near", 8)
    c = _compare(plugin, path)
    assert c.passed, c.summary()


# --------------------------------------------------------------------------
# Parity: the estimator on both hosts, every mutant, MIS on and off
# --------------------------------------------------------------------------

HARD_SCENES = sorted((mcrt.CANONICAL.parent / "hard").glob("*.toml"))
# no_offset is the one bug whose image is the intersector's, not the estimator's: whether a ray
# that starts exactly on a surface hits it again depends on the intersection arithmetic (mcrt's
# convex room never re-hits the face a ray leaves; Mitsuba's triangles do, and mcrt's own
# triangles differently again). It is checked on each host apart, below.
PARITY_MUTANTS = [m for m in MUTANTS if m != "no_offset"]
# Each parity case compares the plugin with the standalone tracer at a level of ALPHA / PARITY_CASES
# (Bonferroni), so that the whole family of parity tests false-alarms with probability at most ALPHA.
PARITY_CASES = 2 * (1 + len(PARITY_MUTANTS)) + len(HARD_SCENES)
PARITY_ALPHA = ALPHA / PARITY_CASES


def _parity(scene, seed, **options):
    a = _render(scene, "plugin", seed, **options)
    b = _render(scene, "mcrt", seed + 500, **options)
    return compare_images(a, b, alpha=PARITY_ALPHA, tile=TILE)


@pytest.mark.parametrize("mis", [False, True], ids=["area-sampling", "mis"])
@pytest.mark.parametrize("mutant", [None, *PARITY_MUTANTS])
def test_every_mutant_agrees_on_both_hosts(scene, mutant, mis):
    """The plugin and the standalone tracer with the same bug switched on render the same image.

    Canonical scene, near camera, 32x32, 512 spp per side, max depth 8;
    seeds 1000 + 10 k (plugin) and 1500 + 10 k (tracer) for the k-th case.
    """
    k = PARITY_MUTANTS.index(mutant) + 1 if mutant else 0
    c = _parity(scene, 1000 + 10 * k + mis, mutants=(mutant,) if mutant else (), mis=mis)
    assert c.passed, f"{mutant or 'no mutant'}, mis={mis}: {c.summary()}"


@pytest.mark.parametrize("path", HARD_SCENES, ids=[p.stem for p in HARD_SCENES])
def test_hard_cases_agree_on_both_hosts(path):
    """Each hard scene (reference/scenes/hard) with MIS where it needs it, as both hosts decide (mcrt.light.needs_mis).

    32x32, 512 spp per side, max depth 8, its default camera; seeds 3000 + k and 3500 + k.
    """
    hard = mcrt.load_scene(path)
    c = _parity(hard, 3000 + HARD_SCENES.index(path))
    assert c.passed, f"{path.stem}: {c.summary()}"


def test_no_offset_darkens_on_each_host(scene):
    """no_offset on either host against the correct renderer of the same host: detected (level ALPHA; seeds 41-44)."""
    for renderer in ("plugin", "mcrt"):
        bad, good = _render(scene, renderer, 41, mutants=("no_offset",)), _render(scene, renderer, 43)
        c = _compare(bad, good)
        assert not c.passed and bad.mean.mean() < good.mean.mean(), f"{renderer}: {c.summary()}"


@pytest.mark.parametrize("mutant", ["nee_no_area", "rr_no_divide", "uniform_as_cosine", "double_count"])
def test_mutant_on_the_plugin_is_detected_against_path(scene, mutant):
    bad = _render(scene, "plugin", SEED_PLUGIN + 7, mutants=(mutant,))
    _, path, _ = _three(scene, "near", 8)
    c = _compare(bad, path)
    assert not c.passed, f"{mutant} not detected: {c.summary()}"
