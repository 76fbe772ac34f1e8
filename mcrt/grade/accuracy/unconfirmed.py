r"""A thirty-third class of hand-ins: what debugging, refactoring and version control leave in a tracer, blind.

How it was written: from what a student's own debugging and housekeeping leave behind in a tracer that once worked,
not from the grader: debug views and colours left blended in (a normals view mixed into the beauty, object-ID colours
mixed into the albedos, a marker round the pixel under inspection, a tint on the camera's hits of the light), loops and
counts narrowed while debugging and never restored (a sample count capped, a Blender-style render region), flags and
command-line defaults toggled (argparse's ``type=bool``, which reads ``--denoise False`` as true; Cycles' default
Blackman-Harris pixel filter; a viewer's zoom and a preview's white-balance gains saved where the batch render reads
them), refactors that reordered a function's parameters under a positional call (a PNG writer's ``bits`` and
``gamma``, a light's ``size`` and ``radiance``), a function copied for the tetrahedron that kept the sphere's variable,
merges resolved by taking one side's half of a change (a renamed configuration key read with ``.get`` and a default,
the light's pdf divided on both sides, a film's count assigned where the other side loops), a fix staged with ``git
add -p`` one hunk short, caches kept after the scene changed (a pickled scene, a precomputed ray table, a memoised
light sample, a ``.gitignore`` that kept the final render out of the commit), print-debugging that changed what the
program evaluates (``logging.debug`` evaluating its argument, ``print(next(seeds))`` consuming a seed), and profiling
builds and hacks (a profile preset's depth, a ``fast_pow`` bit trick, a light range to skip far shadow rays, an
indirect-light gain for a look at the shadows). Its author read the other classes' specs and cause words, the
catalogue (:mod:`mcrt.mutants`), the scene files and design notes, mcrt's scene, camera and image code,
:data:`~mcrt.grade.accuracy.run.CAUSE_OF` and :data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and
to stay clear of their mistakes; never the grader's rules (what decides a cause) nor its reports, and graded none of
it, not one case. Each cause and ``major`` flag was set from the mistake alone; every mistake is worded by a cause the
other classes already have (:data:`NEW_CAUSES` is empty), so ``SAME_MISTAKE`` needed no new entry. The mistakes differ
from those of the thirty-two other classes (:mod:`~mcrt.grade.accuracy.cases`, :mod:`~mcrt.grade.accuracy.outside` and
the modules of :data:`_EARLIER`, from :mod:`~mcrt.grade.accuracy.programs` to :mod:`~mcrt.grade.accuracy.unexamined`)
and from the catalogue's bugs:

* **post-processing**: a 3 x 3 magenta ring drawn round the pixel under inspection, its ``if args.debug_pixel:``
  guard made always true when a refactor gave the option a default; the first hit's normals view (``0.5 n + 0.5``)
  mixed into every sample at the preview slider's 0.1, saved in the config; an edge-avoiding a-trous wavelet denoiser
  run because ``--denoise`` was declared ``type=bool`` and the script passed ``--denoise False``; the grey-world gains
  of a test scene cached in ``wb.json`` and applied to every later render;
* **writing the file**: the sRGB curve's power by a profiling build's ``fast_pow`` (the float's bits as its log2 and
  back); the final EXR kept out of the commit by a ``.gitignore`` line, the 64-spp test render added before handed in
  with the manifest's 256; a PNG writer whose parameters a refactor reordered to ``(img, bits=8, gamma=2.2)`` under the
  old call ``write_png(path, img, 2.2)`` (codes of 2.2 bits);
* **materials**: object-ID debug colours (Matplotlib's ``tab10``) mixed into every albedo at 0.2; the floor's albedo
  read with ``cfg.get("floor_albedo", 0.8)`` after a merge took the other side's renamed key; wall EF's red typed 0.51
  for 0.15 once, fixed in the YAML, and kept by a pickled scene cache keyed by the file's name;
* **geometry**: the sphere's radius read from the other side's ``diameter`` key (3 for 1.5); the tetrahedron's
  ``normal_at`` copied from the sphere's, ``normalize(p - sphere.center)``; the fix lifting the tetrahedron's base
  off the floor staged one hunk short (one base vertex left at z = -5);
* **camera**: the rays looked up in a ray table cached at the preview's half resolution (each 2 x 2 block the same
  window); Cycles' default pixel filter, Blackman-Harris 1.5 pixels wide, importance-sampled per axis; the viewer's
  zoom 1.1 saved into the camera's settings (84.5 degrees for 90);
* **light model**: the light's sample memoised with ``functools.cache`` (one point for the whole render); the light's
  parameters reordered to ``(center, radiance, size)`` under the old positional call (a 20 x 20 light of radiance 2);
  the camera's hits of the light tinted (1, 0.3, 0.3) to see them in the preview; the light's 4 x 4 strata advanced
  four times a sample by a ``logging.debug`` whose argument draws three samples (only every 4th stratum: one strip);
* **integrator**: the profile preset's maximum depth 6 used for the hand-in; the light's pdf divided in the sampler
  and again at its call after a merge (the direct light 4 times too bright); a light range of 11 added while profiling
  (no shadow ray to a light sample farther away); an indirect-light gain of 0.5 at the first hit left from looking at
  the shadows;
* **samples and passes**: ``spp = min(args.spp, 32)`` left from debugging; a render region (0.40 to 0.85 across, 0.50
  to 0.95 down) saved in the config, the rest black; the film's ``count = spp_pass`` (assigned) from one side under
  the other side's loop of two passes; ``print("first seed:", next(seeds))`` consuming one of four passes' seeds, the
  sum divided by all four.

The correct hand-ins come in ways no class used: the pixels traced in a shuffled order (a load-balancing experiment)
and scattered back by their indices, the two sides of a merge (Russian roulette from the 5th and from the 3rd vertex)
rendered and averaged, an EXR written by OpenEXR's ``File`` API from one ``"RGB"`` array with the commit's hash as a
header attribute, Mitsuba with Dr.Jit's ``Debug`` flag left on, Mitsuba with Dr.Jit's symbolic loops and calls off (as
print-debugging inside the loop needs), Mitsuba with Dr.Jit's ``FastMath`` off (a NaN hunt), four passes seeded from
NumPy's ``SeedSequence.spawn``, and an 8-bit PNG re-saved by a pre-commit hook with Pillow's ``optimize=True``.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s ``edit`` and ``mitsuba_edit``), Mitsuba
renders at another spp or depth, combined as the student's leftovers combine them (regions, passes, seeds, the light
seen from one scene and the rest from another, :func:`mcrt.grade.accuracy.unsaid._light_seen_from`), Mitsuba's path
integrator on rays a student's camera makes (:func:`mcrt.grade.accuracy.unsaid._traced`), its samples, one by one,
mixed or reweighted (:func:`mcrt.grade.accuracy.unbeknown._camera_samples`), its first vertex's light redone
(:func:`mcrt.grade.accuracy.unheralded._first_vertex`), or correct renders post-processed and written with NumPy,
Pillow and the standard library as the students' programs do. mcrt renders none of it.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over :data:`CATEGORIES`: the 2nd, 4th, ... of
each category and of the correct hand-ins) are as in :mod:`~mcrt.grade.accuracy.unexamined`, fixed before any case
was graded.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, cases, fresh, novel, programs, unasked, unattended, unattested, unbeknown,
                                 unbidden, unconsidered, unexamined, unforeseen, unguessed, unheard, unheralded,
                                 unlooked, unmet, unnoticed, unprompted, unrecorded, unremarked, unremembered, unsaid,
                                 unseen, unsought, untold, untried, unvisited, unwonted, unanticipated)
from mcrt.grade.accuracy.cases import Spec

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


#: The classes after the first two, in the order they were written (their causes' words are this class's too).
_EARLIER = (programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked, unsought,
            unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted,
            unremarked, unremembered, unnoticed, unrecorded, unattended, unattested, unconsidered, unanticipated,
            unexamined)


def _crc(name: str) -> int:
    return 2001000 + zlib.crc32(name.encode()) % 100000


_render = unseen._render
_posted = unseen._posted
_scene = unprompted._scene

#: The class's spp (the class is built at 64 x 64).
_S = 256
#: The assignment's maximum depth.
_DEPTH = 8


# --------------------------------------------------------------------------
# Post-processing (the render in, what the program writes out)
# --------------------------------------------------------------------------

#: The pixel under inspection, (41, 23) of 64 x 64, as fractions of the width and height; the marker's colour.
_DEBUG_PIXEL = (41 / 64, 23 / 64)
_MAGENTA = (1.0, 0.0, 1.0)


def _marker_ring(w: int, h: int) -> list[tuple[int, int]]:
    """(row, column) of the 8 pixels round the pixel under inspection (the 3 x 3 square less its centre)."""
    cx, cy = int(_DEBUG_PIXEL[0] * w), int(_DEBUG_PIXEL[1] * h)
    return [(cy + dy, cx + dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if (dx, dy) != (0, 0)]


def _debug_marker(image: np.ndarray) -> np.ndarray:
    """The render with the ring round the debugged pixel painted magenta (in the linear values, before the EXR)."""
    out = np.array(image, np.float64)
    h, w = out.shape[:2]
    for r, c in _marker_ring(w, h):
        out[r, c] = _MAGENTA
    return out


#: The preview's debug-view slider, saved in the config (0 meant the beauty alone).
_DEBUG_MIX = 0.1


def _normal_view(n: np.ndarray) -> np.ndarray:
    """The normals view's colour of unit normals: 0.5 n + 0.5."""
    return 0.5 * np.asarray(n, np.float64) + 0.5


