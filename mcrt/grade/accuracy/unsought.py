r"""A fourteenth class of hand-ins: mistakes in students' tracers, scene input and output no class tried, written blind.

How it was written: from what goes wrong in students' programs (the steps
after rendering, the code that saves the image, the scene typed in or
parsed, the camera's rays, the light's samples, the integrator's loop, the
loops that add up the samples), not from the grader. Its author read the
other classes' specs and cause words, the catalogue (:mod:`mcrt.mutants`),
:data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to
stay clear of their mistakes; never the grader's rules (what decides a
cause) nor its reports, and graded none of it, not one case. Each cause and
``major`` flag was set from the mistake alone; every mistake is worded by a
cause the other classes already have (:data:`NEW_CAUSES` is empty), so
``SAME_MISTAKE`` needed no new entry. The mistakes differ from those of the
thirteen other classes (:mod:`~mcrt.grade.accuracy.cases`,
:mod:`~mcrt.grade.accuracy.outside`, :mod:`~mcrt.grade.accuracy.programs`,
:mod:`~mcrt.grade.accuracy.fresh`, :mod:`~mcrt.grade.accuracy.blind`,
:mod:`~mcrt.grade.accuracy.unseen`, :mod:`~mcrt.grade.accuracy.untried`,
:mod:`~mcrt.grade.accuracy.novel`, :mod:`~mcrt.grade.accuracy.untold`,
:mod:`~mcrt.grade.accuracy.unmet`, :mod:`~mcrt.grade.accuracy.unheard`,
:mod:`~mcrt.grade.accuracy.unsaid`, :mod:`~mcrt.grade.accuracy.unasked`) and
from the catalogue's bugs:

* **post-processing**: the image turned 2 degrees (SciPy's ``rotate``, to
  level the horizon); the dark pixels (luminance under 0.1) replaced by a
  Gaussian blur of the image, to hide the noise in the shadows; a 3 x 3 grey
  opening (SciPy's ``grey_opening``) against fireflies; the colours taken
  to YCbCr by BT.601's matrix and back by BT.709's;
* **writing the file**: the channels written G, B, R (the writer's channel
  index one off, ``(c + 1) % 3``); the sRGB curve applied to red and green
  only (a loop over ``range(2)``), blue written as linear codes; a planar
  buffer interleaved with the red plane read one sample late; 8-bit codes in
  video range (16 + 219 v);
* **materials**: wall CD's red typed 0.57 for 0.75; each wall's colour
  looked up by its triangle's index modulo the walls' count (every wall
  split along its diagonal into two walls' colours); the floor's albedo
  parsed from two numbers, its blue 0;
* **geometry**: the sphere's z typed -3.8 for -3.3 (sunk 0.3 into the floor);
  the triangle test's barycentric bounds with a tolerance of 0.02 (a crack
  along every triangle's edges); the tetrahedron's normals turned towards
  the eye (its faces turned away from the camera black under one-sided
  shading);
* **camera model**: the eye moving 0.3 sideways over the exposure (a motion
  blur test's velocity left in); the rows mapped with the course's 100 rows
  hard-coded; the rays built in camera space (OpenGL's -z forward) and never
  turned into the world: the camera looking at the floor; the pixel-to-plane
  mapping in integer arithmetic (``(2 i + 1) / W`` of integers, 0 or 1);
* **light model**: the light's 16 stratified samples at their strata's
  centres (no jitter); the light's square built in the x-z plane (a y-up
  habit), facing -y; the light sampled about (5.5, 0), a second copy of its
  centre mistyped in the sampling code, seen where it is;
* **integrator**: the Lambertian's 1/pi applied to every bounce's weight,
  the mirror's too; the mirror's reflection ``d - (d . n) n`` (its 2
  missing: the rays leave along the tangent plane); the depth counted
  twice a vertex (at the light sample and at the bounce: max depth 5 for 8);
* **samples and passes**: the first column never rendered (the column loop
  from 1); each sample binned to the pixel ``round`` of its film position
  (not ``floor``), divided by the spp; each pixel's sum divided by the count
  of its samples that are not zero; four passes combined by their maximum.

The correct hand-ins come in ways no class used: Mitsuba with one sub-pixel
offset a sample index shared by every pixel, Mitsuba with the light as four
1 x 1 squares, mcrt with two light samples a vertex and no MIS, an 8-bit sRGB
PNG written by scikit-image, a PIZ-compressed float EXR, Mitsuba with
antithetic sub-pixel offsets (u, v) and (1 - u, 1 - v), Mitsuba with the
sphere a unit sphere scaled and moved (``to_world``), and an 8-bit sRGB
binary PPM saved by Pillow.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s
``edit`` and ``mitsuba_edit``), Mitsuba renders combined where light
transport or pixel integrals are linear in what is combined (the light seen
apart, eyes along the motion, passes), Mitsuba's path integrator sampling
the rays a student's camera or mirror makes, or its samples, one by one,
added up as a student's loop adds them (:func:`_film_samples`, and
:func:`mcrt.grade.accuracy.unasked._samples`), or correct renders
post-processed and written with NumPy, SciPy and Pillow as students'
programs do. mcrt renders only correct hand-ins.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over
:data:`CATEGORIES`: the 2nd, 4th, ... of each category and of the correct
hand-ins) are as in :mod:`~mcrt.grade.accuracy.unasked`, fixed before any
case was graded.
"""

