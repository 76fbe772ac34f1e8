r"""An eleventh class of hand-ins: mistakes in students' tracers, scene input and output no class tried, written blind.

How it was written: from what goes wrong in students' programs (the steps
after rendering, the code that saves the image, the scene typed in or built
into meshes, the camera's rays, the light's samples, the integrator's loop,
the loops that add up the samples), not from the grader. Its author read the
other classes' specs and cause words, the catalogue (:mod:`mcrt.mutants`),
:data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to
stay clear of their mistakes; never the grader's rules (what decides a
cause) nor its reports, and graded none of it, not one case. Each cause and
``major`` flag was set from the mistake alone, and the equivalences of the
new cause were added to ``SAME_MISTAKE`` before any grading. The mistakes
differ from those of the ten other classes
(:mod:`~mcrt.grade.accuracy.cases`, :mod:`~mcrt.grade.accuracy.outside`,
:mod:`~mcrt.grade.accuracy.programs`, :mod:`~mcrt.grade.accuracy.fresh`,
:mod:`~mcrt.grade.accuracy.blind`, :mod:`~mcrt.grade.accuracy.unseen`,
:mod:`~mcrt.grade.accuracy.untried`, :mod:`~mcrt.grade.accuracy.novel`,
:mod:`~mcrt.grade.accuracy.untold`, :mod:`~mcrt.grade.accuracy.unmet`) and
from the catalogue's bugs:

* **post-processing**: a bilateral filter (scikit-image's
  ``denoise_bilateral``) to remove the noise; a sepia tone (the usual 3 x 3
  sepia matrix) for the look; a contrast slider (1.2 (x - 0.5) + 0.5,
  clipped at 0); a border of w/32 pixels cropped (to hide edge artefacts) and
  the rest resized back (scikit-image's bilinear ``resize``);
* **writing the file**: the EXR's three channels all given the red plane
  (the channel loop's index unused); an RGBA buffer (4 bytes a pixel)
  written under a binary PPM's RGB header; an 8-bit PNG of ``v ** 2.2`` (the
  gamma applied the wrong way); a binary PPM written through a text-mode
  stream (every newline byte, in the header and the data, written as CR LF);
* **materials**: debug colours left on the tetrahedron's faces (one bright
  colour a face); the sphere's and the tetrahedron's materials swapped (the
  objects' material indices exchanged); the ceiling's material never assigned
  (black, a zero-initialised default); every albedo taken as 1 - albedo (the
  scene's colours read as absorptions);
* **geometry**: the triangle test's barycentric bound ``u + v <= 1``
  written ``u <= 1 and v <= 1`` (each of the tetrahedron's faces a
  parallelogram); the floor's fan built at the ceiling's height (a copied
  line); each wall's quad given its first triangle only;
* **camera model**: the field of view of a 50 mm lens on a 36 mm film
  (39.6 degrees) for the scene's 90; the ray's height computed from the
  pixel's column (``i`` for ``j``, a copied line); stratified sub-pixel
  offsets ``s / n + u`` (the uniform number not divided by n);
* **light model**: every light sample at the light's centre (the random
  numbers a constant 0.5); the light's corners built from the centre plus or
  minus the half-size along one axis at a time (a diamond of half the area);
  one of its two triangles picked at random for each sample and its pdf 1 /
  (the triangle's area), the probability 1/2 of picking it left out;
* **integrator**: no light sampled at the first diffuse vertex after a mirror
  bounce (the specular flag read a bounce late); four rays traced at the
  first hit and their radiance summed, not averaged; Russian roulette's
  survivors divided by the probability of stopping (0.25), not of going on
  (0.75); the cosine-weighted pdf written cos without its 1/pi (each diffuse
  bounce's weight albedo / pi);
* **samples and passes**: image tiles rendered one pixel too wide (the tile
  loop's bound inclusive), the overlapping pixels' samples added twice and
  divided by the spp; each sample weighted by a Gaussian filter (sigma half a
  pixel) and the sum divided by the spp, not by the sum of the weights; n x n
  strata summed and divided by n.

The correct hand-ins come in ways no class used: Mitsuba of the scene and its
camera turned 90 degrees about the vertical and moved (a student's own
frame), mcrt with Russian roulette of a fixed survival from the second
vertex, mcrt with the triangle intersector, Mitsuba with the emitters hidden
plus the light seen apart (max depth 1), an 8-bit PNG with text and pHYs
chunks, an uncompressed float EXR with a header field of the student's, a
BMP written by hand top line first (negative height), and mcrt of the scene
in decimetres (every length times 10).

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s
``edit`` and ``mitsuba_edit``), Mitsuba renders combined where light
transport or pixel integrals are linear in what is combined (paths of each
length, the light seen apart, sub-pixel cells, tiles), or correct renders
post-processed and written with NumPy, SciPy, scikit-image and Pillow as
students' programs do. mcrt renders only correct hand-ins.

Causes (:data:`_REWORDED`, :data:`NEW_CAUSES`) and the held-out rule
(:func:`held_out_rule` over :data:`CATEGORIES`: the 2nd, 4th, ... of each
category and of the correct hand-ins) are as in
:mod:`~mcrt.grade.accuracy.unmet`, fixed before any case was graded.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import blind, cases, fresh, novel, outside, programs, unmet, unseen, untold, untried
from mcrt.grade.accuracy.cases import Spec

#: The causes new in this class, as the report words them.
NEW_CAUSES: dict[str, str] = {
    "indirect_scale": "the indirect light off by a factor (a bounce's rays summed, not averaged; a sampling pdf's "
                      "constant wrong), the direct light right",
}


def _crc(name: str) -> int:
    return 71000 + zlib.crc32(name.encode()) % 100000


_render = unseen._render
_posted = unseen._posted


# --------------------------------------------------------------------------
# Post-processing (linear render in, what the program writes out)
# --------------------------------------------------------------------------


def _bilateral(x, *, sigma_color: float = 0.05, sigma_spatial: float = 1.5):
    """scikit-image's ``denoise_bilateral`` on the linear render (each pixel a mean of its neighbours weighted by
    distance and by likeness of colour)."""
    from skimage.restoration import denoise_bilateral

    x = np.maximum(np.asarray(x, np.float64), 0.0)
    return denoise_bilateral(x, sigma_color=sigma_color, sigma_spatial=sigma_spatial, channel_axis=-1,
                             mode="edge")


#: The usual sepia matrix (rows: the output's R, G, B from the input's R, G, B).
_SEPIA = np.array([[0.393, 0.769, 0.189], [0.349, 0.686, 0.168], [0.272, 0.534, 0.131]])


def _sepia(x):
    return np.asarray(x, np.float64) @ _SEPIA.T


def _contrast(x, *, c: float = 1.2):
    """A contrast slider about 0.5: ``c (x - 0.5) + 0.5``, clipped at 0 (not at 1: the file is an EXR)."""
    return np.maximum(c * (np.asarray(x, np.float64) - 0.5) + 0.5, 0.0)


def _border_cropped(x):
    """A border of max(1, w // 32) pixels cropped on every side, the rest resized back to w x h (scikit-image,
    bilinear, no anti-aliasing): a view about 6 % narrower."""
    from skimage.transform import resize

    h, w = x.shape[:2]
    b = max(1, w // 32)
    return resize(np.asarray(x, np.float64)[b:h - b, b:w - b], (h, w, 3), order=1, mode="edge", anti_aliasing=False)


# --------------------------------------------------------------------------
# Renderer mistakes realised with Mitsuba (the render's shape in, the image out)
# --------------------------------------------------------------------------


def _eye_mirror_light(w: int, h: int, spp: int, seed: int, *, scene_edit=None) -> np.ndarray:
    """The light seen in the mirror (the paths eye, sphere, light): with every diffuse surface black, a max-depth-2
    render minus its same-seed max-depth-1 render."""
    return (_render(w, h, spp, seed, max_depth=2, scene_edit=scene_edit, dict_edit=untold._black_diffuse)
            - _render(w, h, spp, seed, max_depth=1, scene_edit=scene_edit, dict_edit=untold._black_diffuse))


def _ray_height_from_column(x, *, spp: int, seed: int):
    """The ray's height from the pixel's column: pixel (i, j) traces pixel (i, i)'s rays. Row j of column i is
    pixel (i, i) of an independent render (a seed a row), so each pixel keeps noise of its own."""
    h, w = x.shape[:2]
    out = np.empty((h, w, 3))
    d = np.arange(min(w, h))
    for j in range(h):
        r = _render(w, h, spp, seed + j)
        out[j, :len(d)] = r[d, d]
    return out


def _strata_weights(n: int) -> np.ndarray:
    """(2n - 1,): the share of a pixel's samples in each of the cells n times finer from its top-left cell on, when
    stratum s's offset is ``s / n + u`` (u uniform in [0, 1), a whole pixel, not a stratum)."""
    w = np.zeros(2 * n - 1)
    for s in range(n):
        w[s:s + n] += 1.0 / (n * n)
    return w


