r"""An object's material and size, as a student's program gets them wrong.

* **material**: each object rendered with the other material (the mirror
  sphere diffuse, the diffuse tetrahedron a mirror), and each of the
  room's surfaces a mirror (a floor polished to a mirror, a wall given the
  sphere's material), at albedo or reflectance 0, 1/2 and 1; the model
  image is the Lagrange interpolation through them per channel (channel c
  of the image depends on channel c of the material only), the value
  scanned on :data:`GRID` per channel. At 0 in every channel the surface
  is black whatever its material: an object is worded as black with every
  cause of that (:mod:`.surface_black`); a room surface's mirror darker
  than :data:`ROOM_MIRROR` is left to the albedo family. A surface no pixel sees directly is
  fitted by what it reflects onto the rest, as its albedo is
  (:attr:`~mcrt.grade.candidates.Candidate.out_of_view`).
* **object_size**: each object scaled about its centre (a sphere's radius,
  a tetrahedron about its centroid) by the factors :data:`SIZES` (halved
  and doubled among them: a sphere's diameter given where its radius is
  asked, or the other way), with the scene's own; the model image is
  linear between two neighbouring sizes.

Both render with mcrt at the basis's spp and seed
(:func:`mcrt.grade.explain.basis.basis_settings`), so that a variation
minus the base shares its random numbers; the renders are kept in
``Basis.extra[family.name]``. Glossy materials are not among them: mcrt
renders no glossy surface.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.basis import basis_renderer
from mcrt.grade.explain.fit import Fit
from mcrt.grade.explain.scene import _seen, lagrange
from mcrt.grade.explain.surface_black import black_family, black_words, is_black
from mcrt.grade.feedback import fmt_values
from mcrt.grade.feedback import num as _num
from mcrt.scene import Lambertian, Mirror, Scene

#: Albedo or reflectance nodes of an object rendered as another material.
MATERIAL_NODES = (0.0, 0.5, 1.0)
#: Values scanned per channel for an object's albedo or reflectance.
GRID = np.linspace(0.0, 1.0, 41)
#: Least reflectance (in its brightest channel) a room surface's mirror is claimed with: a program makes a surface
#: a mirror to make it shine; a darker mirror looks like a dark surface, which the albedo family reads (a ceiling
#: lit less for any reason fits a near-black mirror about as well as an albedo).
ROOM_MIRROR = 0.5
#: Scale factors of an object's size rendered (1 is the scene's own).
SIZES = (0.5, 0.8, 0.9, 0.95, 1.05, 1.1, 1.2, 2.0)


def _with_object(scene: Scene, name: str, **changes) -> Scene:
    return replace(scene, objects=tuple(replace(o, **changes) if o.name == name else o for o in scene.objects))


def _scaled(o, f: float) -> dict:
    if hasattr(o, "radius"):
        return {"radius": o.radius * f}
    c = np.mean(o.vertices, axis=0)
    return {"vertices": tuple(tuple(float(x) for x in c + f * (np.asarray(v) - c)) for v in o.vertices)}


def _room_surfaces(scene: Scene) -> dict[str, str]:
    """The room's surfaces, the albedo basis's label ('wall AB', 'the floor') -> Scene.surfaces's name."""
    return {**{f"wall {''.join(w.corners)}": f"wall_{''.join(w.corners)}" for w in scene.room.walls},
            "the floor": "floor", "the ceiling": "ceiling"}


def _prepare_material(a, scene: Scene, render) -> dict:
    """{object's name or a room surface's label: (the other material's kind, nodes, images (nodes, H, W, 3))}."""
    img = basis_renderer(a, render)
    out = {}
    for o in scene.objects:
        kind = "mirror" if isinstance(o.material, Lambertian) else "diffuse"
        imgs = [img(_with_object(scene, o.name, material=Mirror(reflectance=(v, v, v)) if kind == "mirror"
                                 else Lambertian(albedo=(v, v, v)))) for v in MATERIAL_NODES]
        out[o.name] = (kind, np.asarray(MATERIAL_NODES), np.stack(imgs))
    for label, name in _room_surfaces(scene).items():
        imgs = [img(replace(scene, room=replace(scene.room, mirrors=((name, (v, v, v)),)))) for v in MATERIAL_NODES]
        out[label] = ("mirror", np.asarray(MATERIAL_NODES), np.stack(imgs))
    return out


