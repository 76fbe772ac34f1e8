r"""A fourth class of hand-ins: mistakes no earlier class tried, written apart from the grader.

How it was written: from what goes wrong in students' ray tracers and in the
code that saves their images, not from the grader. Its author read only the
cause words of the other classes and of
:data:`~mcrt.grade.accuracy.run.CAUSE_OF`, to reuse them; not the grader's
rules, and graded none of it. The mistakes differ from those of the three
other classes (:mod:`~mcrt.grade.accuracy.cases`,
:mod:`~mcrt.grade.accuracy.outside`, :mod:`~mcrt.grade.accuracy.programs`):

* **writing the file**: 8-bit codes truncated instead of rounded; a PFM whose
  header declares big-endian data written little-endian; the image divided by
  its brightest pixel; the display curve applied to each sample before
  averaging; CIE XYZ written where RGB belongs;
* **light model**: the light emitting from both faces;
* **materials**: a glossy coat on every diffuse surface; a tinted mirror; the
  tetrahedron's colour not read (a default grey);
* **normals**: the tetrahedron's faces wound inwards, a wall's outwards, with
  one-sided shading;
* **geometry**: the last wall of the list dropped; one face of the
  tetrahedron missing;
* **camera model**: the up vector negated; the field of view's half-angle
  passed to ``tan`` in degrees; pixel centres mapped with ``W - 1``; an
  orthographic camera;
* **resolution**: a 2x render reduced by taking every other pixel, or by
  ``scipy.ndimage.zoom``;
* **samples**: two handed-in renders made with the same seed; only the last
  pass written but every pass's samples declared;
* **integrator**: Russian roulette whose survivors are not divided by the
  survival probability.

The correct hand-ins come in ways no class used yet: Mitsuba's orthogonal-array
sampler, a half-float EXR with alpha and depth channels, a Radiance HDR written
by hand, a 16-bit PNG declared linear in the manifest, two renders averaged into
a 16-bit PPM, mcrt written as TGA, a dithered 8-bit PNG.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s
``edit`` and ``mitsuba_edit``), Mitsuba renders combined where light transport
is linear in what is combined (the two faces of the light, the paths of each
length), or correct renders post-processed and written with NumPy, Pillow,
pypng and OpenEXR as students' programs do. mcrt renders only a correct
hand-in.

Causes use the words of the other classes where the mistake really is that
cause; the keys new here (:data:`NEW_CAUSES`) describe mistakes no existing
cause does, and the grader may name none.

**Held out, then tuned on.** The class was written after the other classes'
held-out halves had been seen, to measure the rules as they stood, and graded
once with every case held out (commit c4a8457, its report
reports/grading_accuracy/fresh at that commit). The rules were then changed
on what that grading showed (a PFM's byte order, a pair of one seed, a black
surface's causes, a sub-pixel shift), so no case is held out any more
(:data:`HELD_OUT`): the report's figures are those of a class tuned on.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import cases, outside, programs
from mcrt.grade.accuracy.cases import Spec
from mcrt.image_files import RGB_TO_XYZ, srgb_oetf
from mcrt.scene import Scene

#: Whether the class is held out: no longer, since its first grading (the module docstring).
HELD_OUT = False

#: The causes new in this class, as the report words them.
NEW_CAUSES: dict[str, str] = {
    "quantisation": "values quantised wrongly (8-bit codes truncated, not rounded)",
    "file_format": "the file's header and data disagree (byte order)",
    "sample_curve": "the display curve applied to each sample before averaging",
    "colour_space": "values in another colour space (CIE XYZ written as RGB)",
    "light_twosided": "the light emitting from both faces",
    "normals": "surface normals facing the wrong way (one-sided shading)",
    "mesh_face": "a face of a mesh missing",
    "camera_model": "another camera model (orthographic instead of perspective)",
    "same_seed": "renders that should be independent made with the same seed",
    "roulette": "Russian roulette without dividing by the survival probability",
}


def _crc(name: str) -> int:
    return 9000 + zlib.crc32(name.encode()) % 100000


# --------------------------------------------------------------------------
# Files as students' programs write them (the program's buffer in, file out)
# --------------------------------------------------------------------------


def _srgb(x):
    return srgb_oetf(np.clip(np.nan_to_num(x), 0.0, 1.0))


def _write_png8(image: np.ndarray, folder: Path, *, encode: bool = True, truncate: bool = False,
                dither_seed: int | None = None) -> Path:
    """An 8-bit RGB PNG with Pillow: ``encode`` applies the sRGB curve (else the buffer already holds display values);
    ``truncate``: codes as ``(v * 255).astype(uint8)``; ``dither_seed``: uniform dither of one code before rounding."""
    from PIL import Image

    v = _srgb(image) if encode else np.clip(image, 0.0, 1.0)
    x = v * 255.0
    if dither_seed is not None:
        x = x + np.random.default_rng(dither_seed).random(x.shape) - 0.5
        codes = np.clip(np.floor(x + 0.5), 0, 255)
    else:
        codes = np.floor(x) if truncate else np.floor(x + 0.5)
    path = folder / "render.png"
    Image.fromarray(codes.astype(np.uint8), "RGB").save(path, format="PNG")
    return path


def _write_pfm(image: np.ndarray, folder: Path, *, scale: str = "-1.0") -> Path:
    """A PFM as ``f.write(header); f.write(img[::-1].astype(np.float32).tobytes())`` (x86: little-endian bytes) with the
    header's scale ``scale`` (its sign declares the byte order: negative little-endian, positive big-endian)."""
    h, w = image.shape[:2]
    path = folder / "render.pfm"
    path.write_bytes(f"PF\n{w} {h}\n{scale}\n".encode() + np.ascontiguousarray(image[::-1], "<f4").tobytes())
    return path


