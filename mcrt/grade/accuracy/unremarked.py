r"""A twenty-fourth class of hand-ins: mistakes of students' tracers, scene input and output no class tried, blind.

How it was written: from what goes wrong in students' programs written on the
Python scientific stack (NumPy's views, in-place operations, ``uint8``
arithmetic, default axes, broadcasting and argument orders; SciPy's
interpolators, distributions, quasi-random generators and statistics;
Pillow's modes; OpenCV's and Taichi's conventions; Numba's frozen globals;
PyTorch's habits; Python's own loop variables and dictionaries), not from the
grader. Its author read the other classes' specs and cause words, the
catalogue (:mod:`mcrt.mutants`), the scene files and design notes, mcrt's
scene, camera and image code, :data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to
stay clear of their mistakes; never the grader's rules (what decides a cause)
nor its reports, and graded none of it, not one case. Each cause and
``major`` flag was set from the mistake alone; every mistake is worded by a
cause the other classes already have (:data:`NEW_CAUSES` is empty), so
``SAME_MISTAKE`` needed no new entry. The mistakes differ from those of the
twenty-two other classes (:mod:`~mcrt.grade.accuracy.cases`,
:mod:`~mcrt.grade.accuracy.outside` and the modules of :data:`_EARLIER`, from
:mod:`~mcrt.grade.accuracy.programs` to :mod:`~mcrt.grade.accuracy.unlooked`)
and from the catalogue's bugs:

* **post-processing**: a preview made of a strided view (``img[::2, ::2]``)
  tone-mapped in place, a quarter of the render's pixels with it; a
  brightness step ``img8 += 40`` on the ``uint8`` codes (NumPy wraps where
  OpenCV's ``cv2.add`` saturates); a 3 x 3 box blur looped (Numba-style) in
  place, reading the neighbours it has already blurred; a white balance on a
  reference patch indexed ``img[x, y]`` for ``img[y, x]`` (a blue wall taken
  for the grey ceiling);
* **writing the file**: the image saved with Taichi's ``ti.tools.imwrite``,
  which takes (width, height) arrays with their origin at the bottom (turned
  90 degrees); an RGB-to-BGR swap for ``cv2.imwrite`` written as a tuple
  assignment of views (red lost to blue); the sRGB curve looked up with
  SciPy's ``interp1d(..., bounds_error=False)``, NaN past 1 and written 0;
  16-bit codes given to Pillow band by band (``I;16``), converted to ``L``
  (clipped at 255) and merged;
* **materials**: every colour stored as a logit and read through a sigmoid
  (a differentiable renderer's habit); the mirror's ``d . n`` summed over the
  whole batch of rays (``np.sum`` without ``axis``): the reflection along the
  normal; the file's materials merged under the defaults (``{**spec,
  **DEFAULTS}``): every Lambertian the default grey;
* **geometry**: the tetrahedron's triangle test written ``np.logical_and(u >=
  0, v >= 0, u + v <= 1)`` (the third argument is ``out``): each face an
  unbounded wedge; each wall's next corner from ``np.roll(corners, -1)``
  without ``axis`` (the walls across the room); the floor and the ceiling
  given a quad's index list (half of each missing);
* **camera**: the ray directions normalised with ``np.linalg.norm(d,
  axis=0)`` (over the batch, not each ray): a field of view of 120 degrees;
  sub-pixel offsets ``np.sort``-ed along their last axis (each pair ordered, u
  <= v: half of each pixel); the field of view of the scene file's last
  camera (a loop variable used after its loop);
* **light model**: the light's points drawn with ``scipy.stats.uniform(lo,
  hi)`` (whose arguments are loc and scale); the light's radiance a Numba
  kernel's frozen global (its placeholder 1); the first vertex's light sample
  averaged over the batch (``np.mean(axis=0)`` where the light samples' axis
  is 1);
* **integrator**: the bounce weighted by the albedo's mean (a scalar kept for
  Russian roulette); the cosine sampler's square root written into its random
  numbers' buffer (``out=``) and read again: every bounce 45 degrees or more
  off the normal; the rays that meet the light compacted out of the batch
  and the pixel indices not (the rest of each path added a row or two back);
  Russian roulette's survivors divided by the survivors' mean probability (a
  broadcasting error fixed with ``.mean()``);
* **samples and passes**: the pixels shuffled for load balancing and the
  results written in the shuffled order; ``qmc.Sobol.random_base2(int(log2(spp)))``
  (128 of 200 samples); each pixel ``scipy.stats.mode`` of its samples (the
  smallest where none repeat); the samples interpolated onto the pixel centres
  with ``scipy.interpolate.griddata``.

The correct hand-ins come in ways no class used: Mitsuba with sub-pixel offsets
from one scrambled Sobol sequence run on across the pixels, mcrt as an 8-bit PNG
with a tRNS chunk, Mitsuba with the first bounce drawn as the normal plus a
point on the unit sphere, a 32-bit BMP with a BITMAPV4HEADER and bit-field
masks, Mitsuba's samples added into the film with ``np.add.at``, Mitsuba with
the light's radiance the D65 illuminant, Mitsuba with a flat normal map on
every Lambertian, and an 8-bit PNG encoded by scikit-image (``xyz2rgb`` and
``img_as_ubyte``).

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s ``edit``
and ``mitsuba_edit``), Mitsuba renders at another field of view, Mitsuba's path
integrator on rays a student's mirror makes (:func:`mcrt.grade.accuracy.unsaid._traced`)
or on sub-pixel offsets a student's loop makes
(:func:`mcrt.grade.accuracy.unsought._film_samples`), its first vertex's direct
light redone as a student's light sample makes it
(:func:`mcrt.grade.accuracy.unheralded._first_vertex`), its first bounce redrawn
(:func:`mcrt.grade.accuracy.unprompted._first_bounce`), its samples, one by one,
cut or reweighted where a student's path changes (same-seed samples of max depth
2 and 8, :func:`mcrt.grade.accuracy.unbeknown._camera_samples`) or combined as a
student's loop combines them (:func:`mcrt.grade.accuracy.unbidden._all_samples`),
or correct renders post-processed and written with NumPy, SciPy, Pillow and the
standard library as students' programs do. mcrt renders only a correct hand-in.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over
:data:`CATEGORIES`: the 2nd, 4th, ... of each category and of the correct
hand-ins) are as in :mod:`~mcrt.grade.accuracy.unlooked`, fixed before any case
was graded.
"""

from __future__ import annotations

import math
import struct
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unbeknown, unbidden,
                                 unforeseen, unguessed, unheard, unheralded, unlooked, unmet, unprompted, unsaid,
                                 unseen, unsought, untold, untried, unvisited)
from mcrt.grade.accuracy.cases import Spec
from mcrt.image_files import srgb_oetf

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


#: The classes after the first two, in the order they were written (their causes' words are this class's too).
_EARLIER = (programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked, unsought,
            unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked)


def _crc(name: str) -> int:
    return 1101000 + zlib.crc32(name.encode()) % 100000


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


