r"""A fifteenth class of hand-ins: mistakes in students' tracers, scene input and output no class tried, written blind.

How it was written: from what goes wrong in students' programs (the steps
after rendering, the code that saves the image and its manifest, the scene
typed in or parsed, the camera's rays and pixel filter, the light's samples,
the integrator's loop, the loops that add up the samples and place the
tiles), not from the grader. Its author read the other classes' specs and
cause words, the catalogue (:mod:`mcrt.mutants`), the scene files, mcrt's
scene and image code, :data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to
stay clear of their mistakes; never the grader's rules (what decides a
cause) nor its reports, and graded none of it, not one case. Each cause and
``major`` flag was set from the mistake alone; every mistake is worded by a
cause the other classes already have (:data:`NEW_CAUSES` is empty), so
``SAME_MISTAKE`` needed no new entry. The mistakes differ from those of the
fourteen other classes (:mod:`~mcrt.grade.accuracy.cases`,
:mod:`~mcrt.grade.accuracy.outside`, :mod:`~mcrt.grade.accuracy.programs`,
:mod:`~mcrt.grade.accuracy.fresh`, :mod:`~mcrt.grade.accuracy.blind`,
:mod:`~mcrt.grade.accuracy.unseen`, :mod:`~mcrt.grade.accuracy.untried`,
:mod:`~mcrt.grade.accuracy.novel`, :mod:`~mcrt.grade.accuracy.untold`,
:mod:`~mcrt.grade.accuracy.unmet`, :mod:`~mcrt.grade.accuracy.unheard`,
:mod:`~mcrt.grade.accuracy.unsaid`, :mod:`~mcrt.grade.accuracy.unasked`,
:mod:`~mcrt.grade.accuracy.unsought`) and from the catalogue's bugs:

* **post-processing**: a total-variation denoiser (scikit-image's
  ``denoise_tv_chambolle``); the sRGB curve applied to each pixel's
  luminance, its colour scaled along (to keep the hue), as EXR; the image
  shifted half a pixel right and down (SciPy's ``shift``) to "centre the
  pixels"; an adaptive 3 x 3 Wiener filter (SciPy's ``wiener``);
* **writing the file**: an ARGB framebuffer saved as RGBA; the sRGB curve
  written without its ``- 0.055``; a Radiance HDR whose header keeps a
  template's ``EXPOSURE=2`` line over pixels never multiplied; the manifest's
  spp the total sample count (W x H x spp);
* **materials**: the walls' colours in reverse order (the corners reversed
  to wind the room, the colours not); the tetrahedron given a material
  class's default reflectivity 0.1 (a tenth a mirror); every albedo channel
  clamped to 0.7 by the loader;
* **geometry**: the tetrahedron's base typed on the floor (z -5.0 for -4.9);
  the walls built 0.1 inward (a wall thickness); the apex read as
  ``vertices[2]`` (the tetrahedron flat);
* **camera**: the film's filter a Mitchell-Netravali filter of radius 2
  pixels (negatives clipped); a first-person template's eye height 1.7 added to the eye; a TAA
  sub-pixel jitter of four passes (Halton 2, 3) left on;
* **light model**: the light's corners at 0, 90, 180 and 270 degrees from
  its centre (turned 45 degrees); the emission a ray sees tested by the
  distance to the light's centre (a disk's test); each light triangle
  sampled without the square root of its uniform mapping;
* **integrator**: the diffuse bounce's direction drawn in the local frame
  and used as a world direction; the specular flag never reset after a
  mirror bounce (emission counted by light samples and by BSDF hits after
  it); the mirror's sample weighted by its BSDF value R / cos, the cosine
  never multiplied; the indirect light traced at half the resolution and
  enlarged;
* **samples and passes**: the radiance accumulator not reset between a
  pixel's samples; the tiles placed at their transposes' places; a
  thread race losing 3 % of the adds; a firefly rejection against the
  running mean, the sum divided by the samples kept.

The correct hand-ins come in ways no class used: Mitsuba with sub-pixel
offsets stratified in x alone, Mitsuba with every mesh written to a PLY file
and loaded by its ``ply`` plugin, Mitsuba with every Lambertian one-sided,
an EXR with the first hit's albedo and normal as AOV layers, an 8-bit PNG
written by hand with the Sub filter on every row, a PFM whose header's scale
-0.5 stands for data written times 2, mcrt in passes of 8 spp, and
Mitsuba with the floor and ceiling fanned from another corner.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s
``edit`` and ``mitsuba_edit``), Mitsuba renders combined where light
transport or pixel integrals are linear in what is combined (the light seen
apart, passes, paths by length, resolutions), Mitsuba's path integrator
sampling the rays a student's camera, mirror or bounce makes (the helpers
of :mod:`~mcrt.grade.accuracy.unsaid`), or its samples, one by one, added
up as a student's loop adds them (:func:`mcrt.grade.accuracy.unasked._samples`),
or correct renders post-processed and written with NumPy, SciPy,
scikit-image and Pillow as students' programs do. mcrt renders only correct
hand-ins.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over
:data:`CATEGORIES`: the 2nd, 4th, ... of each category and of the correct
hand-ins) are as in :mod:`~mcrt.grade.accuracy.unsought`, fixed before any
case was graded.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unheard, unmet, unsaid,
                                 unseen, unsought, untold, untried)
from mcrt.grade.accuracy.cases import Spec

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


def _crc(name: str) -> int:
    return 201000 + zlib.crc32(name.encode()) % 100000


_render = unseen._render
_posted = unseen._posted

#: The grade's image side, for the totals a manifest or a tile size quotes (the class is built at 64 x 64).
_SIDE = 64


# --------------------------------------------------------------------------
# Post-processing (linear render in, what the program writes out)
# --------------------------------------------------------------------------


def _tv_denoised(x, *, weight: float = 0.05):
    """skimage.restoration.denoise_tv_chambolle on the linear render (colour channels together)."""
    from skimage.restoration import denoise_tv_chambolle

    return denoise_tv_chambolle(np.asarray(x, np.float64), weight=weight, channel_axis=-1)


def _srgb_unclipped(v) -> np.ndarray:
    v = np.maximum(np.asarray(v, np.float64), 0.0)
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(v, 1.0 / 2.4) - 0.055)


def _luma_srgb(x):
    """The sRGB curve applied to each pixel's luminance Y, the colour scaled by sRGB(Y) / Y (the hue kept)."""
    x = np.asarray(x, np.float64)
    y = unseen._luma(x)
    ratio = np.where(y > 0.0, _srgb_unclipped(y) / np.where(y > 0.0, y, 1.0), 12.92)
    return x * ratio[..., None]