def _exr_file(path: Path, channels: dict) -> None:
    import OpenEXR

    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}, channels).write(str(path))


def _write_exr(image: np.ndarray, folder: Path) -> Path:
    """A float EXR with R, G, B written with the OpenEXR bindings (no header fields of mcrt's)."""
    path = folder / "render.exr"
    _exr_file(path, {c: np.ascontiguousarray(image[..., i], np.float32) for i, c in enumerate("RGB")})
    return path


def _write_exr_pair(image: np.ndarray, folder: Path) -> Path:
    """Two EXRs, ``render_1.exr`` and ``render_2.exr``: the program rendered both with one seed, so they are equal."""
    for k in (1, 2):
        _exr_file(folder / f"render_{k}.exr", {c: np.ascontiguousarray(image[..., i], np.float32)
                                               for i, c in enumerate("RGB")})
    return folder / "render_1.exr"


def _write_exr_half_rgba(image: np.ndarray, folder: Path) -> Path:
    """A half-float EXR with R, G, B, A (1) and Z (the depth buffer a program keeps beside the colour)."""
    h, w = image.shape[:2]
    chans = {c: np.ascontiguousarray(image[..., i], np.float16) for i, c in enumerate("RGB")}
    chans["A"] = np.ones((h, w), np.float16)
    chans["Z"] = np.tile(np.linspace(4.0, 14.0, w, dtype=np.float32), (h, 1))
    path = folder / "render.exr"
    _exr_file(path, chans)
    return path


def _write_hdr(image: np.ndarray, folder: Path) -> Path:
    """A Radiance RGBE picture written by hand, flat scanlines: Ward's float-to-RGBE (frexp of the largest channel, the
    channels times 256 / 2^e), rounded to the nearest code (rgbe.c truncates, and readers that do not add half a code
    back, as stb_image's, then read every value low)."""
    h, w = image.shape[:2]
    v = np.maximum(np.nan_to_num(image.astype(np.float64)), 0.0)
    m = v.max(axis=2)
    mant, ex = np.frexp(m)
    rgbe = np.zeros((h, w, 4), np.uint8)
    ok = m > 1e-32
    f = np.where(ok, mant * 256.0 / np.where(ok, m, 1.0), 0.0)
    codes = np.minimum(np.floor(v * f[..., None] + 0.5), 255)  # 255.5 and up: clipped (a mantissa of 1 - 1/512)
    rgbe[..., :3] = np.where(ok[..., None], codes, 0).astype(np.uint8)
    rgbe[..., 3] = np.where(ok, ex + 128, 0).astype(np.uint8)
    path = folder / "render.hdr"
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"-Y {h} +X {w}\n".encode() + rgbe.tobytes())
    return path


def _write_png16_linear(image: np.ndarray, folder: Path) -> Path:
    """A 16-bit PNG holding linear values (pypng); the manifest says ``linear = true``."""
    import png

    h, w = image.shape[:2]
    codes = np.floor(np.clip(np.nan_to_num(image), 0.0, 1.0) * 65535.0 + 0.5).astype(np.uint16)
    path = folder / "render.png"
    with open(path, "wb") as fh:
        png.Writer(w, h, bitdepth=16, greyscale=False).write(fh, codes.reshape(h, w * 3).tolist())
    return path


