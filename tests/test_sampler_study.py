"""``mcrt samplers`` (mcrt.sampler_study): its light-edge mask against geometry, its options, and a small run."""

from __future__ import annotations

import argparse
import json

import numpy as np
import pytest

from mcrt.camera import primary_directions
from mcrt.cli import main
from mcrt.sampler_study import _resolutions, edge_mask
from mcrt.scene import load_scene


def _geometric_coverage(scene, camera: str, res: int, sub: int = 16) -> np.ndarray:
    """Each pixel's covered fraction of the light, from sub x sub rays per pixel hitting its rectangle (no occluders)."""
    cam, light = scene.camera(camera), scene.light
    j, i, v, u = np.meshgrid(np.arange(res), np.arange(res), (np.arange(sub) + 0.5) / sub, (np.arange(sub) + 0.5) / sub,
                             indexing="ij")
    d = primary_directions(cam, res, res, i, j, u, v)
    t = (light.center[2] - cam.eye[2]) / d[..., 2]
    p = np.asarray(cam.eye) + t[..., None] * d
    inside = (t > 0) & (np.abs(p[..., 0] - light.center[0]) < light.size[0] / 2) & \
        (np.abs(p[..., 1] - light.center[1]) < light.size[1] / 2)
    return inside.mean(axis=(2, 3))


def test_edge_mask_is_where_pixels_partly_cover_the_light():
    """The depth-1 coverage agrees with the rectangle's geometry to 0.05 per pixel; the edge is where 0 < coverage < 1.

    Power: the mask is not empty, the light's interior is not in it, and a pixel shifted by one is not the same mask.
    """
    scene = load_scene()
    coverage, edge = edge_mask(scene, "near", 64)
    geo = _geometric_coverage(scene, "near", 64)
    assert np.abs(coverage - geo).max() < 0.05
    assert edge.sum() > 10 and (geo[edge] > 0).all() and (geo[edge] < 1).all()
    assert not edge[geo >= 0.999].any() and (geo >= 0.999).sum() > 10
    assert not np.array_equal(edge, np.roll(edge, 1, axis=1))


def test_resolutions_option():
    assert _resolutions("64:16,64;256:16") == {64: (16, 64), 256: (16,)}
    for bad in ("64", "64:12", "64:8", "x:16"):
        with pytest.raises(argparse.ArgumentTypeError):
            _resolutions(bad)


def test_small_run_writes_the_report(tmp_path):
    """64x64 at 16 spp, 2 seeds: index.md names the goal's verdict, data.json every variant with both efficiency ratios."""
    assert main(["samplers", "--resolutions", "64:16", "--seeds", "2", "--quiet", "--out", str(tmp_path)]) == 0
    text = (tmp_path / "index.md").read_text()
    assert "Goal 3x by MSE" in text and "light's edge" in text
    rows = json.loads((tmp_path / "data.json").read_text())["results"]["64"]["rows"]
    assert {r["label"] for r in rows} == {"mcrt", "sobol pixels (8 replicates)", "bidirectional",
                                          "bidirectional + sobol pixels", "bidirectional + sobol, light budget from a pilot"}
    plain = next(r for r in rows if r["label"] == "mcrt")
    assert plain["eff_mse_own"] == pytest.approx(1.0) and plain["regions"]["edge"]["pixels"] > 0
    assert (tmp_path / "error_64.png").exists() and (tmp_path / "error_map_64.png").exists()