def _strata_undivided(x, *, n: int, spp: int, seed: int):
    """Stratified offsets ``s / n + u`` in both directions: each pixel the cells of a render ``n`` times finer (spp a
    cell) from its top-left cell to 2n - 2 cells on, weighted by :func:`_strata_weights` in x and y (the samples past
    the image's last row and column read its last cells)."""
    h, w = x.shape[:2]
    cells = _render(n * w, n * h, spp, seed)
    pad = np.pad(cells, ((0, n - 1), (0, n - 1), (0, 0)), mode="edge")
    wt = _strata_weights(n)
    out = np.zeros((h, w, 3))
    for a in range(2 * n - 1):
        for b in range(2 * n - 1):
            out += wt[a] * wt[b] * pad[a:a + n * h:n, b:b + n * w:n]
    return out


def _light_changed_for_samples(x, *, spp: int, seed: int, scene_edit=None, dict_edit=None):
    """The light seen directly and in the mirror as the scene has it, its light on surfaces from the light that
    ``scene_edit`` and ``dict_edit`` make: same-seed renders, the scene's max-depth-1 and eye-mirror-light paths plus
    the edited scene's full render minus its own. (The mirror's caustics, which a student's tracer finds by
    emission after the mirror, come from the edited light.)"""
    h, w = x.shape[:2]
    seen = _render(w, h, spp, seed, max_depth=1) + _eye_mirror_light(w, h, spp, seed)
    if dict_edit is None:
        edited = _render(w, h, spp, seed, scene_edit=scene_edit) - _render(w, h, spp, seed, max_depth=1,
                                                                              scene_edit=scene_edit)
        return seen + edited - _eye_mirror_light(w, h, spp, seed, scene_edit=scene_edit)
    edited = _render(w, h, spp, seed, dict_edit=dict_edit) - _render(w, h, spp, seed, max_depth=1,
                                                                       dict_edit=dict_edit)
    mirror = (_render(w, h, spp, seed, max_depth=2, dict_edit=lambda d: untold._black_diffuse(dict_edit(d)))
              - _render(w, h, spp, seed, max_depth=1, dict_edit=lambda d: untold._black_diffuse(dict_edit(d))))
    return seen + edited - mirror


