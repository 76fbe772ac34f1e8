r"""A seventeenth class of hand-ins: mistakes in students' tracers, scene input and output no class tried, written blind.

How it was written: from what goes wrong in students' programs (the steps
after rendering, the code that saves the image, the scene typed in or parsed,
the camera's look-at and sub-pixel offsets, the light's samples, the
integrator's loop and its mirror, the loops and workers that add up the
samples and place the rows and tiles), not from the grader. Its author read
the other classes' specs and cause words, the catalogue
(:mod:`mcrt.mutants`), the scene files and design notes, mcrt's scene,
camera and image code, :data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to
stay clear of their mistakes; never the grader's rules (what decides a
cause) nor its reports, and graded none of it, not one case. Each cause and
``major`` flag was set from the mistake alone; every mistake is worded by a
cause the other classes already have (:data:`NEW_CAUSES` is empty), so
``SAME_MISTAKE`` needed no new entry. The mistakes differ from those of the
sixteen other classes (:mod:`~mcrt.grade.accuracy.cases`,
:mod:`~mcrt.grade.accuracy.outside`, :mod:`~mcrt.grade.accuracy.programs`,
:mod:`~mcrt.grade.accuracy.fresh`, :mod:`~mcrt.grade.accuracy.blind`,
:mod:`~mcrt.grade.accuracy.unseen`, :mod:`~mcrt.grade.accuracy.untried`,
:mod:`~mcrt.grade.accuracy.novel`, :mod:`~mcrt.grade.accuracy.untold`,
:mod:`~mcrt.grade.accuracy.unmet`, :mod:`~mcrt.grade.accuracy.unheard`,
:mod:`~mcrt.grade.accuracy.unsaid`, :mod:`~mcrt.grade.accuracy.unasked`,
:mod:`~mcrt.grade.accuracy.unsought`, :mod:`~mcrt.grade.accuracy.unguessed`,
:mod:`~mcrt.grade.accuracy.unforeseen`) and from the catalogue's bugs:

* **post-processing**: a 3 x 3 box blur written with ``np.roll`` (the
  image's opposite edges wrapped in); every pixel's luminance capped at 4
  times the image's mean (a firefly cap, the hue kept); a lens's cos^4
  fall-off "corrected" on a pinhole render (each pixel divided by it); a
  frequency-domain low-pass denoiser whose ``fftshift`` went to the image it
  returns (its quadrants swapped);
* **writing the file**: a Radiance HDR whose shared exponent comes from the
  red channel alone (green and blue mantissas wrapped past 255); the film's
  per-sample variance buffer written for the mean; RGBE pixels packed into a
  32-bit word written little-endian (bytes E, B, G, R); the PNG's gamma
  written ``v ** 1 / 2.2`` (Python's precedence: v / 2.2);
* **materials**: every colour's channels reversed by the scene loader (an
  OpenCV-style BGR habit); every wall given the mean of the walls' colours
  (``mean(axis=0)``); the ceiling given a template's white (1, 1, 1);
* **geometry**: the room built as a regular hexagon through A and D (the
  corners computed, not read); the sphere's radius squared passed where the
  radius goes (2.25); the tetrahedron's twelve numbers read back as
  ``reshape(3, 4).T``;
* **camera**: a look-at helper's arguments in the wrong order (the up vector
  taken for the target, the forward vector for the up); the sub-pixel
  offsets squared (``u * u``, a tent filter attempted); a template's default
  field of view, 60 degrees, kept (the scene's key misspelt);
* **light model**: the light's half-width forgotten in x only (a 4 x 2
  light); its samples drawn from the disk round it (radius half its
  diagonal) and all counted; its radiance divided by pi in the light sample
  only;
* **integrator**: Russian roulette's test placed before the light sample,
  which is not divided by the survival; the cosine applied twice in the
  diffuse bounce's weight; the mirror's reflected ray leaving from the eye
  (the origin never moved to the hit point); the cosine-weighted disk's
  radius ``u`` for ``sqrt(u)``;
* **samples and passes**: rows handed to 4 workers by stride and stacked
  worker by worker; the pixel's sum updated inside the bounce loop with the
  path's running radiance; 12 x 12 tiles, the remainder of 64 never
  rendered; each sample's luminance clamped to 10 (the hue kept).

The correct hand-ins come in ways no class used: Mitsuba with sub-pixel
offsets from the Halton (2, 3) points shifted at random in each pixel,
Mitsuba with every mesh written to an OBJ file (shared vertices) and loaded
by its ``obj`` plugin, a float EXR with ZIP compression, an 8-bit PNG written
by hand with the Paeth filter on every row, mcrt twice with the light's
radiance halved and the two renders summed, Mitsuba with the sphere an
instance of a shape group, Mitsuba with the six walls one mesh coloured per
face (a ``face_color`` attribute), and Mitsuba with the floor's and the
ceiling's greys typed as uniform textures.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s
``edit`` and ``mitsuba_edit``), Mitsuba renders combined where light
transport or pixel integrals are linear in what is combined (paths by
length, the light's samples apart from the light seen), Mitsuba's path
integrator sampling the rays a student's camera, mirror or bounce makes (the
helpers of :mod:`~mcrt.grade.accuracy.unsaid`), or its samples, one by one,
added up as a student's loop adds them
(:func:`mcrt.grade.accuracy.unasked._samples`,
:func:`mcrt.grade.accuracy.unsought._film_samples`), or correct renders
post-processed and written with NumPy and the standard library as students'
programs do. mcrt renders only correct hand-ins.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over
:data:`CATEGORIES`: the 2nd, 4th, ... of each category and of the correct
hand-ins) are as in :mod:`~mcrt.grade.accuracy.unforeseen`, fixed before any
case was graded.
"""

from __future__ import annotations

import math
import struct
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unforeseen, unguessed,
                                 unheard, unmet, unsaid, unseen, unsought, untold, untried)
