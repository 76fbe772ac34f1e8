r"""A thirty-second class of hand-ins: mistakes of the workflow around students' tracers, not of their loops, blind.

How it was written: from what goes wrong around a tracer rather than inside it, in the steps a student takes between
the scene and the hand-in, not from the grader: render scripts and their configuration (YAML 1.1 as PyYAML reads it,
``off`` a boolean and ``051`` an octal number; JSON numbers that come back as integers into ``np.zeros_like``; an
environment variable's string concatenated in Node, ``"7" + 1``; a length with its unit parsed by a regular expression
that drops the sign; a percentage typed for a probability; Blender's Cycles settings exported with its defaults),
scene exporters and converters (Blender's OBJ exporter and its MTL's ``Kd`` and ``Ke``, its axes, its modifiers applied
on export, its lamps' size and object scale, its objects' origins, its camera's 16:9 frame and lens shift; three.js's
``MTLLoader``, which takes ``Kd`` for sRGB), progressive accumulation, checkpoints and resumed renders (a mean resumed
as a sum, a preset not stored in the checkpoint), time budgets (a pass cut off, frames of as many samples as fit), a
quarter-resolution preview left in the buffer, renders merged from several machines (tiles globbed in the shell's
order, a PFM read top row first), and the tools used to inspect and export the result (ImageMagick's ``-auto-gamma``,
Photoshop's ProPhoto RGB working space and ``Export As``, an HDR viewer's save with its exposure, a screenshot of the
preview under 125 % display scaling, render passes composited by hand). Its author read the other classes' specs and
cause words, the catalogue (:mod:`mcrt.mutants`), the scene files and design notes, mcrt's scene, camera and image
code, :data:`~mcrt.grade.accuracy.run.CAUSE_OF` and :data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words
and to stay clear of their mistakes; never the grader's rules (what decides a cause) nor its reports, and graded none of
it, not one case. Each cause and ``major`` flag was set from the mistake alone; every mistake is worded by a cause the
other classes already have (:data:`NEW_CAUSES` is empty), so ``SAME_MISTAKE`` needed no new entry. The mistakes differ
from those of the thirty other classes (:mod:`~mcrt.grade.accuracy.cases`, :mod:`~mcrt.grade.accuracy.outside` and the
modules of :data:`_EARLIER`, from :mod:`~mcrt.grade.accuracy.programs` to :mod:`~mcrt.grade.accuracy.unconsidered`)
and from the catalogue's bugs:

* **post-processing**: the config's ``tonemap: off``, which YAML 1.1 reads as ``False``, so the script's default
  branch ran Stephen Hill's fitted ACES curve before the EXR; ImageMagick's ``magick render.png -auto-gamma
  render.png`` to brighten the render (one gamma for the three channels, the mean taken to 50 %); the preview window
  screenshotted under Windows' 125 % display scaling (stretched bilinearly) and resized back with Pillow; render passes
  composited by hand, the diffuse direct and indirect passes added without the diffuse colour pass;
* **writing the file**: 16 tiles rendered apart and assembled with ``montage tile_*.png -tile 4x4`` (the shell's glob
  in text order: tile_10 after tile_1); the PNG opened in Photoshop set to convert to its ProPhoto RGB working space
  and exported with neither 'Convert to sRGB' nor the profile; the EXR opened in an HDR viewer at +0.5 EV and saved
  from it as a PNG (the view's exposure baked in); three machines' renders averaged by a script that reads the PFM of
  one of them top row first (that third upside down);
* **materials**: the albedos written as 8-bit codes with ``%03d`` and read by PyYAML, for which ``051`` and ``026`` are
  octal; the walls' colours, from a colour attribute in Blender, exported to the MTL as the BSDF's default ``Kd`` 0.8;
  every ``Kd`` read by three.js's ``MTLLoader``, which takes it for sRGB and decodes it;
* **geometry**: the tetrahedron exported from Blender with its axes as they are (Up Z) and read by a loader that turns
  OBJ's Y up into Z up; the walls' normals written into ``np.zeros_like`` of the JSON's integer corners (the four
  slanted walls' normals truncated to zero); the tetrahedron exported with Blender's Bevel modifier (0.1) applied;
* **camera**: the field of view written by an export script as the vertical one of Blender's 16:9 frame; Blender's
  lens Shift Y left at 0.1 and exported in the camera's projection; the eye ``"-1 m"`` parsed with
  ``re.search(r"[\d.]+", s)`` (the sign dropped);
* **light model**: the light's emissive plane exported with ``Ke`` its emission colour alone (the strength 20 dropped);
  a Blender area lamp's radiance from its power and its size without its object's scale; the light plane's centre
  taken from its object's origin, left at the 3D cursor (the room's centre);
* **integrator**: the maximum depth passed by a Node script as ``process.env.BOUNCES + 1`` (the string ``"71"``);
  Cycles' default 'Clamp Indirect' (10) exported with the render settings and applied to each sample's indirect
  light; a render resumed from its checkpoint with the preview preset's maximum depth (3); Russian roulette's survival
  typed 95 (a percentage);
* **samples and passes**: a checkpoint's mean image resumed as the sum buffer; a time budget that ran out during a
  pass, the rows it had reached divided by the passes completed; a quarter-resolution preview pass left in the
  accumulation buffer; frames of as many samples as fit in a frame's time averaged with equal weights.

The correct hand-ins come in ways no class used: a render resumed from a checkpoint that kept its sum and sample count,
adaptive sampling whose sample counts come from an independent pilot pass (discarded), a render stopped by its time
budget with each tile divided by its own sample count (the least declared), an 8-bit PNG quantised with Floyd and
Steinberg's error diffusion (GIMP's precision conversion), a 16-bit PNG by ffmpeg from the EXR with ``-apply_trc
iec61966_2_1``, Mitsuba with every mesh written to OBJ files by Blender's exporter (Y up) and loaded with the inverse
turn, three machines' renders seeded by their array task's index and averaged, and frames of unequal sample counts
weighted by their counts.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s ``edit`` and ``mitsuba_edit``), Mitsuba renders
at another spp, depth or resolution, combined as the student's workflow combines them (checkpoints, passes, frames,
machines, previews), Mitsuba's path integrator on rays a student's camera makes
(:func:`mcrt.grade.accuracy.unsaid._traced`), its samples, one by one, reweighted or clamped where a student's settings
change them (same-seed samples of max depth 1 to 8, :func:`mcrt.grade.accuracy.unbeknown._camera_samples`), or correct
renders post-processed and written with NumPy, Pillow, pypng and the standard library as the students' tools do
(ImageMagick's, Photoshop's, a viewer's, Windows' and montage's arithmetic emulated). mcrt renders none of it.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over :data:`CATEGORIES`: the 2nd, 4th, ... of
each category and of the correct hand-ins) are as in :mod:`~mcrt.grade.accuracy.unconsidered`, fixed before any case
was graded.
"""

from __future__ import annotations

import math
import re
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, cases, fresh, novel, programs, unasked, unattended, unattested, unbeknown,
                                 unbidden, unconsidered, unforeseen, unguessed, unheard, unheralded, unlooked, unmet,
                                 unnoticed, unprompted, unrecorded, unremarked, unremembered, unsaid, unseen, unsought,
                                 untold, untried, unvisited, unwonted)
from mcrt.grade.accuracy.cases import Spec
from mcrt.image_files import srgb_eotf

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


#: The classes after the first two, in the order they were written (their causes' words are this class's too).
_EARLIER = (programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked, unsought,
            unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted,
            unremarked, unremembered, unnoticed, unrecorded, unattended, unattested, unconsidered)


def _crc(name: str) -> int:
    return 1901000 + zlib.crc32(name.encode()) % 100000


_render = unseen._render
_posted = unseen._posted
_scene = unprompted._scene
_bsdf = unremarked._bsdf

