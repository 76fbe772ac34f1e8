r"""A thirteenth class of hand-ins: mistakes in students' tracers, scene input and output no class tried, written blind.

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
twelve other classes (:mod:`~mcrt.grade.accuracy.cases`,
:mod:`~mcrt.grade.accuracy.outside`, :mod:`~mcrt.grade.accuracy.programs`,
:mod:`~mcrt.grade.accuracy.fresh`, :mod:`~mcrt.grade.accuracy.blind`,
:mod:`~mcrt.grade.accuracy.unseen`, :mod:`~mcrt.grade.accuracy.untried`,
:mod:`~mcrt.grade.accuracy.novel`, :mod:`~mcrt.grade.accuracy.untold`,
:mod:`~mcrt.grade.accuracy.unmet`, :mod:`~mcrt.grade.accuracy.unheard`,
:mod:`~mcrt.grade.accuracy.unsaid`) and from the catalogue's bugs:

* **post-processing**: each pixel averaged with its left and right
  neighbours (a 1 x 3 box along the rows); a smoothstep S-curve
  ``3 x^2 - 2 x^3`` on the values clipped to [0, 1]; a one-pixel white frame
  drawn round the image before the PNG is saved; CLAHE (scikit-image's
  ``equalize_adapthist``) on the values clipped to [0, 1];
* **writing the file**: the linear values times 255 (the 8-bit path's
  scaling left in) written to the EXR; the gamma applied to the values
  already scaled to 0-255 (``(255 v) ** (1 / 2.2)``); float32 sRGB values
  handed to Pillow's ``Image.frombytes("RGB", ...)`` (their bytes taken for
  8-bit codes); 16-bit codes cast to ``uint8`` for an 8-bit PNG (the low
  byte kept);
* **materials**: the mirror's reflectance read as one number into the first
  slot of a zero vector, (1, 0, 0); every wall given the first wall's colour
  (``walls[0]`` in the loop); the tetrahedron's material index -1 (unset,
  read by Python as the last material listed, wall FA's);
* **geometry**: the tetrahedron's normal computed once (its first face's) and
  used on every face; the light's footprint cut out of the floor as well as
  the ceiling (a hole in the floor under the light); the ray-sphere test
  written for unit directions (``a = 1``) and given the camera's
  unnormalised rays;
* **camera model**: the half-angle used in place of its tangent on the image
  plane (a field of view of 76.5 degrees); a 16:9 render letterboxed into
  the square image; the ray's angles linear in the pixel on each axis (their
  tangents then taken); the camera's far clip plane at 10 (a rasteriser's
  default);
* **light model**: the light's sample point drawn once per pixel, not per
  sample (every path of a pixel lit from one point); the light's samples at
  its four corners (``round`` of the random numbers); the light's centre read
  (y, x);
* **integrator**: the mirror handled Whitted-style (what the sphere reflects
  shaded with direct light only); the diffuse bounce's direction drawn on
  the whole sphere with the hemisphere's pdf (half the bounces lost below
  the surface); the radiance assigned, not added, at each vertex (only the
  last vertex's light kept);
* **samples and passes**: a running mean updated with the total spp as its
  count (``mean += (x - mean) / spp``); ``break`` for ``continue`` when a
  camera ray meets the light (the pixel's sample loop ended); one random
  colour channel traced a sample (a "hero" channel) without the factor 3;
  the samples (as many as the image is wide) averaged over the columns'
  axis, not the samples'.

The correct hand-ins come in ways no class used: mcrt in two bands of rows
rendered apart (a seed each) and stacked, Mitsuba with the light's two
triangles lit apart and summed, Mitsuba with the camera rolled a quarter
turn and the image turned back, an 8-bit sRGB PNG saved by Matplotlib's
``imsave`` (RGBA), Mitsuba with the light a ``rectangle`` shape, mcrt of
the scene moved by (3, -2, 1.5), an 8-bit sRGB PNG written by imageio, and
mcrt of the scene typed in another order (walls from CD on, objects
swapped).

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s
``edit`` and ``mitsuba_edit``), Mitsuba renders combined where light
transport or pixel integrals are linear in what is combined (the light seen
apart, sub-pixel cells, paths of each length, lights apart), Mitsuba's path
integrator sampling the rays a student's camera or sphere test makes, or
its samples, one by one, added up as a student's loop adds them
(:func:`_samples`: the integrator's own ``sample`` on the pinhole's rays),
or correct renders post-processed and written with NumPy, SciPy,
scikit-image and Pillow as students' programs do. mcrt renders only correct
hand-ins.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over
:data:`CATEGORIES`: the 2nd, 4th, ... of each category and of the correct
hand-ins) are as in :mod:`~mcrt.grade.accuracy.unsaid`, fixed before any
case was graded.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unheard, unmet, unsaid, unseen,
                                 untold, untried)
from mcrt.grade.accuracy.cases import Spec

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


def _crc(name: str) -> int:
    return 91000 + zlib.crc32(name.encode()) % 100000


_render = unseen._render
_posted = unseen._posted


# --------------------------------------------------------------------------
# Post-processing (linear render in, what the program writes out)
# --------------------------------------------------------------------------


def _row_box(x):
    """Each pixel the mean of itself and its left and right neighbours (the edge pixels' outer neighbour
    themselves)."""
    from scipy.ndimage import uniform_filter1d

    return uniform_filter1d(np.asarray(x, np.float64), size=3, axis=1, mode="nearest")


def _smoothstep(x):
    """The S-curve ``3 c^2 - 2 c^3`` of ``c`` the values clipped to [0, 1]."""
    c = np.clip(np.asarray(x, np.float64), 0.0, 1.0)
    return c * c * (3.0 - 2.0 * c)


def _clahe(x, *, clip_limit: float = 0.01):
    """scikit-image's contrast-limited adaptive histogram equalisation on the values clipped to [0, 1]."""
    from skimage.exposure import equalize_adapthist

    return np.asarray(equalize_adapthist(np.clip(np.asarray(x, np.float64), 0.0, 1.0), clip_limit=clip_limit),
                      np.float64)


