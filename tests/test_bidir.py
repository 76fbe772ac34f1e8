"""The bidirectional renderer (mcrt.bidir): its light tracer, its partition of paths, its importance.

Every comparison is the project's two-sample test (mcrt.stats, Welch on
tiles, Holm over tiles and RGB) at family-wise level ALPHA = 0.01, with fixed
seeds, so each test always passes or always fails on a given machine.

* The light tracer alone (``part='light'``) against the path tracer
  restricted to the same paths (``mirror_caustics='only'``): two
  independent estimators of the class eye D ... D S+ L, at the default
  max depth and at max depth 3 (only eye D S L: the depth rule's edge), where
  a light tracer that counted one segment more or less would differ. At max
  depth 2 the class is empty: the light tracer adds exactly nothing.
* Balance weights: both strategies' shares of the class add up to it, on the
  canonical scene and where the class lies a step from the eye.
* A wrong camera importance (no cos^3, an extra cos) is rejected by the same
  comparison.
* The whole render against the committed Mitsuba reference and against plain
  mcrt at a larger spp.
* A seed gives the same image bit for bit (splats are fixed-point integers).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from mcrt.bidir import render_bidirectional
from mcrt.groundtruth import load_reference
from mcrt.render import render
from mcrt.scene import load_scene
from mcrt.stats import compare, compare_images

ALPHA = 0.01
RES = 64
LIGHT_SPP = 1024  # light tracer: 4M light subpaths at 64x64 (light_paths 1)
CLASS_SPP = 8192  # the path tracer restricted to the class, which it finds only by chance: many samples
CLASS_TILE = 16  # its per-pixel estimates are heavy-tailed: larger tiles give the central limit theorem room
DEPTH_TILE = 32  # at max depth 3 the path tracer's hits of the class are rarer still


@pytest.fixture(scope="module")
def scene():
    return load_scene()


def _settings(scene, spp, seed, max_depth=8):
    return replace(scene.settings(camera="near", width=RES, height=RES, spp=spp, max_depth=max_depth), seed=seed)


@pytest.fixture(scope="module")
def class_c(scene):
    """The path tracer's image of the paths eye D ... D S+ L (seed 31)."""
    return render(scene, _settings(scene, CLASS_SPP, 31), mirror_caustics="only", progress=False)


def _light(scene, seed, max_depth=8, **kw):
    """The light tracer alone, binary weights: all of class C."""
    return render_bidirectional(scene, _settings(scene, LIGHT_SPP, seed, max_depth), part="light", weights="binary",
                                light_paths=1.0, progress=False, **kw)


def test_light_tracer_matches_path_tracer_on_its_paths(scene, class_c):
    """Light tracer (seed 32) against the path tracer on class C (seed 31): same expected image at ALPHA."""
    lt = _light(scene, 32)
    assert lt.mean.max() > 0.01  # the caustics are there (a light tracer that splats nothing could "agree" with noise)
    c = compare_images(lt, class_c, alpha=ALPHA, tile=CLASS_TILE)
    assert c.passed, c.summary()


def test_balance_weights_share_the_class(scene, class_c):
    """Balance weights: both strategies' shares of class C (seed 37) add up to the path tracer's class C (seed 31)."""
    both = render_bidirectional(scene, _settings(scene, LIGHT_SPP, 37), part="caustics", light_paths=1.0,
                                progress=False)
    c = compare_images(both, class_c, alpha=ALPHA, tile=CLASS_TILE)
    assert c.passed, c.summary()


def test_balance_weights_near_the_eye():
    """Class C a step from the eye (hard case grazing_wall, 32x32): the path tracer's share is large there.

    Both shares (seed 38, 4096 spp) agree with the path tracer's class C
    (seed 39, 16384 spp) at ALPHA, 8x8 tiles; the light tracer's share alone
    does not, so weights that left out the path tracer would fail.
    """
    near = load_scene("reference/scenes/hard/grazing_wall.toml")
    s = replace(near.settings(), width=32, height=32, spp=4096, seed=38)
    plain = render(near, replace(s, spp=16384, seed=39), mirror_caustics="only", progress=False)
    both = render_bidirectional(near, s, part="caustics", light_paths=1.0, progress=False)
    assert compare_images(both, plain, alpha=ALPHA, tile=8).passed
    light = render_bidirectional(near, s, part="light", light_paths=1.0, progress=False)
    assert not compare_images(light, plain, alpha=ALPHA, tile=8).passed