def _write_ppm16(image: np.ndarray, folder: Path) -> Path:
    """A binary PPM (P6) of maxval 65535, sRGB-encoded, samples big-endian as netpbm says."""
    h, w = image.shape[:2]
    codes = np.floor(_srgb(image) * 65535.0 + 0.5).astype(">u2")
    path = folder / "render.ppm"
    path.write_bytes(f"P6\n{w} {h}\n65535\n".encode() + codes.tobytes())
    return path


def _write_tga(image: np.ndarray, folder: Path) -> Path:
    from PIL import Image

    path = folder / "render.tga"
    Image.fromarray(np.floor(_srgb(image) * 255.0 + 0.5).astype(np.uint8), "RGB").save(path, format="TGA")
    return path


# --------------------------------------------------------------------------
# Mitsuba renders inside post-processes
# --------------------------------------------------------------------------


def _mitsuba(shape, spp: int, seed: int, *, supersample: int = 1, max_depth: int = 8, rr_depth: int = 5,
             scene_edit=None) -> np.ndarray:
    """A Mitsuba path render of the canonical scene (``scene_edit`` applied) at ``shape`` times ``supersample``."""
    from mcrt.mitsuba_scene import render_with_variance, scene_dict
    from mcrt.scene import load_scene

    s = load_scene()
    if scene_edit is not None:
        s = scene_edit(s)
    h, w = shape[0] * supersample, shape[1] * supersample
    d = scene_dict(s, "near", w, h, max_depth, rr_depth=rr_depth, spp=spp)
    return np.asarray(render_with_variance(d, spp=spp, seed=seed).mean, np.float64)


def _plus_light_facing_up(x, *, spp: int, seed: int):
    """The render plus a render whose light faces the ceiling: light transport is linear in the emitters, so the sum is
    the light emitting from both faces (the camera sees the lower face's radiance, the upper face is hidden from it)."""
    from mcrt.grade.accuracy.cases import light

    return x + _mitsuba(x.shape, spp, seed, scene_edit=light(normal=(0.0, 0.0, 1.0)))


def _roulette(x, *, p: float, start: int, spp: int, seed: int):
    """Paths of each length weighted as roulette without re-weighting leaves them.

    Renders at max depth 1, ..., 8 with the same seed and Mitsuba's own
    roulette off share each path's first segments, so ``R_d - R_{d-1}`` is
    what paths of exactly ``d`` segments bring (``d = 1``: the light seen,
    ``d = 2``: direct light at the first hit). The tracer adds the light
    sampled at each hit, then plays roulette with survival ``p`` before
    going on, from bounce ``start`` on (0: the first hit), and does not divide
    by ``p``: the light sampled at bounce ``k`` (``d = k + 2``) is kept on
    average ``p^(k - start)`` of the time, when ``k > start``.
    """
    renders = [np.zeros(x.shape)] + [_mitsuba(x.shape, spp, seed, max_depth=d, rr_depth=100) for d in range(1, 9)]
    out = np.zeros(x.shape)
    for d in range(1, 9):
        out += p ** max(0, d - 2 - start) * (renders[d] - renders[d - 1])
    return out


def _per_sample_srgb(x, *, k: int, seed: int):
    """One Mitsuba sample in each of ``k x k`` sub-pixels, each sRGB-encoded (clipped to 1) before the pixel's mean:
    the buffer holds display values, written as they are."""
    s = _mitsuba(x.shape, 1, seed, supersample=k)
    h, w = x.shape[:2]
    return _srgb(s).reshape(h, k, w, k, 3).mean(axis=(1, 3))


def _every_other(x, *, spp: int, seed: int):
    """Rendered at twice the resolution, reduced with ``img[1::2, 1::2]`` (one fine pixel of four, not their mean)."""
    return _mitsuba(x.shape, spp, seed, supersample=2)[1::2, 1::2]


def _zoom_half(x, *, spp: int, seed: int):
    """Rendered at twice the resolution, reduced with ``scipy.ndimage.zoom(img, (0.5, 0.5, 1), order=1)`` (its default
    maps the corner pixels' centres onto each other: a bilinear resampling, not a block mean)."""
    from scipy.ndimage import zoom

    return zoom(_mitsuba(x.shape, spp, seed, supersample=2), (0.5, 0.5, 1), order=1)