def _normals_mixed_sample(o, d, seed, *, full, mix: float):
    """A sample mixed with the normals view of its camera ray's first hit (the normal faced to the ray):
    (1 - mix) L + mix (0.5 n + 0.5)."""
    L = unsaid._sampled(full, o, d, seed)
    return (1.0 - mix) * L + mix * _normal_view(unforeseen._first_normal(full, o, d))


def _normals_mixed(x, *, spp: int, seed: int):
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(
        _normals_mixed_sample, full=unsaid._loaded(_DEPTH), mix=_DEBUG_MIX))


def _argparse_bool(text: str) -> bool:
    """``argparse`` with ``type=bool`` calls ``bool`` on the option's text: every non-empty string is true."""
    return bool(text)


#: The a-trous filter's B3-spline taps, its levels (steps 1, 2, 4) and its colour weight's sigma (halved each level).
_ATROUS_TAPS = np.array([1.0 / 16.0, 1.0 / 4.0, 3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0])
_ATROUS_LEVELS, _ATROUS_SIGMA = 3, 0.25


def _atrous(image: np.ndarray, *, levels: int = _ATROUS_LEVELS, sigma: float = _ATROUS_SIGMA) -> np.ndarray:
    """An edge-avoiding a-trous wavelet filter on the colour alone (no normal or albedo buffers): at level i, each
    pixel the weighted mean of the 5 x 5 taps 2^i apart, each weighted by the B3 spline's product times
    exp(-|c_q - c_p|^2 / sigma_i^2), sigma_i = sigma / 2^i; the borders repeat their edge pixels."""
    c = np.array(image, np.float64)
    h, w = c.shape[:2]
    for i in range(levels):
        step, s = 1 << i, sigma / 2.0 ** i
        pad = 2 * step
        cp = np.pad(c, ((pad, pad), (pad, pad), (0, 0)), mode="edge")
        acc, wsum = np.zeros_like(c), np.zeros((h, w))
        for a, dy in enumerate(range(-2, 3)):
            for b, dx in enumerate(range(-2, 3)):
                q = cp[pad + dy * step:pad + dy * step + h, pad + dx * step:pad + dx * step + w]
                wt = _ATROUS_TAPS[a] * _ATROUS_TAPS[b] * np.exp(-np.sum((q - c) ** 2, axis=2) / s ** 2)
                acc += wt[..., None] * q
                wsum += wt
        c = acc / wsum[..., None]
    return c


#: The grey-world gains the white balance cached (``wb.json``) on its first run, on a test scene of red and green walls.
_WB_GAINS = (0.92, 1.0, 1.09)


def _cached_white_balance(image: np.ndarray) -> np.ndarray:
    return np.asarray(image, np.float64) * np.asarray(_WB_GAINS)


# --------------------------------------------------------------------------
# Writers (the render in, the file the program writes)
# --------------------------------------------------------------------------


def _fast_log2(x) -> np.ndarray:
    """A float32's bits read as an integer over 2^23, less 127: log2 exact at powers of 2, linear between them."""
    return np.asarray(x, np.float32).view(np.int32).astype(np.float64) / (1 << 23) - 127.0


def _fast_exp2(p) -> np.ndarray:
    """The inverse: (p + 127) 2^23 as an integer's bits read as a float32."""
    p = np.clip(np.asarray(p, np.float64), -126.0, 127.0)
    return ((p + 127.0) * (1 << 23)).astype(np.int32).view(np.float32).astype(np.float64)


def _fast_pow(a, b: float) -> np.ndarray:
    """The profiling build's ``fast_pow(a, b) = fast_exp2(b * fast_log2(a))`` (0 for a = 0)."""
    a = np.asarray(a, np.float64)
    return np.where(a > 0.0, _fast_exp2(b * _fast_log2(np.maximum(a, 1e-30))), 0.0)


