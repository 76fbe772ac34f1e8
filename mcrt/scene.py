"""The scene description: load a TOML scene file, validate it once, hash it.

A scene file (format: reference/scenes/FORMAT.md) becomes a frozen
:class:`Scene`. Both renderers are built from this object and nothing else:
:meth:`Scene.surfaces` gives every flat surface as triangles with its
material, so the standalone tracer and the Mitsuba scene share one geometry.

Every problem in a file is reported as a :class:`SceneError` whose message
names the file and the field, for example
``canonical.toml: objects[0].material.albedo: must be in [0, 1], got -0.1``.
"""

from __future__ import annotations

import difflib
import hashlib
import json
import math
import os
import stat
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

import mcrt.data as _data

Vec2 = tuple[float, float]
Vec3 = tuple[float, float, float]

#: The ground truth's folder: reference/ of a checkout, installed as the package data mcrt.data.
DATA_DIR = Path(_data.__file__).resolve().parent
SCENE_DIR = DATA_DIR / "scenes"
CANONICAL = SCENE_DIR / "canonical.toml"

# -- What float32 paths can carry ---------------------------------------------
# Both renderers trace in float32 (largest value FLT_MAX = 3.4e38). Scene files
# are refused at load time when a value would overflow it during a render:
#
# * a coordinate or length C: squared distances of points up to 2C apart
#   (3 components, 12 C^2) appear in every intersection and light sample, and
#   products with an area or a cosine follow; with a headroom of 10^6 for
#   those, 12 C^2 * 10^6 <= FLT_MAX, so |C| <= sqrt(FLT_MAX / 1.2e7) ~ 5.3e15;
# * samples per pixel: the tracer's sample counters are 32-bit; at most 2^31 - 1;
# * a radiance L: the per-sample variance sums squares of samples over spp
#   samples, each sample at most L times a throughput and geometry factor
#   (headroom 10^6: 1/d^2 near the light, light_samples, 1/pdf), so
#   spp_max (10^6 L)^2 <= FLT_MAX, L <= sqrt(FLT_MAX / SPP_MAX) / 10^6 ~ 4.0e8;
# * an image side: at most 16384 pixels (pixel indices times the 3 channels and the
#   tracer's accumulation slots stay inside 32-bit integers; 16384^2 float32 RGB is 3 GiB).
FLT_MAX = float(np.finfo(np.float32).max)
_HEADROOM = 1e6
COORD_MAX = math.sqrt(FLT_MAX / (12.0 * _HEADROOM))
SPP_MAX = 2**31 - 1
RADIANCE_MAX = math.sqrt(FLT_MAX / SPP_MAX) / _HEADROOM
MAX_SIDE = 16384
SEED_MAX = 2**64 - 1

# Relative tolerance for "touching is allowed" checks (object on the floor,
# light against a wall), scaled by the size of the room.
_TOUCH = 1e-6


class SceneError(ValueError):
    """A scene file that cannot be used; the message names file and field."""


# --------------------------------------------------------------------------
# Typed description
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class Lambertian:
    """Ideal diffuse reflector, f = albedo / pi, two-sided.

    ``emission`` is a uniform radiance leaving the surface on the side its
    normal faces (into the room for the room's faces, outwards for objects).
    Only closed-form tests use it (the furnace); it is found by BSDF-sampled
    rays alone, never by light sampling.
    """

    albedo: Vec3
    type: str = "lambertian"
    emission: Vec3 = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Mirror:
    """Perfect specular reflector: reflects along 2 (n.wo) n - wo, times reflectance."""

    reflectance: Vec3 = (1.0, 1.0, 1.0)
    type: str = "mirror"


Material = Lambertian | Mirror


