"""Rendering a hard case: mcrt and Mitsuba through the case's camera, at a square resolution."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

from mcrt.film import RenderResult
from mcrt.hardcases.catalogue import HardCase
from mcrt.render import render
from mcrt.scene import RenderSettings, Scene


def settings(scene: Scene, camera: str, res: int, spp: int, max_depth: int | None = None) -> RenderSettings:
    """``res`` x ``res`` pixels at ``spp`` through ``camera`` (max depth None: the scene file's)."""
    return scene.settings(camera=camera, width=res, height=res, spp=spp, max_depth=max_depth)



@contextlib.contextmanager
def mitsuba_clips(near: float, far: float) -> Iterator[None]:
    """Within the block, Mitsuba sensors built by :mod:`mcrt.mitsuba_scene` clip camera rays to [near, far].

    :func:`mcrt.mitsuba_scene.sensor_dict` scales the clip planes with the scene;
    this wraps it for the block, so the float32 sweep can show what Mitsuba's
    absolute defaults (0.01, 1e4) would do (not thread-safe).
    """
    import mcrt.mitsuba_scene as mm

    original = mm.sensor_dict

    def sensor_dict(*args, **kwargs):
        d = original(*args, **kwargs)
        d["near_clip"], d["far_clip"] = float(near), float(far)
        return d

    mm.sensor_dict = sensor_dict
    try:
        yield
    finally:
        mm.sensor_dict = original


def render_mcrt(hc: HardCase, scene: Scene, res: int, spp: int, seed: int, *, intersector: str | None = None,
                max_depth: int | None = None) -> RenderResult:
    """mcrt's render of ``scene`` through the case's camera (its intersector unless given)."""
    return render(scene, settings(scene, hc.camera, res, spp, max_depth), renderer="mcrt", seed=seed, progress=False,
                  intersector=intersector or hc.intersector)


def render_mitsuba_case(hc: HardCase, scene: Scene, res: int, spp: int, seed: int, *,
                        max_depth: int | None = None) -> RenderResult:
    """Mitsuba's render of ``scene`` through the case's camera."""
    return render(scene, settings(scene, hc.camera, res, spp, max_depth), renderer="mitsuba", seed=seed, progress=False)