def _fast_srgb_codes(image: np.ndarray) -> np.ndarray:
    """8-bit codes of the sRGB curve with its power taken by :func:`_fast_pow`."""
    v = np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 1.0)
    e = np.where(v <= 0.0031308, 12.92 * v, 1.055 * _fast_pow(v, 1.0 / 2.4) - 0.055)
    return np.floor(np.clip(e, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def _write_png_fast_pow(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_fast_srgb_codes(image), folder)


def _writer_codes(image: np.ndarray, bits: float = 8, gamma: float = 2.2) -> np.ndarray:
    """The student's ``write_png(path, img, bits=8, gamma=2.2)``: ``round(clip(img, 0, 1) ** (1 / gamma) * (2 **
    bits - 1))`` as ``uint8``."""
    top = 2.0 ** bits - 1.0
    v = np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 1.0)
    return np.round(np.power(v, 1.0 / gamma) * top).astype(np.uint8)


def _write_png_bits_given_gamma(image: np.ndarray, folder: Path) -> Path:
    """The old call ``write_png(path, img, 2.2)`` (then the gamma) after the parameters became ``(bits, gamma)``."""
    return novel._write_png(_writer_codes(image, 2.2), folder)


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits (materials, geometry, light)
# --------------------------------------------------------------------------

#: Matplotlib's ``tab10`` colours (its hex codes over 255), the debug view's colour of surface k being ``k % 10``.
_TAB10 = tuple(tuple(int(h[i:i + 2], 16) / 255.0 for i in (1, 3, 5)) for h in (
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"))
#: How much of the ID colour the debug view mixed into every albedo.
_ID_MIX = 0.2


def _tinted(albedo, k: int) -> tuple[float, ...]:
    c = _TAB10[k % len(_TAB10)]
    return tuple(float((1.0 - _ID_MIX) * a + _ID_MIX * b) for a, b in zip(albedo, c))


def _albedos_id_tinted(s):
    """Every Lambertian's albedo mixed with the ID colour of its index in the student's list: the walls AB to FA 0
    to 5, the floor 6, the ceiling 7, the tetrahedron 8."""
    walls = tuple(replace(w, albedo=_tinted(w.albedo, k)) for k, w in enumerate(s.room.walls))
    room = replace(s.room, walls=walls, floor_albedo=_tinted(s.room.floor_albedo, 6),
                   ceiling_albedo=_tinted(s.room.ceiling_albedo, 7))
    objects = tuple(replace(o, material=replace(o.material, albedo=_tinted(o.material.albedo, 8)))
                    if o.name == "tetrahedron" else o for o in s.objects)
    return replace(s, room=room, objects=objects)


#: The loader's default for a missing ``floor_albedo`` key (the renamed key is ``floor: {albedo: ...}``).
_FLOOR_DEFAULT = (0.8, 0.8, 0.8)
#: Wall EF's colour as first typed (its red 0.51 for 0.15), which the pickled scene kept.
_EF_TYPED = (0.51, 0.70, 0.15)


def _sphere_from_diameter(s):
    """The sphere's ``radius = cfg.get("radius", cfg.get("diameter"))`` given the other side's ``diameter: 3.0``."""
    return replace(s, objects=tuple(replace(o, radius=2.0 * o.radius) if o.name == "sphere" else o
                                    for o in s.objects))


def _sphere_centre() -> np.ndarray:
    return unsaid._sphere()[0]


def _sphere_formula_normals(points) -> np.ndarray:
    """The sphere's ``normal_at``, ``normalize(p - sphere.center)``, at ``points`` (N, 3)."""
    v = np.asarray(points, np.float64) - _sphere_centre()
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _tetra_sphere_normals(d: dict) -> dict:
    """The tetrahedron shaded with the sphere's normal formula: each face's corners given ``normalize(v -
    sphere.center)`` as vertex normals (interpolated and normalised over the face, as the copied function gives at
    each point, to within the faces' small angle seen from the sphere's centre)."""
    import mitsuba as mi

    sf = fresh._surface("tetrahedron")
    tris = np.asarray(sf.triangles, np.float64)
    props = mi.Properties()
    props["bsdf"] = mi.load_dict({"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {
        "type": "rgb", "value": [float(a) for a in sf.material.albedo]}}})
    mesh = mi.Mesh("tetrahedron", 3 * len(tris), len(tris), props, has_vertex_normals=True)
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(tris.reshape(-1).astype(np.float32))
    params["vertex_normals"] = mi.Float(_sphere_formula_normals(tris.reshape(-1, 3)).reshape(-1).astype(np.float32))
    params["faces"] = mi.UInt32(np.arange(3 * len(tris), dtype=np.uint32))
    params.update()
    return dict(d, tetrahedron=mesh)


#: The tetrahedron's base vertex whose line the staged fix left out, and the height it kept.
_UNSTAGED_VERTEX, _OLD_BASE_Z = 2, -5.0


def _tetra_base_half_lifted(s):
    """The tetrahedron with its third vertex (8.5, -3.8) still at z = -5.0, the other two base vertices at -4.9."""
    def lifted(o):
        v = list(o.vertices)
        v[_UNSTAGED_VERTEX] = (v[_UNSTAGED_VERTEX][0], v[_UNSTAGED_VERTEX][1], _OLD_BASE_Z)
        return replace(o, vertices=tuple(v))

    return replace(s, objects=tuple(lifted(o) if o.name == "tetrahedron" else o for o in s.objects))


def _rect(x0: float, x1: float, y0: float, y1: float, z: float) -> np.ndarray:
    """(2, 3, 3): a horizontal rectangle at height z, wound to face down (the light's side)."""
    from mcrt.mitsuba_scene import _light_surface
    from mcrt.scene import Surface

    p = [(x0, y0, z), (x1, y0, z), (x1, y1, z), (x0, y1, z)]
    tris = np.array([[p[0], p[1], p[2]], [p[0], p[2], p[3]]], np.float64)
    return np.array(_light_surface(Surface("rect", tris, None), (0.0, 0.0, -1.0)).triangles)


#: The memoised light sample's random numbers (its first call's), and the side of the small square that stands for
#: the point it gives (its radiance scaled so that it carries the square's weight, Le A).
_MEMO_UV, _POINT_SIDE = (0.7717, 0.3046), 0.01


def _memo_point() -> tuple[float, float, float]:
    lt = _scene().light
    return (lt.center[0] + (_MEMO_UV[0] - 0.5) * lt.size[0], lt.center[1] + (_MEMO_UV[1] - 0.5) * lt.size[1],
            lt.center[2])


def _light_at_memo_point(d: dict) -> dict:
    """The light as its memoised sample makes it for the surfaces: every light sample at one point, weighted by the
    square's area (pdf 1 / A): a tiny square there of radiance Le A / side^2."""
    lt = _scene().light
    x, y, z = _memo_point()
    h = _POINT_SIDE / 2.0
    le = tuple(float(a) * lt.area / _POINT_SIDE ** 2 for a in lt.radiance)
    return unsaid._meshes(d, light=(_rect(x - h, x + h, y - h, y + h, z), le))


def _memoised_light(x, *, spp: int, seed: int):
    """The light seen (directly and in the mirror) as it is, everything else lit from the memoised point."""
    return unsaid._light_seen_from(x, spp=spp, seed=seed, seen_edit=None, rest_edit=_light_at_memo_point)


#: ``AreaLight(center, size=2.0, radiance=20.0)`` became ``AreaLight(center, radiance, size)``; the old positional
#: call's 2.0 is now the radiance and 20.0 the size.
_SWAPPED_SIZE, _SWAPPED_RADIANCE = 20.0, 2.0


def _light_args_swapped(s):
    return cases._light(s, size=(_SWAPPED_SIZE, _SWAPPED_SIZE), radiance=(_SWAPPED_RADIANCE,) * 3)


#: The debug tint on the camera's hits of the light.
_LIGHT_TINT = (1.0, 0.3, 0.3)


def _light_tinted(x, *, spp: int, seed: int):
    """Emission the camera ray meets at its first hit times the tint: the render plus (tint - 1) times its
    same-seed max-depth-1 render (the light seen directly; its reflection in the mirror as it is)."""
    h, w = x.shape[:2]
    seen = _render(w, h, spp, seed, max_depth=1)
    return _render(w, h, spp, seed) + (np.asarray(_LIGHT_TINT) - 1.0) * seen


#: The light's strata a side; the calls of the sampler a sample makes (its own and the debug line's three).
_STRATA, _CALLS = 4, 4


def _strata_used(calls_per_sample: int = _CALLS, n: int = _STRATA * _STRATA) -> list[int]:
    """The strata ``k = counter % n`` the samples use when the counter advances ``calls_per_sample`` times a sample
    (the sample's own call first) from 0."""
    return sorted({(s * calls_per_sample) % n for s in range(n)})


def _stratum_rect(k: int) -> tuple[float, float, float, float]:
    """Stratum k's rectangle on the light: column k // 4 along x, row k % 4 along y."""
    lt = _scene().light
    a, b = divmod(k, _STRATA)
    x0, y0 = lt.center[0] - lt.size[0] / 2.0, lt.center[1] - lt.size[1] / 2.0
    sx, sy = lt.size[0] / _STRATA, lt.size[1] / _STRATA
    return (x0 + a * sx, x0 + (a + 1) * sx, y0 + b * sy, y0 + (b + 1) * sy)


def _light_even_strata(d: dict) -> dict:
    """The light as the surfaces see it when only the strata :func:`_strata_used` gives are sampled, with the
    square's pdf: those strata (0, 4, 8, 12: the strip y in [-1, -0.5]) at radiance Le A / (their area), the rest
    dark."""
    lt = _scene().light
    used = _strata_used()
    area = sum((r[1] - r[0]) * (r[3] - r[2]) for r in map(_stratum_rect, used))
    le = tuple(float(a) * lt.area / area for a in lt.radiance)
    tris = np.concatenate([_rect(*_stratum_rect(k), lt.center[2]) for k in used])
    return unsaid._meshes(d, light=(tris, le))


def _light_strata_logged(x, *, spp: int, seed: int):
    return unsaid._light_seen_from(x, spp=spp, seed=seed, seen_edit=None, rest_edit=_light_even_strata)


# --------------------------------------------------------------------------
# The camera
# --------------------------------------------------------------------------


def _pixel_and_offset(f, n: int):
    """A film coordinate in [0, 1) as its pixel index among ``n`` and its offset in that pixel, in [0, 1)."""
    k = np.minimum(np.floor(np.asarray(f, np.float64) * n), n - 1)
    return k, np.clip(np.asarray(f, np.float64) * n - k, 0.0, 1.0)


def _preview_table_rays(fx, fy, *, w: int, h: int):
    """The rays from the table cached at half the resolution: pixel (i, j) looks up entry (i // 2, j // 2), that
    entry's pixel centre, and jitters it by the current pixel's width: each 2 x 2 block of pixels sees the window one
    pixel wide at the block's centre."""
    i, u = _pixel_and_offset(fx, w)
    j, v = _pixel_and_offset(fy, h)
    cx, cy = (2.0 * (i // 2) + 1.0) / w, (2.0 * (j // 2) + 1.0) / h
    return unsaid._pinhole(cx + (u - 0.5) / w, cy + (v - 0.5) / h)


def _preview_table(x, *, spp: int, seed: int):
    h, w = x.shape[:2]
    return unsaid._traced(x, spp=spp, seed=seed, camera=partial(_preview_table_rays, w=w, h=h))


#: Cycles' default pixel filter: Blackman-Harris, 1.5 pixels wide.
_BH_WIDTH = 1.5


def _blackman_harris(x, width: float = _BH_WIDTH) -> np.ndarray:
    """Cycles' ``filter_func_blackman_harris``: the window over [-width / 2, width / 2] (0 outside)."""
    x = np.asarray(x, np.float64)
    t = 2.0 * math.pi * (x / width + 0.5)
    v = 0.35875 - 0.48829 * np.cos(t) + 0.14128 * np.cos(2.0 * t) - 0.01168 * np.cos(3.0 * t)
    return np.where(np.abs(x) <= width / 2.0, v, 0.0)


def _bh_table(width: float = _BH_WIDTH, n: int = 2049) -> tuple[np.ndarray, np.ndarray]:
    """(offsets, their CDF): the filter's cumulative integral over [-width / 2, width / 2], normalised."""
    xs = np.linspace(-width / 2.0, width / 2.0, n)
    f = _blackman_harris(xs, width)
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(xs))])
    return xs, cdf / cdf[-1]


