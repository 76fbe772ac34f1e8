"""The basis: mcrt renders of the scene's variations that the families fit (what the grading cache holds)."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from mcrt.scene import Lambertian, Mirror, Scene

#: Oversampling of the image warped for the camera families, and samples per grade pixel and axis of a warp;
#: the fine image sees WIDE times further to each side (tan of the half angle), so that warps stay inside it.
FINE = 4
WIDE = 1.2
#: As many warp samples per grade pixel and axis as fine pixels: bilinear samples fewer than the fine pixels give a
#: pixel a footprint whose width changes with a sub-pixel shift (the chi^2 of a shift then ripples with the period of
#: a fine pixel and a quarter-pixel shift is not found, while a rotation, whose shift varies across the image,
#: averages the ripple out); with SUB = FINE every shift's footprint is the same box.
SUB = FINE
#: Albedo nodes rendered per surface (with the scene's own value).
ALBEDO_NODES = (0.0, 0.5, 1.0)
#: Offsets (scene units) of the light, the objects and the eye; light size factors (both sides: twice is a unit square
#: scaled by the light's size, Mitsuba's rectangle spanning [-1, 1]).
LIGHT_OFFSETS = (-2.0, -1.5, -1.0, -0.5, 0.5, 1.0, 1.5, 2.0)
LIGHT_DROPS = (-0.5, -1.0, -2.5)
LIGHT_SIZES = (0.5, 0.75, 1.25, 1.5, 2.0)
#: Factors of one side of the light alone (the other kept).
LIGHT_SIDES = (0.5, 2.0)
OBJECT_OFFSETS = (-1.5, -1.0, -0.5, 0.5, 1.0, 1.5)
EYE_OFFSETS = (-1.0, -0.5, -0.3, -0.2, -0.1, 0.1, 0.2, 0.3, 0.5, 1.0)
DEPTHS = (1, 2, 3, 4, 5, 6, 7, 9, 10, 12, -1)
AXES = "xyz"
#: The orders in which a program can read an object's coordinates (a y-up habit reads (x, z, y)), the scene's own
#: (0, 1, 2) aside.
SWAPS = ((0, 2, 1), (1, 0, 2), (2, 1, 0), (1, 2, 0), (2, 0, 1))
#: Offsets (scene units) of the floor's and the ceiling's heights, as a value typed wrong.
PLANE_OFFSETS = (-1.0, -0.5, 0.5, 1.0)


@dataclass
class Basis:
    """mcrt renders of the scene's variations at the grade resolution (see the module docstring)."""

    camera: str
    spp: int
    base: np.ndarray  # (H, W, 3) the scene as it is, basis seed
    var: np.ndarray  # (H, W, 3) its per-sample variance
    fine: np.ndarray  # (~FINE WIDE H, ~FINE WIDE W, 3) the scene as it is, wider, for warps
    fine_tan: float  # tan of the fine image's horizontal half angle
    fov_deg: float
    max_depth: int
    albedo: dict[str, tuple[np.ndarray, np.ndarray, tuple]] = field(default_factory=dict)  # label -> (nodes, images, scene)
    nodes: dict[str, list[tuple[object, np.ndarray]]] = field(default_factory=dict)  # family/key -> [(value, image)]
    values: dict[str, object] = field(default_factory=dict)  # the scene's values, for the words
    extra: dict[str, object] = field(default_factory=dict)  # family name -> what its prepare() rendered
    prepare_time: float = 0.0



