r"""Each sample clamped: a student's firefly filter, which removes the fireflies' energy with them.

A per-sample clamp :math:`x \mapsto \min(x, c)` (per channel, on each
camera path's radiance before it is averaged) is not a function of the
pixel's value: it darkens every pixel whose *samples* sometimes exceed c
(the light seen directly, light sampled close to it, light reflected by the
mirror sphere onto the room), not only those whose mean does. So no curve on
the values (:mod:`.tonecurve`) describes it; mcrt renders it instead.

mcrt renders the scene with each sample clamped at every value of
:data:`LADDER` (the renderer's ``sample_clamp`` trick,
:class:`mcrt.options.Tricks`), at the basis's spp and seed
(:func:`mcrt.grade.explain.basis.basis_settings`: common random numbers with
the basis's render B of the scene as it is), kept in
``Basis.extra["sample_clamp"]``. The model image at clamp c is

.. math::

    M_c = R + (C_c - B),

with :math:`C_c` interpolated linearly in :math:`\log c` between the two
nearest renders (the expected image is monotone and smooth in c); c is
fitted on a grid of :data:`STEPS` points between neighbouring renders, one
parameter. A clamp's expected image does not depend on the sample count
(the bias of :math:`\min(x, c)` is a property of one sample), so the renders
at the basis's spp describe a hand-in of any spp.
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.basis import basis_settings
from mcrt.grade.explain.fit import Fit
from mcrt.grade.feedback import num as _num
from mcrt.scene import Scene

#: The clamps rendered (powers of 2: the light's radiance is 20 in the course's scene, and students clamp at 1 or
#: at a few times the brightest surface).
LADDER = (0.5, 1.0, 2.0, 4.0, 8.0, 16.0)
#: Grid points per octave between neighbouring renders.
STEPS = 4


def _prepare(a, scene: Scene, render) -> dict:
    """mcrt's renders of the scene with each sample clamped at each value of LADDER (the module docstring)."""
    spp, seed = basis_settings(a)
    imgs = [render(scene, a.camera, a.grade_width, a.grade_height, a.max_depth, spp, seed,
                   sample_clamp=float(c)).mean.astype(np.float32) for c in LADDER]
    return {"ladder": np.asarray(LADDER, np.float64), "images": np.stack(imgs)}


def sample_clamp(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """Each sample clamped at c, c fitted in log c between mcrt's renders (the module docstring)."""
    r = inputs.basis.extra.get(sample_clamp.name)
    if r is None:
        return []
    base = inputs.basis.base.astype(np.float64)
    ladder, imgs = r["ladder"], r["images"]
    logs = np.log2(ladder)
    grid = np.linspace(logs[0], logs[-1], (len(ladder) - 1) * STEPS + 1)

    def change(lc: float) -> np.ndarray:
        i = int(np.clip(np.searchsorted(logs, lc, side="right") - 1, 0, len(logs) - 2))
        t = float(np.clip((lc - logs[i]) / (logs[i + 1] - logs[i]), 0.0, 1.0))
        return (1.0 - t) * imgs[i].astype(np.float64) + t * imgs[i + 1].astype(np.float64) - base

    errs = np.array([fit.delta(change(lc)) for lc in grid])
    k = int(np.argmin(errs))
    c = float(2.0 ** grid[k])
    dm = change(grid[k])
    Le = np.asarray(inputs.basis.values.get("light_radiance", (np.inf,) * 3), np.float64)
    light = (f": the light itself shows {_num(min(c, float(Le.max())))} where the scene says {_num(float(Le.max()))}, "
             if c < float(Le.max()) else ": ")
    text = (f"each sample clamped at about {_num(c)} (fireflies removed with their energy){light}and pixels whose "
            "samples are sometimes brighter than that (near the light, and light the mirror reflects onto the room) "
            "darker than the scene makes them")
    # A curve on the values that maps the light to c reads the same image otherwise (it is no generalisation of a
    # per-sample clamp): where it leaves noise too, the feedback names it beside this one.
    return [Candidate("sample_clamp", "each sample clamped", text, float(errs[k]), 1, value=c, change=dm,
                      rivals=("tone_curve",))]


sample_clamp.name, sample_clamp.prepare = "sample_clamp", _prepare