def _light_at_centre(s, *, side: float = 0.2):
    """The light as a square of ``side`` about its centre, of the same power (radiance times 4 / side^2): every
    sample near the centre, standing in for the point the student's samples all hit."""
    lt = s.light
    k = lt.area / (side * side)
    return replace(s, light=replace(lt, size=(side, side), radiance=tuple(k * r for r in lt.radiance)))


def _light_direct_scaled(x, *, f: float, spp: int, seed: int):
    """The light on surfaces times ``f`` (a light sample's pdf off by 1/f), the light seen directly and in the
    mirror right: same-seed renders, the seen part plus f times the rest."""
    h, w = x.shape[:2]
    seen = _render(w, h, spp, seed, max_depth=1) + _eye_mirror_light(w, h, spp, seed)
    return seen + f * (_render(w, h, spp, seed) - seen)


def _sphere_hit(w: int, h: int, k: int) -> np.ndarray:
    """(k h, k w) bool: whether the centre ray of each cell of a render ``k`` times finer meets the sphere (nothing
    lies in front of it)."""
    from mcrt.mitsuba_scene import sensor_rays
    from mcrt.scene import load_scene

    s = load_scene()
    sph = next(o for o in s.objects if o.name == "sphere")
    jj, ii = np.mgrid[0:k * h, 0:k * w]
    o, d = sensor_rays(s, "near", k * w, k * h, ii, jj, 0.5, 0.5)
    oc = o - np.asarray(sph.center)
    b = np.einsum("ij,ij->i", oc, d)
    disc = b * b - np.einsum("ij,ij->i", oc, oc) + sph.radius ** 2
    return (disc > 0).reshape(k * h, k * w)


def _no_light_after_mirror(x, *, spp: int, seed: int, k: int = 4):
    """No light sampled at the diffuse surfaces seen in the mirror: the plain render minus the paths eye, sphere,
    surface, light. In cells of a render ``k`` times finer whose camera ray meets the sphere, the three-segment paths
    (a max-depth-3 render minus its same-seed max-depth-2 one) are exactly those. (Deeper vertices after a mirror
    bounce, which the mistake also leaves unlit, keep their light.)"""
    h, w = x.shape[:2]
    cseed = seed + 1
    three = _render(k * w, k * h, spp, cseed, max_depth=3) - _render(k * w, k * h, spp, cseed, max_depth=2)
    lost = (three * _sphere_hit(w, h, k)[..., None]).reshape(h, k, w, k, 3).mean(axis=(1, 3))
    return _render(w, h, k * k * spp, seed) - lost


def _first_hit_rays_summed(x, *, rays: int, spp: int, seed: int):
    """``rays`` rays traced from the first hit and their radiance summed (not averaged); the light seen and the direct
    light at the first hit counted once. Same-seed renders: the paths of at most two segments, plus (rays - 1) times
    the light seen in the mirror (a mirror's rays all alike), plus ``rays`` times the paths of three or more."""
    h, w = x.shape[:2]
    full, two = _render(w, h, spp, seed), _render(w, h, spp, seed, max_depth=2)
    return two + (rays - 1) * _eye_mirror_light(w, h, spp, seed) + rays * (full - two)


def _roulette_over_kill(x, *, spp: int, seed: int, survival: float = 0.75, start: int = 5):
    """Russian roulette from segment ``start`` on whose survivors are divided by the probability of stopping: each
    later segment weighs ``survival / (1 - survival)`` (3) in the mean. Paths of each length from same-seed renders
    without roulette (max depth k minus k - 1), weighted so."""
    h, w = x.shape[:2]
    by_depth = np.array([_render(w, h, spp, seed, max_depth=k, dict_edit=unseen._no_roulette) for k in range(1, 9)])
    lengths = np.diff(by_depth, axis=0, prepend=0.0)
    weights = (survival / (1.0 - survival)) ** np.maximum(np.arange(1, 9) - start, 0)
    return np.einsum("k...,k->...", lengths, weights)


def _cosine_pdf_without_pi(x, *, spp: int, seed: int):
    """Each diffuse bounce weighted albedo / pi (the cosine pdf without its 1/pi), the light sample at the last
    diffuse vertex right: pi times a render with every diffuse albedo divided by pi, less (pi - 1) times its paths
    that end without a diffuse vertex before the light (the light seen, directly and in the mirror; same seed).
    (Paths that reach the light by a mirror after a diffuse bounce, which the mistake dims by one more pi, are
    counted with those that end at a diffuse vertex.)"""
    h, w = x.shape[:2]
    dim = partial(blind._diffuse_remapped, factor=1.0 / math.pi)
    seen = _render(w, h, spp, seed, max_depth=1, dict_edit=dim) + _eye_mirror_light(w, h, spp, seed)
    return math.pi * _render(w, h, spp, seed, dict_edit=dim) - (math.pi - 1.0) * seen


