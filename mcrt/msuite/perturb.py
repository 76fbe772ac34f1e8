"""The stated perturbations of the suite's power study, applied to a loaded scene's parameters.

Each finds its parameter in ``mi.traverse(scene)`` (or the integrator's
depth), changes it, and undoes the change afterwards; a scene without such a
parameter gives ``None`` (not applicable, reported as such).

The issue's four, at its sizes:

* ``emitter x1.02``: every emitter's radiance, intensity or irradiance (an
  environment map's ``scale``) times 1.02;
* ``fov x1.005``: the sensor's field of view times 1.005;
* ``max depth - 1``: the integrator's ``max_depth`` one less (where it is
  bounded and at least 2);
* ``BSDF x0.98``: the first reflectance-like parameter of the first
  shape's BSDF (shapes by bounding box, lowest corner first) times 0.98.

At those sizes both tests catch nearly everything on these low-noise scenes,
so power is compared on a ladder fixed before any result was seen
(:data:`LADDER`): each multiplicative kind at its issue size and at 1/4, 1/16
and 1/64 of its deviation from 1 (emitter x1.02, x1.005, x1.00125,
x1.0003125; ...). The depth has one size.
"""

from __future__ import annotations

import re
from contextlib import contextmanager

_EMITTER = re.compile(r"\.(radiance|intensity|irradiance)\.(value|data)$")
_BSDF = re.compile(r"(^|\.)(reflectance|diffuse_reflectance|specular_reflectance|base_color|color0)\.(value|data)$")

#: The multiplicative kinds: (the issue's factor, what it changes).
KINDS = {
    "emitter": (1.02, "every emitter's radiance (intensity, irradiance, environment map scale)"),
    "fov": (1.005, "the camera's field of view"),
    "BSDF": (0.98, "a BSDF's reflectance-like parameter (the first of the first shape by bounding box, lowest corner first)"),
}
#: Each kind's deviation from 1 is divided by these: the issue's size and three subtler ones, fixed in advance.
LADDER = (1, 4, 16, 64)
DEPTH = "max depth - 1"


def factor_name(kind: str, rung: int) -> str:
    """``'emitter x1.005'``: the kind at its issue deviation divided by ``rung``."""
    return f"{kind} x{1 + (KINDS[kind][0] - 1) / rung:.10g}"


#: What each perturbation multiplies its parameters by (the depth is lowered instead).
FACTORS = {factor_name(k, r): 1 + (f - 1) / r for k, (f, _) in KINDS.items() for r in LADDER}
#: The issue's four, at its sizes, in its order.
ISSUE = (factor_name("emitter", 1), factor_name("fov", 1), DEPTH, factor_name("BSDF", 1))
#: Every perturbation rendered: the issue's four, then the subtler rungs of the ladder, kind by kind.
PERTURBATIONS = {
    **{name: (f"{KINDS[name.split()[0]][1]} times {FACTORS[name]:.10g}" if name != DEPTH
              else "the integrator's max_depth one less") for name in ISSUE},
    **{factor_name(k, r): f"{KINDS[k][1]} times {FACTORS[factor_name(k, r)]:.10g} (1/{r} of the issue's deviation)"
       for k in KINDS for r in LADDER[1:]},
}


def _short(key: str) -> str:
    """A parameter key without Mitsuba's generated object ids (``object_1399...``)."""
    return re.sub(r"object_\d+\.?", "", key) or key


def _keys(params, name: str) -> list[str]:
    keys = list(params.keys())
    if name.startswith("emitter"):
        found = [k for k in keys if _EMITTER.search(k)]
        # An environment map has no radiance parameter: its scale (a texture's 'scale' has no 'data' beside it).
        found += [k for k in keys if k.endswith(".scale") and f"{k[:-6]}.data" in params
                  and not any(f.startswith(k[:-6] + ".") for f in found)]
        return found
    if name.startswith("fov"):
        return [k for k in keys if k.endswith("x_fov")]
    raise ValueError(f"unknown perturbation {name!r} (have {', '.join(PERTURBATIONS)})")


def _bsdf_target(mi, scene):
    """``(params, [key], prefix)``: the first reflectance-like parameter of the first shape's BSDF, else the first
    shape's face or vertex colour; ``(None, [], '')`` if none. Emitters' shapes are left out.

    "First" in a fixed order: shapes by their bounding box (lowest corner x, y, z, then the highest), a BSDF's
    parameters as it lists them. Neither the scene's shape list (shapes load in parallel) nor its parameter list
    (keyed by generated object ids, memory addresses) keeps one order from run to run.
    """
    def corners(sh):
        box = sh.bbox()
        return tuple(float(v) for v in (*box.min, *box.max))

    shapes = sorted((sh for sh in scene.shapes() if not sh.is_emitter()), key=corners)
    for sh in shapes:
        if sh.bsdf() is None:
            continue
        params = mi.traverse(sh.bsdf())
        keys = [k for k in params.keys() if _BSDF.search(k) and "opacity" not in k]
        if keys:
            return params, keys[:1], "bsdf."
    for sh in shapes:
        params = mi.traverse(sh)
        keys = [k for k in params.keys() if k.endswith(("face_color", "vertex_color"))]
        if keys:
            return params, keys[:1], "shape."
    return None, [], ""


@contextmanager
def perturbed(mi, scene, name: str, max_depth: int):
    """Within the block the scene is perturbed; yields ``(what changed, max_depth to render with)`` or None.

    ``max_depth`` is the depth of the integrator the suite renders (-1:
    unbounded or none).
    """
    if name == DEPTH:
        yield (f"max_depth {max_depth} -> {max_depth - 1}", max_depth - 1) if max_depth >= 2 else None
        return
    if name.startswith("BSDF"):
        params, keys, prefix = _bsdf_target(mi, scene)
    else:
        params, prefix = mi.traverse(scene), ""
        keys = _keys(params, name)
    if not keys:
        yield None
        return
    import drjit as dr

    factor = FACTORS[name]
    # Copies: a parameter is assigned in place, so the object params[k] returns would take the new value too and
    # the change would never be undone (every later render of the scene perturbed).
    old = {k: dr.copy(params[k]) for k in keys}
    try:
        for k in keys:
            params[k] = old[k] * factor
        params.update()
        yield ", ".join(sorted({prefix + _short(k) for k in keys})) + f" x{factor:g}", None
    finally:
        for k in keys:
            params[k] = old[k]
        params.update()
