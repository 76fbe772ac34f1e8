r"""Bloom (glare) after rendering: the bright part of the image blurred and added back.

A program that imitates a camera's glare takes what exceeds a threshold t,
blurs it with a Gaussian of radius :math:`\sigma` and adds a share a of it:

.. math::

    S = R + a\,G_\sigma * \max(R - t, 0).

For each (t, :math:`\sigma`) of :data:`THRESHOLDS` x :data:`SIGMAS` the
model is linear in a, fitted in closed form by weighted least squares on
the fit's pixel weights; three parameters, worded in the student's terms
(the threshold, the radius in pixels of the graded image, the strength).
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.grade.feedback import num as _num

#: Thresholds (radiance above which the image glows) and blur radii (grade pixels) tried.
THRESHOLDS = (0.5, 1.0, 2.0)
SIGMAS = (1.0, 2.0, 4.0, 8.0)


def bloom(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The best bloom of the grid (the module docstring); none where the image has nothing above a threshold."""
    from scipy.ndimage import gaussian_filter

    R = np.maximum(fit.R, 0.0)
    best = None
    for t in THRESHOLDS:
        over = np.maximum(R - t, 0.0)
        if not over.any():
            continue
        for s in SIGMAS:
            x = gaussian_filter(over, (s, s, 0), mode="constant")
            den = float(np.sum(fit.w * x * x))
            if den <= 0:
                continue
            a = max(0.0, float(np.sum(fit.w * fit.D * x)) / den)
            err = fit.delta(a * x)
            if best is None or err < best[0]:
                best = (err, t, s, a, a * x)
    if best is None or best[3] <= 0:
        return []
    err, t, s, a, change = best
    text = (f"bloom added after rendering: what exceeds {_num(t)} blurred over about {_num(s)} pixels and added back "
            f"at {a:.2g} times its value (a glare or bloom effect)")
    return [Candidate("bloom", "bloom", text, err, 3, value={"threshold": t, "sigma": s, "strength": a},
                      change=change)]


bloom.name = "bloom"
