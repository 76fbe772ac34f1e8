r"""The mirror's reflection computed wrongly: the 2 of d - 2 (d.n) n missing, the sphere's normal not unit length or
taken from the origin, a mirror bounce weighted by the cosine, every ray sent back the way it came, a path that meets
the mirror after its first hit ended.

Each changes what the mirror sphere shows, and the light it reflects onto
the room, in its own way (:func:`mcrt.bsdf.mistaken_mirror`). mcrt renders
each mistake of :data:`mcrt.options.MIRRORS` with the trick ``mirror``, for
a camera ray's first hit only (students often handle the mirror in the
camera's loop alone) and at every hit, at the basis's spp and seed, so that
the render minus the basis's shares its random numbers: the model image is
:math:`R + (B_m - B_0)`. No free parameter: the normal's length is the
sphere's radius, as ``p - c`` has.
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.grade.explain.tricks import best_change, rendered_changes
from mcrt.options import BOUNCE_AT, MIRRORS
from mcrt.scene import Mirror

#: Each mistake in the student's terms.
WORDS = {
    "without_2": "the mirror's reflection computed as d - (d.n) n, its 2 missing: the ray goes on along the surface",
    "normal_unnormalised": "the mirror sphere's normal p - c never divided by the radius: reflect(d, n) with n {r} "
                           "long turns the rays too far",
    "normal_from_origin": "the mirror sphere's normal taken as normalize(p), its centre never subtracted: the rays "
                          "reflected about the wrong normal",
    "cosine_weighted": "each mirror bounce weighted by the cosine, as a diffuse bounce is: the sphere darker towards "
                       "its rim",
    "backwards": "the mirror sending every ray back the way it came (reflect() returning -d, as a placeholder "
                 "left in): the sphere showing what lies behind the ray's origin",
    "camera_only": "the mirror handled for camera rays only: a path that meets it after a bounce ends there (the room "
                   "lit by no light the mirror reflects)",
}
#: What a reflected direction's mistake looks like too: a mirror shows only where its normals send the rays, so the
#: reflection's code, the normal at a hit and a surface that is not the sphere's (a coarse, scrambled or squashed mesh)
#: change what it shows alike, and the sphere's few dozen pixels at a hand-in's resolution cannot tell them apart.
NORMALS_ALIKE = ("or the sphere's own surface wrong (the normal at a hit, or a mesh that is not the sphere: facets, "
                 "scrambled or squashed vertices), which a mirror shows the same way: it reflects about its normals")
#: The mistakes that change the reflected direction (the others change its weight or where paths end).
DIRECTIONS = ("without_2", "normal_unnormalised", "normal_from_origin", "backwards")
#: Where the mistake applies, in the student's terms ('camera_only' says it itself).
AT_WORDS = {"every": ", at every mirror hit", "first": ", for the camera's rays (the mirror seen directly) only"}


def _radius(scene) -> float | None:
    """The radius of the scene's mirror sphere, None without one."""
    return next((float(o.radius) for o in scene.objects if isinstance(o.material, Mirror) and hasattr(o, "radius")),
                None)


def _prepare(a, scene, render) -> dict:
    """((mistake, where), its render minus the basis's) for every mistake and place (the module docstring)."""
    r = _radius(scene)
    if r is None:
        return {"radius": None, "changes": []}
    variants = [((how, at), {"mirror": how, "mirror_at": at, "mirror_normal_length": r})
                for how in MIRRORS if how not in ("reflect", "camera_only") for at in BOUNCE_AT]
    variants.append((("camera_only", "every"), {"mirror": "camera_only"}))
    return {"radius": r, "changes": rendered_changes(a, scene, render, variants)}


def mirror(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The mistaken mirror whose render fits best (the module docstring)."""
    r = inputs.basis.extra.get(mirror.name) or {}
    best = best_change(fit, r.get("changes"))
    if best is None:
        return []
    err, (how, at), change = best
    where = "" if how == "camera_only" else AT_WORDS[at]
    text = WORDS[how].format(r=f"{r['radius']:g}") + where + (f", {NORMALS_ALIKE}" if how in DIRECTIONS else "")
    fam = "mirror_normal" if how.startswith("normal_") else "material"
    return [Candidate(fam, "mirror computed wrongly", text, err, 0, value={"mirror": how, "at": at}, change=change)]


mirror.name, mirror.prepare = "mirror", _prepare
