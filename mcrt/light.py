r"""The square area light: points sampled on it, their densities, its emission.

The light is a rectangle of half-sizes (h_x, h_y) centred at c in a plane
z = c_z, emitting the uniform radiance Le on the side its normal
n_y = (0, 0, n_z) points to and nothing behind.

Sampling a point uniformly on it from (u1, u2) in [0, 1)^2,

    y = c + ((2 u1 - 1) h_x, (2 u2 - 1) h_y, 0),    pdf_area(y) = 1 / A,  A = 4 h_x h_y,

and seen from a receiver x, at distance d = |y - x| along the unit
direction w = (y - x) / d, the same density in solid angle is

    pdf_solid_angle(w) = pdf_area(y) d^2 / cos(theta_y),    cos(theta_y) = -n_y . w

(:func:`solid_angle_pdf`). Next-event estimation weights a sample by
Le cos(theta_x) cos(theta_y) / (d^2 pdf_area) (:mod:`mcrt.estimator`).

Sampling it instead uniformly in the solid angle Omega(x) it subtends at x
(:meth:`RectangleLight.sample_solid_angle`, a spherical rectangle of
:func:`mcrt.sampling.square_to_spherical_rectangle`) gives the point the
area density pdf_area(y) = cos(theta_y) / (d^2 Omega(x)), which makes the
weight Le cos(theta_x) Omega(x): bounded near the light, where the area
sampling's 1 / d^2 is not.
"""

from __future__ import annotations

from dataclasses import dataclass

import drjit as dr
import numpy as np

from mcrt.sampling import square_to_spherical_rectangle
from mcrt.scene import Light, Scene


@dataclass
class LightSample:
    """A point sampled on a light, seen from a receiver x (every field an array over lanes).

    ``wi`` is the unit direction from x to the point, ``dist2`` the squared
    distance and ``inv_dist`` its inverse square root, ``cos_y`` the cosine
    between -wi and the light's emitting-side normal (positive where x sees
    the emitting side), ``radiance`` the radiance of the emitting side there
    (whichever side x is on) and ``pdf_area`` the density of the point in
    area measure.
    """

    wi: object
    dist2: object
    inv_dist: object
    cos_y: object
    radiance: object
    pdf_area: object


def solid_angle_pdf(pdf_area, dist2, cos_y):
    """The density in solid angle at the receiver of a point with area density ``pdf_area``: p_A d^2 / cos_y."""
    return pdf_area * dist2 / cos_y


class RectangleLight:
    """The scene's light as constants baked into the kernel of backend ``m``."""

    def __init__(self, light: Light, m):
        self.m = m
        self.center = tuple(float(x) for x in light.center)
        self.half = (light.size[0] / 2, light.size[1] / 2)
        self.normal_z = float(light.normal[2])
        self.radiance = tuple(float(x) for x in light.radiance)
        self.area = float(light.area)
        self.pdf_area = 1.0 / self.area  # uniform over the rectangle; a Python float, folded into the kernel

    def emitted(self):
        """Le of the emitting side, a constant Array3f."""
        return self.m.Array3f(*self.radiance)

    def cos_toward(self, d):
        """cos(theta_y) of a ray arriving along the unit direction d: -n_y . d (positive on the emitting side)."""
        return -d.z * self.normal_z

    def sample(self, x, u1, u2) -> LightSample:
        """A point uniform on the rectangle from (u1, u2), seen from the points x."""
        m = self.m
        cx, cy, cz = self.center
        hx, hy = self.half
        y = m.Array3f(dr.fma(u1, 2.0 * hx, cx - hx), dr.fma(u2, 2.0 * hy, cy - hy), cz)
        wi = y - x
        dist2 = dr.squared_norm(wi)
        inv_dist = dr.rsqrt(dist2)
        wi = wi * inv_dist
        return LightSample(wi, dist2, inv_dist, self.cos_toward(wi), self.emitted(), self.pdf_area)

    def sample_solid_angle(self, x, u1, u2) -> LightSample:
        """A point whose direction from x is uniform in the light's solid angle, with area density cos_y / (d^2 Omega)."""
        m = self.m
        cx, cy, cz = self.center
        hx, hy = self.half
        x0, y0 = (cx - hx) - x.x, (cy - hy) - x.y
        xu, yv, omega = square_to_spherical_rectangle(u1, u2, x0, y0, cz - x.z, x0 + 2.0 * hx, y0 + 2.0 * hy)
        wi = m.Array3f(xu, yv, cz - x.z)
        dist2 = dr.squared_norm(wi)
        inv_dist = dr.rsqrt(dist2)
        wi = wi * inv_dist
        cos_y = self.cos_toward(wi)
        return LightSample(wi, dist2, inv_dist, cos_y, self.emitted(), cos_y * dr.rcp(dist2 * omega))


def needs_mis(scene: Scene) -> bool:
    """Whether a surface comes closer to the light than the light's larger side.

    Light sampling by area has a weight ~ 1/d^2 that is unbounded where a
    lit surface meets the light (a light touching a wall, a light just above
    the floor); there the estimator switches on MIS with cosine sampling,
    which bounds it. Faces behind the light (the ceiling above a light that
    faces down) receive none of its light and do not count.
    """
    light = scene.light
    corners = light.corners()
    reach = max(light.size)
    for plane in scene.room.planes():
        n, h = plane[:3], plane[3]
        if abs(n[2]) > 0.5 and n[2] * light.normal[2] < 0:  # outward normal against the light normal
            continue  # the face behind the light
        if np.min(h - corners @ n) < reach:
            return True
    return False