def _tile_borders(x, *, spp: int, seed: int, tiles: int = 4):
    """``tiles`` x ``tiles`` tiles each rendered one pixel wider and taller (``range(x0, x0 + t + 1)``): the first
    column and row of every tile after the first also get the samples of the tile before (four tiles' at the
    crossings), all summed and divided by the spp. Four independent renders, added where the tiles overlap."""
    h, w = x.shape[:2]
    r = [_render(w, h, spp, seed + k) for k in range(4)]
    cols = np.zeros(w, bool)
    cols[w // tiles::w // tiles] = True
    rows = np.zeros(h, bool)
    rows[h // tiles::h // tiles] = True
    c, rr = cols[None, :, None], rows[:, None, None]
    return r[0] + c * r[1] + rr * r[2] + (c & rr) * r[3]


def _gaussian_weights(k: int, sigma: float) -> np.ndarray:
    """(k, k): a Gaussian of ``sigma`` pixels about the pixel's centre at the centres of its k x k cells (not
    normalised: 1 at the centre)."""
    t = (np.arange(k) + 0.5) / k - 0.5
    g = np.exp(-t ** 2 / (2.0 * sigma ** 2))
    return np.outer(g, g)


def _filter_unnormalised(x, *, sigma: float, k: int, spp: int, seed: int):
    """Each sample weighted by a Gaussian of its offset from the pixel's centre, the weighted sum divided by the spp
    (not by the weights' sum): the cells of a render ``k`` times finer times their weight, averaged."""
    h, w = x.shape[:2]
    return np.einsum("ykxlc,kl->yxc", untried._cells(w, h, k, spp, seed), _gaussian_weights(k, sigma)) / (k * k)


def _scaled(x, f: float):
    return np.asarray(x, np.float64) * f


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------

#: Debug colours, one a face of the tetrahedron (red, green, blue, yellow at 0.9).
_DEBUG_COLOURS = ((0.9, 0.1, 0.1), (0.1, 0.9, 0.1), (0.1, 0.1, 0.9), (0.9, 0.9, 0.1))


def _diffuse(rho) -> dict:
    return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(rho)}}}


def _tetra_debug_colours(d: dict) -> dict:
    """Each face of the tetrahedron its own debug colour (:data:`_DEBUG_COLOURS`), a mesh a face."""
    tris = np.asarray(fresh._surface("tetrahedron").triangles)
    d = {k: v for k, v in d.items() if k != "tetrahedron"}
    for n, (tri, rho) in enumerate(zip(tris, _DEBUG_COLOURS)):
        d = fresh._rebuilt(d, f"tetrahedron_face{n}", tri[None], _diffuse(rho))
    return d


def _materials_swapped(s):
    """The sphere given the tetrahedron's material and the tetrahedron the sphere's (indices exchanged)."""
    mats = {o.name: o.material for o in s.objects}
    other = {"sphere": "tetrahedron", "tetrahedron": "sphere"}
    return replace(s, objects=tuple(replace(o, material=mats[other[o.name]]) if o.name in other else o
                                    for o in s.objects))


def _ceiling_black(s):
    return replace(s, room=replace(s.room, ceiling_albedo=(0.0, 0.0, 0.0)))


def _complement(v) -> tuple[float, ...]:
    return tuple(float(1.0 - a) for a in v)


def _albedos_complemented(s):
    """Every Lambertian's albedo 1 - albedo (the colours read as absorptions)."""
    from mcrt.scene import Lambertian

    room = replace(s.room, floor_albedo=_complement(s.room.floor_albedo),
                   ceiling_albedo=_complement(s.room.ceiling_albedo),
                   walls=tuple(replace(w, albedo=_complement(w.albedo)) for w in s.room.walls))
    objs = tuple(replace(o, material=replace(o.material, albedo=_complement(o.material.albedo)))
                 if isinstance(o.material, Lambertian) else o for o in s.objects)
    return replace(s, room=room, objects=objs)


def _parallelograms(tris: np.ndarray) -> np.ndarray:
    """(2n, 3, 3): each triangle (p0, p1, p2) as the parallelogram p0 + u (p1 - p0) + v (p2 - p0), u, v in [0, 1]
    (what ``u <= 1 and v <= 1`` accepts), two triangles wound as the first."""
    p0, p1, p2 = tris[:, 0], tris[:, 1], tris[:, 2]
    q = p1 + p2 - p0
    return np.concatenate([np.stack([p0, p1, q], axis=1), np.stack([p0, q, p2], axis=1)])


def _tetra_parallelograms(d: dict) -> dict:
    """The tetrahedron's faces as the parallelograms its barycentric test accepts. (The room's triangles grow only
    outside the room; the light and the sphere are not tested as triangles in such a tracer.)"""
    from mcrt.mitsuba_scene import _bsdf_dict

    sf = fresh._surface("tetrahedron")
    return fresh._rebuilt(d, "tetrahedron", _parallelograms(np.asarray(sf.triangles, np.float64)),
                          _bsdf_dict(sf.material))


def _floor_at_ceiling(d: dict) -> dict:
    """The floor's triangles at the ceiling's height (the line that sets z copied from the ceiling's), coplanar with
    the ceiling: below the room nothing."""
    from mcrt.mitsuba_scene import _bsdf_dict
    from mcrt.scene import load_scene

    sf = fresh._surface("floor")
    tris = np.array(sf.triangles, np.float64)
    tris[..., 2] = load_scene().room.ceiling_z
    return fresh._rebuilt(d, "floor", tris, _bsdf_dict(sf.material))