def _bh_offset(u) -> np.ndarray:
    """An offset from the pixel's centre drawn from the filter by its inverse CDF (Cycles' filter table)."""
    xs, cdf = _bh_table()
    return np.interp(np.asarray(u, np.float64), cdf, xs)


def _bh_rays(fx, fy, *, w: int, h: int):
    """Each sample through its pixel's centre plus an offset drawn from the filter on each axis (equal weights)."""
    i, u = _pixel_and_offset(fx, w)
    j, v = _pixel_and_offset(fy, h)
    return unsaid._pinhole((i + 0.5 + _bh_offset(u)) / w, (j + 0.5 + _bh_offset(v)) / h)


def _bh_filtered(x, *, spp: int, seed: int):
    h, w = x.shape[:2]
    return unsaid._traced(x, spp=spp, seed=seed, camera=partial(_bh_rays, w=w, h=h))


#: The viewer's zoom saved into the camera's settings (the image plane's half-width divided by it).
_ZOOM = 1.1
_ZOOM_FOV = math.degrees(2.0 * math.atan(math.tan(math.radians(45.0)) / _ZOOM))


# --------------------------------------------------------------------------
# The integrator
# --------------------------------------------------------------------------

#: The profile preset's maximum depth.
_PROFILE_DEPTH = 6


