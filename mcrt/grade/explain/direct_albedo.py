r"""The first hit's light sample with its albedo left out, or applied twice.

Next-event estimation at the first surface a camera ray meets adds
:math:`f\,L_e\,G / p` with the Lambertian's :math:`f = \rho / \pi`. A tracer
whose BRDF there is :math:`1/\pi` (the albedo left out) makes that direct
light white; one that multiplies the throughput by :math:`\rho` before the
light sample and the BRDF's :math:`\rho` too applies the albedo twice. With
:math:`D` the direct light at the first hit (the basis's paths of depth 2
less those of depth 1, next-event estimation alone) and :math:`\rho` each
pixel's first-hit albedo (the camera's first hits that
:mod:`mcrt.grade.explain.aov` prepares), the model images are
:math:`R + D\,(\rho^{e - 1} - 1)` for :math:`e = 0` (left out) and
:math:`e = 2` (twice); the bounced light is right. No free parameter.
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit

#: e -> what it is in words (to follow "It looks like").
WORDS = {0: "the light sample at the first surface a camera ray meets without that surface's albedo (its BRDF 1/pi "
            "where albedo/pi belongs): the direct light there white on every surface, the bounced light right",
         2: "the first surface's albedo applied twice to its light sample (the throughput multiplied by the albedo "
            "before the light sample, whose BRDF has the albedo too): the direct light there darker and more "
            "saturated, the bounced light right"}


def first_hit_direct(fit: Fit, inputs: Inputs) -> tuple[np.ndarray, np.ndarray] | None:
    """(D, rho): the direct light at the first hit (the basis's paths of depth 2 less those of depth 1) and each
    pixel's first-hit albedo (the camera's first hits that :mod:`mcrt.grade.explain.aov` prepares), (H, W, 3) each;
    None where the basis has not both."""
    from mcrt.grade.explain.aov import aov

    b = inputs.basis
    hits = b.extra.get(aov.name) if b is not None else None
    depth = dict(b.nodes.get("depth", ())) if b is not None else {}
    if hits is None or 1 not in depth or 2 not in depth or hits["cover"].shape[:2] != fit.R.shape[:2]:
        return None
    return np.asarray(depth[2], np.float64) - np.asarray(depth[1], np.float64), hits["cover"] @ hits["albedo"]


def direct_albedo(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """R + D (rho^(e - 1) - 1) for e in 0 and 2 (the module docstring)."""
    got = first_hit_direct(fit, inputs)
    if got is None:
        return []
    D, rho = got
    diffuse = rho > 0.0
    out = []
    for e, words in WORDS.items():
        factor = np.where(diffuse, np.power(np.where(diffuse, rho, 1.0), e - 1.0) - 1.0, 0.0)
        change = D * factor
        out.append(Candidate("direct_albedo", f"light sample's albedo {e}", words, fit.delta(change), 0,
                             value={"albedo_power": e}, change=change))
    return out


direct_albedo.name = "direct_albedo"