from __future__ import annotations

import math
import zlib
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unheard, unmet, unsaid,
                                 unseen, untold, untried)
from mcrt.grade.accuracy.cases import Spec

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


def _crc(name: str) -> int:
    return 101000 + zlib.crc32(name.encode()) % 100000


_render = unseen._render
_posted = unseen._posted


# --------------------------------------------------------------------------
# Post-processing (linear render in, what the program writes out)
# --------------------------------------------------------------------------


def _rotated(x, *, deg: float = 2.0):
    """The image turned ``deg`` degrees counter-clockwise about its centre (SciPy's ``rotate``, bilinear, the same
    size, the corners filled from the nearest pixels)."""
    from scipy.ndimage import rotate

    return rotate(np.asarray(x, np.float64), deg, axes=(1, 0), reshape=False, order=1, mode="nearest")


def _dark_blurred(x, *, below: float = 0.1, sigma: float = 1.5):
    """The pixels whose luminance is under ``below`` replaced by a Gaussian blur of the image (sigma in pixels)."""
    from scipy.ndimage import gaussian_filter

    x = np.asarray(x, np.float64)
    blurred = gaussian_filter(x, sigma=(sigma, sigma, 0), mode="nearest")
    return np.where((unseen._luma(x) < below)[..., None], blurred, x)


def _opened(x):
    """A 3 x 3 grey opening (a minimum filter, then a maximum filter) of each channel."""
    from scipy.ndimage import grey_opening

    return grey_opening(np.asarray(x, np.float64), size=(3, 3, 1), mode="nearest")


def _ycbcr(kr: float, kb: float) -> np.ndarray:
    """The 3 x 3 matrix from RGB to (Y, Cb, Cr) of luma coefficients ``kr``, ``kb``."""
    kg = 1.0 - kr - kb
    return np.array([[kr, kg, kb],
                     [-kr / (2 * (1 - kb)), -kg / (2 * (1 - kb)), 0.5],
                     [0.5, -kg / (2 * (1 - kr)), -kb / (2 * (1 - kr))]])


def _ycbcr_mismatched(x):
    """The colours taken to YCbCr with BT.601's luma coefficients and back with BT.709's inverse."""
    m = np.linalg.inv(_ycbcr(0.2126, 0.0722)) @ _ycbcr(0.299, 0.114)
    return np.asarray(x, np.float64) @ m.T


# --------------------------------------------------------------------------
# Files as students' programs write them (the program's buffer in, file out)
# --------------------------------------------------------------------------


def _write_exr_gbr(image: np.ndarray, folder: Path) -> Path:
    """A float EXR whose channel c holds the image's channel (c + 1) % 3: R the green, G the blue, B the red."""
    return fresh._write_exr(np.asarray(image)[..., [1, 2, 0]], folder)


def _srgb_red_green(image: np.ndarray) -> np.ndarray:
    """8-bit codes with the sRGB curve applied to red and green only, blue the linear value times 255 (rounded)."""
    v = np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 1.0)
    v[..., :2] = fresh._srgb(v[..., :2])
    return np.floor(v * 255.0 + 0.5).astype(np.uint8)


def _write_png_srgb_red_green(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_srgb_red_green(image), folder)


def _red_one_late(image: np.ndarray) -> np.ndarray:
    """(H, W, 3) 8-bit sRGB codes interleaved from planes, the red plane read one sample late (``R[k - 1]`` for
    ``R[k]``, the first 0): the red moved one pixel right, each row's first red the row above's last."""
    codes = blind._srgb8(image)
    out = codes.copy()
    red = codes[..., 0].reshape(-1)
    out[..., 0] = np.concatenate([[0], red[:-1]]).reshape(codes.shape[:2])
    return out


def _write_png_red_one_late(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_red_one_late(image), folder)


def _video_range(image: np.ndarray) -> np.ndarray:
    """8-bit codes in video range: ``16 + 219 v`` of the sRGB values, rounded (black 16, white 235)."""
    return np.floor(16.0 + 219.0 * fresh._srgb(np.asarray(image, np.float64)) + 0.5).astype(np.uint8)


def _write_png_video_range(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_video_range(image), folder)


# --------------------------------------------------------------------------
# Mitsuba's path integrator on the rays a student's program makes, and its samples one by one
# --------------------------------------------------------------------------


def _rows_of_100(fx, fy, *, h: int):
    """Rows mapped with the course's 100 rows hard-coded: ``t = 1 - 2 (j + v) / 100`` for ``(j + v) / H`` (columns
    right): the top rows of the view, stretched."""
    eye, r, u, f, k = unsaid._frame()
    s, t = k * (2.0 * fx - 1.0), k * (1.0 - 2.0 * fy * h / 100.0)
    return np.broadcast_to(eye, (len(fx), 3)), unsaid._unit(f + s[:, None] * r + t[:, None] * u)


