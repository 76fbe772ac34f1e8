r"""The first hit's light samples averaged over the batch: every surface given one and the same direct light.

A vectorised tracer keeps the light samples of a batch of vertices as an
(N, 1, 3) array and averages them with the wrong axis (``np.mean(L, axis=0)``
for ``axis=1``): the mean over the whole batch, broadcast back, is each
vertex's direct light. Every surface the camera sees then gets the same
direct light, one colour: no shadow, no fall-off, no colour of its own;
the light seen and the bounced light stay right. With :math:`D` the direct
light at the first hit (the basis's paths of depth 2 less those of depth
1, next-event estimation alone) and :math:`m` the pixels whose first hit is
a diffuse surface (the camera's first hits that :mod:`mcrt.grade.explain.aov`
prepares), the model image is

.. math::

    R + m\,(c - D),

with the colour :math:`c` fitted (three parameters, a weighted least
squares in closed form): the batch's mean depends on which rays the
program keeps in it. A colour of next to nothing (under :data:`MIN_SHARE`
of the mean direct light) is not read so: that is the direct light
missing, which the catalogue names.
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.direct_albedo import first_hit_direct
from mcrt.grade.explain.fit import Fit
from mcrt.grade.feedback import num as _num
from mcrt.grade.score import LUMINANCE

#: The least the fitted colour's luminance may be, as a share of the first hits' mean direct light: the batch's mean
#: is that mean (of the rays the program keeps in it); next to nothing is no mean but the direct light missing.
MIN_SHARE = 0.25


def direct_mean(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """R + m (c - D), c fitted (the module docstring)."""
    got = first_hit_direct(fit, inputs)
    if got is None:
        return []
    D, rho = got
    m = np.broadcast_to(rho.max(axis=-1, keepdims=True) > 0.0, D.shape) & fit.ok
    if not m.any():
        return []
    w = np.where(m, fit.w, 0.0)
    c = (w * (fit.D + D)).sum(axis=(0, 1)) / np.maximum(w.sum(axis=(0, 1)), 1e-300)
    if float(c @ LUMINANCE) < MIN_SHARE * float(D[m[..., 0]].mean(axis=0) @ LUMINANCE):
        return []  # a batch's mean of next to nothing is the direct light missing (mcrt.grade.explain.catalogue's)
    change = np.where(m, c - D, 0.0)
    colour = ", ".join(_num(float(v)) for v in c)
    text = (f"every surface's direct light at the first surface a camera ray meets one and the same colour, "
            f"({colour}): the light samples averaged over the whole batch of rays and broadcast back (a mean over "
            "the wrong axis), so no shadow, no fall-off and no colour of its own there, the bounced light right")
    return [Candidate("direct_mean", "direct light one colour", text, fit.delta(change), 3,
                      value={"colour": [float(v) for v in c]}, change=change)]


direct_mean.name = "direct_mean"
