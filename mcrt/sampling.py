"""Warps from [0, 1)^2 to directions and points, with their densities.

Each warp is written over plain arithmetic on Dr.Jit arrays; the same
formulas run on NumPy arrays, which the chi-square tests use.

- Cosine-weighted hemisphere (Malley's method): a uniform point on the unit
  disk, r = sqrt(u1), phi = 2 pi u2, lifted to the hemisphere,
  w = (r cos phi, r sin phi, sqrt(1 - r^2)); pdf_solid_angle = cos(theta) / pi.
- Cosine-weighted about a normal n without a tangent frame: n plus a
  uniform point s on the unit sphere, normalised. The point n + s is uniform
  on the unit sphere centred at n, which passes through the origin; seen from
  the origin, that sphere's area element dA at angle theta from n lies at
  distance 2 cos(theta) and is tilted by theta, so dw = dA cos(theta) /
  (4 cos^2(theta)) and, with pdf_area = 1 / (4 pi), pdf_solid_angle =
  cos(theta) / pi: the cosine density, for three multiplies instead of a frame.
- Uniform hemisphere: cos(theta) = u1; pdf_solid_angle = 1 / (2 pi).
- Uniform point in the unit ball: radius u1^(1/3), a uniform direction.

- Uniform in the solid angle of a rectangle (a spherical rectangle, Urena,
  Fajardo and King 2013): :func:`square_to_spherical_rectangle`;
  pdf_solid_angle = 1 / Omega.

Multiple importance sampling combines two strategies by the balance
heuristic (:func:`balance_heuristic`). Points on the light and their
densities are in :mod:`mcrt.light`; the BSDFs that use these warps in
:mod:`mcrt.bsdf`.
"""

from __future__ import annotations

import math

import drjit as dr

from mcrt.minmax import clamp, fmax, sqrt0

INV_PI = 1.0 / math.pi


def square_to_cosine_hemisphere(u1, u2):
    """Local (x, y, z) of a cosine-distributed direction about +z."""
    r = dr.sqrt(u1)
    phi = 2.0 * math.pi * u2
    s, c = dr.sincos(phi)
    return r * c, r * s, sqrt0(1.0 - u1)


def square_to_uniform_sphere(u1, u2):
    """A uniform point on the unit sphere: z = 1 - 2 u1, phi = 2 pi u2 (Archimedes)."""
    z = 1.0 - 2.0 * u1
    r = 2.0 * sqrt0(u1 - u1 * u1)  # sqrt(1 - z^2) without cancellation near the poles
    s, c = dr.sincos(2.0 * math.pi * u2)
    return r * c, r * s, z


def cosine_about_normal(u1, u2, n):
    """A cosine-distributed direction about the unit normal n: normalize(n + uniform point on the sphere).

    ``n`` is a 3-sequence of arrays. The sum vanishes only for the sphere
    point -n (probability zero; float32 rounding can still reach it), which
    returns n itself.
    """
    sx, sy, sz = square_to_uniform_sphere(u1, u2)
    w = (n[0] + sx, n[1] + sy, n[2] + sz)
    norm2 = dr.fma(w[0], w[0], dr.fma(w[1], w[1], w[2] * w[2]))
    inv = dr.rsqrt(norm2)
    degenerate = norm2 < 1e-12
    return tuple(dr.select(degenerate, n[k], w[k] * inv) for k in range(3))


def cosine_hemisphere_pdf(cos_theta):
    """pdf_solid_angle of the cosine warp: cos(theta) / pi (0 below the horizon)."""
    return fmax(cos_theta, 0.0) * INV_PI


def square_to_uniform_hemisphere(u1, u2):
    """Local (x, y, z) of a uniformly distributed direction about +z."""
    z = u1
    r = sqrt0(1.0 - z * z)
    s, c = dr.sincos(2.0 * math.pi * u2)
    return r * c, r * s, z


def square_to_uniform_ball(u1, u2, u3):
    """A uniform point inside the unit ball: radius u1^(1/3), uniform direction."""
    z = 1.0 - 2.0 * u2
    rr = sqrt0(1.0 - z * z)
    s, c = dr.sincos(2.0 * math.pi * u3)
    r = dr.cbrt(u1)
    return r * rr * c, r * rr * s, r * z


