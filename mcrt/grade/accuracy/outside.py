r"""A second class of hand-ins: mistakes made outside the scene file.

The first class (:mod:`mcrt.grade.accuracy.cases`) edits the scene the way a
student's tracer gets it wrong. Here the scene is right and the program is
not: it post-processes the image (a tone map, a clamp), writes the file
wrongly (channels in BGR order), renders a material of its own (a diffuse or
glossy sphere, a mirror tetrahedron), uses another camera model (rays
weighted by a power of their cosine) or light model (a point light, the
radiance divided by pi), renders at another resolution and enlarges the
image, gets an object's size wrong, or claims more samples per pixel than it
took. Every image comes from **Mitsuba** (edited scene dicts, or correct
renders post-processed with NumPy and SciPy as a student's program would),
never from the grader's own families.

Which cases are **held out** was decided when the class was written, before
any was graded: about half of each cause, marked ``held_out=True`` below.
"""

from __future__ import annotations

import math
from dataclasses import replace
from functools import partial

import numpy as np

from mcrt.grade.accuracy.cases import Spec
from mcrt.scene import Scene

#: The causes of this class, as the report words them.
CAUSES: dict[str, str] = {
    "tone_map": "a tone map, clamp or curve applied before saving",
    "channels": "colour channels written in the wrong order",
    "material": "an object rendered with another material",
    "falloff": "a camera model that weights rays (a fall-off across the image)",
    "light_model": "another light model (a point light)",
    "light_radiance": "the light's radiance (or a constant factor)",
    "resampling": "rendered at a lower resolution and enlarged",
    "object_size": "an object's size",
    "spp_claim": "fewer samples per pixel than declared",
}


# --------------------------------------------------------------------------
# Post-processing as a student's program does it (on the linear render)
# --------------------------------------------------------------------------


def _reinhard(x, exposure: float = 1.0):
    x = exposure * np.maximum(x, 0.0)
    return x / (1.0 + x)


def _aces(x):
    x = np.maximum(x, 0.0)
    return np.clip(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0)


def _clamp(x):
    return np.clip(x, 0.0, 1.0)


def _bgr(x):
    return x[..., ::-1]


def _cos_power(x, k: float, fov_deg: float = 90.0):
    """Each pixel multiplied by cos^k of its ray's angle to the view axis (square pixels, horizontal fov)."""
    h, w = x.shape[:2]
    t = math.tan(math.radians(fov_deg) / 2)
    yy, xx = np.mgrid[0:h, 0:w]
    sx, sy = ((xx + 0.5) / w * 2 - 1) * t, (1 - (yy + 0.5) / h * 2) * t * h / w
    return x * (1.0 / np.sqrt(1 + sx * sx + sy * sy))[..., None] ** k


def _nearest(x, k: int):
    return np.repeat(np.repeat(x, k, axis=0), k, axis=1)


def _bilinear(x, k: int):
    from scipy.ndimage import zoom

    return zoom(x, (k, k, 1), order=1, mode="nearest", grid_mode=True)


#: Post-processes by name (:attr:`mcrt.grade.accuracy.cases.Spec.post`): linear render in, what the file holds out.
POSTS = {
    "reinhard": _reinhard,
    "reinhard_exp2": partial(_reinhard, exposure=2.0),
    "aces": _aces,
    "clamp": _clamp,
    "bgr": _bgr,
    "cos4": partial(_cos_power, k=4.0),
    "cos1": partial(_cos_power, k=1.0),
    "nearest2": partial(_nearest, k=2),
    "bilinear2": partial(_bilinear, k=2),
    "nearest4": partial(_nearest, k=4),
}


# --------------------------------------------------------------------------
# Mitsuba scene dicts edited (materials, light models); scene edits (sizes)
# --------------------------------------------------------------------------


def _sphere_bsdf(d: dict, bsdf: dict) -> dict:
    d = dict(d)
    d["sphere"] = dict(d["sphere"], bsdf=bsdf)
    return d


def _posted(name: str) -> dict:
    """The Spec fields of a post-process of :data:`POSTS`: its name (for the report) and its function."""
    return {"post": name, "post_fn": POSTS[name]}


def _material(s: Scene, name: str, material) -> Scene:
    return replace(s, objects=tuple(replace(o, material=material) if o.name == name else o for o in s.objects))


def _dark_light(s: Scene) -> Scene:
    """The light's rectangle kept, emitting nothing (a point light replaces it: :func:`_point_light`)."""
    return replace(s, light=replace(s.light, radiance=(0.0, 0.0, 0.0)))


def _point_light(d: dict, center, radiance, area: float) -> dict:
    """A point light at the light's centre emitting the area light's power (added to the Mitsuba dict)."""
    # A one-sided Lambertian emitter of radiance L and area A emits pi L A; a point light of intensity I emits 4 pi I.
    intensity = [float(c) * area / 4.0 for c in radiance]
    below = [float(center[0]), float(center[1]), float(center[2]) - 1e-3]
    return dict(d, point_light={"type": "point", "position": below, "intensity": {"type": "rgb", "value": intensity}})


def _scaled_object(s: Scene, name: str, f: float) -> Scene:
    out = []
    for o in s.objects:
        if o.name == name and hasattr(o, "radius"):
            o = replace(o, radius=o.radius * f)
        elif o.name == name:
            c = np.mean(o.vertices, axis=0)
            o = replace(o, vertices=tuple(tuple(float(x) for x in c + f * (np.asarray(v) - c)) for v in o.vertices))
        out.append(o)
    return replace(s, objects=tuple(out))


