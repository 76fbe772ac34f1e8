"""The stated perturbations of the suite's power study, applied to a loaded scene's parameters.

Each finds its parameter in ``mi.traverse(scene)`` (or the integrator's
depth), changes it, and undoes the change afterwards; a scene without such a
parameter gives ``None`` (not applicable, reported as such).

* ``emitter x1.02``: every emitter's radiance, intensity or irradiance (an
  environment map's ``scale``) times 1.02;
* ``fov x1.005``: the sensor's field of view times 1.005;
* ``max depth - 1``: the integrator's ``max_depth`` one less (where it is
  bounded and at least 2);
* ``BSDF x0.98``: the first reflectance-like BSDF parameter (in the order
  the scene lists them) times 0.98;
* ``emitter x1.005`` and ``BSDF x0.995``: the same, four times subtler (where
  the two tests part).
"""

from __future__ import annotations

import re
from contextlib import contextmanager

_EMITTER = re.compile(r"\.(radiance|intensity|irradiance)\.(value|data)$")
_BSDF = re.compile(r"(^|\.)(reflectance|diffuse_reflectance|specular_reflectance|base_color|color0)\.(value|data)$")

PERTURBATIONS = {
    "emitter x1.02": "every emitter's radiance (intensity, irradiance, environment map scale) times 1.02",
    "fov x1.005": "the camera's field of view times 1.005",
    "max depth - 1": "the integrator's max_depth one less",
    "BSDF x0.98": "a BSDF's reflectance-like parameter (the first the scene lists) times 0.98",
    "emitter x1.005": "every emitter's radiance times 1.005 (subtler than the issue's list)",
    "BSDF x0.995": "the same BSDF parameter times 0.995 (subtler than the issue's list)",
}

#: What each perturbation multiplies its parameters by (the depth is lowered instead).
FACTORS = {"emitter x1.02": 1.02, "fov x1.005": 1.005, "BSDF x0.98": 0.98, "emitter x1.005": 1.005, "BSDF x0.995": 0.995}


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
    if name == "fov x1.005":
        return [k for k in keys if k.endswith("x_fov")]
    if name.startswith("BSDF"):
        found = [k for k in keys if _BSDF.search(k) and not _EMITTER.search(k) and "emitter" not in k
                 and "opacity" not in k]
        found = found or [k for k in keys if k.endswith(("face_color", "vertex_color"))]
        return found[:1]
    raise ValueError(f"unknown perturbation {name!r} (have {', '.join(PERTURBATIONS)})")


@contextmanager
def perturbed(mi, scene, name: str, max_depth: int):
    """Within the block the scene is perturbed; yields ``(what changed, max_depth to render with)`` or None.

    ``max_depth`` is the depth of the integrator the suite renders (-1:
    unbounded or none).
    """
    if name == "max depth - 1":
        yield (f"max_depth {max_depth} -> {max_depth - 1}", max_depth - 1) if max_depth >= 2 else None
        return
    params = mi.traverse(scene)
    keys = _keys(params, name)
    if not keys:
        yield None
        return
    factor = FACTORS[name]
    old = {k: params[k] for k in keys}
    try:
        for k in keys:
            params[k] = old[k] * factor
        params.update()
        yield ", ".join(sorted({_short(k) for k in keys})) + f" x{factor:g}", None
    finally:
        for k in keys:
            params[k] = old[k]
        params.update()