@dataclass(frozen=True)
class Wall:
    corners: tuple[str, str]
    albedo: Vec3
    emission: Vec3 = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Room:
    """A convex polygonal prism: corners counter-clockwise seen from above."""

    floor_z: float
    ceiling_z: float
    floor_albedo: Vec3
    ceiling_albedo: Vec3
    corners: dict[str, Vec2]
    walls: tuple[Wall, ...]  # in counter-clockwise order
    floor_emission: Vec3 = (0.0, 0.0, 0.0)
    ceiling_emission: Vec3 = (0.0, 0.0, 0.0)
    # Room surfaces (named as Scene.surfaces names them: 'floor', 'ceiling', 'wall_AB', ...) made mirrors of these
    # reflectances in place of their albedos: the grader's renders of a surface given another material. No scene
    # file sets it.
    mirrors: tuple[tuple[str, Vec3], ...] = ()

    def polygon(self) -> np.ndarray:
        """Corner positions (n, 2), counter-clockwise, in wall order."""
        return np.array([self.corners[w.corners[0]] for w in self.walls], dtype=np.float64)

    def planes(self) -> np.ndarray:
        """Bounding planes (n_walls + 2, 4) as (outward normal, offset): inside is n.p <= offset."""
        poly = self.polygon()
        out = []
        for a, b in zip(poly, np.roll(poly, -1, axis=0)):
            e = b - a
            n = np.array([e[1], -e[0], 0.0]) / np.hypot(*e)  # right of a CCW edge = outside
            out.append([*n, n[:2] @ a])
        out.append([0.0, 0.0, -1.0, -self.floor_z])
        out.append([0.0, 0.0, 1.0, self.ceiling_z])
        return np.array(out)

    def contains(self, p, margin: float = 0.0) -> bool:
        """Whether point p lies inside the room, at least ``margin`` from every face."""
        pl = self.planes()
        return bool(np.all(pl[:, :3] @ np.asarray(p, float) <= pl[:, 3] - margin))

    def size(self) -> float:
        poly = self.polygon()
        return float(max(np.ptp(poly[:, 0]), np.ptp(poly[:, 1]), self.ceiling_z - self.floor_z))


@dataclass(frozen=True)
class Tetrahedron:
    name: str
    vertices: tuple[Vec3, Vec3, Vec3, Vec3]
    material: Material
    type: str = "tetrahedron"

    def triangles(self) -> np.ndarray:
        """The four faces (4, 3, 3), wound so that their normals point outwards."""
        v = np.array(self.vertices)
        faces = []
        for i in range(4):
            tri = [v[j] for j in range(4) if j != i]
            n = np.cross(tri[1] - tri[0], tri[2] - tri[0])
            if n @ (v[i] - tri[0]) > 0:  # normal towards the opposite vertex: flip
                tri = [tri[0], tri[2], tri[1]]
            faces.append(tri)
        return np.array(faces)


@dataclass(frozen=True)
class Sphere:
    name: str
    center: Vec3
    radius: float
    material: Material
    type: str = "sphere"


Object = Tetrahedron | Sphere


@dataclass(frozen=True)
class Light:
    """A horizontal rectangle emitting uniform radiance from the side its normal points to."""

    center: Vec3
    size: Vec2
    normal: Vec3
    radiance: Vec3

    @property
    def area(self) -> float:
        return self.size[0] * self.size[1]

    def corners(self) -> np.ndarray:
        """The four corners (4, 3), counter-clockwise seen from the emitting side."""
        cx, cy, cz = self.center
        hx, hy = self.size[0] / 2, self.size[1] / 2
        c = np.array([[cx - hx, cy - hy, cz], [cx + hx, cy - hy, cz], [cx + hx, cy + hy, cz], [cx - hx, cy + hy, cz]])
        return c if self.normal[2] > 0 else c[::-1].copy()

    def power(self) -> np.ndarray:
        """Emitted flux per channel, Phi = pi * A * Le (Lambertian emitter)."""
        return math.pi * self.area * np.array(self.radiance)