def _preview_tonemapped_in_place(x):
    """A preview made of a strided view, ``preview = img[::2, ::2]``, tone-mapped in place (``preview /= 1 +
    preview``, Reinhard's curve for the screen): the view shares the render's memory, so the pixels of even row and
    even column (a quarter) are written tone-mapped, the rest as rendered."""
    img = np.array(x, np.float64)
    preview = img[::2, ::2]
    preview /= 1.0 + preview
    return img


def _brightened_codes(image: np.ndarray, *, step: int = 40) -> np.ndarray:
    """8-bit sRGB codes brightened by ``codes += step`` on the ``uint8`` array: NumPy's integer add wraps past 255
    (OpenCV's ``cv2.add`` would saturate), so the codes ``256 - step`` and up come back as 0 to ``step - 1``."""
    codes = blind._srgb8(image)
    codes += step
    return codes


def _write_png_brightened(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_brightened_codes(image), folder)


def _box_blur_in_place(x):
    """A 3 x 3 box blur looped over the pixels (a Numba kernel's loop) and written into the array it reads: each
    inside pixel the mean of its 3 x 3 block, whose upper and left neighbours are already blurred (the border kept)."""
    img = np.array(x, np.float64)
    h, w = img.shape[:2]
    for j in range(1, h - 1):
        for i in range(1, w - 1):
            img[j, i] = img[j - 1:j + 2, i - 1:i + 2].mean(axis=(0, 1))
    return img


def _white_balance_patch(x, *, swapped: bool = True):
    """A white balance on a reference patch meant to be grey: each channel times the patch's mean over its own
    value. The patch is picked at viewer coordinates (x, y) = (W / 2, H / 4), on the ceiling, and indexed
    ``img[x, y]`` (``swapped``) for ``img[y, x]``: row H / 2, column W / 4, a patch of the blue wall DE."""
    img = np.asarray(x, np.float64)
    h, w = img.shape[:2]
    px, py = w // 2, h // 4
    r, c = (px, py) if swapped else (py, px)
    ref = img[r - 1:r + 2, c - 1:c + 2].reshape(-1, 3).mean(axis=0)
    return img * (ref.mean() / ref)


# --------------------------------------------------------------------------
# Writers (the render in, the file a program writes)
# --------------------------------------------------------------------------


def _taichi_imwrite_codes(image: np.ndarray) -> np.ndarray:
    """What Taichi's ``ti.tools.imwrite(img, path)`` writes of a (H, W, 3) image stored row 0 at the top: it takes
    the array as (width, height) with its origin at the bottom left, ``img.swapaxes(0, 1)[::-1]`` (after its own
    ``clip(0, 1) * 255 + 0.5`` of floats): the image turned 90 degrees counter-clockwise."""
    codes = blind._srgb8(image)
    return np.ascontiguousarray(codes.swapaxes(0, 1)[::-1])


def _write_png_taichi(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_taichi_imwrite_codes(image), folder)


def _view_swapped_codes(image: np.ndarray) -> np.ndarray:
    """The codes as ``cv2.imwrite`` writes them after an RGB-to-BGR swap written as a tuple assignment of views,
    ``img[..., 0], img[..., 2] = img[..., 2], img[..., 0]``: the right side holds views, so channel 0 is given the
    blue, then channel 2 the new channel 0 (the blue again): (B, G, B), which OpenCV writes reversed, (B, G, B)."""
    codes = blind._srgb8(image)
    codes[..., 0], codes[..., 2] = codes[..., 2], codes[..., 0]
    return np.ascontiguousarray(codes[..., ::-1])


def _write_png_view_swapped(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_view_swapped_codes(image), folder)


#: The linear values of the sRGB table the program interpolates (4096 entries from 0 to 1).
_TABLE = np.linspace(0.0, 1.0, 4096)


def _interp1d_nan_codes(image: np.ndarray) -> np.ndarray:
    """8-bit codes of the sRGB curve looked up with ``scipy.interpolate.interp1d(table, srgb(table),
    bounds_error=False)`` on the unclipped values: its ``fill_value`` is NaN, so every channel over 1 is NaN, and
    ``np.round(v * 255).astype(np.uint8)`` casts NaN to 0 (with a warning the program never shows)."""
    from scipy.interpolate import interp1d

    v = np.maximum(np.nan_to_num(np.asarray(image, np.float64)), 0.0)
    enc = interp1d(_TABLE, srgb_oetf(_TABLE), bounds_error=False)(v)
    return np.nan_to_num(np.round(enc * 255.0), nan=0.0).astype(np.uint8)


def _write_png_interp1d_nan(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_interp1d_nan_codes(image), folder)


def _codes16(image: np.ndarray) -> np.ndarray:
    """16-bit sRGB codes, rounded."""
    v = np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 1.0)
    return np.floor(srgb_oetf(v) * 65535.0 + 0.5).astype(np.uint16)


def _write_png16_bands_to_l(image: np.ndarray, folder: Path) -> Path:
    """16-bit sRGB codes handed to Pillow band by band (``Image.fromarray`` of a 2-D ``uint16`` array is mode
    ``I;16``; Pillow has no 16-bit RGB), each band converted to ``L`` for ``Image.merge('RGB', ...)``: Pillow
    clips I;16 to L at 255, not scaling, so every code over 255 (an sRGB value over 1/257) is written 255."""
    from PIL import Image

    c16 = _codes16(image)
    bands = [Image.fromarray(np.ascontiguousarray(c16[..., k])).convert("L") for k in range(3)]
    path = folder / "render.png"
    Image.merge("RGB", bands).save(path, format="PNG")
    return path


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _sigmoid(a) -> tuple[float, ...]:
    return tuple(float(1.0 / (1.0 + math.exp(-c))) for c in a)


def _colours_through_sigmoid(s):
    """Every colour parameter (the Lambertians' albedos and the mirror's reflectance) read through ``torch.sigmoid``,
    as a differentiable renderer stores them (as logits), though the file gives them as they are: 0.6 to 0.646, 0.15
    to 0.537, 0.75 to 0.679, 0.8 to 0.690, 1 to 0.731."""
    from mcrt.scene import Mirror

    s = unbidden._albedos_mapped(s, _sigmoid)
    objects = tuple(replace(o, material=replace(o.material, reflectance=_sigmoid(o.material.reflectance)))
                    if isinstance(getattr(o, "material", None), Mirror) else o for o in s.objects)
    return replace(s, objects=objects)


#: The default material's albedo a loader's ``DEFAULTS`` dict holds.
_DEFAULT_ALBEDO = (0.5, 0.5, 0.5)


def _defaults_merged_last(s):
    """Each material merged with the defaults as ``{**spec, **DEFAULTS}`` (for ``{**DEFAULTS, **spec}``): the
    defaults win, every Lambertian the default albedo 0.5 (the mirror's reflectance has no default)."""
    return unbidden._albedos_mapped(s, lambda _: _DEFAULT_ALBEDO)


def _wedge_triangles(tris: np.ndarray, *, reach: float = 60.0) -> np.ndarray:
    """(n, 3, 3): the wedge each triangle (v0, v1, v2) becomes when only u >= 0 and v >= 0 bound it, cut at ``reach``
    times its edges from v0 (far past the room): (v0, v0 + reach (v1 - v0), v0 + reach (v2 - v0))."""
    t = np.asarray(tris, np.float64)
    v0 = t[:, 0]
    return np.stack([v0, v0 + reach * (t[:, 1] - v0), v0 + reach * (t[:, 2] - v0)], axis=1)