#: The class's spp (the class is built at 64 x 64).
_S = 256
#: The assignment's maximum depth.
_DEPTH = 8


# --------------------------------------------------------------------------
# Post-processing (the render or its 8-bit codes in, what the program or tool writes out)
# --------------------------------------------------------------------------

#: Stephen Hill's fit of the ACES reference rendering and output transforms (BakingLab's ``ACESFitted``): sRGB to the
#: RRT's input space, and back from the ODT's output.
_ACES_IN = np.array([[0.59719, 0.35458, 0.04823], [0.07600, 0.90834, 0.01566], [0.02840, 0.13383, 0.83777]])
_ACES_OUT = np.array([[1.60475, -0.53108, -0.07367], [-0.10208, 1.10813, -0.00605], [-0.00327, -0.07276, 1.07602]])


def _rrt_odt_fit(v):
    return (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.4329510) + 0.238081)


def _aces_fitted(x):
    """``ACESFitted``: the input matrix, the RRT and ODT's rational fit, the output matrix, clamped to [0, 1]."""
    v = np.asarray(x, np.float64) @ _ACES_IN.T
    return np.clip(_rrt_odt_fit(v) @ _ACES_OUT.T, 0.0, 1.0)


#: The YAML 1.1 words PyYAML reads as booleans (its ``bool`` resolver), lower case.
_YAML11_BOOLS = {"yes": True, "no": False, "true": True, "false": False, "on": True, "off": False}


def _tonemap_setting(word: str):
    """The config's ``tonemap:`` value as PyYAML gives it: a YAML 1.1 boolean word a bool, any other word a string."""
    return _YAML11_BOOLS.get(word.lower(), word)


def _tonemap_chosen(word: str) -> str:
    """The script's choice, ``op = cfg.get("tonemap", "aces")``, then ``if op in ("off", "none"): ...``, ``elif op ==
    "reinhard": ...``, ``else: aces``: the string ``off`` would skip it, the boolean ``False`` falls to ACES."""
    op = _tonemap_setting(word)
    if op in ("off", "none"):
        return "none"
    if op == "reinhard":
        return "reinhard"
    return "aces"


def _auto_gamma_codes(image: np.ndarray) -> np.ndarray:
    """ImageMagick's ``-auto-gamma`` on the 8-bit sRGB codes, its channels synchronised (the default ``-channel
    RGB,sync``): gamma = log(mean) / log(0.5) over all the values, each value v ** (1 / gamma) (``LevelImage``), the
    mean taken to 50 %, written back as 8-bit codes."""
    v = blind._srgb8(image).astype(np.float64) / 255.0
    gamma = math.log(float(v.mean())) / math.log(0.5)
    return np.floor(np.power(v, 1.0 / gamma) * 255.0 + 0.5).astype(np.uint8)


def _write_png_auto_gamma(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_auto_gamma_codes(image), folder)


#: Windows' display scaling for the screenshot (a preview window that is not DPI-aware is stretched by it).
_DISPLAY_SCALE = 1.25


def _screenshot_codes(image: np.ndarray, *, scale: float = _DISPLAY_SCALE) -> np.ndarray:
    """The preview (the 8-bit sRGB codes drawn 1:1) as a screenshot under 125 % display scaling shows it: stretched
    bilinearly by the scale (80 x 80 for 64 x 64), the image's region cropped and resized back with Pillow's default
    (bicubic)."""
    from PIL import Image

    h, w = image.shape[:2]
    shot = Image.fromarray(blind._srgb8(image), "RGB").resize((round(w * scale), round(h * scale)),
                                                                Image.Resampling.BILINEAR)
    return np.asarray(shot.resize((w, h), Image.Resampling.BICUBIC))


def _write_png_screenshot(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_screenshot_codes(image), folder)


def _without_colour_sample(o, d, seed, *, full, seen):
    """A sample as the passes composited without the diffuse colour make it: where a camera ray meets a Lambertian
    first, the light it reflects there (the sample less the emission the ray sees, same seed) over that surface's
    albedo (the passes DiffDir + DiffInd, not DiffCol x (DiffDir + DiffInd)); the mirror (the glossy passes) and the
    light (the emission pass) as they are."""
    L, le = unsaid._sampled(full, o, d, seed), unsaid._sampled(seen, o, d, seed)
    rho = unsaid._first_albedo(full, o, d)
    diffuse = rho.min(axis=1) > 0.0
    return np.where(diffuse[:, None], le + (L - le) / np.where(diffuse[:, None], rho, 1.0), L)


def _without_colour(x, *, spp: int, seed: int):
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(
        _without_colour_sample, full=unsaid._loaded(_DEPTH), seen=unsaid._loaded(1)))


# --------------------------------------------------------------------------
# Writers and merges (the render in, the file the tools write)
# --------------------------------------------------------------------------

#: The tiles a side (16 tiles named tile_0.png to tile_15.png, row by row).
_TILES = 4


def _glob_order(n: int = _TILES * _TILES) -> list[int]:
    """The tiles' indices in the order the shell's ``tile_*.png`` lists them: sorted as text (tile_0, tile_1,
    tile_10, ..., tile_15, tile_2, ..., tile_9)."""
    names = sorted(f"tile_{k}.png" for k in range(n))
    return [int(name[5:-4]) for name in names]


def _montage_glob(codes: np.ndarray, *, tiles: int = _TILES) -> np.ndarray:
    """``montage tile_*.png -tile 4x4 -geometry +0+0 render.png``: the k-th file the glob gives placed at the k-th
    place (row by row)."""
    h, w = codes.shape[:2]
    th, tw = h // tiles, w // tiles
    out = np.empty_like(codes)
    for place, k in enumerate(_glob_order(tiles * tiles)):
        (r, c), (rk, ck) = divmod(place, tiles), divmod(k, tiles)
        out[th * r:th * (r + 1), tw * c:tw * (c + 1)] = codes[th * rk:th * (rk + 1), tw * ck:tw * (ck + 1)]
    return out


def _write_png_montage(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_montage_glob(blind._srgb8(image)), folder)


#: ROMM (ProPhoto) RGB's primaries and its D50 white; sRGB's primaries and D65.
_PROPHOTO = ((0.7347, 0.2653), (0.1596, 0.8404), (0.0366, 0.0001))
_SRGB = ((0.640, 0.330), (0.300, 0.600), (0.150, 0.060))
_D50, _D65 = (0.3457, 0.3585), (0.3127, 0.3290)


def _xyz(white) -> np.ndarray:
    return np.array([white[0] / white[1], 1.0, (1.0 - white[0] - white[1]) / white[1]])


def _srgb_to_prophoto() -> np.ndarray:
    """Linear sRGB (D65) to linear ProPhoto RGB (D50), the white adapted by Bradford's matrix (as the ICC profiles'
    conversion does)."""
    srgb_xyz = untried._rgb_to_xyz(_SRGB, _D65)
    prophoto_xyz = untried._rgb_to_xyz(_PROPHOTO, _D50)
    gain = (novel._BRADFORD @ _xyz(_D50)) / (novel._BRADFORD @ _xyz(_D65))
    cat = np.linalg.solve(novel._BRADFORD, np.diag(gain) @ novel._BRADFORD)
    return np.linalg.solve(prophoto_xyz, cat @ srgb_xyz)


def _romm_encode(v) -> np.ndarray:
    """ROMM RGB's transfer curve: 16 v below 1/512, v ** (1 / 1.8) above."""
    v = np.clip(np.asarray(v, np.float64), 0.0, 1.0)
    return np.where(v < 1.0 / 512.0, 16.0 * v, np.power(v, 1.0 / 1.8))


def _prophoto_codes(image: np.ndarray) -> np.ndarray:
    """The 8-bit sRGB codes converted to ProPhoto RGB (Photoshop's 'Convert to Working RGB' on opening): decoded,
    turned into ProPhoto's primaries and white, encoded by its curve, 8 bits; written with no profile."""
    lin = srgb_eotf(blind._srgb8(image).astype(np.float64) / 255.0)
    return np.floor(_romm_encode(lin @ _srgb_to_prophoto().T) * 255.0 + 0.5).astype(np.uint8)


