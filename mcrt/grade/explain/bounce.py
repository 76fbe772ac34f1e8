r"""The diffuse bounce drawn or weighted wrongly: the light that bounces off, the light sampled at each hit right.

A student's tracer draws the direction a path goes on in from a diffuse hit
and weighs it by f cos / pdf. Getting either wrong (a direction on the whole
sphere weighted as the hemisphere's, the cosine applied twice, a direction
left in the local frame, the azimuth pi u for 2 pi u, the disk's radius u
for sqrt(u), the albedo left out of the throughput, the weight times the pdf
for over it, the albedo's mean for the albedo) changes only the light
that bounces, by a factor that depends on the direction
(:func:`mcrt.bsdf.mistaken_bounce` gives each one's expectation), so no
constant factor (:mod:`.path_weight`) and no depth cut reproduces it.

mcrt renders each mistake of :data:`mcrt.options.BOUNCES` with the trick
``bounce``, at every diffuse hit and at the first hit of a camera path only
(a mistake in a branch for the first bounce, or in the code of a tracer
that samples one bounce by hand), at the basis's spp and seed, so that the
render minus the basis's shares its random numbers: the model image is
:math:`R + (B_m - B_0)`. No free parameter: each mistake is a program's, and
the three half-circle azimuths are the three tangent frames students build.
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.grade.explain.tricks import best_change, rendered_changes
from mcrt.options import BOUNCE_AT, BOUNCES

#: Each mistake in the student's terms (what the code does, then what it does to the light).
WORDS = {
    "uniform_sphere": "the diffuse bounce's direction drawn uniformly on the whole sphere but weighted with the "
                      "hemisphere's pdf 1/(2 pi): the half below the surface is lost, and the light that bounces is "
                      "half what it should be",
    "cosine_squared": "the diffuse bounce weighted by the albedo times the cosine (the cosine applied in f cos / pdf "
                      "and again after it): the light that bounces about two-thirds of what it should be, and less "
                      "from grazing directions",
    "local_frame": "the diffuse bounce's direction drawn about +z and never turned to the surface's normal (left in "
                   "the local frame): right on the floor, half of it into the walls, all of it into the ceiling",
    "half_azimuth_duff": "the diffuse bounce's azimuth drawn as pi u for 2 pi u: only half of the hemisphere sampled "
                         "(the side of the second tangent of Duff et al.'s frame, as in pbrt and Mitsuba), weighted "
                         "as the whole",
    "half_azimuth_axis": "the diffuse bounce's azimuth drawn as pi u for 2 pi u: only half of the hemisphere sampled "
                         "(the side of the second tangent n x (n x a) of a frame built with a = (1, 0, 0)), weighted "
                         "as the whole",
    "half_azimuth_cross": "the diffuse bounce's azimuth drawn as pi u for 2 pi u: only half of the hemisphere "
                          "sampled (the side of the second tangent n x a of a frame built with a = (1, 0, 0)), "
                          "weighted as the whole",
    "disk_radius_u": "the cosine-weighted bounce drawn from a disk of radius u for sqrt(u) (too many directions near "
                     "the normal), weighted as cosine-distributed",
    "no_albedo": "the surface's albedo left out of the path's throughput at the bounce (beta *= albedo missing), "
                 "the light sample there right",
    "times_pdf": "the diffuse bounce's throughput multiplied by the pdf, beta *= f cos pdf for f cos / pdf (albedo "
                 "cos^2 / pi^2 a bounce): the light that bounces nearly gone, the same image as paths that end at "
                 "the first diffuse surface they meet, after its light sample (a throughput that becomes 0 there: "
                 "kept in an integer array, or reset at the bounce)",
    "albedo_mean": "the diffuse bounce weighted by the mean of the albedo's channels (a scalar, as kept for "
                   "Russian roulette) for the albedo: the light that bounces grey, the surface's own colour lost from "
                   "it",
}
#: Where the mistake applies, in the student's terms.
AT_WORDS = {"every": "at every diffuse surface a path meets",
            "first": "at the first surface a camera ray meets only (a branch for the first bounce)"}


def _prepare(a, scene, render) -> list[tuple[tuple[str, str], np.ndarray]]:
    """((mistake, where), its render minus the basis's) for every mistake and place (the module docstring)."""
    return rendered_changes(a, scene, render, [((how, at), {"bounce": how, "bounce_at": at})
                                               for how in BOUNCES if how != "cosine" for at in BOUNCE_AT])


def bounce(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The mistaken bounce whose render fits best (the module docstring)."""
    best = best_change(fit, inputs.basis.extra.get(bounce.name))
    if best is None:
        return []
    err, (how, at), change = best
    return [Candidate("bounce", "diffuse bounce drawn wrongly", f"{WORDS[how]}, {AT_WORDS[at]}", err, 0,
                      value={"bounce": how, "at": at}, change=change, gain=True)]


bounce.name, bounce.prepare = "bounce", _prepare