def _tetra_wedges(d: dict) -> dict:
    """The tetrahedron's triangle test ``np.logical_and(u >= 0, v >= 0, u + v <= 1)``: NumPy's ``logical_and``
    takes two arrays, the third positional argument is ``out``, so ``u + v <= 1`` is never tested: each face the
    wedge from its first vertex along its two edges, four orange planes through the room."""
    sf = fresh._surface("tetrahedron")
    return fresh._rebuilt(d, "tetrahedron", _wedge_triangles(sf.triangles), _bsdf(sf.material))


def _bsdf(material) -> dict:
    from mcrt.mitsuba_scene import _bsdf_dict

    return _bsdf_dict(material)


def _rolled_next_corners() -> np.ndarray:
    """(6, 2): each corner's 'next' corner as ``np.roll(corners, -1)`` makes it without ``axis=0``: the (6, 2) array
    rolled as its 12 numbers, every x and y shifted one place: (0, 0), (-6, 10), (-6, 13), (0, 10), (6, 0), (6, -3)
    for B, C, D, E, F, A."""
    corners = np.array([_scene().room.corners[k] for k in "ABCDEF"], np.float64)
    return np.roll(corners, -1)


def _wall_quads_rolled() -> dict[str, np.ndarray]:
    """Each wall's two triangles from its first corner to :func:`_rolled_next_corners`'s next corner, floor to
    ceiling, by the wall's name."""
    room = _scene().room
    a = np.array([room.corners[k] for k in "ABCDEF"], np.float64)
    b = _rolled_next_corners()
    out = {}
    for k, wall in enumerate(room.walls):
        p0, p1 = (*a[k], room.floor_z), (*b[k], room.floor_z)
        p2, p3 = (*b[k], room.ceiling_z), (*a[k], room.ceiling_z)
        out["wall_" + "".join(wall.corners)] = np.array([[p0, p1, p2], [p0, p2, p3]], np.float64)
    return out


def _walls_rolled(d: dict) -> dict:
    """The walls as :func:`_wall_quads_rolled` builds them (their colours kept): six walls across the room, none
    where the room's walls are, the floor and the ceiling as they were."""
    for name, tris in _wall_quads_rolled().items():
        d = fresh._rebuilt(d, name, tris, _bsdf(fresh._surface(name).material))
    return d


#: A quad's index list (the walls' two triangles), reused for the floor's and the ceiling's six corners.
_QUAD = ((0, 1, 2), (0, 2, 3))


def _quad_indexed(name: str) -> np.ndarray:
    """(2, 3, 3): the floor or the ceiling triangulated with :data:`_QUAD` over the corners A, B, C, D, E, F: A, B,
    C and A, C, D only, wound as the face's own (the floor's normals up, the ceiling's down)."""
    room = _scene().room
    z = room.floor_z if name == "floor" else room.ceiling_z
    corners = np.array([(*room.corners[k], z) for k in "ABCDEF"], np.float64)
    tris = corners[np.array(_QUAD)]
    up = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])[:, 2] > 0
    return np.where((up != (name == "floor"))[:, None, None], tris[:, [0, 2, 1]], tris)


def _floor_ceiling_quad_indexed(d: dict) -> dict:
    """The floor and the ceiling as :func:`_quad_indexed` makes them: the half A, D, E, F (y > 0) of each missing,
    the void seen through them."""
    for name in ("floor", "ceiling"):
        d = fresh._rebuilt(d, name, _quad_indexed(name), _bsdf(fresh._surface(name).material))
    return d


def _light_d65(d: dict) -> dict:
    """The light's radiance typed as Mitsuba's D65 illuminant scaled by 20 (``{'type': 'd65', 'scale': 20}``: white
    in an RGB variant)."""
    from mcrt.mitsuba_scene import _light_surface, _mesh

    s = _scene()
    sf = next(x for x in s.surfaces() if x.material is None)
    emitter = {"type": "area", "radiance": {"type": "d65", "scale": float(s.light.radiance[0])}}
    return dict(d, **{sf.name: _mesh(_light_surface(sf, s.light.normal), _bsdf(None), emitter)})