def _radiance_over_pi(s: Scene) -> Scene:
    return replace(s, light=replace(s.light, radiance=tuple(x / math.pi for x in s.light.radiance)))


def _light_args():
    from mcrt.scene import load_scene

    lt = load_scene().light
    return {"center": tuple(lt.center), "radiance": tuple(lt.radiance), "area": float(lt.size[0] * lt.size[1])}


def _specs() -> tuple[Spec, ...]:
    from mcrt.scene import Lambertian, Mirror

    glossy = {"type": "roughconductor", "material": "none", "alpha": 0.15}
    return (
        # Post-processing and file writing
        Spec("tm_reinhard", "tone_map", **_posted("reinhard"),
             truth="Reinhard's x/(1+x) applied before writing the EXR"),
        Spec("tm_reinhard_exp2", "tone_map", held_out=True, **_posted("reinhard_exp2"),
             truth="exposure 2 then Reinhard's x/(1+x), written as EXR"),
        Spec("tm_aces", "tone_map", held_out=True, **_posted("aces"),
             truth="the ACES filmic curve applied before writing the EXR"),
        Spec("tm_clamp", "tone_map", **_posted("clamp"), truth="values clamped to [0, 1] before writing the EXR"),
        Spec("tm_reinhard_png", "tone_map", held_out=True, **_posted("reinhard"), file="png-srgb",
             truth="Reinhard's x/(1+x), then an sRGB 8-bit PNG"),
        Spec("bgr_exr", "channels", **_posted("bgr"), truth="channels written in BGR order (an EXR)"),
        Spec("bgr_png", "channels", held_out=True, **_posted("bgr"), file="png-srgb",
             truth="channels written in BGR order (an sRGB PNG, as OpenCV writes them)"),
        # Materials
        Spec("sphere_diffuse", "material", True,
             edit=partial(_material, name="sphere", material=Lambertian((0.8, 0.8, 0.8))),
             truth="the mirror sphere rendered as a white diffuse surface (albedo 0.8)"),
        Spec("sphere_grey", "material", True, held_out=True,
             edit=partial(_material, name="sphere", material=Lambertian((0.5, 0.5, 0.5))),
             truth="the mirror sphere rendered as a grey diffuse surface (albedo 0.5)"),
        Spec("sphere_glossy", "material", True, held_out=True, mitsuba_edit=partial(_sphere_bsdf, bsdf=glossy),
             truth="the mirror sphere rendered glossy (a rough conductor, alpha 0.15)"),
        Spec("tetra_mirror", "material", True, edit=partial(_material, name="tetrahedron", material=Mirror()),
             truth="the tetrahedron rendered as a mirror"),
        # Camera models
        Spec("cos4", "falloff", **_posted("cos4"),
             truth="each pixel weighted by cos^4 of its ray's angle (a lens fall-off)"),
        Spec("cos1", "falloff", held_out=True, **_posted("cos1"),
             truth="each pixel weighted by the cosine of its ray's angle"),
        # Light models
        Spec("point_light", "light_model", True, edit=_dark_light,
             mitsuba_edit=partial(_point_light, **_light_args()),
             truth="a point light of the same power at the light's centre"),
        Spec("radiance_over_pi", "light_radiance", True, held_out=True, edit=_radiance_over_pi,
             truth="the light's radiance divided by pi (radiance taken for power per area)"),
        # Resolution
        Spec("nearest2", "resampling", render_scale=2, **_posted("nearest2"),
             truth="rendered at half the resolution, enlarged 2x by repeating pixels"),
        Spec("bilinear2", "resampling", held_out=True, render_scale=2, **_posted("bilinear2"),
             truth="rendered at half the resolution, enlarged 2x bilinearly"),
        Spec("nearest4", "resampling", held_out=True, render_scale=4, **_posted("nearest4"),
             truth="rendered at a quarter of the resolution, enlarged 4x by repeating pixels"),
        # Object sizes
        Spec("sphere_small", "object_size", True, edit=partial(_scaled_object, name="sphere", f=0.9),
             truth="the sphere's radius 0.9 times the scene's"),
        Spec("sphere_large", "object_size", True, held_out=True, edit=partial(_scaled_object, name="sphere", f=1.1),
             truth="the sphere's radius 1.1 times the scene's"),
        Spec("tetra_small", "object_size", True, held_out=True,
             edit=partial(_scaled_object, name="tetrahedron", f=0.85),
             truth="the tetrahedron 0.85 times its size (about its centroid)"),
        # Claimed samples per pixel
        Spec("claims_1024", "spp_claim", spp=64, declared_spp=1024, truth="64 spp rendered, 1024 declared"),
        Spec("claims_256", "spp_claim", held_out=True, spp=16, declared_spp=256, truth="16 spp rendered, 256 declared"),
        # Correct hand-ins
        Spec("ok_path_256", None, spp=256, truth="Mitsuba path, 256 spp, EXR"),
        Spec("ok_strat_128", None, spp=128, sampler="stratified", truth="Mitsuba path, stratified, 128 spp"),
        Spec("ok_png_1024", None, spp=1024, file="png-srgb", held_out=True,
             truth="Mitsuba path 1024 spp as an sRGB PNG"),
        Spec("ok_mcrt_64", None, spp=64, renderer="mcrt", held_out=True, truth="mcrt, 64 spp"),
    )


#: The class (built once; each edit is a partial of a module-level function, so that cases pickle).
SPECS: tuple[Spec, ...] = _specs()