def _write_png_prophoto(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_prophoto_codes(image), folder)


#: The HDR viewer's exposure when the PNG was saved from it (EV).
_VIEW_EV = 0.5


def _viewer_codes(image: np.ndarray, *, ev: float = _VIEW_EV) -> np.ndarray:
    """What the viewer saves as a PNG: the values times 2^EV, the sRGB curve, 8-bit codes."""
    return blind._srgb8(np.asarray(image, np.float64) * 2.0 ** ev)


def _write_png_viewer(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_viewer_codes(image), folder)


def _merge_one_flipped(renders: list[np.ndarray], *, flipped: int) -> np.ndarray:
    """The machines' renders averaged (equal spp) with render ``flipped`` read top row first from a PFM, whose rows
    run from the bottom: that one upside down."""
    return sum(r[::-1] if k == flipped else r for k, r in enumerate(renders)) / len(renders)


#: The machines and each one's spp.
_MACHINES, _MACHINE_SPP = 3, 96


def _machines_one_pfm(x, *, seed: int):
    h, w = x.shape[:2]
    return _merge_one_flipped([_render(w, h, _MACHINE_SPP, seed + k) for k in range(_MACHINES)], flipped=_MACHINES - 1)


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits (materials, geometry, light)
# --------------------------------------------------------------------------


def _yaml11_int(text: str):
    """A plain scalar of digits as PyYAML's YAML 1.1 resolver reads it: ``0`` followed by octal digits an octal int,
    ``0`` or a number without a leading zero a decimal int, anything else (``038``) a string."""
    if re.fullmatch(r"[-+]?0[0-7_]+", text):
        return int(text.replace("_", ""), 8)
    if re.fullmatch(r"[-+]?(?:0|[1-9][0-9_]*)", text):
        return int(text.replace("_", ""))
    return text


def _albedo_via_codes(albedo) -> tuple[float, ...]:
    """An albedo written as 8-bit codes with ``"%03d" % round(a * 255)`` and read back: each scalar as PyYAML reads
    it (:func:`_yaml11_int`), ``float(v) / 255``."""
    return tuple(float(_yaml11_int("%03d" % round(a * 255))) / 255.0 for a in albedo)


def _albedos_yaml_octal(s):
    """Every Lambertian's albedo through :func:`_albedo_via_codes` (the tetrahedron's too)."""
    walls = tuple(replace(w, albedo=_albedo_via_codes(w.albedo)) for w in s.room.walls)
    room = replace(s.room, walls=walls, floor_albedo=_albedo_via_codes(s.room.floor_albedo),
                   ceiling_albedo=_albedo_via_codes(s.room.ceiling_albedo))
    objects = tuple(replace(o, material=replace(o.material, albedo=_albedo_via_codes(o.material.albedo)))
                    if o.name == "tetrahedron" else o for o in s.objects)
    return replace(s, room=room, objects=objects)


#: Blender's Principled BSDF's default base colour, which its OBJ exporter writes as ``Kd`` when the socket is linked.
_KD_DEFAULT = (0.8, 0.8, 0.8)


def _walls_kd_default(s):
    walls = tuple(replace(w, albedo=_KD_DEFAULT) for w in s.room.walls)
    return replace(s, room=replace(s.room, walls=walls))


def _decoded(albedo) -> tuple[float, ...]:
    return tuple(float(v) for v in srgb_eotf(np.asarray(albedo, np.float64)))


def _albedos_srgb_decoded(s):
    """Every ``Kd`` (each Lambertian's albedo) decoded from sRGB, as three.js's ``MTLLoader`` does
    (``color.setRGB(r, g, b, SRGBColorSpace)``)."""
    walls = tuple(replace(w, albedo=_decoded(w.albedo)) for w in s.room.walls)
    room = replace(s.room, walls=walls, floor_albedo=_decoded(s.room.floor_albedo),
                   ceiling_albedo=_decoded(s.room.ceiling_albedo))
    objects = tuple(replace(o, material=replace(o.material, albedo=_decoded(o.material.albedo)))
                    if o.name == "tetrahedron" else o for o in s.objects)
    return replace(s, room=room, objects=objects)


def _y_up_to_z_up(v) -> tuple[float, float, float]:
    """An OBJ's point turned from Y up to Z up, as a loader for Y-up files turns it: (x, y, z) to (x, -z, y)."""
    x, y, z = (float(a) for a in v)
    return (x, -z, y)


def _tetra_y_up_converted(s):
    """The tetrahedron written by Blender's exporter with Up Z (its own axes) and turned by a Y-up loader: every
    vertex (x, y, z) placed at (x, -z, y)."""
    return replace(s, objects=tuple(replace(o, vertices=tuple(_y_up_to_z_up(v) for v in o.vertices))
                                    if o.name == "tetrahedron" else o for o in s.objects))


def _truncated_wall_normals(s) -> dict[str, np.ndarray]:
    """Each wall's normal in the floor's plane as the loader computes it, into ``n = np.zeros_like(corners[0])``
    where ``corners`` is the array of the JSON's corners, all integers (JavaScript's ``JSON.stringify`` wrote -3.0 as
    -3, so ``json.load`` gives ints): the unit normal's components truncated to integers, (0, 0) for every wall that
    is not parallel to an axis."""
    names = list(s.room.corners)
    corners = np.array([s.room.corners[k] for k in names]).astype(np.int64)
    out = {}
    for w in s.room.walls:
        a, b = corners[names.index(w.corners[0])], corners[names.index(w.corners[1])]
        t = (b - a).astype(np.float64)
        n = np.zeros_like(corners[0])
        n[:] = np.array([t[1], -t[0]]) / np.hypot(t[0], t[1])
        out["".join(w.corners)] = n
    return out


def _walls_zero_normals_black(s):
    """The walls whose truncated normal is zero (:func:`_truncated_wall_normals`) reflecting nothing: their light
    sample's cosine 0 and their bounce's frame built from a zero vector (NaN, the path ended): black, still in the
    way of every ray."""
    zero = {k for k, n in _truncated_wall_normals(s).items() if not n.any()}
    walls = tuple(replace(w, albedo=(0.0, 0.0, 0.0)) if "".join(w.corners) in zero else w for w in s.room.walls)
    return replace(s, room=replace(s.room, walls=walls))


#: Blender's Bevel modifier's default width (its 'Offset' width type: each new edge 0.1 from the old one in its face).
_BEVEL = 0.1


def _tetra_face_indices(vertices) -> tuple[tuple[int, int, int], ...]:
    """The tetrahedron's faces as vertex indices, wound outwards (face i without vertex i)."""
    v = np.asarray(vertices, np.float64)
    faces = []
    for i in range(4):
        f = [j for j in range(4) if j != i]
        if np.cross(v[f[1]] - v[f[0]], v[f[2]] - v[f[0]]) @ (v[i] - v[f[0]]) > 0:
            f = [f[0], f[2], f[1]]
        faces.append(tuple(f))
    return tuple(faces)


def _inset(p, q, r, width: float) -> np.ndarray:
    """Corner p of triangle (p, q, r) moved into the triangle to where the two edges at p, each moved ``width``
    inwards in the triangle's plane, meet: along the bisector, ``width / sin(angle / 2)`` from p."""
    e1, e2 = unsaid._unit(q - p), unsaid._unit(r - p)
    half = 0.5 * math.acos(float(np.clip(e1 @ e2, -1.0, 1.0)))
    return p + unsaid._unit(e1 + e2) * width / math.sin(half)


