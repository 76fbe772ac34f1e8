r"""Lambert's cosine taken for the way to the eye too: a diffuse surface darker the more obliquely it is seen.

A Lambertian BRDF is :math:`\rho / \pi`, with no cosine of its own; a
tracer that multiplies in :math:`|n \cdot \omega_o|` as well (the cosine
written into the BRDF, or the rendering equation's cosine taken at both
ends) where a camera ray meets a diffuse surface scales that pixel's
radiance by it. The model image is :math:`R \, c` with :math:`c` each
pixel's mean of :math:`|n \cdot d|` over its rays that meet a Lambertian
first (1 for those meeting the mirror or the light), from the camera's first
hits that :mod:`mcrt.grade.explain.aov` prepares; no free parameter.
"""

from __future__ import annotations

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit


def view_cosine(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """R times the first hits' cosine to the eye on diffuse surfaces (the module docstring)."""
    from mcrt.grade.explain.aov import aov

    hits = inputs.basis.extra.get(aov.name) if inputs.basis is not None else None
    if hits is None or hits["view_cosine"].shape[:2] != fit.R.shape[:2]:
        return []
    M = fit.R * hits["view_cosine"]
    return [Candidate("view_cosine", "cosine to the eye", "each diffuse surface seen from the camera times the cosine "
                      "between its normal and the way to the eye (Lambert's cosine taken at the outgoing direction too, "
                      "or written into the BRDF): a surface darker the more obliquely it is seen, the light and the "
                      "mirror as they are", fit.model(M), 0, value="view_cosine", change=M - fit.R)]


view_cosine.name = "view_cosine"
