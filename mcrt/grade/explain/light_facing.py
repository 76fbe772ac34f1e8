r"""The light emitting on the wrong side: its normal flipped (it lights the ceiling), or on both sides.

mcrt renders the scene with the light's normal flipped, F, at the basis's
spp and seed (:func:`mcrt.grade.explain.basis.basis_settings`), kept in
``Basis.extra["light_facing"]`` with the scene's normal. Radiance is linear
in what the light emits and the geometry is the same, so with B the basis's
render of the scene as it is, the model images are

* the light facing the other way: :math:`R + (F - B)`;
* the light emitting on both sides (a cosine taken as its absolute value):
  :math:`R + F`.

Neither has a free parameter.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.basis import basis_settings
from mcrt.grade.explain.fit import Fit
from mcrt.scene import Scene


def _prepare(a, scene: Scene, render) -> dict:
    """The scene's light normal, and mcrt's render F of the scene with it flipped (the module docstring)."""
    spp, seed = basis_settings(a)
    lt = scene.light
    flipped = replace(scene, light=replace(lt, normal=tuple(-float(x) for x in lt.normal)))
    F = render(flipped, a.camera, a.grade_width, a.grade_height, a.max_depth, spp, seed).mean.astype(np.float32)
    return {"normal": tuple(float(x) for x in lt.normal), "image": F}


def light_facing(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The light facing the other way, and emitting on both sides (the module docstring)."""
    r = inputs.basis.extra.get(light_facing.name)
    if r is None:
        return []
    F = r["image"].astype(np.float64)
    up = "up, into the ceiling" if r["normal"][2] < 0 else "down, onto the floor"
    flip, both = F - inputs.basis.base.astype(np.float64), F
    return [Candidate("light_facing", "light facing the other way", f"the light emitting on its other side ({up}): "
                      "its normal flipped, or the cosine at the light taken with the wrong sign", fit.delta(flip), 0,
                      value="flipped", change=flip),
            Candidate("light_facing", "light emitting on both sides", "the light emitting on both sides (the cosine at "
                      "the light taken as its absolute value)", fit.delta(both), 0, value="both sides", change=both)]


light_facing.name, light_facing.prepare = "light_facing", _prepare
