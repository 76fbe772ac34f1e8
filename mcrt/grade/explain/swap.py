r"""Colours or materials given to the wrong surfaces: two exchanged, or every wall's one place off.

A program that keeps its materials in a list and gives each surface an
index into it gets the index wrong in two usual ways: two surfaces' indices
exchanged (a copied line, two entries of the list in the wrong order), or
every wall's index one place off in the list (the loop's counter started at
1, or the walls built from the next corner). The image is then that of the
scene with

* **two surfaces' colours exchanged**: any two diffuse surfaces (the walls,
  the floor, the ceiling, a diffuse object) each with the other's albedo;
* **two objects' materials exchanged**: a mirror and a diffuse object, each
  with the other's material (the mirror sphere orange and diffuse, the
  tetrahedron a mirror);
* **the walls' colours some walls off**: each wall with the albedo of the
  wall k places after it in the room's order (k = 1 ... n - 1 for n walls;
  k = 1 and n - 1 are one wall off);
* **the walls' colours in reverse order**: wall i with the albedo of wall
  k - i (mod n), for each k (the corner list reversed to wind the room, the
  colours kept in their order).

Every such scene is rendered with mcrt at the basis's spp and seed
(:func:`mcrt.grade.explain.basis.basis_settings`), so that a variation minus
the base shares its random numbers; nothing is fitted but which of them:
one parameter (the choice among a few dozen scenes). A single surface's
colour (:func:`mcrt.grade.explain.scene.albedo`) cannot fit two surfaces
wrong at once, and each of these needs no colour that is not the scene's.
"""

from __future__ import annotations

from dataclasses import replace
from itertools import combinations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.basis import _surface_edits
from mcrt.grade.explain.fit import Fit
from mcrt.grade.explain.basis import basis_renderer
from mcrt.scene import Lambertian, Scene


def _colour(scene: Scene, label: str, value) -> Scene:
    """``scene`` with the surface ``label`` (:func:`~mcrt.grade.explain.basis._surface_edits`' labels) of colour
    ``value``."""
    return _surface_edits(scene)[label][2](tuple(value))


def _diffuse(scene: Scene) -> dict[str, tuple]:
    """label -> albedo of every diffuse surface, in the room's order (walls, floor, ceiling, objects)."""
    return {k: v for k, (kind, v, _) in _surface_edits(scene).items() if kind == "albedo"}


def variants(scene: Scene) -> list[tuple[str, tuple, Scene]]:
    """(family, what, scene) of every exchange the module docstring lists; an exchange that changes nothing (two
    surfaces of one colour) is left out."""
    out = []
    diffuse = _diffuse(scene)
    for a, b in combinations(diffuse, 2):
        if diffuse[a] != diffuse[b]:
            out.append(("albedo_swap", ("swap", a, b), _colour(_colour(scene, a, diffuse[b]), b, diffuse[a])))
    lam = [o for o in scene.objects if isinstance(o.material, Lambertian)]
    for m in (o for o in scene.objects if not isinstance(o.material, Lambertian)):
        for d in lam:
            mats = {m.name: d.material, d.name: m.material}
            objs = tuple(replace(o, material=mats.get(o.name, o.material)) for o in scene.objects)
            out.append(("material_swap", ("swap", m.name, d.name), replace(scene, objects=objs)))
    walls, n = scene.room.walls, len(scene.room.walls)
    if len({w.albedo for w in walls}) > 1:
        steps = [k if k <= n // 2 else k - n for k in range(1, n)]  # signed: -1 is the wall before
        orders = [(("walls", "after", k), [(i + k) % n for i in range(n)]) for k in steps]
        orders += [(("walls", "reversed", k), [(k - i) % n for i in range(n)]) for k in range(n)]
        for what, order in orders:
            recoloured = tuple(replace(w, albedo=walls[j].albedo) for w, j in zip(walls, order))
            if recoloured != walls:
                out.append(("albedo_swap", what, replace(scene, room=replace(scene.room, walls=recoloured))))
    return out


def _prepare(a, scene: Scene, render) -> list[tuple[str, tuple, np.ndarray]]:
    """(family, what, image) of every variant, at the basis's spp and seed."""
    img = basis_renderer(a, render)
    return [(fam, what, img(s)) for fam, what, s in variants(scene)]


def _words(fam: str, what: tuple) -> str:
    if what[0] == "walls":
        _, how, k = what
        if how == "reversed":
            return (f"the walls' colours in reverse order, wall number i (from 0) given the colour of wall {k} - i: "
                    "the corner list reversed to wind the room, its colours kept in their order")
        place = "after" if k > 0 else "before"
        if abs(k) == 1:
            return (f"every wall with the colour of the wall {place} it in the room's order: the walls' colour index "
                    "one place off (a loop's counter, or the walls built from the next corner)")
        return (f"every wall with the colour of the wall {abs(k)} places {place} it in the room's order: the walls' "
                f"colour index {abs(k)} places off")
    _, a, b = what
    if fam == "material_swap":
        return (f"the materials of the {a} and the {b} exchanged (each object given the other's material index): "
                f"the {a} a diffuse surface of the {b}'s colour, the {b} a mirror")
    return (f"the colours of {a} and {b} exchanged (each given the other's albedo: two material indices the wrong way "
            "round)")


def swap(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The exchange (the module docstring) that fits best, of each family."""
    r = inputs.basis.extra.get(swap.name)
    if not r:
        return []
    base = inputs.basis.base.astype(np.float64)
    best: dict[str, Candidate] = {}
    for fam, what, img in r:
        change = img.astype(np.float64) - base
        chi = fit.delta(change)
        if fam not in best or chi < best[fam].chi2:
            value = {"exchanged": list(what[1:])} if what[0] == "swap" else {"walls": what[1], "k": what[2]}
            best[fam] = Candidate(fam, " ".join(map(str, what)), _words(fam, what), chi, 1, value=value, change=change)
    return list(best.values())


swap.name, swap.prepare = "swap", _prepare