def _surface_edits(scene: Scene) -> dict[str, tuple[str, tuple, callable]]:
    """label -> (kind, the scene's value, value -> edited scene) for every surface with a colour."""
    out = {}
    room = scene.room
    for w in room.walls:
        key = "".join(w.corners)

        def wall(v, key=key):
            walls = tuple(replace(x, albedo=tuple(v)) if "".join(x.corners) == key else x for x in scene.room.walls)
            return replace(scene, room=replace(scene.room, walls=walls))
        out[f"wall {key}"] = ("albedo", tuple(w.albedo), wall)
    out["the floor"] = ("albedo", tuple(room.floor_albedo),
                        lambda v: replace(scene, room=replace(scene.room, floor_albedo=tuple(v))))
    out["the ceiling"] = ("albedo", tuple(room.ceiling_albedo),
                          lambda v: replace(scene, room=replace(scene.room, ceiling_albedo=tuple(v))))
    for o in scene.objects:
        def obj(v, name=o.name):
            objs = []
            for x in scene.objects:
                if x.name == name:
                    m = x.material
                    x = replace(x, material=replace(m, albedo=tuple(v)) if isinstance(m, Lambertian)
                                else replace(m, reflectance=tuple(v)))
                objs.append(x)
            return replace(scene, objects=tuple(objs))
        m = o.material
        if isinstance(m, Lambertian):
            out[f"the {o.name}"] = ("albedo", tuple(m.albedo), obj)
        elif isinstance(m, Mirror):
            out[f"the mirror {o.name}"] = ("reflectance", tuple(m.reflectance), obj)
    return out


def _shift(p, axis: int, d: float):
    q = list(p)
    q[axis] = float(q[axis] + d)
    return tuple(q)


def _light_variants(scene: Scene) -> dict[str, list[tuple[float, Scene]]]:
    lt = scene.light
    out: dict[str, list] = {}
    # Lower still: at z = 0 (its height left 0, or read as a distance below a ceiling at its own height) and at the
    # room's mid-height.
    room = scene.room
    drops = sorted(set(LIGHT_DROPS) | {-float(lt.center[2]), (room.floor_z + room.ceiling_z) / 2 - float(lt.center[2])})
    for axis, offsets in ((0, LIGHT_OFFSETS), (1, LIGHT_OFFSETS), (2, tuple(d for d in drops if d < 0))):
        out[f"light_{AXES[axis]}"] = [(d, replace(scene, light=replace(lt, center=_shift(lt.center, axis, d))))
                                      for d in offsets]
    # Each side times f, or one side alone (a half-width forgotten, or halved twice, along x or y only).
    sides = [(f, f) for f in LIGHT_SIZES] + [(f, 1.0) for f in LIGHT_SIDES] + [(1.0, f) for f in LIGHT_SIDES]
    out["light_size"] = [(f, replace(scene, light=replace(lt, size=(lt.size[0] * f[0], lt.size[1] * f[1]))))
                         for f in sides]
    # A coordinate of the centre typed with the wrong sign (its height -4.99 for 4.99).
    out["light_sign"] = [(axis, replace(scene, light=replace(lt, center=tuple(-float(x) if i == axis else float(x)
                                                                          for i, x in enumerate(lt.center)))))
                         for axis in range(3) if lt.center[axis] != 0]
    kept = {k: [(d, s) for d, s in v if _light_inside(s)] for k, v in out.items()}
    # The centre read (y, x) can put part of the light through a wall, as the student's program does: rendered so.
    if lt.center[0] != lt.center[1]:
        kept["light_swapped"] = [((1, 0, 2), replace(scene, light=replace(lt, center=(
            float(lt.center[1]), float(lt.center[0]), float(lt.center[2])))))]
    return kept


def _light_inside(s: Scene) -> bool:
    return all(s.room.contains(c, -1e-6 * s.room.size()) for c in s.light.corners()) and \
        s.light.center[2] < s.room.ceiling_z


