r"""The two materials of the room: Lambertian and perfect mirror.

Lambertian, albedo rho:

    f(x, wi, wo) = rho / pi,

sampled by the cosine warp (:func:`mcrt.sampling.cosine_about_normal`),
pdf = cos(theta) / pi, so the path weight f cos / pdf is rho and the BRDF's
1/pi appears only where the BRDF is evaluated: in next-event estimation.

Perfect mirror, reflectance R: the reflected direction wr = d - 2 (d.n) n
with weight R (a delta distribution: f cos / pdf = R), never light-sampled.

Each function takes the estimator's named option that a catalogued bug
changes (:mod:`mcrt.mutants`); the defaults are the correct physics.
"""

from __future__ import annotations

import math

import drjit as dr

from mcrt.options import LAMBERTIAN_SAMPLERS
from mcrt.sampling import (
    INV_PI,
    coordinate_frame,
    cosine_about_normal,
    square_to_uniform_ball,
    square_to_uniform_hemisphere,
    to_world,
)



def lambertian_f(albedo, *, inv_pi: bool = True):
    """The Lambertian BRDF rho / pi (rho alone with ``inv_pi=False``, the catalogued bug)."""
    return albedo * INV_PI if inv_pi else albedo


def lambertian_weight(albedo, *, inv_pi: bool = True):
    """f cos / pdf of a cosine-distributed direction: rho (pi rho when the BRDF lacks its 1/pi)."""
    return albedo if inv_pi else albedo * math.pi


def sample_lambertian(Vector3f, n, u1, u2, sampler, *, method: str = "cosine"):
    """A direction about the unit normal ``n`` from (u1, u2), weighted as cosine-distributed.

    ``method`` 'cosine' draws it with pdf cos/pi (:func:`mcrt.sampling.cosine_hemisphere_pdf`);
    'uniform_as_cosine' draws it uniformly (pdf 1/(2 pi)) and
    'ball_plus_normal' normalises n plus a point inside the unit ball
    (a third number from ``sampler``): both are then weighted as if their pdf
    were cos/pi, the catalogued mistakes.
    """
    if method == "cosine":
        return Vector3f(*cosine_about_normal(u1, u2, (n.x, n.y, n.z)))
    if method == "ball_plus_normal":
        b = square_to_uniform_ball(u1, u2, sampler.next_1d())
        return dr.normalize(Vector3f(*b) + n)
    if method == "uniform_as_cosine":
        local = square_to_uniform_hemisphere(u1, u2)
        s, t = coordinate_frame(n.x, n.y, n.z)
        return Vector3f(*to_world(local, s, t, (n.x, n.y, n.z)))
    raise ValueError(f"unknown Lambertian sampler {method!r} (one of {', '.join(LAMBERTIAN_SAMPLERS)})")


def reflect(d, n, *, sign: float = 1.0):
    """The mirror direction d - 2 (d.n) n of the unit direction d about the unit normal n.

    ``sign=-1`` returns its negation, the catalogued wrong-sign bug.
    """
    r = dr.fma(-2.0 * dr.dot(d, n), n, d)
    return r if sign > 0 else -r
