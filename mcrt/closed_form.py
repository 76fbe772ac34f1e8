"""Images known in closed form: checks of the tracer that need no reference.

- Furnace: in a closed room where every surface has albedo rho and emits Le,
  every pixel of a render with max depth D is

      L = Le (1 - rho^D) / (1 - rho)        (Le / (1 - rho) unbounded).

- Direct light on a plane: a uniformly emitting polygon of radiance Le gives a
  point x with unit normal n the irradiance (Lambert's formula)

      E(x) = (Le / 2) |sum_i beta_i n . u_i|,

  with r_i = v_i - x, beta_i the angle between r_i and r_{i+1} and
  u_i = r_i x r_{i+1} / |r_i x r_{i+1}|. A Lambertian point reflects
  (albedo / pi) E(x) towards the eye.
"""

from __future__ import annotations

import copy
import tomllib

import numpy as np

from mcrt.camera import primary_directions
from mcrt.scene import CANONICAL, Scene, scene_from_dict


def furnace_radiance(albedo: float, emission: float, max_depth: int) -> float:
    """Le (1 - rho^D) / (1 - rho); max_depth -1 is unbounded."""
    if max_depth == -1:
        return emission / (1.0 - albedo)
    return emission * (1.0 - albedo**max_depth) / (1.0 - albedo)


def polygon_irradiance(points: np.ndarray, normals: np.ndarray, polygon: np.ndarray, radiance: float) -> np.ndarray:
    """Irradiance at points (N, 3) with normals (N, 3) from a Lambertian polygon (M, 3) of uniform radiance."""
    total = np.zeros(len(points))
    for a, b in zip(polygon, np.roll(polygon, -1, axis=0)):
        ra, rb = a - points, b - points
        cross = np.cross(ra, rb)
        norm = np.linalg.norm(cross, axis=1)
        cosang = np.einsum("ij,ij->i", ra, rb) / (np.linalg.norm(ra, axis=1) * np.linalg.norm(rb, axis=1))
        beta = np.arccos(np.clip(cosang, -1.0, 1.0))
        total += beta * np.einsum("ij,ij->i", normals, cross) / np.where(norm > 0, norm, 1.0)
    return 0.5 * radiance * np.abs(total)


def _canonical_dict() -> dict:
    return tomllib.loads(CANONICAL.read_text())


def furnace_scene(albedo: float = 0.5, emission: float = 1.0, mirror: bool = False) -> Scene:
    """The canonical room with every surface of albedo rho emitting Le.

    The light keeps its place but shrinks to 1e-4 x 1e-4 with zero radiance,
    so its black surface removes a fraction ~1e-11 of the energy. The sphere
    is kept as a mirror only when ``mirror`` is set (a mirror bounce adds a
    segment but no emission, so only the unbounded furnace is unchanged).
    """
    d = _canonical_dict()
    a, e = [albedo] * 3, [emission] * 3
    for w in d["room"]["walls"]:
        w["albedo"], w["emission"] = a, e
    d["room"].update(floor_albedo=a, ceiling_albedo=a, floor_emission=e, ceiling_emission=e)
    objs = []
    for o in d["objects"]:
        if o["type"] == "tetrahedron":
            o["material"] = {"type": "lambertian", "albedo": a, "emission": e}
            objs.append(o)
        elif mirror:
            objs.append(o)
    d["objects"] = objs
    d["light"].update(size=[1e-4, 1e-4], radiance=[0.0, 0.0, 0.0])
    d["name"] = "furnace"
    return scene_from_dict(d, "furnace")


def lit_floor_scene(floor_albedo: float = 0.5) -> Scene:
    """The canonical room and light with no objects, every surface black but the floor."""
    d = copy.deepcopy(_canonical_dict())
    for w in d["room"]["walls"]:
        w["albedo"] = [0.0, 0.0, 0.0]
    d["room"].update(floor_albedo=[floor_albedo] * 3, ceiling_albedo=[0.0, 0.0, 0.0])
    d["objects"] = []
    d["name"] = "lit-floor"
    return scene_from_dict(d, "lit-floor")


def lit_floor_image(scene: Scene, camera: str, width: int, height: int, sub: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Expected image of :func:`lit_floor_scene` at max depth 2, and the mask of pure floor pixels.

    Each pixel is the mean of (albedo / pi) E(x) over a sub x sub grid of its
    footprint (midpoint rule; the integrand is smooth on the floor).
    """
    cam = scene.camera(camera)
    room = scene.room
    light = scene.light
    albedo = room.floor_albedo[0]
    jj, ii = np.mgrid[0:height, 0:width]
    offsets = (np.arange(sub) + 0.5) / sub
    acc = np.zeros((height, width))
    floor = np.ones((height, width), bool)
    poly_planes = room.planes()[:-2]
    eye = np.array(cam.eye)
    for u in offsets:
        for v in offsets:
            d = primary_directions(cam, width, height, ii, jj, np.full(ii.shape, u), np.full(ii.shape, v))
            with np.errstate(divide="ignore", invalid="ignore"):
                t = (room.floor_z - eye[2]) / d[..., 2]
            p = eye + t[..., None] * d
            inside = (t > 0) & np.all(p @ poly_planes[:, :3].T <= poly_planes[:, 3] + 1e-9, axis=-1)
            floor &= inside
            pts = p.reshape(-1, 3)
            e = polygon_irradiance(pts, np.tile([0.0, 0.0, 1.0], (len(pts), 1)), light.corners(), light.radiance[0])
            acc += np.where(inside, e.reshape(height, width), 0.0)
    return albedo / np.pi * acc / sub**2, floor