def _object_variants(scene: Scene) -> dict[str, list[tuple[object, Scene]]]:
    out: dict[str, list] = {}
    if len(scene.objects) > 1:  # every object left out (never added to the scene's list, or always behind the room)
        out["missing:objects"] = [(None, replace(scene, objects=()))]
    for o in scene.objects:
        out[f"missing:{o.name}"] = [(None, replace(scene, objects=tuple(x for x in scene.objects if x.name != o.name)))]
        for axis in range(3):
            vs = []
            for d in OBJECT_OFFSETS:
                if hasattr(o, "center"):
                    moved = replace(o, center=_shift(o.center, axis, d))
                    ok = scene.room.contains(moved.center, moved.radius)
                else:
                    moved = replace(o, vertices=tuple(_shift(v, axis, d) for v in o.vertices))
                    ok = all(scene.room.contains(v, 0.0) for v in moved.vertices)
                if ok:
                    vs.append((d, replace(scene, objects=tuple(moved if x.name == o.name else x for x in scene.objects))))
            out[f"moved:{o.name}:{AXES[axis]}"] = vs
        swaps = []
        for order in SWAPS:
            if hasattr(o, "center"):
                moved = replace(o, center=tuple(float(o.center[i]) for i in order))
                ok = scene.room.contains(moved.center, moved.radius)
            else:
                moved = replace(o, vertices=tuple(tuple(float(v[i]) for i in order) for v in o.vertices))
                ok = all(scene.room.contains(v, 0.0) for v in moved.vertices)
            if ok:
                swaps.append((order, replace(scene, objects=tuple(moved if x.name == o.name else x for x in scene.objects))))
        out[f"swapped:{o.name}"] = swaps
        # Left in model space: the object about the origin, its placement never applied.
        centre = np.asarray(o.center if hasattr(o, "center") else np.mean(o.vertices, axis=0), float)
        if np.any(centre != 0) and scene.room.contains((0.0, 0.0, 0.0), getattr(o, "radius", 0.0)):
            moved = (replace(o, center=(0.0, 0.0, 0.0)) if hasattr(o, "center") else
                     replace(o, vertices=tuple(tuple(float(x) for x in np.asarray(v) - centre) for v in o.vertices)))
            out[f"origin:{o.name}"] = [(None, replace(scene, objects=tuple(moved if x.name == o.name else x
                                                                         for x in scene.objects)))]
    return out


def _room_variants(scene: Scene) -> dict[str, list[tuple[object, Scene]]]:
    """The room's corners read (y, x): the room mirrored about the line x = y, each wall between the same two
    corners (their order reversed to keep them counter-clockwise); the light and the objects where they were.
    None where a camera's eye would fall outside it."""
    room = scene.room
    mirrored = replace(room, corners={k: (float(v[1]), float(v[0])) for k, v in room.corners.items()},
                       walls=tuple(replace(w, corners=w.corners[::-1]) for w in reversed(room.walls)))
    if not all(mirrored.contains(c.eye, 1e-3) for c in scene.cameras.values()):
        return {}
    return {"swapped:room": [((1, 0, 2), replace(scene, room=mirrored))]}


def _plane_variants(scene: Scene) -> dict[str, list[tuple[float, Scene]]]:
    """The floor and the ceiling at other heights (the light stays below the ceiling, the eyes inside the room)."""
    room, out = scene.room, {}
    for plane in ("floor_z", "ceiling_z"):
        vs = []
        for d in PLANE_OFFSETS:
            moved = replace(scene, room=replace(room, **{plane: getattr(room, plane) + d}))
            if _light_inside(moved) and all(moved.room.contains(c.eye, 1e-3) for c in scene.cameras.values()):
                vs.append((d, moved))
        out[f"plane:{plane[:-2]}"] = vs
    return out


def _eye_variants(scene: Scene, camera: str) -> dict[str, list[tuple[float, Scene]]]:
    c = scene.cameras[camera]
    out = {}
    for axis in range(3):
        vs = []
        for d in EYE_OFFSETS:
            c2 = replace(c, eye=_shift(c.eye, axis, d))
            if scene.room.contains(c2.eye, 1e-3 * scene.room.size()):
                vs.append((d, replace(scene, cameras={**scene.cameras, camera: c2})))
        out[f"eye_{AXES[axis]}"] = vs
    # The forward vector's sign flipped: the camera looking back (its right vector flips with it).
    out["eye_back"] = [("back", replace(scene, cameras={**scene.cameras, camera: replace(
        c, forward=tuple(-float(x) for x in c.forward))}))]
    # The forward vector turned a quarter about the up vector (its x and y exchanged: atan2's arguments swapped in
    # a yaw, or a y-up convention's axes), to the left (+) or the right (-).
    out["eye_turned"] = [(side, replace(scene, cameras={**scene.cameras, camera: replace(
        c, forward=_turned(c.forward, c.up, sign))})) for side, sign in (("left", 1.0), ("right", -1.0))]
    # The rays built in camera space and never turned into the world: looking along the world's -z with y up
    # (OpenGL's convention), or along +z.
    out["eye_axis"] = [(f, replace(scene, cameras={**scene.cameras, camera: replace(c, forward=f, up=(0.0, 1.0, 0.0))}))
                       for f in ((0.0, 0.0, -1.0), (0.0, 0.0, 1.0)) if tuple(c.forward) != f]
    return out