from mcrt.grade.accuracy.cases import Spec

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


def _crc(name: str) -> int:
    return 401000 + zlib.crc32(name.encode()) % 100000


_render = unseen._render
_posted = unseen._posted

#: The class's spp (the class is built at 64 x 64).
_S = 256
#: The assignment's maximum depth.
_DEPTH = 8


def _scene():
    from mcrt.scene import load_scene

    return load_scene()


# --------------------------------------------------------------------------
# Post-processing (linear render in, what the program writes out)
# --------------------------------------------------------------------------


def _roll_box_blur(x):
    """A 3 x 3 box blur written with ``np.roll``: each pixel the mean of itself and its 8 neighbours, the image's
    opposite edges wrapped in at the borders."""
    x = np.asarray(x, np.float64)
    return sum(np.roll(np.roll(x, dy, axis=0), dx, axis=1) for dy in (-1, 0, 1) for dx in (-1, 0, 1)) / 9.0


def _luminance_capped(x, *, k: float = 4.0):
    """Every pixel whose luminance exceeds ``k`` times the image's mean luminance scaled down to it (the hue kept)."""
    x = np.asarray(x, np.float64)
    y = unseen._luma(x)
    cap = k * float(y.mean())
    scale = np.where(y > cap, cap / np.maximum(y, 1e-300), 1.0)
    return x * scale[..., None]


def _cos_ray(h: int, w: int) -> np.ndarray:
    """(H, W): the cosine of the angle between each pixel centre's ray and the view (90 degrees across)."""
    k = math.tan(math.radians(_scene().cameras["near"].fov_x_deg) / 2.0)
    s = k * (2.0 * (np.arange(w) + 0.5) / w - 1.0)
    t = k * (2.0 * (np.arange(h) + 0.5) / h - 1.0)
    return 1.0 / np.sqrt(1.0 + s[None, :] ** 2 + t[:, None] ** 2)


def _devignetted(x):
    """Each pixel divided by cos^4 of its ray's angle (a lens's fall-off 'corrected' on a pinhole render)."""
    x = np.asarray(x, np.float64)
    return x / _cos_ray(*x.shape[:2])[..., None] ** 4


def _fft_lowpass_shifted(x, *, sigma: float = 0.25):
    """A Gaussian low-pass in the frequency domain (``np.fft.fft2``, sigma ``sigma`` cycles a pixel), its result
    passed through ``np.fft.fftshift`` (meant for the spectrum): the image's quadrants swapped, negatives clipped."""
    x = np.asarray(x, np.float64)
    h, w = x.shape[:2]
    f2 = np.fft.fftfreq(h)[:, None] ** 2 + np.fft.fftfreq(w)[None, :] ** 2
    gain = np.exp(-f2 / (2.0 * sigma * sigma))
    y = np.real(np.fft.ifft2(np.fft.fft2(x, axes=(0, 1)) * gain[..., None], axes=(0, 1)))
    return np.maximum(np.fft.fftshift(y, axes=(0, 1)), 0.0)


# --------------------------------------------------------------------------
# Files as students' programs write them (the program's buffer in, file out)
# --------------------------------------------------------------------------


def _write_hdr_flat(pixels: np.ndarray, folder: Path) -> Path:
    """A Radiance HDR of the (H, W, 4) RGBE bytes ``pixels``, flat scanlines, top row first."""
    h, w = pixels.shape[:2]
    path = folder / "render.hdr"
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"-Y {h} +X {w}\n".encode()
                     + np.ascontiguousarray(pixels, np.uint8).tobytes())
    return path


def _rgbe_red_exponent(image: np.ndarray) -> np.ndarray:
    """(H, W, 4) RGBE bytes whose shared exponent is the red channel's (``frexp(r)``), not the largest channel's:
    each mantissa ``int(c * 256 / 2^e)`` cast to a byte (past 255 it wraps), the exponent byte e + 128."""
    a = np.maximum(np.nan_to_num(np.asarray(image, np.float64)), 0.0)
    _, e = np.frexp(a[..., 0])
    m = np.floor(a * np.ldexp(1.0, 8 - e)[..., None]).astype(np.int64) % 256
    out = np.zeros(a.shape[:2] + (4,), np.uint8)
    out[..., :3] = m.astype(np.uint8)
    out[..., 3] = np.clip(e + 128, 0, 255).astype(np.uint8)
    return out


def _write_hdr_red_exponent(image: np.ndarray, folder: Path) -> Path:
    return _write_hdr_flat(_rgbe_red_exponent(image), folder)


def _rgbe_word_little_endian(image: np.ndarray) -> np.ndarray:
    """Correct RGBE pixels (mcrt's encoder) packed as the word ``r << 24 | g << 16 | b << 8 | e`` and written
    little-endian: the bytes E, B, G, R for R, G, B, E."""
    from mcrt.image_files import _rgbe_encode

    rgbe = _rgbe_encode("render.hdr", np.maximum(np.nan_to_num(np.asarray(image, np.float64)), 0.0))
    words = ((rgbe[..., 0].astype(np.uint32) << 24) | (rgbe[..., 1].astype(np.uint32) << 16)
             | (rgbe[..., 2].astype(np.uint32) << 8) | rgbe[..., 3].astype(np.uint32))
    return np.ascontiguousarray(words.astype("<u4")).view(np.uint8).reshape(rgbe.shape)


def _write_hdr_word_little_endian(image: np.ndarray, folder: Path) -> Path:
    return _write_hdr_flat(_rgbe_word_little_endian(image), folder)


