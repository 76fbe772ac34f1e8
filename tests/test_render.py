"""The one renderer interface (mcrt.render): every renderer called the same way, through one registry."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import mcrt
from mcrt.render import RENDERERS, get_renderer, render


@pytest.fixture(scope="module")
def small():
    scene = mcrt.load_scene()
    return scene, scene.settings(camera="near", width=8, height=8, spp=4, max_depth=3)


def test_the_registry_names_three_renderers_and_what_they_share():
    assert list(RENDERERS) == ["mcrt", "plugin", "mitsuba"]
    assert [(r.geometry, r.estimator) for r in RENDERERS.values()] == [("mcrt", "mcrt"), ("mitsuba", "mcrt"), ("mitsuba", "mitsuba")]
    with pytest.raises(ValueError, match="unknown renderer 'cycles'.*mcrt, plugin, mitsuba"):
        get_renderer("cycles")


@pytest.mark.parametrize("name", list(RENDERERS))
def test_every_renderer_is_reproducible_from_its_seed(small, name):
    scene, s = small
    a = render(scene, s, renderer=name, seed=3, progress=False)
    b = render(scene, replace(s, seed=3), renderer=name, progress=False)  # the seed from the settings
    c = render(scene, s, renderer=name, seed=4, progress=False)
    assert a.seed == b.seed == 3 and a.spp == 4 and a.max_depth == 3 and a.mean.shape == (8, 8, 3)
    assert np.array_equal(a.mean, b.mean) and np.array_equal(a.variance, b.variance)
    assert not np.array_equal(a.mean, c.mean)


def test_an_option_a_renderer_lacks_is_refused_by_name(small):
    scene, s = small
    with pytest.raises(ValueError, match="renderer 'mitsuba' has no option 'mutants'"):
        render(scene, s, renderer="mitsuba", mutants=("nee_no_area",))
    with pytest.raises(ValueError, match="renderer 'plugin' has no option 'intersector'"):
        render(scene, s, renderer="plugin", intersector="triangles")
