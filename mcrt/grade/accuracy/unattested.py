r"""A twenty-ninth class of hand-ins: mistakes of tracers written with array and GPU frameworks, blind.

How it was written: from what goes wrong in students' tracers written with NumPy and the array and GPU frameworks
they reach for to make them fast (PyTorch's ``conv2d``, ``avg_pool2d``, ``grid_sample``, ``normalize``,
``meshgrid``, ``randn_like``, ``max`` and ``save_image``; JAX's immutable arrays and keys; Numba's ``prange``
reductions; Taichi's compile-time globals; CUDA's launch grids, pitched buffers and ``curand_init``; Dr.Jit's
``dr.select`` and Mitsuba's ``ray_test`` and ``rectangle``; NumPy's operator precedence, ``reshape``,
``searchsorted``, ``np.diff``, aliasing, silent casts and ``uint8`` arithmetic; matplotlib's ``origin``; OpenCV's
conversion of what ``imwrite`` cannot write), not from the grader. Its author read the other classes' specs and cause
words, the catalogue (:mod:`mcrt.mutants`), the scene files and design notes, mcrt's scene, camera and image code,
:data:`~mcrt.grade.accuracy.run.CAUSE_OF` and :data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words
and to stay clear of their mistakes; never the grader's rules (what decides a cause) nor its reports, and graded none
of it, not one case. Each cause and ``major`` flag was set from the mistake alone; every mistake is worded by a cause
the other classes already have (:data:`NEW_CAUSES` is empty), so ``SAME_MISTAKE`` needed no new entry. The mistakes
differ from those of the twenty-eight other classes (:mod:`~mcrt.grade.accuracy.cases`,
:mod:`~mcrt.grade.accuracy.outside` and the modules of :data:`_EARLIER`, from :mod:`~mcrt.grade.accuracy.programs`
to :mod:`~mcrt.grade.accuracy.unattended`) and from the catalogue's bugs:

* **post-processing**: a box blur as ``F.conv2d(x, torch.ones(3, 3, 3, 3) / 9, padding=1)``, ``groups=3`` left out
  (every channel the sum of the three: grey); a box blur by ``F.avg_pool2d(x, 3, 1, 1)``, its ``count_include_pad``
  left on (the border darkened); an identity warp by ``affine_grid(..., align_corners=True)`` and ``grid_sample``
  (``align_corners`` False): the image shrunk a pixel, its border half faded; ``F.normalize(img, dim=1)`` taken for a
  min-max normalisation (every pixel's colour of length 1);
* **writing the file**: the codes saved with ``plt.imsave(..., origin='lower')`` (upside down); ``save_image(...,
  normalize=True)`` (stretched from the darkest value); 16-bit codes in ``int16`` given to ``cv2.imwrite``, which
  saturates them to 8 bits (bright black, dark white); a pitched GPU film (``cudaMallocPitch``) copied back as if
  packed (rows slipping into their padding);
* **materials**: a mask ``ids == MIRROR & hit`` (``&`` before ``==``: the ceiling a mirror, the mirror a white
  Lambertian); the colour table held channel-first and turned with ``reshape(9, 3)`` for ``.T``; each triangle's
  material by ``np.searchsorted(ends, t)`` (``side='left'``: every object's first triangle the previous object's);
* **geometry**: the walls' quads written into one array and appended (five walls missing); Möller-Trumbore's edges
  taken as ``np.diff(tri, axis=1)`` (``v2 - v1`` for ``v2 - v0``); the floor's corners set with ``.at[...].set``,
  its result discarded (JAX: no floor);
* **camera**: a CUDA kernel's row ``blockIdx.y * blockDim.x + threadIdx.y`` (every other band of rows black); the
  pixel grid from ``torch.meshgrid`` (``'ij'``: transposed); ``dr.select(pinhole, lens_ray, pinhole_ray)`` (a thin
  lens);
* **light model**: Mitsuba's ``scene.ray_test`` (True where blocked) taken for visibility; an 8-bit white times the
  power 20 in ``uint8`` (236 / 255); the light a Mitsuba ``rectangle`` scaled by its size (4 x 4);
* **integrator**: the bounce's numbers from ``torch.randn_like`` for ``rand_like`` (most bounces NaN, lost); the
  throughput ``np.ones_like`` of the pixel indices (integers: every path ended at its first diffuse bounce);
  roulette's survival ``beta.max(dim=1)[1]``, the channel's index; roulette's number drawn with the bounce's JAX key
  (its own ``u1``);
* **samples and passes**: a Numba ``prange`` over the pixels adding into an accumulator set once before it (each
  thread's previous pixels carried); pixel indices in ``uint8`` (wrapped into the first four rows);
  ``curand_init(seed, 0, 0, &state)`` in every thread (every pixel the same stream); Taichi's global ``SPP`` frozen
  at its preview's 48 (256 declared).

The correct hand-ins come in ways no class used: Mitsuba with the first bounce by Mitsuba's own
``mi.warp.square_to_cosine_hemisphere`` (Shirley and Chiu's concentric disk) in ``mi.Frame3f``, an 8-bit PNG by
``save_image(..., normalize=True, value_range=(0, 1))`` (a clamp), Mitsuba with the first bounce uniform on the
hemisphere (``torch.randn`` normalised, turned to the normal's side) weighted 2 cos, a binary PPM of a
``torch.channels_last`` tensor's storage, Mitsuba with the first vertex's light from a 4 x 4 lattice on the light
shifted by one random offset a pass (a Cranley-Patterson rotation), an 8-bit PNG from float codes that OpenCV rounds
and saturates, Mitsuba's samples summed in ``float32`` with Kahan's compensation, and an 8-bit PNG by Taichi's
``ti.tools.imwrite`` of a (width, height) field whose origin is the bottom left.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s ``edit``, ``sensor`` and ``mitsuba_edit``),
Mitsuba renders at another spp, Mitsuba's path integrator on rays a student's camera or mirror makes
(:func:`mcrt.grade.accuracy.unsaid._traced`) or with every lane's random numbers one stream (:func:`_one_stream`),
its first vertex's direct light redone as a student's light sample makes it
(:func:`mcrt.grade.accuracy.unheralded._first_vertex`), its first bounce redrawn
(:func:`mcrt.grade.accuracy.unprompted._first_bounce`), its samples, one by one, reweighted where a student's roulette
changes them (same-seed samples of max depth 2 and 8, :func:`mcrt.grade.accuracy.unbeknown._camera_samples`), or
correct renders post-processed and written with NumPy, Pillow, matplotlib and the standard library as students'
programs do. PyTorch, torchvision, JAX, Numba, Taichi, CUDA and OpenCV are not installed: what they do is emulated
with NumPy (their documented behaviour: ``conv2d``'s groups, ``avg_pool2d``'s padding count, ``grid_sample``'s
corners, ``normalize``'s norm, ``save_image``'s range, ``imwrite``'s conversion to 8 bits, a pitched copy, a Numba
reduction's private copies, a Taichi kernel's constants). mcrt renders none of it.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over :data:`CATEGORIES`: the 2nd, 4th, ... of
each category and of the correct hand-ins) are as in :mod:`~mcrt.grade.accuracy.unattended`, fixed before any case
was graded.
"""

from __future__ import annotations

import math
import zlib
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unattended, unbeknown,
                                 unbidden, unforeseen, unguessed, unheard, unheralded, unlooked, unmet, unnoticed,
                                 unprompted, unrecorded, unremarked, unremembered, unsaid, unseen, unsought, untold,
                                 untried, unvisited, unwonted)