@dataclass(frozen=True)
class Camera:
    """A pinhole looking along ``forward``; the image plane is 1 unit in front of the eye."""

    name: str
    eye: Vec3
    forward: Vec3
    up: Vec3
    fov_x_deg: float

    def frame(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Orthonormal (right, up, forward); the image's right is forward x up."""
        f = np.array(self.forward, float)
        f /= np.linalg.norm(f)
        r = np.cross(f, np.array(self.up, float))
        r /= np.linalg.norm(r)
        return r, np.cross(r, f), f


@dataclass(frozen=True)
class RenderSettings:
    camera: str = "near"
    width: int = 256
    height: int = 256
    spp: int = 64
    max_depth: int = 8
    light_samples: int = 1
    rr_depth: int = 5
    seed: int = 0


@dataclass(frozen=True)
class Surface:
    """A flat piece of the scene as triangles, for both renderers."""

    name: str
    triangles: np.ndarray  # (n, 3, 3); room faces wound towards the inside, objects outwards
    material: Material | None  # None: the light's black surface


@dataclass(frozen=True)
class Scene:
    name: str
    description: str
    room: Room
    objects: tuple[Object, ...]
    light: Light
    cameras: dict[str, Camera]
    render: RenderSettings
    presets: dict[str, dict[str, Any]] = field(default_factory=dict)
    path: str = "<memory>"

    # -- derived geometry ---------------------------------------------------

    def surfaces(self) -> list[Surface]:
        """Walls, floor, ceiling, flat objects and the light as triangle lists."""
        room = self.room
        poly = room.polygon()
        z0, z1 = room.floor_z, room.ceiling_z
        out = []
        for w, a, b in zip(room.walls, poly, np.roll(poly, -1, axis=0)):
            p = [np.array([*a, z0]), np.array([*b, z0]), np.array([*b, z1]), np.array([*a, z1])]
            # a->b is counter-clockwise from above, so (b-a) x up points outwards:
            # wind the quad a,top_a,top_b,b for an inward normal.
            tris = np.array([[p[0], p[3], p[2]], [p[0], p[2], p[1]]])
            out.append(Surface(f"wall_{w.corners[0]}{w.corners[1]}", tris, Lambertian(w.albedo, emission=w.emission)))
        # A light lying in the floor's or ceiling's plane is cut out of it, so that no
        # renderer has two coplanar surfaces to choose between (z-fighting).
        light = self.light
        tol = 1e-9 * room.size()
        hole_floor = abs(light.center[2] - z0) <= tol
        hole_ceiling = abs(light.center[2] - z1) <= tol
        floor = np.array([[[*a, z0], [*b, z0], [*c, z0]] for a, b, c in _fan(poly, self._hole() if hole_floor else None)])
        ceil = np.array([[[*a, z1], [*c, z1], [*b, z1]] for a, b, c in _fan(poly, self._hole() if hole_ceiling else None)])
        out.append(Surface("floor", floor, Lambertian(room.floor_albedo, emission=room.floor_emission)))  # normal +z
        out.append(Surface("ceiling", ceil, Lambertian(room.ceiling_albedo, emission=room.ceiling_emission)))  # normal -z
        mirrors = dict(room.mirrors)
        unknown = set(mirrors) - {s.name for s in out}
        if unknown:
            raise SceneError(f"{self.path}: room: no surface named {sorted(unknown)[0]!r} to make a mirror")
        out = [replace(s, material=Mirror(reflectance=mirrors[s.name])) if s.name in mirrors else s for s in out]
        for o in self.objects:
            if isinstance(o, Tetrahedron):
                out.append(Surface(o.name, o.triangles(), o.material))
        c = self.light.corners()
        out.append(Surface("light", np.array([[c[0], c[1], c[2]], [c[0], c[2], c[3]]]), None))
        return out

    def _hole(self) -> tuple[float, float, float, float]:
        """The light's footprint (x0, x1, y0, y1) seen from above."""
        cx, cy, _ = self.light.center
        hx, hy = self.light.size[0] / 2, self.light.size[1] / 2
        return cx - hx, cx + hx, cy - hy, cy + hy

    def spheres(self) -> list[Sphere]:
        return [o for o in self.objects if isinstance(o, Sphere)]

    def camera(self, name: str | None = None) -> Camera:
        name = name or self.render.camera
        if name not in self.cameras:
            raise SceneError(f"{self.path}: cameras: no camera named {name!r} (have {', '.join(self.cameras)})")
        return self.cameras[name]

    def settings(self, preset: str | None = None, **overrides: Any) -> RenderSettings:
        """Render settings: file defaults, then a named preset, then explicit overrides (None = keep)."""
        s = self.render
        if preset is not None:
            if preset not in self.presets:
                raise SceneError(f"{self.path}: presets: no preset named {preset!r} (have {', '.join(self.presets) or 'none'})")
            s = replace(s, **self.presets[preset])
        s = replace(s, **{k: v for k, v in overrides.items() if v is not None})
        _check_settings(s, f"{self.path}: render")
        return s

    def scaled(self, factor: float, offset: Vec3 = (0.0, 0.0, 0.0)) -> "Scene":
        """The scene (cameras included) scaled about the origin, then moved by ``offset``."""
        t = lambda p: tuple(float(factor * x + o) for x, o in zip(p, offset))  # noqa: E731
        t2 = lambda p: tuple(float(factor * x + o) for x, o in zip(p, offset[:2]))  # noqa: E731
        room = replace(
            self.room,
            floor_z=factor * self.room.floor_z + offset[2],
            ceiling_z=factor * self.room.ceiling_z + offset[2],
            corners={k: t2(v) for k, v in self.room.corners.items()},
        )
        objs = []
        for o in self.objects:
            if isinstance(o, Sphere):
                objs.append(replace(o, center=t(o.center), radius=factor * o.radius))
            else:
                objs.append(replace(o, vertices=tuple(t(v) for v in o.vertices)))
        light = replace(self.light, center=t(self.light.center), size=tuple(factor * s for s in self.light.size))
        cams = {k: replace(c, eye=t(c.eye)) for k, c in self.cameras.items()}
        return replace(self, room=room, objects=tuple(objs), light=light, cameras=cams, name=f"{self.name}-x{factor:g}")

    # -- identity -----------------------------------------------------------

    def canonical_dict(self) -> dict[str, Any]:
        """What the scene hash covers: geometry, materials, light, cameras (not render defaults)."""

        def mat(m):
            if isinstance(m, Mirror):
                return {"type": m.type, "reflectance": m.reflectance}
            return {"type": m.type, "albedo": m.albedo, **({"emission": m.emission} if any(m.emission) else {})}

        def obj(o):
            d = {"name": o.name, "type": o.type, "material": mat(o.material)}
            if isinstance(o, Sphere):
                d.update(center=o.center, radius=o.radius)
            else:
                d.update(vertices=o.vertices)
            return d

        r = self.room
        return {
            "room": {
                "floor_z": r.floor_z,
                "ceiling_z": r.ceiling_z,
                "floor_albedo": r.floor_albedo,
                "ceiling_albedo": r.ceiling_albedo,
                "walls": [
                    {"from": r.corners[w.corners[0]], "to": r.corners[w.corners[1]], "albedo": w.albedo, **({"emission": w.emission} if any(w.emission) else {})}
                    for w in r.walls
                ],
                **({"floor_emission": r.floor_emission} if any(r.floor_emission) else {}),
                **({"ceiling_emission": r.ceiling_emission} if any(r.ceiling_emission) else {}),
                **({"mirrors": [list(m) for m in r.mirrors]} if r.mirrors else {}),
            },
            "objects": [obj(o) for o in self.objects],
            "light": {k: getattr(self.light, k) for k in ("center", "size", "normal", "radiance")},
            "cameras": {k: {"eye": c.eye, "forward": c.forward, "up": c.up, "fov_x_deg": c.fov_x_deg} for k, c in sorted(self.cameras.items())},
        }

    def content_hash(self) -> str:
        """A stable hash of the scene's content: formatting, comments and order of tables do not matter."""
        text = json.dumps(self.canonical_dict(), sort_keys=True, separators=(",", ":"), default=float)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def _clip(poly: list, axis: int, value: float, keep_below: bool) -> list:
    """Clip a convex polygon (list of 2D points) to coordinate[axis] <= value (or >=)."""
    out = []
    sign = 1.0 if keep_below else -1.0
    for a, b in zip(poly, poly[1:] + poly[:1]):
        da, db = sign * (a[axis] - value), sign * (b[axis] - value)
        if da <= 0:
            out.append(a)
        if da * db < 0:
            t = da / (da - db)
            out.append((a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])))
    return out