def _half_pixel_shift(x):
    """The image moved half a pixel right and down (scipy.ndimage.shift, bilinear, the edges repeated)."""
    from scipy.ndimage import shift

    return shift(np.asarray(x, np.float64), (0.5, 0.5, 0.0), order=1, mode="nearest")


def _clipped_at_zero(x):
    """Negative values (a filter's negative lobes) set to 0 before saving."""
    return np.maximum(np.asarray(x, np.float64), 0.0)


def _wiener(x, *, size: int = 3):
    """scipy.signal.wiener of each channel over ``size`` x ``size`` pixels, its noise power estimated from the image
    (the mean local variance: the light's edges make it large, so most pixels become their local mean); the window
    zero-padded at the image's edges, as SciPy pads it."""
    from scipy.signal import wiener

    x = np.asarray(x, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):  # flat 3 x 3 patches (the light's) take their mean
        return np.stack([wiener(x[..., c], mysize=size) for c in range(3)], axis=-1)


# --------------------------------------------------------------------------
# Files as students' programs write them (the program's buffer in, file out)
# --------------------------------------------------------------------------


def _argb_as_rgba(image: np.ndarray) -> np.ndarray:
    """(H, W, 4) 8-bit codes of an ARGB buffer (alpha 255 first, then the sRGB R, G, B) read as R, G, B, A."""
    codes = blind._srgb8(image)
    return np.concatenate([np.full(codes.shape[:2] + (1,), 255, np.uint8), codes], axis=-1)


def _write_png_argb_as_rgba(image: np.ndarray, folder: Path) -> Path:
    from PIL import Image

    path = folder / "render.png"
    Image.fromarray(_argb_as_rgba(image), "RGBA").save(path, format="PNG")
    return path