@pytest.mark.parametrize("cos_power", [0, 4], ids=["no_cos3", "cos4"])
def test_wrong_camera_importance_is_rejected(scene, class_c, cos_power):
    """The light tracer with W = 1/(A_pix cos^p), p != 3 (seed 32), differs from the path tracer at ALPHA."""
    lt = _light(scene, 32, importance_cos_power=cos_power)
    assert not compare_images(lt, class_c, alpha=ALPHA, tile=CLASS_TILE).passed


def test_depth_rule_matches_path_tracer(scene):
    """At max depth 3 only eye D S L is in the class: light tracer (seed 33) vs path tracer (seed 34) at ALPHA.

    One segment too many would add eye D D S L, one too few would give black.
    DEPTH_TILE-pixel tiles: the path tracer's rare hits need them.
    """
    lt = _light(scene, 33, max_depth=3)
    pt = render(scene, _settings(scene, CLASS_SPP, 34, max_depth=3), mirror_caustics="only", progress=False)
    assert lt.mean.max() > 0.01
    assert compare_images(lt, pt, alpha=ALPHA, tile=DEPTH_TILE).passed
    wrong = _light(scene, 33, max_depth=4)  # the class up to 4 segments holds more light
    assert not compare_images(wrong, pt, alpha=ALPHA, tile=DEPTH_TILE).passed


def test_no_class_paths_at_depth_2(scene):
    """Max depth 2 leaves no path eye D S+ L: the light tracer splats nothing, and the path tracer finds nothing."""
    assert not _light(scene, 35, max_depth=2).mean.any()
    pt = render(scene, _settings(scene, 256, 36, max_depth=2), mirror_caustics="only", progress=False)
    assert not pt.mean.any()


@pytest.fixture(scope="module")
def bidirectional(scene):
    """The whole bidirectional render, 1024 spp, seed 40."""
    return render(scene, _settings(scene, 1024, 40), bidirectional=True, progress=False)


def test_bidirectional_matches_mitsuba_reference(scene, bidirectional):
    """Against the committed Mitsuba reference (near, 64x64, depth 8), independent policy, ALPHA, 8x8 tiles."""
    ref = load_reference(scene, "near", RES, 8)
    assert compare(bidirectional, ref, policy="independent", alpha=ALPHA).passed


def test_bidirectional_matches_plain_mcrt(scene, bidirectional):
    """Against plain mcrt at 8192 spp (seed 41), ALPHA, 8x8 tiles.

    Not at equal spp: plain mcrt at 1024 spp often misses the rare paths
    that light tracing takes over, and then underestimates both their mean
    and its variance (the fireflies this renderer is for).
    """
    plain = render(scene, _settings(scene, 8192, 41), progress=False)
    assert compare_images(bidirectional, plain, alpha=ALPHA).passed


def test_same_seed_same_image(scene):
    """Splats are added as integers: two renders with one seed are equal bit for bit, another seed differs."""
    a, b = (render(scene, _settings(scene, 64, 7), bidirectional=True, progress=False) for _ in range(2))
    c = render(scene, _settings(scene, 64, 8), bidirectional=True, progress=False)
    assert np.array_equal(a.mean, b.mean) and np.array_equal(a.variance, b.variance)
    assert not np.array_equal(a.mean, c.mean)


def test_refusals(scene):
    """Mutants, an unknown part and no light paths are refused with a one-line error."""
    s = _settings(scene, 64, 1)
    with pytest.raises(ValueError, match="no mutants"):
        render(scene, s, bidirectional=True, mutants=("brdf_no_inv_pi",), progress=False)
    with pytest.raises(ValueError, match="part must be one of"):
        render_bidirectional(scene, s, part="eye", progress=False)
    with pytest.raises(ValueError, match="light_paths must be > 0"):
        render_bidirectional(scene, s, light_paths=0, progress=False)