def _bevelled(vertices, width: float = _BEVEL) -> np.ndarray:
    """(20, 3, 3): the tetrahedron with every edge bevelled by ``width`` (one segment): each face inset (its edges
    moved ``width`` inwards), each edge a strip between its two faces' inset edges, each corner a triangle between its
    three faces' copies of it."""
    v = np.asarray(vertices, np.float64)
    faces = _tetra_face_indices(v)
    copy = {}
    for f, (a, b, c) in enumerate(faces):
        for p, q, r in ((a, b, c), (b, c, a), (c, a, b)):
            copy[f, p] = _inset(v[p], v[q], v[r], width)
    tris = [[copy[f, a], copy[f, b], copy[f, c]] for f, (a, b, c) in enumerate(faces)]
    for i in range(4):
        for j in range(i + 1, 4):
            f, g = (k for k, face in enumerate(faces) if i in face and j in face)
            tris += [[copy[f, i], copy[f, j], copy[g, j]], [copy[f, i], copy[g, j], copy[g, i]]]
    for i in range(4):
        f = [k for k, face in enumerate(faces) if i in face]
        tris.append([copy[f[0], i], copy[f[1], i], copy[f[2], i]])
    return np.array(tris)


def _tetra_bevelled(d: dict) -> dict:
    t = next(o for o in _scene().objects if o.name == "tetrahedron")
    return fresh._rebuilt(d, "tetrahedron", _bevelled(t.vertices), _bsdf(t.material))


#: The light's emissive plane as the MTL gives it: ``Ke`` its emission colour (white), its strength 20 not written.
_KE_COLOUR = (1.0, 1.0, 1.0)

#: Blender's area lamp: its size 1 (scaled 2 by its object), its power set to give radiance 20 on the 2 x 2 square.
_LAMP_SIZE, _LAMP_SCALE = 1.0, 2.0
_LAMP_POWER = 20.0 * math.pi * (_LAMP_SIZE * _LAMP_SCALE) ** 2


def _lamp_unscaled(s):
    """The lamp exported with ``size = lamp.data.size`` (its object's scale left out) and ``radiance = power / (pi
    size^2)``: a 1 x 1 square of radiance 80 (the same power) at the light's centre."""
    radiance = _LAMP_POWER / (math.pi * _LAMP_SIZE ** 2)
    return cases._light(s, size=(_LAMP_SIZE, _LAMP_SIZE), radiance=(radiance,) * 3)


def _room_box_centre(s) -> tuple[float, float, float]:
    """The centre of the room's bounding box (where 'Cursor to Selected' puts Blender's 3D cursor): (5, 0, 0)."""
    xy = np.array(list(s.room.corners.values()), np.float64)
    mid = 0.5 * (xy.min(axis=0) + xy.max(axis=0))
    return (float(mid[0]), float(mid[1]), 0.5 * (s.room.floor_z + s.room.ceiling_z))


def _light_at_origin(s):
    """The light plane's centre exported as its object's location, the 3D cursor where the plane was added (the
    room's centre), its vertices raised to 4.99 in Edit Mode: the 2 x 2 light at (5, 0, 0), facing down."""
    return cases._light(s, center=_room_box_centre(s))


# --------------------------------------------------------------------------
# The camera
# --------------------------------------------------------------------------

#: Blender's default frame (1920 x 1080) with a horizontal field of view of 90 degrees: its vertical one.
_FRAME = (1920, 1080)
_FOV_VERTICAL = math.degrees(2.0 * math.atan(math.tan(math.radians(45.0)) * _FRAME[1] / _FRAME[0]))

#: Blender's Shift Y (a fraction of the frame's larger side).
_SHIFT_Y = 0.1


def _shifted(fx, fy, *, shift: float = _SHIFT_Y):
    """The pinhole with Blender's lens shift: the image plane moved up by ``shift`` times its width (2 tan(fov / 2)),
    t = tan(fov / 2) (1 - 2 fy + 2 shift); the view's axis kept."""
    eye, r, u, f, k = unsaid._frame()
    s, t = k * (2.0 * fx - 1.0), k * (1.0 - 2.0 * fy + 2.0 * shift)
    return np.broadcast_to(eye, (len(fx), 3)), unsaid._unit(f + s[:, None] * r + t[:, None] * u)


def _length(text: str) -> float:
    """A length with its unit parsed as ``float(re.search(r"[\\d.]+", text).group())``: the digits, without a sign."""
    return float(re.search(r"[\d.]+", text).group())


def _eye_sign_dropped(s):
    """The eye written ``["-1 m", "0 m", "0 m"]`` in the camera's file and parsed by :func:`_length`: (1, 0, 0)."""
    eye = tuple(_length(f"{v:g} m") for v in s.cameras["near"].eye)
    return cases._camera(s, eye=eye)


# --------------------------------------------------------------------------
# The integrator
# --------------------------------------------------------------------------

#: Node's ``process.env.BOUNCES + 1`` with BOUNCES=7: the string "71", the maximum depth the tracer was given.
_BOUNCES = "7"
_DEPTH_CONCATENATED = int(_BOUNCES + "1")


def _clamped_sample(o, d, seed, *, full, two, one, limit: float):
    """A sample with its indirect light clamped as Cycles' 'Clamp Indirect' does (``if sum(|L|) > limit: L *= limit
    / sum``): everything after the first vertex's light sample where a camera ray meets a Lambertian first (the
    max-depth-8 sample less the max-depth-2 one, same seed), everything after the emission it sees elsewhere (after
    the mirror: the light and the room seen in it)."""
    L, L2, L1 = (unsaid._sampled(m, o, d, seed) for m in (full, two, one))
    direct = np.where(unbeknown._diffuse_first(full, o, d)[:, None], L2, L1)
    ind = L - direct
    total = np.abs(ind).sum(axis=1)
    scale = np.where(total > limit, limit / np.maximum(total, 1e-30), 1.0)
    return direct + ind * scale[:, None]


#: Cycles' default 'Clamp Indirect'.
_CLAMP_INDIRECT = 10.0


def _clamped(x, *, spp: int, seed: int):
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(
        _clamped_sample, full=unsaid._loaded(_DEPTH), two=unsaid._loaded(2), one=unsaid._loaded(1),
        limit=_CLAMP_INDIRECT))


#: The preview preset's maximum depth, which the resumed run read (the checkpoint kept no preset).
_PREVIEW_DEPTH = 3


def _resumed_preview(x, *, spp: int, seed: int):
    """Half the samples (the first run) at the assignment's depth, half (the resumed run) at the preview's, summed
    and divided by the total."""
    h, w = x.shape[:2]
    half = spp // 2
    return (half * _render(w, h, half, seed) + (spp - half) * _render(w, h, spp - half, seed + 1,
                                                                      max_depth=_PREVIEW_DEPTH)) / spp


#: Russian roulette from the 3rd vertex with the config's fixed survival, typed 95 (a percentage) for 0.95.
_RR_START, _RR_SURVIVAL = 3, 95.0


def _roulette_weights(depth: int = _DEPTH, *, start: int = _RR_START, survival: float = _RR_SURVIVAL) -> np.ndarray:
    """(depth + 1,): the weight of what a path gathers at each segment count d: the test ``if rand() > p: break``
    never ends a path (p = 95), and each survivor's throughput is divided by p, once at each vertex from ``start``
    on: 1 up to ``start`` segments, p^-(d - start) past them."""
    d = np.arange(depth + 1)
    return np.power(survival, -np.maximum(d - start, 0).astype(np.float64))


def _roulette_sample(o, d, seed, *, scenes):
    """A sample of segments weighted by :func:`_roulette_weights`: the max-depth-``start`` sample plus, for each d past
    it, (L_d - L_{d-1}) p^-(d - start) (same-seed samples of max depth ``start`` to 8)."""
    Ls = {k: unsaid._sampled(m, o, d, seed) for k, m in scenes.items()}
    wts = _roulette_weights()
    out = Ls[_RR_START].copy()
    for k in range(_RR_START + 1, _DEPTH + 1):
        out += wts[k] * (Ls[k] - Ls[k - 1])
    return out