def _fan(poly: np.ndarray, hole: tuple[float, float, float, float] | None):
    """Counter-clockwise triangles covering a convex polygon, minus an axis-aligned rectangle inside it.

    Without a hole, a fan from the first corner. With one, the polygon is cut
    into the convex pieces above, below, left and right of the rectangle.
    """
    pts = [tuple(map(float, p)) for p in poly]
    if hole is None:
        pieces = [pts]
    else:
        x0, x1, y0, y1 = hole
        below = _clip(pts, 1, y0, True)
        above = _clip(pts, 1, y1, False)
        band = _clip(_clip(pts, 1, y0, False), 1, y1, True)
        pieces = [below, above, _clip(band, 0, x0, True), _clip(band, 0, x1, False)]
    tris = []
    for piece in pieces:
        for i in range(1, len(piece) - 1):
            a, b, c = np.array(piece[0]), np.array(piece[i]), np.array(piece[i + 1])
            if (b - a)[0] * (c - a)[1] - (b - a)[1] * (c - a)[0] > 1e-12 * max(1.0, float(np.abs(poly).max())) ** 2:
                tris.append((a, b, c))
    return tris


# --------------------------------------------------------------------------
# Loading and validation
# --------------------------------------------------------------------------


class _Reader:
    """Walks the parsed TOML, checking fields and naming them in errors."""

    def __init__(self, path: str):
        self.path = path

    def fail(self, where: str, problem: str) -> SceneError:
        return SceneError(f"{self.path}: {where}: {problem}")

    def table(self, d: Any, where: str, required: set[str], optional: set[str] = frozenset()) -> dict:
        if not isinstance(d, dict):
            raise self.fail(where, f"must be a table, got {type(d).__name__}")
        allowed = required | optional
        for k in d:
            if k not in allowed:
                near = difflib.get_close_matches(k, sorted(allowed), n=1)
                hint = f" (did you mean {near[0]!r}?)" if near else f" (allowed: {', '.join(sorted(allowed))})"
                raise self.fail(f"{where}.{k}" if where else k, f"unknown field{hint}")
        for k in sorted(required):
            if k not in d:
                raise self.fail(f"{where}.{k}" if where else k, "missing required field")
        return d

    def number(self, v: Any, where: str, *, lo: float | None = None, hi: float | None = None, positive: bool = False) -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise self.fail(where, f"must be a number, got {v!r}")
        try:
            v = float(v)
        except OverflowError:  # an integer beyond float64
            raise self.fail(where, f"must be finite, got an integer of {len(str(abs(v)))} digits") from None
        if not math.isfinite(v):
            raise self.fail(where, f"must be finite, got {v}")
        if abs(v) > COORD_MAX:
            raise self.fail(where, f"{v:g} is beyond +-{COORD_MAX:.2g}, the largest value whose squared distances "
                            "float32 paths can carry (sqrt(FLT_MAX / 1.2e7), with 10^6 of headroom)")
        if positive and v <= 0:
            raise self.fail(where, f"must be positive, got {v}")
        if lo is not None and v < lo or hi is not None and v > hi:
            raise self.fail(where, f"must be in [{lo if lo is not None else '-inf'}, {hi if hi is not None else 'inf'}], got {v}")
        return v

    def vec(self, v: Any, where: str, n: int, **kw) -> tuple[float, ...]:
        if not isinstance(v, list) or len(v) != n:
            raise self.fail(where, f"must be a list of {n} numbers, got {v!r}")
        return tuple(self.number(x, f"{where}[{i}]", **kw) for i, x in enumerate(v))

    def integer(self, v: Any, where: str, lo: int, hi: int | None = None, why: str = "") -> int:
        if isinstance(v, bool) or not isinstance(v, int) or v < lo:
            raise self.fail(where, f"must be an integer >= {lo}, got {_short_repr(v)}")
        if hi is not None and v > hi:
            raise self.fail(where, f"must be at most {hi}{why}, got {v}")
        return v

    def albedo(self, v: Any, where: str) -> Vec3:
        return self.vec(v, where, 3, lo=0.0, hi=1.0)

    def radiance(self, v: Any, where: str) -> Vec3:
        for i, x in enumerate(v if isinstance(v, list) and len(v) == 3 else []):
            if isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) and x > RADIANCE_MAX:
                raise self.fail(f"{where}[{i}]", f"{x:g} is beyond {RADIANCE_MAX:.2g}, the largest radiance whose samples "
                                f"and their squares (for the variance) stay finite in float32 at up to {SPP_MAX} spp "
                                "(sqrt(FLT_MAX / spp_max) / 10^6 of headroom)")
        return self.vec(v, where, 3, lo=0.0)

    def material(self, d: Any, where: str) -> Material:
        if not isinstance(d, dict) or "type" not in d:
            raise self.fail(f"{where}.type", "missing required field (lambertian or mirror)")
        if d["type"] == "lambertian":
            self.table(d, where, {"type", "albedo"}, {"emission"})
            return Lambertian(self.albedo(d["albedo"], f"{where}.albedo"), emission=self.radiance(d.get("emission", [0, 0, 0]), f"{where}.emission"))
        if d["type"] == "mirror":
            self.table(d, where, {"type"}, {"reflectance"})
            return Mirror(self.albedo(d.get("reflectance", [1.0, 1.0, 1.0]), f"{where}.reflectance"))
        raise self.fail(f"{where}.type", f"unknown material {d['type']!r} (lambertian or mirror)")


