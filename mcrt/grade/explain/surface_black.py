r"""A surface of the room black: missing from the scene, or of albedo 0 (the image cannot tell which).

The room is closed and nothing lies outside it, so a wall, the floor or the
ceiling left out of the scene (a list of surfaces one short, a face culled)
looks exactly like that surface with albedo 0: it reflects nothing, and no
light comes from behind it. The model image is the basis's render of the
surface at albedo 0 (:data:`mcrt.grade.explain.basis.ALBEDO_NODES` holds
0), with no free parameter, and its words name both causes. The objects are
not among them: an object left out shows what lies behind it (the
``object_missing`` candidates of :mod:`.scene`).
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.grade.feedback import fmt_values

#: Labels of the room's own surfaces in the basis (mcrt.grade.explain.basis._surface_edits).
ROOM = ("wall ", "the floor", "the ceiling")


def surface_black(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """Each surface of the room at albedo 0 (the module docstring)."""
    b = inputs.basis
    base = b.base.astype(np.float64)
    out = []
    for label, (nodes, imgs, scene_v) in b.albedo.items():
        zero = np.flatnonzero(np.asarray(nodes) == 0.0)
        if not label.startswith(ROOM) or zero.size == 0 or max(scene_v) <= 0.0:
            continue
        change = imgs[zero[0]].astype(np.float64) - base
        out.append(Candidate("surface_black", f"{label} black", f"{label} black: missing from the scene (nothing lies "
                             f"behind it in the closed room), or with albedo 0 where the scene says "
                             f"{fmt_values(scene_v)}", fit.delta(change), 0, value=label, change=change))
    return out


surface_black.name = "surface_black"