def _light_times(d: dict, *, f: float) -> dict:
    """The light's radiance times ``f`` (its shape as it is)."""
    return unsaid._meshes(d, light=(unsaid._light_tris(), tuple(f * float(a) for a in _scene().light.radiance)))


#: Dividing by the pdf 1 / A twice multiplies the light sample by A once more.
_PDF_TWICE = 4.0


def _pdf_twice(x, *, spp: int, seed: int):
    """The light seen as it is, the light sampled at every vertex A = 4 times too bright."""
    return unsaid._light_seen_from(x, spp=spp, seed=seed, seen_edit=None,
                                   rest_edit=partial(_light_times, f=_PDF_TWICE))


#: The light's range added while profiling: no shadow ray to a light sample farther than this.
_LIGHT_RANGE = 11.0


def _visible_in_range(mscene, p, wi, dist, *, light_range: float):
    return (np.asarray(dist) <= light_range) & unheralded._visible_within(mscene, p, wi, dist, reach=np.inf)


def _ranged_direct(mscene, rng, p, n, rho, mitsuba, *, light_range: float):
    """A first vertex's light sample (uniform on the square, pdf 1 / A) that counts only within the range."""
    return rho * unheralded._light_sample(mscene, rng, p, n, partial(_visible_in_range, light_range=light_range))


def _light_range(x, *, spp: int, seed: int):
    return unheralded._first_vertex(x, spp=spp, seed=seed, direct=partial(_ranged_direct, light_range=_LIGHT_RANGE))


#: The debug knob on the indirect light at the first hit.
_INDIRECT_GAIN = 0.5


def _indirect_gain_sample(o, d, seed, *, full, two, gain: float):
    """Where a camera ray meets a Lambertian first: its direct light (the max-depth-2 sample) plus ``gain`` times the
    rest (the max-depth-8 sample less it, same seed); elsewhere the sample as it is."""
    L, L2 = unsaid._sampled(full, o, d, seed), unsaid._sampled(two, o, d, seed)
    diffuse = unbeknown._diffuse_first(full, o, d)
    return np.where(diffuse[:, None], L2 + gain * (L - L2), L)


def _indirect_gain(x, *, spp: int, seed: int):
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(
        _indirect_gain_sample, full=unsaid._loaded(_DEPTH), two=unsaid._loaded(2), gain=_INDIRECT_GAIN))


# --------------------------------------------------------------------------
# Samples and passes
# --------------------------------------------------------------------------

#: The debugging cap on the spp.
_SPP_CAP = 32

#: The render region (x from, x to, y from, y to) as fractions of the width and height.
_REGION = (0.40, 0.85, 0.50, 0.95)


def _region_bounds(w: int, h: int) -> tuple[int, int, int, int]:
    x0, x1, y0, y1 = _REGION
    return round(x0 * w), round(x1 * w), round(y0 * h), round(y1 * h)


def _region_only(image: np.ndarray) -> np.ndarray:
    """The pixels outside the render region left at the buffer's 0."""
    h, w = image.shape[:2]
    x0, x1, y0, y1 = _region_bounds(w, h)
    out = np.zeros_like(np.asarray(image, np.float64))
    out[y0:y1, x0:x1] = np.asarray(image, np.float64)[y0:y1, x0:x1]
    return out


#: Two passes of 128 spp, the film's count assigned (not added) each pass.
_PASS2 = 128


def _count_assigned(sums: list[np.ndarray], per_pass: int) -> np.ndarray:
    """The passes' sums added, divided by the count the last pass assigned (``count = spp_pass``)."""
    return sum(sums) / per_pass


def _two_passes_one_count(x, *, seed: int):
    h, w = x.shape[:2]
    return _count_assigned([_PASS2 * _render(w, h, _PASS2, seed + k) for k in range(2)], _PASS2)


#: Four passes of 64 spp, one seed consumed by the debug print: three rendered, the sum divided by all four's spp.
_PASSES, _PASS_SPP = 4, 64


def _passes_run(seeds) -> list[int]:
    """The passes' seeds the loop gets after ``print("first seed:", next(seeds))`` took the first."""
    seeds = iter(seeds)
    next(seeds)  # the debug line's argument
    return list(seeds)


def _seed_consumed(x, *, seed: int):
    h, w = x.shape[:2]
    run = _passes_run(seed + k for k in range(_PASSES))
    return sum(_PASS_SPP * _render(w, h, _PASS_SPP, s) for s in run) / (_PASSES * _PASS_SPP)


# --------------------------------------------------------------------------
# Correct renders made in other ways
# --------------------------------------------------------------------------


