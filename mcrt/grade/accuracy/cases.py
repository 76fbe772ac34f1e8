r"""A class of realistic hand-ins for measuring the grader, built without mcrt's mutants.

Every wrong render is a **Mitsuba** render of the scene changed as a
student's tracer changes it (:data:`MISTAKES`): the camera (field of view,
rotation, eye, pixel-centre offset), the geometry (an object missing or
moved), a material (a wall's colour), the light (radiance, position, size,
not seen by the camera), the path depth, a post-process (blur, denoising) or
the encoding of the file. Correct renders (:data:`CORRECT`) come from mcrt
and from Mitsuba's ``path`` and ``volpath`` integrators with its
``independent``, ``stratified``, ``ldsampler`` and ``multijitter`` samplers,
at 16 to 1024 spp, as EXR or as 8-bit PNGs in the common encodings.

Each case says what a grader should conclude (:class:`Case`): the cause
(a key of :data:`CAUSES`, ``None`` for a correct render), whether a TA would
call the mistake major, and whether it is **held out**: held-out cases were
not looked at while the diagnosis and the detection were tuned, and the
report gives their rates apart.

Seeds are fixed per case (:func:`build_class`), so the class is the same
bit for bit on the same machine.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path
from typing import Callable

import numpy as np

from mcrt.image_files import srgb_oetf
from mcrt.scene import Scene

#: The causes a wrong render can have, as the report words them.
CAUSES: dict[str, str] = {
    "camera_fov": "the camera's field of view",
    "camera_rotation": "the camera's rotation (forward or up vector)",
    "camera_eye": "the camera's eye position",
    "pixel_offset": "the pixel centres (the image shifted by a fraction of a pixel)",
    "object_missing": "an object missing",
    "object_moved": "an object moved",
    "albedo": "a surface's colour",
    "light_radiance": "the light's radiance (or a constant factor)",
    "light_position": "the light's position",
    "light_size": "the light's size",
    "light_hidden": "the light not seen directly",
    "depth": "the path depth",
    "blur": "a blur or denoiser after rendering",
    "encoding": "the values' encoding (a display curve, or a PNG's curve undeclared)",
}


@dataclass(frozen=True)
class Spec:
    """One hand-in of the class, before rendering (see the module docstring)."""

    name: str
    cause: str | None  # a key of CAUSES; None: a correct render
    major: bool = False
    held_out: bool = False
    spp: int = 256
    edit: Callable[[Scene], Scene] | None = None  # a change of the scene
    renderer: str = "mitsuba"  # 'mitsuba' (a Mitsuba scene dict) or 'mcrt'
    integrator: str = "path"
    sampler: str = "independent"
    max_depth: int | None = None  # None: the assignment's
    sensor: dict = field(default_factory=dict)  # entries of the Mitsuba sensor that change
    hide_emitters: bool = False
    post: str | None = None  # 'blur', 'denoise', another post-process's name (post_fn), or None
    post_fn: Callable[[np.ndarray], np.ndarray] | None = None  # a post-process other than blur and denoise
    file: str = "exr"  # 'exr', or 'png-srgb', 'png-gamma2.2', 'png-gamma2', 'png-linear', 'exr-srgb', 'exr-gamma2'
    truth: str = ""  # the mistake in words, for the report
    mitsuba_edit: Callable[[dict], dict] | None = None  # a change of the Mitsuba scene dict (a material, a light)
    render_scale: int = 1  # rendered at 1/render_scale of the resolution (a post then enlarges it)
    declared_spp: int | None = None  # the spp the manifest claims, when not the rendered one
    writer: Callable[[np.ndarray, Path], Path] | None = None  # writes the image file as a student's program does
    manifest: str = ""  # more lines of the manifest (TOML), e.g. "linear = true\n"


@dataclass
class Case:
    """A rendered hand-in: the linear image (grade resolution), its per-sample variance, and what it should get."""

    spec: Spec
    image: np.ndarray  # (H, W, 3) linear radiance as the student's tracer computed it (before the file encoding)
    variance: np.ndarray  # (H, W, 3) per-sample variance
    spp: int
    seed: int

    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def cause(self) -> str | None:
        return self.spec.cause

    @property
    def major(self) -> bool:
        return self.spec.major

    @property
    def held_out(self) -> bool:
        return self.spec.held_out


# --------------------------------------------------------------------------
# Scene edits
# --------------------------------------------------------------------------


def _camera(scene: Scene, **changes) -> Scene:
    cams = dict(scene.cameras)
    c = cams["near"]
    cams["near"] = replace(c, **changes)
    return replace(scene, cameras=cams)


def _rotate(v, axis, deg):
    """v rotated about ``axis`` by ``deg`` degrees (Rodrigues)."""
    v, k = np.asarray(v, float), np.asarray(axis, float) / np.linalg.norm(axis)
    t = math.radians(deg)
    return tuple(float(x) for x in v * math.cos(t) + np.cross(k, v) * math.sin(t) + k * (k @ v) * (1 - math.cos(t)))


# Each edit is a partial of a module-level function, so that cases pickle (worker processes, caches).


def _fov(s: Scene, deg: float) -> Scene:
    return _camera(s, fov_x_deg=deg)


def _yaw(s: Scene, deg: float) -> Scene:
    """The camera turned left (positive) about the vertical."""
    return _camera(s, forward=_rotate(s.cameras["near"].forward, (0, 0, 1), deg))


def _pitch(s: Scene, deg: float) -> Scene:
    """The camera tilted up (positive)."""
    c = s.cameras["near"]
    right = np.cross(c.forward, c.up)
    return _camera(s, forward=_rotate(c.forward, right, deg), up=_rotate(c.up, right, deg))


def _roll(s: Scene, deg: float) -> Scene:
    return _camera(s, up=_rotate(s.cameras["near"].up, s.cameras["near"].forward, deg))


def _eye(s: Scene, d: tuple[float, float, float]) -> Scene:
    return _camera(s, eye=tuple(float(a + b) for a, b in zip(s.cameras["near"].eye, d)))


def _without(s: Scene, name: str) -> Scene:
    return replace(s, objects=tuple(o for o in s.objects if o.name != name))


def _moved(s: Scene, name: str, d: tuple[float, float, float]) -> Scene:
    out = []
    for o in s.objects:
        if o.name == name and hasattr(o, "center"):
            o = replace(o, center=tuple(float(a + b) for a, b in zip(o.center, d)))
        elif o.name == name:
            o = replace(o, vertices=tuple(tuple(float(a + b) for a, b in zip(v, d)) for v in o.vertices))
        out.append(o)
    return replace(s, objects=tuple(out))


def _wall_albedo(s: Scene, corners: str, albedo) -> Scene:
    walls = tuple(replace(w, albedo=tuple(albedo)) if "".join(w.corners) == corners else w for w in s.room.walls)
    return replace(s, room=replace(s.room, walls=walls))


def _floor_albedo(s: Scene, albedo) -> Scene:
    return replace(s, room=replace(s.room, floor_albedo=tuple(albedo)))


def _light(s: Scene, move=(0.0, 0.0, 0.0), **changes) -> Scene:
    lt = s.light
    changes.setdefault("center", tuple(float(a + b) for a, b in zip(lt.center, move)))
    return replace(s, light=replace(lt, **changes))


def fov(deg: float):
    return partial(_fov, deg=deg)


def yaw(deg: float):
    return partial(_yaw, deg=deg)


def pitch(deg: float):
    return partial(_pitch, deg=deg)


def roll(deg: float):
    return partial(_roll, deg=deg)


def eye(dx: float = 0.0, dy: float = 0.0, dz: float = 0.0):
    return partial(_eye, d=(dx, dy, dz))


def without(name: str):
    return partial(_without, name=name)


def moved(name: str, d: tuple[float, float, float]):
    return partial(_moved, name=name, d=d)


def wall_albedo(corners: str, albedo):
    return partial(_wall_albedo, corners=corners, albedo=albedo)


def floor_albedo(albedo):
    return partial(_floor_albedo, albedo=albedo)


def light(**changes):
    return partial(_light, **changes)


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: Wrong hand-ins (a TA's judgement in ``major``); the held-out ones were never used for tuning.
MISTAKES: tuple[Spec, ...] = (
    Spec("fov_95", "camera_fov", True, edit=fov(95.0), truth="field of view 95 degrees instead of 90"),
    Spec("fov_87", "camera_fov", True, held_out=True, edit=fov(87.0), truth="field of view 87 degrees instead of 90"),
    Spec("yaw_2deg", "camera_rotation", True, edit=yaw(2.0), truth="camera turned 2 degrees to the left"),
    Spec("pitch_1deg", "camera_rotation", True, held_out=True, edit=pitch(-1.0), truth="camera tilted 1 degree down"),
    Spec("roll_3deg", "camera_rotation", True, held_out=True, edit=roll(3.0), truth="camera rolled 3 degrees"),
    Spec("eye_forward", "camera_eye", True, edit=eye(dx=0.3), truth="eye 0.3 forward of where the scene puts it"),
    Spec("pixel_offset", "pixel_offset", True, sensor={"principal_point_offset_x": 0.5 / 64, "principal_point_offset_y": 0.5 / 64},
         truth="pixel centres at the corner (i/W instead of (i+0.5)/W): the image shifted by half a pixel"),
    Spec("no_tetrahedron", "object_missing", True, edit=without("tetrahedron"), truth="the tetrahedron missing"),
    Spec("no_sphere", "object_missing", True, held_out=True, edit=without("sphere"), truth="the mirror sphere missing"),
    Spec("tetra_moved", "object_moved", True, edit=moved("tetrahedron", (0.0, 1.0, 0.0)), truth="tetrahedron moved 1 along +y"),
    Spec("sphere_moved", "object_moved", True, held_out=True, edit=moved("sphere", (-1.0, 0.0, 0.0)),
         truth="sphere moved 1 towards the camera"),
    Spec("wall_DE_swapped", "albedo", True, edit=wall_albedo("DE", (0.75, 0.20, 0.15)),
         truth="wall DE albedo (0.75, 0.20, 0.15) instead of (0.15, 0.20, 0.75): channels reversed"),
    Spec("wall_EF_blue", "albedo", True, held_out=True, edit=wall_albedo("EF", (0.15, 0.20, 0.75)),
         truth="wall EF albedo (0.15, 0.20, 0.75) instead of (0.15, 0.70, 0.15)"),
    Spec("floor_dark", "albedo", True, held_out=True, edit=floor_albedo((0.4, 0.4, 0.4)),
         truth="floor albedo 0.4 instead of 0.6"),
    Spec("light_25", "light_radiance", True, edit=light(radiance=(25.0, 25.0, 25.0)), truth="light radiance 25 instead of 20"),
    Spec("light_warm", "light_radiance", True, held_out=True, edit=light(radiance=(22.0, 20.0, 16.0)),
         truth="light radiance (22, 20, 16) instead of (20, 20, 20)"),
    Spec("light_moved_x", "light_position", True, edit=light(move=(1.5, 0.0, 0.0)), truth="light moved 1.5 along +x"),
    Spec("light_moved_y", "light_position", True, held_out=True, edit=light(move=(0.0, 1.0, 0.0)), truth="light moved 1 along +y"),
    Spec("light_size_3", "light_size", True, edit=light(size=(3.0, 3.0)), truth="light 3x3 instead of 2x2 (same radiance)"),
    Spec("light_size_1.5", "light_size", True, held_out=True, edit=light(size=(1.5, 1.5)), truth="light 1.5x1.5 instead of 2x2"),
    Spec("light_hidden", "light_hidden", False, hide_emitters=True, truth="the light itself black where the camera sees it"),
    Spec("depth_4", "depth", True, max_depth=4, truth="paths cut at depth 4 instead of 8"),
    Spec("depth_3", "depth", True, held_out=True, max_depth=3, truth="paths cut at depth 3 instead of 8"),
    Spec("blur", "blur", False, spp=1024, post="blur", truth="a Gaussian blur (sigma 0.8 pixel) after rendering"),
    Spec("denoised", "blur", False, held_out=True, spp=64, post="denoise", truth="non-local-means denoising after rendering"),
    Spec("exr_srgb", "encoding", False, file="exr-srgb", truth="an EXR holding sRGB-encoded values"),
    Spec("exr_gamma2", "encoding", False, held_out=True, file="exr-gamma2", truth="an EXR holding square-rooted values (gamma 2)"),
    Spec("png_linear", "encoding", False, file="png-linear", truth="an 8-bit PNG holding linear values, not declared linear"),
)

#: Correct hand-ins: estimators, samplers, spp and file encodings.
CORRECT: tuple[Spec, ...] = (
    Spec("mcrt_16", None, spp=16, renderer="mcrt", truth="mcrt, 16 spp"),
    Spec("mcrt_100", None, spp=100, renderer="mcrt", truth="mcrt, 100 spp"),
    Spec("mcrt_1024", None, spp=1024, renderer="mcrt", truth="mcrt, 1024 spp"),
    Spec("path_indep_64", None, spp=64, truth="Mitsuba path, independent sampler, 64 spp"),
    Spec("path_strat_256", None, spp=256, sampler="stratified", truth="Mitsuba path, stratified sampler, 256 spp"),
    Spec("path_ld_256", None, spp=256, sampler="ldsampler", truth="Mitsuba path, low-discrepancy sampler, 256 spp"),
    Spec("path_mj_1024", None, spp=1024, sampler="multijitter", held_out=True,
         truth="Mitsuba path, multi-jittered sampler, 1024 spp"),
    Spec("volpath_100", None, spp=100, integrator="volpath", truth="Mitsuba volpath, independent sampler, 100 spp"),
    Spec("volpath_ld_16", None, spp=16, integrator="volpath", sampler="ldsampler", held_out=True,
         truth="Mitsuba volpath, low-discrepancy sampler, 16 spp"),
    Spec("png_srgb_256", None, spp=256, file="png-srgb", truth="Mitsuba path 256 spp as an 8-bit sRGB PNG"),
    Spec("png_gamma22_100", None, spp=100, renderer="mcrt", file="png-gamma2.2", truth="mcrt 100 spp as an 8-bit gamma-2.2 PNG"),
    Spec("png_gamma2_64", None, spp=64, file="png-gamma2", held_out=True, truth="Mitsuba path 64 spp as an 8-bit gamma-2 PNG"),
)

SPECS: tuple[Spec, ...] = MISTAKES + CORRECT


def _seed(name: str) -> int:
    """A fixed seed per case name (the class is reproducible; cases are independent)."""
    import zlib

    return 1000 + zlib.crc32(name.encode()) % 100000


def _render_spec(spec: Spec, scene: Scene, *, width: int, height: int, max_depth: int, seed: int):
    from mcrt.render import render

    width, height = width // spec.render_scale, height // spec.render_scale
    s = scene.settings(camera="near", width=width, height=height, spp=spec.spp, max_depth=spec.max_depth or max_depth)
    if spec.renderer == "mcrt":
        return render(scene, s, seed=seed, progress=False)
    from mcrt.mitsuba_scene import render_with_variance, scene_dict

    d = scene_dict(scene, "near", width, height, s.max_depth, spec.integrator, rr_depth=s.rr_depth, spp=spec.spp)
    d["integrator"]["hide_emitters"] = spec.hide_emitters
    sensor = dict(d["sensor"], **spec.sensor)
    sensor["sampler"] = {"type": spec.sampler, "sample_count": spec.spp}
    d["sensor"] = sensor
    if spec.mitsuba_edit is not None:
        d = spec.mitsuba_edit(d)
    # A stratified or low-discrepancy sampler stratifies over its whole sample count: all of it in one pass.
    per_pass = spec.spp if spec.sampler != "independent" else None
    if d["sensor"]["film"].get("rfilter", {"type": "box"})["type"] != "box":
        # A dictionary's film filter is made a box (the reference's): a filter the mistake sets must be
        # rendered from the loaded scene, which Mitsuba renders with its own film.
        import mitsuba as mi

        d = mi.load_dict(d)
    return render_with_variance(d, spp=spec.spp, seed=seed, spp_per_pass=per_pass)


def _post(spec: Spec, mean: np.ndarray, noise_sd: float) -> np.ndarray:
    """The post-process a student applied to the rendered image (scipy and scikit-image).

    The denoiser is told the render's noise (``noise_sd``, the mean standard
    deviation of a pixel, from the render's own variance) as a renderer's
    denoiser is.
    """
    if spec.post == "blur":
        from scipy.ndimage import gaussian_filter

        return gaussian_filter(mean, sigma=(0.8, 0.8, 0), mode="nearest")
    if spec.post == "denoise":
        from skimage.restoration import denoise_nl_means

        return denoise_nl_means(mean, h=0.8 * noise_sd, sigma=noise_sd, patch_size=3, patch_distance=4, channel_axis=-1,
                                fast_mode=True).astype(np.float32)
    if spec.post_fn is not None:
        return spec.post_fn(mean)
    return mean


def build_class(scene: Scene | None = None, *, width: int = 64, height: int = 64, max_depth: int = 8,
                names: tuple[str, ...] | None = None, held_out: bool | None = None, log=None,
                specs: tuple[Spec, ...] = SPECS) -> list[Case]:
    """Render the class ``specs`` (or its cases ``names``; ``held_out`` True/False: only those) at ``width`` x ``height``.

    ``scene`` defaults to the canonical scene; ``log`` takes one line of
    progress per case; ``specs`` defaults to this module's class
    (:data:`mcrt.grade.accuracy.outside.SPECS` is the second).
    """
    import time

    from mcrt.scene import load_scene

    scene = scene or load_scene()
    unknown = sorted(set(names or ()) - {s.name for s in specs})
    if unknown:
        raise ValueError(f"no case named {unknown[0]!r} in the class (have {', '.join(s.name for s in specs)})")
    specs = [s for s in specs if (names is None or s.name in names) and (held_out is None or s.held_out == held_out)]
    out = []
    t0 = time.perf_counter()
    for k, spec in enumerate(specs):
        edited = spec.edit(scene) if spec.edit else scene
        seed = _seed(spec.name)
        r = _render_spec(spec, edited, width=width, height=height, max_depth=max_depth, seed=seed)
        sd = float(np.mean(np.sqrt(np.maximum(r.variance, 0) / r.spp)))
        mean = _post(spec, np.asarray(r.mean, np.float32), sd)
        out.append(Case(spec, mean.astype(np.float32), np.asarray(r.variance, np.float32), int(r.spp), seed))
        if log:
            el = time.perf_counter() - t0
            log(f"class: {k + 1}/{len(specs)} rendered ({spec.name}), {el:.0f} s, ~{el / (k + 1) * (len(specs) - k - 1):.0f} s left")
    return out


# --------------------------------------------------------------------------
# Files as students write them
# --------------------------------------------------------------------------

_CURVES: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "srgb": srgb_oetf,
    "gamma2.2": lambda x: np.power(np.maximum(x, 0.0), 1 / 2.2),
    "gamma2": lambda x: np.sqrt(np.maximum(x, 0.0)),
    "linear": lambda x: np.asarray(x, np.float64),
}


def encoded(case: Case) -> np.ndarray:
    """The values the hand-in's file holds (before 8-bit quantisation for a PNG)."""
    f = case.spec.file
    curve = f.split("-", 1)[1] if "-" in f else "linear"
    return _CURVES[curve](case.image.astype(np.float64))


def write_submission(case: Case, folder: str | Path) -> Path:
    """Write the case as one student's folder: the image file (EXR or 8-bit PNG) and a manifest with its spp."""
    from PIL import Image

    from mcrt.film import RenderResult
    from mcrt.image_files import write_exr

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    if case.spec.writer is not None:  # the program's own writer: its file name, format and encoding
        path = case.spec.writer(case.image, folder)
    elif case.spec.file.startswith("png"):
        codes = np.floor(np.clip(np.nan_to_num(encoded(case)), 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)
        path = folder / "render.png"
        Image.fromarray(codes, "RGB").save(path, format="PNG")
    else:
        path = folder / "render.exr"
        write_exr(path, RenderResult(mean=encoded(case).astype(np.float32), variance=None, spp=case.spp, seed=case.seed, max_depth=-1,
                                     renderer="student", scene_hash="", camera="near"))
    (folder / "manifest.toml").write_text(f"spp = {case.spec.declared_spp or case.spp}\n{case.spec.manifest}")
    return path