def _gamma_precedence_codes(image: np.ndarray) -> np.ndarray:
    """8-bit codes of ``v ** 1 / 2.2`` (Python reads (v ** 1) / 2.2): the linear values over 2.2, clipped, rounded."""
    v = np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, None)
    return np.floor(np.clip(v ** 1 / 2.2, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def _write_png_gamma_precedence(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_gamma_precedence_codes(image), folder)


def _variance_buffer(x, *, spp: int, seed: int):
    """The film's per-sample variance buffer of a Mitsuba path render of ``spp`` samples (written for its mean)."""
    from mcrt.mitsuba_scene import render_with_variance, scene_dict

    h, w = x.shape[:2]
    d = scene_dict(_scene(), "near", w, h, _DEPTH, spp=spp)
    return np.maximum(np.asarray(render_with_variance(d, spp=spp, seed=seed).variance, np.float64), 0.0)


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _reversed_colours(s):
    """Every albedo's channels reversed (the loader's BGR habit): the walls, the floor, the ceiling and the
    tetrahedron."""
    from mcrt.scene import Lambertian

    def rev(a):
        return tuple(float(c) for c in tuple(a)[::-1])

    walls = tuple(replace(w, albedo=rev(w.albedo)) for w in s.room.walls)
    room = replace(s.room, walls=walls, floor_albedo=rev(s.room.floor_albedo),
                   ceiling_albedo=rev(s.room.ceiling_albedo))
    objects = tuple(replace(o, material=replace(o.material, albedo=rev(o.material.albedo)))
                    if isinstance(o.material, Lambertian) else o for o in s.objects)
    return replace(s, room=room, objects=objects)


def _walls_mean(s):
    """Every wall given the mean of the six walls' albedos (``np.mean(albedos, axis=0)`` for the wall's own row)."""
    mean = tuple(float(c) for c in np.mean([w.albedo for w in s.room.walls], axis=0))
    return replace(s, room=replace(s.room, walls=tuple(replace(w, albedo=mean) for w in s.room.walls)))


def _regular_corners(s) -> dict[str, tuple[float, float]]:
    """The corners of the regular hexagon through A and D (centre their midpoint, circumradius half their distance),
    A at 180 degrees and each next corner 60 degrees on, counter-clockwise."""
    a, d = np.asarray(s.room.corners["A"], np.float64), np.asarray(s.room.corners["D"], np.float64)
    c, r = (a + d) / 2.0, float(np.linalg.norm(d - a)) / 2.0
    return {k: (float(c[0] + r * math.cos(math.radians(180.0 + 60.0 * i))),
                float(c[1] + r * math.sin(math.radians(180.0 + 60.0 * i))))
            for i, k in enumerate("ABCDEF")}


def _regular_hexagon(s):
    return replace(s, room=replace(s.room, corners=_regular_corners(s)))


def _sphere_radius_squared(s):
    """The sphere's radius squared (2.25) passed where its radius goes."""
    return replace(s, objects=tuple(replace(o, radius=o.radius ** 2) if o.name == "sphere" else o for o in s.objects))


def _column_major(vertices):
    """The tetrahedron's 12 numbers read back as ``np.reshape(flat, (3, 4)).T``: vertex i = (flat[i], flat[4 + i],
    flat[8 + i])."""
    flat = np.asarray(vertices, np.float64).reshape(-1)
    return tuple(tuple(float(c) for c in v) for v in flat.reshape(3, 4).T)


def _tetra_column_major(s):
    return unguessed._tetra_vertices(s, _column_major)


def _look_at_swapped(s):
    """``look_at(eye, up, forward)`` for ``look_at(eye, eye + forward, up)``: the target the point (0, 0, 1) (the up
    vector), the up hint (1, 0, 0) (the forward vector): forward (1, 0, 1) from the eye (-1, 0, 0)."""
    c = s.cameras["near"]
    target = np.asarray(c.up, np.float64)
    forward = tuple(float(v) for v in target - np.asarray(c.eye, np.float64))
    return cases._camera(s, forward=forward, up=tuple(float(v) for v in c.forward))


def _disk_tris(*, segments: int = 96) -> np.ndarray:
    """(segments, 3, 3): a disk about the light's centre of radius half the light's diagonal, facing down."""
    from mcrt.mitsuba_scene import _light_surface
    from mcrt.scene import Surface

    lt = _scene().light
    cx, cy, z = lt.center
    r = math.hypot(lt.size[0], lt.size[1]) / 2.0
    a = np.linspace(0.0, 2.0 * math.pi, segments + 1)
    tris = np.array([[(cx, cy, z), (cx + r * math.cos(a[k]), cy + r * math.sin(a[k]), z),
                      (cx + r * math.cos(a[k + 1]), cy + r * math.sin(a[k + 1]), z)] for k in range(segments)])
    return np.array(_light_surface(Surface("disk", tris, None), (0.0, 0.0, -1.0)).triangles, np.float64)


def _light_disk_for_samples(d: dict) -> dict:
    """The light as its samples see it: the disk of :func:`_disk_tris` at the light's radiance."""
    return unsaid._meshes(d, light=(_disk_tris(), _scene().light.radiance))


def _obj_text(tris: np.ndarray) -> str:
    """An OBJ of the triangles ``tris`` (n, 3, 3) with shared vertices (``v`` lines, then ``f`` lines, 1-based)."""
    verts, index = np.unique(np.asarray(tris, np.float64).reshape(-1, 3), axis=0, return_inverse=True)
    index = np.asarray(index).reshape(-1, 3) + 1
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in verts.tolist()] + [f"f {a} {b} {c}" for a, b, c in index.tolist()]
    return "\n".join(lines) + "\n"


def _from_obj(d: dict) -> dict:
    """Every mesh of the scene written to an OBJ file (shared vertices) and loaded back by Mitsuba's ``obj`` plugin
    with face normals, its BSDF and emitter from the scene."""
    import tempfile

    import mitsuba as mi

    from mcrt.mitsuba_scene import _bsdf_dict, _light_surface, _rgb

    s = _scene()
    out = dict(d)
    with tempfile.TemporaryDirectory() as tmp:
        for sf in s.surfaces():
            if sf.material is None:
                sf = _light_surface(sf, s.light.normal)
            path = Path(tmp) / f"{sf.name}.obj"
            path.write_text(_obj_text(sf.triangles))
            shape = {"type": "obj", "filename": str(path), "face_normals": True, "bsdf": _bsdf_dict(sf.material)}
            if sf.material is None:
                shape["emitter"] = {"type": "area", "radiance": _rgb(s.light.radiance)}
            out[sf.name] = mi.load_dict(shape)
    return out


def _sphere_instanced(d: dict) -> dict:
    """The sphere put in a shape group and placed by an ``instance`` of it (no transform): the same sphere."""
    out = {k: v for k, v in d.items() if k != "sphere"}
    out["sphere_group"] = {"type": "shapegroup", "sphere": dict(d["sphere"])}
    out["sphere"] = {"type": "instance", "shapegroup": {"type": "ref", "id": "sphere_group"}}
    return out


def _walls_face_coloured(d: dict) -> dict:
    """The six walls one mesh, each face coloured by its wall's albedo (a ``face_color`` attribute read by a
    two-sided diffuse BSDF's ``mesh_attribute`` texture)."""
    import mitsuba as mi

    tris, colours = [], []
    for w in _scene().room.walls:
        t = np.asarray(fresh._surface(f"wall_{w.corners[0]}{w.corners[1]}").triangles, np.float64)
        tris.append(t)
        colours += [w.albedo] * len(t)
    tris = np.concatenate(tris)
    n = len(tris)
    props = mi.Properties()
    props["bsdf"] = mi.load_dict({"type": "twosided", "bsdf": {
        "type": "diffuse", "reflectance": {"type": "mesh_attribute", "name": "face_color"}}})
    mesh = mi.Mesh("walls", 3 * n, n, props)
    mesh.add_attribute("face_color", 3, mi.Float(np.asarray(colours, np.float32).reshape(-1)))
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(tris.reshape(-1).astype(np.float32))
    params["faces"] = mi.UInt32(np.arange(3 * n, dtype=np.uint32))
    params.update()
    out = {k: v for k, v in d.items() if not k.startswith("wall_")}
    out["walls"] = mesh
    return out


def _greys_uniform(d: dict) -> dict:
    """The floor's and the ceiling's grey reflectances typed as ``uniform`` textures (one number each)."""
    for name in ("floor", "ceiling"):
        sf = fresh._surface(name)
        bsdf = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {
            "type": "uniform", "value": float(sf.material.albedo[0])}}}
        d = fresh._rebuilt(d, name, sf.triangles, bsdf)
    return d