def _srgb_without_offset(image: np.ndarray) -> np.ndarray:
    """8-bit codes of ``12.92 v`` up to 0.0031308, ``1.055 v^(1/2.4)`` above it (the ``- 0.055`` left out), clipped
    to [0, 1] and rounded."""
    v = np.maximum(np.nan_to_num(np.asarray(image, np.float64)), 0.0)
    e = np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(v, 1.0 / 2.4))
    return np.floor(np.clip(e, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def _write_png_srgb_without_offset(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_srgb_without_offset(image), folder)


def _write_hdr_exposure_kept(image: np.ndarray, folder: Path, *, exposure: float = 2.0) -> Path:
    """A Radiance HDR (flat RGBE, as :func:`mcrt.grade.accuracy.fresh._write_hdr`) whose header has an ``EXPOSURE=2``
    line from a template, the pixels written as they are (a reader divides them by 2)."""
    path = fresh._write_hdr(image, folder)
    data = path.read_bytes()
    path.write_bytes(data.replace(b"FORMAT=32-bit_rle_rgbe\n", f"FORMAT=32-bit_rle_rgbe\nEXPOSURE={exposure:g}\n"
                                  .encode(), 1))
    return path


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _walls_reversed(s):
    """The walls' colours in reverse order: wall k given wall 5 - k's albedo (AB FA's, BC EF's, CD DE's, ...)."""
    walls = s.room.walls
    out = tuple(replace(w, albedo=r.albedo) for w, r in zip(walls, reversed(walls)))
    return replace(s, room=replace(s.room, walls=out))


def _tetra_reflectivity(d: dict, *, reflectivity: float = 0.1) -> dict:
    """The tetrahedron a blend of its Lambertian (weight 0.9) and a perfect mirror (weight ``reflectivity``)."""
    sf = fresh._surface("tetrahedron")
    albedo = {"type": "rgb", "value": [float(a) for a in sf.material.albedo]}
    bsdf = {"type": "blendbsdf", "weight": float(reflectivity),
            "bsdf_0": {"type": "diffuse", "reflectance": albedo},
            "bsdf_1": {"type": "conductor", "material": "none"}}
    return fresh._rebuilt(d, "tetrahedron", sf.triangles, bsdf)


def _capped(v, cap: float) -> tuple[float, ...]:
    return tuple(float(min(a, cap)) for a in v)


def _albedos_capped(s, *, cap: float = 0.7):
    """Every albedo channel clamped to ``cap``: the walls', the floor's, the ceiling's and the tetrahedron's."""
    from mcrt.scene import Lambertian

    walls = tuple(replace(w, albedo=_capped(w.albedo, cap)) for w in s.room.walls)
    room = replace(s.room, walls=walls, floor_albedo=_capped(s.room.floor_albedo, cap),
                   ceiling_albedo=_capped(s.room.ceiling_albedo, cap))
    objects = tuple(replace(o, material=Lambertian(_capped(o.material.albedo, cap)))
                    if isinstance(o.material, Lambertian) else o for o in s.objects)
    return replace(s, room=room, objects=objects)


def _tetra_vertices(s, change):
    """The tetrahedron's vertices as ``change`` (a tuple of four (x, y, z)) -> four makes them."""
    objects = tuple(replace(o, vertices=change(o.vertices)) if o.name == "tetrahedron" else o for o in s.objects)
    return replace(s, objects=objects)


def _base_on_floor(vertices):
    return tuple((x, y, -5.0) if z == -4.9 else (x, y, z) for x, y, z in vertices)


def _tetra_base_on_floor(s):
    """The tetrahedron's three base vertices at z = -5.0 (the floor) for -4.9."""
    return _tetra_vertices(s, _base_on_floor)


def _inset_corners(s, *, thickness: float = 0.1) -> dict:
    """The room's corners moved so that every wall lies ``thickness`` inside its place (each corner the meeting of its
    two walls' lines moved inward)."""
    room = s.room
    poly = room.polygon()
    planes = room.planes()[: len(poly)]  # (n, 4): outward normal, offset
    out = {}
    for k, w in enumerate(room.walls):
        a, b = planes[k - 1], planes[k]  # the wall ending at this corner, the wall starting there
        m = np.array([a[:2], b[:2]])
        p = np.linalg.solve(m, [a[3] - thickness, b[3] - thickness])
        out[w.corners[0]] = (float(p[0]), float(p[1]))
    return out


def _walls_inset(s, *, thickness: float = 0.1):
    """The walls built ``thickness`` inward (the room's polygon inset; the floor and ceiling follow it)."""
    return replace(s, room=replace(s.room, corners=_inset_corners(s, thickness=thickness)))


def _tetra_flat(d: dict) -> dict:
    """The tetrahedron of vertices v0, v1, v2, v2 (the apex read as ``vertices[2]``): its three side faces degenerate
    (no area), only its base triangle left."""
    from mcrt.mitsuba_scene import _bsdf_dict

    sf = fresh._surface("tetrahedron")
    v = np.asarray(next(o for o in _scene().objects if o.name == "tetrahedron").vertices, np.float64)
    return fresh._rebuilt(d, "tetrahedron", v[None, :3], _bsdf_dict(sf.material))


def _scene():
    from mcrt.scene import load_scene

    return load_scene()


def _light_rotated_tris(deg: float = 45.0) -> np.ndarray:
    """(2, 3, 3): the light's square turned ``deg`` about its centre (corners at half its diagonal from the centre, at
    0, 90, 180, 270 degrees for 45), wound to face down."""
    from mcrt.mitsuba_scene import _light_surface
    from mcrt.scene import Surface

    lt = _scene().light
    cx, cy, cz = lt.center
    r = math.hypot(lt.size[0], lt.size[1]) / 2.0
    a = [math.radians(deg - 45.0 + 90.0 * k) for k in range(4)]
    p = [(cx + r * math.cos(t), cy + r * math.sin(t), cz) for t in a]
    tris = np.array([[p[0], p[1], p[2]], [p[0], p[2], p[3]]], np.float64)
    return np.array(_light_surface(Surface("light", tris, None), lt.normal).triangles, np.float64)


def _light_rotated(d: dict) -> dict:
    return unsaid._meshes(d, light=(_light_rotated_tris(), _scene().light.radiance))


def _strips(tri: np.ndarray, n: int) -> list[tuple[np.ndarray, float]]:
    """The triangle (V0, V1, V2) cut into ``n`` strips of barycentric b0 (V0's weight) in [k/n, (k+1)/n], each with
    the factor by which a sampler of b0 = 1 - u, b1 = u v (the square root of u forgotten) over-samples it against a
    uniform one: its density over the strip's area, 1 / (2 (1 - b0)), averaged, = (1/n) / ((1 - a)^2 - (1 - b)^2)."""
    v0, v1, v2 = tri

    def p(b0, b1):
        return b0 * v0 + b1 * v1 + (1.0 - b0 - b1) * v2

    out = []
    for k in range(n):
        a, b = k / n, (k + 1) / n
        quad = [p(a, 0.0), p(a, 1.0 - a), p(b, 1.0 - b), p(b, 0.0)]
        tris = [np.array([quad[0], quad[1], quad[2]])]
        if k < n - 1:
            tris.append(np.array([quad[0], quad[2], quad[3]]))
        out.append((np.array(tris), (1.0 / n) / ((1.0 - a) ** 2 - (1.0 - b) ** 2)))
    return out


def _light_sqrt_missing(d: dict, *, n: int = 8) -> dict:
    """The light as it is sampled when each triangle's barycentrics are (1 - u, u v), not (1 - sqrt u, v sqrt u), with
    the uniform pdf: each of its two triangles (as the scene lists them, both from the corner (4, 1)) in ``n`` strips
    that emit the light's radiance times how much more often they are sampled (:func:`_strips`). The strips tile the
    square, so it shades and blocks as the light does."""
    from mcrt.mitsuba_scene import _light_surface
    from mcrt.scene import Surface

    lt = _scene().light
    out = fresh._without_mesh(d, "light")
    shapes = {}
    for t, tri in enumerate(unsaid._light_tris()):
        for k, (tris, f) in enumerate(_strips(tri, n)):
            wound = np.array(_light_surface(Surface("strip", tris, None), lt.normal).triangles, np.float64)
            shapes[f"light_strip_{t}_{k}"] = (wound, tuple(f * r for r in lt.radiance))
    return unsaid._meshes(out, **shapes)


def _one_sided(d: dict) -> dict:
    """Every Lambertian one-sided (Mitsuba's ``diffuse`` without ``twosided``): the room's faces face in, the
    tetrahedron's out, so nothing is seen or lit from its back."""
    from mcrt.scene import Lambertian

    for sf in _scene().surfaces():
        if isinstance(sf.material, Lambertian):
            rho = {"type": "rgb", "value": [float(a) for a in sf.material.albedo]}
            d = fresh._rebuilt(d, sf.name, sf.triangles, {"type": "diffuse", "reflectance": rho})
    return d


def _fan(poly: np.ndarray, start: int, z: float, *, up: bool) -> np.ndarray:
    """The polygon fanned from corner ``start`` at height z, wound to face up (the floor) or down (the ceiling)."""
    p = np.roll(poly, -start, axis=0)
    tris = [[(*p[0], z), (*p[k], z), (*p[k + 1], z)] for k in range(1, len(p) - 1)]
    tris = np.array(tris, np.float64)
    return tris if up else tris[:, [0, 2, 1]]


def _fans_from(d: dict, *, corner: int = 3) -> dict:
    """The floor and the ceiling triangulated as fans from corner ``corner`` (D), not from A."""
    from mcrt.mitsuba_scene import _bsdf_dict

    s = _scene()
    poly = s.room.polygon()
    for name, z, up in (("floor", s.room.floor_z, True), ("ceiling", s.room.ceiling_z, False)):
        d = fresh._rebuilt(d, name, _fan(poly, corner, z, up=up), _bsdf_dict(fresh._surface(name).material))
    return d


def _from_ply(d: dict) -> dict:
    """Every mesh of the scene written to a PLY file (Mitsuba's ``Mesh.write_ply``) and loaded back by Mitsuba's
    ``ply`` plugin with face normals, its BSDF and emitter from the scene."""
    import tempfile

    import mitsuba as mi

    from mcrt.mitsuba_scene import _bsdf_dict, _light_surface, _mesh, _rgb

    s = _scene()
    out = dict(d)
    with tempfile.TemporaryDirectory() as tmp:
        for sf in s.surfaces():
            if sf.material is None:
                sf = _light_surface(sf, s.light.normal)
            path = str(Path(tmp) / f"{sf.name}.ply")
            _mesh(sf, _bsdf_dict(sf.material)).write_ply(path)
            shape = {"type": "ply", "filename": path, "face_normals": True, "bsdf": _bsdf_dict(sf.material)}
            if sf.material is None:
                shape["emitter"] = {"type": "area", "radiance": _rgb(s.light.radiance)}
            out[sf.name] = mi.load_dict(shape)
    return out


# --------------------------------------------------------------------------
# Renderer mistakes realised with Mitsuba renders combined (the render's shape in, the image out)
# --------------------------------------------------------------------------

#: The first four points of the Halton sequence in bases 2 and 3 (from index 1), less 0.5: a TAA's sub-pixel jitter.
_HALTON_23 = ((0.0, -1.0 / 6.0), (-0.25, 1.0 / 6.0), (0.25, -7.0 / 18.0), (-0.375, -1.0 / 18.0))


def _taa_jitter(x, *, spp: int, seed: int):
    """Four passes of spp / 4, each with the camera's principal point moved by one of :data:`_HALTON_23`'s offsets (in
    pixels), averaged: the TAA jitter of a real-time renderer left on, never undone."""
    h, w = x.shape[:2]
    n = max(1, spp // len(_HALTON_23))
    return np.mean([_render(w, h, n, seed + k, sensor={"principal_point_offset_x": dx / w,
                                                       "principal_point_offset_y": dy / h})
                    for k, (dx, dy) in enumerate(_HALTON_23)], axis=0)


def _light_seen_as_disk(x, *, spp: int, seed: int):
    """The emission a camera or mirror ray sees counted only within the light's inscribed disk (its corners black),
    the light's samples (its light on surfaces) from the square: :func:`mcrt.grade.accuracy.unsaid._light_seen_from`
    with the seen light :func:`mcrt.grade.accuracy.blind._light_disk`'s."""
    return unsaid._light_seen_from(x, spp=spp, seed=seed, seen_edit=blind._light_disk)


def _specular_flag_stuck(x, *, spp: int, seed: int):
    """After a camera ray's mirror bounce the 'last bounce specular' flag stays set: every later vertex counts the
    light both by its light sample and when its BSDF ray meets the light. For camera rays that meet the sphere, the
    reflected ray's radiance 2 L7 - L1 (L7 Mitsuba's path of the 7 segments left, L1 the emission it sees at once,
    same seed), the rest Mitsuba's path on the pinhole's rays."""
    h, w = x.shape[:2]
    full, rest, seen = unsaid._loaded(8), unsaid._loaded(7), unsaid._loaded(1)
    total = np.zeros((h * w, 3))
    for cseed, n, fx, fy in unsaid._lanes(w, h, spp, seed):
        o, d = unsaid._pinhole(fx, fy)
        o, d, used = unsaid._reflected(np.asarray(o, np.float64), np.asarray(d, np.float64))
        L = np.zeros((len(o), 3))
        plain, hit = used == 0, used == 1
        L[plain] = unsaid._sampled(full, o[plain], d[plain], cseed)
        if hit.any():
            l7 = unsaid._sampled(rest, o[hit], d[hit], cseed + 7919)
            L[hit] = 2.0 * l7 - unsaid._sampled(seen, o[hit], d[hit], cseed + 7919)
        total += L.reshape(h * w, n, 3).sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _cosine_about_z(rng, n: int) -> np.ndarray:
    """(n, 3): directions cosine-distributed about +z (the local frame's normal), in the local frame."""
    u1, u2 = rng.random((2, n))
    r, phi = np.sqrt(u1), 2.0 * math.pi * u2
    return np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(1.0 - u1, 0.0))], axis=1)