def _averaged(x, *, spp: int, seed: int):
    """The mean of the render and a second one of the same spp and another seed."""
    return 0.5 * (x + _mitsuba(x.shape, spp, seed))


def _over_max(x):
    return x / np.max(x)


def _to_xyz(x):
    return x @ RGB_TO_XYZ.T


def _posted(name: str, fn) -> dict:
    return {"post": name, "post_fn": fn}


# --------------------------------------------------------------------------
# Scene edits (Scene) and Mitsuba dict edits
# --------------------------------------------------------------------------


def _up_negated(s: Scene) -> Scene:
    return cases._camera(s, up=tuple(-u for u in s.cameras["near"].up))


def _object_material(s: Scene, name: str, material) -> Scene:
    return replace(s, objects=tuple(replace(o, material=material) if o.name == name else o for o in s.objects))


def _surface(name: str):
    from mcrt.scene import load_scene

    return next(sf for sf in load_scene().surfaces() if sf.name == name)


def _rebuilt(d: dict, name: str, triangles, bsdf: dict) -> dict:
    """The dict with mesh ``name`` rebuilt from ``triangles`` (n, 3, 3) with ``bsdf``."""
    from mcrt.mitsuba_scene import _mesh
    from mcrt.scene import Surface

    return dict(d, **{name: _mesh(Surface(name, np.asarray(triangles, np.float64), None), bsdf)})


def _one_sided_flipped(d: dict, name: str) -> dict:
    """Mesh ``name`` wound the other way (room faces wound outwards, objects inwards) with a one-sided diffuse BSDF:
    its normals face away from where it is seen and lit, and a one-sided Lambertian is black from its back."""
    sf = _surface(name)
    tris = np.asarray(sf.triangles)[:, [0, 2, 1]]
    albedo = {"type": "rgb", "value": list(sf.material.albedo)}
    return _rebuilt(d, name, tris, {"type": "diffuse", "reflectance": albedo})


def _tetra_without_face(d: dict) -> dict:
    """The tetrahedron built from three of its four triangles: the one the camera sees most of is left out."""
    from mcrt.scene import load_scene

    sf, eye = _surface("tetrahedron"), np.asarray(load_scene().cameras["near"].eye)
    tris = np.asarray(sf.triangles, np.float64)
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])  # outward, length twice the area
    to_eye = eye - tris.mean(axis=1)
    seen = np.einsum("ij,ij->i", n, to_eye / np.linalg.norm(to_eye, axis=1, keepdims=True))
    keep = np.delete(tris, int(np.argmax(seen)), axis=0)
    return _rebuilt(d, "tetrahedron", keep, {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {
        "type": "rgb", "value": list(sf.material.albedo)}}})


def _glossy_everywhere(d: dict, alpha: float) -> dict:
    """Every diffuse surface (room and tetrahedron) a rough plastic of the same diffuse colour (a Phong material whose
    specular coefficient keeps its default)."""
    from mcrt.scene import Lambertian, load_scene

    for sf in load_scene().surfaces():
        if isinstance(sf.material, Lambertian):
            bsdf = {"type": "twosided", "bsdf": {"type": "roughplastic", "distribution": "ggx", "alpha": alpha,
                                                 "int_ior": 1.5, "diffuse_reflectance": {
                                                     "type": "rgb", "value": list(sf.material.albedo)}}}
            d = _rebuilt(d, sf.name, sf.triangles, bsdf)
    return d


def _without_mesh(d: dict, name: str) -> dict:
    return {k: v for k, v in d.items() if k != name}


def _orthographic(d: dict) -> dict:
    """The perspective sensor replaced by an orthographic one, same frame: rays parallel to the view axis from a
    2 x 2 window (the image plane's size at distance 1 for a 90-degree field of view)."""
    s = {k: v for k, v in d["sensor"].items() if k not in ("fov", "fov_axis")}
    return dict(d, sensor=dict(s, type="orthographic"))


def _fov_of_tan(t: float) -> float:
    return math.degrees(2.0 * math.atan(t))