def _framed(codes: np.ndarray, value: int = 255) -> np.ndarray:
    """8-bit codes with their outermost rows and columns set to ``value`` (a one-pixel frame)."""
    out = np.array(codes, copy=True)
    out[0], out[-1], out[:, 0], out[:, -1] = value, value, value, value
    return out


def _write_png_framed(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB PNG with a one-pixel white frame drawn round it."""
    return novel._write_png(_framed(blind._srgb8(image)), folder)


# --------------------------------------------------------------------------
# Files as students' programs write them (the program's buffer in, file out)
# --------------------------------------------------------------------------


def _write_exr_times_255(image: np.ndarray, folder: Path) -> Path:
    """A float EXR of the linear values times 255 (the scaling for 8-bit codes done before the writer)."""
    return fresh._write_exr(np.asarray(image, np.float64) * 255.0, folder)


def _gamma_after_scaling(image: np.ndarray) -> np.ndarray:
    """8-bit codes ``(255 v) ** (1 / 2.2)``, rounded and clipped: the gamma applied to values already scaled to
    0-255."""
    v = np.maximum(np.nan_to_num(np.asarray(image, np.float64)), 0.0) * 255.0
    return np.clip(np.floor(np.power(v, 1.0 / 2.2) + 0.5), 0, 255).astype(np.uint8)


def _write_png_gamma_after_scaling(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_gamma_after_scaling(image), folder)


def _float_bytes_as_codes(image: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8: the bytes of the float32 sRGB values (clipped to [0, 1]) taken as 8-bit codes, as
    ``Image.frombytes("RGB", (W, H), values.tobytes())`` takes them: the first quarter of the buffer."""
    h, w = image.shape[:2]
    srgb = fresh._srgb(np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 1.0)).astype(np.float32)
    return np.frombuffer(srgb.tobytes(), np.uint8)[:h * w * 3].reshape(h, w, 3)


def _write_png_float_bytes(image: np.ndarray, folder: Path) -> Path:
    """``Image.frombytes("RGB", (W, H), srgb.astype(np.float32).tobytes())`` saved as a PNG."""
    from PIL import Image

    h, w = image.shape[:2]
    srgb = fresh._srgb(np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 1.0)).astype(np.float32)
    path = folder / "render.png"
    Image.frombytes("RGB", (w, h), srgb.tobytes()).save(path, format="PNG")
    return path


def _low_byte(image: np.ndarray) -> np.ndarray:
    """16-bit sRGB codes cast to ``uint8``: each code's low byte."""
    return (untried._codes16(image) & 0xFF).astype(np.uint8)


def _write_png_low_byte(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_low_byte(image), folder)


# --------------------------------------------------------------------------
# Mitsuba's path integrator on the rays a student's program makes, and its samples one by one
# --------------------------------------------------------------------------


def _angles_linear(fx, fy):
    """The ray's angles linear in the pixel on each axis (``yaw = (2 fx - 1) fov / 2``, pitch alike), their tangents
    then taken on the image plane: direction ``forward + tan(yaw) right + tan(pitch) up``."""
    eye, r, u, f, k = unsaid._frame()
    half = math.atan(k)
    s, t = np.tan((2.0 * fx - 1.0) * half), np.tan((1.0 - 2.0 * fy) * half)
    return np.broadcast_to(eye, (len(fx), 3)), unsaid._unit(f + s[:, None] * r + t[:, None] * u)


def _room_distance(o, d) -> np.ndarray:
    """(N,): the distance along each ray (unit ``d``) to the first surface other than the sphere."""
    mscene = unsaid._loaded(8, partial(fresh._without_mesh, name="sphere"))
    return np.array(mscene.ray_intersect(unsaid._rays(o, d)).t, np.float64)


