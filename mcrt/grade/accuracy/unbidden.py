r"""An eighteenth class of hand-ins: mistakes of students' tracers, scene input and output no class tried, blind.

How it was written: from what goes wrong in students' programs (the filters
run after rendering, the conversions and writers that save the image, the
scene's colour table and geometry as a loader builds them, the camera's
matrix, image plane and sub-pixel offsets, the light's position, shape and
samples, the integrator's bounce and mirror, the loops and buffers that add
up the samples and place the tiles), not from the grader. Its author read the
other classes' specs and cause words, the catalogue (:mod:`mcrt.mutants`),
the scene files and design notes, mcrt's scene, camera and image code,
:data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to
stay clear of their mistakes; never the grader's rules (what decides a
cause) nor its reports, and graded none of it, not one case. Each cause and
``major`` flag was set from the mistake alone; every mistake is worded by a
cause the other classes already have (:data:`NEW_CAUSES` is empty), so
``SAME_MISTAKE`` needed no new entry. The mistakes differ from those of the
seventeen other classes (:mod:`~mcrt.grade.accuracy.cases`,
:mod:`~mcrt.grade.accuracy.outside`, :mod:`~mcrt.grade.accuracy.programs`,
:mod:`~mcrt.grade.accuracy.fresh`, :mod:`~mcrt.grade.accuracy.blind`,
:mod:`~mcrt.grade.accuracy.unseen`, :mod:`~mcrt.grade.accuracy.untried`,
:mod:`~mcrt.grade.accuracy.novel`, :mod:`~mcrt.grade.accuracy.untold`,
:mod:`~mcrt.grade.accuracy.unmet`, :mod:`~mcrt.grade.accuracy.unheard`,
:mod:`~mcrt.grade.accuracy.unsaid`, :mod:`~mcrt.grade.accuracy.unasked`,
:mod:`~mcrt.grade.accuracy.unsought`, :mod:`~mcrt.grade.accuracy.unguessed`,
:mod:`~mcrt.grade.accuracy.unforeseen`, :mod:`~mcrt.grade.accuracy.unprompted`)
and from the catalogue's bugs:

* **post-processing**: ``scipy.ndimage.gaussian_filter(img, 1)`` with the
  channel axis filtered too; the scikit-image documentation's contrast
  stretch (``rescale_intensity`` between the 2nd and 98th percentiles);
  every value over 10 set to 0 against fireflies; a 2 x 2 box
  (``uniform_filter``, an even size);
* **writing the file**: the film's albedo AOV written for the beauty; the
  sRGB curve's two pieces swapped in ``np.where``; the XYZ-to-RGB matrix
  applied to an RGB render; the values times 683 lm/W (photometric units);
* **materials**: every albedo gamma-encoded (``a ** (1 / 2.2)``) by the
  loader; the colour table read one number late; the walls' colours read as
  their emission (a struct's fields in the other order);
* **geometry**: each wall's quad triangulated from its corners in Z order
  (a quarter missing); the room's corners read (y, x); the sphere's height
  typed positive;
* **camera**: the camera's translation applied before its rotation (the eye
  moved by it); ``i / W + u`` for ``(i + u) / W``; the image plane's full
  width taken for its half;
* **light model**: the light's height taken as its distance below the
  ceiling; its samples drawn from a normal distribution about its centre,
  with the square's pdf; its quad built from three corners;
* **integrator**: the diffuse bounce's ray keeping the camera ray's t_max;
  GLSL's ``reflect`` called with its arguments swapped at the mirror; the
  bounce's direction the light sample's; no light sample on the tetrahedron;
* **samples and passes**: each tile's pixels normalised by the tile's size
  (the whole view in every tile); the median of each pixel's samples; a
  row's sums carried into the next row; the sample loop left at a black
  sample.

The correct hand-ins come in ways no class used: Mitsuba with sub-pixel
offsets from a Latin hypercube in each pixel, Mitsuba with the camera given
as a 35 mm focal length, a two-part EXR (the beauty first), an 8-bit PNG
written by hand with the Average filter on every row, mcrt with the
tetrahedron's vertices listed in another order, Mitsuba of the scene in a
y-up frame, a float EXR with HTJ2K compression, and an 8-bit PNG written by
Mitsuba's ``mi.Bitmap``.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s
``edit`` and ``mitsuba_edit``), Mitsuba renders combined where light
transport or pixel integrals are linear in what is combined (the light's
samples apart from the light seen, tiles, rows), Mitsuba's path integrator
sampling the rays a student's camera, mirror or bounce makes (the helpers of
:mod:`~mcrt.grade.accuracy.unsaid`), or its samples, one by one, added up as
a student's loop adds them (:func:`mcrt.grade.accuracy.unasked._samples`,
:func:`mcrt.grade.accuracy.unsought._film_samples`), or correct renders
post-processed and written with NumPy, SciPy, scikit-image and the standard
library as students' programs do. mcrt renders only a correct hand-in.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over
:data:`CATEGORIES`: the 2nd, 4th, ... of each category and of the correct
hand-ins) are as in :mod:`~mcrt.grade.accuracy.unprompted`, fixed before any
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
                                 unheard, unmet, unprompted, unsaid, unseen, unsought, untold, untried)
from mcrt.grade.accuracy.cases import Spec

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


def _crc(name: str) -> int:
    return 501000 + zlib.crc32(name.encode()) % 100000


_render = unseen._render
_posted = unseen._posted
_scene = unprompted._scene

#: The class's spp (the class is built at 64 x 64).
_S = 256
#: The assignment's maximum depth.
_DEPTH = 8


# --------------------------------------------------------------------------
# Post-processing (linear render in, what the program writes out)
# --------------------------------------------------------------------------


def _gaussian_all_axes(x, *, sigma: float = 1.0):
    """``scipy.ndimage.gaussian_filter(img, sigma)`` on the (H, W, 3) image: the channel axis filtered as well (its
    borders reflected), so each channel takes in the others."""
    from scipy.ndimage import gaussian_filter

    return gaussian_filter(np.asarray(x, np.float64), sigma=sigma)


def _contrast_stretched(x, *, low: float = 2.0, high: float = 98.0):
    """scikit-image's contrast stretching: ``rescale_intensity(img, in_range=(p2, p98))``, the percentiles over every
    value of the image, the result in [0, 1] (clipped)."""
    from skimage import exposure

    x = np.asarray(x, np.float64)
    p_low, p_high = np.percentile(x, (low, high))
    return exposure.rescale_intensity(x, in_range=(p_low, p_high))


def _bright_zeroed(x, *, limit: float = 10.0):
    """``img[img > limit] = 0``: every value over ``limit`` taken for a firefly and set to 0."""
    out = np.array(x, np.float64)
    out[out > limit] = 0.0
    return out


def _box_2x2(x):
    """``scipy.ndimage.uniform_filter(img, size=(2, 2, 1))``: each pixel the mean of itself and its neighbours above,
    to the left and above-left (an even size has no centre), edges reflected."""
    from scipy.ndimage import uniform_filter

    return uniform_filter(np.asarray(x, np.float64), size=(2, 2, 1))


# --------------------------------------------------------------------------
# Values the writer converts (the render in, what goes into the file)
# --------------------------------------------------------------------------


def _albedo_aov(x, *, spp: int, seed: int):
    """The film's albedo AOV: each pixel the mean over ``spp`` jittered pinhole rays of the diffuse reflectance of the
    first surface each meets (0 for the mirror and for the light's black surface)."""
    h, w = x.shape[:2]
    mscene = unsaid._loaded(_DEPTH)
    total = np.zeros((h * w, 3))
    for _, n, fx, fy in unsaid._lanes(w, h, spp, seed):
        o, d = unsaid._pinhole(fx, fy)
        total += unsaid._first_albedo(mscene, np.asarray(o, np.float64), d).reshape(h * w, n, 3).sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _xyz_matrix_on_rgb(x):
    """The XYZ-to-linear-sRGB matrix applied to the RGB render (the film believed to hold CIE XYZ), negatives clipped
    to 0 before saving."""
    from mcrt.image_files import XYZ_TO_RGB

    return np.maximum(np.asarray(x, np.float64) @ XYZ_TO_RGB.T, 0.0)


def _photometric(x, *, efficacy: float = 683.0):
    """Each value times ``efficacy`` lm/W: radiance converted to luminance units (cd/m^2) before the EXR."""
    return np.asarray(x, np.float64) * efficacy


def _srgb_branches_swapped(image: np.ndarray) -> np.ndarray:
    """8-bit codes of the sRGB curve with ``np.where``'s two branches swapped: ``1.055 v^(1/2.4) - 0.055`` at or below
    0.0031308, ``12.92 v`` above (white from 0.0774 on), clipped to [0, 1] and rounded."""
    v = np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, None)
    s = np.where(v <= 0.0031308, 1.055 * np.power(v, 1.0 / 2.4) - 0.055, 12.92 * v)
    return np.floor(np.clip(s, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def _write_png_srgb_branches_swapped(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_srgb_branches_swapped(image), folder)


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _albedos_mapped(s, f):
    """Every Lambertian albedo of the scene passed through ``f`` (a tuple -> tuple), in the scene file's order: the
    floor, the ceiling, the walls, the objects."""
    from mcrt.scene import Lambertian

    floor, ceiling = f(s.room.floor_albedo), f(s.room.ceiling_albedo)
    walls = tuple(replace(w, albedo=f(w.albedo)) for w in s.room.walls)
    room = replace(s.room, walls=walls, floor_albedo=floor, ceiling_albedo=ceiling)
    objects = tuple(replace(o, material=replace(o.material, albedo=f(o.material.albedo)))
                    if isinstance(o.material, Lambertian) else o for o in s.objects)
    return replace(s, room=room, objects=objects)


def _gamma_encoded(a, *, gamma: float = 2.2):
    return tuple(float(c) ** (1.0 / gamma) for c in a)


def _albedos_gamma_encoded(s):
    """Every albedo gamma-encoded by the loader, ``a ** (1 / 2.2)`` (a texture loader's colour step, the wrong way)."""
    return _albedos_mapped(s, _gamma_encoded)


def _colour_table(s) -> list[tuple[float, float, float]]:
    """The Lambertian colours in the scene file's order (:func:`_albedos_mapped`'s)."""
    table: list = []
    _albedos_mapped(s, lambda a: table.append(tuple(a)) or a)
    return table


def _one_number_late(s):
    """The colour table flattened and read one number late (an item count assumed at its start): colour k from
    numbers 3k + 1 to 3k + 3, the last colour's last number read past the table's end as 0 (a zeroed buffer)."""
    flat = np.asarray(_colour_table(s), np.float64).reshape(-1)
    late = iter(tuple(float(c) for c in v) for v in np.append(flat[1:], 0.0).reshape(-1, 3))
    return _albedos_mapped(s, lambda _: next(late))


def _walls_emitting(d: dict) -> dict:
    """The walls' colours read as their emission (a struct's albedo and emission fields filled in the other order):
    each wall black, emitting its colour as radiance from its front (into the room)."""
    from mcrt.mitsuba_scene import _mesh

    for w in _scene().room.walls:
        sf = fresh._surface(f"wall_{w.corners[0]}{w.corners[1]}")
        d = dict(d, **{sf.name: _mesh(sf, dict(unsaid._BLACK), unsaid._emitter(w.albedo))})
    return d


def _z_order_tris(s, wall) -> np.ndarray:
    """(2, 3, 3): a wall's quad from its corners in Z order (bottom a, bottom b, top a, top b) taken as a cycle:
    (a0, b0, a1) and (a0, a1, b1), overlapping by a quarter, the quarter at its b end (b0, b1, the centre) missing."""
    (ax, ay), (bx, by) = s.room.corners[wall.corners[0]], s.room.corners[wall.corners[1]]
    z0, z1 = s.room.floor_z, s.room.ceiling_z
    q = np.array([[ax, ay, z0], [bx, by, z0], [ax, ay, z1], [bx, by, z1]], np.float64)
    return np.array([[q[0], q[1], q[2]], [q[0], q[2], q[3]]])


def _walls_z_order(d: dict) -> dict:
    from mcrt.mitsuba_scene import _bsdf_dict
    from mcrt.scene import Lambertian

    s = _scene()
    for w in s.room.walls:
        name = f"wall_{w.corners[0]}{w.corners[1]}"
        d = fresh._rebuilt(d, name, _z_order_tris(s, w), _bsdf_dict(Lambertian(w.albedo)))
    return d


def _corners_yx(s):
    """The room's corners read (y, x): A (0, -3), B (-6, 0), C (-6, 10), D (0, 13), E (6, 10), F (6, 0). The swap
    mirrors the hexagon, so the walls are listed the other way round (the same walls and colours) for the floor's and
    the ceiling's fans, which a student's two-sided floor and ceiling have either way."""
    corners = {k: (float(v[1]), float(v[0])) for k, v in s.room.corners.items()}
    walls = tuple(replace(w, corners=w.corners[::-1]) for w in reversed(s.room.walls))
    return replace(s, room=replace(s.room, corners=corners, walls=walls))


def _sphere_z_positive(s):
    """The sphere's centre with its z typed positive (3.3 for -3.3): the ball just under the ceiling."""
    return replace(s, objects=tuple(replace(o, center=(o.center[0], o.center[1], abs(o.center[2])))
                                    if o.name == "sphere" else o for o in s.objects))


def _eye_rotated(s):
    """The camera's matrix built as rotation times translation (``R @ T`` for ``T @ R``): the eye, applied in camera
    space, is turned with the frame: eye' = (right, up, forward) @ eye, (0, 1, 0) for (-1, 0, 0)."""
    c = s.cameras["near"]
    m = np.stack(c.frame(), axis=1)
    return cases._camera(s, eye=tuple(float(v) for v in m @ np.asarray(c.eye, np.float64)))


def _fov_full_width(s):
    """The image plane's full width 2 tan(fov / 2) used as its half-width: the field of view 2 atan(2 tan(fov / 2))
    (126.9 degrees for 90)."""
    fov = s.cameras["near"].fov_x_deg
    return cases._camera(s, fov_x_deg=math.degrees(2.0 * math.atan(2.0 * math.tan(math.radians(fov) / 2.0))))


def _light_z_from_ceiling(s):
    """The light's z read as its distance below the ceiling: z = ceiling - 4.99 = 0.01, just above the eye's
    height."""
    cx, cy, cz = s.light.center
    return replace(s, light=replace(s.light, center=(cx, cy, float(s.room.ceiling_z - cz))))


def _light_three_corners(d: dict) -> dict:
    """The light's quad built from its first three corners (a triangle's loop, ``range(3)``, reused): one triangle,
    emitting, half the square."""
    return unsaid._meshes(d, light=(unsaid._light_tris()[:1], _scene().light.radiance))


def _truncated_normal_density(t: np.ndarray, sigma: float) -> np.ndarray:
    """The density on [-1, 1] of a normal number of deviation ``sigma`` redrawn until it falls in [-1, 1]."""
    z = math.erf(1.0 / (sigma * math.sqrt(2.0)))
    return np.exp(-0.5 * (t / sigma) ** 2) / (sigma * math.sqrt(2.0 * math.pi) * z)


def _light_gaussian_texture(*, sigma: float = 0.5, texels: int = 64) -> np.ndarray:
    """(texels, texels, 3): the radiance the light's samples act with when drawn about its centre from a normal of
    deviation ``sigma`` half-sides (redrawn until on the square) and weighted with the square's pdf 1 / A:
    Le A g(p), g their density on the square."""
    lt = _scene().light
    t = (np.arange(texels) + 0.5) / texels * 2.0 - 1.0
    g = np.outer(_truncated_normal_density(t, sigma), _truncated_normal_density(t, sigma)) / (
        lt.size[0] / 2.0 * lt.size[1] / 2.0)
    return (lt.area * g)[..., None] * np.asarray(lt.radiance, np.float64)


def _light_gaussian(d: dict) -> dict:
    """The light as its samples see it: its square (a ``rectangle``), black, emitting the radiance of
    :func:`_light_gaussian_texture` (a bitmap, bilinear)."""
    import mitsuba as mi

    out = unasked._light_rectangle(d)
    tex = {"type": "bitmap", "data": mi.TensorXf(_light_gaussian_texture().astype(np.float32)), "raw": True,
           "filter_type": "bilinear"}
    return dict(out, light=dict(out["light"], emitter={"type": "area", "radiance": tex}))


# --------------------------------------------------------------------------
# The camera's sub-pixel offsets (Mitsuba's samples through them, unsought._film_samples)
# --------------------------------------------------------------------------


def _bracket_misplaced(rng, n: int, *, w: int, pixels: int):
    """``i / W + u`` for ``(i + u) / W``: the offsets in image widths, not pixels (W u and H v in pixel units): each
    pixel's samples over a whole image's width and height from its own corner."""
    u, v = rng.random((2, pixels, n))
    return u * w, v * (pixels // w)


def _latin_hypercube(rng, n: int, *, w: int, pixels: int):
    """Sub-pixel offsets from a Latin hypercube in each pixel: ``n`` strata in x and in y, one sample in each row and
    each column of strata (random permutations), jittered in its cell: every offset uniform on the pixel."""
    px = np.argsort(rng.random((pixels, n)), axis=1)
    py = np.argsort(rng.random((pixels, n)), axis=1)
    u, v = rng.random((2, pixels, n))
    return (px + u) / n, (py + v) / n


# --------------------------------------------------------------------------
# Renderer mistakes realised on rays, sample by sample, or with Mitsuba renders combined
# --------------------------------------------------------------------------


def _sampled_within(mscene, o: np.ndarray, d: np.ndarray, maxt, seed: int) -> np.ndarray:
    """:func:`mcrt.grade.accuracy.unsaid._sampled` of rays whose first segment reaches at most ``maxt`` (N,) (None:
    unbounded): a ray meeting nothing nearer returns 0."""
    import drjit as dr
    import mitsuba as mi

    ray = unsaid._rays(o, d)
    if maxt is not None:
        ray.maxt = mi.Float(np.asarray(maxt, np.float32))
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(dr.opaque(mi.UInt32, seed), len(o))
    L = mscene.integrator().sample(mscene, sampler, mi.RayDifferential3f(ray), None, True)[0]
    return np.stack([np.array(L[c], np.float64) for c in range(3)], axis=1)


def _first_bounce_turned(x, *, spp: int, seed: int, turn):
    """The diffuse bounce at the first surface a camera ray meets made by ``turn`` (rng, points, normals, camera
    distances) -> (directions, reaches or None), weighted by the albedo as a cosine-weighted sample: its light
    sample right (Mitsuba's max-depth-2 sample minus max-depth-1, same seed), the bounce going on from the hit point
    with Mitsuba's path of the 7 segments left less the emission it sees at once. Mirror and light hits, Mitsuba's."""
    h, w = x.shape[:2]
    full, two, one, rest = (unsaid._loaded(k) for k in (_DEPTH, 2, 1, _DEPTH - 1))
    rng = np.random.default_rng(seed + 13)
    total = np.zeros((h * w, 3))
    for cseed, n, fx, fy in unsaid._lanes(w, h, spp, seed):
        o, d = (np.array(a, np.float64) for a in unsaid._pinhole(fx, fy))
        L = unsaid._sampled(full, o, d, cseed)
        rho = unsaid._first_albedo(full, o, d)
        t, valid = unguessed._first_hit(full, o, d)
        sel = valid & (rho.max(axis=1) > 0.0)
        if sel.any():
            nrm = unforeseen._first_normal(full, o[sel], d[sel])
            p = o[sel] + t[sel, None] * d[sel]
            nd, reach = turn(rng, p, nrm, t[sel])
            po, s2 = p + 1e-4 * nrm, cseed + 104729
            cont = _sampled_within(rest, po, nd, reach, s2) - _sampled_within(one, po, nd, reach, s2)
            direct = unsaid._sampled(two, o[sel], d[sel], cseed) - unsaid._sampled(one, o[sel], d[sel], cseed)
            L[sel] = direct + rho[sel] * cont
        total += L.reshape(h * w, n, 3).sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _reach_kept(rng, p, n, t):
    """Cosine-weighted directions, the bounce's ray reaching only as far as the camera ray did (its t_max kept)."""
    return unprompted._cosine_directions(rng, n)[0], t


def _towards_light_sample(rng, p, n, t):
    """The bounce along the light sample's direction (the shadow ray's ``wi`` reused): towards a point drawn
    uniformly on the light's square."""
    lt = _scene().light
    u, v = rng.random((2, len(p)))
    q = np.stack([lt.center[0] + (u - 0.5) * lt.size[0], lt.center[1] + (v - 0.5) * lt.size[1],
                  np.full(len(p), lt.center[2])], axis=1)
    return unsaid._unit(q - p), None


def _reflect_swapped(o, d):
    """Camera rays that meet the sphere turned by ``reflect(n, d) = n - 2 (n . d) d`` (GLSL's ``reflect(I, N)`` given
    its arguments the other way round; a unit vector too), leaving from the hit point: (origins, directions, segments
    used)."""
    c, radius = unsaid._sphere()
    p, _, hit = unsaid._reflected(o, d)
    n = unsaid._unit(p - c)
    r = unsaid._unit(n - 2.0 * np.einsum("ij,ij->i", n, d)[:, None] * d)
    return p, np.where(hit[:, None] == 1, r, d), hit


def _is_tetra(rho: np.ndarray) -> np.ndarray:
    """Whether each first hit's diffuse reflectance (N, 3) is the tetrahedron's (no other surface has its colour)."""
    from mcrt.scene import Lambertian

    tetra = next(o for o in _scene().objects if isinstance(o.material, Lambertian) and o.name == "tetrahedron")
    return np.all(np.abs(rho - np.asarray(tetra.material.albedo)) < 1e-4, axis=1)


def _tetra_unlit(x, *, spp: int, seed: int):
    """No light sample on the tetrahedron (its faces go through another branch of the shading code): a path whose
    camera ray (or that ray after the mirror) meets the tetrahedron first loses that vertex's direct light, Mitsuba's
    max-depth-2 sample minus max-depth-1 from it, same seed; the rest Mitsuba's path on the pinhole's rays (its
    mirror bounce traced here, as :func:`mcrt.grade.accuracy.unsaid._traced` does)."""
    h, w = x.shape[:2]
    scenes = {k: unsaid._loaded(k) for k in (_DEPTH, _DEPTH - 1, 2, 1)}
    total = np.zeros((h * w, 3))
    for cseed, n, fx, fy in unsaid._lanes(w, h, spp, seed):
        o, d = unsaid._pinhole(fx, fy)
        o, d, used = unsaid._reflected(np.asarray(o, np.float64), np.asarray(d, np.float64))
        L = np.zeros((len(o), 3))
        for k in (0, 1):
            sel, s = used == k, cseed + 7919 * k
            if not sel.any():
                continue
            L[sel] = unsaid._sampled(scenes[_DEPTH - k], o[sel], d[sel], s)
            tetra = np.flatnonzero(sel)[_is_tetra(unsaid._first_albedo(scenes[_DEPTH], o[sel], d[sel]))]
            if len(tetra):
                L[tetra] -= (unsaid._sampled(scenes[2], o[tetra], d[tetra], s)
                             - unsaid._sampled(scenes[1], o[tetra], d[tetra], s))
        total += L.reshape(h * w, n, 3).sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _tiles_whole_view(x, *, spp: int, seed: int, tiles: int = 4):
    """Each of the ``tiles`` x ``tiles`` tiles' pixel coordinates normalised by the tile's size, not the image's: every
    tile renders the whole view at its own size (a seed each)."""
    h, w = x.shape[:2]
    th, tw = h // tiles, w // tiles
    out = np.zeros((h, w, 3))
    for r in range(tiles):
        for c in range(tiles):
            out[r * th:(r + 1) * th, c * tw:(c + 1) * tw] = _render(tw, th, spp, seed + r * tiles + c)
    return out


def _all_samples(w: int, h: int, spp: int, seed: int) -> np.ndarray:
    """(W H, spp, 3): Mitsuba's samples of each pixel in the order its loop draws them."""
    return np.concatenate([L for L, _, _ in unasked._samples(w, h, spp, seed)], axis=1)


def _median_of_samples(x, *, spp: int, seed: int):
    """Each pixel the median of its samples, channel by channel (``np.median`` for ``np.mean``)."""
    h, w = x.shape[:2]
    return np.median(_all_samples(w, h, spp, seed), axis=1).reshape(h, w, 3)


def _row_sums_carried(x):
    """The row buffer declared outside the row loop and never cleared: row j holds the sums of rows 0 to j (divided
    by the spp as each row's own)."""
    return np.cumsum(np.asarray(x, np.float64), axis=0)


def _stopped_at_black(x, *, spp: int, seed: int):
    """The pixel's sample loop left (``break``) at its first sample of radiance 0, the sum of the samples before it
    divided by the spp."""
    h, w = x.shape[:2]
    L = _all_samples(w, h, spp, seed)
    black = L.max(axis=2) <= 0.0
    first = np.where(black.any(axis=1), np.argmax(black, axis=1), spp)
    kept = np.arange(spp)[None, :] < first[:, None]
    return ((L * kept[..., None]).sum(axis=1) / spp).reshape(h, w, 3)


# --------------------------------------------------------------------------
# Correct renders made in other ways
# --------------------------------------------------------------------------


def _focal_length(d: dict) -> dict:
    """The camera given as a 35 mm-equivalent focal length (Mitsuba's ``focal_length``, taken along the film's
    43.3 mm diagonal): 15.297 mm for 90 degrees across a square image."""
    half = math.tan(math.radians(_scene().cameras["near"].fov_x_deg) / 2.0)
    mm = math.hypot(36.0, 24.0) / 2.0 / (math.sqrt(2.0) * half)
    sensor = {k: v for k, v in d["sensor"].items() if k not in ("fov", "fov_axis")}
    return dict(d, sensor=dict(sensor, focal_length=f"{mm:.6f}mm"))


def _y_up(p) -> list[float]:
    """A point or vector of the scene in a y-up frame: (x, y, z) -> (x, z, -y), a quarter turn about x."""
    x, y, z = (float(a) for a in p)
    return [x, z, -y]


def _y_up_world(d: dict) -> dict:
    """The scene written in a y-up frame (every mesh, the sphere and the camera turned by :func:`_y_up`): the same
    image."""
    import mitsuba as mi

    from mcrt.mitsuba_scene import _bsdf_dict, _light_surface, _mesh
    from mcrt.scene import Surface

    s = _scene()
    out = dict(d)
    for sf in s.surfaces():
        if sf.material is None:
            sf = _light_surface(sf, s.light.normal)
        tris = np.asarray(sf.triangles, np.float64) @ np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])
        out[sf.name] = _mesh(Surface(sf.name, tris, sf.material), _bsdf_dict(sf.material),
                             None if sf.material is not None else unsaid._emitter(s.light.radiance))
    out["sphere"] = dict(d["sphere"], center=_y_up(d["sphere"]["center"]))
    cam = s.cameras["near"]
    eye = np.asarray(cam.eye, np.float64)
    to_world = mi.ScalarTransform4f().look_at(origin=_y_up(eye), target=_y_up(eye + np.asarray(cam.forward)),
                                             up=_y_up(cam.up))
    return dict(out, sensor=dict(d["sensor"], to_world=to_world))


def _tetra_permuted(s):
    """The tetrahedron's four vertices listed in another order (apex first): the same faces, the same object."""
    return unguessed._tetra_vertices(s, lambda v: (v[3], v[1], v[0], v[2]))


def _write_exr_two_parts(image: np.ndarray, folder: Path) -> Path:
    """A two-part float EXR (ZIP): the beauty (R, G, B) first, its sRGB-encoded preview (R, G, B in [0, 1]) second."""
    import OpenEXR

    from mcrt.srgb import srgb_oetf

    path = folder / "render.exr"
    head = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    preview = srgb_oetf(np.clip(np.nan_to_num(image), 0.0, 1.0))
    parts = [OpenEXR.Part(dict(head), {c: np.ascontiguousarray(a[..., i], np.float32) for i, c in enumerate("RGB")},
                          name=name) for name, a in (("beauty", image), ("preview", preview))]
    OpenEXR.File(parts).write(str(path))
    return path


def _write_exr_htj2k(image: np.ndarray, folder: Path) -> Path:
    """A float EXR (R, G, B) with HTJ2K compression (High-Throughput JPEG 2000, lossless; 256 scanlines a block)."""
    import OpenEXR

    path = folder / "render.exr"
    chans = {c: np.ascontiguousarray(image[..., i], np.float32) for i, c in enumerate("RGB")}
    OpenEXR.File({"compression": OpenEXR.HTJ2K256_COMPRESSION, "type": OpenEXR.scanlineimage}, chans).write(str(path))
    return path


def _average_filtered(codes: np.ndarray) -> bytes:
    """The PNG scanlines of (H, W, 3) 8-bit codes, each with filter type 3 (Average: each byte less the floor of the
    mean of its left and upper bytes)."""
    rows = codes.astype(np.int16).reshape(codes.shape[0], -1)
    out, above = [], np.zeros_like(rows[0])
    for r in rows:
        left = np.concatenate([np.zeros(3, np.int16), r[:-3]])
        out.append(b"\x03" + ((r - (left + above) // 2) % 256).astype(np.uint8).tobytes())
        above = r
    return b"".join(out)


def _write_png_average(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB PNG written by hand: IHDR, one IDAT of the zlib stream of Average-filtered rows, IEND."""
    h, w = image.shape[:2]
    data = (b"\x89PNG\r\n\x1a\n" + unseen._png_chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
            + unseen._png_chunk(b"IDAT", zlib.compress(_average_filtered(blind._srgb8(image)), 9))
            + unseen._png_chunk(b"IEND", b""))
    path = folder / "render.png"
    path.write_bytes(data)
    return path


def _write_png_mitsuba_bitmap(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB PNG written by Mitsuba's ``mi.Bitmap`` (converted to UInt8 with its sRGB curve)."""
    import mitsuba as mi

    path = folder / "render.png"
    bmp = mi.Bitmap(np.ascontiguousarray(np.clip(np.nan_to_num(image), 0.0, None), np.float32))
    bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, True).write(str(path))
    return path


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_gaussian_over_channels", "pp_contrast_stretch_p2_p98", "pp_values_over_10_zeroed",
                        "pp_box_2x2_uniform_filter"),
    "file": ("file_exr_albedo_aov", "file_png_srgb_branches_swapped", "file_exr_xyz_matrix_on_rgb",
             "file_exr_photometric_683"),
    "materials": ("albedos_gamma_encoded", "colour_table_one_number_late", "walls_colour_as_emission"),
    "geometry": ("walls_quads_z_order", "room_corners_read_yx", "sphere_z_typed_positive"),
    "camera": ("camera_translation_before_rotation", "jitter_bracket_misplaced", "plane_full_width_as_half"),
    "light": ("light_z_below_ceiling_as_height", "light_samples_normal_about_centre", "light_quad_three_corners"),
    "integrator": ("bounce_ray_tmax_kept", "mirror_reflect_arguments_swapped", "bounce_along_light_sample",
                   "tetra_not_light_sampled"),
    "samples": ("tiles_normalised_by_tile_size", "pixel_median_of_samples", "row_buffer_not_cleared",
                "sample_loop_breaks_at_black"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    c = _crc
    return (
        # Post-processing
        Spec("pp_gaussian_over_channels", "blur", True, **_posted("gaussian_all_axes", _gaussian_all_axes),
             truth="scipy.ndimage.gaussian_filter(img, sigma=1) on the (H, W, 3) render, as EXR: blurred over "
             "the pixels and over the channel axis too (its ends reflected), each channel mixed with the others: "
             "blurred and the colours washed out"),
        Spec("pp_contrast_stretch_p2_p98", "normalised", True, held_out=True,
             **_posted("contrast_stretched", _contrast_stretched),
             truth="the scikit-image documentation's contrast stretch, exposure.rescale_intensity(img, in_range=(p2, "
             "p98)) with the 2nd and 98th percentiles of all the values, as EXR: the values mapped linearly onto "
             "[0, 1] and clipped, the 98th percentile on the light (18.7): the light 1, the room under a "
             "nineteenth of its values, nearly black"),
        Spec("pp_values_over_10_zeroed", "bad_pixels", **_posted("bright_zeroed", _bright_zeroed),
             truth="a firefly filter after rendering, img[img > 10] = 0, as EXR: every value over 10 set to 0, the "
             "light's pixels black (its reflection in the sphere, under 10 in its pixels, kept), the rest right"),
        Spec("pp_box_2x2_uniform_filter", "blur", held_out=True, **_posted("box_2x2", _box_2x2),
             truth="scipy.ndimage.uniform_filter(img, size=(2, 2, 1)) to smooth the noise, as EXR: each pixel the "
             "mean of a 2 x 2 block, itself and its neighbours above and to the left (an even size has no "
             "centre): blurred and shifted half a pixel down and right"),
        # Writing the file
        Spec("file_exr_albedo_aov", "wrong_buffer", True, **_posted("albedo_aov", partial(
            _albedo_aov, spp=_S, seed=c("file_exr_albedo_aov"))),
             truth="the film's albedo AOV (each pixel the mean diffuse reflectance of the first surface its rays "
             "meet; 0 for the mirror and the light) written to the EXR for the beauty pass (the layer names mixed "
             "up): the surfaces flat in their own colours, no light or shading, the sphere and the light black"),
        Spec("file_png_srgb_branches_swapped", "encoding", True, held_out=True,
             writer=_write_png_srgb_branches_swapped, file="png-srgb-swapped",
             truth="an 8-bit PNG of the sRGB curve written with np.where's branches swapped, 1.055 v^(1/2.4) - "
             "0.055 at or below 0.0031308 and 12.92 v above: every value over 0.0774 white, the darker ones "
             "linear times 12.92"),
        Spec("file_exr_xyz_matrix_on_rgb", "colour_space", True, **_posted("xyz_matrix_on_rgb", _xyz_matrix_on_rgb),
             truth="the CIE XYZ-to-linear-sRGB matrix applied to the RGB render before the EXR (the film believed "
             "to hold XYZ), negatives clipped to 0: the colours converted a second time, every colour pushed "
             "further from grey (the walls oversaturated, the tetrahedron red)"),
        Spec("file_exr_photometric_683", "light_radiance", True, held_out=True,
             **_posted("photometric_683", _photometric),
             truth="the EXR written in photometric units, every value times 683 lm/W (radiance taken to "
             "luminance): 683 times too bright"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("albedos_gamma_encoded", "albedo", True, edit=_albedos_gamma_encoded,
             truth="every albedo gamma-encoded by the scene loader, a ** (1 / 2.2) (a texture loader's colour step "
             "applied the wrong way): the floor 0.79, the ceiling 0.90, the red wall (0.88, 0.42, 0.42), every "
             "surface lighter and greyer, the room much brighter"),
        Spec("colour_table_one_number_late", "albedo", True, held_out=True, edit=_one_number_late,
             truth="the colour table (floor, ceiling, walls AB to FA, tetrahedron) flattened and read one number "
             "late (a count assumed at its start): the floor (0.6, 0.6, 0.8), the ceiling (0.8, 0.8, 0.75), wall "
             "AB (0.15, 0.15, 0.55), BC (0.15, 0.7, 0.75), CD (0.7, 0.15, 0.15), DE (0.2, 0.75, 0.15), EF (0.7, "
             "0.15, 0.15), FA (0.65, 0.7, 0.8), the tetrahedron (0.45, 0.1, 0)"),
        Spec("walls_colour_as_emission", "object_emits", True, mitsuba_edit=_walls_emitting,
             truth="the walls' colours read into their emission and their albedos left 0 (a struct's fields "
             "filled in the other order): the six walls black, glowing with their colours as radiance (0.75, "
             "0.15, 0.15) and so on, reflecting nothing"),
        # Geometry
        Spec("walls_quads_z_order", "mesh_face", True, mitsuba_edit=_walls_z_order,
             truth="each wall's quad triangulated from its corners in Z order (bottom a, bottom b, top a, top b) "
             "taken as a cycle: triangles (a0, b0, a1) and (a0, a1, b1), overlapping, a quarter of every wall "
             "(the triangle from its second corner's bottom and top to its centre) missing onto the void"),
        Spec("room_corners_read_yx", "object_moved", True, held_out=True, edit=_corners_yx,
             truth="the room's corners read (y, x): A (0, -3), B (-6, 0), C (-6, 10), D (0, 13), E (6, 10), F (6, "
             "0): another hexagon, its walls elsewhere, the tetrahedron and the sphere outside it, the light "
             "through wall FA"),
        Spec("sphere_z_typed_positive", "object_moved", True, edit=_sphere_z_positive,
             truth="the sphere's centre typed (9.5, 2.0, 3.3) for (9.5, 2.0, -3.3) (the sign of z lost): the "
             "mirror ball hanging 0.2 under the ceiling"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera
        Spec("camera_translation_before_rotation", "camera_eye", True, edit=_eye_rotated,
             truth="the camera's matrix composed R @ T for T @ R (its translation applied before its rotation): "
             "the eye (-1, 0, 0) turned with the frame to (0, 1, 0), one forward and one to the left, the view's "
             "direction right"),
        Spec("jitter_bracket_misplaced", "pixel_footprint", True, held_out=True,
             **_posted("bracket_misplaced", partial(unforeseen._mean_through, spp=_S,
                                                    seed=c("jitter_bracket_misplaced"), jitter=_bracket_misplaced)),
             truth="the film position i / W + u for (i + u) / W (a bracket misplaced): each pixel's samples spread "
             "over a whole image's width and height from its own corner (past the view's right and bottom "
             "edges): every pixel a mean over a wide window, the image a smooth blur"),
        Spec("plane_full_width_as_half", "camera_fov", True, edit=_fov_full_width,
             truth="the image plane's full width 2 tan(fov / 2) used as its half-width: a field of view of 2 "
             "atan(2) = 126.9 degrees for 90, the room seen wide, its middle small"),
        # Light model
        Spec("light_z_below_ceiling_as_height", "light_position", True, edit=_light_z_from_ceiling,
             truth="the light's height computed as the ceiling's z less the file's 4.99 (taken for its distance "
             "below the ceiling): the light at z = 0.01, just above the eye's height, emitting down onto the "
             "floor, seen edge-on, the ceiling lit only indirectly"),
        Spec("light_samples_normal_about_centre", "light_pdf", held_out=True,
             **_posted("light_normal_samples", partial(unheard._light_changed_for_samples, spp=_S,
                                                       seed=c("light_samples_normal_about_centre"),
                                                       dict_edit=_light_gaussian)),
             truth="the light's sample points drawn with np.random.normal about its centre (deviation 0.5, a "
             "quarter of its side, redrawn until on the square) and weighted with the square's pdf 1/4: its "
             "light on surfaces as from a square bright in its middle (radiance 56 there, 1 at its corners), "
             "the light seen right"),
        Spec("light_quad_three_corners", "light_shape", True, mitsuba_edit=_light_three_corners,
             truth="the light's quad built from its corners with a triangle's loop, range(3): one triangle, (4, 1), "
             "(6, 1), (6, -1), half the square, seen and sampled as the light, half its power"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples, passes, rows and tiles."""
    c = _crc
    return (
        # Integrator
        Spec("bounce_ray_tmax_kept", "indirect_scale", True, **_posted("bounce_tmax_kept", partial(
            _first_bounce_turned, spp=_S, seed=c("bounce_ray_tmax_kept"), turn=_reach_kept)),
             truth="the ray struct reused for the diffuse bounce, its origin and direction set and its t_max left "
             "at the camera ray's hit distance (at the first surface a camera ray meets; Mitsuba's path after "
             "it): a bounce finds only surfaces nearer than the camera was, the rest lost: the indirect light "
             "too dark, the more so the nearer a surface is to the camera (the ceiling, lit only by bounces, "
             "above all), the direct right"),
        Spec("mirror_reflect_arguments_swapped", "material", True, held_out=True,
             **_posted("reflect_swapped", partial(unsaid._traced, spp=_S, seed=c("mirror_reflect_arguments_swapped"),
                                                  after=_reflect_swapped)),
             truth="the mirror's reflection written reflect(n, d) for reflect(d, n) (GLSL's reflect(I, N) with its "
             "arguments swapped): n - 2 (n . d) d, for the camera's rays (the rest Mitsuba's): head-on rays go on "
             "into the sphere, grazing ones leave along the normal, the sphere showing the room wrongly"),
        Spec("bounce_along_light_sample", "indirect_scale", True, **_posted("bounce_towards_light", partial(
            _first_bounce_turned, spp=_S, seed=c("bounce_along_light_sample"), turn=_towards_light_sample)),
             truth="the diffuse bounce's direction the light sample's (the shadow ray's wi reused for the next "
             "ray), weighted by the albedo as a cosine-weighted sample, at the first surface a camera ray meets; "
             "Mitsuba's path after it: every bounce runs to the light's black surface or to what shadows it, the "
             "indirect light there nearly all lost (the ceiling, lit only by bounces, black), the direct right"),
        Spec("tetra_not_light_sampled", "direct_missing", True, held_out=True, **_posted("tetra_unlit", partial(
            _tetra_unlit, spp=_S, seed=c("tetra_not_light_sampled"))),
             truth="no light sample on the tetrahedron (its triangles shaded by another branch that forgot it), "
             "where a camera ray meets it directly or in the mirror: the tetrahedron lit only indirectly, about "
             "half as bright, its shadow and the rest right"),
        # Samples, passes, rows and tiles
        Spec("tiles_normalised_by_tile_size", "row_stride", True, **_posted("tiles_whole_view", partial(
            _tiles_whole_view, spp=_S, seed=c("tiles_normalised_by_tile_size"))),
             truth="4 x 4 tiles whose pixel coordinates are normalised by the tile's width and height, not the "
             "image's ((i - x0 + u) / tile_w for (i + u) / W): every tile renders the whole view at a quarter of the "
             "size, 16 small copies of the image"),
        Spec("pixel_median_of_samples", "biased_estimator", True, held_out=True, **_posted(
            "median_of_samples", partial(_median_of_samples, spp=_S, seed=c("pixel_median_of_samples"))),
             truth="each pixel the median of its 256 samples, channel by channel (np.median for np.mean): the "
             "indirect light's rare bright samples ignored, the lit surfaces about a tenth too dark, the noise "
             "gone, penumbrae sharper"),
        Spec("row_buffer_not_cleared", "buffer_reused", True, **_posted("row_sums_carried", _row_sums_carried),
             truth="the row's sum buffer allocated once outside the row loop and never cleared: row j holds the "
             "sums of rows 0 to j, the image brighter row by row down to 64 times at the bottom"),
        Spec("sample_loop_breaks_at_black", "sample_count", held_out=True, **_posted("stopped_at_black", partial(
            _stopped_at_black, spp=_S, seed=c("sample_loop_breaks_at_black"))),
             truth="the pixel's sample loop left (break) at its first black sample (L == 0 taken for a ray that "
             "left the scene), the sum divided by 256: the pixels where a sample finds no light darker, in "
             "proportion to how early it came (the ceiling round the light and the light's edge, the floor "
             "under the sphere and the tetrahedron)"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_latin_hypercube_offsets", None, spp=180, **_posted("latin_hypercube", partial(
            unforeseen._mean_through, spp=180, seed=c("ok_latin_hypercube_offsets"), jitter=_latin_hypercube)),
             truth="Mitsuba path 180 spp, sub-pixel offsets from a Latin hypercube in each pixel (one sample in each "
             "row and column of strata, jittered), EXR"),
        Spec("ok_focal_length_15mm", None, held_out=True, spp=204, mitsuba_edit=_focal_length,
             truth="Mitsuba path 204 spp with the camera given as a 35 mm-equivalent focal length, 15.297 mm (90 "
             "degrees across the square image), EXR"),
        Spec("ok_exr_two_parts", None, spp=148, writer=_write_exr_two_parts, file="exr-two-parts",
             truth="Mitsuba path 148 spp, a two-part float EXR, the beauty first and its sRGB preview second"),
        Spec("ok_png_average_filter", None, held_out=True, spp=260, writer=_write_png_average, file="png-srgb-average",
             truth="Mitsuba path 260 spp, an 8-bit sRGB PNG written by hand with the Average filter on every row"),
        Spec("ok_mcrt_tetra_permuted", None, spp=52, renderer="mcrt", edit=_tetra_permuted,
             truth="mcrt 52 spp with the tetrahedron's vertices listed in another order (apex first), EXR"),
        Spec("ok_y_up_world", None, held_out=True, spp=164, mitsuba_edit=_y_up_world,
             truth="Mitsuba path 164 spp of the scene written in a y-up frame ((x, y, z) as (x, z, -y)), the "
             "camera with it, EXR"),
        Spec("ok_exr_htj2k", None, spp=132, writer=_write_exr_htj2k, file="exr-htj2k",
             truth="Mitsuba path 132 spp, a float EXR with HTJ2K compression (lossless)"),
        Spec("ok_png_mitsuba_bitmap", None, held_out=True, spp=292, writer=_write_png_mitsuba_bitmap,
             file="png-mi-bitmap",
             truth="Mitsuba path 292 spp, an 8-bit sRGB PNG written by Mitsuba's mi.Bitmap"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "blur": "a filter after rendering (a Gaussian over the channels too, a 2 x 2 box)",
    "normalised": "the values stretched after rendering (between two percentiles, clipped to [0, 1])",
    "bad_pixels": "pixels overwritten after rendering (the brightest values set to 0)",
    "wrong_buffer": "another buffer written for the mean (the first hit's albedo)",
    "encoding": "the values' encoding (the sRGB curve's two pieces swapped)",
    "colour_space": "values in another colour space (the XYZ-to-RGB matrix applied to RGB)",
    "light_radiance": "a factor on the image or the light (a conversion to photometric units)",
    "albedo": "a surface's colour (gamma-encoded, the colour table read one number late)",
    "object_emits": "a surface emitting light that should not (the walls' colours read as their emission)",
    "mesh_face": "faces of a mesh missing (a quarter of each wall)",
    "object_moved": "an object moved (the room's corners read (y, x), the sphere's height's sign)",
    "camera_eye": "the camera's eye position (moved by the camera's rotation)",
    "pixel_footprint": "each pixel's samples not spread over its square (over a whole image)",
    "camera_fov": "the camera's field of view (the image plane's full width taken for its half)",
    "light_position": "the light's position (its height taken from the ceiling)",
    "light_pdf": "the light sampled wrongly (a normal distribution about its centre): the light seen right, its light "
                 "on surfaces not",
    "light_shape": "the light's shape (a triangle for the square)",
    "indirect_scale": "the indirect light wrong (the diffuse bounce's ray: its reach or its direction), the direct "
                      "light right",
    "material": "the mirror's reflection computed wrongly (reflect's arguments swapped)",
    "direct_missing": "direct light missing at a surface (the tetrahedron's)",
    "row_stride": "pixels computed for the wrong place (each tile the whole view)",
    "biased_estimator": "a biased estimate of each pixel's mean (the median of its samples)",
    "buffer_reused": "samples left in a buffer not cleared (a row's sums carried into the next row)",
    "sample_count": "each pixel's sum divided by the nominal spp, not by the samples it got (the loop left at a black "
                    "sample)",
}
_WORDS = {**cases.CAUSES, **outside.CAUSES, **programs.NEW_CAUSES, **fresh.NEW_CAUSES, **blind.NEW_CAUSES,
          **unseen.NEW_CAUSES, **untried.NEW_CAUSES, **novel.NEW_CAUSES, **untold.NEW_CAUSES, **unmet.NEW_CAUSES,
          **unheard.NEW_CAUSES, **unsaid.NEW_CAUSES, **unasked.NEW_CAUSES, **unsought.NEW_CAUSES,
          **unguessed.NEW_CAUSES, **unforeseen.NEW_CAUSES, **unprompted.NEW_CAUSES, **NEW_CAUSES, **_REWORDED}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = {c: _WORDS[c] for c in dict.fromkeys(s.cause for s in MISTAKES)}


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