#: Field of view for ``tan(fov / 2)`` computed with the half-angle 45 (degrees) passed as radians.
FOV_RADIANS_SLIP = _fov_of_tan(math.tan(45.0))
#: Field of view of pixel centres mapped as ``2 (i + 0.5) / (W - 1) - 1`` at the assignment's 64 pixels: every centre
#: 64/63 times as far from the axis as ``2 (i + 0.5) / W - 1`` puts it.
FOV_W_MINUS_1 = _fov_of_tan(64.0 / 63.0)


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: spp of the renders inside post-processes; a case whose post-process renders the image itself renders its own
#: (unused) image at the same spp, so that the spp the report shows and the manifest declares are those of the file.
_S = 256


def _mistakes() -> tuple[Spec, ...]:
    from mcrt.scene import Lambertian, Mirror

    H = {"held_out": HELD_OUT}
    return (
        # Writing the file
        Spec("png_truncated", "quantisation", **H, writer=partial(_write_png8, truncate=True), file="png-srgb-truncated",
             truth="sRGB 8-bit PNG with codes (v * 255).astype(uint8): truncated, not rounded"),
        Spec("pfm_big_endian_header", "file_format", True, writer=partial(_write_pfm, scale="1.0"), file="pfm-scale+1",
             **H, truth="a PFM whose header scale 1.0 declares big-endian data, written little-endian (x86)"),
        Spec("pfm_over_max", "light_radiance", True, writer=_write_pfm, file="pfm", **H,
             **_posted("over_max", _over_max), truth="the image divided by its brightest pixel (the light) before "
             "writing the PFM"),
        Spec("srgb_per_sample", "sample_curve", True, spp=64, file="png-display-buffer", **H,
             **_posted("srgb_per_sample", partial(_per_sample_srgb, k=8, seed=_crc("srgb_per_sample"))),
             writer=partial(_write_png8, encode=False),
             truth="each of 64 samples clipped and sRGB-encoded before the pixel's mean, written as an 8-bit PNG"),
        Spec("xyz_as_rgb", "colour_space", True, writer=_write_exr, **H, **_posted("xyz", _to_xyz),
             truth="CIE XYZ (a spectral tracer's output) written into the EXR's R, G, B"),
        # Light model
        Spec("light_two_sided", "light_twosided", **H,
             **_posted("plus_light_up", partial(_plus_light_facing_up, spp=_S, seed=_crc("light_two_sided"))),
             truth="the light emits from both faces (|cos| at the light): its upper face lights the ceiling above it"),
        # Materials
        Spec("glossy_coat", "material", True, **H, mitsuba_edit=partial(_glossy_everywhere, alpha=0.1),
             truth="every diffuse surface with a glossy coat (rough plastic, GGX alpha 0.1): a Phong default specular"),
        Spec("mirror_tinted", "albedo", True, **H,
             edit=partial(_object_material, name="sphere", material=Mirror((0.8, 0.8, 0.8))),
             truth="the mirror sphere's reflectance 0.8 (the default albedo multiplied in) instead of 1"),
        Spec("tetra_default_grey", "albedo", True, **H,
             edit=partial(_object_material, name="tetrahedron", material=Lambertian((0.5, 0.5, 0.5))),
             truth="the tetrahedron's colour not read: the material's default grey 0.5 instead of (0.8, 0.45, 0.1)"),
        # Normals
        Spec("tetra_normals_in", "normals", True, **H, mitsuba_edit=partial(_one_sided_flipped, name="tetrahedron"),
             truth="the tetrahedron's faces wound inwards, shaded one-sided (max(0, n.l)): black"),
        Spec("wall_normal_out", "normals", True, **H, mitsuba_edit=partial(_one_sided_flipped, name="wall_BC"),
             truth="the purple wall BC wound outwards, shaded one-sided: black, and reflecting nothing"),
        # Geometry
        Spec("last_wall_dropped", "object_missing", True, **H, mitsuba_edit=partial(_without_mesh, name="wall_FA"),
             truth="wall FA (behind the camera) missing: the walls' loop stops one short; seen in the mirror"),
        Spec("tetra_face_missing", "mesh_face", True, **H, mitsuba_edit=_tetra_without_face,
             truth="the tetrahedron built from 3 triangles: the face most seen missing, its inside visible"),
        # Camera model
        Spec("up_negated", "orientation", True, **H, edit=_up_negated,
             truth="the camera's up vector negated: the image turned 180 degrees"),
        Spec("fov_tan_degrees", "camera_fov", True, **H, edit=cases.fov(FOV_RADIANS_SLIP),
             truth="tan(fov / 2) given the half-angle 45 in degrees as radians: field of view 116.6 degrees"),
        Spec("pixel_map_w_minus_1", "camera_fov", True, **H, edit=cases.fov(FOV_W_MINUS_1),
             truth="pixel centres at 2 (i + 0.5) / (W - 1) - 1: the image 64/63 wider (field of view 90.9 degrees)"),
        Spec("orthographic", "camera_model", True, **H, mitsuba_edit=_orthographic,
             truth="an orthographic camera: parallel rays through the 2 x 2 image plane"),
        # Resolution
        Spec("every_other_pixel", "resampling", **H, spp=64,
             **_posted("every_other", partial(_every_other, spp=64, seed=_crc("every_other_pixel"))),
             truth="rendered at 128 x 128 (64 spp), reduced with img[1::2, 1::2]"),
        Spec("zoom_half", "resampling", **H, spp=64,
             **_posted("zoom_half", partial(_zoom_half, spp=64, seed=_crc("zoom_half"))),
             truth="rendered at 128 x 128 (64 spp), reduced with scipy.ndimage.zoom(order=1)"),
        # Samples
        Spec("pair_same_seed", "same_seed", **H, spp=128, writer=_write_exr_pair, file="exr-pair",
             truth="two renders handed in to measure the noise, both made with the same seed: the same image twice"),
        Spec("last_pass_only", "spp_claim", **H, spp=32, declared_spp=256,
             truth="8 passes of 32 spp, the buffer cleared each pass: only the last written, 256 spp declared"),
        # Integrator
        Spec("roulette_half_from_3", "roulette", True, **H, spp=_S,
             **_posted("roulette", partial(_roulette, p=0.5, start=2, spp=_S, seed=_crc("roulette_half_from_3"))),
             truth="Russian roulette with survival 0.5 from the 3rd hit on, survivors not divided by 0.5"),
        Spec("roulette_08_from_1", "roulette", True, **H, spp=_S,
             **_posted("roulette", partial(_roulette, p=0.8, start=0, spp=_S, seed=_crc("roulette_08_from_1"))),
             truth="Russian roulette with survival 0.8 from the first hit on, survivors not divided by 0.8"),
    )