def _roulette_percent(x, *, spp: int, seed: int):
    scenes = {k: unsaid._loaded(k) for k in range(_RR_START, _DEPTH + 1)}
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(_roulette_sample, scenes=scenes))


# --------------------------------------------------------------------------
# Samples and passes
# --------------------------------------------------------------------------


def _mean_resumed_as_sum(mean: np.ndarray, n: int, later: np.ndarray, m: int) -> np.ndarray:
    """A checkpoint's mean image (of n samples) loaded into the sum buffer, m more samples' sum added, the buffer
    divided by n + m."""
    return (mean + m * later) / (n + m)


#: The two runs of the checkpointed render.
_RUN = 128


def _checkpoint_mean_as_sum(x, *, seed: int):
    h, w = x.shape[:2]
    return _mean_resumed_as_sum(_render(w, h, _RUN, seed), _RUN, _render(w, h, _RUN, seed + 1), _RUN)


#: The time-budgeted render: passes of 32 spp, 6 done, the 7th cut off when it had reached 13/32 of the rows.
_PASS, _PASSES_DONE, _ROWS_REACHED = 32, 6, 13 / 32


def _partial_pass(done: np.ndarray, extra: np.ndarray, *, passes: int, rows: int) -> np.ndarray:
    """``passes`` passes' mean ``done``, and a last pass's mean ``extra`` added to the first ``rows`` rows only; every
    row's sum divided by the passes completed."""
    out = np.array(done, np.float64)
    out[:rows] = (passes * done[:rows] + extra[:rows]) / passes
    return out


def _time_budget(x, *, seed: int):
    h, w = x.shape[:2]
    done = _render(w, h, _PASS * _PASSES_DONE, seed)
    return _partial_pass(done, _render(w, h, _PASS, seed + 1), passes=_PASSES_DONE, rows=int(h * _ROWS_REACHED))


#: The preview: a quarter of the resolution (each of its pixels a 4 x 4 block), 16 spp, counted as 16 of the 256.
_PREVIEW_FACTOR, _PREVIEW_SPP = 4, 16


def _preview_kept(preview: np.ndarray, full: np.ndarray, *, factor: int, n_preview: int, n_full: int) -> np.ndarray:
    """The preview's pixels written into the buffer as sums over each one's block (``np.repeat``), the full
    resolution's sums added, divided by all the samples counted."""
    up = np.repeat(np.repeat(preview, factor, axis=0), factor, axis=1)
    return (n_preview * up + n_full * full) / (n_preview + n_full)


