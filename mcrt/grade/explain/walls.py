r"""Every wall given one colour (a loop that reads one wall's colour for all six, a default, or their mean), or every
diffuse surface (a default colour shared by every material, one material for all).

The six walls light one another, so the image of all six changed at once is
not the sum of each one's change (:func:`~mcrt.grade.explain.scene.albedos`
leaves those second-order terms out, and they are large when every wall
changes). mcrt renders the room with every wall of albedo v for v in
:data:`NODES`, at the basis's spp and seed; channel c of the image depends
on channel c of the albedo only, so each channel's colour is fitted on the
polynomial through those renders (:func:`~mcrt.grade.explain.scene.fit_channel`),
three parameters in all. The same for every diffuse surface (the walls,
the floor, the ceiling and the diffuse objects) of albedo v. The words name
the colour, and which surface's it is (or the walls' mean) where it is
within :data:`SAME` of one.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.grade.explain.basis import basis_renderer
from mcrt.grade.explain.reflectance import remapped_reflectance
from mcrt.grade.explain.scene import fit_channel
from mcrt.grade.explain.surface_black import is_black
from mcrt.grade.feedback import fmt_values as _fmt

#: The albedos every wall is rendered with.
NODES = (0.0, 0.25, 0.5, 0.75, 1.0)
#: A fitted colour within this of a wall's (or the walls' mean), in every channel, is named as that one.
SAME = 0.05


def _prepare(a, scene, render) -> dict:
    """The renders of the room with every wall, and with every diffuse surface, of each albedo of :data:`NODES` (the
    module docstring)."""
    img = basis_renderer(a, render)

    def walls_of(v):
        walls = tuple(replace(w, albedo=(v, v, v)) for w in scene.room.walls)
        return replace(scene, room=replace(scene.room, walls=walls))

    def all_of(v):
        return remapped_reflectance(scene, lambda x: np.full(3, v))

    return {"nodes": np.asarray(NODES), "images": np.stack([img(walls_of(v)) for v in NODES]),
            "all": np.stack([img(all_of(v)) for v in NODES])}


def _which(colour: np.ndarray, walls: dict[str, tuple]) -> str:
    """Whose colour ``colour`` is, in words: a wall's, the walls' mean, or none (the module docstring)."""
    named = {f"{label}'s": np.asarray(c) for label, c in walls.items()}
    named["the walls' mean"] = np.mean([c for who, c in walls.items() if who.startswith("wall ")], axis=0)
    close = [(float(np.abs(colour - c).max()), who) for who, c in named.items()]
    gap, who = min(close)
    return f", {who} colour" if gap <= SAME else ""


def _fitted(fit: Fit, base: np.ndarray, xs: np.ndarray, imgs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(the colour, its change) fitted per channel on the renders ``imgs`` at albedos ``xs``."""
    colour, dm = np.zeros(3), np.zeros_like(base)
    for c in range(3):
        colour[c], dm[..., c] = fit_channel(fit, c, xs, imgs[..., c], base[..., c])
    return colour, dm


def walls_one_colour(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """Every wall of one albedo, and every diffuse surface of one albedo, fitted per channel (the module docstring)."""
    b = inputs.basis
    r = b.extra.get(walls_one_colour.name)
    colours = {label: v[1] for label, v in b.values.items() if isinstance(v, tuple) and len(v) == 2
               and v[0] == "albedo"}
    walls = {label: v for label, v in colours.items() if label.startswith("wall ")}
    if r is None or not walls:
        return []
    base = b.base.astype(np.float64)
    colour, dm = _fitted(fit, base, r["nodes"], r["images"].astype(np.float64))
    fam, text = "albedo", (f"every wall with the albedo {_fmt(colour)}{_which(colour, walls)}, where the scene gives "
                           f"the {len(walls)} walls their own colours (one colour read for all of them: a loop that "
                           "reads one wall's, a default, or their mean)")
    if is_black(colour):  # every wall black: missing, albedo 0 or facing away alike (as one wall's fit is worded)
        fam, text = "surface_black", ("every wall black: missing from the scene (nothing lies behind them in the "
                                      "closed room), with albedo 0, or with their normals facing away, so that "
                                      "one-sided shading (max(0, n.l)) gives 0 (check the list of walls, the "
                                      "triangles' winding, or flip each normal toward the incoming ray)")
    out = [Candidate(fam, "every wall one colour", text, fit.delta(dm), 3, value=tuple(colour), change=dm)]
    if "all" in r:
        colour, dm = _fitted(fit, base, r["nodes"], r["all"].astype(np.float64))
        text = (f"every diffuse surface (the walls, the floor, the ceiling, the objects) with the albedo {_fmt(colour)}"
                f"{_which(colour, colours)}, where the scene gives each its own colour (one colour for all of them: "
                "a default shared by every material, such as a mutable default argument, or one material for all)")
        out.append(Candidate("albedo", "every diffuse surface one colour", text, fit.delta(dm), 3, value=tuple(colour),
                             change=dm))
    return out


walls_one_colour.name, walls_one_colour.prepare = "walls_one_colour", _prepare