def _flat_normal_map(d: dict) -> dict:
    """Every Lambertian under a normal map of one texel (0.5, 0.5, 1): the normal (0, 0, 1) of tangent space, the
    surface's own."""
    import mitsuba as mi

    from mcrt.scene import Lambertian

    texel = mi.Bitmap(np.array([[[0.5, 0.5, 1.0]]], np.float32))
    for sf in _scene().surfaces():
        if isinstance(sf.material, Lambertian):
            nmap = {"type": "normalmap", "normalmap": {"type": "bitmap", "bitmap": texel, "raw": True,
                                                      "filter_type": "nearest"},
                    "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(sf.material.albedo)}}}
            d = fresh._rebuilt(d, sf.name, sf.triangles, {"type": "twosided", "bsdf": nmap})
    return d


# --------------------------------------------------------------------------
# The camera's field of view and sub-pixel offsets
# --------------------------------------------------------------------------

#: The field of view the rays have once each coordinate is divided by its norm over the batch: the forward
#: component 1 in every ray, the image plane's s and t uniform on [-1, 1] (root mean square 1 / sqrt(3)), so the
#: plane's half-width becomes sqrt(3): 2 atan(sqrt(3)) = 120 degrees.
_FOV_BATCH_NORM = math.degrees(2.0 * math.atan(math.sqrt(3.0) * math.tan(math.radians(45.0))))


def _batch_normalised(x, *, spp: int, seed: int):
    """The camera's ray directions normalised with ``d / np.linalg.norm(d, axis=0)`` for ``axis=1``: each world
    coordinate divided by its norm over the batch of rays (the view is axis-aligned: forward +x, right -y, up +z),
    the directions' ratios those of an image plane sqrt(3) times wider: Mitsuba at the field of view
    :data:`_FOV_BATCH_NORM`."""
    h, w = x.shape[:2]
    return _render(w, h, spp, seed, sensor={"fov": _FOV_BATCH_NORM})


def _pairs_sorted(rng, n: int, *, w: int, pixels: int):
    """Sub-pixel offsets drawn as ``offsets = rng.random((n, 2))`` and ordered with ``np.sort(offsets)`` (meant along
    the samples, sorting along the last axis): each pair ordered, u <= v, every sample in the half of its pixel below
    the diagonal from its top-left corner."""
    u, v = rng.random((2, pixels, n))
    return np.minimum(u, v), np.maximum(u, v)


#: The scene file's last camera's field of view (the far camera's), left in the loop variable.
_FOV_LAST_CAMERA = 2.0 * math.degrees(math.atan(0.5))


def _sobol_run_on(rng, n: int, *, w: int, pixels: int, points, used):
    """Offsets of one scrambled Sobol sequence run on across the pixels: pixel p takes the points p spp to (p + 1)
    spp - 1 (each aligned block of 2^k points a (0, k, 2)-net: stratified in the pixel, each point uniform), ``n``
    of them a chunk (``used`` counts the samples taken so far)."""
    k = used[0]
    used[0] += n
    chunk = points[:pixels, k:k + n]
    return chunk[..., 0], chunk[..., 1]


def _sobol_run_on_mean(x, *, spp: int, seed: int):
    """Each pixel the mean of Mitsuba's samples through :func:`_sobol_run_on`'s offsets."""
    from scipy.stats import qmc

    h, w = x.shape[:2]
    pts = qmc.Sobol(2, scramble=True, rng=np.random.default_rng(seed + 5)).random(w * h * spp).reshape(w * h, spp, 2)
    jitter = partial(_sobol_run_on, w=w, pixels=w * h, points=pts, used=[0])
    total = np.zeros((h * w, 3))
    for L, _, _ in unsought._film_samples(w, h, spp, seed, jitter):
        total += L.sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _sobol_base2(rng, n: int, *, w: int, pixels: int):
    """Offsets of a scrambled Sobol set of ``n`` points (``qmc.Sobol(2).random_base2(m)``), shifted at random in
    each pixel."""
    from scipy.stats import qmc

    m = int(round(math.log2(n)))
    pts = qmc.Sobol(2, scramble=True, rng=rng).random_base2(m)
    shift = rng.random((2, pixels, 1))
    return np.mod(pts[:, 0] + shift[0], 1.0), np.mod(pts[:, 1] + shift[1], 1.0)


def _sobol_base2_floor(x, *, spp: int, seed: int):
    """``qmc.Sobol(2).random_base2(m=int(np.log2(spp)))`` for the sub-pixel offsets, ``spp`` asked for: 2^7 = 128
    samples for 200 (``random_base2`` takes the exponent; the floor of log2 drops the rest), their mean."""
    n = 2 ** int(np.log2(spp))
    return unforeseen._mean_through(x, spp=n, seed=seed, jitter=_sobol_base2)


# --------------------------------------------------------------------------
# Light samples at the first vertex (unheralded._first_vertex's ``direct``)
# --------------------------------------------------------------------------


def _scipy_uniform_points(rng, n: int) -> np.ndarray:
    """(n, 3) points drawn as ``scipy.stats.uniform(c - h, c + h).rvs(n)`` on each axis of the light: SciPy's
    arguments are loc and scale, [loc, loc + scale], so x in [4, 10] and y in [-1, 0] (at the light's height)."""
    lt = _scene().light
    lo = np.asarray(lt.center[:2]) - 0.5 * np.asarray(lt.size)
    hi = np.asarray(lt.center[:2]) + 0.5 * np.asarray(lt.size)
    u, v = rng.random((2, n))
    return np.stack([lo[0] + u * hi[0], lo[1] + v * hi[1], np.full(n, lt.center[2])], axis=1)


def _light_from_scipy_uniform(mscene, rng, p, n, rho, mitsuba):
    """A first vertex's light sample at :func:`_scipy_uniform_points`'s point, weighted with the square's pdf
    1 / A: rho Le G A / pi where nothing lies between (points off the light counted as on it)."""
    lt = _scene().light
    q = _scipy_uniform_points(rng, len(p))
    g = np.where(unbeknown._unblocked(mscene, p, q), unbeknown._geometry(p, n, q), 0.0)
    return rho * (g * lt.area / math.pi)[:, None] * np.asarray(lt.radiance, np.float64)


def _batch_mean_light(mscene, rng, p, n, rho, mitsuba):
    """The light samples kept as (N, 1, 3) and averaged with ``np.mean(Ls, axis=0)`` (for ``axis=1``): a (1, 3)
    mean over the batch's vertices, broadcast to every vertex (Mitsuba's own light samples)."""
    return np.broadcast_to(np.asarray(mitsuba, np.float64).mean(axis=0), np.shape(mitsuba)).copy()


def _light_sample(name: str, direct) -> dict:
    """A spec's post-process: Mitsuba's path with its first vertex's light sample made by ``direct``."""
    return _posted(name, partial(unheralded._first_vertex, spp=_S, seed=_crc(name), direct=direct))


#: The light's radiance a Numba kernel compiled before the scene was loaded keeps: the module-level placeholder
#: ``LIGHT_RADIANCE = np.ones(3)`` (Numba freezes a global array into the machine code when it compiles).
_FROZEN_RADIANCE = (1.0, 1.0, 1.0)


# --------------------------------------------------------------------------
# Mirror, bounces and samples of the path
# --------------------------------------------------------------------------


def _reflect_batch_sum(o, d):
    """Camera rays that meet the sphere reflected as ``d - 2 * np.sum(d * n) * n`` (no ``axis``): the dot product
    summed over every ray of the batch that meets it (a large negative number), so each reflection lies along the
    normal: (origins, directions, segments used)."""
    c, radius = unsaid._sphere()
    oc = o - c
    b = np.einsum("ij,ij->i", oc, d)
    disc = b * b - (np.einsum("ij,ij->i", oc, oc) - radius * radius)
    t = -b - np.sqrt(np.maximum(disc, 0.0))
    hit = (disc > 0.0) & (t > 0.0)
    p = o + t[:, None] * d
    n = (p - c) / radius
    total = float(np.sum(d[hit] * n[hit]))
    r = unsaid._unit(d - 2.0 * total * n)
    return (np.where(hit[:, None], p + 1e-4 * n, o), np.where(hit[:, None], r, d), hit.astype(int))


def _albedo_mean_sample(o, d, seed, *, full, direct):
    """A sample whose first vertex's bounce is weighted by the albedo's mean for the albedo (``rho = albedo.mean()``,
    kept for Russian roulette, multiplied into the throughput): L2 + (L8 - L2) mean(rho) / rho where the camera ray
    meets a Lambertian first (L2, L8 the same seed's samples of max depth 2 and 8)."""
    L, near = unsaid._sampled(full, o, d, seed), unsaid._sampled(direct, o, d, seed)
    rho = unsaid._first_albedo(full, o, d)
    sel = rho.min(axis=1) > 0.0
    scale = np.ones_like(rho)
    scale[sel] = rho[sel].mean(axis=1, keepdims=True) / rho[sel]
    return near + (L - near) * scale


def _albedo_mean(x, *, spp: int, seed: int):
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(
        _albedo_mean_sample, full=unsaid._loaded(_DEPTH), direct=unsaid._loaded(2)))


def _sqrt_out_aliased(rng, n):
    """Cosine-weighted directions whose sampler writes ``z = np.sqrt(1 - u1, out=u1)`` (reusing the buffer) and then
    takes ``r = np.sqrt(u1)``: r = sqrt(z), so r >= z and every direction (normalised) 45 degrees or more off the
    normal, weighted by the albedo as a cosine sample."""
    u1, u2 = rng.random((2, len(n)))
    z = np.sqrt(1.0 - u1, out=u1)
    r = np.sqrt(u1)
    phi = 2.0 * math.pi * u2
    t, b = unforeseen._frame_of(n)
    return unsaid._unit((r * np.cos(phi))[:, None] * t + (r * np.sin(phi))[:, None] * b + z[:, None] * n), \
        np.ones(len(n))