def _sphere_test_unit_a(o, d):
    """The camera's rays met by a ray-sphere test written for unit directions (``t^2 + 2 b t + c = 0``, ``a = 1``)
    and given the unnormalised direction ``forward + s right + t up`` (``d / (d . forward)``): it takes rays that miss
    for hits and puts every hit at the wrong place, off the sphere (outside it), kept where it lies nearer than the
    room's surfaces; reflected there about ``normalize(p - c)``. Returns (origins, directions, segments used: 1 where reflected, else 0)."""
    _, _, _, f, _ = unsaid._frame()
    c, radius = unsaid._sphere()
    ds = d / (d @ f)[:, None]  # the student's ray: its component along the view 1
    oc = o - c
    b = np.einsum("ij,ij->i", oc, ds)
    disc = b * b - (np.einsum("ij,ij->i", oc, oc) - radius * radius)
    t = -b - np.sqrt(np.maximum(disc, 0.0))
    hit = (disc > 0.0) & (t > 0.0) & (t * np.linalg.norm(ds, axis=1) < _room_distance(o, d))
    p = o + t[:, None] * ds
    n = unsaid._unit(p - c)
    r = unsaid._unit(d - 2.0 * np.einsum("ij,ij->i", d, n)[:, None] * n)
    return (np.where(hit[:, None], p + 1e-4 * n, o), np.where(hit[:, None], r, d), hit.astype(int))


def _samples(w: int, h: int, spp: int, seed: int):
    """Mitsuba path's samples on the pinhole's rays, pixel by pixel: for each chunk, (W H, n, 3) radiance samples and
    the rays (origins and directions, (W H, n, 3) each), sample k of a pixel its k-th sample in the loop (chunks in
    order)."""
    mscene = unsaid._loaded(8)
    for cseed, n, fx, fy in unsaid._lanes(w, h, spp, seed):
        o, d = unsaid._pinhole(fx, fy)
        L = unsaid._sampled(mscene, o, d, cseed)
        yield L.reshape(h * w, n, 3), np.asarray(o).reshape(h * w, n, 3), np.asarray(d).reshape(h * w, n, 3)


def _running_mean_fixed_n(x, *, spp: int, seed: int):
    """``mean += (sample - mean) / spp`` over the pixel's samples in order, ``spp`` the total, not the count so far:
    sample k (from 0) weighs ``(1 - 1/spp)^(spp - 1 - k) / spp`` (the weights sum to ``1 - (1 - 1/spp)^spp``,
    0.63)."""
    h, w = x.shape[:2]
    mean = np.zeros((h * w, 3))
    for L, _, _ in _samples(w, h, spp, seed):
        for k in range(L.shape[1]):
            mean += (L[:, k] - mean) / spp
    return mean.reshape(h, w, 3)