def _short_repr(v: Any) -> str:
    try:
        t = repr(v)
    except (RecursionError, ValueError):  # a deeply nested list; an integer too long to print
        return f"a {type(v).__name__}"
    return t if len(t) <= 80 else t[:77] + "..."


def _check_settings(s: RenderSettings, where: str) -> None:
    r = _Reader(where.split(": ")[0])
    field_where = where.split(": ", 1)[1] if ": " in where else where
    if not isinstance(s.camera, str) or not s.camera:
        raise r.fail(f"{field_where}.camera", f"must be a camera's name, got {_short_repr(s.camera)}")
    side = f" (the largest image side mcrt renders: 32-bit pixel indices, {MAX_SIDE}^2 RGB float32 is 3 GiB)"
    r.integer(s.width, f"{field_where}.width", 1, MAX_SIDE, side)
    r.integer(s.height, f"{field_where}.height", 1, MAX_SIDE, side)
    r.integer(s.spp, f"{field_where}.spp", 1, SPP_MAX, " (the tracer's sample counters are 32-bit)")
    r.integer(s.light_samples, f"{field_where}.light_samples", 1, 1 << 16, " (shadow rays per vertex)")
    r.integer(s.rr_depth, f"{field_where}.rr_depth", 1, 1 << 16)
    r.integer(s.seed, f"{field_where}.seed", 0, SEED_MAX, " (seeds are 64-bit)")
    if isinstance(s.max_depth, bool) or not isinstance(s.max_depth, int) or (s.max_depth < 1 and s.max_depth != -1):
        raise r.fail(f"{field_where}.max_depth", f"must be -1 (unbounded) or an integer >= 1, got {s.max_depth!r}")