def _walls_first_triangle(d: dict) -> dict:
    """Each wall's quad with its first triangle only (the second never appended)."""
    from mcrt.mitsuba_scene import _bsdf_dict
    from mcrt.scene import load_scene

    for sf in load_scene().surfaces():
        if sf.name.startswith("wall_"):
            d = fresh._rebuilt(d, sf.name, np.asarray(sf.triangles)[:1], _bsdf_dict(sf.material))
    return d


def _fov_of_lens(focal_mm: float = 50.0, film_mm: float = 36.0) -> float:
    return math.degrees(2.0 * math.atan(film_mm / (2.0 * focal_mm)))


def _light_diamond(d: dict) -> dict:
    """The light's corners at its centre plus or minus its half-size along x, then along y (the edges' midpoints): a
    square turned 45 degrees, of half the area, same radiance, black, facing down."""
    from mcrt.mitsuba_scene import _light_surface, _mesh
    from mcrt.scene import Surface, load_scene

    lt = load_scene().light
    c = np.asarray(lt.center, np.float64)
    hx, hy = lt.size[0] / 2.0, lt.size[1] / 2.0
    p = [c + (hx, 0, 0), c + (0, hy, 0), c - (hx, 0, 0), c - (0, hy, 0)]
    tris = np.array([[p[0], p[1], p[2]], [p[0], p[2], p[3]]])
    black = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0] * 3}}
    emitter = {"type": "area", "radiance": {"type": "rgb", "value": [float(r) for r in lt.radiance]}}
    return dict(d, light=_mesh(_light_surface(Surface("light", tris, None), lt.normal), black, emitter))


# --------------------------------------------------------------------------
# Files as students' programs write them (the program's buffer in, file out)
# --------------------------------------------------------------------------


def _write_exr_red_everywhere(image: np.ndarray, folder: Path) -> Path:
    """A float EXR whose R, G and B all hold the red plane (``image[..., 0]`` where ``image[..., i]`` belongs)."""
    path = folder / "render.exr"
    fresh._exr_file(path, {c: np.ascontiguousarray(image[..., 0], np.float32) for c in "RGB"})
    return path


def _ppm_header(w: int, h: int, newline: bytes = b"\n") -> bytes:
    return b"P6" + newline + f"{w} {h}".encode() + newline + b"255" + newline


def _write_ppm_rgba(image: np.ndarray, folder: Path) -> Path:
    """A binary PPM (P6, maxval 255) whose data is the program's RGBA buffer (sRGB codes, alpha 255): 4 bytes a
    pixel under a header that says 3."""
    h, w = image.shape[:2]
    rgba = np.concatenate([blind._srgb8(image), np.full((h, w, 1), 255, np.uint8)], axis=2)
    path = folder / "render.ppm"
    path.write_bytes(_ppm_header(w, h) + rgba.tobytes())
    return path


def _gamma_inverted(image: np.ndarray) -> np.ndarray:
    """8-bit codes of ``v ** 2.2`` (the gamma applied the wrong way)."""
    return np.floor(np.clip(np.nan_to_num(image), 0.0, 1.0) ** 2.2 * 255.0 + 0.5).astype(np.uint8)


def _write_png_gamma_inverted(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_gamma_inverted(image), folder)


def _text_mode(data: bytes) -> bytes:
    """What a text-mode stream on Windows writes: every LF byte as CR LF."""
    return data.replace(b"\n", b"\r\n")