def _correct() -> tuple[Spec, ...]:
    H = {"held_out": HELD_OUT}
    return (
        Spec("ok_orthogonal_121", None, **H, spp=121, sampler="orthogonal",
             truth="Mitsuba path, orthogonal-array sampler, two passes of 121 spp, EXR"),
        Spec("ok_exr_half_rgba", None, **H, spp=200, writer=_write_exr_half_rgba, file="exr-half-rgbaz",
             truth="Mitsuba path 200 spp, a half-float EXR with A and Z channels"),
        Spec("ok_hdr_by_hand", None, **H, spp=256, writer=_write_hdr, file="hdr",
             truth="Mitsuba path 256 spp, a Radiance HDR written by hand (flat RGBE, rounded)"),
        Spec("ok_png16_declared_linear", None, **H, spp=100, sampler="stratified", writer=_write_png16_linear,
             file="png16-linear", manifest="linear = true\n",
             truth="Mitsuba path, stratified, two passes of 100 spp, a 16-bit linear PNG declared linear"),
        Spec("ok_two_averaged_ppm16", None, **H, spp=128, declared_spp=256, writer=_write_ppm16, file="ppm16-srgb",
             **_posted("averaged", partial(_averaged, spp=128, seed=_crc("ok_two_averaged_ppm16"))),
             truth="two Mitsuba renders of 128 spp (two seeds) averaged, a 16-bit sRGB PPM"),
        Spec("ok_mcrt_48_tga", None, **H, spp=48, renderer="mcrt", writer=_write_tga, file="tga",
             truth="mcrt 48 spp, an 8-bit sRGB TGA written with Pillow"),
        Spec("ok_png_dithered", None, **H, spp=512, writer=partial(_write_png8, dither_seed=_crc("dither")),
             file="png-srgb-dithered", truth="Mitsuba path 512 spp, an 8-bit sRGB PNG dithered by one code"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: An existing cause worded for this class's cases (outside's words speak of enlarging only).
_REWORDED = {"resampling": "resampled wrongly (a render at another resolution enlarged or reduced without averaging)"}
_WORDS = {**cases.CAUSES, **outside.CAUSES, **programs.NEW_CAUSES, **NEW_CAUSES, **_REWORDED}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = {c: _WORDS[c] for c in dict.fromkeys(s.cause for s in MISTAKES)}