# --------------------------------------------------------------------------
# The camera's sub-pixel offsets (Mitsuba's samples through them, unsought._film_samples)
# --------------------------------------------------------------------------


def _squared_offsets(rng, n: int, *, w: int, pixels: int):
    """Sub-pixel offsets ``u * u``, ``v * v`` (a tent filter attempted): crowded towards each pixel's top-left corner,
    their mean a third of a pixel in."""
    u, v = rng.random((2, pixels, n))
    return u * u, v * v


def _radical_inverse(i: np.ndarray, base: int) -> np.ndarray:
    i = np.asarray(i, np.int64).copy()
    out, f = np.zeros(i.shape), 1.0 / base
    while np.any(i > 0):
        out += f * (i % base)
        i //= base
        f /= base
    return out


def _halton(rng, n: int, *, w: int, pixels: int):
    """Sub-pixel offsets the Halton (2, 3) points 1..n, shifted at random in each pixel (Cranley-Patterson): every
    offset uniform on the pixel."""
    i = np.arange(1, n + 1)
    shift = rng.random((2, pixels, 1))
    return np.mod(_radical_inverse(i, 2) + shift[0], 1.0), np.mod(_radical_inverse(i, 3) + shift[1], 1.0)


# --------------------------------------------------------------------------
# Renderer mistakes realised with Mitsuba renders combined, on rays, or sample by sample
# --------------------------------------------------------------------------


def _roulette_before_light_sample(x, *, spp: int, seed: int, start: int = 3, survival: float = 0.5):
    """Russian roulette from vertex ``start`` tested before the vertex's light sample, the survivors' throughput divided
    by ``survival`` only for the bounce after it: every light sample from ``start`` on counted ``survival`` times
    (the continuation unbiased). Same-seed Mitsuba renders: the paths of at most ``start`` segments plus
    ``survival`` times the rest."""
    h, w = x.shape[:2]
    full, short = _render(w, h, spp, seed), _render(w, h, spp, seed, max_depth=start)
    return short + survival * (full - short)


def _cosine_directions(rng, n: np.ndarray, *, sqrt_radius: bool = True):
    """(directions, cosines) about the unit normals ``n`` (N, 3) from a disk sample of radius ``sqrt(u1)`` (or
    ``u1``) lifted to the hemisphere."""
    u1, u2 = rng.random((2, len(n)))
    r = np.sqrt(u1) if sqrt_radius else u1
    cos = np.sqrt(np.maximum(1.0 - r * r, 0.0))
    t, b = unforeseen._frame_of(n)
    phi = 2.0 * math.pi * u2
    return (r * np.cos(phi))[:, None] * t + (r * np.sin(phi))[:, None] * b + cos[:, None] * n, cos


def _cosine_twice(rng, n):
    """Cosine-weighted directions whose weight is the albedo times the cosine again (f cos^2 / pdf)."""
    return _cosine_directions(rng, n)


def _radius_without_sqrt(rng, n):
    """Directions from a disk radius ``u1`` for ``sqrt(u1)`` (too many near the normal), weighted by the albedo as
    cosine-weighted samples."""
    d, _ = _cosine_directions(rng, n, sqrt_radius=False)
    return d, np.ones(len(n))