def _hits_light(o: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Whether each camera ray (..., 3) meets the light's square first (nothing lies between the camera and it)."""
    from mcrt.scene import load_scene

    lt = load_scene().light
    cx, cy, cz = lt.center
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (cz - o[..., 2]) / d[..., 2]
        p = o + t[..., None] * d
    return ((d[..., 2] > 0.0) & (np.abs(p[..., 0] - cx) <= lt.size[0] / 2.0)
            & (np.abs(p[..., 1] - cy) <= lt.size[1] / 2.0))


def _break_on_light(x, *, spp: int, seed: int):
    """``break`` for ``continue`` where a camera ray meets the light: the light's radiance added, then the pixel's
    sample loop left; the sum (the samples before it and that one) divided by the spp."""
    h, w = x.shape[:2]
    total = np.zeros((h * w, 3))
    stopped = np.zeros(h * w, bool)
    for L, o, d in _samples(w, h, spp, seed):
        seen = _hits_light(o, d)
        for k in range(L.shape[1]):
            live = ~stopped
            total[live] += L[live, k]
            stopped |= live & seen[:, k]
    return (total / spp).reshape(h, w, 3)


def _hero_channel(x, *, spp: int, seed: int):
    """One colour channel drawn at random for each sample (a spectral tracer's hero wavelength), only its value
    added, without the factor 3 of its probability 1/3: the mean a third of the truth, its colour noisy."""
    h, w = x.shape[:2]
    rng = np.random.default_rng(seed + 17)
    total = np.zeros((h * w, 3))
    for L, _, _ in _samples(w, h, spp, seed):
        pick = rng.integers(0, 3, size=L.shape[:2])
        total += (L * (pick[..., None] == np.arange(3))).sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _mean_over_columns(x, *, seed: int):
    """The samples stored as (H, W, spp, 3) with spp the image's width, averaged with ``mean(axis=1)`` (the columns)
    for ``axis=2`` (the samples): the result, (H, spp, 3), has the image's shape, each pixel (j, k) the mean of row j's
    k-th samples over its columns."""
    h, w = x.shape[:2]
    per = np.concatenate([L for L, _, _ in _samples(w, h, w, seed)], axis=1).reshape(h, w, w, 3)
    return per.mean(axis=1)


# --------------------------------------------------------------------------
# Renderer mistakes realised with Mitsuba renders combined (the render's shape in, the image out)
# --------------------------------------------------------------------------


def _letterboxed(x, *, spp: int, seed: int, aspect: float = 16.0 / 9.0):
    """A 16:9 render (the image's width, its height 9/16 of it, the same horizontal field of view) put in the middle
    of the square image, black bars above and below."""
    h, w = x.shape[:2]
    rows = int(round(w / aspect))
    top = (h - rows) // 2
    out = np.zeros((h, w, 3))
    out[top:top + rows] = _render(w, rows, spp, seed)
    return out


def _whitted_mirror(x, *, spp: int, seed: int, k: int = 4):
    """The mirror handled Whitted-style: a camera ray reflected by the sphere and the surface it meets shaded with
    its direct light only (no path traced on from there). In the cells of a render ``k`` times finer whose camera ray
    meets the sphere, the max-depth-3 render (eye, sphere, surface, light) takes the place of the full one (same
    seed)."""
    h, w = x.shape[:2]
    cells = max(1, spp // (k * k))
    cseed = seed + 1
    lost = (_render(k * w, k * h, cells, cseed, max_depth=3) - _render(k * w, k * h, cells, cseed))
    lost = (lost * unheard._sphere_hit(w, h, k)[..., None]).reshape(h, k, w, k, 3).mean(axis=(1, 3))
    return _render(w, h, spp, seed) + lost


def _seen_light(w: int, h: int, spp: int, seed: int) -> np.ndarray:
    """The light seen, directly (max depth 1) and in the mirror (the paths eye, sphere, light)."""
    return _render(w, h, spp, seed, max_depth=1) + unheard._eye_mirror_light(w, h, spp, seed)


def _whole_sphere_bounce(x, *, spp: int, seed: int):
    """Each diffuse bounce's direction uniform on the whole sphere, weighted as a hemisphere's (pdf 1 / (2 pi)), those
    below the surface lost: each bounce weighs half its due, every vertex's light sample right. Twice a render of
    every diffuse albedo halved, less the paths that meet no diffuse surface before the light (same seed; as in
    :func:`mcrt.grade.accuracy.unheard._cosine_pdf_without_pi`)."""
    h, w = x.shape[:2]
    half = partial(blind._diffuse_remapped, factor=0.5)
    return 2.0 * _render(w, h, spp, seed, dict_edit=half) - _seen_light(w, h, spp, seed)


def _last_vertex_only(x, *, spp: int, seed: int, depth: int = 8):
    """The radiance assigned, not added, at each vertex (``L = beta * direct`` for ``L +=``), no Russian roulette:
    only the paths of ``depth`` segments (max depth 8 minus max depth 7, same seed, without roulette), plus the light
    seen directly and in the mirror (a path that meets the light ends there, its ``L`` the light's radiance)."""
    h, w = x.shape[:2]
    full = _render(w, h, spp, seed, max_depth=depth, dict_edit=unseen._no_roulette)
    short = _render(w, h, spp, seed, max_depth=depth - 1, dict_edit=unseen._no_roulette)
    return _seen_light(w, h, spp, seed) + full - short


def _under_light(d: dict, points, *, side: float = 0.1) -> dict:
    """The light's square black and dark (geometry only), with small emitting squares of ``side`` just below it at
    ``points`` (x, y), sharing its power equally: where the light samples come from."""
    from mcrt.scene import load_scene

    lt = load_scene().light
    z = lt.center[2]
    le = np.asarray(lt.radiance, np.float64) * lt.area / (len(points) * side * side)
    shapes = {"light": (unsaid._light_tris(), None)}
    shapes.update({f"light_sample_{k}": (unsaid._square(px, py, z - 1e-3, side / 2.0), tuple(le))
                   for k, (px, py) in enumerate(points)})
    return unsaid._meshes(d, **shapes)


def _light_corners():
    from mcrt.scene import load_scene

    lt = load_scene().light
    cx, cy, _ = lt.center
    hx, hy = lt.size[0] / 2.0, lt.size[1] / 2.0
    return [(cx + a * hx, cy + b * hy) for a in (-1.0, 1.0) for b in (-1.0, 1.0)]


def _light_points_per_pixel(x, *, spp: int, seed: int, points: int = 8):
    """The light's sample point drawn once per pixel (outside the sample loop): every light sample of a pixel's paths
    at that point. ``points`` points uniform on the light, a render each with the light sampled there alone (the light
    seen right), each pixel taking one of them at random."""
    from mcrt.scene import load_scene

    h, w = x.shape[:2]
    lt = load_scene().light
    rng = np.random.default_rng(seed)
    uv = rng.random((points, 2)) - 0.5
    renders = np.stack([unheard._light_changed_for_samples(
        x, spp=spp, seed=seed + 1 + k, dict_edit=partial(_under_light, points=[
            (lt.center[0] + a * lt.size[0], lt.center[1] + b * lt.size[1])])) for k, (a, b) in enumerate(uv)])
    pick = rng.integers(0, points, size=(h, w))
    return np.take_along_axis(renders, pick[None, ..., None], axis=0)[0]


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _mirror_red(d: dict) -> dict:
    """The mirror's reflectance (1, 0, 0): its one number read into the first slot of a zero vector."""
    return blind._sphere_bsdf(d, {"type": "conductor", "material": "none",
                                  "specular_reflectance": {"type": "rgb", "value": [1.0, 0.0, 0.0]}})


def _walls_first_colour(s):
    """Every wall given the first wall's (AB's) albedo."""
    first = s.room.walls[0].albedo
    return replace(s, room=replace(s.room, walls=tuple(replace(w, albedo=first) for w in s.room.walls)))


def _tetra_last_material(s):
    """The tetrahedron given the last material listed (its index -1): wall FA's Lambertian."""
    from mcrt.scene import Lambertian

    return fresh._object_material(s, "tetrahedron", Lambertian(s.room.walls[-1].albedo))


def _tetra_one_normal(d: dict) -> dict:
    """The tetrahedron shaded with its first face's normal on every face (shading normals all that normal)."""
    import mitsuba as mi

    sf = fresh._surface("tetrahedron")
    tris = np.asarray(sf.triangles, np.float64)
    n0 = unsaid._unit(np.cross(tris[0, 1] - tris[0, 0], tris[0, 2] - tris[0, 0]))
    props = mi.Properties()
    props["bsdf"] = mi.load_dict({"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {
        "type": "rgb", "value": [float(a) for a in sf.material.albedo]}}})
    mesh = mi.Mesh("tetrahedron", 3 * len(tris), len(tris), props, has_vertex_normals=True)
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(tris.reshape(-1).astype(np.float32))
    params["vertex_normals"] = mi.Float(np.tile(n0, 3 * len(tris)).astype(np.float32))
    params["faces"] = mi.UInt32(np.arange(3 * len(tris), dtype=np.uint32))
    params.update()
    return dict(d, tetrahedron=mesh)


