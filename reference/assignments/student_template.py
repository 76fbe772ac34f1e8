"""Template of a code-mode hand-in for `mcrt grade --mode code` (see course2023_code.toml).

Implement the functions below (NumPy is available; nothing else is
guaranteed). Each one is called by the grader in a separate process with a
time and memory limit, in a sandbox: your module may read its own folder and
the Python installation, write only its current folder, and may not start
processes, open network connections or send signals. Return NumPy arrays (or
anything ``numpy.asarray`` turns into float64 of the stated shape).

The grader checks them statistically: a chi-square goodness-of-fit test of
your directions, a comparison of your intersections with a float64
reference, your direct-light estimates against Lambert's closed form, and
your whole render against the course's reference image with the same
noise-aware test as image mode. Randomness comes in as arguments (``u``,
``seed``), so your functions must be deterministic given them.
"""

import numpy as np


def sample_cosine_hemisphere(u1: np.ndarray, u2: np.ndarray) -> np.ndarray:
    """(N,) uniforms in [0, 1) -> (N, 3) unit directions about +z with pdf cos(theta) / pi."""
    raise NotImplementedError


def intersect_triangle(origins: np.ndarray, directions: np.ndarray, v0: np.ndarray, v1: np.ndarray,
                       v2: np.ndarray) -> np.ndarray:
    """(N, 3) ray origins and unit directions, (3,) vertices -> (N,) distance t > 0 to the triangle
    (hit from either side), or inf where the ray misses."""
    raise NotImplementedError


def estimate_direct(points: np.ndarray, normals: np.ndarray, light: dict, u: np.ndarray) -> np.ndarray:
    """One-sample estimates of the irradiance each point receives from the area light (no occluders).

    points, normals: (N, 3); light: {"corners": 4x3 list, counter-clockwise seen from the lit side,
    "normal": [x, y, z] (the side that emits), "radiance": Le}; u: (N, 2) uniforms.
    Returns (N,) values whose mean over many u is E = integral over the light of
    Le cos(theta_x) cos(theta_y) / d^2 dA.
    """
    raise NotImplementedError


def render(scene: dict, camera: str, width: int, height: int, spp: int, seed: int, max_depth: int) -> np.ndarray:
    """The scene file as a dict (reference/scenes/FORMAT.md) and a camera name -> (height, width, 3)
    linear radiance, row 0 at the top, ``spp`` samples per pixel, paths of at most ``max_depth`` segments.
    Different seeds must give independent renders."""
    raise NotImplementedError