def _first_bounce(x, *, spp: int, seed: int, draw):
    """The diffuse bounce at the first surface a camera ray meets drawn by ``draw`` (rng, normals) -> (directions,
    weights), weighted by the albedo times the weight: its light sample right (Mitsuba's max-depth-2 sample minus
    max-depth-1, same seed), the bounce going on from the hit point with Mitsuba's path of the 7 segments left less
    the emission it sees at once (a student's tracer counts the light by light samples). Mirror and light hits,
    Mitsuba's."""
    h, w = x.shape[:2]
    full, two, one, rest = unsaid._loaded(8), unsaid._loaded(2), unsaid._loaded(1), unsaid._loaded(7)
    rng = np.random.default_rng(seed + 13)
    total = np.zeros((h * w, 3))
    for cseed, n, fx, fy in unsaid._lanes(w, h, spp, seed):
        o, d = unsaid._pinhole(fx, fy)
        o, d = np.array(o, np.float64), np.asarray(d, np.float64)
        L = unsaid._sampled(full, o, d, cseed)
        rho = unsaid._first_albedo(full, o, d)
        t, valid = unguessed._first_hit(full, o, d)
        diffuse = valid & (rho.max(axis=1) > 0.0)
        if diffuse.any():
            od, dd = o[diffuse], d[diffuse]
            direct = unsaid._sampled(two, od, dd, cseed) - unsaid._sampled(one, od, dd, cseed)
            nrm = unforeseen._first_normal(full, od, dd)
            p = od + t[diffuse, None] * dd
            nd, weight = draw(rng, nrm)
            po = p + 1e-4 * nrm
            cont = unsaid._sampled(rest, po, nd, cseed + 104729) - unsaid._sampled(one, po, nd, cseed + 104729)
            L[diffuse] = direct + rho[diffuse] * weight[:, None] * cont
        total += L.reshape(h * w, n, 3).sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _reflect_from_eye(o, d):
    """Camera rays that meet the sphere reflected there, the reflected ray leaving from the ray's old origin (the eye)
    for the hit point: (origins, directions, segments used)."""
    _, r, hit = unsaid._reflected(o, d)
    return o, r, hit


def _pixel_sum_in_bounce_loop(x, *, spp: int, seed: int, depth: int = _DEPTH):
    """``pixel += L / spp`` inside the bounce loop, L the path's running radiance: the light of a path's k-th
    segment counted depth + 1 - k times. Same-seed Mitsuba renders of max depth 1 to ``depth``, summed."""
    h, w = x.shape[:2]
    return sum(_render(w, h, spp, seed, max_depth=k) for k in range(1, depth + 1))


def _rows_strided(x, *, workers: int = 4):
    """Rows handed out by stride (worker k rendering rows k, k + workers, ...) and the workers' results stacked one
    after another: four copies of the image, each from every fourth row."""
    x = np.asarray(x, np.float64)
    return np.concatenate([x[k::workers] for k in range(workers)], axis=0)