def _sphere_plus_normal(rng, n):
    """Cosine-weighted directions drawn as the normal plus a point on the unit sphere (normal deviates normalised),
    normalised: weight 1 (times the albedo)."""
    s = unsaid._unit(rng.standard_normal((len(n), 3)))
    v = n + s
    length = np.linalg.norm(v, axis=1, keepdims=True)
    return np.where(length > 1e-9, v / np.maximum(length, 1e-12), n), np.ones(len(n))


def _compacted_sample(o, d, seed, *, full, direct, seen):
    """A batch of samples whose rays that meet the light first are removed after the first hit (``rays =
    rays[alive]``, the light's surface ending a path) while their pixel indices are not: the rest of the k-th
    surviving path (everything after the first vertex's light sample, L8 - L2 of the same seed) is added to the
    k-th lane of the batch, so each is moved back by the count of removed lanes before it, and the last lanes get
    none."""
    L, near = unsaid._sampled(full, o, d, seed), unsaid._sampled(direct, o, d, seed)
    alive = unsaid._sampled(seen, o, d, seed).max(axis=1) <= 0.0
    rest = (L - near)[alive]
    out = near.copy()
    out[:len(rest)] += rest
    return out


def _compacted(x, *, spp: int, seed: int):
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(
        _compacted_sample, full=unsaid._loaded(_DEPTH), direct=unsaid._loaded(2), seen=unsaid._loaded(1)))


def _survivors_mean_sample(o, d, seed, *, full, direct):
    """A sample whose path meets Russian roulette at its first bounce, survival p = max(albedo) (the throughput's
    largest channel there), the survivors divided by the mean of p over the batch's survivors (``beta[alive] /=
    p[alive]`` did not broadcast, so ``p[alive].mean()``): L2 + (L8 - L2) [u < p] / mean(p | survived)."""
    L, near = unsaid._sampled(full, o, d, seed), unsaid._sampled(direct, o, d, seed)
    rho = unsaid._first_albedo(full, o, d)
    p = rho.max(axis=1)
    diffuse = p > 0.0
    survive = diffuse & (np.random.default_rng(seed + 31).random(len(p)) < p)
    if not survive.any():
        return L
    weight = np.where(survive, 1.0 / p[survive].mean(), 0.0)
    return np.where(diffuse[:, None], near + (L - near) * weight[:, None], L)


def _survivors_mean(x, *, spp: int, seed: int):
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(
        _survivors_mean_sample, full=unsaid._loaded(_DEPTH), direct=unsaid._loaded(2)))


def _pixels_shuffled(x, *, seed: int):
    """The pixels rendered in an order ``np.random.permutation`` gave (to share the slow pixels among workers) and
    the results written in that order, ``img.flat`` slot k the k-th pixel rendered, never put back: pixel k holds
    pixel ``order[k]``'s value."""
    img = np.asarray(x, np.float64)
    h, w = img.shape[:2]
    order = np.random.default_rng(seed).permutation(h * w)
    return img.reshape(h * w, 3)[order].reshape(h, w, 3)


def _pixel_mode(x, *, spp: int, seed: int):
    """Each pixel ``scipy.stats.mode(samples, axis=0)`` of its samples, channel by channel (the most frequent value,
    taken for a robust mean): no two samples of a lit surface are equal, so the mode is the smallest; the light's 20
    wherever two samples or more see it."""
    from scipy.stats import mode

    h, w = x.shape[:2]
    return np.asarray(mode(unbidden._all_samples(w, h, spp, seed), axis=1).mode, np.float64).reshape(h, w, 3)


def _griddata_centres(x, *, spp: int, seed: int, near: float = 0.2):
    """The samples at their film positions (i + u, j + v) interpolated onto the pixel centres with
    ``scipy.interpolate.griddata(points, values, centres)`` (linear, its default), not averaged: each pixel the
    interpolation of the three samples round its centre. Only the samples within ``near`` of a centre (on each axis)
    are triangulated, the only ones its triangle can use (Qhull on all of them takes a minute at 64 x 64)."""
    from scipy.interpolate import griddata

    h, w = x.shape[:2]
    jj, ii = np.divmod(np.arange(w * h), w)
    pts, vals = [], []
    for L, u, v in unsought._film_samples(w, h, spp, seed, partial(unsought._independent, pixels=w * h)):
        keep = (np.abs(u - 0.5) < near) & (np.abs(v - 0.5) < near)
        px = np.broadcast_to(ii[:, None], u.shape) + u
        py = np.broadcast_to(jj[:, None], v.shape) + v
        pts.append(np.stack([px[keep], py[keep]], axis=1))
        vals.append(L[keep])
    pts, vals = np.concatenate(pts), np.concatenate(vals)
    gx, gy = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
    out = griddata(pts, vals, (gx, gy), method="linear")
    gone = np.isnan(out).any(axis=2)
    if gone.any():
        out[gone] = griddata(pts, vals, (gx[gone], gy[gone]), method="nearest")
    return out


def _samples_added_at(x, *, spp: int, seed: int):
    """Mitsuba's samples added into the film with ``np.add.at(film, pixel_index, samples)`` (unbuffered: every repeat
    of an index counted), divided by the spp."""
    h, w = x.shape[:2]
    L = unbidden._all_samples(w, h, spp, seed)
    film = np.zeros((h * w, 3))
    np.add.at(film, np.repeat(np.arange(h * w), spp), L.reshape(-1, 3))
    return (film / spp).reshape(h, w, 3)


# --------------------------------------------------------------------------
# Correct files made in other ways
# --------------------------------------------------------------------------