from mcrt.grade.accuracy.cases import Spec
from mcrt.image_files import srgb_oetf

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


#: The classes after the first two, in the order they were written (their causes' words are this class's too).
_EARLIER = (programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked, unsought,
            unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted,
            unremarked, unremembered, unnoticed, unrecorded, unattended)


def _crc(name: str) -> int:
    return 1601000 + zlib.crc32(name.encode()) % 100000


_render = unseen._render
_posted = unseen._posted
_scene = unprompted._scene
_bsdf = unremarked._bsdf

#: The class's spp (the class is built at 64 x 64).
_S = 256
#: The assignment's maximum depth.
_DEPTH = 8


# --------------------------------------------------------------------------
# Post-processing (linear render in, what the program writes out)
# --------------------------------------------------------------------------


def _box_sums(x) -> np.ndarray:
    """Each value's 3 x 3 sum over its channel, the image padded with zeros (a convolution's ``padding=1``)."""
    img = np.asarray(x, np.float64)
    h, w = img.shape[:2]
    p = np.pad(img, ((1, 1), (1, 1), (0, 0)))
    return sum(p[a:a + h, b:b + w] for a in range(3) for b in range(3))


def _conv2d_groups_missing(x):
    """``F.conv2d(x, torch.ones(3, 3, 3, 3) / 9, padding=1)`` on the (1, 3, H, W) tensor, ``groups=3`` left out: the
    weight's (out, in) pairs all 1/9, so each output channel is the 3 x 3 box mean of all three input channels,
    summed (zero padding at the border)."""
    total = (_box_sums(x) / 9.0).sum(axis=2, keepdims=True)
    return np.repeat(total, 3, axis=2)


def _avg_pool_padded(x):
    """``F.avg_pool2d(x, 3, stride=1, padding=1)``: its ``count_include_pad`` defaults to True, so every 3 x 3 sum,
    the border's with the zero padding in it, is divided by 9."""
    return _box_sums(x) / 9.0


def _corners_mixed(n: int) -> np.ndarray:
    """The source pixel (centres at 0 .. n - 1) that output pixel i samples when ``affine_grid(theta, size,
    align_corners=True)`` (the identity: x_n = -1 + 2 i / (n - 1)) meets ``grid_sample(img, grid)`` (``align_corners``
    False: pixel ((x_n + 1) n - 1) / 2): i n / (n - 1) - 1/2."""
    i = np.arange(n, dtype=np.float64)
    return i * n / (n - 1) - 0.5


def _bilinear_rows(pos: np.ndarray, n: int) -> np.ndarray:
    """(len(pos), n): the bilinear weights of each position over n pixels, those outside the image dropped
    (``padding_mode='zeros'``)."""
    m = np.zeros((len(pos), n))
    i0 = np.floor(pos).astype(int)
    f = pos - i0
    for k, (a, t) in enumerate(zip(i0, f)):
        for j, wgt in ((a, 1.0 - t), (a + 1, t)):
            if 0 <= j < n:
                m[k, j] += wgt
    return m


def _grid_sample_corners_mixed(x):
    """The render passed through ``grid_sample(img, affine_grid(identity, size, align_corners=True))``, bilinear with
    zero padding: the image shrunk by (n - 1) / n about its centre, the border rows and columns half faded."""
    img = np.asarray(x, np.float64)
    h, w = img.shape[:2]
    rows, cols = _bilinear_rows(_corners_mixed(h), h), _bilinear_rows(_corners_mixed(w), w)
    return np.einsum("ij,jkc,lk->ilc", rows, img, cols)


def _normalized_per_pixel(x, *, eps: float = 1e-12):
    """``F.normalize(img, dim=1)`` on the (1, 3, H, W) tensor: each pixel's colour divided by its Euclidean length
    (at least ``eps``)."""
    img = np.asarray(x, np.float64)
    return img / np.maximum(np.linalg.norm(img, axis=2, keepdims=True), eps)


# --------------------------------------------------------------------------
# Writers (the render in, the file a program writes)
# --------------------------------------------------------------------------


def _write_png_imsave_origin_lower(image: np.ndarray, folder: Path) -> Path:
    """The 8-bit sRGB codes saved by ``matplotlib.pyplot.imsave(path, codes, origin='lower')``: matplotlib turns the
    rows over for that origin (an RGBA PNG, alpha opaque)."""
    from matplotlib.image import imsave

    path = folder / "render.png"
    imsave(path, blind._srgb8(image), format="png", origin="lower")
    return path


def _save_image_codes(image: np.ndarray, *, value_range: tuple[float, float] | None = None) -> np.ndarray:
    """The 8-bit codes ``torchvision.utils.save_image(t, path, normalize=True, value_range=...)`` writes of the
    sRGB-encoded tensor (values past 1 where the render is): ``make_grid`` clamps to the range (the tensor's own
    minimum and maximum when none is given) and maps it onto [0, 1], then ``mul(255).add_(0.5).clamp_(0, 255)`` is
    cast to ``uint8``."""
    s = srgb_oetf(np.maximum(np.nan_to_num(np.asarray(image, np.float64)), 0.0))
    lo, hi = value_range if value_range is not None else (float(s.min()), float(s.max()))
    v = (np.clip(s, lo, hi) - lo) / max(hi - lo, 1e-5)
    return np.floor(np.clip(v * 255.0 + 0.5, 0.0, 255.0)).astype(np.uint8)


def _write_png_save_image_normalize(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_save_image_codes(image), folder)


def _write_png_save_image_value_range(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_save_image_codes(image, value_range=(0.0, 1.0)), folder)


def _cv2_int16_codes(image: np.ndarray) -> np.ndarray:
    """What ``cv2.imwrite`` writes of 16-bit sRGB codes cast to ``int16`` (``np.round(v * 65535).astype(np.int16)``,
    PyTorch's ``.to(torch.int16)`` before it had ``uint16``): the codes from 32768 wrap to negatives, and OpenCV, whose
    PNG writer takes 8 or 16 unsigned bits only, converts the signed image to 8 bits with saturation: min(code, 255)
    below 32768, 0 from there."""
    v = np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 1.0)
    c16 = np.floor(srgb_oetf(v) * 65535.0 + 0.5).astype(np.int64)
    signed = (c16 + 32768) % 65536 - 32768
    return np.clip(signed, 0, 255).astype(np.uint8)


def _write_png_cv2_int16(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_cv2_int16_codes(image), folder)


def _cv2_float_codes(image: np.ndarray) -> np.ndarray:
    """What ``cv2.imwrite`` writes of the sRGB values times 255 as ``float32`` (BGR, unclipped): OpenCV converts a
    float image to 8 bits with ``saturate_cast``, rounding (half to even) and clamping to 0 .. 255."""
    s = srgb_oetf(np.maximum(np.nan_to_num(np.asarray(image, np.float64)), 0.0))
    return np.clip(np.rint((s * 255.0).astype(np.float32)), 0.0, 255.0).astype(np.uint8)


def _write_png_cv2_float(image: np.ndarray, folder: Path) -> Path:
    from PIL import Image

    path = folder / "render.png"
    Image.fromarray(_cv2_float_codes(image), "RGB").save(path, format="PNG", compress_level=1)
    return path


#: The row alignment of ``cudaMallocPitch`` (bytes).
_PITCH_ALIGN = 512


