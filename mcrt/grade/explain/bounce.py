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

A program that draws its directions one way and weighs them for another
gets a mistake's shape times a constant: cosine-distributed directions
weighted with the uniform hemisphere's pdf are twice the cosine applied
twice, uniform ones weighted with the whole sphere's pdf twice the right
bounce. At the first hit, where the light
that bounces on is linear in the bounce's weight, mcrt renders it once
more with the bounce carrying nothing (``zero``, :math:`Z = B_z - B_0`, so
the light that bounces on is :math:`-Z`), and mistake m's shape scaled by k
is the change :math:`k C_m - (k - 1) Z`, with :math:`C_m = B_m - B_0`
(:data:`SCALED`: the pairs programs produce, one parameter for the choice).
At every hit the light of a path of j bounces goes as :math:`k^j`; that is
the constant factors of :mod:`.path_weight`, or a render of its own.
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


#: (mistake's shape, factor k, words) of a bounce drawn one way and weighted for another at the first hit (the module
#: docstring); "cosine" is the right shape, its light only scaled. The other constants of :mod:`.path_weight` (1/2,
#: pi, 1/pi) are not among them: at the first hit alone they fit a halved weight at every hit as well as its own
#: render does (a uniform sphere's bounce at every hit was claimed as 1/pi at the first), and their programs are
#: that family's.
SCALED = (
    ("cosine", 2.0, "the diffuse bounce weighted twice what it should be, its directions right (uniform directions "
                    "on the hemisphere weighted with the whole sphere's pdf 1/(4 pi): 4 albedo cos for 2 albedo cos)"),
    ("cosine_squared", 2.0, "the diffuse bounce drawn cosine-weighted and weighted with the uniform hemisphere's pdf "
                            "1/(2 pi) (f cos / pdf = 2 albedo cos for albedo): the light that bounces a third too "
                            "bright on average, most of it from near the normal"),
)


def _prepare(a, scene, render) -> list[tuple[tuple[str, str], np.ndarray]]:
    """((mistake, where), its render minus the basis's) for every mistake and place, and the bounce carrying nothing
    at the first hit (the module docstring)."""
    return rendered_changes(a, scene, render, [((how, at), {"bounce": how, "bounce_at": at})
                                               for how in BOUNCES if how not in ("cosine", "zero") for at in BOUNCE_AT]
                            + [(("zero", "first"), {"bounce": "zero", "bounce_at": "first"})])


def bounce(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The mistaken bounce whose render fits best, and the best mistake's shape scaled at the first hit (the module
    docstring)."""
    changes = dict(inputs.basis.extra.get(bounce.name) or ())
    best = best_change(fit, [(k, c) for k, c in changes.items() if k[0] != "zero"])
    if best is None:
        return []
    err, (how, at), change = best
    out = [Candidate("bounce", "diffuse bounce drawn wrongly", f"{WORDS[how]}, {AT_WORDS[at]}", err, 0,
                     value={"bounce": how, "at": at}, change=change, gain=True)]
    z = changes.get(("zero", "first"))
    if z is not None:
        z = z.astype(np.float64)
        scaled = [((how, k, words), k * changes[(how, "first")].astype(np.float64) - (k - 1.0) * z if how != "cosine"
                   else (1.0 - k) * z) for how, k, words in SCALED]
        err, (how, k, words), change = best_change(fit, scaled)
        out.append(Candidate("bounce", "diffuse bounce weighted for another", f"{words}, {AT_WORDS['first']}", err, 1,
                             value={"bounce": how, "factor": round(float(k), 6), "at": "first"}, change=change,
                             gain=True))
    return out


bounce.name, bounce.prepare = "bounce", _prepare