def _first_hit(mscene, o: np.ndarray, d: np.ndarray):
    """(distances t, whether a surface was met) of each ray's first hit."""
    si = mscene.ray_intersect(unsaid._rays(o, d))
    return np.array(si.t, np.float64), np.array(si.is_valid(), bool)


def _bounce_in_local_frame(x, *, spp: int, seed: int):
    """The diffuse bounce's direction drawn cosine-weighted in the local frame (about +z) and used as a world
    direction, weighted by the albedo, at the first surface a camera ray meets: there its light sample is right
    (Mitsuba's max-depth-2 sample minus max-depth-1, same seed), and the bounce goes on along the local direction
    from the hit point (offset along it) with Mitsuba's path of the 7 segments left less the emission it sees at once
    (a student's tracer counts the light by light samples). On the floor that is right; on the ceiling every bounce
    leaves the room, on the walls those through the wall. Mirror and light hits, Mitsuba's."""
    h, w = x.shape[:2]
    full, two, one, rest = unsaid._loaded(8), unsaid._loaded(2), unsaid._loaded(1), unsaid._loaded(7)
    rng = np.random.default_rng(seed + 13)
    total = np.zeros((h * w, 3))
    for cseed, n, fx, fy in unsaid._lanes(w, h, spp, seed):
        o, d = unsaid._pinhole(fx, fy)
        o, d = np.array(o, np.float64), np.asarray(d, np.float64)
        L = unsaid._sampled(full, o, d, cseed)
        rho = unsaid._first_albedo(full, o, d)
        t, valid = _first_hit(full, o, d)
        diffuse = valid & (rho.max(axis=1) > 0.0)
        if diffuse.any():
            od, dd = o[diffuse], d[diffuse]
            direct = unsaid._sampled(two, od, dd, cseed) - unsaid._sampled(one, od, dd, cseed)
            p = od + t[diffuse, None] * dd
            nd = _cosine_about_z(rng, len(od))
            po = p + 1e-4 * nd
            cont = unsaid._sampled(rest, po, nd, cseed + 104729) - unsaid._sampled(one, po, nd, cseed + 104729)
            L[diffuse] = direct + rho[diffuse] * cont
        total += L.reshape(h * w, n, 3).sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _mirror_over_cosine(x, *, spp: int, seed: int, k: int = 4, floor: float = 1e-3):
    """The mirror's sample weighted by its BSDF value R / cos (pbrt's specular BSDF) with the cosine never multiplied
    back: each cell of a render ``k`` times finer (``spp`` a cell, k^2 spp a pixel) whose ray meets the sphere divided
    by its cosine there (at least ``floor``); the sphere's rim bright. (Mirror bounces deeper in a path, which the
    mistake also brightens, are kept.)"""
    h, w = x.shape[:2]
    cos = np.maximum(unmet._sphere_cosines(w, h, k), floor)
    return (untried._cells(w, h, k, spp, seed) / cos[..., None]).mean(axis=(1, 3))


