r"""A smooth fall-off across the image: a vignette, a weight per pixel, a camera model that weights rays.

Two candidates: :math:`R\,(1 + \sum_j \beta_j \phi_j)` with the five
monomials :math:`\phi` of degree 1 and 2 in the pixel's position (x right,
y up, in [-1, 1]), fitted by weighted least squares and worded by the
factor at the edges and corners relative to the centre; and
:math:`R \cos^k\theta` with :math:`\theta` the angle between a pixel's
ray and the view axis, k scanned in quarters from -4 to 4 (a pinhole
camera that weights its rays by a power of their cosine).
"""

from __future__ import annotations

import math

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.grade.feedback import num as _num


def _coords(h: int, w: int):
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    return (xx + 0.5) / w * 2 - 1, 1 - (yy + 0.5) / h * 2  # x right, y up, in [-1, 1]


def falloff(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """A multiplicative quadratic field (weighted least squares), and cos^k of the ray's angle (k scanned)."""
    h, w = fit.R.shape[:2]
    x, y = _coords(h, w)
    cols = [x, y, x * x, x * y, y * y]
    A = np.stack([np.where(fit.ok, fit.R * c[..., None], 0.0).ravel() for c in cols], axis=1)
    sw = np.sqrt(np.where(fit.ok, fit.w, 0.0)).ravel()
    beta, *_ = np.linalg.lstsq(A * sw[:, None], fit.D.ravel() * sw, rcond=None)
    g = 1.0 + sum(b * c for b, c in zip(beta, cols))
    change = fit.R * (g[..., None] - 1.0)
    edges = {"left": g[:, 0].mean(), "right": g[:, -1].mean(), "top": g[0].mean(), "bottom": g[-1].mean(),
             "corners": float(np.mean([g[0, 0], g[0, -1], g[-1, 0], g[-1, -1]]))}
    words = ", ".join(f"{100 * v:.0f} % at the {k}" for k, v in edges.items())  # the centre's factor is 1
    out = [Candidate("falloff", "smooth fall-off", "the brightness changing smoothly across the image, relative to its centre: "
                      f"{words} (a vignette, a weight per pixel, a light's fall-off)", fit.delta(change), 5,
                      value={k: float(v) for k, v in edges.items()}, change=change)]
    basis = getattr(inputs, "basis", None)
    fov = getattr(basis, "fov_deg", 90.0)
    t = math.tan(math.radians(fov) / 2)
    cos = 1.0 / np.sqrt(1.0 + (x * t) ** 2 + (y * t * h / w) ** 2)
    ks = np.arange(-4.0, 4.01, 0.25)
    errs = [fit.delta(fit.R * (cos[..., None] ** k - 1.0)) for k in ks]
    i = int(np.argmin(errs))
    k = float(ks[i])
    how = (f"multiplied by cos^{_num(k)} of the angle between its ray and the view axis" if k > 0 else
           f"divided by cos^{_num(-k)} of the angle between its ray and the view axis")
    out.append(Candidate("falloff", "cosine weight", f"each pixel {how} (a camera model that weights rays)",
                          errs[i], 1, value={"cos_power": k}, change=fit.R * (cos[..., None] ** k - 1.0)))
    return out


falloff.name = "falloff"