#: The largest scene file read (a scene is a few KiB; this stops ``--scene /dev/zero`` from reading without end).
MAX_SCENE_BYTES = 1 << 20


def read_capped(path: Path, limit: int, error: type[Exception], what: str = "scene file") -> bytes:
    """The bytes of the regular file ``path``, at most ``limit`` of them; else ``error`` naming the file and why.

    A FIFO, device or folder is refused without reading it (``/dev/zero`` would never end); the file is opened
    non-blocking so that a FIFO cannot hang the open.
    """
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as e:
        raise error(f"{path}: cannot read: {e.strerror or e}") from None
    with os.fdopen(fd, "rb") as f:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise error(f"{path}: not a regular file (a {what} must be one)")
        try:
            raw = f.read(limit + 1)
        except OSError as e:
            raise error(f"{path}: cannot read: {e.strerror or e}") from None
    if len(raw) > limit:
        raise error(f"{path}: larger than {limit // 1024} KiB, too large for a {what}")
    return raw


def load_scene(path: str | Path = CANONICAL) -> Scene:
    """Load and validate a scene file; raise :class:`SceneError` naming file and field."""
    path = Path(path)
    raw = read_capped(path, MAX_SCENE_BYTES, SceneError)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        line = raw[: e.start].count(b"\n") + 1
        raise SceneError(f"{path}: not valid UTF-8 (byte 0x{raw[e.start]:02x} on line {line}); TOML files are UTF-8") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise SceneError(f"{path}: not valid TOML: {e}") from None
    except RecursionError:
        raise SceneError(f"{path}: not valid TOML: arrays or tables nested too deeply to read") from None
    try:
        return scene_from_dict(data, str(path))
    except RecursionError:
        raise SceneError(f"{path}: a value is nested too deeply (arrays inside arrays hundreds of levels deep)") from None


def scene_from_dict(data: dict, path: str = "<memory>") -> Scene:
    """Validate a parsed scene description (the TOML file's tables) into a :class:`Scene`."""
    r = _Reader(path)
    r.table(data, "", {"format", "room", "light", "cameras"}, {"name", "description", "objects", "render", "presets"})
    if data["format"] != 1:
        raise r.fail("format", f"unsupported format {data['format']!r} (this mcrt reads format 1)")
    room = _room(r, data["room"])
    objects = tuple(_object(r, o, f"objects[{i}]", room) for i, o in enumerate(_list(r, data.get("objects", []), "objects")))
    names = [o.name for o in objects]
    for n in names:
        if names.count(n) > 1:
            raise r.fail("objects", f"two objects are named {n!r}")
    light = _light(r, data["light"], room)
    cams = r.table(data["cameras"], "cameras", set(), set(data["cameras"]) if isinstance(data["cameras"], dict) else set())
    if not cams:
        raise r.fail("cameras", "at least one camera is required")
    cameras = {k: _camera(r, v, f"cameras.{k}", k, room) for k, v in cams.items()}
    render = data.get("render", {})
    r.table(render, "render", set(), set(RenderSettings.__dataclass_fields__))
    settings = RenderSettings(**render)
    _check_settings(settings, f"{path}: render")
    if settings.camera not in cameras:
        raise r.fail("render.camera", f"no camera named {settings.camera!r} (have {', '.join(cameras)})")
    presets = r.table(data.get("presets", {}), "presets", set(), set(data.get("presets", {})) if isinstance(data.get("presets", {}), dict) else set())
    for k, p in presets.items():
        r.table(p, f"presets.{k}", set(), set(RenderSettings.__dataclass_fields__))
        ps = replace(settings, **p)
        _check_settings(ps, f"{path}: presets.{k}")
        if ps.camera not in cameras:
            raise r.fail(f"presets.{k}.camera", f"no camera named {ps.camera!r} (have {', '.join(cameras)})")
    return Scene(
        name=str(data.get("name", Path(path).stem)),
        description=str(data.get("description", "")),
        room=room,
        objects=objects,
        light=light,
        cameras=cameras,
        render=settings,
        presets={k: dict(v) for k, v in presets.items()},
        path=path,
    )