def _shuffled_rays(fx, fy, *, w: int, h: int, perm: np.ndarray):
    """The lane of pixel p traced for pixel perm[p] (its offset in the pixel kept)."""
    i, u = _pixel_and_offset(fx, w)
    j, v = _pixel_and_offset(fy, h)
    q = perm[(j * w + i).astype(np.int64)]
    return unsaid._pinhole((q % w + u) / w, (q // w + v) / h)


def _unshuffled(traced: np.ndarray, perm: np.ndarray) -> np.ndarray:
    """Each traced value scattered back to its pixel: out[perm[p]] = traced[p]."""
    flat = traced.reshape(-1, traced.shape[-1])
    out = np.empty_like(flat)
    out[perm] = flat
    return out.reshape(traced.shape)


def _shuffled(x, *, seed: int):
    h, w = x.shape[:2]
    perm = np.random.default_rng(seed + 5).permutation(w * h)
    traced = unsaid._traced(x, spp=_S, seed=seed, camera=partial(_shuffled_rays, w=w, h=h, perm=perm))
    return _unshuffled(traced, perm)


def _rr_from(d: dict, *, rr_depth: int) -> dict:
    return dict(d, integrator=dict(d["integrator"], rr_depth=int(rr_depth)))


def _both_sides(x, *, seed: int):
    """The two sides' renders (roulette from the 5th and from the 3rd vertex), 128 spp each, averaged."""
    h, w = x.shape[:2]
    return 0.5 * (_render(w, h, _PASS2, seed, dict_edit=partial(_rr_from, rr_depth=5))
                  + _render(w, h, _PASS2, seed + 1, dict_edit=partial(_rr_from, rr_depth=3)))


#: The commit whose build made the render, as the EXR's header attribute.
_COMMIT = "3f9c2ab"


def _write_exr_rgb_key(image: np.ndarray, folder: Path) -> Path:
    """OpenEXR's ``File`` API given one ``"RGB"`` array (written as R, G, B) and a ``gitCommit`` string attribute."""
    import OpenEXR

    path = folder / "render.exr"
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage, "gitCommit": _COMMIT}
    OpenEXR.File(header, {"RGB": np.ascontiguousarray(image, np.float32)}).write(str(path))
    return path


def _with_flags(x, *, spp: int, seed: int, flags: tuple[tuple[str, bool], ...]):
    """A Mitsuba render with Dr.Jit's ``flags`` set (by name), each restored afterwards."""
    import drjit as dr

    h, w = x.shape[:2]
    old = [(f, dr.flag(getattr(dr.JitFlag, f))) for f, _ in flags]
    try:
        for f, on in flags:
            dr.set_flag(getattr(dr.JitFlag, f), on)
        return _render(w, h, spp, seed)
    finally:
        for f, on in old:
            dr.set_flag(getattr(dr.JitFlag, f), on)


def _spawned_seeds(seed: int, n: int) -> list[int]:
    """``n`` 32-bit seeds from ``np.random.SeedSequence(seed).spawn(n)``, one word of each child's state."""
    return [int(c.generate_state(1)[0]) for c in np.random.SeedSequence(seed).spawn(n)]


def _spawned_passes(x, *, seed: int):
    h, w = x.shape[:2]
    return sum(_render(w, h, _PASS_SPP, s) for s in _spawned_seeds(seed, _PASSES)) / _PASSES


def _write_png_optimized(image: np.ndarray, folder: Path) -> Path:
    """The 8-bit sRGB PNG re-saved by the pre-commit hook with Pillow's ``optimize=True``."""
    from PIL import Image

    path = folder / "render.png"
    Image.fromarray(blind._srgb8(image), "RGB").save(path, format="PNG", optimize=True)
    return path


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_debug_pixel_marker_left", "pp_normals_view_mixed_in", "pp_denoise_type_bool_flag",
                        "pp_white_balance_gains_cached"),
    "file": ("file_png_fast_pow_profile_build", "file_exr_gitignored_test_render", "file_png_writer_bits_for_gamma"),
    "materials": ("albedos_object_id_colours_mixed", "floor_key_renamed_merge_default", "wall_ef_stale_scene_pickle"),
    "geometry": ("sphere_radius_from_diameter_key", "tetra_normal_copied_from_sphere", "tetra_base_fix_half_staged"),
    "camera": ("camera_ray_table_cached_preview", "pixel_filter_cycles_default", "camera_viewer_zoom_saved"),
    "light": ("light_sample_memoised", "light_args_reordered_size_radiance", "light_hits_debug_tint",
              "light_strata_logging_evaluated"),
    "integrator": ("depth_profile_preset", "merge_light_pdf_divided_twice", "light_range_profiling",
                   "indirect_gain_debug_knob"),
    "samples": ("spp_debug_cap_left", "render_region_left", "merge_film_count_assigned", "print_next_seed_consumed"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    c = _crc
    return (
        # Post-processing
        Spec("pp_debug_pixel_marker_left", "bad_pixels", **_posted("debug_marker", _debug_marker),
             truth="a debug block that paints a magenta ring round the pixel under inspection (41, 23) to find it in "
             "the viewer, guarded by if args.debug_pixel:, which a refactor made always true by giving the option "
             "the default (41, 23) in place of None: the 8 pixels round it (1, 0, 1) in the EXR, the rest right"),
        Spec("pp_normals_view_mixed_in", "wrong_buffer", True, held_out=True, **_posted("normals_mixed", partial(
            _normals_mixed, spp=_S, seed=c("pp_normals_view_mixed_in"))),
             truth="the preview's debug view (the first hit's normal as 0.5 n + 0.5) mixed into every sample as "
             "(1 - mix) L + mix view, its slider's 0.1 saved in the config by the preview's 'save settings' and read "
             "by the batch render: a tenth of every pixel the normals' colour (the floor's (0.5, 0.5, 1)), "
             "the dark walls lifted and tinted, the light a tenth darker"),
        Spec("pp_denoise_type_bool_flag", "blur", **_posted("atrous_denoised", _atrous),
             truth="an edge-avoiding a-trous wavelet denoiser (three levels of 5 x 5 B3-spline taps, steps 1, 2 and "
             "4, each tap weighted by exp(-|dc|^2 / sigma^2) on the colour alone, sigma 0.25 halved each level) run "
             "on the render because --denoise was declared type=bool and the render script passed --denoise "
             "False, which bool('False') reads as true: the noise and the fine detail smoothed, the light's edges "
             "kept"),
        Spec("pp_white_balance_gains_cached", "white_balance", held_out=True, **_posted(
            "wb_cached", _cached_white_balance),
             truth="the grey-world white balance run once on a test scene of red and green walls, its gains (0.92, "
             "1.0, 1.09) cached in wb.json and read whenever the file exists, though the config's "
             "auto_white_balance is off: every render since scaled by them, red 8 % too dark and blue 9 % too "
             "bright, as EXR"),
        # Writing the file
        Spec("file_png_fast_pow_profile_build", "encoding", writer=_write_png_fast_pow, file="png-fast-pow",
             truth="the hand-in built with the profiling configuration, whose -DFAST_MATH swaps powf for a fast_pow "
             "(log2 read from the float's bits, exp2 written into them, Schraudolph's trick) in the sRGB encoder: "
             "1.055 fast_pow(v, 1/2.4) - 0.055 up to 6 % off between powers of two (a linear 0.5 written 199 for "
             "188), an 8-bit PNG"),
        Spec("file_exr_gitignored_test_render", "spp_claim", held_out=True, spp=64, declared_spp=_S,
             truth="the renders kept out of the repository by a *.exr line added to .gitignore when they grew, so "
             "the final 256-spp render was never committed and the hand-in's render.exr is the 64-spp test render "
             "added with git add -f before it, beside the manifest the final run wrote (spp = 256): unbiased, as "
             "noisy as 64 spp"),
        Spec("file_png_writer_bits_for_gamma", "code_range", True, writer=_write_png_bits_given_gamma,
             file="png-bits-2.2",
             truth="a PNG writer whose parameters a refactor reordered from (path, img, gamma=2.2, bits=8) to "
             "(path, img, bits=8, gamma=2.2), called as before with write_png(path, img, 2.2): bits 2.2, the codes "
             "round(v ** (1 / 2.2) * (2 ** 2.2 - 1)), 0 to 4 of 255: the image nearly black, an 8-bit PNG"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("albedos_object_id_colours_mixed", "albedo", True, edit=_albedos_id_tinted,
             truth="the debug view that colours each surface by its index (Matplotlib's tab10, to check the "
             "intersection's IDs) mixed into every Lambertian's albedo as 0.8 albedo + 0.2 colour, its weight left "
             "at 0.2: the walls AB to FA, the floor, the ceiling and the tetrahedron each shifted a fifth of the "
             "way to blue, orange, green, red, purple, brown, pink, grey and olive"),
        Spec("floor_key_renamed_merge_default", "albedo", True, held_out=True, edit=cases.floor_albedo(
            _FLOOR_DEFAULT),
             truth="a merge that took the partner's scene file, where floor_albedo had become floor: {albedo: "
             "...}, and the student's loader, which reads cfg.get('floor_albedo', 0.8): the floor's albedo the "
             "default 0.8 for 0.6, the floor and what it lights a third brighter"),
        Spec("wall_ef_stale_scene_pickle", "albedo", True, edit=cases.wall_albedo("EF", _EF_TYPED),
             truth="wall EF's colour first typed (0.51, 0.70, 0.15), its red's digits swapped, and corrected in "
             "the YAML later; the parsed scene cached as scene.pkl, rebuilt only when the file is missing (keyed by "
             "the file's name, not its time or hash), so the render still has the typo: the green wall on the left "
             "yellow-green"),
        # Geometry
        Spec("sphere_radius_from_diameter_key", "object_size", True, edit=_sphere_from_diameter,
             truth="a merge that took the partner's scene file, which gives the sphere as diameter: 3.0 (a Blender "
             "export), and the student's loader's radius = cfg.get('radius', cfg.get('diameter')): the mirror "
             "sphere of radius 3 for 1.5 about the same centre, through the floor and wall DE, filling the right "
             "of the far room"),
        Spec("tetra_normal_copied_from_sphere", "normals", True, held_out=True,
             mitsuba_edit=_tetra_sphere_normals,
             truth="the tetrahedron's normal_at copied from the sphere's class, keeping return normalize(p - "
             "sphere.center) with the module's sphere: the tetrahedron shaded as if each point's normal pointed "
             "away from the mirror sphere's centre (9.5, 2, -3.3), mostly along -y: its faces' light and shade "
             "wrong, its outline right"),
        Spec("tetra_base_fix_half_staged", "object_shape", edit=_tetra_base_half_lifted,
             truth="the fix lifting the tetrahedron's base from z = -5.0 (on the floor, speckled where the two "
             "met) to -4.9, staged with git add -p one hunk short and the rest stashed: the base vertex (8.5, "
             "-3.8) still at -5.0, the other two at -4.9: the tetrahedron tilted a little, one corner touching the "
             "floor"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera
        Spec("camera_ray_table_cached_preview", "resampling", **_posted("ray_table_preview", partial(
            _preview_table, spp=_S, seed=c("camera_ray_table_cached_preview"))),
             truth="the camera's rays looked up in a table cached to rays.npy (to skip the trigonometry), keyed by "
             "the camera's name, not the resolution, and built by the 32 x 32 preview: pixel (i, j) reads entry "
             "(i // 2, j // 2) and jitters it by its own pixel's width: every 2 x 2 block of pixels the same, the "
             "window one pixel wide at the block's centre"),
        Spec("pixel_filter_cycles_default", "pixel_footprint", held_out=True, **_posted("blackman_harris", partial(
            _bh_filtered, spp=_S, seed=c("pixel_filter_cycles_default"))),
             truth="the --filter option's default copied from Cycles, Blackman-Harris 1.5 pixels wide, sampled by "
             "its inverse CDF on each axis with equal weights: each pixel the filter's weighted mean about its "
             "centre (a footprint narrower than the pixel's square in its middle, reaching a quarter pixel into its "
             "neighbours), not the box's mean"),
        Spec("camera_viewer_zoom_saved", "camera_fov", True, edit=cases.fov(_ZOOM_FOV),
             truth="the interactive viewer's zoom (1.1, from looking at the tetrahedron's edges) written into the "
             "camera's settings by its 'save view' button, the image plane's half-width tan 45 / 1.1: a field of "
             "view of 84.5 degrees for 90, the view 10 % magnified"),
        # Light model
        Spec("light_sample_memoised", "light_model", True, **_posted("light_memoised", partial(
            _memoised_light, spp=_S, seed=c("light_sample_memoised"))),
             truth="the light's sample_light() decorated with functools.cache after a profiler showed it hot; it "
             "takes no argument, so its first point (5.54, -0.39, 4.99) is every vertex's light sample, weighted by "
             "the square's area: the light on every surface from one point of the square (hard shadows), the "
             "light seen as it is"),
        Spec("light_args_reordered_size_radiance", "light_size", True, held_out=True,
             edit=_light_args_swapped,
             truth="AreaLight(center, size, radiance) reordered by a refactor to (center, radiance, size) and the "
             "scene builder's positional call AreaLight(c, 2.0, 20.0) left as it was: a light 20 x 20 of radiance "
             "2, as large as the ceiling (clipped by the walls) and 4 times the power: the whole ceiling glowing, "
             "the room brighter, soft shadows"),
        Spec("light_hits_debug_tint", "light_seen", **_posted("light_tinted", partial(
            _light_tinted, spp=_S, seed=c("light_hits_debug_tint"))),
             truth="a debug line left in the camera-ray branch, if depth == 0 and hit.is_emitter: L = Le * "
             "DEBUG_TINT with the tint (1, 0.3, 0.3), added to see in the preview that the rays meet the light: the "
             "light seen red (20, 6, 6), its reflection in the mirror and its light on every surface right"),
        Spec("light_strata_logging_evaluated", "light_pdf", True, held_out=True, **_posted(
            "light_strata_logged", partial(_light_strata_logged, spp=_S, seed=c("light_strata_logging_evaluated"))),
             truth="the light's 4 x 4 strata taken in turn by a counter (k = n % 16), and a line log.debug('light "
             "samples %s', [light.sample() for _ in range(3)]) added while debugging: logging evaluates its "
             "arguments though the level is INFO, so each vertex's sample takes every 4th stratum, 0, 4, 8 and 12: "
             "only the strip y in [-1, -0.5] sampled (with the square's pdf): the light on surfaces from that strip "
             "at 4 times the radiance, the light seen as it is"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples and passes."""
    c = _crc
    return (
        # Integrator
        Spec("depth_profile_preset", "depth", True, max_depth=_PROFILE_DEPTH,
             truth="the hand-in rendered with make render PRESET=profile left in the Makefile, the preset that "
             "times the BVH with shorter paths: max depth 6 for 8, the light of the 7th and 8th segments lost (a "
             "few per cent, most in the corners)"),
        Spec("merge_light_pdf_divided_twice", "light_pdf", True, held_out=True, **_posted("pdf_twice", partial(
            _pdf_twice, spp=_S, seed=c("merge_light_pdf_divided_twice"))),
             truth="a merge of the partner's branch, which moved the division by the light's pdf into "
             "light.sample() (returning Le / pdf), and the student's, which kept / pdf at the call: both kept, the "
             "light sample divided by 1 / A twice: every vertex's direct light 4 times too bright, the light seen "
             "right"),
        Spec("light_range_profiling", "light_pdf", True, **_posted("light_range", partial(
            _light_range, spp=_S, seed=c("light_range_profiling"))),
             truth="a light range of 11 (a game engine's point-light radius) added while profiling, so that no "
             "shadow ray is traced to a light sample farther away: at the first hit, the light samples more than "
             "11 from it count 0: the far floor under the sphere and the tetrahedron and the foot of the far walls "
             "without most of their direct light"),
        Spec("indirect_gain_debug_knob", "indirect_scale", True, held_out=True, **_posted("indirect_gain", partial(
            _indirect_gain, spp=_S, seed=c("indirect_gain_debug_knob"))),
             truth="a knob INDIRECT_GAIN = 0.5 added to shade_primary() to see the direct light's shadows better, "
             "never set back to 1: where a camera ray meets a Lambertian, everything after its light sample halved "
             "(the colour bleeding and the light in the shadows), the direct light, the mirror and the light "
             "right"),
        # Samples and passes
        Spec("spp_debug_cap_left", "spp_claim", spp=_SPP_CAP, declared_spp=_S,
             truth="spp = min(args.spp, 32)  # DEBUG: fast left in the render function after debugging, the "
             "manifest writing args.spp: 32 samples a pixel for the 256 declared, unbiased, 8 times the variance"),
        Spec("render_region_left", "bad_pixels", True, held_out=True, **_posted("region", _region_only),
             truth="a render region (x 0.40 to 0.85, y 0.50 to 0.95, as Blender's, around the tetrahedron while "
             "its shading was debugged) saved in the config and never cleared: only that rectangle rendered, the "
             "rest of the image the buffer's zeros (black)"),
        Spec("merge_film_count_assigned", "sample_count", True, **_posted("count_assigned", partial(
            _two_passes_one_count, seed=c("merge_film_count_assigned"))),
             truth="a merge of the partner's loop of two passes of 128 spp into the film and the student's "
             "film.add_pass(), which sets self.count = spp_pass (assigned, written when there was one pass): the "
             "sums of 256 samples divided by 128: the image twice too bright"),
        Spec("print_next_seed_consumed", "sample_count", True, held_out=True, spp=_PASSES * _PASS_SPP - _PASS_SPP,
             declared_spp=_S, **_posted("seed_consumed", partial(_seed_consumed, seed=c("print_next_seed_consumed"))),
             truth="the passes' seeds a generator (seed + k for k in range(4)) and a debug line print('first "
             "seed:', next(seeds)) before the pass loop, which took the first: 3 passes of 64 spp rendered, the sum "
             "divided by the 4 passes' 256: the image 3/4 as bright, 256 declared"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_pixels_shuffled_scattered_back", None, **_posted("pixels_shuffled", partial(
            _shuffled, seed=c("ok_pixels_shuffled_scattered_back"))),
             truth="Mitsuba path 256 spp on the pixels in a shuffled order (a load-balancing experiment left on), "
             "each result scattered back by its pixel's index, EXR"),
        Spec("ok_merge_both_sides_averaged", None, held_out=True, **_posted("both_sides", partial(
            _both_sides, seed=c("ok_merge_both_sides_averaged"))),
             truth="Mitsuba path at 128 spp from each side of a merge, Russian roulette from the 5th and from the "
             "3rd vertex, averaged, 256 declared, EXR"),
        Spec("ok_exr_rgb_key_commit_attribute", None, spp=240, writer=_write_exr_rgb_key, file="exr-rgb-key",
             truth="Mitsuba path 240 spp, an EXR by OpenEXR's File API from one 'RGB' array with a gitCommit "
             "header attribute"),
        Spec("ok_drjit_debug_flag_left_on", None, held_out=True, spp=224, **_posted("drjit_debug", partial(
            _with_flags, spp=224, seed=c("ok_drjit_debug_flag_left_on"), flags=(("Debug", True),))),
             truth="Mitsuba path 224 spp with Dr.Jit's Debug flag left on (bounds checks), EXR"),
        Spec("ok_drjit_symbolic_off", None, spp=208, **_posted("drjit_symbolic_off", partial(
            _with_flags, spp=208, seed=c("ok_drjit_symbolic_off"),
            flags=(("SymbolicLoops", False), ("SymbolicCalls", False)))),
             truth="Mitsuba path 208 spp with Dr.Jit's symbolic loops and calls off (evaluated, as printing inside "
             "the loop needs), EXR"),
        Spec("ok_drjit_fast_math_off", None, held_out=True, spp=192, **_posted("drjit_fast_math_off", partial(
            _with_flags, spp=192, seed=c("ok_drjit_fast_math_off"), flags=(("FastMath", False),))),
             truth="Mitsuba path 192 spp with Dr.Jit's FastMath flag off (left from hunting a NaN), EXR"),
        Spec("ok_passes_seed_sequence_spawned", None, **_posted("seed_sequence", partial(
            _spawned_passes, seed=c("ok_passes_seed_sequence_spawned"))),
             truth="Mitsuba path in 4 passes of 64 spp seeded from NumPy's SeedSequence(seed).spawn(4), averaged, "
             "EXR"),
        Spec("ok_png_precommit_optimized", None, held_out=True, spp=216, writer=_write_png_optimized,
             file="png-optimized",
             truth="Mitsuba path 216 spp, an 8-bit sRGB PNG re-saved by a pre-commit hook with Pillow's "
             "optimize=True"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "bad_pixels": "pixels not the render's (a debug marker drawn on them; a render region's outside left black)",
    "wrong_buffer": "another buffer mixed into the mean (a debug view of the normals)",
    "blur": "a filter after rendering (a denoiser switched on by a flag)",
    "white_balance": "each colour channel scaled after rendering (a white balance's cached gains)",
    "encoding": "the values' encoding (the sRGB curve's power approximated)",
    "spp_claim": "fewer samples per pixel than declared (a debugging cap; an older, smaller render handed in)",
    "code_range": "codes of another bit depth in the file (a bit depth of 2.2)",
    "albedo": "a surface's colour (debug colours mixed in, a default for a renamed key, a stale cache's typo)",
    "object_size": "an object's size (the sphere's diameter read as its radius)",
    "normals": "surface normals wrong (the tetrahedron's from the sphere's formula)",
    "object_shape": "an object's shape (one vertex of the tetrahedron left where it was)",
    "resampling": "the image at a lower resolution (rays from a table of the preview's)",
    "pixel_footprint": "each pixel's samples not spread over its square (another pixel filter)",
    "camera_fov": "the camera's field of view (a viewer's zoom saved)",
    "light_model": "another light model (every light sample one point)",
    "light_size": "the light's size (its size and radiance swapped)",
    "light_seen": "the light's own pixels (where the camera sees it) tinted, its light on surfaces right",
    "light_pdf": "the light sampled wrongly (half its strata, its pdf twice, a range): the light seen right, its light "
                 "on surfaces not",
    "depth": "the path depth (a profiling preset's)",
    "indirect_scale": "the indirect light off by a factor (a debug gain), the direct light right",
    "sample_count": "each pixel's sum divided by a count it does not hold (a count assigned, a pass's seed consumed)",
}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = blind.class_causes(MISTAKES, _EARLIER, NEW_CAUSES, _REWORDED)


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
