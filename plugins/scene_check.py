"""What the estimator models, checked on a Mitsuba scene: one-line errors for everything else.

Accepted: shapes with BSDF ``diffuse``, ``twosided`` (around ``diffuse`` or a
perfect mirror) or ``conductor`` with Fresnel reflectance 1 (material
``none``); emitters of type ``area``; no participating media.
"""

from __future__ import annotations

from typing import Any

import mcrt  # noqa: F401  (sets DRJIT_LIBLLVM_PATH before drjit is imported)
import drjit as dr
import mitsuba as mi

# Class names of Mitsuba plugins -> their plugin names, for error messages.
_PLUGIN_NAMES = {
    "SmoothDiffuse": "diffuse", "TwoSidedBRDF": "twosided", "SmoothConductor": "conductor",
    "RoughConductor": "roughconductor", "SmoothDielectric": "dielectric", "RoughDielectric": "roughdielectric",
    "ThinDielectric": "thindielectric", "SmoothPlastic": "plastic", "RoughPlastic": "roughplastic",
    "PolarizedPlastic": "pplastic", "Principled": "principled", "PrincipledThin": "principledthin",
    "BlendBSDF": "blendbsdf", "MaskBSDF": "mask", "BumpMap": "bumpmap", "NormalMap": "normalmap",
    "Measured": "measured", "MeasuredPolarized": "measured_polarized", "Hair": "hair", "Null": "null",
    "AreaLight": "area", "PointLight": "point", "SpotLight": "spot", "DirectionalEmitter": "directional",
    "DirectionalArea": "directionalarea", "ConstantBackgroundEmitter": "constant",
    "EnvironmentMapEmitter": "envmap", "Projector": "projector", "SunskyEmitter": "sunsky",
}


def _plugin(obj) -> str:
    """'name' (ClassName) of a Mitsuba object for messages."""
    cls = obj.class_name()
    name = _PLUGIN_NAMES.get(cls)
    return f"'{name}' ({cls})" if name else f"{cls}"


def _params(obj) -> dict[str, Any]:
    return {k: v for k, v in mi.traverse(obj).items()}


def _is_perfect_mirror(params: dict[str, Any], prefix: str = "") -> bool:
    """A smooth conductor whose Fresnel term is 1: eta 0 and k 1 as constants (material 'none')."""
    eta, k = params.get(prefix + "eta.value"), params.get(prefix + "k.value")
    if eta is None or k is None:
        return False
    return bool(dr.all(dr.ravel(eta) == 0, axis=None)) and bool(dr.all(dr.ravel(k) == 1, axis=None))


def _check_bsdf(bsdf, where: str) -> None:
    cls = bsdf.class_name()
    flags = [int(bsdf.flags(i)) for i in range(bsdf.component_count())]
    F = mi.BSDFFlags
    diffuse = all((f & int(F.All)) == int(F.DiffuseReflection) for f in flags)
    delta = all((f & int(F.All)) == int(F.DeltaReflection) for f in flags)
    ok = False
    if cls == "SmoothDiffuse":
        ok = True
    elif cls == "SmoothConductor":
        ok = _is_perfect_mirror(_params(bsdf))
        if not ok:
            raise ValueError(
                f"mcrt integrator: {where} has a 'conductor' that is not a perfect mirror "
                f"(use material 'none': mcrt's mirror has no Fresnel term)"
            )
    elif cls == "TwoSidedBRDF":
        # The nested BSDFs are not reachable from Python; their components and
        # parameters are: only 'reflectance' (diffuse) or eta/k/specular_reflectance (mirror).
        params = _params(bsdf)
        if diffuse:
            ok = all(k.split(".", 1)[1].startswith("reflectance") for k in params)
        elif delta:
            ok = all(_is_perfect_mirror(params, f"brdf_{i}.") for i in (0, 1) if f"brdf_{i}.eta.value" in params) and any(
                k.endswith("eta.value") for k in params
            )
    if not ok:
        raise ValueError(
            f"mcrt integrator: {where} has BSDF {_plugin(bsdf)}, which mcrt's estimator does not model "
            f"(supported: 'diffuse', 'twosided' diffuse, 'conductor' with material 'none')"
        )


def check_scene(scene: "mi.Scene") -> None:
    """Raise a one-line ``ValueError`` unless ``scene`` holds only what mcrt's estimator models.

    Accepted: shapes with BSDF ``diffuse``, ``twosided`` (around ``diffuse``
    or a perfect mirror) or ``conductor`` with Fresnel reflectance 1
    (material ``none``); emitters of type ``area``; no participating media.
    The message names the offending plugin and shape.
    """
    for shape in scene.shapes():
        where = f"shape '{shape.id()}'"
        if shape.is_medium_transition():
            raise ValueError(f"mcrt integrator: {where} bounds a participating medium, which mcrt's estimator does not model")
        bsdf = shape.bsdf()
        if bsdf is not None:
            _check_bsdf(bsdf, where)
    for emitter in scene.emitters():
        if emitter.class_name() != "AreaLight":
            raise ValueError(
                f"mcrt integrator: emitter '{emitter.id()}' is of type {_plugin(emitter)}; "
                f"mcrt's estimator supports only 'area' emitters"
            )
