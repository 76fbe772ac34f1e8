"""The three-way comparison names the source of a disagreement (alpha 0.01, Holm; seeds 5, 6, 7)."""

from __future__ import annotations

import pytest

from mcrt.scene import load_scene
from mcrt.threeway import three_way


@pytest.fixture(scope="module")
def settings():
    scene = load_scene()
    return scene, scene.settings(width=32, height=32, spp=512, seed=5, max_depth=8)


@pytest.mark.parametrize(
    "mutants, verdict",
    [
        ((), "consistent"),
        (("no_jitter",), "geometry"),  # a camera bug of the standalone tracer only (the plugin uses Mitsuba's sensor)
        (("nee_no_area",), "estimator"),  # an estimator bug shared by mcrt and its plugin
    ],
)
def test_three_way_verdict(settings, mutants, verdict):
    scene, s = settings
    result = three_way(scene, s, mutants=mutants, progress=False)
    assert result.verdict.startswith(verdict), result.summary()