def _integer_division(fx, fy, *, w: int, h: int):
    """The pixel-to-plane mapping in integer arithmetic: ``s = (2 i + 1) / W - 1`` with ``/`` of integers (so -1 or
    0), the jitter ``(2 u - 1) / W`` then added; t alike (1 or 0). Four blocks of the image, each a pixel's worth of
    one place in the view."""
    eye, r, u, f, k = unsaid._frame()
    x, y = np.asarray(fx) * w, np.asarray(fy) * h
    i, j = np.floor(x), np.floor(y)
    s = (np.floor_divide(2 * i + 1, w) - 1.0) + (2.0 * (x - i) - 1.0) / w
    t = (1.0 - np.floor_divide(2 * j + 1, h)) - (2.0 * (y - j) - 1.0) / h
    return np.broadcast_to(eye, (len(fx), 3)), unsaid._unit(f + k * s[:, None] * r + k * t[:, None] * u)


def _camera_traced(x, *, spp: int, seed: int, camera):
    """:func:`unsaid._traced` on the rays of ``camera`` given the image's size (``camera(fx, fy, w=, h=)``)."""
    h, w = x.shape[:2]
    return unsaid._traced(x, spp=spp, seed=seed, camera=partial(camera, w=w, h=h))


def _camera_rows_of_100(fx, fy, *, w: int, h: int):
    return _rows_of_100(fx, fy, h=h)


def _reflect_without_2(o, d):
    """Camera rays that meet the sphere (nothing in front of it) reflected as ``d - (d . n) n`` (the 2 missing,
    normalised): along the sphere's tangent plane. Returns (origins, directions, segments used: 1 where reflected)."""
    c, radius = unsaid._sphere()
    oc = o - c
    b = np.einsum("ij,ij->i", oc, d)
    disc = b * b - (np.einsum("ij,ij->i", oc, oc) - radius * radius)
    t = -b - np.sqrt(np.maximum(disc, 0.0))
    hit = (disc > 0.0) & (t > 0.0)
    p = o + t[:, None] * d
    n = (p - c) / radius
    r = d - np.einsum("ij,ij->i", d, n)[:, None] * n
    norm = np.linalg.norm(r, axis=1, keepdims=True)
    r = np.where(norm > 1e-9, r / np.maximum(norm, 1e-30), n)
    return (np.where(hit[:, None], p + 1e-4 * n, o), np.where(hit[:, None], r, d), hit.astype(int))