def coordinate_frame(nx, ny, nz):
    """Two unit tangents (s, t) with (s, t, n) right-handed and orthonormal.

    Branchless construction of Duff et al. (JCGT 2017), stable for every unit n.
    """
    sign = dr.select(nz >= 0, 1.0, -1.0)
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    s = (1.0 + sign * nx * nx * a, sign * b, -sign * nx)
    t = (b, sign + ny * ny * a, -ny)
    return s, t


def to_world(local, s, t, n):
    """local[0] s + local[1] t + local[2] n, component-wise tuples."""
    return tuple(local[0] * s[k] + local[1] * t[k] + local[2] * n[k] for k in range(3))


def balance_heuristic(n_a, pdf_a, n_b, pdf_b):
    """Veach's balance heuristic: the weight of a sample of strategy a, n_a p_a / (n_a p_a + n_b p_b).

    ``n_a`` and ``n_b`` are the strategies' sample counts, ``pdf_a`` and
    ``pdf_b`` their densities at the sample, in the same measure (solid angle
    here). The weights of the two strategies add up to one wherever either
    density is positive.
    """
    a = n_a * pdf_a
    return a / dr.fma(n_b, pdf_b, a)


def square_to_spherical_rectangle(u1, u2, x0, y0, z0, x1, y1):
    r"""A direction uniform in the solid angle of a rectangle, as its point on the rectangle, and that solid angle.

    The rectangle is [x0, x1] x [y0, y1] in the plane z = z0 of a frame
    whose origin is the receiver (x0 < x1, y0 < y1, z0 < 0: a receiver
    above the plane is mirrored below it first). After Urena, Fajardo and
    King (2013): the planes through the origin and the four edges have unit
    normals n_i with z components

        n0z = -y0 / sqrt(z0^2 + y0^2),  n1z = x1 / sqrt(z0^2 + x1^2),
        n2z = y1 / sqrt(z0^2 + y1^2),   n3z = -x0 / sqrt(z0^2 + x0^2),

    and inner angles g_i = acos(-n_iz n_(i+1)z); the solid angle is
    Omega = g0 + g1 + g2 + g3 - 2 pi (Girard). u1 picks the angle
    a = u1 Omega - g2 - g3 that cuts off the fraction u1 of Omega, whose
    edge plane meets the rectangle at x = xu; along that line, u2 is
    uniform in the sine of the elevation, which is uniform in solid angle:

        xu = -cu z0 / sqrt(1 - cu^2),  cu = sign(fu) / sqrt(fu^2 + n0z^2),  fu = (cos(a) n0z - n2z) / sin(a),
        yv = hv d / sqrt(1 - hv^2),    hv = h0 + u2 (h1 - h0),  h_k = y_k / sqrt(d^2 + y_k^2),  d^2 = xu^2 + z0^2.

    Returns (xu, yv, Omega); the point's density on the rectangle is
    cos(theta_y) / (dist^2 Omega).
    """
    z0 = -dr.abs(z0)
    zz = z0 * z0
    n0z = -y0 * dr.rsqrt(zz + y0 * y0)
    n1z = x1 * dr.rsqrt(zz + x1 * x1)
    n2z = y1 * dr.rsqrt(zz + y1 * y1)
    n3z = -x0 * dr.rsqrt(zz + x0 * x0)
    g0 = dr.acos(clamp(-n0z * n1z, -1.0, 1.0))
    g1 = dr.acos(clamp(-n1z * n2z, -1.0, 1.0))
    g2 = dr.acos(clamp(-n2z * n3z, -1.0, 1.0))
    g3 = dr.acos(clamp(-n3z * n0z, -1.0, 1.0))
    omega = g0 + g1 + g2 + g3 - 2.0 * math.pi
    a = u1 * omega - (g2 + g3)
    sin_a, cos_a = dr.sincos(a)
    fu = (cos_a * n0z - n2z) / sin_a
    cu = clamp(dr.copysign(dr.rsqrt(fu * fu + n0z * n0z), fu), -1.0 + 2.0**-23, 1.0 - 2.0**-23)
    xu = clamp(-(cu * z0) * dr.rsqrt(1.0 - cu * cu), x0, x1)
    d2 = xu * xu + zz
    h0 = y0 * dr.rsqrt(d2 + y0 * y0)
    h1 = y1 * dr.rsqrt(d2 + y1 * y1)
    hv = dr.fma(u2, h1 - h0, h0)
    hv2 = hv * hv
    yv = dr.select(hv2 < 1.0 - 1e-6, hv * dr.sqrt(d2) * dr.rsqrt(fmax(1.0 - hv2, 1e-12)), y1)
    return xu, clamp(yv, y0, y1), omega
