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
        (("nee_no_area",), "estimator"),  # an estimator bug: it runs on both hosts of the estimator
    ],
)
def test_three_way_verdict(settings, mutants, verdict):
    scene, s = settings
    result = three_way(scene, s, mutants=mutants, progress=False)
    assert result.verdict.startswith(verdict), result.summary()


def test_a_bug_in_mcrts_geometry_is_named_geometry(settings, monkeypatch):
    """mcrt's sphere intersected 1.5 times too large (a bug in mcrt's geometry only, not in the estimator the hosts share)."""
    import mcrt.geometry
    import mcrt.tracer

    scene, s = settings
    sphere = mcrt.geometry.Geometry._sphere
    monkeypatch.setattr(mcrt.geometry.Geometry, "_sphere", lambda self, o, d, c, r: sphere(self, o, d, c, 1.5 * r))
    monkeypatch.setattr(mcrt.tracer, "_TRACERS", {})  # a tracer traced before the patch must not be reused
    result = three_way(scene, s, progress=False)
    assert result.verdict.startswith("geometry"), result.summary()