def _write_png_trns(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB PNG saved by Pillow with ``transparency=(0, 0, 0)``: a tRNS chunk marking black transparent (the
    colours as they are)."""
    from PIL import Image

    path = folder / "render.png"
    Image.fromarray(blind._srgb8(image), "RGB").save(path, format="PNG", transparency=(0, 0, 0))
    return path


def _bmp_v4_bytes(codes: np.ndarray) -> bytes:
    """A 32-bit BMP by hand with a BITMAPV4HEADER (108 bytes), BI_BITFIELDS and the masks R 0xff, G 0xff00, B
    0xff0000, A 0xff000000 (the bytes R, G, B, A; alpha 255), the bottom row first."""
    h, w = codes.shape[:2]
    rgba = np.concatenate([codes, np.full((h, w, 1), 255, np.uint8)], axis=2)[::-1]
    body = np.ascontiguousarray(rgba).tobytes()
    v4 = struct.pack("<IiiHHIIiiII", 108, w, h, 1, 32, 3, len(body), 2835, 2835, 0, 0)
    v4 += struct.pack("<IIII", 0xFF, 0xFF00, 0xFF0000, 0xFF000000) + b"BGRs" + bytes(36) + bytes(12)
    return b"BM" + struct.pack("<IHHI", 14 + len(v4) + len(body), 0, 0, 14 + len(v4)) + v4 + body


def _write_bmp_v4(image: np.ndarray, folder: Path) -> Path:
    path = folder / "render.bmp"
    path.write_bytes(_bmp_v4_bytes(blind._srgb8(image)))
    return path


def _skimage_codes(image: np.ndarray) -> np.ndarray:
    """8-bit sRGB codes as scikit-image makes them: the render taken to CIE XYZ with ``skimage.color``'s own matrix,
    ``xyz2rgb`` (linear sRGB, then its sRGB curve, clipped to [0, 1]) and ``img_as_ubyte``."""
    from skimage.color import xyz2rgb
    from skimage.color.colorconv import xyz_from_rgb
    from skimage.util import img_as_ubyte

    v = np.maximum(np.nan_to_num(np.asarray(image, np.float64)), 0.0)
    return img_as_ubyte(xyz2rgb(v @ xyz_from_rgb.T))


def _write_png_skimage_xyz(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_skimage_codes(image), folder)


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_preview_view_tonemapped", "pp_uint8_brightness_wraps", "pp_box_blur_in_place",
                        "pp_white_balance_patch_swapped"),
    "file": ("file_png_taichi_imwrite", "file_png_bgr_swap_views", "file_png_interp1d_nan", "file_png16_bands_to_l"),
    "materials": ("colours_through_sigmoid", "mirror_dot_summed_over_batch", "materials_defaults_merged_last"),
    "geometry": ("tetra_logical_and_out", "walls_np_roll_without_axis", "floor_ceiling_quad_indices"),
    "camera": ("rays_normalised_over_batch", "jitter_pairs_sorted", "fov_last_camera_loop_variable"),
    "light": ("light_scipy_uniform_loc_scale", "light_radiance_numba_frozen", "light_samples_mean_over_batch"),
    "integrator": ("bounce_weight_albedo_mean", "bounce_sqrt_out_aliased", "rays_compacted_pixels_not",
                   "roulette_survivors_mean"),
    "samples": ("pixels_shuffled_unpermuted", "sobol_base2_floor", "pixel_scipy_mode", "samples_griddata_centres"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_preview_view_tonemapped", "tone_map", True, **_posted("preview_in_place",
                                                                      _preview_tonemapped_in_place),
             truth="a screen preview made of a strided view, preview = img[::2, ::2], tone-mapped in place (preview "
             "/= 1 + preview) before the EXR is written from img: the view shares the render's memory, so every "
             "pixel of even row and even column (a quarter of them, in a grid) is Reinhard-mapped, x / (1 + x): a "
             "wall of 0.5 at 0.33, the light 0.95, the rest as rendered"),
        Spec("pp_uint8_brightness_wraps", "code_overflow", True, held_out=True, writer=_write_png_brightened,
             file="png-uint8-brightened",
             truth="a brightness step img8 += 40 on the uint8 sRGB codes before the PNG (NumPy's integer add wraps "
             "where OpenCV's cv2.add saturates): every code 40 higher, the codes 216 and over (linear 0.69 and "
             "more) wrapped to 0-39: the light, its reflection and the brightest surfaces nearly black, the rest "
             "too bright"),
        Spec("pp_box_blur_in_place", "blur", **_posted("box_blur_in_place", _box_blur_in_place),
             truth="a 3 x 3 box blur against the noise looped over the pixels (a Numba kernel) and written into the "
             "array it reads, as EXR: each pixel the mean of a block whose upper and left neighbours are already "
             "blurred, a blur smeared down and to the right (a tail from every bright edge), the border pixels "
             "kept"),
        Spec("pp_white_balance_patch_swapped", "white_balance", True, held_out=True, **_posted(
            "white_balance_swapped", _white_balance_patch),
             truth="a white balance on a 3 x 3 patch meant to be grey, each channel times the patch's mean over its "
             "own value, the patch picked at viewer coordinates (x, y) = (W / 2, H / 4) on the ceiling and indexed "
             "img[x, y] for img[y, x]: row H / 2, column W / 4, the blue wall DE: red and green raised (about 2.5 "
             "and 1.7 times), blue cut by half, the whole image orange-yellow, as EXR"),
        # Writing the file
        Spec("file_png_taichi_imwrite", "orientation", True, writer=_write_png_taichi, file="png-taichi",
             truth="the sRGB image (H, W, 3), row 0 at the top, saved with Taichi's ti.tools.imwrite, which takes "
             "arrays as (width, height) with their origin at the bottom left (img.swapaxes(0, 1)[::-1]): the "
             "image turned 90 degrees counter-clockwise, the ceiling on the left"),
        Spec("file_png_bgr_swap_views", "colour_lost", True, held_out=True, writer=_write_png_view_swapped,
             file="png-bgr-views",
             truth="an RGB-to-BGR swap for cv2.imwrite written as img[..., 0], img[..., 2] = img[..., 2], img[..., "
             "0]: the right side holds views of the array, so channel 0 takes the blue and channel 2 then takes "
             "the new channel 0 (the blue again): the PNG (B, G, B), its red channel the blue: the red walls "
             "dark grey, the blue wall magenta, the yellow wall and the tetrahedron green"),
        Spec("file_png_interp1d_nan", "bad_pixels", writer=_write_png_interp1d_nan, file="png-interp1d-nan",
             truth="an 8-bit PNG whose sRGB curve is looked up with scipy.interpolate.interp1d(table, srgb(table), "
             "bounds_error=False) on a table from 0 to 1, the values not clipped: its fill_value is NaN, so every "
             "channel over 1 is NaN and np.round(v * 255).astype(np.uint8) writes 0: the light and its reflection "
             "black, a few bright pixels with a channel black, the rest right"),
        Spec("file_png16_bands_to_l", "code_range", True, held_out=True, writer=_write_png16_bands_to_l,
             file="png16-bands-l",
             truth="16-bit sRGB codes saved with Pillow, which has no 16-bit RGB mode: each channel as a 2-D uint16 "
             "image (mode I;16) converted to L for Image.merge('RGB', ...), Pillow's I;16 to L clipping at 255 "
             "instead of scaling: every code over 255 (an sRGB value over 1/257) written 255, the 8-bit PNG white "
             "but for the blackest pixels"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("colours_through_sigmoid", "albedo", True, edit=_colours_through_sigmoid,
             truth="every colour parameter read through torch.sigmoid, as a differentiable renderer stores them "
             "(logits), though the file gives them as they are: the floor 0.646, the ceiling 0.690, the red wall "
             "(0.679, 0.537, 0.537), the tetrahedron (0.690, 0.611, 0.525), the mirror 0.731: every colour washed "
             "out towards a pale grey, the room brighter, the mirror darker"),
        Spec("mirror_dot_summed_over_batch", "material", True, held_out=True, **_posted(
            "mirror_batch_sum", partial(unsaid._traced, spp=_S, seed=_crc("mirror_dot_summed_over_batch"),
                                        after=_reflect_batch_sum)),
             truth="the mirror's reflection d - 2 * np.sum(d * n) * n with no axis (for camera rays; Mitsuba's path "
             "after it): the dot product summed over the whole batch of rays that meet the sphere, a large "
             "negative number, so every reflected ray leaves along the sphere's normal: the sphere shows the room "
             "as seen outwards from its centre, a distorted panorama in place of the reflection"),
        Spec("materials_defaults_merged_last", "albedo", True, edit=_defaults_merged_last,
             truth="each material merged with the loader's defaults as {**spec, **DEFAULTS} (for {**DEFAULTS, "
             "**spec}): the defaults win, every Lambertian the default albedo 0.5: the walls, the floor, the "
             "ceiling and the tetrahedron one grey, no colour anywhere, the floor and the ceiling darker"),
        # Geometry
        Spec("tetra_logical_and_out", "object_shape", True, mitsuba_edit=_tetra_wedges,
             truth="the tetrahedron's triangle test written np.logical_and(u >= 0, v >= 0, u + v <= 1): "
             "logical_and takes two arrays and its third positional argument is out, so u + v <= 1 is never "
             "tested: each face the wedge from its first vertex along its two edges, four orange planes cutting "
             "through the room"),
        Spec("walls_np_roll_without_axis", "object_shape", True, held_out=True, mitsuba_edit=_walls_rolled,
             truth="each wall built from a corner to the next, the next corners taken as np.roll(corners, -1) "
             "without axis=0: the (6, 2) array rolled as its 12 numbers, every x and y one place on, (0, 0), (-6, "
             "10), (-6, 13), (0, 10), (6, 0), (6, -3): six walls in their colours across the room, one just in "
             "front of the camera, the floor and the ceiling as they were, the void seen past the walls' ends"),
        Spec("floor_ceiling_quad_indices", "mesh_face", True, mitsuba_edit=_floor_ceiling_quad_indexed,
             truth="the floor and the ceiling triangulated with the walls' quad index list [[0, 1, 2], [0, 2, 3]] "
             "over their six corners: triangles A, B, C and A, C, D only, the half A, D, E, F (y > 0, the left of "
             "the image) of each missing, the void seen through it"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera
        Spec("rays_normalised_over_batch", "camera_fov", True, **_posted("batch_normalised", partial(
            _batch_normalised, spp=_S, seed=c("rays_normalised_over_batch"))),
             truth="the camera rays' directions normalised with d / np.linalg.norm(d, axis=0) for axis=1: each "
             "world coordinate divided by its norm over the batch (the forward one in every ray, s and t uniform "
             "on [-1, 1]), the image plane sqrt(3) times wider: a field of view of 120 degrees for 90, the room "
             "small in the middle"),
        Spec("jitter_pairs_sorted", "pixel_footprint", held_out=True, **_posted("pairs_sorted", partial(
            unforeseen._mean_through, spp=_S, seed=c("jitter_pairs_sorted"), jitter=_pairs_sorted)),
             truth="the sub-pixel offsets drawn as rng.random((n, 2)) and ordered with np.sort(offsets) (meant "
             "along the samples; the default axis is the last): each pair sorted, u <= v, every sample in the half "
             "of its pixel below its diagonal: each pixel a triangle's mean, centred a sixth of a pixel left of and "
             "below the pixel's centre (the image a sixth of a pixel right and up)"),
        Spec("fov_last_camera_loop_variable", "camera_fov", True, edit=cases.fov(_FOV_LAST_CAMERA),
             truth="the field of view taken from the loop variable left by the loop over the scene file's cameras "
             "(for name, cam in cameras.items(): fov = cam['fov']), the last camera's: the far camera's 53.13 "
             "degrees with the near camera's eye: the view narrower, its middle magnified"),
        # Light model
        Spec("light_scipy_uniform_loc_scale", "light_pdf", True, **_light_sample(
            "light_scipy_uniform_loc_scale", _light_from_scipy_uniform),
             truth="the light's sample points drawn with scipy.stats.uniform(c - h, c + h).rvs(n) on each axis, "
             "whose arguments are loc and scale ([loc, loc + scale]): x in [4, 10], y in [-1, 0], weighted with "
             "the square's pdf 1 / 4, at the first surface a camera ray meets (Mitsuba's path after it): light "
             "from a 6 x 1 strip reaching towards wall CD, the points off the light counted, the light seen "
             "right"),
        Spec("light_radiance_numba_frozen", "light_radiance", True, held_out=True,
             edit=cases.light(radiance=_FROZEN_RADIANCE),
             truth="the light's radiance a module global read by a Numba kernel compiled before the scene was "
             "loaded: Numba froze its placeholder np.ones(3) into the machine code, the loader's 20 never seen: "
             "radiance 1 for 20, the light and everything it lights 20 times too dark"),
        Spec("light_samples_mean_over_batch", "light_pdf", True, **_light_sample(
            "light_samples_mean_over_batch", _batch_mean_light),
             truth="the light samples of each vertex kept as (N, 1, 3) and averaged with np.mean(Ls, axis=0) for "
             "axis=1, at the first surface a camera ray meets (Mitsuba's path after it): a (1, 3) mean over the "
             "batch broadcast to every vertex: every surface given the same direct light, the image's average "
             "(no shadows, no fall-off, no colour of its own), the light seen right"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples, passes and counters."""
    c = _crc
    return (
        # Integrator
        Spec("bounce_weight_albedo_mean", "indirect_scale", True, **_posted("albedo_mean", partial(
            _albedo_mean, spp=_S, seed=c("bounce_weight_albedo_mean"))),
             truth="the diffuse bounce weighted by rho = albedo.mean() (a scalar kept for Russian roulette) for the "
             "albedo, at the first surface a camera ray meets (Mitsuba's path after it): the light after the bounce "
             "grey-weighted, the walls' colour bleeding gone (the red wall's red indirect light halved, its green "
             "and blue 2.3 times), the direct light right"),
        Spec("bounce_sqrt_out_aliased", "indirect_scale", held_out=True, **_posted("sqrt_out_aliased", partial(
            unprompted._first_bounce, spp=_S, seed=c("bounce_sqrt_out_aliased"), draw=_sqrt_out_aliased)),
             truth="the cosine sampler writing z = np.sqrt(1 - u1, out=u1) into its random numbers' buffer, then "
             "r = np.sqrt(u1), the square root of z, at the first surface a camera ray meets (Mitsuba's path after "
             "it): every bounce (normalised) 45 degrees or more off the normal, weighted as a cosine sample: the "
             "indirect light from grazing directions only"),
        Spec("rays_compacted_pixels_not", "row_stride", True, **_posted("compacted", partial(
            _compacted, spp=_S, seed=c("rays_compacted_pixels_not"))),
             truth="the camera rays that meet the light removed from the batch after the first hit (o, d, beta = "
             "o[alive], d[alive], beta[alive]), the pixel index array left as it was: the rest of each path after "
             "its first light sample (the indirect light, and nearly all the mirror shows) added to the pixel whose "
             "ray had that place in the batch: moved back in row order by as many pixels as see the light (two "
             "rows and a half at 64 x 64): the mirror's picture and the indirect light displaced up and sideways, "
             "a ghost of the sphere, the sphere dark, the last pixels without them, the direct light right"),
        Spec("roulette_survivors_mean", "roulette", held_out=True, **_posted("survivors_mean", partial(
            _survivors_mean, spp=_S, seed=c("roulette_survivors_mean"))),
             truth="Russian roulette at the first bounce with survival p = max(albedo) (the throughput's largest "
             "channel), the survivors divided by p[alive].mean() (beta[alive] /= p[alive] did not broadcast), at "
             "the first surface a camera ray meets (Mitsuba's path after it): the paths off the floor (0.6) "
             "weighted about 0.85, off the ceiling and the tetrahedron about 1.1: the floor's indirect light "
             "darker, the ceiling's brighter"),
        # Samples, passes and counters
        Spec("pixels_shuffled_unpermuted", "row_stride", True, **_posted("pixels_shuffled", partial(
            _pixels_shuffled, seed=c("pixels_shuffled_unpermuted"))),
             truth="the pixels rendered in the order np.random.permutation gave (to share the slow pixels among "
             "workers) and written in that order, never put back: every pixel some other pixel's value, the image "
             "a noise of the render's colours"),
        Spec("sobol_base2_floor", "spp_claim", held_out=True, spp=200, **_posted("sobol_base2_floor", partial(
            _sobol_base2_floor, spp=200, seed=c("sobol_base2_floor"))),
             truth="sub-pixel offsets from qmc.Sobol(2).random_base2(m=int(np.log2(spp))) for 200 spp: random_base2 "
             "takes the exponent and the floor of log2 drops the rest, 2^7 = 128 samples a pixel, 200 declared: "
             "the image right, as noisy as 128 spp"),
        Spec("pixel_scipy_mode", "biased_estimator", True, **_posted("scipy_mode", partial(
            _pixel_mode, spp=_S, seed=c("pixel_scipy_mode"))),
             truth="each pixel scipy.stats.mode(samples, axis=0) of its 256 samples, channel by channel (the most "
             "frequent value, taken for a robust mean): no two samples of a lit surface agree, so the mode is the "
             "smallest: every surface about half as bright (its darkest sample), the noise gone, the shadows black, "
             "and 20 wherever two samples or more see the light (the light's edges and its reflection widened)"),
        Spec("samples_griddata_centres", "spp_claim", held_out=True, **_posted("griddata_centres", partial(
            _griddata_centres, spp=_S, seed=c("samples_griddata_centres"))),
             truth="the 256 samples of each pixel placed at their film positions (i + u, j + v) and interpolated "
             "onto the pixel centres with scipy.interpolate.griddata (linear, its default) for their mean: each "
             "pixel the interpolation of the three samples round its centre, as noisy as 2 or 3 spp and "
             "unfiltered, 256 declared"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_sobol_run_on_offsets", None, **_posted("sobol_run_on", partial(
            _sobol_run_on_mean, spp=_S, seed=c("ok_sobol_run_on_offsets"))),
             truth="Mitsuba path 256 spp, sub-pixel offsets from one scrambled Sobol sequence run on across the "
             "pixels (pixel p the points 256 p to 256 p + 255, an aligned block), EXR"),
        Spec("ok_mcrt_png_trns", None, held_out=True, spp=72, renderer="mcrt", writer=_write_png_trns,
             file="png-trns",
             truth="mcrt 72 spp, an 8-bit sRGB PNG saved by Pillow with transparency=(0, 0, 0) (a tRNS chunk)"),
        Spec("ok_bounce_sphere_plus_normal", None, **_posted("sphere_plus_normal", partial(
            unprompted._first_bounce, spp=_S, seed=c("ok_bounce_sphere_plus_normal"), draw=_sphere_plus_normal)),
             truth="Mitsuba path 256 spp with the first bounce drawn as the normal plus a point on the unit sphere "
             "(normal deviates normalised), normalised: cosine-weighted, EXR"),
        Spec("ok_bmp_v4_bitfields", None, held_out=True, spp=204, writer=_write_bmp_v4, file="bmp-v4",
             truth="Mitsuba path 204 spp, a 32-bit sRGB BMP written by hand with a BITMAPV4HEADER, BI_BITFIELDS and "
             "RGBA masks, the bottom row first"),
        Spec("ok_samples_added_at", None, spp=128, **_posted("samples_added_at", partial(
            _samples_added_at, spp=128, seed=c("ok_samples_added_at"))),
             truth="Mitsuba path 128 spp, its samples added into the film with np.add.at over the repeated pixel "
             "indices, EXR"),
        Spec("ok_light_d65", None, held_out=True, spp=188, mitsuba_edit=_light_d65,
             truth="Mitsuba path 188 spp with the light's radiance typed as the D65 illuminant scaled by 20 (white in "
             "Mitsuba's RGB variant), EXR"),
        Spec("ok_flat_normal_map", None, spp=164, mitsuba_edit=_flat_normal_map,
             truth="Mitsuba path 164 spp with every Lambertian under a flat normal map (one texel (0.5, 0.5, 1)), "
             "EXR"),
        Spec("ok_png_skimage_xyz2rgb", None, held_out=True, spp=212, writer=_write_png_skimage_xyz,
             file="png-skimage-xyz",
             truth="Mitsuba path 212 spp, an 8-bit sRGB PNG encoded by scikit-image: the render taken to CIE XYZ, "
             "color.xyz2rgb (the sRGB curve) and util.img_as_ubyte"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "tone_map": "a tone map applied before saving (to a quarter of the pixels, through a strided view)",
    "code_overflow": "codes past 255 wrapped round (a brightness step added in uint8)",
    "blur": "a filter after rendering (a box blur written into the array it reads)",
    "white_balance": "each colour channel scaled after rendering (a white balance on the wrong patch)",
    "orientation": "the image written turned (Taichi's image writer's axes)",
    "colour_lost": "colour lost (the red channel replaced by the blue)",
    "bad_pixels": "pixels not computed (NaN past the sRGB table's range, written as 0)",
    "code_range": "codes of another bit depth in the file (16-bit codes clipped to 8 bits)",
    "albedo": "a surface's colour (every colour through a sigmoid, every Lambertian the default grey)",
    "material": "an object rendered with another material (the mirror reflecting along its normal)",
    "object_shape": "an object's shape (the tetrahedron's faces unbounded, the room's walls between the wrong "
                    "corners)",
    "mesh_face": "a face of a mesh missing (half of the floor and the ceiling)",
    "camera_fov": "the camera's field of view (the rays normalised over the batch, the last camera's field of view)",
    "pixel_footprint": "each pixel's samples not spread over its square (half of it: the offsets sorted)",
    "light_pdf": "the light sampled wrongly (from a strip off the light, averaged over the batch): the light seen "
                 "right, its light on surfaces not",
    "light_radiance": "the light's radiance (a placeholder 1 for 20)",
    "indirect_scale": "the indirect light wrong (the bounce weighted by the albedo's mean, bounces off the normal), "
                      "the direct light right",
    "roulette": "Russian roulette wrong (its survivors divided by the survivors' mean probability)",
    "row_stride": "pixels written at the wrong addresses (in a shuffled order, or the rest of each path added to "
                  "another pixel)",
    "spp_claim": "fewer samples per pixel than declared (a Sobol set's exponent floored, samples interpolated)",
    "biased_estimator": "a biased estimate of each pixel's mean (the mode of its samples)",
}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = blind.class_causes(MISTAKES, _EARLIER, NEW_CAUSES, _REWORDED)


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