def _floor_holed(d: dict) -> dict:
    """The floor's fan built with the light's footprint cut out (the hole the ceiling would need): a 2 x 2 hole in
    the floor under the light."""
    from mcrt.mitsuba_scene import _bsdf_dict
    from mcrt.scene import _fan, load_scene

    s = load_scene()
    z0 = s.room.floor_z
    tris = np.array([[[*a, z0], [*b, z0], [*c, z0]] for a, b, c in _fan(s.room.polygon(), s._hole())])
    return fresh._rebuilt(d, "floor", tris, _bsdf_dict(fresh._surface("floor").material))


def _light_yx(s):
    """The light's centre read (y, x): (0, 5) for (5, 0), at the same height."""
    x, y, z = s.light.center
    return replace(s, light=replace(s.light, center=(float(y), float(x), float(z))))


# --------------------------------------------------------------------------
# Correct renders made in other ways
# --------------------------------------------------------------------------


def _mcrt_bands(x, *, spp: int, seed: int):
    """mcrt in two bands of rows rendered apart (the tracer's ``rows``), a seed each, stacked."""
    from mcrt.scene import load_scene
    from mcrt.tracer import render_tracer

    h, w = x.shape[:2]
    s = load_scene()
    bands = ((0, h // 2), (h // 2, h - h // 2))
    return np.concatenate([np.asarray(render_tracer(s, s.settings(camera="near", width=w, height=h, spp=spp,
                                                                  max_depth=8, seed=seed + k),
                                                    progress=False, rows=[band]).mean, np.float64).reshape(band[1], w, 3)
                           for k, band in enumerate(bands)])


def _one_triangle_lit(d: dict, *, k: int) -> dict:
    """The light's triangle ``k`` emitting, the other black and dark (same geometry)."""
    from mcrt.scene import load_scene

    tris = unsaid._light_tris()
    return unsaid._meshes(d, light=(tris[k:k + 1], load_scene().light.radiance),
                          light_other=(np.delete(tris, k, axis=0), None))


def _light_halves_summed(x, *, spp: int, seed: int):
    """Two Mitsuba renders, the light's first triangle alone emitting, then its second, summed: light transport is
    linear in the emitters."""
    h, w = x.shape[:2]
    return sum(_render(w, h, spp, seed + k, dict_edit=partial(_one_triangle_lit, k=k)) for k in range(2))


def _rolled_quarter(s):
    """The near camera rolled a quarter turn: its up vector its right."""
    r, _, _ = s.cameras["near"].frame()
    return cases._camera(s, up=tuple(float(a) for a in r))


def _rolled_back(x, *, spp: int, seed: int):
    """A Mitsuba render with the camera rolled a quarter turn (:func:`_rolled_quarter`), turned back a quarter turn
    clockwise (``np.rot90(img, -1)``)."""
    h, w = x.shape[:2]
    return np.rot90(_render(w, h, spp, seed, scene_edit=_rolled_quarter), -1)


def _write_png_matplotlib(image: np.ndarray, folder: Path) -> Path:
    """The 8-bit sRGB codes (rounded) saved by ``matplotlib.pyplot.imsave``: an RGBA PNG, alpha opaque."""
    from matplotlib.image import imsave

    path = folder / "render.png"
    imsave(path, blind._srgb8(image), format="png")
    return path


def _light_rectangle(d: dict) -> dict:
    """The light a Mitsuba ``rectangle`` (its [-1, 1]^2 square scaled to the light's size, turned to face down and
    moved to its centre), black, emitting the light's radiance."""
    import mitsuba as mi

    from mcrt.scene import load_scene

    lt = load_scene().light
    to_world = (mi.ScalarTransform4f().translate([float(a) for a in lt.center])
                @ mi.ScalarTransform4f().rotate([1.0, 0.0, 0.0], 180.0)
                @ mi.ScalarTransform4f().scale([lt.size[0] / 2.0, lt.size[1] / 2.0, 1.0]))
    return dict(d, light={"type": "rectangle", "to_world": to_world, "bsdf": dict(unsaid._BLACK),
                          "emitter": unsaid._emitter(lt.radiance)})


def _shifted(p, *, move) -> tuple[float, ...]:
    return tuple(float(a + b) for a, b in zip(p, move))


def _moved(s, *, move=(3.0, -2.0, 1.5)):
    """The scene and its cameras moved by ``move`` (the student's own origin): the same image."""
    return unheard._mapped(s, partial(_shifted, move=move))


def _reordered(s):
    """The scene typed in another order: the walls listed from CD on (still counter-clockwise), the objects
    swapped."""
    walls = s.room.walls
    return replace(s, room=replace(s.room, walls=walls[2:] + walls[:2]), objects=tuple(reversed(s.objects)))


def _write_png_imageio(image: np.ndarray, folder: Path) -> Path:
    """The 8-bit sRGB codes (rounded) written by ``imageio.v3.imwrite``."""
    import imageio.v3 as iio

    path = folder / "render.png"
    iio.imwrite(path, blind._srgb8(image))
    return path


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_row_box_3", "pp_smoothstep_curve", "pp_white_frame", "pp_clahe"),
    "file": ("file_exr_times_255", "file_png_gamma_after_255", "file_png_float_bytes", "file_png_low_byte"),
    "materials": ("mirror_red_only", "walls_first_colour", "tetra_material_minus_one"),
    "geometry": ("tetra_first_face_normal", "floor_hole_under_light", "sphere_test_unit_direction"),
    "camera": ("plane_angle_for_tangent", "letterboxed_16_9", "angles_linear_per_axis", "far_clip_10"),
    "light": ("light_point_once_per_pixel", "light_samples_at_corners", "light_centre_yx"),
    "integrator": ("mirror_whitted", "bounce_on_whole_sphere", "radiance_assigned_per_vertex"),
    "samples": ("running_mean_total_count", "break_on_light", "hero_channel_unweighted",
                "mean_over_columns_axis"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_row_box_3", "blur", **_posted("row_box_3", _row_box),
             truth="each pixel averaged with its left and right neighbours (a 1 x 3 box along the rows, to smooth the "
             "noise), as EXR"),
        Spec("pp_smoothstep_curve", "tone_map", held_out=True, **_posted("smoothstep", _smoothstep),
             truth="an S-curve for contrast, smoothstep 3 x^2 - 2 x^3 of the values clipped to [0, 1], as EXR"),
        Spec("pp_white_frame", "bad_pixels", writer=_write_png_framed, file="png-srgb-frame",
             truth="a one-pixel white frame drawn round the image (for the report's figure), then the 8-bit sRGB PNG "
             "saved"),
        Spec("pp_clahe", "tone_map", True, held_out=True, **_posted("clahe", _clahe),
             truth="CLAHE (skimage.exposure.equalize_adapthist, clip limit 0.01) on the values clipped to [0, 1], to "
             "bring out the dark corners, as EXR"),
        # Writing the file
        Spec("file_exr_times_255", "light_radiance", True, writer=_write_exr_times_255, file="exr-times-255",
             truth="the linear values times 255 (the 8-bit path's scaling left in) written to a float EXR"),
        Spec("file_png_gamma_after_255", "encoding", held_out=True, writer=_write_png_gamma_after_scaling,
             file="png-gamma-after-255",
             truth="8-bit codes (255 v) ** (1 / 2.2): the gamma applied to values already scaled to 0-255, an almost "
             "black PNG (white at code 12)"),
        Spec("file_png_float_bytes", "file_format", True, writer=_write_png_float_bytes, file="png-float-bytes",
             truth="Image.frombytes('RGB', (W, H), srgb.astype(np.float32).tobytes()) saved as PNG: the float32 "
             "values' bytes taken for 8-bit codes, the first quarter of the buffer"),
        Spec("file_png_low_byte", "code_overflow", True, held_out=True, writer=_write_png_low_byte,
             file="png-16bit-low-byte",
             truth="16-bit sRGB codes cast to uint8 for an 8-bit PNG: each code's low byte kept"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    c = _crc
    return (
        # Materials
        Spec("mirror_red_only", "albedo", True, mitsuba_edit=_mirror_red,
             truth="the mirror's reflectance read as one number into the first slot of a zero vector: (1, 0, 0), the "
             "room seen in the sphere in red only"),
        Spec("walls_first_colour", "albedo", True, held_out=True, edit=_walls_first_colour,
             truth="every wall given the first wall's colour (walls[0] in the loop): all six walls AB's red "
             "(0.75, 0.15, 0.15)"),
        Spec("tetra_material_minus_one", "albedo", True, edit=_tetra_last_material,
             truth="the tetrahedron's material index -1 (left unset, read by Python as the last material listed): "
             "wall FA's cyan (0.15, 0.65, 0.70) for its orange"),
        # Geometry
        Spec("tetra_first_face_normal", "normals", True, mitsuba_edit=_tetra_one_normal,
             truth="the tetrahedron's normal computed once, its first face's, and used on every face: its faces "
             "shaded as if they all faced one way"),
        Spec("floor_hole_under_light", "mesh_face", True, held_out=True, mitsuba_edit=_floor_holed,
             truth="the light's footprint cut out of the floor as well as the ceiling: a 2 x 2 hole in the floor "
             "under the light, the void seen through it"),
        Spec("sphere_test_unit_direction", "object_size", True, **_posted("sphere_test_a_1", partial(
            unsaid._traced, spp=256, seed=c("sphere_test_unit_direction"), after=_sphere_test_unit_a)),
             truth="the ray-sphere test written for unit directions (a = 1) and given the camera's unnormalised rays "
             "(forward + s right + t up): the sphere seen over about 16 times its area, hits put off the sphere "
             "where nearer than the room, reflected there (the other rays normalised, right)"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera model
        Spec("plane_angle_for_tangent", "camera_fov", True, edit=cases.fov(math.degrees(2.0 * math.atan(math.pi / 4))),
             truth="the half-angle in radians used in place of its tangent on the image plane (s = (2 fx - 1) pi / 4): "
             "a field of view of 76.5 degrees for 90"),
        Spec("letterboxed_16_9", "resolution_crop", True, held_out=True, **_posted("letterboxed", partial(
            _letterboxed, spp=256, seed=c("letterboxed_16_9"))),
             truth="rendered 16:9 (the width's 90 degrees, 9/16 of the rows) and letterboxed into the square image: "
             "black bars above and below"),
        Spec("angles_linear_per_axis", "camera_model", True, **_posted("angles_linear", partial(
            unsaid._traced, spp=256, seed=c("angles_linear_per_axis"), camera=_angles_linear)),
             truth="the ray's angles linear in the pixel on each axis (yaw = (2 fx - 1) 45 degrees, pitch alike), "
             "then their tangents on the image plane: the middle magnified, the edges right"),
        Spec("far_clip_10", "object_missing", True, held_out=True, sensor={"far_clip": 10.0},
             truth="the camera's far clip plane at 10 along the view (a rasteriser's default): the far walls, the "
             "back of the room and the sphere's far side missing, black"),
        # Light model
        Spec("light_point_once_per_pixel", "light_pdf", True, **_posted("light_point_per_pixel", partial(
            _light_points_per_pixel, spp=256, seed=c("light_point_once_per_pixel"))),
             truth="the light's sample point drawn once per pixel, outside the sample loop: every light sample of a "
             "pixel's paths at one point (8 points, a pixel each at random), hard shadows changing from pixel to "
             "pixel, the light seen right"),
        Spec("light_samples_at_corners", "light_pdf", True, held_out=True, **_posted("light_corners", partial(
            unheard._light_changed_for_samples, spp=256, seed=c("light_samples_at_corners"),
            dict_edit=partial(_under_light, points=_light_corners()))),
             truth="the light's samples at its four corners (its random numbers rounded): four hard shadows, the "
             "light seen right"),
        Spec("light_centre_yx", "light_position", True, edit=_light_yx,
             truth="the light's centre read (y, x): (0, 5, 4.99) for (5, 0, 4.99), over the room's left end and "
             "partly through wall FA"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples and passes."""
    c = _crc
    return (
        # Integrator
        Spec("mirror_whitted", "depth", True, **_posted("mirror_whitted", partial(
            _whitted_mirror, spp=256, seed=c("mirror_whitted"))),
             truth="the mirror handled Whitted-style: a camera ray reflected by the sphere and the surface it meets "
             "shaded with its direct light only, no path on from there: the room in the mirror without its indirect "
             "light"),
        Spec("bounce_on_whole_sphere", "indirect_scale", True, held_out=True, **_posted("bounce_whole_sphere", partial(
            _whole_sphere_bounce, spp=256, seed=c("bounce_on_whole_sphere"))),
             truth="the diffuse bounce's direction drawn uniformly on the whole sphere with the hemisphere's pdf "
             "1 / (2 pi), those below the surface lost: each bounce weighs half, every light sample right"),
        Spec("radiance_assigned_per_vertex", "depth", True, **_posted("last_vertex_only", partial(
            _last_vertex_only, spp=256, seed=c("radiance_assigned_per_vertex"))),
             truth="the radiance assigned, not added, at each vertex (L = beta * direct for L +=), no Russian "
             "roulette: only the last vertex's light kept (paths of 8 segments), the light seen right"),
        # Samples and passes
        Spec("running_mean_total_count", "light_radiance", True, **_posted("running_mean_fixed_n", partial(
            _running_mean_fixed_n, spp=256, seed=c("running_mean_total_count"))),
             truth="a running mean updated as mean += (x - mean) / spp with the total spp, not the count so far: the "
             "later samples weigh more, the mean 63 % of the truth"),
        Spec("break_on_light", "light_seen", held_out=True, **_posted("break_on_light", partial(
            _break_on_light, spp=256, seed=c("break_on_light"))),
             truth="break for continue where a camera ray meets the light: its radiance added, then the pixel's "
             "sample loop left, the sum divided by 256: the light's own pixels nearly black, the rest right"),
        Spec("hero_channel_unweighted", "light_radiance", True, **_posted("hero_channel", partial(
            _hero_channel, spp=256, seed=c("hero_channel_unweighted"))),
             truth="one colour channel drawn at random for each sample (a hero wavelength), its value added without "
             "the factor 3: a third of the truth, its colours noisy"),
        Spec("mean_over_columns_axis", "blur", True, held_out=True, spp=64, **_posted("mean_axis_1", partial(
            _mean_over_columns, seed=c("mean_over_columns_axis"))),
             truth="64 spp (the image's width) stored as (H, W, spp, 3) and averaged over axis 1 (the columns) for "
             "axis 2 (the samples): each pixel its row's mean over the columns at one sample index, every row flat"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_mcrt_row_bands", None, spp=128, renderer="mcrt", **_posted("mcrt_bands", partial(
            _mcrt_bands, spp=128, seed=c("ok_mcrt_row_bands"))),
             truth="mcrt 128 spp in two bands of rows rendered apart (the tracer's rows), a seed each, stacked, EXR"),
        Spec("ok_light_halves_summed", None, held_out=True, spp=256, **_posted("light_halves_summed", partial(
            _light_halves_summed, spp=256, seed=c("ok_light_halves_summed"))),
             truth="two Mitsuba renders of 256 spp, the light's first triangle alone emitting, then its second, "
             "summed, EXR"),
        Spec("ok_camera_rolled_back", None, spp=224, **_posted("rolled_back", partial(
            _rolled_back, spp=224, seed=c("ok_camera_rolled_back"))),
             truth="Mitsuba path 224 spp with the camera rolled a quarter turn (up its right), the image turned back "
             "with np.rot90, EXR"),
        Spec("ok_png_matplotlib", None, held_out=True, spp=176, writer=_write_png_matplotlib,
             file="png-srgb-matplotlib",
             truth="Mitsuba path 176 spp, 8-bit sRGB codes saved by matplotlib's imsave (an RGBA PNG)"),
        Spec("ok_light_rectangle", None, spp=192, mitsuba_edit=_light_rectangle,
             truth="Mitsuba path 192 spp with the light a rectangle shape (scaled, turned to face down, moved), EXR"),
        Spec("ok_mcrt_world_moved", None, held_out=True, spp=112, renderer="mcrt", edit=_moved,
             truth="mcrt 112 spp of the scene and its cameras moved by (3, -2, 1.5), EXR"),
        Spec("ok_png_imageio", None, spp=272, writer=_write_png_imageio, file="png-srgb-imageio",
             truth="Mitsuba path 272 spp, an 8-bit sRGB PNG written by imageio"),
        Spec("ok_mcrt_reordered", None, held_out=True, spp=80, renderer="mcrt", edit=_reordered,
             truth="mcrt 80 spp of the scene typed in another order (walls from CD on, the objects swapped), EXR"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "blur": "a filter after rendering, or pixels averaged together (a box along the rows, each row's mean)",
    "tone_map": "a curve on the values after rendering (an S-curve, adaptive histogram equalisation)",
    "bad_pixels": "pixels overwritten after rendering (a frame drawn round the image)",
    "light_radiance": "the light's radiance (or a constant factor: values scaled for 8 bits, samples weighted or "
                      "counted wrongly)",
    "encoding": "the values' encoding (a curve applied to codes, not to values)",
    "file_format": "the file's bytes not what its format says (float bytes taken for 8-bit codes)",
    "code_overflow": "codes wrapped past the top 8-bit code (16-bit codes cast to 8 bits)",
    "albedo": "a surface's colour (the mirror's reflectance, walls or an object given another's colour)",
    "normals": "surface normals wrong (one face's normal on every face)",
    "mesh_face": "a face of a mesh missing (a hole cut in the floor)",
    "object_size": "an object's size (the sphere's test wrong for the camera's rays)",
    "camera_fov": "the camera's field of view (the half-angle for its tangent)",
    "resolution_crop": "rendered at another resolution, then padded or cropped to the assignment's (letterboxed)",
    "camera_model": "each pixel's ray wrong (angles linear in the pixel)",
    "object_missing": "an object missing (or part of the room: clipped by the camera)",
    "light_pdf": "the light sampled wrongly (one point per pixel, its corners): the light seen right, its light on "
                 "surfaces not",
    "light_position": "the light's position",
    "depth": "the path depth (paths cut after the mirror, only the last vertex's light kept)",
    "indirect_scale": "the indirect light off by a factor (half the bounces lost), the direct light right",
    "light_seen": "the light's own pixels (where the camera sees it) wrong, its light on surfaces right",
}
_WORDS = {**cases.CAUSES, **outside.CAUSES, **programs.NEW_CAUSES, **fresh.NEW_CAUSES, **blind.NEW_CAUSES,
          **unseen.NEW_CAUSES, **untried.NEW_CAUSES, **novel.NEW_CAUSES, **untold.NEW_CAUSES, **unmet.NEW_CAUSES,
          **unheard.NEW_CAUSES, **unsaid.NEW_CAUSES, **NEW_CAUSES, **_REWORDED}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = {c: _WORDS[c] for c in dict.fromkeys(s.cause for s in MISTAKES)}


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
