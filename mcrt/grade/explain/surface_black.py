r"""A surface black: missing from the scene, of albedo 0, or shaded on its back (the image cannot tell which).

A surface that sends no light to the camera is black whatever the reason,
and the image alone cannot say which reason it is:

* its albedo (or a mirror's reflectance) is 0;
* its normals face away from the light and the camera (triangles wound the
  other way, a normal not flipped toward the incoming ray), so that
  one-sided shading, :math:`\max(0, n \cdot l)`, gives 0 at every hit;
* for a surface of the room, it is missing: the room is closed and nothing
  lies outside it, so a wall, the floor or the ceiling left out of the scene
  (a list of surfaces one short, a face culled) reflects nothing and no
  light comes from behind it. An *object* left out is not black: what lies
  behind it shows (the ``object_missing`` candidates of :mod:`.scene`).

Every face of the room black at once (its corners taken in the other
order, so that every face's normal points out) is rendered too, with the
objects as they are.

So every family that can predict a black surface words it as one statement
naming every cause (:func:`black_words`), under one family name
(:func:`black_family`): this module's candidates (each surface of the room
at albedo 0: the basis's render at albedo 0,
:data:`mcrt.grade.explain.basis.ALBEDO_NODES` holds 0, with no free
parameter), the albedo or reflectance family where its fitted value is
:data:`BLACK` or less in every channel (:func:`mcrt.grade.explain.scene.albedo`),
and the material family at reflectance or albedo 0
(:func:`mcrt.grade.explain.objects.material`).
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.grade.feedback import fmt_values

#: Labels of the room's own surfaces in the basis (mcrt.grade.explain.basis._surface_edits).
ROOM = ("wall ", "the floor", "the ceiling")
#: A fitted albedo or reflectance at most this in every channel is the surface black (the albedo family's grid
#: steps by 0.01, the material family's by 0.025: the first node above 0 of either is not black).
BLACK = 0.02


def is_room(label: str) -> bool:
    """Whether ``label`` ('wall BC', 'the floor', 'the tetrahedron') is a surface of the closed room."""
    return label.startswith(ROOM)


def is_black(values) -> bool:
    """Whether a fitted albedo or reflectance (one value per channel) is black in every channel."""
    return bool(np.all(np.asarray(values, np.float64) <= BLACK))


def black_family(label: str) -> str:
    """The family a black reading of ``label`` belongs to: 'surface_black' for the room's surfaces (missing is among
    its causes), 'object_black' for an object (an object missing shows what lies behind it)."""
    return "surface_black" if is_room(label) else "object_black"


def black_words(label: str, scene_values, word: str = "albedo") -> str:
    """One clause, to follow "It looks like", naming every cause of ``label`` black (the module docstring);
    ``word`` is what the scene sets ('albedo', or 'reflectance' for a mirror), ``scene_values`` its value."""
    missing = "missing from the scene (nothing lies behind it in the closed room), " if is_room(label) else ""
    return (f"{label} black: {missing}with {word} 0 where the scene says {fmt_values(scene_values)}, or with its "
            "normals facing away, so that one-sided shading (max(0, n.l)) gives 0 (check the triangles' winding, "
            "or flip each normal toward the incoming ray)")


def surface_black(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """Each surface of the room at albedo 0 (the module docstring)."""
    b = inputs.basis
    base = b.base.astype(np.float64)
    out = []
    for label, (nodes, imgs, scene_v) in b.albedo.items():
        zero = np.flatnonzero(np.asarray(nodes) == 0.0)
        if not is_room(label) or zero.size == 0 or max(scene_v) <= 0.0:
            continue
        change = imgs[zero[0]].astype(np.float64) - base
        out.append(Candidate("surface_black", f"{label} black", black_words(label, scene_v), fit.delta(change), 0,
                             value=label, change=change))
    room = b.extra.get(surface_black.name)
    if room is not None and room.shape == base.shape:
        change = room.astype(np.float64) - base
        out.append(Candidate("surface_black", "the room black", ROOM_WORDS, fit.delta(change), 0, value="room",
                             change=change))
    return out


#: Every face of the room black at once, in words (one clause, to follow "It looks like").
ROOM_WORDS = ("every face of the room (the walls, the floor and the ceiling) black: their normals facing out of the "
              "room, so that one-sided shading (max(0, n.l)) gives 0 (the room's corners taken in the other order, "
              "or a test of their orientation of the wrong sign), or their albedo 0; the light and the objects lit "
              "by it alone")


def _prepare(a, scene, render) -> np.ndarray:
    """The render with every face of the room at albedo 0 (the objects as they are), at the basis's spp and seed."""
    from dataclasses import replace

    from mcrt.grade.explain.basis import basis_renderer

    room, black = scene.room, (0.0, 0.0, 0.0)
    room = replace(room, floor_albedo=black, ceiling_albedo=black,
                   walls=tuple(replace(w, albedo=black) for w in room.walls))
    return basis_renderer(a, render)(replace(scene, room=room))


surface_black.name, surface_black.prepare = "surface_black", _prepare
