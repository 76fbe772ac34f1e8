"""The pinhole camera: pixel coordinates to primary rays (scene.md mapping).

For a W x H image, pixel (i, j) with jitter (u, v) in [0, 1)^2 goes through
the image-plane point one unit in front of the eye

    p = eye + forward + t_x (2 (i + u) / W - 1) right + t_y (1 - 2 (j + v) / H) up,

with t_x = tan(fov_x / 2) and t_y = t_x H / W, where right = forward x up.
Column 0 is on the left, row 0 at the top; every sample's ray starts at the
eye. For the canonical cameras this is the plane x = 0 with
y = 1 - 2 (i + u) / W and z = 1 - 2 (j + v) / H.

The functions are written over plain arithmetic so that they run on NumPy
arrays (tests, the Mitsuba cross-check) and on Dr.Jit arrays (the tracer).
"""

from __future__ import annotations

import math

import numpy as np

from mcrt.scene import Camera


def image_plane_basis(camera: Camera, width: int, height: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(center, half_right, half_up): the plane point is center + sx half_right + sy half_up, sx, sy in [-1, 1]."""
    right, up, forward = camera.frame()
    tx = math.tan(math.radians(camera.fov_x_deg) / 2)
    ty = tx * height / width
    return forward, tx * right, ty * up


def film_coordinates(width: int, height: int, i, j, u, v):
    """Pixel (i, j) plus jitter (u, v) to (sx, sy) in [-1, 1]^2, sx to the right, sy up."""
    return 2.0 * (i + u) / width - 1.0, 1.0 - 2.0 * (j + v) / height


def primary_directions(camera: Camera, width: int, height: int, i, j, u, v) -> np.ndarray:
    """Unit directions (..., 3) of the rays through pixel samples, NumPy arrays in and out."""
    center, hr, hu = image_plane_basis(camera, width, height)
    sx, sy = film_coordinates(width, height, np.asarray(i, float), np.asarray(j, float), np.asarray(u, float), np.asarray(v, float))
    d = center + sx[..., None] * hr + sy[..., None] * hu
    return d / np.linalg.norm(d, axis=-1, keepdims=True)