def _indirect_half_resolution(x, *, spp: int, seed: int):
    """The direct light (paths of at most two segments: the light seen, the first hit's light sample, the light in
    the mirror) at full resolution, the rest (a same-seed max-depth-8 render minus max-depth-2) at half the resolution
    and enlarged bilinearly (skimage.transform.resize, pixel centres aligned): the indirect light and the room in the
    mirror blurred."""
    from skimage.transform import resize

    h, w = x.shape[:2]
    direct = _render(w, h, spp, seed, max_depth=2)
    hs, ws = h // 2, w // 2
    indirect = _render(ws, hs, spp, seed + 1) - _render(ws, hs, spp, seed + 1, max_depth=2)
    return direct + resize(indirect, (h, w, 3), order=1, mode="edge", anti_aliasing=False)


# --------------------------------------------------------------------------
# Sample loops (Mitsuba's samples in a pixel's order, added up as a student's loop adds them)
# --------------------------------------------------------------------------


def _accumulator_not_reset(x, *, spp: int, seed: int):
    """``L`` set to 0 once per pixel, outside the sample loop: sample k adds the running total of samples 1..k to the
    sum, which is divided by the spp (sample j weighs N - j + 1: the mean (N + 1) / 2 times the truth)."""
    h, w = x.shape[:2]
    total, running = np.zeros((h * w, 3)), np.zeros((h * w, 3))
    for L, _, _ in unasked._samples(w, h, spp, seed):
        cum = running[:, None] + np.cumsum(L, axis=1)
        total += cum.sum(axis=1)
        running = cum[:, -1]
    return (total / spp).reshape(h, w, 3)


def _tiles_transposed(x, *, tiles: int = 4):
    """The image's ``tiles`` x ``tiles`` tiles each written at its transpose's place (tile (r, c) at (c, r)), each
    tile's pixels right."""
    x = np.asarray(x, np.float64)
    h, w = x.shape[:2]
    th, tw = h // tiles, w // tiles
    out = x.copy()
    for r in range(tiles):
        for c in range(tiles):
            out[c * th:(c + 1) * th, r * tw:(r + 1) * tw] = x[r * th:(r + 1) * th, c * tw:(c + 1) * tw]
    return out


def _race_lost(x, *, spp: int, seed: int, lost: float = 0.03):
    """Each sample's add to its pixel's sum lost with probability ``lost`` (two threads adding without a lock), the sum
    divided by the spp."""
    h, w = x.shape[:2]
    rng = np.random.default_rng(seed + 31)
    total = np.zeros((h * w, 3))
    for L, _, _ in unasked._samples(w, h, spp, seed):
        kept = rng.random(L.shape[:2]) >= lost
        total += (L * kept[..., None]).sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _rejected_mean(samples: np.ndarray, *, factor: float, after: int) -> np.ndarray:
    """(P, 3): each row's mean of ``samples`` (P, N, 3) in order, a sample from the ``after``-th on (counting from 1)
    dropped when its luminance is over ``factor`` times that of the running mean of the samples kept."""
    total, count = np.zeros((samples.shape[0], 3)), np.zeros(samples.shape[0])
    for j in range(samples.shape[1]):
        s = samples[:, j]
        mean = total / np.maximum(count, 1.0)[:, None]
        keep = (j < after - 1) | (unseen._luma(s) <= factor * unseen._luma(mean))
        total += s * keep[:, None]
        count += keep
    return total / np.maximum(count, 1.0)[:, None]


def _firefly_rejection(x, *, spp: int, seed: int, factor: float = 10.0, after: int = 16):
    """A firefly rejection against the running mean (:func:`_rejected_mean`) of Mitsuba's samples in a pixel's order."""
    h, w = x.shape[:2]
    samples = np.concatenate([L for L, _, _ in unasked._samples(w, h, spp, seed)], axis=1)
    return _rejected_mean(samples, factor=factor, after=after).reshape(h, w, 3)


# --------------------------------------------------------------------------
# Correct renders made or written in other ways
# --------------------------------------------------------------------------


def _x_strata(rng, n: int, *, pixels: int):
    """Sub-pixel offsets stratified in x alone: in each chunk of n samples of a pixel, u = (s + r) / n over the strata s
    in a random order, v uniform on its own."""
    order = np.argsort(rng.random((pixels, n)), axis=1)
    u = (order + rng.random((pixels, n))) / n
    return np.stack([u, rng.random((pixels, n))])


def _aovs(image: np.ndarray) -> dict:
    """The first hit's diffuse albedo and shading normal at each pixel's centre (Mitsuba), as a renderer's AOVs."""
    import mitsuba as mi

    h, w = image.shape[:2]
    jj, ii = np.mgrid[0:h, 0:w]
    o, d = unsaid._pinhole(((ii + 0.5) / w).ravel(), ((jj + 0.5) / h).ravel())
    o, d = np.array(o, np.float64), np.asarray(d, np.float64)
    mscene = unsaid._loaded(1)
    albedo = unsaid._first_albedo(mscene, o, d).reshape(h, w, 3)
    si = mscene.ray_intersect(unsaid._rays(o, d))
    n = mi.Vector3f(si.sh_frame.n)
    normal = np.stack([np.array(n[c], np.float64) for c in range(3)], axis=1).reshape(h, w, 3)
    out = {f"albedo.{c}": albedo[..., i] for i, c in enumerate("RGB")}
    out.update({f"normal.{c}": normal[..., i] for i, c in enumerate("XYZ")})
    return {k: np.ascontiguousarray(np.nan_to_num(v), np.float32) for k, v in out.items()}