def _list(r: _Reader, v: Any, where: str) -> list:
    if not isinstance(v, list):
        raise r.fail(where, f"must be an array of tables, got {type(v).__name__}")
    return v


def _room(r: _Reader, d: Any) -> Room:
    r.table(d, "room", {"floor_z", "ceiling_z", "floor_albedo", "ceiling_albedo", "corners", "walls"}, {"floor_emission", "ceiling_emission"})
    z0 = r.number(d["floor_z"], "room.floor_z")
    z1 = r.number(d["ceiling_z"], "room.ceiling_z")
    if z1 <= z0:
        raise r.fail("room.ceiling_z", f"must be above floor_z ({z0}), got {z1}")
    corners_d = r.table(d["corners"], "room.corners", set(), set(d["corners"]) if isinstance(d["corners"], dict) else set())
    corners = {k: r.vec(v, f"room.corners.{k}", 2) for k, v in corners_d.items()}
    if len(corners) < 3:
        raise r.fail("room.corners", f"a room needs at least 3 corners, got {len(corners)}")
    walls = []
    for i, w in enumerate(_list(r, d["walls"], "room.walls")):
        where = f"room.walls[{i}]"
        r.table(w, where, {"corners", "albedo"}, {"emission"})
        c = w["corners"]
        if not (isinstance(c, list) and len(c) == 2 and all(isinstance(x, str) for x in c)):
            raise r.fail(f"{where}.corners", f"must be two corner names, got {c!r}")
        for x in c:
            if x not in corners:
                raise r.fail(f"{where}.corners", f"unknown corner {x!r} (have {', '.join(corners)})")
        if c[0] == c[1] or np.allclose(corners[c[0]], corners[c[1]]):
            raise r.fail(f"{where}.corners", f"degenerate wall: corners {c[0]} and {c[1]} coincide")
        walls.append(Wall((c[0], c[1]), r.albedo(w["albedo"], f"{where}.albedo"), r.radiance(w.get("emission", [0, 0, 0]), f"{where}.emission")))
    # Closed: the walls chain into one loop through every corner.
    start = {w.corners[0]: w for w in walls}
    if len(start) != len(walls) or len({w.corners[1] for w in walls}) != len(walls) or len(walls) != len(corners):
        raise r.fail("room.walls", "the room is open: every corner must start exactly one wall and end exactly one")
    loop, w = [], walls[0]
    while w not in loop:
        loop.append(w)
        w = start.get(w.corners[1])
        if w is None:
            raise r.fail("room.walls", f"the room is open: no wall starts at corner {loop[-1].corners[1]}")
    if len(loop) != len(walls):
        raise r.fail("room.walls", "the room is open: the walls form more than one loop")
    poly = np.array([corners[w.corners[0]] for w in loop])
    cross = [(b - a)[0] * (c - b)[1] - (b - a)[1] * (c - b)[0] for a, b, c in zip(poly, np.roll(poly, -1, 0), np.roll(poly, -2, 0))]
    if all(x < 0 for x in cross):
        loop = [Wall((w.corners[1], w.corners[0]), w.albedo, w.emission) for w in reversed(loop)]
    elif not all(x > 0 for x in cross):
        raise r.fail("room.walls", "the room must be a convex polygon (no straight or reflex corners)")
    return Room(
        z0, z1, r.albedo(d["floor_albedo"], "room.floor_albedo"), r.albedo(d["ceiling_albedo"], "room.ceiling_albedo"), corners, tuple(loop),
        r.radiance(d.get("floor_emission", [0, 0, 0]), "room.floor_emission"), r.radiance(d.get("ceiling_emission", [0, 0, 0]), "room.ceiling_emission"),
    )