def _write_ppm_text_mode(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB binary PPM written through a text-mode stream: every byte 10 (in the header and among the
    codes) written as 13, 10."""
    h, w = image.shape[:2]
    path = folder / "render.ppm"
    path.write_bytes(_text_mode(_ppm_header(w, h) + blind._srgb8(image).tobytes()))
    return path


def _write_png_text_chunks(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB PNG (Pillow) with tEXt chunks (Software, Comment) and a pHYs chunk (72 dpi)."""
    from PIL import Image
    from PIL.PngImagePlugin import PngInfo

    info = PngInfo()
    info.add_text("Software", "hexroom tracer 0.3")
    info.add_text("Comment", "linear radiance, sRGB-encoded")
    path = folder / "render.png"
    Image.fromarray(blind._srgb8(image), "RGB").save(path, format="PNG", pnginfo=info, dpi=(72, 72))
    return path


def _write_exr_uncompressed(image: np.ndarray, folder: Path) -> Path:
    """A float EXR (R, G, B) without compression, with a string attribute of the student's in its header."""
    import OpenEXR

    path = folder / "render.exr"
    header = {"compression": OpenEXR.NO_COMPRESSION, "type": OpenEXR.scanlineimage, "student": "hexroom tracer"}
    OpenEXR.File(header, {c: np.ascontiguousarray(image[..., i], np.float32) for i, c in enumerate("RGB")}
                 ).write(str(path))
    return path


def _bmp_top_down(codes: np.ndarray) -> bytes:
    """A 24-bit BMP (BITMAPINFOHEADER) of ``codes`` (H, W, 3) with a negative height: rows stored top first, as the
    header declares; BGR, rows padded to 4 bytes."""
    import struct

    h, w = codes.shape[:2]
    row = w * 3
    pad = (-row) % 4
    rows = b"".join(codes[j, :, ::-1].tobytes() + b"\0" * pad for j in range(h))
    info = struct.pack("<IiiHHIIiiII", 40, w, -h, 1, 24, 0, len(rows), 2835, 2835, 0, 0)
    head = struct.pack("<2sIHHI", b"BM", 14 + 40 + len(rows), 0, 0, 14 + 40)
    return head + info + rows


def _write_bmp_top_down(image: np.ndarray, folder: Path) -> Path:
    path = folder / "render.bmp"
    path.write_bytes(_bmp_top_down(blind._srgb8(image)))
    return path


# --------------------------------------------------------------------------
# Correct renders made in other ways
# --------------------------------------------------------------------------


def _mapped(s, point, vector=lambda v: v, length: float = 1.0):
    """The scene and its cameras moved by a similarity: every point through ``point``, every direction through
    ``vector`` (a rotation about z), every length times ``length``."""
    room = replace(s.room, floor_z=point((0.0, 0.0, s.room.floor_z))[2],
                   ceiling_z=point((0.0, 0.0, s.room.ceiling_z))[2],
                   corners={k: point((x, y, 0.0))[:2] for k, (x, y) in s.room.corners.items()})
    objs = tuple(replace(o, center=point(o.center), radius=length * o.radius) if hasattr(o, "center")
                 else replace(o, vertices=tuple(point(v) for v in o.vertices)) for o in s.objects)
    size = tuple(abs(a) for a in vector((s.light.size[0], s.light.size[1], 0.0))[:2])
    lt = replace(s.light, center=point(s.light.center), size=tuple(length * a for a in size))
    cams = {k: replace(c, eye=point(c.eye), forward=vector(c.forward), up=vector(c.up)) for k, c in s.cameras.items()}
    return replace(s, room=room, objects=objs, light=lt, cameras=cams)


def _turn(p, *, move=(0.0, 0.0, 0.0)) -> tuple[float, ...]:
    """Point or vector ``p`` turned 90 degrees about z ((x, y, z) -> (-y, x, z)) and moved by ``move``."""
    x, y, z = p
    return (float(-y + move[0]), float(x + move[1]), float(z + move[2]))


def _times(p, *, f: float) -> tuple[float, ...]:
    return tuple(float(f * a) for a in p)


def _world_turned(s, *, move=(2.0, -3.0, 1.0)):
    """The scene and its cameras turned 90 degrees about the vertical and moved by ``move`` (a student's own frame):
    the same image. The light's square, turned a quarter, is the same square."""
    return _mapped(s, partial(_turn, move=move), _turn)


def _in_decimetres(s, *, f: float = 10.0):
    """Every length of the scene times ``f`` (the scene typed in decimetres), the cameras' eyes too: the same
    image."""
    return _mapped(s, partial(_times, f=f), length=f)


def _hidden_plus_seen(x, *, spp: int, seed: int):
    """Mitsuba path with the emitters hidden from the camera, plus a max-depth-1 render (the light seen alone)."""
    h, w = x.shape[:2]

    def hide(d):
        return dict(d, integrator=dict(d["integrator"], hide_emitters=True))

    return _render(w, h, spp, seed, dict_edit=hide) + _render(w, h, spp, seed + 1, max_depth=1)


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_bilateral", "pp_sepia", "pp_contrast_slider", "pp_border_cropped"),
    "file": ("file_exr_red_everywhere", "file_ppm_rgba_buffer", "file_png_gamma_inverted", "file_ppm_text_mode"),
    "materials": ("tetra_debug_colours", "sphere_tetra_materials_swapped", "ceiling_unassigned",
                  "albedos_as_absorption"),
    "geometry": ("tetra_parallelogram_faces", "floor_at_ceiling_height", "wall_quads_half"),
    "camera": ("fov_50mm_lens", "ray_height_from_column", "strata_offsets_undivided"),
    "light": ("light_samples_at_centre", "light_diamond", "light_triangle_choice_unweighted"),
    "integrator": ("no_light_after_mirror", "first_hit_rays_summed", "roulette_over_kill_probability",
                   "cosine_pdf_without_pi"),
    "samples": ("tiles_overlapping", "filter_weights_unnormalised", "strata_divided_by_n"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_bilateral", "blur", **_posted("bilateral", _bilateral),
             truth="skimage.restoration.denoise_bilateral (sigma_color 0.05, sigma_spatial 1.5) on the linear render "
             "to remove the noise, as EXR"),
        Spec("pp_sepia", "colour_grade", True, held_out=True, **_posted("sepia", _sepia),
             truth="a sepia tone for the look (the usual 3 x 3 sepia matrix on the linear colours), as EXR"),
        Spec("pp_contrast_slider", "tone_map", True, **_posted("contrast_1.2", _contrast),
             truth="a contrast slider: 1.2 (x - 0.5) + 0.5, clipped at 0 (dark values darker, bright brighter), as "
             "EXR"),
        Spec("pp_border_cropped", "resolution_crop", True, held_out=True, **_posted("border_cropped", _border_cropped),
             truth="a border of 2 pixels cropped on every side (to hide edge artefacts), the 60 x 60 middle resized "
             "back to 64 x 64 (bilinear), as EXR"),
        # Writing the file
        Spec("file_exr_red_everywhere", "colour_lost", True, writer=_write_exr_red_everywhere, file="exr-red-plane",
             truth="a float EXR whose R, G and B all hold the red plane (the channel loop's index unused)"),
        Spec("file_ppm_rgba_buffer", "row_stride", True, held_out=True, writer=_write_ppm_rgba, file="ppm-rgba",
             truth="the program's RGBA buffer (4 bytes a pixel) written under a binary PPM's RGB header: pixels and "
             "channels slip, the last quarter of the buffer unread"),
        Spec("file_png_gamma_inverted", "encoding", writer=_write_png_gamma_inverted, file="png-power-2.2",
             truth="an 8-bit PNG of v ** 2.2 (the gamma applied the wrong way): much too dark"),
        Spec("file_ppm_text_mode", "file_format", True, held_out=True, writer=_write_ppm_text_mode,
             file="ppm-text-mode",
             truth="a binary PPM written through a text-mode stream: every byte 10 written as 13, 10 (the header's "
             "too), the samples after each one slipped"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("tetra_debug_colours", "albedo", True, mitsuba_edit=_tetra_debug_colours,
             truth="debug colours left on the tetrahedron's faces: red, green, blue and yellow (0.9)"),
        Spec("sphere_tetra_materials_swapped", "material", True, held_out=True, edit=_materials_swapped,
             truth="the sphere's and the tetrahedron's materials swapped: an orange Lambertian sphere, a mirror "
             "tetrahedron"),
        Spec("ceiling_unassigned", "albedo", True, edit=_ceiling_black,
             truth="the ceiling's material never assigned: a zero-initialised default, black"),
        Spec("albedos_as_absorption", "albedo", True, held_out=True, edit=_albedos_complemented,
             truth="every albedo taken as 1 - albedo (the colours read as absorptions): red wall cyan, floor 0.4, "
             "ceiling 0.2"),
        # Geometry
        Spec("tetra_parallelogram_faces", "object_shape", True, mitsuba_edit=_tetra_parallelograms,
             truth="the triangle test's u + v <= 1 written u <= 1 and v <= 1: each tetrahedron face a parallelogram"),
        Spec("floor_at_ceiling_height", "object_missing", True, held_out=True, mitsuba_edit=_floor_at_ceiling,
             truth="the floor's fan built at the ceiling's height (a copied line): no floor, a second ceiling"),
        Spec("wall_quads_half", "mesh_face", True, mitsuba_edit=_walls_first_triangle,
             truth="each wall's quad given its first triangle only: half of every wall missing, the void behind"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera model
        Spec("fov_50mm_lens", "camera_fov", True, edit=cases.fov(_fov_of_lens()),
             truth="the field of view of a 50 mm lens on 36 mm film, 39.6 degrees, for 90"),
        Spec("ray_height_from_column", "camera_model", True, held_out=True, **_posted("height_from_column", partial(
            _ray_height_from_column, spp=256, seed=c("ray_height_from_column"))),
             truth="the ray's height computed from the pixel's column (i for j): every column the colour of its "
             "diagonal pixel"),
        Spec("strata_offsets_undivided", "pixel_footprint", **_posted("strata_undivided", partial(
            _strata_undivided, n=4, spp=16, seed=c("strata_offsets_undivided"))),
             truth="4 x 4 stratified offsets s / 4 + u (u not divided by 4): each pixel's samples over 1.75 pixels, "
             "shifted 3/8 pixel right and down"),
        # Light model
        Spec("light_samples_at_centre", "light_pdf", True, **_posted("light_centre", partial(
            _light_changed_for_samples, spp=256, seed=c("light_samples_at_centre"), scene_edit=_light_at_centre)),
             truth="every light sample at the light's centre (its random numbers a constant 0.5): hard shadows, "
             "the light seen right"),
        Spec("light_diamond", "light_shape", True, held_out=True, mitsuba_edit=_light_diamond,
             truth="the light's corners at its centre plus or minus 1 along x, then along y: a diamond of half the "
             "area"),
        Spec("light_triangle_choice_unweighted", "light_pdf", True, **_posted("light_triangle_pdf", partial(
            _light_direct_scaled, f=2.0, spp=256, seed=c("light_triangle_choice_unweighted"))),
             truth="one of the light's two triangles picked for each sample, pdf 1 / (its area), the 1/2 of the "
             "pick left out: light on surfaces twice the truth, the light seen right"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples and passes."""
    c = _crc
    return (
        # Integrator
        Spec("no_light_after_mirror", "direct_missing", True, **_posted("no_light_after_mirror", partial(
            _no_light_after_mirror, spp=16, seed=c("no_light_after_mirror"))),
             truth="no light sampled at the diffuse vertex after a mirror bounce (the specular flag read a bounce "
             "late): the room seen in the sphere lit only indirectly"),
        Spec("first_hit_rays_summed", "indirect_scale", True, held_out=True, **_posted("rays_summed", partial(
            _first_hit_rays_summed, rays=4, spp=256, seed=c("first_hit_rays_summed"))),
             truth="4 rays traced from the first hit and their radiance summed, not averaged: indirect light and "
             "everything in the mirror 4 times"),
        Spec("roulette_over_kill_probability", "roulette", True, **_posted("roulette_over_kill", partial(
            _roulette_over_kill, spp=128, seed=c("roulette_over_kill_probability"))),
             truth="Russian roulette from the 5th segment, survival 0.75, survivors divided by 0.25 (the stopping "
             "probability): each later segment weighs 3"),
        Spec("cosine_pdf_without_pi", "indirect_scale", True, held_out=True, **_posted("cosine_pdf_no_pi", partial(
            _cosine_pdf_without_pi, spp=256, seed=c("cosine_pdf_without_pi"))),
             truth="the cosine-weighted pdf written cos without 1/pi: each diffuse bounce weighs albedo / pi, the "
             "direct light right, the indirect much too dark"),
        # Samples and passes
        Spec("tiles_overlapping", "sample_count", True, **_posted("tiles_overlapping", partial(
            _tile_borders, spp=256, seed=c("tiles_overlapping"))),
             truth="16 x 16 tiles rendered 17 wide and tall: the tiles' first rows and columns twice as bright "
             "(4 times at crossings), a grid of lines"),
        Spec("filter_weights_unnormalised", "light_radiance", True, held_out=True, **_posted("filter_unnormalised",
             partial(_filter_unnormalised, sigma=0.5, k=8, spp=4, seed=c("filter_weights_unnormalised"))),
             truth="each sample weighted by a Gaussian (sigma 0.5 pixel) of its offset, the sum divided by the spp: "
             "26 % dark"),
        Spec("strata_divided_by_n", "light_radiance", True, **_posted("times_16", partial(_scaled, f=16.0)),
             truth="16 x 16 strata summed and divided by 16, not 256: 16 times too bright"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_world_turned", None, spp=256, edit=_world_turned,
             truth="Mitsuba path 256 spp of the scene and cameras turned 90 degrees about z and moved (2, -3, 1), EXR"),
        Spec("ok_mcrt_fixed_roulette", None, held_out=True, spp=128, renderer="mcrt", **_posted(
            "mcrt_fixed_roulette", partial(untold._mcrt, spp=128, seed=c("ok_mcrt_fixed_roulette"),
                                           roulette_survival=0.6, roulette_start=2)),
             truth="mcrt 128 spp, Russian roulette of survival 0.6 from the 2nd vertex (survivors divided), EXR"),
        Spec("ok_mcrt_triangles", None, spp=96, renderer="mcrt", **_posted("mcrt_triangles", partial(
            untold._mcrt, spp=96, seed=c("ok_mcrt_triangles"), intersector="triangles")),
             truth="mcrt 96 spp with the triangle intersector (the room as triangles), EXR"),
        Spec("ok_hidden_plus_seen", None, held_out=True, spp=256, **_posted("hidden_plus_seen", partial(
            _hidden_plus_seen, spp=256, seed=c("ok_hidden_plus_seen"))),
             truth="Mitsuba path 256 spp with the emitters hidden, plus the light seen alone (max depth 1), EXR"),
        Spec("ok_png_text_chunks", None, spp=192, writer=_write_png_text_chunks, file="png-text-phys",
             truth="Mitsuba path 192 spp, an 8-bit sRGB PNG with tEXt and pHYs chunks (Pillow)"),
        Spec("ok_exr_uncompressed", None, held_out=True, spp=224, writer=_write_exr_uncompressed,
             file="exr-uncompressed",
             truth="Mitsuba path 224 spp, an uncompressed float EXR with a string attribute of the student's"),
        Spec("ok_bmp_top_down", None, spp=160, writer=_write_bmp_top_down, file="bmp-top-down",
             truth="Mitsuba path 160 spp, an 8-bit sRGB BMP written by hand, top line first (negative height)"),
        Spec("ok_mcrt_decimetres", None, held_out=True, spp=64, renderer="mcrt", edit=_in_decimetres,
             truth="mcrt 64 spp of the scene in decimetres (every length times 10), EXR"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "blur": "a filter after rendering (a bilateral denoiser)",
    "colour_grade": "a colour grade after rendering (a sepia tone)",
    "tone_map": "a curve on the values after rendering (a contrast slider)",
    "resolution_crop": "the image cropped and resized back (a border cut off): a narrower view",
    "colour_lost": "colour lost in the file (one channel written into all three)",
    "row_stride": "pixels stored at the wrong places (a 4-byte RGBA buffer under a 3-byte RGB header)",
    "encoding": "the values' encoding (the gamma applied the wrong way)",
    "file_format": "the file's bytes not what its format says (a binary file written in text mode)",
    "albedo": "a surface's colour (debug colours left, a material never assigned, albedos read as absorptions)",
    "material": "a surface rendered with another material (two objects' materials swapped)",
    "object_shape": "an object's shape wrong (triangles tested as parallelograms)",
    "object_missing": "an object missing (the floor built at the ceiling's height)",
    "mesh_face": "faces of a mesh missing (half of each wall's quad)",
    "camera_fov": "the camera's field of view (a lens's focal length for the angle)",
    "camera_model": "each pixel's ray wrong (its height taken from its column)",
    "pixel_footprint": "each pixel's samples not spread over its square (strata offsets not divided)",
    "light_pdf": "the light sampled wrongly (at its centre only; a triangle's pick probability left out): the light "
                 "seen right, its light on surfaces not",
    "light_shape": "the light's shape (a diamond for the square)",
    "direct_missing": "direct light missing at some surfaces (those seen in the mirror: no light sample after a "
                      "mirror bounce)",
    "roulette": "Russian roulette done wrongly (survivors divided by the probability of stopping)",
    "sample_count": "some pixels' sums divided by the spp, not by the samples they got (overlapping tiles)",
    "light_radiance": "the light's radiance (or a constant factor: filter weights or strata not divided out)",
}
_WORDS = {**cases.CAUSES, **outside.CAUSES, **programs.NEW_CAUSES, **fresh.NEW_CAUSES, **blind.NEW_CAUSES,
          **unseen.NEW_CAUSES, **untried.NEW_CAUSES, **novel.NEW_CAUSES, **untold.NEW_CAUSES, **unmet.NEW_CAUSES,
          **NEW_CAUSES, **_REWORDED}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = {c: _WORDS[c] for c in dict.fromkeys(s.cause for s in MISTAKES)}


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
