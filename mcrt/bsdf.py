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
:func:`mistaken_bounce` draws the Lambertian bounce and :func:`mistaken_mirror`
reflects as students' tracers get them wrong (:data:`mcrt.options.BOUNCES`,
:data:`mcrt.options.MIRRORS`), for the grader's explanation.
"""

from __future__ import annotations

import math

import drjit as dr

from mcrt.minmax import fmax, fmin, sqrt0
from mcrt.options import BOUNCES, LAMBERTIAN_SAMPLERS, MIRRORS
from mcrt.sampling import (
    INV_PI,
    coordinate_frame,
    cosine_about_normal,
    square_to_cosine_hemisphere,
    square_to_uniform_ball,
    square_to_uniform_hemisphere,
    square_to_uniform_sphere,
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


def mistaken_bounce(Vector3f, n, u1, u2, weight, how: str):
    r"""A Lambertian bounce about the unit normal ``n`` drawn or weighted as ``how`` (:data:`mcrt.options.BOUNCES`).

    ``weight`` is the correct bounce's f cos / pdf (the albedo rho). Each
    mistake's expectation, for incident radiance L, against the correct
    :math:`(\rho/\pi) \int_H L \cos\theta \, d\omega`:

    * 'uniform_sphere': uniform on the whole sphere, weighted with the
      hemisphere's pdf 1/(2 pi) (2 rho cos); half the directions lie below
      the surface: :math:`(\rho / 2\pi) \int_H L \cos\theta`, half the truth;
    * 'cosine_squared': cosine-distributed, weighted rho cos (the cosine
      applied in the weight and again): :math:`(\rho/\pi) \int_H L \cos^2\theta`;
    * 'local_frame': cosine-distributed about +z, never turned to n,
      weighted rho; those below the surface lost;
    * 'half_azimuth_*': the azimuth pi u for 2 pi u, so only the half of the
      hemisphere on the frame's second tangent's side, weighted rho:
      :math:`(2\rho/\pi) \int_{H/2} L \cos\theta`. The half depends on the frame:
      '_duff' mcrt's (Duff et al.), '_axis' the tangent n x a and second
      tangent n x (n x a), '_cross' the second tangent n x a itself, with
      a = (1, 0, 0), or (0, 1, 0) where n is within 0.9 of the x axis;
    * 'disk_radius_u': the disk radius u1 for sqrt(u1) (sin theta uniform,
      pdf cos / (2 pi sin)), weighted rho:
      :math:`(\rho / 2\pi) \int_H L \cos\theta / \sin\theta`;
    * 'no_albedo': cosine-distributed, weight 1 (rho left out of the throughput);
    * 'times_pdf': cosine-distributed, weighted f cos pdf for f cos / pdf
      (rho cos^2 / pi^2): :math:`(\rho/\pi^3) \int_H L \cos^3\theta`;
    * 'albedo_mean': cosine-distributed, weighted by the mean of rho's
      channels (a scalar kept for Russian roulette) for rho: the light that
      bounces grey-weighted, the surface's colour lost from it.
    * 'zero': cosine-distributed, weighted 0: the path carries nothing on
      from the vertex (its light sample counted, as a throughput reset to 0
      there does).

    A direction below the surface goes on mirrored into the room with weight
    0: it carries nothing, as a ray through the wall would, and stays inside
    the closed room.
    """
    if how not in BOUNCES or how == "cosine":
        raise ValueError(f"no bounce mistake {how!r} (one of {', '.join(BOUNCES[1:])})")
    nn = (n.x, n.y, n.z)
    if how == "uniform_sphere":
        d = Vector3f(*square_to_uniform_sphere(u1, u2))
        w = weight * (2.0 * fmax(dr.dot(d, n), 0.0))
    elif how == "local_frame":
        d = Vector3f(*square_to_cosine_hemisphere(u1, u2))
        w = dr.select(dr.dot(d, n) > 0.0, weight, 0.0)
    elif how == "disk_radius_u":
        s, t = coordinate_frame(*nn)
        sn, cs = dr.sincos(2.0 * math.pi * u2)
        d = Vector3f(*to_world((u1 * cs, u1 * sn, sqrt0(1.0 - u1 * u1)), s, t, nn))
        w = weight
    else:
        d = Vector3f(*cosine_about_normal(u1, u2, nn))
        cos = dr.dot(d, n)
        w = (weight * cos if how == "cosine_squared" else type(weight)(1.0) if how == "no_albedo"
             else weight * dr.square(cos / math.pi) if how == "times_pdf"
             else type(weight)((weight.x + weight.y + weight.z) / 3.0) if how == "albedo_mean"
             else weight * 0.0 if how == "zero" else weight)
        if how.startswith("half_azimuth"):
            b = _second_tangent(Vector3f, n, how)
            d = dr.fma(-2.0 * fmin(dr.dot(d, b), 0.0), b, d)  # the other half mirrored onto this one
    below = dr.dot(d, n) <= 0.0
    return dr.select(below, dr.fma(-2.0 * dr.dot(d, n), n, d), d), dr.select(below, 0.0, w)


def _second_tangent(Vector3f, n, how: str):
    """The unit tangent whose side a half-circle azimuth keeps (:func:`mistaken_bounce`)."""
    if how == "half_azimuth_duff":
        return Vector3f(*coordinate_frame(n.x, n.y, n.z)[1])
    a = dr.select(dr.abs(n.x) < 0.9, Vector3f(1.0, 0.0, 0.0), Vector3f(0.0, 1.0, 0.0))
    t = dr.normalize(dr.cross(n, a))
    return t if how == "half_azimuth_cross" else dr.cross(n, t)


def mistaken_mirror(Vector3f, d, n, p, how: str, *, normal_length: float = 1.0):
    r"""The direction a mirror at p with unit normal ``n`` sends the unit direction ``d`` on, and the factor on its
    weight, as ``how`` (:data:`mcrt.options.MIRRORS`) gets it wrong:

    * 'without_2': d - (d.n) n, its 2 missing (normalised): the ray goes on
      along the surface;
    * 'normal_unnormalised': reflected about a normal of length
      ``normal_length`` (a sphere's p - c never divided by its radius):
      d - 2 l^2 (d.n) n, normalised;
    * 'normal_from_origin': reflected about p normalised (a sphere's
      centre never subtracted);
    * 'cosine_weighted': reflected right, weighted by |d.n| as a diffuse
      bounce;
    * 'camera_only': reflected right, weight 0 (the caller applies it after
      a camera ray's first hit only: a path that meets the mirror later ends);
    * 'backwards': -d, every ray sent back the way it came (``reflect``
      left as a placeholder that returns ``-d``).
    """
    if how not in MIRRORS or how == "reflect":
        raise ValueError(f"no mirror mistake {how!r} (one of {', '.join(MIRRORS[1:])})")
    if how == "backwards":
        return -d, 1.0
    c = dr.dot(d, n)
    if how == "without_2":
        return dr.normalize(dr.fma(-c, n, d)), 1.0
    if how == "normal_unnormalised":
        return dr.normalize(dr.fma(-2.0 * normal_length**2 * c, n, d)), 1.0
    if how == "normal_from_origin":
        m = dr.normalize(p)
        return dr.fma(-2.0 * dr.dot(d, m), m, d), 1.0
    r = dr.fma(-2.0 * c, n, d)
    return r, (dr.abs(c) if how == "cosine_weighted" else 0.0)


def reflect(d, n, *, sign: float = 1.0):
    """The mirror direction d - 2 (d.n) n of the unit direction d about the unit normal n.

    ``sign=-1`` returns its negation, the catalogued wrong-sign bug.
    """
    r = dr.fma(-2.0 * dr.dot(d, n), n, d)
    return r if sign > 0 else -r