def _object(r: _Reader, d: Any, where: str, room: Room) -> Object:
    if not isinstance(d, dict) or "type" not in d:
        raise r.fail(f"{where}.type", "missing required field (tetrahedron or sphere)")
    tol = _TOUCH * room.size()
    if d["type"] == "tetrahedron":
        r.table(d, where, {"name", "type", "vertices", "material"})
        v = d["vertices"]
        if not isinstance(v, list) or len(v) != 4:
            raise r.fail(f"{where}.vertices", f"a tetrahedron needs 4 vertices, got {v!r}")
        verts = tuple(r.vec(x, f"{where}.vertices[{i}]", 3) for i, x in enumerate(v))
        obj = Tetrahedron(str(d["name"]), verts, r.material(d["material"], f"{where}.material"))
        for k, tri in enumerate(obj.triangles()):
            area = 0.5 * np.linalg.norm(np.cross(tri[1] - tri[0], tri[2] - tri[0]))
            edge = max(np.linalg.norm(tri[i] - tri[j]) for i, j in ((0, 1), (1, 2), (2, 0)))
            if area <= 1e-7 * edge * edge:
                raise r.fail(f"{where}.vertices", f"degenerate triangle: face {k} has zero area (collinear or coincident vertices)")
        # Four coplanar vertices make four fine triangles but no solid: its faces have no outside to point to.
        e = np.array(verts[1:]) - np.array(verts[0])
        longest = max(np.linalg.norm(np.subtract(a, b)) for a in verts for b in verts)
        if abs(np.linalg.det(e)) <= 1e-6 * longest**3:
            raise r.fail(f"{where}.vertices", "flat tetrahedron: the four vertices lie in one plane (zero volume)")
        for i, p in enumerate(verts):
            if not room.contains(p, -tol):
                raise r.fail(f"{where}.vertices[{i}]", f"object outside the room: {p}")
        return obj
    if d["type"] == "sphere":
        r.table(d, where, {"name", "type", "center", "radius", "material"})
        c = r.vec(d["center"], f"{where}.center", 3)
        rad = r.number(d["radius"], f"{where}.radius", positive=True)
        if not room.contains(c, rad - tol):
            raise r.fail(where, f"object outside the room: sphere at {c} with radius {rad} crosses a wall, the floor or the ceiling")
        return Sphere(str(d["name"]), c, rad, r.material(d["material"], f"{where}.material"))
    raise r.fail(f"{where}.type", f"unknown object type {d['type']!r} (tetrahedron or sphere)")


def _light(r: _Reader, d: Any, room: Room) -> Light:
    r.table(d, "light", {"center", "size", "normal", "radiance"})
    light = Light(
        center=r.vec(d["center"], "light.center", 3),
        size=r.vec(d["size"], "light.size", 2, positive=True),
        normal=r.vec(d["normal"], "light.normal", 3),
        radiance=r.radiance(d["radiance"], "light.radiance"),
    )
    if light.normal not in ((0.0, 0.0, 1.0), (0.0, 0.0, -1.0)):
        raise r.fail("light.normal", f"must be [0, 0, -1] (down) or [0, 0, 1] (up): only horizontal lights are supported, got {list(light.normal)}")
    tol = _TOUCH * room.size()
    for c in light.corners():
        if not room.contains(c, -tol):
            raise r.fail("light", f"light outside the room: corner {tuple(float(x) for x in c)}")
    # It must face the room: the middle of the room lies on its emitting side.
    middle_z = 0.5 * (room.floor_z + room.ceiling_z)
    if light.normal[2] * (middle_z - light.center[2]) <= 0:
        raise r.fail("light.normal", f"the light faces away from the room (normal {list(light.normal)} at z = {light.center[2]})")
    return light


def _camera(r: _Reader, d: Any, where: str, name: str, room: Room) -> Camera:
    r.table(d, where, {"eye", "forward", "up", "fov_x_deg"})
    cam = Camera(
        name=name,
        eye=r.vec(d["eye"], f"{where}.eye", 3),
        forward=r.vec(d["forward"], f"{where}.forward", 3),
        up=r.vec(d["up"], f"{where}.up", 3),
        fov_x_deg=r.number(d["fov_x_deg"], f"{where}.fov_x_deg", lo=1e-3, hi=179.0),
    )
    f, u = np.array(cam.forward), np.array(cam.up)
    if np.linalg.norm(f) == 0:
        raise r.fail(f"{where}.forward", "must be a non-zero vector")
    if np.linalg.norm(np.cross(f, u)) <= 1e-6 * np.linalg.norm(f) * np.linalg.norm(u):
        raise r.fail(f"{where}.up", "must not be parallel to forward")
    if not room.contains(cam.eye, 0.0):
        raise r.fail(f"{where}.eye", f"the eye {cam.eye} is outside the room")
    return cam