def _prepare_size(a, scene: Scene, render) -> dict:
    """{object: [(scale, image)]}."""
    img = basis_renderer(a, render)
    return {o.name: [(f, img(_with_object(scene, o.name, **_scaled(o, f)))) for f in SIZES] for o in scene.objects}


def material(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """Each object rendered as the other material, its albedo or reflectance fitted per channel."""
    r = inputs.basis.extra.get(material.name)
    if not r:
        return []
    base = inputs.basis.base.astype(np.float64)
    seen = _seen(inputs)
    out = []
    for name, (kind, nodes, imgs) in r.items():
        L = lagrange(GRID, nodes)  # (grid, nodes)
        fitted, change = [], np.zeros_like(base)
        for c in range(3):
            curves = np.tensordot(L, imgs[..., c].astype(np.float64), axes=(1, 0)) - base[None, ..., c]
            errs = []
            for k in range(len(GRID)):
                dm = np.zeros_like(base)
                dm[..., c] = curves[k]
                errs.append(fit.delta(dm))
            k = int(np.argmin(errs))
            fitted.append(float(GRID[k]))
            change[..., c] = curves[k]
        word = "a mirror of reflectance" if kind == "mirror" else "a diffuse (Lambertian) surface of albedo"
        was = "a diffuse surface" if kind == "mirror" else "a mirror"
        room = name in inputs.basis.values  # a room surface, keyed by its label
        hidden = room and seen is not None and name not in seen
        fam, text = "material", (f"{name if room else f'the {name}'}{' (not in view)' if hidden else ''} rendered as "
                                 f"{word} {fmt_values(fitted)} where the scene makes it {was}")
        label = name if room else next((k for k in (f"the {name}", f"the mirror {name}") if k in inputs.basis.values),
                                       None)
        if room and max(fitted) < ROOM_MIRROR:  # a dark surface to the eye: the albedo family's reading
            continue
        if is_black(fitted) and label is not None:  # black whatever the material: the surface black, every cause named
            own = inputs.basis.values[label]
            fam, text, hidden = black_family(label), black_words(label, own[1], own[0]), False
        out.append(Candidate(fam, f"{name} as {kind}", text, fit.delta(change), 3,
                             value={"object": name, "material": kind, "value": fitted}, change=change,
                             out_of_view=hidden))
    return out


def object_size(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """Each object's size: the scale between the two rendered sizes that fit best (linear between them)."""
    r = inputs.basis.extra.get(object_size.name)
    if not r:
        return []
    base = inputs.basis.base.astype(np.float64)
    out = []
    for name, nodes in r.items():
        pts = sorted([(1.0, base)] + [(f, i.astype(np.float64)) for f, i in nodes], key=lambda p: p[0])
        best = None
        for (f0, i0), (f1, i1) in zip(pts, pts[1:]):
            for t in np.linspace(0.0, 1.0, 11):
                dm = (1 - t) * i0 + t * i1 - base
                e = fit.delta(dm)
                if best is None or e < best[0]:
                    best = (e, f0 + t * (f1 - f0), dm)
        e, f, dm = best
        what = "radius" if name == "sphere" else "size"
        why = {0.5: " (the scene's radius taken for a diameter and halved)",
               2.0: " (the radius doubled, as when a diameter is used for it)"}
        out.append(Candidate("object_size", f"size of the {name}", f"the {name}'s {what} {_num(f)} times the scene's"
                             + next((w for k, w in why.items() if name == "sphere" and abs(f / k - 1) <= 0.1), ""),
                             e, 1, value={"object": name, "scale": f}, change=dm))
    return out


material.name, material.prepare = "material", _prepare_material
object_size.name, object_size.prepare = "object_size", _prepare_size
