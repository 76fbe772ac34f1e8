"""The pinhole camera: how a pixel sample becomes a primary ray (scene.md mapping).

For a W x H image, pixel (i, j) with jitter (u, v) in [0, 1)^2 sends a ray from
the eye through the image-plane point one unit in front of it,

    d = forward + s_x t_x right + s_y t_y up,    s_x = 2 (i + u) / W - 1,  s_y = 1 - 2 (j + v) / H,

normalised, with t_x = tan(fov_x / 2), t_y = t_x H / W and right = forward x up.
Column 0 is on the left, row 0 at the top. For the canonical cameras the plane
is x = 0 and the point (0, 1 - 2 (i + u) / W, 1 - 2 (j + v) / H).

:meth:`Pinhole.direction` is the one implementation: the tracer's kernel
calls it on Dr.Jit arrays (through :meth:`Pinhole.pixel_position` and
:meth:`Pinhole.ray`: pixel index to column and row, then to the ray), and the
same code runs on NumPy arrays for the closed-form images and the Mitsuba
cross-check. Where in its pixel a sample lands, the jitter (u, v), is the
tracer's to draw (:func:`mcrt.tracer.pixel_jitter`).
"""

from __future__ import annotations

import math
import sys

import drjit as dr
import numpy as np

from mcrt.scene import Camera


def _fma(a, b, c):
    """a b + c: one instruction on Dr.Jit arrays, plain arithmetic on NumPy arrays and floats."""
    return dr.fma(a, b, c) if dr.is_array_v(a) else a * b + c


class Pinhole:
    """The pixel-to-ray mapping of one camera at one resolution.

    ``jitter=False`` sends every sample through its pixel's centre (the
    catalogued no-jitter bug).
    """

    def __init__(self, camera: Camera, width: int, height: int, *, jitter: bool = True):
        right, up, forward = camera.frame()
        tx = math.tan(math.radians(camera.fov_x_deg) / 2)
        ty = tx * height / width
        self.width, self.height, self.jitter = width, height, jitter
        self.eye = tuple(float(x) for x in camera.eye)
        self.center = tuple(float(x) for x in forward)
        self.half_right = tuple(float(x) for x in tx * right)
        self.half_up = tuple(float(x) for x in ty * up)

    def film(self, col, row, u, v):
        """(s_x, s_y) in [-1, 1]^2 of pixel (col, row) at jitter (u, v): s_x to the right, s_y up."""
        if not self.jitter:
            u = v = 0.5
        return _fma(col + u, 2.0 / self.width, -1.0), _fma(row + v, -2.0 / self.height, 1.0)

    def pixel_position(self, pixel):
        """(column, row) as floats of pixel indices ``pixel`` (row-major: row * width + column), a Dr.Jit UInt32."""
        m = sys.modules[type(pixel).__module__]
        return m.Float(pixel % self.width), m.Float(pixel // self.width)

    def ray(self, col, row, u, v):
        """(origin, unit direction) of the primary rays through pixel (col, row) at jitter (u, v): Dr.Jit arrays."""
        return sys.modules[type(col).__module__].Array3f(*self.eye), self.direction(col, row, u, v)

    def direction(self, col, row, u, v):
        """Unit direction of the ray through pixel (col, row) at jitter (u, v).

        On Dr.Jit arrays an Array3f; on NumPy arrays an array (..., 3).
        """
        sx, sy = self.film(col, row, u, v)
        d = [_fma(sy, self.half_up[k], _fma(sx, self.half_right[k], self.center[k])) for k in range(3)]
        if dr.is_array_v(sx):
            return dr.normalize(sys.modules[type(sx).__module__].Array3f(*d))
        d = np.stack(np.broadcast_arrays(*d), axis=-1)
        return d / np.linalg.norm(d, axis=-1, keepdims=True)


def primary_directions(camera: Camera, width: int, height: int, i, j, u, v) -> np.ndarray:
    """Unit directions (..., 3) of the rays through pixel samples (i, j) + (u, v): NumPy arrays in and out."""
    asf = lambda a: np.asarray(a, dtype=float)  # noqa: E731
    return Pinhole(camera, width, height).direction(asf(i), asf(j), asf(u), asf(v))