def _turned(forward, up, sign: float) -> tuple[float, float, float]:
    """``forward`` turned by sign x 90 degrees about the unit ``up`` (Rodrigues' formula at a right angle)."""
    f, u = np.asarray(forward, float), np.asarray(up, float) / np.linalg.norm(up)
    return tuple(float(x) for x in np.dot(f, u) * u + sign * np.cross(u, f))


def basis_settings(a) -> tuple[int, int]:
    """(spp, seed) of every basis render of assignment ``a``: one seed for all, so that a variation minus the
    base shares its random numbers (families that render for themselves use them too)."""
    return max(64, a.diagnosis_spp // 4), a.seed + 7


def basis_renderer(a, render):
    """A function of a scene (and the renderer's tricks, a mistake of the estimator): its mcrt render at the basis's
    spp and seed, the assigned camera, grade size."""
    spp, seed = basis_settings(a)

    def img(s: Scene, **tricks) -> np.ndarray:
        return render(s, a.camera, a.grade_width, a.grade_height, a.max_depth, spp, seed,
                      **tricks).mean.astype(np.float32)

    return img


def prepare_basis(a, scene: Scene, render) -> Basis:
    """Render every image :func:`explain` needs, for the assignment ``a``.

    ``render(scene, camera, width, height, max_depth, spp, seed)`` returns a
    :class:`mcrt.film.RenderResult`; the grading context passes its cached
    mcrt render (:func:`mcrt.grade.expected.cached_render`), so each image is
    rendered once per machine.
    """
    t0 = time.perf_counter()
    w, h, d, cam = a.grade_width, a.grade_height, a.max_depth, a.camera
    spp, seed = basis_settings(a)

    def img(s: Scene, depth: int = d, width: int = w, height: int = h, n: int = spp) -> np.ndarray:
        return render(s, cam, width, height, depth, n, seed).mean.astype(np.float32)

    base_r = render(scene, cam, w, h, d, spp, seed)
    c0 = scene.cameras[cam]
    t_fine = WIDE * math.tan(math.radians(c0.fov_x_deg) / 2)
    wide = replace(scene, cameras={**scene.cameras, cam: replace(c0, fov_x_deg=math.degrees(2 * math.atan(t_fine)))})
    fine = img(wide, width=round(FINE * WIDE * w), height=round(FINE * WIDE * h), n=max(16, spp // FINE**2 * 4))
    b = Basis(camera=cam, spp=spp, base=base_r.mean.astype(np.float32),
              var=np.maximum(base_r.variance, 0).astype(np.float32), fine=fine, fine_tan=t_fine,
              fov_deg=float(c0.fov_x_deg), max_depth=d)
    for label, (kind, value, edit) in _surface_edits(scene).items():
        nodes = [v for v in ALBEDO_NODES if not (kind == "reflectance" and v == 1.0 and all(x == 1.0 for x in value))]
        imgs = [img(edit((v, v, v))) for v in nodes]
        b.albedo[label] = (np.asarray(nodes, np.float64), np.stack(imgs), tuple(value))
        b.values[label] = (kind, tuple(value))
    for fam in (_light_variants(scene), _object_variants(scene), _room_variants(scene), _plane_variants(scene),
                _eye_variants(scene, cam)):
        for key, vs in fam.items():
            if vs:
                b.nodes[key] = [(v, img(s)) for v, s in vs]
    b.nodes["depth"] = [(k, img(scene, depth=k)) for k in DEPTHS if k != d]
    lt, c = scene.light, scene.cameras[cam]
    b.values.update(light_center=tuple(lt.center), light_size=tuple(lt.size), light_radiance=tuple(lt.radiance),
                    eye=tuple(c.eye), forward=tuple(c.forward), up=tuple(c.up), floor=scene.room.floor_z, ceiling=scene.room.ceiling_z, objects={o.name: tuple(float(x) for x in (o.center if hasattr(o, "center")
                                                                            else np.mean(o.vertices, axis=0)))
                                                for o in scene.objects})
    b.prepare_time = time.perf_counter() - t0
    return b