def _pitch_ignored(x, *, align: int = _PITCH_ALIGN):
    """A float3 film in a pitched GPU buffer (each row of W pixels, 12 W bytes, padded to the next multiple of
    ``align``; the padding never written, zeros in a fresh allocation) copied back with ``cudaMemcpy(host, dev, W H
    sizeof(float3))``: the first 12 W H bytes read as packed rows."""
    img = np.asarray(x, np.float32)
    h, w = img.shape[:2]
    row = 3 * w
    pitch = -(-4 * row // align) * align // 4
    dev = np.zeros(h * pitch, np.float32)
    for r in range(h):
        dev[r * pitch:r * pitch + row] = img[r].reshape(-1)
    return dev[:h * row].reshape(h, w, 3).astype(np.float64)


def _write_ppm_channels_last(image: np.ndarray, folder: Path) -> Path:
    """A binary PPM whose raster is the raw storage of a (1, 3, H, W) ``uint8`` tensor in ``torch.channels_last``
    memory format (``bytes(t.untyped_storage())``): NHWC in memory, each pixel's R, G, B together."""
    h, w = image.shape[:2]
    nchw = blind._srgb8(image).transpose(2, 0, 1)[None]  # the tensor's logical (N, C, H, W)
    storage = np.ascontiguousarray(nchw.transpose(0, 2, 3, 1))  # channels_last: its memory in N, H, W, C order
    path = folder / "render.ppm"
    path.write_bytes(unheard._ppm_header(w, h) + storage.tobytes())
    return path


def _taichi_imwrite_codes(field_wh: np.ndarray) -> np.ndarray:
    """What ``ti.tools.imwrite(field, path)`` writes of a float (W, H, 3) array whose origin is the bottom left:
    ``(clip(v, 0, 1) * 255 + 0.5)`` cast to ``uint8``, then turned to rows from the top (``swapaxes(0, 1)[::-1]``)."""
    codes = (np.clip(np.asarray(field_wh, np.float64), 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)
    return np.ascontiguousarray(codes.swapaxes(0, 1)[::-1])


def _write_png_taichi_field(image: np.ndarray, folder: Path) -> Path:
    """The sRGB values in a Taichi field of shape (W, H), pixel (i, j) the column i and the row j from the bottom,
    saved with ``ti.tools.imwrite``."""
    s = srgb_oetf(np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 1.0))
    field = s[::-1].swapaxes(0, 1)
    return novel._write_png(_taichi_imwrite_codes(field), folder)


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------

#: The students' surface ids, in the scene file's order: the floor, the ceiling, walls AB to FA, the tetrahedron, the
#: sphere.
_IDS = ("floor", "ceiling", "wall_AB", "wall_BC", "wall_CD", "wall_DE", "wall_EF", "wall_FA", "tetrahedron",
        "sphere")


def _mask_precedence(ids: np.ndarray, hit: np.ndarray, mirror: int = _IDS.index("sphere")) -> np.ndarray:
    """``ids == MIRROR & hit`` as NumPy evaluates it: ``&`` binds before ``==``, so ``ids == (MIRROR & hit)``, the
    id 1 where a ray hits anything (9 & True), 0 where it does not."""
    return ids == (mirror & hit)


def _ceiling_mirror_sphere_white(d: dict) -> dict:
    """The materials the mask of :func:`_mask_precedence` gives: the ceiling (id 1) reflecting as the mirror
    (weight 1), the sphere shaded as a Lambertian of its table entry, the mirror's (1, 1, 1)."""
    mirror = {"type": "twosided", "bsdf": {"type": "conductor", "material": "none"}}
    d = fresh._rebuilt(d, "ceiling", fresh._surface("ceiling").triangles, mirror)
    return blind._sphere_bsdf(d, {"type": "diffuse", "reflectance": {"type": "rgb", "value": [1.0, 1.0, 1.0]}})


def _channel_first_reshaped(s) -> list[tuple[float, ...]]:
    """The colour table (floor, ceiling, walls AB to FA, tetrahedron) held channel-first, a (3, 9) array, and turned
    with ``.reshape(9, 3)`` for ``.T``: colour k the numbers 3 k to 3 k + 2 of the reds, then the greens, then the
    blues."""
    table = np.asarray(unbidden._colour_table(s), np.float64)
    return [tuple(float(c) for c in row) for row in table.T.reshape(-1, 3)]


def _albedos_reshaped(s):
    wrong = iter(_channel_first_reshaped(s))
    return unbidden._albedos_mapped(s, lambda _: next(wrong))


def _triangle_materials() -> tuple[list, np.ndarray, np.ndarray]:
    """The students' triangle list (the scene's surfaces but the light, in order), each triangle's surface and the
    surface ``np.searchsorted(ends, t)`` gives it, ``ends`` the surfaces' cumulative triangle counts and ``side``
    left at 'left' (for 'right'): the first triangle of each surface but the first taken for the surface before."""
    surfaces = [sf for sf in _scene().surfaces() if sf.material is not None]
    counts = [len(sf.triangles) for sf in surfaces]
    own = np.repeat(np.arange(len(surfaces)), counts)
    read = np.searchsorted(np.cumsum(counts), np.arange(sum(counts)))
    return surfaces, own, read


def _materials_searchsorted(d: dict) -> dict:
    """Each surface's triangles given the materials :func:`_triangle_materials` reads for them."""
    surfaces, own, read = _triangle_materials()
    tris = np.concatenate([np.asarray(sf.triangles, np.float64) for sf in surfaces])
    for k, sf in enumerate(surfaces):
        mine = own == k
        d = fresh._rebuilt(d, sf.name, tris[mine & (read == k)], _bsdf(sf.material))
        for j in np.unique(read[mine & (read != k)]):
            d = fresh._rebuilt(d, f"{sf.name}_as_{surfaces[j].name}", tris[mine & (read == j)],
                               _bsdf(surfaces[j].material))
    return d


def _walls_one_array(d: dict) -> dict:
    """The walls' quads written into one array in the loop over the walls and appended without a copy: six
    references to the last wall's quad, FA's, the nearest-hit test keeping the first of equal hits (``t < t_best``),
    the first wall's colour, AB's: walls AB to EF gone, wall FA red."""
    for wall in _scene().room.walls[:-1]:
        d = fresh._without_mesh(d, "wall_" + "".join(wall.corners))
    return fresh._rebuilt(d, "wall_FA", fresh._surface("wall_FA").triangles,
                          _bsdf(fresh._surface("wall_AB").material))


def _diff_edge_triangles(tris) -> np.ndarray:
    """(n, 3, 3): the region Möller-Trumbore's test accepts when its edges are ``e1, e2 = np.diff(tri, axis=1)``
    (``v1 - v0`` and ``v2 - v1``) for ``v1 - v0`` and ``v2 - v0``: the triangle (v0, v0 + e1, v0 + e2) = (v0, v1, v0 +
    v2 - v1), in the same plane."""
    t = np.asarray(tris, np.float64)
    e = np.diff(t, axis=1)
    return np.stack([t[:, 0], t[:, 0] + e[:, 0], t[:, 0] + e[:, 1]], axis=1)


def _triangles_diff_edges(d: dict) -> dict:
    """Every triangle of the room and the tetrahedron as :func:`_diff_edge_triangles` makes it (the light, a
    rectangle, tested by its own bounds)."""
    for sf in _scene().surfaces():
        if sf.material is not None:
            d = fresh._rebuilt(d, sf.name, _diff_edge_triangles(sf.triangles), _bsdf(sf.material))
    return d


def _floor_discarded(d: dict) -> dict:
    """The floor's corners made as ``jnp.full((6, 3), floor_z)`` and their x and y set with
    ``floor.at[:, :2].set(corners)``, its result discarded: every corner (-5, -5, -5), a fan of no area."""
    return fresh._without_mesh(d, "floor")


#: The light's colour as an 8-bit white times its integer power, ``colour * power / 255`` in ``uint8``: 255 * 20 =
#: 5100 wraps to 236.
_WRAPPED_RADIANCE = tuple(float(c) for c in np.full(3, 255, np.uint8) * 20 / 255)

#: Mitsuba's ``rectangle`` spans [-1, 1]^2 (two units a side); scaled by the light's size (2, 2), it is 4 x 4.
_RECTANGLE_SIZE = (4.0, 4.0)

#: The thin lens the camera's unused branch builds (its class's defaults): aperture radius 0.05, focused at 1 (the
#: image plane).
_LENS = {"type": "thinlens", "aperture_radius": 0.05, "focus_distance": 1.0}


# --------------------------------------------------------------------------
# The camera and the launch grid
# --------------------------------------------------------------------------

#: The CUDA kernel's thread blocks, 16 x 8 threads.
_BLOCK = (16, 8)


def _rows_written(h: int, block: tuple[int, int] = _BLOCK) -> np.ndarray:
    """(h,) whether the kernel writes each row when its row is ``blockIdx.y * blockDim.x + threadIdx.y`` (blockDim.x
    for blockDim.y), the grid ``H / blockDim.y`` blocks high and the rows past H skipped by the bounds test."""
    bx, by = block
    written = np.zeros(h, bool)
    for b in range(-(-h // by)):
        for t in range(by):
            if b * bx + t < h:
                written[b * bx + t] = True
    return written


def _blockdim_typo(x):
    """The rows :func:`_rows_written` says the kernel writes, the others left 0 (``cudaMemset``)."""
    img = np.array(x, np.float64)
    img[~_rows_written(img.shape[0])] = 0.0
    return img


def _meshgrid_ij(x):
    """The pixel grid ``xs, ys = torch.meshgrid(torch.arange(W), torch.arange(H))`` (PyTorch's default indexing 'ij',
    where NumPy's is 'xy'): film[a, b] traced through column a and row b, saved as row a, column b."""
    img = np.asarray(x, np.float64)
    h, w = img.shape[:2]
    xs, ys = np.meshgrid(np.arange(w), np.arange(h), indexing="ij")
    return img[ys, xs]


# --------------------------------------------------------------------------
# Light samples at the first vertex (unheralded._first_vertex's ``direct``)
# --------------------------------------------------------------------------


def _blocked(mscene, p, wi, dist):
    """Mitsuba's ``scene.ray_test(shadow_ray)``: True where something lies between the point and the light's."""
    return unheralded._occluded(mscene, p, wi, dist * (1.0 - 1e-4))


def _light_where_blocked(mscene, rng, p, n, rho, mitsuba):
    """The light sample counted where :func:`_blocked` is True (``dr.select(scene.ray_test(ray), Ld, 0)``)."""
    return rho * unheralded._light_sample(mscene, rng, p, n, _blocked)


#: The lattice of the correct hand-in's light samples, k x k points.
_LATTICE = 4


def _lattice_points(shift, k: int = _LATTICE) -> np.ndarray:
    """(k k, 3): the points ((i + s0) / k mod 1, (j + s1) / k mod 1) of the light's square, ``shift`` (s0, s1) one
    random offset (a Cranley-Patterson rotation of the lattice: each point uniform on the light)."""
    lt = _scene().light
    i, j = np.meshgrid(np.arange(k), np.arange(k), indexing="ij")
    u = np.mod((i.reshape(-1) + shift[0]) / k, 1.0)
    v = np.mod((j.reshape(-1) + shift[1]) / k, 1.0)
    return np.stack([lt.center[0] + (u - 0.5) * lt.size[0], lt.center[1] + (v - 0.5) * lt.size[1],
                     np.full(k * k, lt.center[2])], axis=1)


def _light_rotated_lattice(mscene, rng, p, n, rho, mitsuba, *, k: int = _LATTICE):
    """The first vertex's light from the k x k points of :func:`_lattice_points` (one shift a pass, shared by every
    vertex: ``torch.rand(2)``), averaged."""
    lt = _scene().light
    g = np.zeros(len(p))
    for q in _lattice_points(rng.random(2), k):
        qq = np.broadcast_to(q, p.shape)
        g += np.where(unbeknown._unblocked(mscene, p, qq), unbeknown._geometry(p, n, qq), 0.0)
    return rho * (g / (k * k) * lt.area / math.pi)[:, None] * np.asarray(lt.radiance, np.float64)


def _light_sample(name: str, direct) -> dict:
    """A spec's post-process: Mitsuba's path with its first vertex's light sample made by ``direct``."""
    return _posted(name, partial(unheralded._first_vertex, spp=_S, seed=_crc(name), direct=direct))


# --------------------------------------------------------------------------
# Bounces, roulette and paths
# --------------------------------------------------------------------------


def _cosine_from(u1, u2, n):
    """Malley's cosine-weighted directions from the numbers (u1, u2) about the normals ``n``: r = sqrt(u1), z =
    sqrt(1 - u1), the azimuth 2 pi u2 (numbers outside [0, 1] clipped: the caller marks them)."""
    r = np.sqrt(np.clip(u1, 0.0, 1.0))
    z = np.sqrt(np.clip(1.0 - u1, 0.0, 1.0))
    phi = 2.0 * math.pi * u2
    t, b = unforeseen._frame_of(n)
    return unsaid._unit((r * np.cos(phi))[:, None] * t + (r * np.sin(phi))[:, None] * b + z[:, None] * n)


def _randn_like_bounce(rng, n):
    """The bounce's (u1, u2) from ``torch.randn_like`` for ``torch.rand_like``: normal numbers; where u1 < 0 or u1 >
    1 a square root is NaN, the ray meets nothing and the path ends (weight 0); the rest, u1 in [0, 1] with a normal's
    density (more near 0: near the normal), weighted by the albedo as cosine samples."""
    u1, u2 = rng.standard_normal((2, len(n)))
    ok = (u1 >= 0.0) & (u1 <= 1.0)
    return np.where(ok[:, None], _cosine_from(u1, u2, n), n), ok.astype(np.float64)


#: The survival probability of the roulette whose number is the bounce's.
_SURVIVAL = 0.8


def _roulette_on_u1(rng, n, *, p: float = _SURVIVAL):
    """A cosine-weighted bounce from (u1, u2) followed by Russian roulette with survival ``p`` whose number is
    ``jax.random.uniform(subkey, (n, 2))[:, 0]`` with the bounce's subkey (its split forgotten): u1 itself, so only
    the bounces with u1 < p (within asin(sqrt(p)) of the normal) survive, divided by p."""
    u1, u2 = rng.random((2, len(n)))
    return _cosine_from(u1, u2, n), np.where(u1 < p, 1.0 / p, 0.0)


def _uniform_hemisphere(rng, n):
    """A direction uniform on the hemisphere (``torch.randn`` normalised, turned to the normal's side), weighted
    f cos / pdf = (albedo / pi) cos 2 pi: 2 cos times the albedo."""
    v = unsaid._unit(rng.standard_normal((len(n), 3)))
    cos = np.einsum("ij,ij->i", v, n)
    v = np.where((cos < 0.0)[:, None], -v, v)
    return v, 2.0 * np.abs(cos)


def _concentric_disk(u1, u2):
    """Shirley and Chiu's concentric map of the square to the unit disk (``mi.warp.square_to_uniform_disk_concentric``):
    (x, y)."""
    a, b = 2.0 * np.asarray(u1) - 1.0, 2.0 * np.asarray(u2) - 1.0
    first = np.abs(a) > np.abs(b)
    r = np.where(first, a, b)
    safe = np.where(first, np.where(a == 0.0, 1.0, a), np.where(b == 0.0, 1.0, b))
    phi = np.where(first, (math.pi / 4.0) * b / safe, math.pi / 2.0 - (math.pi / 4.0) * a / safe)
    return r * np.cos(phi), r * np.sin(phi)


def _frame3f(n):
    """Mitsuba's ``Frame3f(n)`` (its ``coordinate_system``, Duff et al.'s): (s, t)."""
    sign = np.where(n[:, 2] >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + n[:, 2])
    b = n[:, 0] * n[:, 1] * a
    s = np.stack([1.0 + sign * n[:, 0] ** 2 * a, sign * b, -sign * n[:, 0]], axis=1)
    t = np.stack([b, sign + n[:, 1] ** 2 * a, -n[:, 1]], axis=1)
    return s, t


def _warp_cosine(rng, n):
    """``mi.warp.square_to_cosine_hemisphere`` (the concentric disk lifted, z = sqrt(1 - x^2 - y^2)) taken to the
    world by ``mi.Frame3f(n).to_world``: cosine-weighted, weight 1."""
    u1, u2 = rng.random((2, len(n)))
    x, y = _concentric_disk(u1, u2)
    z = np.sqrt(np.maximum(1.0 - x * x - y * y, 0.0))
    s, t = _frame3f(n)
    return unsaid._unit(x[:, None] * s + y[:, None] * t + z[:, None] * n), np.ones(len(n))


def _bounce(name: str, draw) -> dict:
    """A spec's post-process: Mitsuba's path with its first bounce drawn by ``draw``."""
    return _posted(name, partial(unprompted._first_bounce, spp=_S, seed=_crc(name), draw=draw))


def _reflected_same_depth(o, d):
    """Camera rays reflected by the mirror where they meet it (the rest as they are), the segment not counted: a
    path through the mirror cut as one from the camera."""
    o2, d2, _ = unsaid._reflected(o, d)
    return o2, d2, np.zeros(len(o), int)


def _ended_at_first_diffuse(x, *, spp: int, seed: int):
    """The throughput an integer array (``np.ones_like`` of the pixel indices) updated as ``beta[alive] =
    beta[alive] * weight[alive]``: the float product cast back to integers, 0 after the first diffuse bounce
    (albedos under 1), 1 through the mirror: each path's light that of its first diffuse vertex (its light sample)
    and the emission it sees before it: Mitsuba's max-depth-2 samples, from the mirror where a camera ray meets it."""
    return unsaid._traced(x, spp=spp, seed=seed, after=_reflected_same_depth, max_depth=2)


def _max_index_weight(beta: np.ndarray, u: np.ndarray) -> np.ndarray:
    """(N,) the weight Russian roulette gives a path of throughput ``beta`` (N, 3) with survival ``p =
    beta.max(dim=1)[1]``: the index of its first largest channel, 0, 1 or 2, for its value; ``u < p`` with u in [0,
    1): never for 0, always for 1 and 2, the survivors divided by p."""
    p = np.argmax(beta, axis=1).astype(np.float64)
    return np.where(u < p, 1.0 / np.where(p > 0.0, p, 1.0), 0.0)


def _max_indices_sample(o, d, seed, *, full, direct):
    """A sample whose path meets :func:`_max_index_weight`'s roulette at its first bounce (its throughput the first
    hit's albedo): L2 + (L8 - L2) times the weight."""
    L, near = unsaid._sampled(full, o, d, seed), unsaid._sampled(direct, o, d, seed)
    rho = unsaid._first_albedo(full, o, d)
    diffuse = rho.max(axis=1) > 0.0
    weight = _max_index_weight(rho, np.random.default_rng(seed + 41).random(len(rho)))
    return np.where(diffuse[:, None], near + (L - near) * weight[:, None], L)


def _roulette_max_indices(x, *, spp: int, seed: int):
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(
        _max_indices_sample, full=unsaid._loaded(_DEPTH), direct=unsaid._loaded(2)))


# --------------------------------------------------------------------------
# Samples and passes
# --------------------------------------------------------------------------

#: Numba's threads (the machine's cores) sharing the ``prange`` over the pixels, a block each.
_THREADS = 8


def _prange_private_sums(x, *, threads: int = _THREADS):
    """Each pixel's samples added into ``acc``, set to 0 once before ``for p in prange(W * H)``, ``img[p] = acc /
    spp``: Numba takes ``acc += L`` for a reduction, each thread a private copy from 0 over its block of pixels (the
    pixels in row order split in ``threads`` equal blocks): every pixel the sum of the means of its block's pixels up
    to it."""
    img = np.asarray(x, np.float64)
    h, w = img.shape[:2]
    flat = img.reshape(h * w, 3)
    out = np.empty_like(flat)
    for block in np.array_split(np.arange(h * w), threads):
        out[block] = np.cumsum(flat[block], axis=0)
    return out.reshape(h, w, 3)


def _uint8_indices(x):
    """The pixel indices from ``np.indices((H, W), dtype=np.uint8)`` and the film's flat index ``ys * W + xs`` in
    ``uint8`` (wrapping at 256), each pixel's mean written there (``film[idx] = L``, the last write winning), the
    pixels never written 0."""
    img = np.asarray(x, np.float64)
    h, w = img.shape[:2]
    ys, xs = np.indices((h, w), dtype=np.uint8)
    idx = ys * np.uint8(w) + xs
    film = np.zeros((h * w, 3))
    film[idx.reshape(-1).astype(np.int64)] = img.reshape(-1, 3)
    return film.reshape(h, w, 3)


def _sampled_one_stream(mscene, o: np.ndarray, d: np.ndarray, seed: int) -> np.ndarray:
    """(N, 3): one radiance sample of each ray by the scene's integrator, its sampler seeded for one lane: every
    lane draws that lane's numbers, the same random numbers in every ray."""
    import drjit as dr
    import mitsuba as mi

    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(dr.opaque(mi.UInt32, seed), 1)
    L = mscene.integrator().sample(mscene, sampler, mi.RayDifferential3f(unsaid._rays(o, d)), None, True)[0]
    return np.broadcast_to(np.stack([np.array(L[c], np.float64) for c in range(3)], axis=-1), (len(o), 3))


def _one_stream(x, *, spp: int, seed: int):
    """``curand_init(seed, 0, 0, &state)`` in every thread (the sequence number 0 where the pixel's index belongs):
    every pixel draws the same stream, its k-th sample's sub-pixel offset and path the same random numbers as every
    other pixel's k-th (each pixel's samples independent of each other): Mitsuba's path, one sample index at a time,
    on rays through one offset, with :func:`_sampled_one_stream`."""
    from mcrt.mitsuba_scene import pass_seed

    h, w = x.shape[:2]
    mscene = unsaid._loaded(_DEPTH)
    rng = np.random.default_rng(seed)
    jj, ii = np.divmod(np.arange(w * h), w)
    total = np.zeros((h * w, 3))
    for k in range(spp):
        u, v = rng.random(2)
        o, d = unsaid._pinhole((ii + u) / w, (jj + v) / h)
        total += _sampled_one_stream(mscene, np.array(o, np.float64), np.asarray(d, np.float64), pass_seed(seed, k))
    return (total / spp).reshape(h, w, 3)


#: The preview's spp a Taichi kernel froze (Taichi compiles a Python global into the kernel as a constant).
_FROZEN_SPP = 48


def _kahan_float32(x, *, spp: int, seed: int):
    """Mitsuba's samples summed in ``float32`` with Kahan's compensation (a Numba kernel's loop), divided by the
    spp."""
    h, w = x.shape[:2]
    L = unbidden._all_samples(w, h, spp, seed).astype(np.float32)
    total, carry = np.zeros((h * w, 3), np.float32), np.zeros((h * w, 3), np.float32)
    for k in range(spp):
        y = L[:, k] - carry
        t = total + y
        carry = (t - total) - y
        total = t
    return (total / np.float32(spp)).astype(np.float64).reshape(h, w, 3)


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_torch_conv2d_groups_missing", "pp_torch_avg_pool_pad_counted",
                        "pp_torch_grid_sample_corners_mixed", "pp_torch_normalize_per_pixel"),
    "file": ("file_png_imsave_origin_lower", "file_png_save_image_normalize", "file_png_cv2_int16_saturated",
             "file_exr_cuda_pitch_ignored"),
    "materials": ("materials_mask_precedence", "albedos_channel_first_reshaped", "materials_searchsorted_left"),
    "geometry": ("walls_one_quad_array", "triangles_np_diff_edges", "floor_jax_at_discarded"),
    "camera": ("rows_cuda_blockdim_typo", "pixels_torch_meshgrid_ij", "camera_drjit_select_swapped"),
    "light": ("light_ray_test_as_visible", "light_uint8_colour_times_power", "light_mitsuba_rectangle_scaled"),
    "integrator": ("bounce_torch_randn_like", "throughput_int_ones_like", "roulette_torch_max_indices",
                   "roulette_jax_key_reused"),
    "samples": ("pixels_numba_prange_accumulator", "pixels_uint8_indices", "samples_curand_sequence_zero",
                "spp_taichi_frozen_global"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_torch_conv2d_groups_missing", "colour_lost", True, **_posted("conv2d_groups", _conv2d_groups_missing),
             truth="a 3 x 3 box blur against the noise written as torch.nn.functional.conv2d(x, torch.ones(3, 3, 3, "
             "3) / 9, padding=1) on the (1, 3, H, W) tensor, groups=3 left out: every output channel the box mean of "
             "all three input channels summed: the image grey, about three times as bright, blurred, its border "
             "pixels darker (the zero padding), as EXR"),
        Spec("pp_torch_avg_pool_pad_counted", "blur", held_out=True, **_posted("avg_pool_padded", _avg_pool_padded),
             truth="a 3 x 3 box blur against the noise written as torch.nn.functional.avg_pool2d(x, 3, stride=1, "
             "padding=1), its count_include_pad left True (the default): every 3 x 3 sum divided by 9, the zero "
             "padding counted at the border: the image blurred, its first and last rows and columns two thirds as "
             "bright, its corners four ninths, as EXR"),
        Spec("pp_torch_grid_sample_corners_mixed", "resampling", **_posted(
            "grid_sample_corners", _grid_sample_corners_mixed),
             truth="the render passed through a viewer's zoom step left at zoom 1, torch's affine_grid(theta, size, "
             "align_corners=True) with theta the identity and grid_sample(img, grid), whose align_corners defaults "
             "to False: each pixel sampled bilinearly at i W / (W - 1) - 1/2: the image shrunk by 63/64 about its "
             "centre, slightly blurred, its border rows and columns half faded into the zero padding (the corners a "
             "quarter), as EXR"),
        Spec("pp_torch_normalize_per_pixel", "normalised", True, held_out=True, **_posted(
            "normalize_per_pixel", _normalized_per_pixel),
             truth="the render 'normalised to [0, 1]' for display with torch.nn.functional.normalize(img, dim=1) on "
             "the (1, 3, H, W) tensor, which divides each pixel's colour by its Euclidean length: every pixel a "
             "colour of length 1 (the greys and the light 0.577), the shading, the shadows and the light's "
             "brightness gone, each pixel's hue and saturation left, as EXR"),
        # Writing the file
        Spec("file_png_imsave_origin_lower", "orientation", True, writer=_write_png_imsave_origin_lower,
             file="png-imsave-origin-lower",
             truth="the 8-bit sRGB codes saved with matplotlib's plt.imsave(path, codes, origin='lower') (taken for "
             "'the origin at the lower left, as in the maths'), the image's row 0 its top: matplotlib turns the "
             "rows over for that origin: an RGBA PNG upside down, the floor at the top"),
        Spec("file_png_save_image_normalize", "normalised", True, held_out=True, writer=_write_png_save_image_normalize,
             file="png-save-image-normalize",
             truth="the sRGB-encoded tensor saved with torchvision.utils.save_image(img, path, normalize=True) "
             "(copied from a GAN tutorial): make_grid maps the values from their minimum (the darkest channel's, a "
             "few hundredths) to their maximum (the light's, past 1) onto [0, 1] before the 8-bit PNG: the room far "
             "too dark (its sRGB values divided by about 3.6), the light white"),
        Spec("file_png_cv2_int16_saturated", "code_overflow", True, writer=_write_png_cv2_int16,
             file="png-cv2-int16",
             truth="16-bit sRGB codes cast with .astype(np.int16) (a port of PyTorch's .to(torch.int16), it had no "
             "uint16) and handed to cv2.imwrite for a 16-bit PNG: the codes from 32768 (sRGB 0.5 and up) wrap to "
             "negatives, and OpenCV, whose PNG writer takes 8 or 16 unsigned bits, converts the signed image to 8 "
             "bits with saturation: every sRGB value from 1/256 to 1/2 written 255, from 1/2 up 0: an 8-bit PNG "
             "almost all white, black wherever the linear value is 0.214 or more (the light, its reflection, the "
             "brightest patches)"),
        Spec("file_exr_cuda_pitch_ignored", "row_stride", True, held_out=True, **_posted(
            "cuda_pitch_ignored", _pitch_ignored),
             truth="the float3 film allocated on the GPU with cudaMallocPitch (each row of 64 pixels, 768 bytes, "
             "padded to a pitch of 1024) and copied back with cudaMemcpy(host, dev, W * H * sizeof(float3)) for "
             "cudaMemcpy2D: rows read 768 bytes apart where they lie 1024 apart: every 4 rows of the image holding 3 "
             "of the render's cut up by their 256 bytes of padding (zeros, never written): black gaps, rows shifted "
             "by a third or two thirds of their width, the view squeezed to three quarters of the height, the "
             "render's last 16 rows never read, as EXR"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("materials_mask_precedence", "material", True, mitsuba_edit=_ceiling_mirror_sphere_white,
             truth="the mirror's lanes picked with is_mirror = ids == MIRROR & hit (NumPy's & binds before ==): ids "
             "== (9 & hit), 1 wherever a ray hits: the surface of id 1, the ceiling, reflecting as the perfect "
             "mirror, the sphere (id 9) shaded as a Lambertian of its table entry, white (1, 1, 1): a mirror "
             "ceiling showing the room upside down, a white ball"),
        Spec("albedos_channel_first_reshaped", "albedo", True, held_out=True, edit=_albedos_reshaped,
             truth="the colour table (floor, ceiling, walls AB to FA, tetrahedron) held channel-first as a (3, 9) "
             "tensor and turned into a colour a row with .reshape(9, 3) for .T: the floor (0.6, 0.8, 0.75), the "
             "ceiling (0.55, 0.75, 0.15), AB (0.15, 0.15, 0.8), BC (0.6, 0.8, 0.15), CD (0.15, 0.7, 0.2), DE (0.7, "
             "0.65, 0.45), EF (0.6, 0.8, 0.15), FA (0.7, 0.15, 0.75), the tetrahedron green (0.15, 0.7, 0.1)"),
        Spec("materials_searchsorted_left", "albedo", True, mitsuba_edit=_materials_searchsorted,
             truth="each triangle's material found with np.searchsorted(ends, t), ends the surfaces' cumulative "
             "triangle counts (walls AB to FA, the floor, the ceiling, the tetrahedron), its side left at 'left' "
             "for 'right': the first triangle of every surface but the first given the surface before's material: "
             "each wall split along its diagonal, half in the previous wall's colour, the floor's first triangle (A, "
             "B, C) wall FA's cyan, the ceiling's first the floor's grey, a face of the tetrahedron the ceiling's "
             "white"),
        # Geometry
        Spec("walls_one_quad_array", "object_missing", True, mitsuba_edit=_walls_one_array,
             truth="the walls' quads written into one array, quad[:] = ..., and appended to the list in the loop "
             "over the walls without a copy: six references to the last wall's quad, FA's, the nearest-hit test "
             "keeping the first of equal hits (t < t_best), wall AB's colour: walls AB to EF missing, the void "
             "seen where they stand, wall FA (behind the camera, in the mirror) red"),
        Spec("triangles_np_diff_edges", "object_shape", True, held_out=True, mitsuba_edit=_triangles_diff_edges,
             truth="Möller-Trumbore's edges taken as e1, e2 = np.diff(tri, axis=1), v1 - v0 and v2 - v1, for v1 - "
             "v0 and v2 - v0: every triangle of the room and the tetrahedron the triangle (v0, v1, v0 + v2 - v1) in "
             "its own plane: parts of every wall, of the floor and of the ceiling missing (the void seen through "
             "them), slivers standing past the room's corners, the tetrahedron misshapen"),
        Spec("floor_jax_at_discarded", "object_missing", True, mitsuba_edit=_floor_discarded,
             truth="the floor's corners made as jnp.full((6, 3), z_floor) and their x and y set with "
             "floor.at[:, :2].set(corners), its result never assigned (JAX arrays are immutable): every corner "
             "(-5, -5, -5), a fan of no area: the floor missing, the void below the room, the objects standing on "
             "nothing"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    return (
        # Camera
        Spec("rows_cuda_blockdim_typo", "bad_pixels", True, **_posted("blockdim_typo", _blockdim_typo),
             truth="the CUDA kernel's row computed as blockIdx.y * blockDim.x + threadIdx.y (blockDim.x for "
             "blockDim.y, the blocks 16 x 8 threads, the grid H / 8 blocks high): rows 16 b to 16 b + 7 written, "
             "rows 16 b + 8 to 16 b + 15 never, left 0 (cudaMemset), the rows past the image skipped: the image in "
             "bands of 8 rows, every other band black"),
        Spec("pixels_torch_meshgrid_ij", "orientation", True, held_out=True, **_posted("meshgrid_ij", _meshgrid_ij),
             truth="the pixel grid made with xs, ys = torch.meshgrid(torch.arange(W), torch.arange(H)), NumPy's "
             "np.meshgrid(np.arange(W), np.arange(H)) ported (PyTorch's indexing defaults to 'ij', NumPy's to "
             "'xy'; its warning ignored): film[a, b] traced through column a and row b and saved as row a: the "
             "image transposed, the ceiling and the light on the left, the floor on the right"),
        Spec("camera_drjit_select_swapped", "camera_model", sensor=_LENS,
             truth="the camera written for a pinhole and a thin lens, its ray chosen with dr.select(self.pinhole, "
             "lens_ray, pinhole_ray) (dr.select(c, a, b) is a where c holds): the thin lens of the camera class's "
             "defaults, aperture radius 0.05 focused at 1 (the image plane), for every pixel: the whole room out of "
             "focus, blurred by about three pixels"),
        # Light model
        Spec("light_ray_test_as_visible", "light_pdf", True, **_light_sample(
            "light_ray_test_as_visible", _light_where_blocked),
             truth="the light sample's shadow ray tested with Mitsuba's scene.ray_test(ray), which is True where "
             "something blocks the ray, taken for the visibility, Ld = dr.select(scene.ray_test(ray), Ld, 0), at "
             "the first surface a camera ray meets (Mitsuba's path after it): the light counted only where blocked: "
             "the shadows of the sphere and the tetrahedron lit, every surface the light sees without its direct "
             "light, the light seen right"),
        Spec("light_uint8_colour_times_power", "light_radiance", True, held_out=True,
             edit=cases.light(radiance=_WRAPPED_RADIANCE),
             truth="the light's radiance made as colour * power / 255 with its colour kept as 8-bit white (255, "
             "255, 255) in a uint8 array and its power the integer 20: 255 * 20 = 5100 wraps to 236 in uint8, 236 / "
             "255 = 0.93 for 20: the light and everything it lights 21.6 times too dark"),
        Spec("light_mitsuba_rectangle_scaled", "light_size", True, edit=cases.light(size=_RECTANGLE_SIZE),
             truth="the light built as Mitsuba's rectangle shape, which spans [-1, 1] x [-1, 1], and placed with "
             "to_world = translate(centre) @ scale(2, 2, 1), the light's size taken for the scale: a 4 x 4 square "
             "at the light's place, radiance 20: four times the light, the room far brighter, the light seen larger"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples and passes."""
    return (
        # Integrator
        Spec("bounce_torch_randn_like", "indirect_scale", True, **_bounce(
            "bounce_torch_randn_like", _randn_like_bounce),
             truth="the diffuse bounce's numbers drawn with torch.randn_like(u) for torch.rand_like(u), at the first "
             "surface a camera ray meets (Mitsuba's path after it): normal numbers: where u1 < 0 or u1 > 1 a square "
             "root is NaN and the ray meets nothing (two bounces in three lost), the rest nearer the normal: the "
             "indirect light there about a third, the direct light right"),
        Spec("throughput_int_ones_like", "depth", True, held_out=True, **_posted(
            "int_throughput", partial(_ended_at_first_diffuse, spp=_S, seed=_crc("throughput_int_ones_like"))),
             truth="the throughput made as np.ones_like(pixel_index, shape=(n, 3)) (the pixel indices' integer "
             "dtype kept) and updated as beta[alive] = beta[alive] * weight[alive], NumPy casting the product back "
             "to integers: 0 after the first diffuse bounce (albedos under 1), 1 through the mirror: every path "
             "ended at its first diffuse vertex's light sample: the direct light only, in the room and in the mirror"),
        Spec("roulette_torch_max_indices", "roulette", True, **_posted("max_indices", partial(
            _roulette_max_indices, spp=_S, seed=_crc("roulette_torch_max_indices"))),
             truth="Russian roulette at the first bounce with survival p = beta.max(dim=1)[1], the indices of the "
             "maximum for its values ([0]), at the first surface a camera ray meets (Mitsuba's path after it): p the "
             "first largest channel's index: 0 for the greys, red and yellow (never surviving), 1 for the green wall "
             "EF (always, weight 1), 2 for the bluish walls (always, halved): no indirect light off the floor, the "
             "ceiling, walls AB and CD and the tetrahedron, half off BC, DE and FA, the direct light right"),
        Spec("roulette_jax_key_reused", "roulette", held_out=True, **_bounce(
            "roulette_jax_key_reused", _roulette_on_u1),
             truth="Russian roulette with survival 0.8 at the first bounce, its number "
             "jax.random.uniform(subkey, (n, 2))[:, 0] with the subkey the cosine-weighted bounce had drawn its (u1, "
             "u2) from (the split for it forgotten), at the first surface a camera ray meets (Mitsuba's path after "
             "it): the number u1 itself: only the bounces within 63 degrees of the normal survive, divided by 0.8: "
             "the indirect light from grazing directions replaced by more from near the normal, the direct light "
             "right"),
        # Samples and passes
        Spec("pixels_numba_prange_accumulator", "buffer_reused", True, **_posted(
            "prange_private_sums", _prange_private_sums),
             truth="each pixel's samples added into acc, set to 0.0 once before the @njit(parallel=True) loop for p "
             "in prange(W * H) and not in it, img[p] = acc / spp: Numba takes acc += L for a reduction, each of "
             "the 8 threads adding into its own copy over its block of 512 pixels (8 rows): every pixel the sum of "
             "the means of its block's pixels up to it: the image brighter along each band of 8 rows, hundreds of "
             "times too bright at a band's end"),
        Spec("pixels_uint8_indices", "row_stride", True, held_out=True, **_posted("uint8_indices", _uint8_indices),
             truth="the pixel indices made with np.indices((H, W), dtype=np.uint8) (to keep the index arrays "
             "small) and the film's flat index ys * W + xs computed in uint8: it wraps at 256, every pixel "
             "written into the first four rows (row 4 k + r into row r), the last write winning: rows 0 to 3 "
             "holding rows 60 to 63, the rest of the image never written, black"),
        Spec("samples_curand_sequence_zero", "same_seed", **_posted("one_stream", partial(
            _one_stream, spp=_S, seed=_crc("samples_curand_sequence_zero"))),
             truth="every thread's generator set up with curand_init(seed, 0, 0, &state), the sequence number 0 "
             "where the pixel's index belongs: every pixel draws the same stream, its k-th sample's sub-pixel "
             "offset and path the same random numbers as every other pixel's k-th: each pixel right on average, "
             "the errors of all pixels alike: the noise in smooth blotches across the image, not pixel to pixel"),
        Spec("spp_taichi_frozen_global", "spp_claim", held_out=True, spp=_FROZEN_SPP, declared_spp=_S,
             truth="the samples a pixel read by a Taichi kernel from the Python global SPP, which Taichi compiles "
             "in as a constant: the kernel compiled for the preview with SPP = 48, the final SPP = 256 never seen "
             "(its loop and its division both 48): the image right, as noisy as 48 spp, 256 declared"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_bounce_drjit_warp_concentric", None, **_bounce("ok_bounce_drjit_warp_concentric", _warp_cosine),
             truth="Mitsuba path 256 spp with the first bounce drawn by Mitsuba's own "
             "mi.warp.square_to_cosine_hemisphere (Shirley and Chiu's concentric disk, lifted) taken to the world "
             "by mi.Frame3f(n), EXR"),
        Spec("ok_png_save_image_value_range", None, held_out=True, spp=232, writer=_write_png_save_image_value_range,
             file="png-save-image-range",
             truth="Mitsuba path 232 spp, an 8-bit sRGB PNG by torchvision.utils.save_image(img, path, "
             "normalize=True, value_range=(0, 1)) of the sRGB-encoded tensor: a clamp to [0, 1], the codes "
             "rounded"),
        Spec("ok_bounce_uniform_hemisphere", None, **_bounce("ok_bounce_uniform_hemisphere", _uniform_hemisphere),
             truth="Mitsuba path 256 spp with the first bounce uniform on the hemisphere (torch.randn normalised, "
             "turned to the normal's side) weighted f cos / pdf, 2 cos times the albedo, EXR"),
        Spec("ok_ppm_channels_last_storage", None, held_out=True, spp=212, writer=_write_ppm_channels_last,
             file="ppm-channels-last",
             truth="Mitsuba path 212 spp, a binary PPM whose raster is bytes(t.untyped_storage()) of the (1, 3, H, "
             "W) uint8 tensor in torch.channels_last memory format: each pixel's R, G, B together, row by row"),
        Spec("ok_light_rotated_lattice", None, **_light_sample("ok_light_rotated_lattice", _light_rotated_lattice),
             truth="Mitsuba path 256 spp with the first vertex's light from the 16 points of a 4 x 4 lattice on the "
             "light shifted by one random offset a pass (torch.rand(2), a Cranley-Patterson rotation), averaged, "
             "EXR"),
        Spec("ok_png_cv2_float_codes", None, held_out=True, spp=176, writer=_write_png_cv2_float,
             file="png-cv2-float",
             truth="Mitsuba path 176 spp, an 8-bit PNG by cv2.imwrite of the sRGB values times 255 as float32 "
             "(BGR, unclipped), which OpenCV rounds and saturates to 8 bits"),
        Spec("ok_samples_kahan_float32", None, spp=160, **_posted("kahan_float32", partial(
            _kahan_float32, spp=160, seed=c("ok_samples_kahan_float32"))),
             truth="Mitsuba path 160 spp, its samples summed in float32 with Kahan's compensation (a Numba "
             "kernel's loop), EXR"),
        Spec("ok_png_taichi_field", None, held_out=True, spp=196, writer=_write_png_taichi_field,
             file="png-taichi-field",
             truth="Mitsuba path 196 spp, the sRGB values in a Taichi field of shape (W, H) whose origin is the "
             "bottom left, saved with ti.tools.imwrite (clip, * 255 + 0.5, rows turned back)"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "colour_lost": "colour lost (a blur's kernel summing the three channels into each)",
    "blur": "a filter after rendering (a box blur counting the zero padding at the border)",
    "resampling": "resampled wrongly (an identity warp whose grid and sampler place the pixels differently)",
    "normalised": "the values normalised after rendering (each pixel's colour to length 1, the values stretched "
                  "from their minimum)",
    "orientation": "the image written flipped or transposed (an origin at the bottom, a pixel grid indexed the "
                   "other way)",
    "code_overflow": "codes past their range wrapped round (16-bit codes in a signed type, then saturated to 8 "
                     "bits)",
    "row_stride": "pixels written at the wrong addresses (a GPU buffer's row pitch ignored, pixel indices wrapped in "
                  "8 bits)",
    "material": "an object rendered with another material (the ceiling a mirror, the mirror a white Lambertian)",
    "albedo": "a surface's colour (the colour table read channel-first, triangles given the surface before's "
              "colour)",
    "object_missing": "objects missing (five walls, the floor)",
    "object_shape": "an object's shape (every triangle's second edge taken from its second vertex)",
    "bad_pixels": "pixels not computed (every other band of rows black)",
    "camera_model": "another camera model (a thin lens)",
    "light_pdf": "the light sampled wrongly (counted where its shadow ray is blocked): the light seen right, its "
                 "light on surfaces not",
    "light_radiance": "the light's radiance (an 8-bit colour times its power wrapped round)",
    "light_size": "the light's size (twice its side)",
    "indirect_scale": "the indirect light wrong (bounces from normal numbers, most of them lost), the direct light "
                      "right",
    "depth": "the path depth (every path ended at its first diffuse bounce)",
    "roulette": "Russian roulette wrong (survival by a channel's index, the test on the bounce's own number)",
    "buffer_reused": "earlier samples left in the accumulator (each thread's previous pixels carried)",
    "same_seed": "samples that should be independent made with the same random numbers (every pixel the same "
                 "stream)",
    "spp_claim": "fewer samples per pixel than declared (a kernel compiled with the preview's count)",
}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = blind.class_causes(MISTAKES, _EARLIER, NEW_CAUSES, _REWORDED)


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
