"""Where float32 rendering of a scene stops being right, and a guard that says so.

mcrt traces in float32. Two things limit it; ``mcrt hardcases`` renders scenes
on both sides of each limit (reports/hardcases/index.md, "Float32 limits"):

**Distance from the origin against the smallest feature.** A ray leaving a
surface at p starts ``eps(p) = OFFSET_SCALE (|p|_inf + S)`` off it
(:mod:`mcrt.geometry`, ``OFFSET_SCALE = 2^-17``; S is the room's size). Moving
the scene a distance N from the origin makes that offset about
``2^-17 N``, while the scene's own lengths stay put. Once the offset exceeds
the smallest feature M (a sphere's radius, the light's side, the gap between
an object and the floor, the eye's distance to a wall), rays start on the
wrong side of it: shadows leak, a small mirror reflects from the wrong place.
The offset reaches M when

    N / M = 1 / OFFSET_SCALE = 2^17 = 131072,

which is :data:`LIMIT_RATIO`. Float32 rounding itself (2^-24 N) is 128 times
smaller than the offset and never decides first. The hard cases with a tiny
mirror sphere (reference/scenes/hard/sphere_tiny.toml) and a tiny light
(tiny_light.toml) are moved across this limit.

The offset also moves every shading point towards or away from the light by
up to eps, which biases direct light by about 2 eps / d at a distance d from
it. It grows with the distance from the origin even where every feature is
large, and a moved canonical room shows it (the report). So no feature
counts as larger than :data:`ROOM_FRACTION` of the room's size S: with
M <= S / 500 an accepted scene has eps <= 2^-17 * 2^17 M <= S / 500, a
bias of at most about 2 (S / 500) / d, 0.6 % for the canonical light's d of about 10, and the
canonical room's limit becomes N = 2^17 * 16 / 500 = 4.2e3.

**Squares of lengths.** Squared distances (1/d^2 of a light sample, |v|^2 of
a normalisation) must stay inside float32's normal range, 1.2e-38 to
3.4e38, that is lengths between about 1.1e-19 and 1.1e19 (three components);
beyond them a render returns NaN and inf or goes silently dark (the hard
cases scale the canonical scene past both ends). The guard refuses rooms
smaller than :data:`MIN_SIZE` and scenes reaching beyond :data:`MAX_EXTENT`.

Scaling a scene about the origin changes neither ratio, so a scene is
refused at every scale or at none (between the two range limits), as the
scale invariance of the expected image requires.

Features that are not counted, and why: the light's size and gaps when it
emits nothing (the furnace scenes shrink it to a black 1e-4 square); the
gap between the light's non-emitting side and the face behind it
(canonical: 0.01 below the ceiling), because a path ends at the light, so
no ray is ever spawned into that gap; gaps between two objects (not
measured; rare in this project's scenes); contacts (a gap within the scene
loader's touching tolerance, 1e-6 S), which are not gaps at all.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mcrt.scene import _TOUCH, Scene, Sphere, Tetrahedron

#: Largest accepted ratio of the scene's distance from the origin to its smallest feature: 1 / OFFSET_SCALE.
LIMIT_RATIO = 2.0**17
#: No feature counts as larger than this fraction of the room's size (bounds the direct-light bias).
ROOM_FRACTION = 1.0 / 500.0
#: Smallest room size whose squared lengths stay in float32's normal range (with a 1e3 margin for shorter ones).
MIN_SIZE = 1e-16
#: Largest coordinate magnitude plus room size whose squared lengths stay below float32's maximum.
MAX_EXTENT = 1e18


@dataclass(frozen=True)
class PrecisionReport:
    """The numbers :func:`check_precision` decides on.

    ``distance`` N is the largest absolute coordinate of any point of the
    scene (room corners, floor and ceiling, light, objects, eyes);
    ``feature`` M the smallest feature, named by ``feature_name``; ``ratio``
    is N / M; ``size`` S the room's size.
    """

    distance: float
    feature: float
    feature_name: str
    ratio: float
    size: float
    limit: float = LIMIT_RATIO

    @property
    def ok(self) -> bool:
        return self.ratio <= self.limit and MIN_SIZE <= self.size and self.distance + self.size <= MAX_EXTENT

    @property
    def offset_limit(self) -> float:
        """The largest distance from the origin at which this scene would still be accepted."""
        return self.limit * self.feature


def scene_distance(scene: Scene) -> float:
    """N: the largest absolute coordinate of any point of the scene (the L-infinity distance)."""
    room = scene.room
    pts = [np.array([*c, z]) for c in room.corners.values() for z in (room.floor_z, room.ceiling_z)]
    pts += list(scene.light.corners())
    for o in scene.objects:
        if isinstance(o, Sphere):
            pts += [np.asarray(o.center) + s * o.radius for s in (-1.0, 1.0)]
        else:
            pts += [np.asarray(v) for v in o.vertices]
    pts += [np.asarray(c.eye) for c in scene.cameras.values()]
    return float(max(np.max(np.abs(p)) for p in pts))


def scene_features(scene: Scene) -> list[tuple[str, float]]:
    """Every feature length that float32 rendering must resolve, with its name (module docstring)."""
    room = scene.room
    size = room.size()
    tol = _TOUCH * size
    planes = room.planes()
    face_names = [f"wall {w.corners[0]}{w.corners[1]}" for w in room.walls] + ["the floor", "the ceiling"]
    feats: list[tuple[str, float]] = [("1/500 of the room's size (direct-light bias)", size * ROOM_FRACTION)]

    def gaps(where: str, points: np.ndarray, skip: set[int] = frozenset()) -> None:
        for k, (pl, face) in enumerate(zip(planes, face_names)):
            if k in skip:
                continue
            gap = float(np.min(pl[3] - points @ pl[:3]))
            if gap > tol:
                feats.append((f"{where}: gap to {face}", gap))

    light = scene.light
    if any(light.radiance):  # a black light (the furnace scenes' placeholder) is only a black patch
        feats.append(("light.size", float(min(light.size))))
        # The face behind the light's non-emitting side is skipped: paths end at the light.
        behind = len(planes) - 1 if light.normal[2] < 0 else len(planes) - 2
        gaps("light", light.corners(), {behind})
    for i, o in enumerate(scene.objects):
        where = f"objects[{i}] ({o.name})"
        if isinstance(o, Sphere):
            feats.append((f"{where}.radius", float(o.radius)))
            c = np.asarray(o.center)
            for pl, face in zip(planes, face_names):
                gap = float(pl[3] - c @ pl[:3] - o.radius)
                if gap > tol:
                    feats.append((f"{where}: gap to {face}", gap))
        elif isinstance(o, Tetrahedron):
            v = np.asarray(o.vertices, dtype=np.float64)
            alt = math.inf
            for k in range(4):
                tri = np.delete(v, k, axis=0)
                n = np.cross(tri[1] - tri[0], tri[2] - tri[0])
                alt = min(alt, abs(float((v[k] - tri[0]) @ n)) / float(np.linalg.norm(n)))
            feats.append((f"{where}: thickness (smallest altitude)", alt))
            gaps(where, v)
    for name, cam in scene.cameras.items():
        eye = np.asarray(cam.eye, dtype=np.float64)
        d = float(np.min(planes[:, 3] - planes[:, :3] @ eye))
        if d > tol:
            feats.append((f"cameras.{name}.eye: distance to the nearest face", d))
    return feats


def precision_report(scene: Scene) -> PrecisionReport:
    """N, M and N / M of ``scene`` (see :class:`PrecisionReport`)."""
    name, feature = min(scene_features(scene), key=lambda f: f[1])
    distance = scene_distance(scene)
    return PrecisionReport(distance, feature, name, distance / feature, scene.room.size())


def check_precision(scene: Scene) -> None:
    """Raise ``ValueError`` when float32 rendering of ``scene`` would be wrong; return None otherwise.

    The scene is refused when its distance from the origin N exceeds
    :data:`LIMIT_RATIO` (2^17) times its smallest feature M, or when its
    squared lengths would leave float32's range (module docstring for the
    derivation and the measurements). The message names the file, N, M, the
    feature and the limit, for example::

        canonical.toml: the scene lies 10013 units from the origin but is only
        0.032 units small (1/500 of the room's size (direct-light bias)):
        float32 rendering would be wrong (limit ratio 131072, here 312906);
        move it closer to the origin
    """
    r = precision_report(scene)
    where = scene.path
    if r.size < MIN_SIZE:
        raise ValueError(
            f"{where}: the room is only {r.size:.3g} units large: its squared lengths would underflow float32 "
            f"(smallest size {MIN_SIZE:g}); scale the scene up"
        )
    if r.distance + r.size > MAX_EXTENT:
        raise ValueError(
            f"{where}: the scene reaches {r.distance + r.size:.3g} units from the origin: its squared lengths would "
            f"overflow float32 (largest extent {MAX_EXTENT:g}); scale it down or move it closer to the origin"
        )
    if r.ratio > r.limit:
        if r.feature * r.limit < r.size:  # wrong even at the origin: moving cannot help
            raise ValueError(
                f"{where}: the scene is {r.size:.6g} units large but its smallest feature is only {r.feature:.3g} units "
                f"({r.feature_name}): float32 rendering would be wrong (limit ratio {r.limit:.0f}, here {r.ratio:.0f}); "
                f"enlarge the feature"
            )
        raise ValueError(
            f"{where}: the scene lies {r.distance:.6g} units from the origin but is only {r.feature:.3g} units small "
            f"({r.feature_name}): float32 rendering would be wrong (limit ratio {r.limit:.0f}, here {r.ratio:.0f}); "
            f"move it closer to the origin"
        )