def _film_samples(w: int, h: int, spp: int, seed: int, jitter, *, lanes: int = 1 << 18):
    """Mitsuba path's samples of each pixel on the pinhole's rays through sub-pixel offsets ``jitter(rng, n)`` ->
    (u, v), each (W H, n): for each chunk, the (W H, n, 3) radiance samples and the offsets (chunks of an even n)."""
    from mcrt.mitsuba_scene import pass_seed

    mscene = unsaid._loaded(8)
    rng = np.random.default_rng(seed)
    n_chunk = max(2, (lanes // (w * h)) // 2 * 2)
    jj, ii = np.divmod(np.arange(w * h), w)
    for k, start in enumerate(range(0, spp, n_chunk)):
        n = min(n_chunk, spp - start)
        u, v = jitter(rng, n)
        fx, fy = (ii[:, None] + u) / w, (jj[:, None] + v) / h
        o, d = unsaid._pinhole(fx.reshape(-1), fy.reshape(-1))
        L = unsaid._sampled(mscene, np.asarray(o), d, pass_seed(seed, k))
        yield L.reshape(w * h, n, 3), u, v


def _independent(rng, n: int, *, pixels: int):
    return rng.random((2, pixels, n))


def _rounded_bins(x, *, spp: int, seed: int):
    """Each sample's film position ``(i + u, j + v)`` binned to the pixel ``(round(i + u), round(j + v))``, not the
    one it lies in, each pixel's sum divided by the spp: the image half a pixel off, the first row and column
    with half their samples (half as bright), the samples rounded past the last dropped."""
    h, w = x.shape[:2]
    jj, ii = np.divmod(np.arange(w * h), w)
    total = np.zeros((h + 1, w + 1, 3))
    for L, u, v in _film_samples(w, h, spp, seed, partial(_independent, pixels=w * h)):
        bx = np.floor(ii[:, None] + u + 0.5).astype(int)
        by = np.floor(jj[:, None] + v + 0.5).astype(int)
        np.add.at(total, (by.reshape(-1), bx.reshape(-1)), L.reshape(-1, 3))
    return total[:h, :w] / spp


def _zeros_left_out(x, *, spp: int, seed: int):
    """Each pixel's sum divided by the count of its samples that are not zero (black samples taken for failed ones),
    not by the spp."""
    h, w = x.shape[:2]
    total, count = np.zeros((h * w, 3)), np.zeros(h * w)
    for L, _, _ in unasked._samples(w, h, spp, seed):
        total += L.sum(axis=1)
        count += (L.max(axis=2) > 0.0).sum(axis=1)
    return (total / np.maximum(count, 1.0)[:, None]).reshape(h, w, 3)


def _shared(rng, n: int, *, pixels: int):
    """One sub-pixel offset a sample index, the same for every pixel."""
    return np.broadcast_to(rng.random((2, 1, n)), (2, pixels, n))


def _antithetic(rng, n: int, *, pixels: int):
    """Sub-pixel offsets in pairs (u, v), (1 - u, 1 - v), each pixel its own."""
    base = rng.random((2, pixels, n // 2))
    out = np.empty((2, pixels, n))
    out[..., 0::2], out[..., 1::2] = base, 1.0 - base
    return out


def _mean_of(x, *, spp: int, seed: int, jitter):
    """Each pixel the mean of its :func:`_film_samples` with sub-pixel offsets from ``jitter``."""
    h, w = x.shape[:2]
    total = np.zeros((h * w, 3))
    for L, _, _ in _film_samples(w, h, spp, seed, partial(jitter, pixels=w * h)):
        total += L.sum(axis=1)
    return (total / spp).reshape(h, w, 3)


# --------------------------------------------------------------------------
# Renderer mistakes realised with Mitsuba renders combined (the render's shape in, the image out)
# --------------------------------------------------------------------------


def _eye_moving(x, *, spp: int, seed: int, move: float = 0.3, steps: int = 8):
    """The eye moving ``move`` along +y (the camera's left) over the exposure: ``steps`` renders of spp / steps with
    the eye at the middles of the motion's equal parts, averaged."""
    h, w = x.shape[:2]
    n = max(1, spp // steps)
    return np.mean([_render(w, h, n, seed + k, scene_edit=cases.eye(dy=move * (k + 0.5) / steps))
                    for k in range(steps)], axis=0)


def _passes_max(x, *, passes: int, spp: int, seed: int):
    """``passes`` Mitsuba renders of ``spp`` each combined by their maximum, channel by channel."""
    h, w = x.shape[:2]
    return np.max([_render(w, h, spp, seed + k) for k in range(passes)], axis=0)


def _first_column_unrendered(x):
    """The first column never rendered (``for i in range(1, W)``): left black."""
    out = np.array(x, np.float64, copy=True)
    out[:, 0] = 0.0
    return out


def _strata_centres(n: int = 4):
    """The centres of the light's n x n strata, (x, y)."""
    from mcrt.scene import load_scene

    lt = load_scene().light
    cx, cy, _ = lt.center
    a = (np.arange(n) + 0.5) / n - 0.5
    return [(cx + p * lt.size[0], cy + q * lt.size[1]) for p in a for q in a]


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _floor_two_numbers(s):
    """The floor's albedo parsed from two numbers into a zero vector: (0.6, 0.6, 0)."""
    return cases.floor_albedo((0.6, 0.6, 0.0))(s)


def _wall_colours(d: dict) -> dict:
    """Each wall's two triangles given the colours of walls ``t % 6``, t the triangle's index in the walls' list
    (two a wall): wall k's triangles take walls 2k % 6 and (2k + 1) % 6."""
    from mcrt.mitsuba_scene import _bsdf_dict
    from mcrt.scene import load_scene

    s = load_scene()
    walls = [sf for sf in s.surfaces() if sf.name.startswith("wall_")]
    out = dict(d)
    t = 0
    for sf in walls:
        tris = np.asarray(sf.triangles, np.float64)
        out = {k: v for k, v in out.items() if k != sf.name}
        for m, tri in enumerate(tris):
            mat = walls[t % len(walls)].material
            out = fresh._rebuilt(out, f"{sf.name}_{m}", tri[None], _bsdf_dict(mat))
            t += 1
    return out


def _shrunk(tris: np.ndarray, f: float) -> np.ndarray:
    c = tris.mean(axis=1, keepdims=True)
    return c + f * (tris - c)


def _edge_tolerance(d: dict, *, eps: float = 0.02) -> dict:
    """Every triangle hit only where its barycentrics are all at least ``eps``: each mesh triangle shrunk about its
    centroid by 1 - 3 eps (the light's too, its radiance the same)."""
    from mcrt.mitsuba_scene import _bsdf_dict
    from mcrt.scene import load_scene

    s = load_scene()
    f = 1.0 - 3.0 * eps
    out = dict(d)
    for sf in s.surfaces():
        tris = _shrunk(np.asarray(sf.triangles, np.float64), f)
        if sf.name == "light":
            out = unsaid._meshes(out, light=(_shrunk(unsaid._light_tris(), f), s.light.radiance))
        else:
            out = fresh._rebuilt(out, sf.name, tris, _bsdf_dict(sf.material))
    return out


def _faces_away(tris: np.ndarray, eye) -> np.ndarray:
    """Which of the tetrahedron's faces turn their outside away from ``eye``."""
    centre = tris.reshape(-1, 3).mean(axis=0)
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    fc = tris.mean(axis=1)
    n = n * np.sign(np.einsum("ij,ij->i", n, fc - centre))[:, None]  # outward
    return np.einsum("ij,ij->i", n, np.asarray(eye) - fc) < 0.0


def _tetra_normals_to_eye(d: dict) -> dict:
    """The tetrahedron's normals turned towards the eye, shaded one-sided: the faces that turn away from the camera
    black from outside (wound inwards, a one-sided diffuse), the others as they are."""
    from mcrt.scene import load_scene

    sf = fresh._surface("tetrahedron")
    tris = np.asarray(sf.triangles, np.float64)
    away = _faces_away(tris, load_scene().cameras["near"].eye)
    albedo = {"type": "rgb", "value": [float(a) for a in sf.material.albedo]}
    out = fresh._rebuilt(d, "tetrahedron", tris[~away], {"type": "twosided", "bsdf": {"type": "diffuse",
                                                                                          "reflectance": albedo}})
    centre = tris.reshape(-1, 3).mean(axis=0)
    back = tris[away]
    n = np.cross(back[:, 1] - back[:, 0], back[:, 2] - back[:, 0])
    inward = np.einsum("ij,ij->i", n, back.mean(axis=1) - centre) < 0.0
    back = np.where(inward[:, None, None], back, back[:, [0, 2, 1]])
    return fresh._rebuilt(out, "tetrahedron_away", back, {"type": "diffuse", "reflectance": albedo})


def _camera_space(s):
    """The rays built in camera space (x right, y up, looking down -z) and used as world directions: forward
    (0, 0, -1), up (0, 1, 0)."""
    return cases._camera(s, forward=(0.0, 0.0, -1.0), up=(0.0, 1.0, 0.0))


def _light_xz_tris() -> np.ndarray:
    """(2, 3, 3): the light's square in the x-z plane through its centre, wound to face -y."""
    from mcrt.scene import load_scene

    lt = load_scene().light
    cx, cy, cz = lt.center
    hx, hz = lt.size[0] / 2.0, lt.size[1] / 2.0
    a, b, c, e = ((cx - hx, cy, cz - hz), (cx + hx, cy, cz - hz), (cx + hx, cy, cz + hz), (cx - hx, cy, cz + hz))
    return np.array([[a, b, c], [a, c, e]], np.float64)


def _light_xz(d: dict) -> dict:
    """The light's square built in the x-z plane about its centre, emitting towards -y."""
    from mcrt.scene import load_scene

    return unsaid._meshes(d, light=(_light_xz_tris(), load_scene().light.radiance))


def _mirror_over_pi(d: dict) -> dict:
    """The mirror's reflection weighted by 1 / pi (the Lambertian's normalisation applied to every BSDF)."""
    return blind._sphere_bsdf(d, {"type": "conductor", "material": "none",
                                  "specular_reflectance": {"type": "rgb", "value": [1.0 / math.pi] * 3}})


def _light_four_squares(d: dict) -> dict:
    """The light as four 1 x 1 emitting squares tiling its 2 x 2 square (the same radiance)."""
    from mcrt.scene import load_scene

    lt = load_scene().light
    cx, cy, cz = lt.center
    qx, qy = lt.size[0] / 4.0, lt.size[1] / 4.0
    squares = np.concatenate([unsaid._square(cx + a * qx, cy + b * qy, cz, qx)
                              for a in (-1.0, 1.0) for b in (-1.0, 1.0)])
    return unsaid._meshes(d, light=(squares, lt.radiance))


def _sphere_transformed(d: dict) -> dict:
    """The sphere a unit sphere at the origin scaled by its radius and moved to its centre (``to_world``)."""
    import mitsuba as mi

    c, radius = unsaid._sphere()
    sph = {k: v for k, v in d["sphere"].items() if k not in ("center", "radius")}
    sph["to_world"] = mi.ScalarTransform4f().translate([float(a) for a in c]) @ mi.ScalarTransform4f().scale(radius)
    return dict(d, sphere=sph)


# --------------------------------------------------------------------------
# Correct renders written in other ways
# --------------------------------------------------------------------------


def _write_png_skimage(image: np.ndarray, folder: Path) -> Path:
    """The 8-bit sRGB codes (rounded) saved by ``skimage.io.imsave``."""
    from skimage.io import imsave

    path = folder / "render.png"
    imsave(path, blind._srgb8(image), check_contrast=False)
    return path


def _write_exr_piz(image: np.ndarray, folder: Path) -> Path:
    """A float32 EXR with R, G, B, PIZ-compressed."""
    import OpenEXR

    path = folder / "render.exr"
    OpenEXR.File({"compression": OpenEXR.PIZ_COMPRESSION, "type": OpenEXR.scanlineimage},
                 {c: np.ascontiguousarray(image[..., i], np.float32) for i, c in enumerate("RGB")}).write(str(path))
    return path


def _write_ppm_pillow(image: np.ndarray, folder: Path) -> Path:
    """The 8-bit sRGB codes (rounded) saved by Pillow as a binary PPM (``Image.save(..., format="PPM")``)."""
    from PIL import Image

    path = folder / "render.ppm"
    Image.fromarray(blind._srgb8(image), "RGB").save(path, format="PPM")
    return path


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_rotated_2_degrees", "pp_dark_pixels_blurred", "pp_grey_opening", "pp_ycbcr_601_709"),
    "file": ("file_exr_gbr", "file_png_srgb_red_green", "file_png_red_one_late", "file_png_video_range"),
    "materials": ("wall_cd_red_typed_057", "walls_colour_by_triangle", "floor_blue_missing"),
    "geometry": ("sphere_z_typed_3_8", "triangle_edge_tolerance", "tetra_normals_to_eye"),
    "camera": ("eye_moving_shutter", "rows_mapped_with_100", "camera_space_minus_z", "pixel_integer_division"),
    "light": ("light_strata_unjittered", "light_in_xz_plane", "light_sampled_at_5_5"),
    "integrator": ("mirror_over_pi", "mirror_reflect_without_2", "depth_counted_twice"),
    "samples": ("first_column_unrendered", "samples_rounded_to_pixel", "zeros_left_out_of_count",
                "passes_combined_by_max"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_rotated_2_degrees", "camera_rotation", **_posted("rotated_2", _rotated),
             truth="the image turned 2 degrees counter-clockwise (scipy.ndimage.rotate, bilinear, the same size) to "
             "level the horizon, as EXR"),
        Spec("pp_dark_pixels_blurred", "blur", held_out=True, **_posted("dark_blurred", _dark_blurred),
             truth="the pixels of luminance under 0.1 replaced by a Gaussian blur of the image (sigma 1.5 pixels), to "
             "hide the noise in the shadows, as EXR"),
        Spec("pp_grey_opening", "blur", True, **_posted("grey_opening", _opened),
             truth="a 3 x 3 grey opening (scipy.ndimage.grey_opening: a minimum, then a maximum filter) against "
             "fireflies: every bright detail narrower than 3 pixels removed, as EXR"),
        Spec("pp_ycbcr_601_709", "colour_space", held_out=True, **_posted("ycbcr_601_709", _ycbcr_mismatched),
             truth="the colours taken to YCbCr by BT.601's luma coefficients and back by BT.709's (a video library's "
             "defaults mixed): a slight colour cast, as EXR"),
        # Writing the file
        Spec("file_exr_gbr", "channels", True, writer=_write_exr_gbr, file="exr-gbr",
             truth="the writer's channel index one off (out[..., c] = img[..., (c + 1) % 3]): an EXR whose R holds "
             "the green, G the blue, B the red"),
        Spec("file_png_srgb_red_green", "encoding", True, held_out=True, writer=_write_png_srgb_red_green,
             file="png-srgb-red-green",
             truth="the sRGB curve applied in a loop over range(2): red and green sRGB-encoded, blue written as "
             "linear 8-bit codes (too dark, the image yellowed)"),
        Spec("file_png_red_one_late", "channel_misaligned", writer=_write_png_red_one_late,
             file="png-srgb-red-one-late",
             truth="a planar buffer interleaved with the red plane read one sample late (R[k - 1] for R[k]): the red "
             "one pixel right of green and blue, each row's first red the last of the row above, 8-bit sRGB PNG"),
        Spec("file_png_video_range", "code_range", held_out=True, writer=_write_png_video_range,
             file="png-video-range",
             truth="8-bit codes in video range, 16 + 219 v of the sRGB values (a video library's default): black at "
             "16, white at 235"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("wall_cd_red_typed_057", "albedo", edit=cases.wall_albedo("CD", (0.57, 0.7, 0.15)),
             truth="wall CD's red typed 0.57 for 0.75 (digits swapped): (0.57, 0.70, 0.15)"),
        Spec("walls_colour_by_triangle", "albedo", True, held_out=True, mitsuba_edit=_wall_colours,
             truth="each wall's colour looked up by its triangle's index modulo the walls' count: wall k's two "
             "triangles in walls 2k % 6's and (2k + 1) % 6's colours, every wall split along its diagonal"),
        Spec("floor_blue_missing", "albedo", True, edit=_floor_two_numbers,
             truth="the floor's albedo parsed from two numbers into a zero vector: (0.6, 0.6, 0), a yellow floor"),
        # Geometry
        Spec("sphere_z_typed_3_8", "object_moved", edit=cases.moved("sphere", (0.0, 0.0, -0.5)),
             truth="the sphere's z typed -3.8 for -3.3: sunk 0.3 into the floor"),
        Spec("triangle_edge_tolerance", "mesh_face", True, held_out=True, mitsuba_edit=_edge_tolerance,
             truth="the triangle test's barycentric bounds with a tolerance, u, v, 1 - u - v >= 0.02: every triangle "
             "of the room, the tetrahedron and the light shrunk about its centroid by 0.94, cracks along their "
             "edges and diagonals (the void seen through them)"),
        Spec("tetra_normals_to_eye", "normals", mitsuba_edit=_tetra_normals_to_eye,
             truth="the tetrahedron's normals turned towards the eye, shaded one-sided: its faces that turn away "
             "from the camera (seen in the mirror, lighting the floor) black, the rest right"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera model
        Spec("eye_moving_shutter", "camera_eye", **_posted("eye_moving", partial(
            _eye_moving, spp=256, seed=c("eye_moving_shutter"))),
             truth="a camera velocity left from a motion-blur test: the eye moving 0.3 along +y (to the camera's "
             "left) over the exposure, the near objects smeared sideways"),
        Spec("rows_mapped_with_100", "camera_fov", True, held_out=True, **_posted("rows_of_100", partial(
            _camera_traced, spp=256, seed=c("rows_mapped_with_100"), camera=_camera_rows_of_100)),
             truth="the rows mapped with the course's 100 rows hard-coded, t = 1 - 2 (j + v) / 100: at another "
             "height only the top rows of the view, stretched (the columns right)"),
        Spec("camera_space_minus_z", "camera_rotation", True, edit=_camera_space,
             truth="the rays built in camera space (x right, y up, looking down -z, OpenGL's convention) and never "
             "turned into the world: the camera looking straight down at the floor"),
        Spec("pixel_integer_division", "camera_model", True, held_out=True, **_posted("integer_division", partial(
            _camera_traced, spp=256, seed=c("pixel_integer_division"), camera=_integer_division)),
             truth="the pixel-to-plane mapping in integer arithmetic, s = (2 i + 1) / W - 1 with / of integers (-1 or "
             "0), the jitter added after: four flat blocks, each one pixel's view"),
        # Light model
        Spec("light_strata_unjittered", "light_pdf", **_posted("light_strata_centres", partial(
            unheard._light_changed_for_samples, spp=256, seed=c("light_strata_unjittered"),
            dict_edit=partial(unasked._under_light, points=_strata_centres(4)))),
             truth="the light's 16 stratified samples (4 x 4 strata) at their strata's centres, no jitter: 16 hard "
             "shadows in each penumbra, the light seen right"),
        Spec("light_in_xz_plane", "light_facing", True, held_out=True, mitsuba_edit=_light_xz,
             truth="the light's square built in the x-z plane about its centre (a y-up habit), facing -y: a vertical "
             "light, half of it above the ceiling, lighting wall BC's side of the room"),
        Spec("light_sampled_at_5_5", "light_pdf", **_posted("light_sampled_elsewhere", partial(
            unheard._light_changed_for_samples, spp=256, seed=c("light_sampled_at_5_5"),
            scene_edit=cases.light(move=(0.5, 0.0, 0.0)))),
             truth="the light sampled about (5.5, 0, 4.99), a second copy of its centre mistyped in the sampling "
             "code: its light on surfaces from there, the light seen where it is"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples and passes."""
    c = _crc
    return (
        # Integrator
        Spec("mirror_over_pi", "brdf_norm", True, mitsuba_edit=_mirror_over_pi,
             truth="the Lambertian's 1 / pi applied to every bounce's weight, the mirror's too: what the sphere "
             "reflects 1 / pi as bright, the diffuse surfaces right"),
        Spec("mirror_reflect_without_2", "material", True, held_out=True, **_posted("reflect_without_2", partial(
            unsaid._traced, spp=256, seed=c("mirror_reflect_without_2"), after=_reflect_without_2)),
             truth="the mirror's reflection d - (d . n) n, its 2 missing (for the camera's rays, the rest "
             "Mitsuba's): the rays leave along the sphere's tangent plane, the sphere showing the room round its "
             "rim"),
        Spec("depth_counted_twice", "depth", max_depth=5,
             truth="the depth counted twice a vertex (at its light sample and at its bounce): four surface vertices "
             "where seven belong, Mitsuba's max depth 5 for 8"),
        # Samples and passes
        Spec("first_column_unrendered", "bad_pixels", **_posted("first_column_black", _first_column_unrendered),
             truth="the column loop from 1 (for i in range(1, W)): the first column never rendered, black"),
        Spec("samples_rounded_to_pixel", "pixel_offset", held_out=True, **_posted("rounded_bins", partial(
            _rounded_bins, spp=256, seed=c("samples_rounded_to_pixel"))),
             truth="each sample binned to the pixel round(i + u), round(j + v) of its film position, not floor, each "
             "pixel's sum divided by 256: the image half a pixel off, the first row and column half as bright"),
        Spec("zeros_left_out_of_count", "biased_estimator", **_posted("zeros_left_out", partial(
            _zeros_left_out, spp=256, seed=c("zeros_left_out_of_count"))),
             truth="each pixel's sum divided by the count of its samples that are not zero (black samples taken for "
             "failed ones): the shadows brighter"),
        Spec("passes_combined_by_max", "biased_estimator", True, held_out=True, **_posted("passes_max", partial(
            _passes_max, passes=4, spp=64, seed=c("passes_combined_by_max"))),
             truth="four passes of 64 spp combined by their maximum (np.maximum) for their mean, 256 declared: every "
             "noisy pixel too bright"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_shared_subpixel_offsets", None, spp=192, **_posted("shared_offsets", partial(
            _mean_of, spp=192, seed=c("ok_shared_subpixel_offsets"), jitter=_shared)),
             truth="Mitsuba path 192 spp, one sub-pixel offset a sample index shared by every pixel, EXR"),
        Spec("ok_light_four_squares", None, held_out=True, spp=224, mitsuba_edit=_light_four_squares,
             truth="Mitsuba path 224 spp with the light typed as four 1 x 1 squares, EXR"),
        Spec("ok_mcrt_two_light_samples", None, spp=96, renderer="mcrt", **_posted("mcrt_two_light_samples", partial(
            untold._mcrt, spp=96, seed=c("ok_mcrt_two_light_samples"), light_samples=2, mis=False)),
             truth="mcrt 96 spp with two light samples a vertex, averaged, MIS off, EXR"),
        Spec("ok_png_skimage", None, held_out=True, spp=160, writer=_write_png_skimage, file="png-srgb-skimage",
             truth="Mitsuba path 160 spp, an 8-bit sRGB PNG saved by scikit-image's io.imsave"),
        Spec("ok_exr_piz", None, spp=208, writer=_write_exr_piz, file="exr-piz",
             truth="Mitsuba path 208 spp, a float EXR PIZ-compressed"),
        Spec("ok_antithetic_offsets", None, held_out=True, spp=256, **_posted("antithetic_offsets", partial(
            _mean_of, spp=256, seed=c("ok_antithetic_offsets"), jitter=_antithetic)),
             truth="Mitsuba path 256 spp with antithetic sub-pixel offsets, (u, v) and (1 - u, 1 - v) in pairs, EXR"),
        Spec("ok_sphere_transformed", None, spp=176, mitsuba_edit=_sphere_transformed,
             truth="Mitsuba path 176 spp with the sphere a unit sphere scaled by 1.5 and moved (to_world), EXR"),
        Spec("ok_ppm_pillow", None, held_out=True, spp=240, writer=_write_ppm_pillow, file="ppm-srgb-pillow",
             truth="Mitsuba path 240 spp, an 8-bit sRGB binary PPM saved by Pillow"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "camera_rotation": "the camera's rotation (its forward or up vector, or the image turned after rendering)",
    "blur": "a filter after rendering (the dark pixels blurred, a grey opening)",
    "colour_space": "values in another colour space (YCbCr matrices mismatched)",
    "channels": "colour channels written in the wrong order (G, B, R)",
    "encoding": "the values' encoding (the display curve on two channels only)",
    "channel_misaligned": "the colour channels out of register (one channel a pixel off)",
    "code_range": "codes of another range in the file (video range, 16 to 235)",
    "albedo": "a surface's colour (a value mistyped, the walls' colours looked up by triangle, a channel missing)",
    "object_moved": "an object moved (the sphere sunk into the floor)",
    "mesh_face": "parts of a mesh's faces missing (cracks along every triangle's edges)",
    "normals": "surface normals facing the wrong way (turned towards the eye, one-sided shading)",
    "camera_eye": "the camera's eye position (moving over the exposure)",
    "camera_fov": "the camera's field of view (the rows mapped for another height)",
    "camera_model": "each pixel's ray wrong (the pixel-to-plane mapping in integer arithmetic)",
    "light_pdf": "the light sampled wrongly (strata centres, about another centre): the light seen right, its light on "
                 "surfaces not",
    "light_facing": "the light emitting the wrong way (its square vertical, facing -y)",
    "brdf_norm": "a BRDF's normalisation (the Lambertian's 1 / pi on the mirror too)",
    "material": "an object rendered with another material (the mirror's reflection formula wrong)",
    "depth": "the path depth (counted twice a vertex)",
    "bad_pixels": "pixels not computed (the first column never rendered)",
    "pixel_offset": "the pixel centres (samples binned half a pixel off, the edges' samples lost)",
    "biased_estimator": "a biased estimate of each pixel's mean (zero samples left out of the count, the passes' "
                        "maximum)",
}
_WORDS = {**cases.CAUSES, **outside.CAUSES, **programs.NEW_CAUSES, **fresh.NEW_CAUSES, **blind.NEW_CAUSES,
          **unseen.NEW_CAUSES, **untried.NEW_CAUSES, **novel.NEW_CAUSES, **untold.NEW_CAUSES, **unmet.NEW_CAUSES,
          **unheard.NEW_CAUSES, **unsaid.NEW_CAUSES, **unasked.NEW_CAUSES, **NEW_CAUSES, **_REWORDED}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = {c: _WORDS[c] for c in dict.fromkeys(s.cause for s in MISTAKES)}


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