def _quarter_preview(x, *, spp: int, seed: int):
    h, w = x.shape[:2]
    f = _PREVIEW_FACTOR
    return _preview_kept(_render(w // f, h // f, _PREVIEW_SPP, seed + 1), _render(w, h, spp - _PREVIEW_SPP, seed),
                         factor=f, n_preview=_PREVIEW_SPP, n_full=spp - _PREVIEW_SPP)


#: The frames' sample counts: as many as fitted in the frame's time (the first frames slow, compiling): 256 in all.
_FRAMES = (1, 1, 2, 4, 8, 16, 32, 64, 64, 64)


def _frames(x, *, seed: int, weighted: bool):
    """The frames (each of its own seed) averaged with equal weights, or (``weighted``) with their sample counts."""
    h, w = x.shape[:2]
    means = [_render(w, h, n, seed + k) for k, n in enumerate(_FRAMES)]
    wts = np.asarray(_FRAMES, np.float64) if weighted else np.ones(len(_FRAMES))
    return sum(wt * m for wt, m in zip(wts, means)) / wts.sum()


# --------------------------------------------------------------------------
# Correct renders made in other ways
# --------------------------------------------------------------------------


def _checkpoint_resumed(x, *, seed: int, first: int = 96, later: int = 160):
    """A checkpoint of the sum buffer and its sample count (an ``.npz``), resumed: both runs' sums over their count."""
    h, w = x.shape[:2]
    return (first * _render(w, h, first, seed) + later * _render(w, h, later, seed + 1)) / (first + later)


#: The adaptive render: batches of 32 spp, 2 to 8 of them a pixel, from an independent 16-spp pilot.
_BATCH, _BATCHES, _PILOT = 32, 8, 16


def _batches_for(pilot_mean: np.ndarray, pilot_var: np.ndarray, *, batches: int = _BATCHES) -> np.ndarray:
    """(H, W): the batches each pixel gets, in proportion to the pilot's relative variance of its luminance (the
    largest gets ``batches``), 2 at least."""
    rel = (pilot_var @ programs._LUMA) / np.maximum(pilot_mean @ programs._LUMA, 1e-6) ** 2
    return np.clip(np.ceil(batches * rel / max(float(rel.max()), 1e-30)), 2, batches).astype(int)


def _adaptive_pilot(x, *, seed: int):
    """Each pixel the mean of its first n batches (their own seeds), n from :func:`_batches_for` of a pilot render of
    its own seed, discarded: the counts do not depend on the samples averaged."""
    from mcrt.mitsuba_scene import render_with_variance, scene_dict

    h, w = x.shape[:2]
    pilot = render_with_variance(scene_dict(_scene(), "near", w, h, _DEPTH, spp=_PILOT), spp=_PILOT, seed=seed + 97)
    n = _batches_for(np.asarray(pilot.mean, np.float64), np.asarray(pilot.variance, np.float64))
    means = np.stack([_render(w, h, _BATCH, seed + k) for k in range(_BATCHES)])
    kept = np.arange(_BATCHES)[:, None, None] < n[None]
    return (means * kept[..., None]).sum(axis=0) / n[..., None]


#: The time-budgeted tiles: 4 x 4, the first 10 (row by row) with a 5th pass of 64 spp, the rest with 4.
_TILES_DONE = 10


def _tiles_own_counts(x, *, seed: int):
    """Each tile its sum over its own sample count: 320 spp in the first :data:`_TILES_DONE`, 256 in the rest."""
    h, w = x.shape[:2]
    four, fifth = _render(w, h, 256, seed), _render(w, h, 64, seed + 1)
    out, th, tw = four.copy(), h // _TILES, w // _TILES
    for t in range(_TILES_DONE):
        r, c = divmod(t, _TILES)
        sl = (slice(th * r, th * (r + 1)), slice(tw * c, tw * (c + 1)))
        out[sl] = (256 * four[sl] + 64 * fifth[sl]) / 320
    return out


def _floyd_steinberg_codes(image: np.ndarray) -> np.ndarray:
    """8-bit sRGB codes by Floyd and Steinberg's error diffusion (GIMP's 'Image > Precision' to 8 bits with that
    dither): each pixel, left to right and top to bottom, rounded, its error passed on 7/16 right, 3/16 down-left,
    5/16 down, 1/16 down-right."""
    v = fresh._srgb(image) * 255.0
    h, w = v.shape[:2]
    out = np.zeros((h, w, 3), np.uint8)
    for y in range(h):
        for x in range(w):
            old = v[y, x].copy()
            new = np.clip(np.floor(old + 0.5), 0, 255)
            out[y, x] = new
            err = old - new
            if x + 1 < w:
                v[y, x + 1] += err * 7 / 16
            if y + 1 < h:
                if x > 0:
                    v[y + 1, x - 1] += err * 3 / 16
                v[y + 1, x] += err * 5 / 16
                if x + 1 < w:
                    v[y + 1, x + 1] += err * 1 / 16
    return out


def _write_png_floyd_steinberg(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_floyd_steinberg_codes(image), folder)


def _write_png16_ffmpeg(image: np.ndarray, folder: Path) -> Path:
    """``ffmpeg -apply_trc iec61966_2_1 -i render.exr render.png``: the sRGB curve applied by the EXR decoder, the
    floats scaled to 16 bits (rgb48be), a PNG with no colour chunk."""
    import png

    h, w = image.shape[:2]
    codes = np.floor(fresh._srgb(image) * 65535.0 + 0.5).astype(np.uint16)
    path = folder / "render.png"
    with open(path, "wb") as f:
        png.Writer(w, h, greyscale=False, bitdepth=16).write(f, codes.reshape(h, w * 3).tolist())
    return path


def _meshes_from_blender_obj(d: dict) -> dict:
    """Every mesh written to an OBJ file as Blender's exporter writes it with its defaults (Forward -Z, Up Y: (x, y, z)
    written (x, z, -y)) and loaded by Mitsuba's ``obj`` plugin turned back (``to_world``: 90 degrees about x), its
    BSDF and emitter from the scene."""
    import tempfile

    import mitsuba as mi

    from mcrt.mitsuba_scene import _bsdf_dict, _light_surface, _rgb

    s = _scene()
    out = dict(d)
    with tempfile.TemporaryDirectory() as tmp:
        for sf in s.surfaces():
            if sf.material is None:
                sf = _light_surface(sf, s.light.normal)
            tris = np.asarray(sf.triangles, np.float64)
            y_up = np.stack([tris[..., 0], tris[..., 2], -tris[..., 1]], axis=-1)
            path = Path(tmp) / f"{sf.name}.obj"
            path.write_text(unprompted._obj_text(y_up))
            shape = {"type": "obj", "filename": str(path), "face_normals": True, "bsdf": _bsdf_dict(sf.material),
                     "to_world": mi.ScalarTransform4f().rotate([1.0, 0.0, 0.0], 90.0)}
            if sf.material is None:
                shape["emitter"] = {"type": "area", "radiance": _rgb(s.light.radiance)}
            out[sf.name] = mi.load_dict(shape)
    return out


def _machines_averaged(x, *, seed: int):
    """The machines' renders (seeds ``seed + SLURM_ARRAY_TASK_ID``), equal spp, averaged."""
    h, w = x.shape[:2]
    return sum(_render(w, h, _MACHINE_SPP, seed + k) for k in range(_MACHINES)) / _MACHINES


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_yaml_tonemap_off_aces_fitted", "pp_imagemagick_auto_gamma", "pp_screenshot_display_scaled",
                        "pp_passes_composited_without_colour"),
    "file": ("file_png_montage_glob_order", "file_png_photoshop_prophoto_untagged", "file_png_viewer_exposure_saved",
             "file_exr_merge_pfm_top_row_first"),
    "materials": ("albedos_yaml_octal_codes", "walls_mtl_kd_node_default", "albedos_threejs_mtl_srgb_decoded"),
    "geometry": ("tetra_obj_y_up_converted_twice", "walls_json_integer_normals", "tetra_blender_bevel_applied"),
    "camera": ("fov_blender_vertical_16_9", "camera_blender_shift_y_left", "eye_units_regex_sign_dropped"),
    "light": ("light_mtl_ke_strength_dropped", "light_lamp_size_unscaled", "light_plane_origin_at_cursor"),
    "integrator": ("depth_env_string_concatenated", "clamp_cycles_indirect_default", "resume_preview_preset_depth",
                   "roulette_survival_percent"),
    "samples": ("checkpoint_mean_resumed_as_sum", "time_budget_partial_pass", "preview_quarter_resolution_kept",
                "frames_unequal_spp_equal_weights"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    c = _crc
    return (
        # Post-processing
        Spec("pp_yaml_tonemap_off_aces_fitted", "tone_map", True, **_posted("aces_fitted", _aces_fitted),
             truth="the render script's config saying tonemap: off, which PyYAML (YAML 1.1) reads as the boolean "
             "False, so the script's test if op in ('off', 'none') failed and its default branch ran Stephen Hill's "
             "fitted ACES curve (ACESFitted: input matrix, the RRT and ODT's rational fit, output matrix, clamped) "
             "before the EXR: every value in [0, 1], the light 0.995 for 20, a grey of 0.18 written 0.106, the "
             "colours shifted"),
        Spec("pp_imagemagick_auto_gamma", "tone_map", True, held_out=True, writer=_write_png_auto_gamma,
             file="png-im-auto-gamma",
             truth="the 8-bit sRGB PNG brightened with ImageMagick's magick render.png -auto-gamma render.png "
             "(channels synchronised, IM's default): one gamma, log(mean) / log(0.5) of all the codes' values, each "
             "value v ** (1 / gamma), so that the mean becomes 50 %: the dark render lifted, its mid-tones much "
             "brighter, black and white kept, an 8-bit PNG"),
        Spec("pp_screenshot_display_scaled", "blur", writer=_write_png_screenshot, file="png-screenshot",
             truth="the hand-in a screenshot of the preview window (the 8-bit sRGB codes drawn 1:1) on Windows at "
             "125 % display scaling, which stretches a window that is not DPI-aware bilinearly: the image's 80 x 80 "
             "region cropped from it and resized back to 64 x 64 with Pillow's Image.resize (bicubic): every edge "
             "softened, an 8-bit PNG"),
        Spec("pp_passes_composited_without_colour", "albedo", True, held_out=True, **_posted(
            "passes_without_colour", partial(_without_colour, spp=_S, seed=c("pp_passes_composited_without_colour"))),
             truth="the render written as Cycles-style passes (emission, glossy, diffuse direct, diffuse indirect, "
             "diffuse colour) and composited by hand as Emit + Glossy + DiffDir + DiffInd, the diffuse colour pass "
             "never multiplied in (for DiffCol x (DiffDir + DiffInd)): where a camera ray meets a Lambertian first, "
             "the light it reflects divided by its albedo (the red wall's green and blue 6.7 times), the mirror and "
             "the light right, as EXR"),
        # Writing the file
        Spec("file_png_montage_glob_order", "row_stride", True, writer=_write_png_montage, file="png-montage",
             truth="the render made as 16 tiles of 16 x 16 (four machines, four each), saved as tile_0.png to "
             "tile_15.png row by row and assembled with montage tile_*.png -tile 4x4 -geometry +0+0 render.png: the "
             "shell's glob lists them in text order, tile_0, tile_1, tile_10 to tile_15, tile_2 to tile_9, and "
             "montage places them in that order: 14 of the 16 tiles in another tile's place, each right inside, "
             "an 8-bit PNG"),
        Spec("file_png_photoshop_prophoto_untagged", "colour_space", True, held_out=True, writer=_write_png_prophoto,
             file="png-prophoto",
             truth="the PNG opened in Photoshop whose colour settings convert to the working space, ProPhoto RGB (a "
             "photographer's set-up), then exported with Export As, 'Convert to sRGB' and 'Embed Color Profile' "
             "unchecked: ProPhoto RGB codes (D50, its gamma 1.8) in an untagged 8-bit PNG, read as sRGB: the "
             "colours washed out towards grey, the greys darker (a linear 0.2 read 0.14)"),
        Spec("file_png_viewer_exposure_saved", "light_radiance", True, writer=_write_png_viewer, file="png-viewer-ev",
             truth="the EXR opened in an HDR viewer (tev) with its exposure at +0.5 EV to see the dark corners and "
             "saved from the viewer as render.png, which bakes the view's exposure and the sRGB curve into the 8-bit "
             "codes: every value 1.41 times too bright, the bright ones clipped"),
        Spec("file_exr_merge_pfm_top_row_first", "orientation", True, held_out=True, spp=_MACHINES * _MACHINE_SPP,
             **_posted("merge_pfm_flipped", partial(_machines_one_pfm, seed=c("file_exr_merge_pfm_top_row_first"))),
             truth="three machines' renders of 96 spp (their own seeds) averaged by a merge script: two wrote EXRs, "
             "the third (no OpenEXR on it) a PFM, read by the script's own reader as np.fromfile(...).reshape(h, w, "
             "3) with the rows in the file's order, PFM's bottom row first: that render upside down, a third of the "
             "image a faint upside-down room (the light's ghost at the bottom), 288 spp declared, EXR"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("albedos_yaml_octal_codes", "albedo", edit=_albedos_yaml_octal,
             truth="the albedos written to the scene's YAML as 8-bit codes with '%03d' (aligned columns) and read "
             "back by PyYAML, whose YAML 1.1 resolver takes 051 and 026 for octal numbers (41 and 22) and 038 for a "
             "string (float('038') = 38): wall DE's green 0.161 for 0.20 and the tetrahedron's blue 0.086 for 0.10, "
             "every other albedo within half a code"),
        Spec("walls_mtl_kd_node_default", "albedo", True, held_out=True, edit=_walls_kd_default,
             truth="the walls' colours given in Blender by a colour attribute (an Attribute node into the Principled "
             "BSDF's Base Color), which Blender's OBJ exporter cannot write: each wall's MTL Kd the socket's default "
             "0.8 0.8 0.8: all six walls a light grey, the whole room grey but for the orange tetrahedron, and "
             "brighter"),
        Spec("albedos_threejs_mtl_srgb_decoded", "albedo", True, edit=_albedos_srgb_decoded,
             truth="the scene loaded from the OBJ and MTL with three.js's MTLLoader, which takes every Kd for an sRGB "
             "colour and decodes it (color.setRGB(r, g, b, SRGBColorSpace)): every albedo sRGB-decoded, the floor "
             "0.32 for 0.6, the ceiling 0.60 for 0.8, the walls' weak channels 0.019 for 0.15: the room darker and "
             "more saturated"),
        # Geometry
        Spec("tetra_obj_y_up_converted_twice", "object_moved", True, edit=_tetra_y_up_converted,
             truth="the tetrahedron exported from Blender as an OBJ with Up Z and Forward Y (the scene's own axes) "
             "and read by a loader that turns OBJ's Y up into Z up, (x, y, z) to (x, -z, y): its base standing "
             "upright at y = 4.9 by wall EF (z from -3.8 to -1), its apex at (8.5, 2, -2.3) inside the mirror "
             "sphere: the tetrahedron gone from the right, an orange shape on the left by the sphere"),
        Spec("walls_json_integer_normals", "normals", True, held_out=True, edit=_walls_zero_normals_black,
             truth="the room exported to JSON by a JavaScript tool (JSON.stringify writes -3.0 as -3), so json.load "
             "gives integer corners, and each wall's unit normal written into n = np.zeros_like(corners[0]) (an int64 "
             "array, which truncates what it is given): the four slanted walls' normals (0.89, 0.45) and the like "
             "truncated to (0, 0), their "
             "light sample's cosine 0 and their bounce NaN: walls AB, CD, DE and FA black, BC and EF right"),
        Spec("tetra_blender_bevel_applied", "object_shape", mitsuba_edit=_tetra_bevelled,
             truth="the tetrahedron modelled in Blender with a Bevel modifier (width 0.1, one segment, added to see "
             "its edges in the viewport) and exported to OBJ with 'Apply Modifiers' (on by default): every edge cut "
             "by a flat strip and every corner by a triangle, 0.1 in from each edge: the tetrahedron a little "
             "smaller, its edges chamfered"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    return (
        # Camera
        Spec("fov_blender_vertical_16_9", "camera_fov", True, edit=cases.fov(_FOV_VERTICAL),
             truth="the camera exported from Blender, whose frame was its default 1920 x 1080 with a horizontal "
             "field of view of 90, by a script that writes the vertical one (three.js's and OpenGL's convention), "
             "2 atan(tan 45 x 1080 / 1920) = 58.7 degrees, which the tracer takes as the square image's: the view "
             "narrower, its middle magnified"),
        Spec("camera_blender_shift_y_left", "camera_model", True, held_out=True, **_posted("blender_shift_y", partial(
            unsaid._traced, spp=_S, seed=_crc("camera_blender_shift_y_left"), camera=_shifted)),
             truth="Blender's camera Shift Y left at 0.1 (from framing the room in the viewport) and exported in the "
             "camera's projection matrix, which the tracer inverts for its rays: the image plane moved up by a tenth "
             "of its width, the view's axis kept (an off-axis view): the image shows 6.4 pixels more of the ceiling "
             "and fewer of the floor, the walls' verticals still vertical"),
        Spec("eye_units_regex_sign_dropped", "camera_eye", True, edit=_eye_sign_dropped,
             truth="the camera's eye written with its unit, eye = ['-1 m', '0 m', '0 m'], in the student's camera "
             "file and parsed with float(re.search(r'[\\d.]+', s).group()): the minus sign dropped, the eye at (1, "
             "0, 0) for (-1, 0, 0), two units forward, the field of view kept: the room's far end larger, the near "
             "walls out of view"),
        # Light model
        Spec("light_mtl_ke_strength_dropped", "light_radiance", True, edit=cases.light(radiance=_KE_COLOUR),
             truth="the light an emissive plane in Blender (emission colour white, strength 20) exported to the OBJ's "
             "MTL, whose Ke the exporter wrote from the emission colour alone, Ke 1 1 1, the strength dropped: the "
             "light's radiance 1 for 20, the whole image 20 times too dark"),
        Spec("light_lamp_size_unscaled", "light_size", True, held_out=True, edit=_lamp_unscaled,
             truth="the light a Blender area lamp of size 1 whose object was scaled by 2 in the viewport, its power "
             "251 W set to give radiance 20 on the 2 x 2 square, exported with size = lamp.data.size (the object's "
             "scale left out) and radiance = power / (pi size^2): a 1 x 1 light of radiance 80 at the same centre, "
             "the same power: the light seen smaller and 4 times as bright, the shadows sharper, the room's "
             "brightness nearly the same"),
        Spec("light_plane_origin_at_cursor", "light_position", True, edit=_light_at_origin,
             truth="the light a plane added in Blender at the 3D cursor, which sat at the room's centre (5, 0, 0) "
             "after 'Cursor to Selected' on the room, its vertices moved up to z = 4.99 in Edit Mode, and exported "
             "with center = obj.location: the 2 x 2 light at (5, 0, 0), in mid-air at the eye's height, facing "
             "down: seen edge-on, the floor under it bright, the ceiling lit only by the light that bounces"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples and passes."""
    c = _crc
    return (
        # Integrator
        Spec("depth_env_string_concatenated", "depth", max_depth=_DEPTH_CONCATENATED,
             truth="the maximum depth passed to the tracer by a Node render script as --max-depth ${process.env."
             "BOUNCES + 1}, the course's 7 bounces in an environment variable, which is a string: '7' + 1 = '71': "
             "paths of up to 71 segments for 8, the light of the 9th segment on added (a few per cent, most in the "
             "dark corners)"),
        Spec("clamp_cycles_indirect_default", "sample_clamp", held_out=True, **_posted("cycles_clamp", partial(
            _clamped, spp=_S, seed=c("clamp_cycles_indirect_default"))),
             truth="the render settings exported from the student's Blender file with Cycles' defaults, Clamp "
             "Indirect 10 among them, which the tracer applies to each sample's indirect light (if its channels' "
             "sum exceeds 10, scaled down to 10): the light's reflection in the mirror (sum 60) 3.3 for 20, the "
             "rare bright paths after a bounce cut, the direct light right"),
        Spec("resume_preview_preset_depth", "depth", True, **_posted("resumed_preview", partial(
            _resumed_preview, spp=_S, seed=c("resume_preview_preset_depth"))),
             truth="a render of 256 spp interrupted after 128 and resumed with --resume, which restored the sum "
             "buffer and the count but read the settings from the config's default preset, the preview's (max depth "
             "3), since the checkpoint kept no preset name: the second half's paths cut at 3 segments, the light "
             "of the 4th segment on halved"),
        Spec("roulette_survival_percent", "roulette", True, held_out=True, **_posted("roulette_percent", partial(
            _roulette_percent, spp=_S, seed=c("roulette_survival_percent"))),
             truth="Russian roulette from the 3rd vertex with the config's fixed survival probability, rr_survival: "
             "95 (typed as a percentage for 0.95): if rand() > p: break never ends a path and every survivor is "
             "divided by 95 at each vertex: what paths gather at their 4th segment 95 times too dark, at their "
             "5th 95^2 times: the light of paths of 4 segments or more almost gone, the room darker"),
        # Samples and passes
        Spec("checkpoint_mean_resumed_as_sum", "sample_count", True, **_posted("checkpoint_mean_as_sum", partial(
            _checkpoint_mean_as_sum, seed=c("checkpoint_mean_resumed_as_sum"))),
             truth="a progressive render checkpointed after 128 spp as checkpoint.exr (the mean, which the preview "
             "shows) and checkpoint.json ({'spp': 128}), resumed by loading the EXR into the sum buffer, adding 128 "
             "more samples' sums and dividing by 256: the first run's mean weighted 1/256, the image about half as "
             "bright (0.504 of it)"),
        Spec("time_budget_partial_pass", "sample_count", True, held_out=True, spp=_PASS * _PASSES_DONE,
             **_posted("time_budget", partial(_time_budget, seed=c("time_budget_partial_pass"))),
             truth="a render given 60 seconds, in passes of 32 spp over the rows, the clock checked after each row: "
             "6 passes done, the 7th stopped at row 26 of 64, the buffer divided by the 6 passes' 192 spp: the top "
             "26 rows 7/6 as bright (their 7th pass counted in the sum, not the count), the rest right, 192 "
             "declared"),
        Spec("preview_quarter_resolution_kept", "preview_kept", **_posted("quarter_preview", partial(
            _quarter_preview, spp=_S, seed=c("preview_quarter_resolution_kept"))),
             truth="a progressive renderer's first pass at a quarter of the resolution (16 x 16, 16 spp) for a quick "
             "preview, written into the accumulation buffer as each 4 x 4 block's sums and counted as 16 samples, "
             "then 240 spp at full resolution added, divided by 256: a blocky 1/16 of the image under the rest, the "
             "edges smeared over their blocks"),
        Spec("frames_unequal_spp_equal_weights", "spp_claim", held_out=True, **_posted("frames_equal", partial(
            _frames, seed=c("frames_unequal_spp_equal_weights"), weighted=False)),
             truth="an interactive renderer's frames, each with as many samples as fitted in its 33 ms (1, 1, 2, 4, "
             "8, 16, 32, 64, 64, 64 as the kernels compiled and warmed up, 256 in all), blended as frames with "
             "acc += (frame - acc) / k: each frame weighted 1/10 whatever its samples, the 1-spp frames' noise kept: "
             "unbiased, as noisy as about 33 spp, 256 declared"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_checkpoint_sum_and_count", None, **_posted("checkpoint_sum_count", partial(
            _checkpoint_resumed, seed=c("ok_checkpoint_sum_and_count"))),
             truth="Mitsuba path 96 spp checkpointed as its sum buffer and sample count (an .npz) and resumed for "
             "160 more (the next passes' seeds), the sums over 256, EXR"),
        Spec("ok_adaptive_independent_pilot", None, held_out=True, spp=_BATCH * 2, **_posted(
            "adaptive_pilot", partial(_adaptive_pilot, seed=c("ok_adaptive_independent_pilot"))),
             truth="Mitsuba path with adaptive sampling: a 16-spp pilot (discarded) gives each pixel 2 to 8 batches "
             "of 32 spp by its relative variance, each pixel the mean of its batches, 64 declared, EXR"),
        Spec("ok_time_budget_tiles_own_counts", None, **_posted("tiles_own_counts", partial(
            _tiles_own_counts, seed=c("ok_time_budget_tiles_own_counts"))),
             truth="Mitsuba path in passes of 64 spp over 4 x 4 tiles until its time budget ran out: 10 tiles with 5 "
             "passes, 6 with 4, each tile divided by its own count, 256 declared, EXR"),
        Spec("ok_png_floyd_steinberg", None, held_out=True, spp=232, writer=_write_png_floyd_steinberg,
             file="png-floyd-steinberg",
             truth="Mitsuba path 232 spp, an 8-bit sRGB PNG quantised with Floyd-Steinberg error diffusion (GIMP's "
             "Image > Precision > 8 bit with that dither)"),
        Spec("ok_png16_ffmpeg_apply_trc", None, spp=204, writer=_write_png16_ffmpeg, file="png16-ffmpeg",
             truth="Mitsuba path 204 spp, a 16-bit sRGB PNG by ffmpeg -apply_trc iec61966_2_1 -i render.exr "
             "render.png (rgb48be, no colour chunk)"),
        Spec("ok_meshes_blender_obj_y_up", None, held_out=True, spp=196, mitsuba_edit=_meshes_from_blender_obj,
             truth="Mitsuba path 196 spp with every mesh written to an OBJ as Blender's exporter writes it (Forward "
             "-Z, Up Y) and loaded by the obj plugin turned back by its to_world, EXR"),
        Spec("ok_machines_task_seeds", None, spp=_MACHINES * _MACHINE_SPP, **_posted("machines_averaged", partial(
            _machines_averaged, seed=c("ok_machines_task_seeds"))),
             truth="Mitsuba path on three machines, 96 spp each seeded with its SLURM_ARRAY_TASK_ID, averaged, 288 "
             "declared, EXR"),
        Spec("ok_frames_weighted_by_spp", None, held_out=True, **_posted("frames_weighted", partial(
            _frames, seed=c("ok_frames_weighted_by_spp"), weighted=True)),
             truth="Mitsuba path in frames of 1 to 64 spp (256 in all) accumulated with each frame weighted by its "
             "sample count, EXR"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "tone_map": "a curve applied before saving (a tone map switched on by a config, ImageMagick's -auto-gamma)",
    "blur": "a filter after rendering (a screenshot's stretch and resize)",
    "albedo": "a surface's colour (albedos read as octal codes, left at an exporter's default, decoded as sRGB, or "
              "left out of the composited passes)",
    "row_stride": "pixels written at the wrong addresses (tiles assembled in the wrong order)",
    "colour_space": "values in another colour space (ProPhoto RGB codes saved without their profile)",
    "light_radiance": "the light's radiance (or a constant factor: an emission's strength dropped, a viewer's "
                      "exposure saved)",
    "orientation": "the image written flipped (one of the renders merged into it upside down)",
    "object_moved": "an object moved (its mesh turned from Y up to Z up that was already Z up)",
    "normals": "surface normals wrong (truncated to zero: four walls black)",
    "object_shape": "an object's shape (its edges bevelled)",
    "camera_fov": "the camera's field of view (the vertical one of another frame)",
    "camera_model": "another camera model (a lens shifted off the view's axis)",
    "camera_eye": "the camera's eye position (the sign of its coordinate lost)",
    "light_size": "the light's size (a lamp's size without its object's scale)",
    "light_position": "the light's position (its object's origin for its centre)",
    "depth": "the path depth (a string for a number; half the samples at a preview's depth)",
    "sample_clamp": "samples clamped (each sample's indirect light, as Cycles' default clamp)",
    "roulette": "Russian roulette wrong (the survivors divided by a percentage for a probability)",
    "sample_count": "each pixel's sum divided by a count it does not hold (a checkpoint's mean resumed as a sum, a "
                    "pass cut off)",
    "preview_kept": "a preview pass's samples (at a quarter of the resolution) kept in each pixel's mean",
    "spp_claim": "fewer samples per pixel than declared (frames of unequal sample counts given equal weights)",
}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = blind.class_causes(MISTAKES, _EARLIER, NEW_CAUSES, _REWORDED)


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