def _write_exr_aovs(image: np.ndarray, folder: Path) -> Path:
    """A float EXR with R, G, B and the AOV layers albedo.R/G/B and normal.X/Y/Z (:func:`_aovs`)."""
    chans = {c: np.ascontiguousarray(image[..., i], np.float32) for i, c in enumerate("RGB")}
    chans.update(_aovs(image))
    path = folder / "render.exr"
    fresh._exr_file(path, chans)
    return path


def _sub_filtered(codes: np.ndarray) -> bytes:
    """The PNG scanlines of (H, W, 3) 8-bit codes, each with filter type 1 (Sub: each byte less the byte 3 before)."""
    rows = []
    for row in codes.astype(np.int16).reshape(codes.shape[0], -1):
        left = np.concatenate([np.zeros(3, np.int16), row[:-3]])
        rows.append(b"\x01" + ((row - left) % 256).astype(np.uint8).tobytes())
    return b"".join(rows)


def _write_png_sub_filter(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB PNG written by hand: IHDR, one zlib IDAT of Sub-filtered rows, IEND."""
    import struct

    h, w = image.shape[:2]
    ihdr = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)
    data = (b"\x89PNG\r\n\x1a\n" + unseen._png_chunk(b"IHDR", ihdr)
            + unseen._png_chunk(b"IDAT", zlib.compress(_sub_filtered(blind._srgb8(image)), 9))
            + unseen._png_chunk(b"IEND", b""))
    path = folder / "render.png"
    path.write_bytes(data)
    return path


def _write_pfm_scale_half(image: np.ndarray, folder: Path) -> Path:
    """A little-endian PFM, bottom row first, its header's scale -0.5 and its data the image times 2 (a reader
    multiplies by the scale's magnitude)."""
    h, w = image.shape[:2]
    path = folder / "render.pfm"
    path.write_bytes(f"PF\n{w} {h}\n-0.5\n".encode()
                     + np.ascontiguousarray(2.0 * np.asarray(image)[::-1], "<f4").tobytes())
    return path


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_tv_denoised", "pp_srgb_on_luminance", "pp_shifted_half_pixel", "pp_wiener_3x3"),
    "file": ("file_png_argb_as_rgba", "file_png_srgb_offset_missing", "file_hdr_exposure_line_kept",
             "manifest_spp_total_samples"),
    "materials": ("walls_colours_reversed", "tetra_reflectivity_default", "albedos_clamped_to_07"),
    "geometry": ("tetra_base_on_floor", "walls_inset_by_thickness", "tetra_apex_index_typo"),
    "camera": ("film_filter_mitchell", "eye_height_template", "taa_jitter_left_on"),
    "light": ("light_turned_45_degrees", "light_emission_disk_test", "light_triangle_sqrt_missing"),
    "integrator": ("bounce_in_local_frame", "specular_flag_stuck", "mirror_weight_over_cosine",
                   "indirect_half_resolution"),
    "samples": ("accumulator_not_reset", "tiles_at_transposed_places", "race_lost_adds",
                "firefly_rejection_running_mean"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file and the manifest."""
    return (
        # Post-processing
        Spec("pp_tv_denoised", "blur", **_posted("tv_chambolle", _tv_denoised),
             truth="a total-variation denoiser (skimage.restoration.denoise_tv_chambolle, weight 0.05, channels "
             "together) on the linear render to remove the noise, as EXR"),
        Spec("pp_srgb_on_luminance", "encoding", held_out=True, **_posted("srgb_luminance", _luma_srgb),
             truth="the sRGB curve applied to each pixel's luminance and its colour scaled by the same ratio (to keep "
             "the hue), written as EXR: the values display-encoded, the colours' ratios linear"),
        Spec("pp_shifted_half_pixel", "pixel_offset", True, **_posted("half_pixel_shift", _half_pixel_shift),
             truth="the image shifted half a pixel right and down (scipy.ndimage.shift, bilinear) to 'centre the "
             "pixels', as EXR: moved and slightly blurred"),
        Spec("pp_wiener_3x3", "blur", held_out=True, **_posted("wiener", _wiener),
             truth="an adaptive Wiener filter (scipy.signal.wiener, 3 x 3, each channel) against the noise, its noise "
             "power estimated from the image (the light's edges make it large: most pixels their 3 x 3 mean), its "
             "zero padding darkening the border pixels, as EXR"),
        # Writing the file and the manifest
        Spec("file_png_argb_as_rgba", "channels", True, writer=_write_png_argb_as_rgba, file="png-argb-as-rgba",
             truth="an ARGB framebuffer (alpha first, Qt's and Java's layout) saved as RGBA: red all 255, green the "
             "red, blue the green, the blue in the dropped alpha, 8-bit sRGB PNG"),
        Spec("file_png_srgb_offset_missing", "encoding", held_out=True, writer=_write_png_srgb_without_offset,
             file="png-srgb-no-offset",
             truth="the sRGB curve written 1.055 v^(1/2.4) without its - 0.055 (above 0.0031308): every code 0.055 "
             "(14 codes) too high, the darks lifted, values over 0.88 clipped white, 8-bit PNG"),
        Spec("file_hdr_exposure_line_kept", "light_radiance", True, writer=_write_hdr_exposure_kept,
             file="hdr-exposure-2",
             truth="a Radiance HDR whose header keeps a template's EXPOSURE=2 line, its pixels written as rendered: "
             "read back (the exposure divided out) at half the truth"),
        Spec("manifest_spp_total_samples", "spp_claim", held_out=True, declared_spp=_SIDE * _SIDE * 256,
             truth="the manifest's spp the render's total sample count, 64 x 64 x 256 = 1048576, for the 256 a pixel "
             "rendered (the image right)"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("walls_colours_reversed", "albedo", True, edit=_walls_reversed,
             truth="the walls' colours in reverse order (the corner list reversed to wind the room, the colour list "
             "not): AB given FA's cyan, BC EF's green, CD DE's blue and back"),
        Spec("tetra_reflectivity_default", "material", held_out=True, mitsuba_edit=_tetra_reflectivity,
             truth="the tetrahedron given a material class's default reflectivity 0.1: a blend of 0.9 its Lambertian "
             "and 0.1 a perfect mirror, the room faintly reflected in it"),
        Spec("albedos_clamped_to_07", "albedo", edit=_albedos_capped,
             truth="every albedo channel clamped to 0.7 by the scene loader's check (min(a, 0.7)): the red walls' "
             "0.75, the ceiling's 0.8 and the tetrahedron's 0.8 down to 0.7"),
        # Geometry
        Spec("tetra_base_on_floor", "object_shape", edit=_tetra_base_on_floor,
             truth="the tetrahedron's three base vertices typed at z = -5.0 (on the floor) for -4.9: 0.1 taller, its "
             "base on the floor, the apex where it was"),
        Spec("walls_inset_by_thickness", "object_moved", held_out=True, edit=_walls_inset,
             truth="the walls built 0.1 inward (a wall thickness of 0.1 taken off the inside): every corner moved "
             "in, the floor and the ceiling smaller with them"),
        Spec("tetra_apex_index_typo", "object_shape", True, mitsuba_edit=_tetra_flat,
             truth="the apex read as vertices[2] (an index typo): the tetrahedron flat, its side faces without area, "
             "only its base triangle left 0.1 above the floor"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera
        Spec("film_filter_mitchell", "blur", mitsuba_edit=partial(novel._film_filter, rfilter={"type": "mitchell"}),
             **_posted("negatives_clipped", _clipped_at_zero),
             truth="the film's reconstruction filter a Mitchell-Netravali filter (B = C = 1/3, radius 2 pixels): each "
             "sample splatted over its neighbours with the filter's weights, slightly blurred, ringing at the "
             "light's edges (its negative values clipped to 0 before the EXR)"),
        Spec("eye_height_template", "camera_eye", True, held_out=True, edit=cases.eye(dz=1.7),
             truth="a first-person template's eye height 1.7 added to the eye: (-1, 0, 1.7) for (-1, 0, 0), the view "
             "from higher up"),
        Spec("taa_jitter_left_on", "pixel_footprint", **_posted("taa_jitter", partial(
            _taa_jitter, spp=256, seed=c("taa_jitter_left_on"))),
             truth="a real-time renderer's TAA jitter left on: four passes of 64 spp, each with the camera's "
             "principal point moved by a Halton (2, 3) offset, (0, -1/6), (-1/4, 1/6), (1/4, -7/18), (-3/8, -1/18) "
             "pixels, averaged: each pixel's samples spread past its square and shifted"),
        # Light model
        Spec("light_turned_45_degrees", "light_shape", mitsuba_edit=_light_rotated,
             truth="the light's corners computed at 0, 90, 180 and 270 degrees from its centre (a polygon helper's "
             "start angle 0 for 45): the square turned 45 degrees, the same area and radiance"),
        Spec("light_emission_disk_test", "light_seen", held_out=True, **_posted("light_seen_disk", partial(
            _light_seen_as_disk, spp=256, seed=c("light_emission_disk_test"))),
             truth="the emission a camera or mirror ray sees tested by the distance to the light's centre (a disk's "
             "test, radius 1): the light's four corners black where seen and in the mirror, its light samples from "
             "the whole square (its light on surfaces right)"),
        Spec("light_triangle_sqrt_missing", "light_pdf", **_posted("light_sqrt_missing", partial(
            unheard._light_changed_for_samples, spp=256, seed=c("light_triangle_sqrt_missing"),
            dict_edit=_light_sqrt_missing)),
             truth="each of the light's two triangles sampled at barycentrics (1 - u, u v), the square root of u "
             "forgotten, with the uniform pdf: the samples crowd towards the triangles' shared first corner (4, 1), "
             "its light on surfaces as from a light brighter there, the light seen right"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples, passes and tiles."""
    c = _crc
    return (
        # Integrator
        Spec("bounce_in_local_frame", "indirect_scale", True, **_posted("bounce_local_frame", partial(
            _bounce_in_local_frame, spp=256, seed=c("bounce_in_local_frame"))),
             truth="the diffuse bounce's direction drawn cosine-weighted in the local frame (about +z) and never "
             "turned to the normal, weighted by the albedo (at the first surface a camera ray meets; Mitsuba's path "
             "after it): right on the floor, every bounce off the ceiling and half of those off the walls leave "
             "the room: the ceiling (lit only indirectly) black, the walls' indirect light wrong, the direct right"),
        Spec("specular_flag_stuck", "direct_twice", held_out=True, **_posted("specular_flag_stuck", partial(
            _specular_flag_stuck, spp=256, seed=c("specular_flag_stuck"))),
             truth="the 'last bounce specular' flag never reset after a mirror bounce: every later vertex counts the "
             "light by its light sample and again when its BSDF ray meets the light (for camera rays reflected by the "
             "sphere): the room in the mirror with its light on surfaces doubled, the rest right"),
        Spec("mirror_weight_over_cosine", "specular_weight", True, **_posted("mirror_over_cosine", partial(
            _mirror_over_cosine, spp=16, seed=c("mirror_weight_over_cosine"))),
             truth="the mirror's sample weighted by its BSDF value R / |cos| (as pbrt's specular BSDF returns it), "
             "the |cos| never multiplied back (for camera rays): the sphere's reflection brighter towards its rim, "
             "a bright ring"),
        Spec("indirect_half_resolution", "resampling", held_out=True, **_posted("indirect_half", partial(
            _indirect_half_resolution, spp=256, seed=c("indirect_half_resolution"))),
             truth="the indirect light (paths of three segments or more) traced at half the resolution and enlarged "
             "bilinearly to save time, the direct light at full resolution: the indirect light and the room in the "
             "mirror blurred"),
        # Samples, passes and tiles
        Spec("accumulator_not_reset", "light_radiance", True, **_posted("accumulator_kept", partial(
            _accumulator_not_reset, spp=256, seed=c("accumulator_not_reset"))),
             truth="the radiance accumulator set to 0 once per pixel, outside the sample loop: each sample adds the "
             "running total to the sum, divided by 256: 128.5 times too bright, the early samples weighing more"),
        Spec("tiles_at_transposed_places", "row_stride", True, held_out=True,
             **_posted("tiles_transposed", _tiles_transposed),
             truth="the 4 x 4 tiles (16 x 16 pixels) each written at its transpose's place, tile (r, c) at (c, r) "
             "(the tile's x and y offsets swapped), each tile right inside"),
        Spec("race_lost_adds", "sample_count", **_posted("race_lost", partial(
            _race_lost, spp=256, seed=c("race_lost_adds"))),
             truth="two threads adding into each pixel's sum without a lock: 3 % of the adds lost at random, the sum "
             "divided by 256: about 3 % dark, a little noisier"),
        Spec("firefly_rejection_running_mean", "biased_estimator", held_out=True, **_posted(
            "firefly_rejection", partial(_firefly_rejection, spp=256, seed=c("firefly_rejection_running_mean"))),
             truth="a firefly rejection: from the 16th sample on, a sample over 10 times the running mean's luminance "
             "dropped, the sum divided by the samples kept: the rare bright paths lost (the light's edges and what "
             "the mirror shows of it darker)"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_x_strata_offsets", None, spp=200, **_posted("x_strata", partial(
            unsought._mean_of, spp=200, seed=c("ok_x_strata_offsets"), jitter=_x_strata)),
             truth="Mitsuba path 200 spp, sub-pixel offsets stratified in x alone (u over the samples' strata, v "
             "uniform), EXR"),
        Spec("ok_meshes_from_ply", None, held_out=True, spp=168, mitsuba_edit=_from_ply,
             truth="Mitsuba path 168 spp with every mesh written to a PLY file and loaded by Mitsuba's ply plugin, "
             "EXR"),
        Spec("ok_one_sided_surfaces", None, spp=232, mitsuba_edit=_one_sided,
             truth="Mitsuba path 232 spp with every Lambertian one-sided (the room's faces facing in, the "
             "tetrahedron's out), EXR"),
        Spec("ok_exr_aovs", None, held_out=True, spp=216, writer=_write_exr_aovs, file="exr-aovs",
             truth="Mitsuba path 216 spp, a float EXR with the first hit's albedo and normal as AOV layers beside R, "
             "G, B"),
        Spec("ok_png_sub_filter", None, spp=184, writer=_write_png_sub_filter, file="png-srgb-sub-filter",
             truth="Mitsuba path 184 spp, an 8-bit sRGB PNG written by hand with the Sub filter on every row"),
        Spec("ok_pfm_scale_half", None, held_out=True, spp=264, writer=_write_pfm_scale_half, file="pfm-scale-half",
             truth="Mitsuba path 264 spp, a PFM whose header's scale -0.5 stands for its data, written times 2"),
        Spec("ok_mcrt_passes_of_8", None, spp=144, renderer="mcrt", **_posted("mcrt_passes_of_8", partial(
            untold._mcrt, spp=144, seed=c("ok_mcrt_passes_of_8"), spp_per_pass=8)),
             truth="mcrt 144 spp in 18 passes of 8 spp (spp_per_pass 8), EXR"),
        Spec("ok_fans_from_corner_d", None, held_out=True, spp=248, mitsuba_edit=_fans_from,
             truth="Mitsuba path 248 spp with the floor and the ceiling triangulated as fans from corner D, EXR"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "blur": "a filter (a denoiser after rendering, or the film's filter wider than a pixel)",
    "encoding": "the values' encoding (the display curve on the luminance, or the curve without its offset)",
    "pixel_offset": "the pixel centres (the image shifted half a pixel after rendering)",
    "channels": "colour channels written in the wrong order (an ARGB buffer read as RGBA)",
    "light_radiance": "a constant factor on the image (an exposure line the pixels lack, an accumulator not reset)",
    "spp_claim": "more samples per pixel declared than rendered (the total sample count given)",
    "albedo": "a surface's colour (the walls' colours in reverse order, every albedo clamped)",
    "material": "an object rendered with another material (part a mirror)",
    "object_shape": "an object's shape (a vertex in the wrong place, the tetrahedron flat)",
    "object_moved": "an object moved (the walls moved inward)",
    "camera_eye": "the camera's eye position (higher up)",
    "pixel_footprint": "each pixel's samples not spread over its square (a sub-pixel jitter of the camera left on)",
    "light_shape": "the light's shape (its square turned 45 degrees)",
    "light_seen": "the light's own pixels (where the camera or the mirror sees it) wrong (its corners black), its "
                  "light on surfaces right",
    "light_pdf": "the light sampled wrongly (its triangles sampled unevenly with a uniform pdf): the light seen right, "
                 "its light on surfaces not",
    "indirect_scale": "the indirect light wrong (the bounce's direction left in the local frame), the direct light "
                      "right",
    "direct_twice": "direct light counted twice (after a mirror bounce)",
    "specular_weight": "a perfect mirror's reflection weighted wrongly (its BSDF value over the cosine)",
    "resampling": "part of the image rendered at a lower resolution and enlarged (the indirect light)",
    "row_stride": "pixels written at the wrong addresses (tiles at their transposes' places)",
    "sample_count": "each pixel's sum divided by the nominal spp, not by the samples it kept (adds lost)",
    "biased_estimator": "a biased estimate of each pixel's mean (bright samples rejected)",
}
_WORDS = {**cases.CAUSES, **outside.CAUSES, **programs.NEW_CAUSES, **fresh.NEW_CAUSES, **blind.NEW_CAUSES,
          **unseen.NEW_CAUSES, **untried.NEW_CAUSES, **novel.NEW_CAUSES, **untold.NEW_CAUSES, **unmet.NEW_CAUSES,
          **unheard.NEW_CAUSES, **unsaid.NEW_CAUSES, **unasked.NEW_CAUSES, **unsought.NEW_CAUSES, **NEW_CAUSES,
          **_REWORDED}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = {c: _WORDS[c] for c in dict.fromkeys(s.cause for s in MISTAKES)}


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