def _tiles_remainder_black(x, *, tile: int = 12):
    """Tiles of ``tile`` x ``tile`` pixels, ``range(W // tile)`` of them a row and a column: the last W mod ``tile``
    rows and columns never rendered (black)."""
    out = np.array(x, np.float64)
    h, w = out.shape[:2]
    out[(h // tile) * tile:] = 0.0
    out[:, (w // tile) * tile:] = 0.0
    return out


def _luminance_clamped_samples(x, *, spp: int, seed: int, limit: float = 10.0):
    """Each of Mitsuba's samples whose luminance exceeds ``limit`` scaled down to it (the hue kept), then averaged."""
    h, w = x.shape[:2]
    total = np.zeros((h * w, 3))
    for L, _, _ in unasked._samples(w, h, spp, seed):
        y = L @ programs._LUMA
        scale = np.where(y > limit, limit / np.maximum(y, 1e-300), 1.0)
        total += (L * scale[..., None]).sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _mcrt_light_halves(x, *, spp: int, seed: int):
    """mcrt twice with the light's radiance halved (10), two seeds, the two renders summed: light transport is linear
    in the emission."""
    half = cases.light(radiance=tuple(a / 2.0 for a in _scene().light.radiance))
    return sum(unsaid._mcrt_scene(x, spp=spp, seed=seed + k, scene_edit=half) for k in (0, 1))


# --------------------------------------------------------------------------
# Correct files written in other ways
# --------------------------------------------------------------------------


def _write_exr_zip(image: np.ndarray, folder: Path) -> Path:
    """A float EXR (R, G, B) with ZIP compression (16 scanlines a block, lossless)."""
    import OpenEXR

    path = folder / "render.exr"
    chans = {c: np.ascontiguousarray(image[..., i], np.float32) for i, c in enumerate("RGB")}
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}, chans).write(str(path))
    return path


def _paeth_filtered(codes: np.ndarray) -> bytes:
    """The PNG scanlines of (H, W, 3) 8-bit codes, each with filter type 4 (Paeth: each byte less the predictor of
    its left, upper and upper-left bytes)."""
    rows = codes.astype(np.int16).reshape(codes.shape[0], -1)
    out = []
    above = np.zeros_like(rows[0])
    for r in rows:
        a = np.concatenate([np.zeros(3, np.int16), r[:-3]])
        b = above
        c = np.concatenate([np.zeros(3, np.int16), above[:-3]])
        p = a + b - c
        pa, pb, pc = np.abs(p - a), np.abs(p - b), np.abs(p - c)
        pred = np.where((pa <= pb) & (pa <= pc), a, np.where(pb <= pc, b, c))
        out.append(b"\x04" + ((r - pred) % 256).astype(np.uint8).tobytes())
        above = r
    return b"".join(out)


def _write_png_paeth(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB PNG written by hand: IHDR, one IDAT of the zlib stream of Paeth-filtered rows, IEND."""
    h, w = image.shape[:2]
    data = (b"\x89PNG\r\n\x1a\n" + unseen._png_chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
            + unseen._png_chunk(b"IDAT", zlib.compress(_paeth_filtered(blind._srgb8(image)), 9))
            + unseen._png_chunk(b"IEND", b""))
    path = folder / "render.png"
    path.write_bytes(data)
    return path


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_roll_box_blur", "pp_luminance_capped_at_mean", "pp_devignette_cos4",
                        "pp_fft_lowpass_shifted"),
    "file": ("file_hdr_exponent_from_red", "file_exr_variance_buffer", "file_hdr_rgbe_word_little_endian",
             "file_png_gamma_precedence"),
    "materials": ("albedos_channels_reversed", "walls_mean_colour", "ceiling_template_white"),
    "geometry": ("room_regular_hexagon", "sphere_radius_squared", "tetra_vertices_reshaped_transposed"),
    "camera": ("look_at_arguments_swapped", "jitter_squared", "fov_template_default_60"),
    "light": ("light_half_width_x_only", "light_sampled_circumscribed_disk", "light_sample_radiance_over_pi"),
    "integrator": ("roulette_before_light_sample", "bounce_cosine_twice", "mirror_ray_from_eye",
                   "bounce_disk_radius_without_sqrt"),
    "samples": ("workers_rows_strided", "pixel_sum_in_bounce_loop", "tiles_12_remainder_unrendered",
                "samples_luminance_clamped_10"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    c = _crc
    return (
        # Post-processing
        Spec("pp_roll_box_blur", "blur", **_posted("roll_box_blur", _roll_box_blur),
             truth="a 3 x 3 box blur written with np.roll (the mean of the image and its 8 shifted copies) after "
             "rendering, as EXR: blurred, the opposite edge's colours wrapped into the border pixels"),
        Spec("pp_luminance_capped_at_mean", "tone_map", held_out=True,
             **_posted("luminance_capped", _luminance_capped),
             truth="a firefly cap after rendering: every pixel whose luminance exceeds 4 times the image's mean "
             "luminance scaled down to it (the hue kept), as EXR: the light and its reflection dimmed, the rest "
             "right"),
        Spec("pp_devignette_cos4", "falloff", True, **_posted("devignetted", _devignetted),
             truth="a lens's cos^4 fall-off 'corrected' on the pinhole render (each pixel divided by cos^4 of its "
             "ray's angle to the view), as EXR: the corners up to 9 times too bright"),
        Spec("pp_fft_lowpass_shifted", "row_stride", True, held_out=True,
             **_posted("fft_shifted", _fft_lowpass_shifted),
             truth="a frequency-domain denoiser (a Gaussian low-pass on np.fft.fft2, sigma 0.25 cycles a pixel) "
             "whose np.fft.fftshift, meant for the spectrum, went to the image it returns, as EXR: the image's four "
             "quadrants swapped (shifted by half its width and height), lightly smoothed"),
        # Writing the file
        Spec("file_hdr_exponent_from_red", "code_overflow", True, writer=_write_hdr_red_exponent,
             file="hdr-red-exponent",
             truth="a Radiance HDR written by hand whose shared exponent comes from the red channel (frexp(r)), not "
             "the largest: green and blue mantissas over 255 wrap round in the byte cast (the blue and green walls "
             "and every pixel where red is smaller come out wrong)"),
        Spec("file_exr_variance_buffer", "wrong_buffer", True, held_out=True, **_posted("variance_buffer", partial(
            _variance_buffer, spp=_S, seed=c("file_exr_variance_buffer"))),
             truth="the film's per-sample variance buffer written to the EXR for the mean buffer (the two "
             "buffers' names mixed up): zero where every sample agrees (the light), large where the samples vary"),
        Spec("file_hdr_rgbe_word_little_endian", "file_format", True, writer=_write_hdr_word_little_endian,
             file="hdr-rgbe-word-le",
             truth="a Radiance HDR written by hand, each pixel packed as the 32-bit word r << 24 | g << 16 | b << 8 "
             "| e and written little-endian: the bytes E, B, G, R read as R, G, B, E (the exponent taken from the "
             "red mantissa)"),
        Spec("file_png_gamma_precedence", "encoding", True, held_out=True, writer=_write_png_gamma_precedence,
             file="png-v-over-2.2",
             truth="an 8-bit PNG of v ** 1 / 2.2 (for v ** (1 / 2.2): Python's precedence makes it v / 2.2): linear "
             "codes at 1/2.2 of the values, read as sRGB (much too dark)"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("albedos_channels_reversed", "albedo", True, edit=_reversed_colours,
             truth="every colour's channels reversed by the scene loader (an OpenCV-style BGR habit, albedo[::-1]): "
             "the red wall AB blue (0.15, 0.15, 0.75), the blue wall DE red, the tetrahedron blue (0.1, 0.45, 0.8)"),
        Spec("walls_mean_colour", "albedo", True, held_out=True, edit=_walls_mean,
             truth="every wall given the mean of the six walls' colours (np.mean over axis 0 of the colour table, "
             "for the wall's own row): all six walls (0.417, 0.425, 0.433), a grey"),
        Spec("ceiling_template_white", "albedo", True, edit=partial(untold._ceiling_albedo, albedo=(1.0, 1.0, 1.0)),
             truth="the ceiling given a template's white (1, 1, 1) for 0.8 (its colour never read): the ceiling "
             "and, by its light, the whole room brighter"),
        # Geometry
        Spec("room_regular_hexagon", "object_moved", True, edit=_regular_hexagon,
             truth="the room built as a regular hexagon through A (-3, 0) and D (13, 0) (the corners computed, not "
             "read): B (1, -6.93), C (9, -6.93), E (9, 6.93), F (1, 6.93), every wall but none of its ends where it "
             "belongs"),
        Spec("sphere_radius_squared", "object_size", True, held_out=True, edit=_sphere_radius_squared,
             truth="the sphere's radius squared (2.25, kept for the intersection test) passed where its radius goes: "
             "a mirror ball of radius 2.25 for 1.5, sunk through the floor"),
        Spec("tetra_vertices_reshaped_transposed", "object_shape", True, edit=_tetra_column_major,
             truth="the tetrahedron's 12 numbers read back as np.reshape(flat, (3, 4)).T (x's, y's and z's taken "
             "from the flat list's thirds): vertices (7.5, -1, -4.9), (-2, -4.9, 8.5), (-4.9, 8.5, -2.3), (9.5, "
             "-3.8, -2): a huge sliver through the room, its walls and the ceiling, across the view and between "
             "the light and most of the room (the image nearly dark)"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera
        Spec("look_at_arguments_swapped", "camera_rotation", True, edit=_look_at_swapped,
             truth="a look-at helper called look_at(eye, up, forward) for look_at(eye, eye + forward, up): the "
             "camera aimed at the point (0, 0, 1), 45 degrees up, with (1, 0, 0) for its up: the ceiling and the "
             "light seen, the image upside down"),
        Spec("jitter_squared", "pixel_footprint", held_out=True, **_posted("jitter_squared", partial(
            unforeseen._mean_through, spp=_S, seed=c("jitter_squared"), jitter=_squared_offsets)),
             truth="the sub-pixel offsets squared, u * u and v * v (a tent filter attempted): each pixel's samples "
             "crowded towards its top-left corner, their mean a third of a pixel in (the image a sixth of a pixel "
             "off, a little sharper)"),
        Spec("fov_template_default_60", "camera_fov", True, edit=cases.fov(60.0),
             truth="the scene's field-of-view key misspelt, so the template's default 60 degrees was used for 90: "
             "the view narrower, the middle magnified"),
        # Light model
        Spec("light_half_width_x_only", "light_size", True, edit=cases.light(size=(4.0, 2.0)),
             truth="the light's half-width forgotten in x only (hx = size[0], hy = size[1] / 2): a 4 x 2 light "
             "for the 2 x 2, same radiance, its hole in the ceiling with it"),
        Spec("light_sampled_circumscribed_disk", "light_pdf", True, held_out=True,
             **_posted("light_disk_samples", partial(unheard._light_changed_for_samples, spp=_S,
                                                     seed=c("light_sampled_circumscribed_disk"),
                                                     dict_edit=_light_disk_for_samples)),
             truth="the light's samples drawn from a disk sampler reused, radius half the light's diagonal (1.41), "
             "with the disk's pdf and every sample counted (the points off the square too): its light on surfaces "
             "from a disk of 6.28 for the 4 square units, the light seen right"),
        Spec("light_sample_radiance_over_pi", "light_pdf", True, **_posted("light_sample_over_pi", partial(
            unheard._light_changed_for_samples, spp=_S, seed=c("light_sample_radiance_over_pi"),
            scene_edit=cases.light(radiance=(20.0 / math.pi,) * 3))),
             truth="the light's radiance divided by pi in the light sample only (the emitter taken for a Lambertian's "
             "exitance): its light on surfaces 1/pi of the truth, the light seen directly and in the mirror right"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples, passes, workers and tiles."""
    c = _crc
    return (
        # Integrator
        Spec("roulette_before_light_sample", "roulette", True, **_posted("roulette_before_light", partial(
            _roulette_before_light_sample, spp=_S, seed=c("roulette_before_light_sample"))),
             truth="Russian roulette from the 3rd vertex with survival 0.5 tested before the vertex's light sample, "
             "the survivors' throughput divided by 0.5 only for the bounce after it: the light of paths of 4 "
             "segments or more counted half"),
        Spec("bounce_cosine_twice", "indirect_scale", True, held_out=True, **_posted("bounce_cosine_twice", partial(
            _first_bounce, spp=_S, seed=c("bounce_cosine_twice"), draw=_cosine_twice)),
             truth="the diffuse bounce's weight the albedo times the cosine (f cos^2 / pdf: the cosine applied in the "
             "weight and again after it), at the first surface a camera ray meets; Mitsuba's path after it: the "
             "indirect light there two-thirds of the truth and from grazing directions less, the direct right"),
        Spec("mirror_ray_from_eye", "material", True, **_posted("mirror_from_eye", partial(
            unsaid._traced, spp=_S, seed=c("mirror_ray_from_eye"), after=_reflect_from_eye)),
             truth="the mirror's reflected direction computed but the ray's origin never moved to the hit point: "
             "each camera ray meeting the sphere goes on from the eye along its reflection, the sphere showing what "
             "the eye sees in those directions (behind and beside the camera)"),
        Spec("bounce_disk_radius_without_sqrt", "indirect_scale", held_out=True,
             **_posted("bounce_radius_u", partial(_first_bounce, spp=_S, seed=c("bounce_disk_radius_without_sqrt"),
                                                  draw=_radius_without_sqrt)),
             truth="the cosine-weighted bounce drawn from a disk of radius u1 for sqrt(u1), lifted to the hemisphere "
             "and weighted by the albedo as a cosine-weighted sample, at the first surface a camera ray meets; "
             "Mitsuba's path after it: too many directions near the normal, the indirect light from there "
             "overweighted, the direct right"),
        # Samples, passes, workers and tiles
        Spec("workers_rows_strided", "row_stride", True, **_posted("rows_strided", _rows_strided),
             truth="the rows handed to 4 workers by stride (worker k rendering rows k, k + 4, ...) and their results "
             "stacked worker by worker: the image as four copies one above the other, each from every fourth row"),
        Spec("pixel_sum_in_bounce_loop", "light_radiance", True, held_out=True, **_posted("sum_in_loop", partial(
            _pixel_sum_in_bounce_loop, spp=_S, seed=c("pixel_sum_in_bounce_loop"))),
             truth="pixel += L / spp inside the bounce loop (indented one level too deep), L the path's running "
             "radiance: the light of a path's k-th segment counted 9 - k times, the light itself 8 times, the "
             "direct light 7, the room several times too bright"),
        Spec("tiles_12_remainder_unrendered", "bad_pixels", True, **_posted("tiles_12", _tiles_remainder_black),
             truth="tiles of 12 x 12 pixels, range(W // 12) of them in each direction: the last 4 rows and "
             "columns (64 mod 12) never rendered, black"),
        Spec("samples_luminance_clamped_10", "sample_clamp", True, held_out=True, **_posted("samples_clamped_10",
                                                                                            partial(
            _luminance_clamped_samples, spp=_S, seed=c("samples_luminance_clamped_10"))),
             truth="each sample whose luminance exceeds 10 scaled down to it (a firefly clamp keeping the hue) "
             "before the pixel's mean: the light and its reflection at 10 for 20, the rare bright paths lost"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_halton_offsets", None, spp=196, **_posted("halton", partial(
            unforeseen._mean_through, spp=196, seed=c("ok_halton_offsets"), jitter=_halton)),
             truth="Mitsuba path 196 spp, sub-pixel offsets the Halton (2, 3) points shifted at random in each pixel "
             "(Cranley-Patterson), EXR"),
        Spec("ok_meshes_from_obj", None, held_out=True, spp=228, mitsuba_edit=_from_obj,
             truth="Mitsuba path 228 spp with every mesh written to an OBJ file (shared vertices) and loaded by "
             "Mitsuba's obj plugin, EXR"),
        Spec("ok_exr_zip", None, spp=212, writer=_write_exr_zip, file="exr-zip",
             truth="Mitsuba path 212 spp, a float EXR with ZIP compression"),
        Spec("ok_png_paeth_filter", None, held_out=True, spp=236, writer=_write_png_paeth, file="png-srgb-paeth",
             truth="Mitsuba path 236 spp, an 8-bit sRGB PNG written by hand with the Paeth filter on every row"),
        Spec("ok_mcrt_light_halves", None, spp=72, renderer="mcrt", **_posted("mcrt_light_halves", partial(
            _mcrt_light_halves, spp=72, seed=c("ok_mcrt_light_halves"))),
             truth="mcrt 72 spp twice with the light's radiance halved (10), two seeds, the renders summed, EXR"),
        Spec("ok_sphere_instanced", None, held_out=True, spp=252, mitsuba_edit=_sphere_instanced,
             truth="Mitsuba path 252 spp with the sphere in a shape group placed by an instance, EXR"),
        Spec("ok_walls_face_colours", None, spp=116, mitsuba_edit=_walls_face_coloured,
             truth="Mitsuba path 116 spp with the six walls one mesh coloured per face (a face_color attribute), "
             "EXR"),
        Spec("ok_greys_uniform", None, held_out=True, spp=276, mitsuba_edit=_greys_uniform,
             truth="Mitsuba path 276 spp with the floor's and the ceiling's greys typed as uniform textures, EXR"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "blur": "a filter after rendering (a box blur, the edges wrapped)",
    "tone_map": "a curve on the bright values before saving (a cap on the luminance)",
    "falloff": "each pixel weighted by its ray's angle (a lens's fall-off divided out)",
    "row_stride": "pixels computed or written for the wrong place (quadrants swapped, rows stacked by worker)",
    "code_overflow": "values past the top code wrapped round (an RGBE exponent from one channel)",
    "wrong_buffer": "another buffer written for the mean (the samples' variance)",
    "file_format": "the file's bytes in another layout than its format says (an RGBE word's bytes reversed)",
    "encoding": "the values' encoding (a gamma exponent written with the wrong precedence)",
    "albedo": "a surface's colour (channels reversed, walls' colours averaged, a template's white)",
    "object_moved": "an object moved (the room's walls)",
    "object_size": "an object's size (the sphere's radius squared)",
    "object_shape": "an object's shape (its vertices read in the wrong order)",
    "camera_rotation": "the camera's rotation (a look-at's arguments swapped)",
    "pixel_footprint": "each pixel's samples not spread over its square (offsets squared)",
    "camera_fov": "the camera's field of view (a default kept)",
    "light_size": "the light's size (one side doubled)",
    "light_pdf": "the light sampled wrongly (a disk for the square, its radiance divided by pi): the light seen "
                 "right, its light on surfaces not",
    "roulette": "Russian roulette's division in the wrong place (the light sample not divided by the survival)",
    "indirect_scale": "the indirect light wrong (the diffuse bounce's directions or weight), the direct light right",
    "material": "the mirror's reflection computed wrongly (its ray leaving from the eye)",
    "light_radiance": "a factor on the image or the light (a path's light added at every bounce)",
    "bad_pixels": "pixels never rendered (the rows and columns past the last whole tile)",
    "sample_clamp": "each sample clamped (its luminance capped)",
}
_WORDS = {**cases.CAUSES, **outside.CAUSES, **programs.NEW_CAUSES, **fresh.NEW_CAUSES, **blind.NEW_CAUSES,
          **unseen.NEW_CAUSES, **untried.NEW_CAUSES, **novel.NEW_CAUSES, **untold.NEW_CAUSES, **unmet.NEW_CAUSES,
          **unheard.NEW_CAUSES, **unsaid.NEW_CAUSES, **unasked.NEW_CAUSES, **unsought.NEW_CAUSES,
          **unguessed.NEW_CAUSES, **unforeseen.NEW_CAUSES, **NEW_CAUSES, **_REWORDED}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = {c: _WORDS[c] for c in dict.fromkeys(s.cause for s in MISTAKES)}


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
