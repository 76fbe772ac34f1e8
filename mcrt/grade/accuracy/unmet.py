r"""A tenth class of hand-ins: mistakes in students' tracers, scene input and output that no class met, written blind.

How it was written: from what goes wrong in students' programs (the steps
after rendering, the code that saves the image and its manifest, the scene
typed in, the camera, the light, the integrator's loop, the passes that add up
the samples), not from the grader. Its author read the other classes' specs
and cause words, the catalogue (:mod:`mcrt.mutants`),
:data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to
stay clear of their mistakes; never the grader's rules (what decides a
cause) nor its reports, and graded none of it, not one case. Each cause and
``major`` flag was set from the mistake alone, and the equivalences of the
new causes were added to ``SAME_MISTAKE`` before any grading. The mistakes
differ from those of the nine other classes
(:mod:`~mcrt.grade.accuracy.cases`, :mod:`~mcrt.grade.accuracy.outside`,
:mod:`~mcrt.grade.accuracy.programs`, :mod:`~mcrt.grade.accuracy.fresh`,
:mod:`~mcrt.grade.accuracy.blind`, :mod:`~mcrt.grade.accuracy.unseen`,
:mod:`~mcrt.grade.accuracy.untried`, :mod:`~mcrt.grade.accuracy.novel`,
:mod:`~mcrt.grade.accuracy.untold`) and from the catalogue's bugs:

* **post-processing**: film grain added for the look (a normal number a
  pixel, scaled by the square root of its luminance); the histogram
  equalised (scikit-image's ``equalize_hist``); the highlights compressed
  above 0.8 by a soft knee; edges smoothed by an FXAA-like pass (pixels
  whose 3 x 3 display-luma contrast is high replaced by their 3 x 3 mean);
* **writing the file**: a Radiance HDR whose exponent is ``floor(log2(m))``
  where ``frexp`` belongs (the largest channel's mantissa past 255, wrapped);
  an 8-bit PNG encoded by the power 1/2.4 alone (sRGB's exponent without its
  linear segment and offset); the values rounded to two decimals before the
  EXR; an sRGB PNG whose manifest says ``linear = true`` (a template copied);
* **materials**: a tutorial's checkerboard left on the floor (squares of 2,
  albedos 0.6 and 0.3); the floor given wall AB's colour (the walls' list
  indexed from the floor's slot); the tetrahedron half see-through (an
  opacity field left at 0.5); every albedo normalised to unit length (read
  through the vector type's normalising constructor);
* **geometry**: the floor's triangle fan one triangle short (triangle
  A, E, F missing); the tetrahedron in model space (about its centroid,
  never moved into place); the sphere's normal taken as the hit point
  normalised (its centre never subtracted);
* **camera model**: the view vector's sign flipped (the camera looking back,
  the image mirrored as that mistake makes it); sub-pixel offsets in a disk
  of diameter one pixel; four fixed sub-pixel points (a 2 x 2 grid, not
  jittered);
* **light model**: the light sampled over 4 x 4 (its half-size taken for its
  size), pdf 1/16; the second of its two triangles wound the other way (that
  half emitting into the ceiling); its height typed -4.99 for 4.99;
* **integrator**: no light sampled at the first surface hit (a depth
  condition off by one); Russian roulette whose losers are not stopped
  (survival 0.8 from the 3rd segment, survivors divided by 0.8); the mirror's
  BSDF evaluated as its reflectance 1 in light sampling (a diffuse glow on
  the sphere); each mirror bounce weighted by the cosine, as a diffuse one;
* **samples and passes**: the buffer divided by the pass's spp after each
  pass (the earlier passes' means added in, 1.6 % too bright); each sample
  thrown at a random pixel, each pixel's sum divided by the nominal spp; the
  buffer of squared samples (kept for the variance) written instead of the
  mean's.

The correct hand-ins come in ways no class used: mcrt's bidirectional
estimator, mcrt's estimator as a Mitsuba integrator (renderer ``plugin``), mcrt
with Owen-scrambled Sobol pixel samples, 8 Mitsuba passes combined by a
running (Welford) mean, Mitsuba's own ``mi.render`` through its film, an 8-bit
PNG with an ``sRGB`` chunk, a float EXR stored bottom line first
(``DECREASING_Y``), and mcrt's paths with and without mirror caustics
rendered apart and summed.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s
``edit``, ``integrator`` and ``mitsuba_edit``), Mitsuba renders combined where
light transport or pixel integrals are linear in what is combined (paths of
each length, direct light at the first hit, sub-pixel cells, passes), or
correct renders post-processed and written with NumPy, SciPy, scikit-image and
Pillow as students' programs do. mcrt renders only correct hand-ins.

Causes (:data:`_REWORDED`, :data:`NEW_CAUSES`) and the held-out rule
(:func:`held_out_rule` over :data:`CATEGORIES`: the 2nd, 4th, ... of each
category and of the correct hand-ins) are as in
:mod:`~mcrt.grade.accuracy.untold`, fixed before any case was graded.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import blind, cases, fresh, novel, outside, programs, unseen, untold, untried
from mcrt.grade.accuracy.cases import Spec
from mcrt.image_files import srgb_oetf

#: The causes new in this class, as the report words them.
NEW_CAUSES: dict[str, str] = {
    "grain": "noise added after rendering (film grain for the look)",
    "direct_missing": "direct light missing at the first surface hit (the light sampled only from the second bounce "
                      "on)",
    "specular_weight": "a perfect mirror's reflection weighted like a diffuse bounce (by the cosine)",
    "sample_count": "each pixel's sum divided by the nominal spp, not by the samples it got (samples thrown at random "
                    "pixels)",
    "wrong_buffer": "another buffer written in place of the mean (the mean of the squared samples)",
}


def _crc(name: str) -> int:
    return 61000 + zlib.crc32(name.encode()) % 100000


_render = unseen._render
_posted = unseen._posted


# --------------------------------------------------------------------------
# Post-processing (linear render in, what the program writes out)
# --------------------------------------------------------------------------


def _grain(x, *, seed: int, sigma: float = 0.05):
    """Film grain: each pixel plus ``sigma`` sqrt(luminance) times a normal number (one a pixel, the same in its three
    channels), clipped at 0."""
    lum = np.maximum(x @ programs._LUMA, 0.0)
    noise = sigma * np.sqrt(lum) * np.random.default_rng(seed).standard_normal(lum.shape)
    return np.maximum(x + noise[..., None], 0.0)


def _equalised(x):
    """scikit-image's histogram equalisation over the whole image (256 bins from its minimum to its maximum)."""
    from skimage.exposure import equalize_hist

    x = np.asarray(x, np.float64)
    return equalize_hist(x.reshape(-1), nbins=256).reshape(x.shape)


def _soft_knee(x, *, knee: float = 0.8):
    """Values above ``knee`` compressed towards 1 (``knee + (1 - knee) t / (1 + t)``, t the excess in units of
    ``1 - knee``), per channel; the rest kept."""
    t = np.maximum(x - knee, 0.0) / (1.0 - knee)
    return np.where(x > knee, knee + (1.0 - knee) * t / (1.0 + t), x)


def _edges_smoothed(x, *, rel: float = 0.125, floor: float = 0.0625):
    """An FXAA-like pass: where the 3 x 3 range of the display luma (sRGB-encoded luminance) exceeds ``floor`` and
    ``rel`` times its maximum, the pixel replaced by its 3 x 3 mean."""
    from scipy.ndimage import maximum_filter, minimum_filter, uniform_filter

    luma = srgb_oetf(np.clip(x @ programs._LUMA, 0.0, 1.0))
    hi, lo = maximum_filter(luma, 3, mode="nearest"), minimum_filter(luma, 3, mode="nearest")
    edge = hi - lo > np.maximum(floor, rel * hi)
    return np.where(edge[..., None], uniform_filter(x, size=(3, 3, 1), mode="nearest"), x)


def _columns_reversed(x):
    return x[:, ::-1]


# --------------------------------------------------------------------------
# Renderer mistakes realised with Mitsuba (the render's shape in, the image out)
# --------------------------------------------------------------------------


def _disk_weights(k: int, sub: int = 16) -> np.ndarray:
    """(k, k): the share of the disk of diameter one pixel, centred in the pixel, in each of its k x k cells."""
    t = (np.arange(k * sub) + 0.5) / (k * sub) - 0.5
    inside = (t[:, None] ** 2 + t[None, :] ** 2 <= 0.25).reshape(k, sub, k, sub).mean(axis=(1, 3))
    return inside / inside.sum()


def _jitter_disk(x, *, spp: int, seed: int, k: int = 8):
    """Sub-pixel offsets uniform in the disk of diameter one pixel (a disk sampler reused): a render ``k`` times
    finer, each pixel's cells weighted by the disk's share of them."""
    h, w = x.shape[:2]
    return np.einsum("ykxlc,kl->yxc", untried._cells(w, h, k, spp, seed), _disk_weights(k))


def _grid_2x2(x, *, spp: int, seed: int, k: int = 6):
    """Every sample through one of four fixed points of its pixel, (0.25, 0.25) to (0.75, 0.75): the cells of a render
    ``k`` times finer (a sixth of a pixel wide) centred on them."""
    h, w = x.shape[:2]
    at = [round(f * k - 0.5) for f in (0.25, 0.75)]
    return untried._cells(w, h, k, spp, seed)[:, at][:, :, :, at].mean(axis=(1, 3))


def _sphere_black(d: dict) -> dict:
    return blind._sphere_bsdf(d, {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0] * 3}})


def _sphere_white_rest_black(d: dict) -> dict:
    white = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [1.0] * 3}}}
    return blind._sphere_bsdf(untold._black_diffuse(d), white)


def _two_segments(w: int, h: int, spp: int, seed: int, dict_edit) -> np.ndarray:
    """The paths of two segments (camera, a surface, the light) of the scene as ``dict_edit`` makes it: a
    max-depth-2 render minus its same-seed max-depth-1 render (the same camera rays)."""
    return (_render(w, h, spp, seed, max_depth=2, dict_edit=dict_edit)
            - _render(w, h, spp, seed, max_depth=1, dict_edit=dict_edit))


def _first_hit_unlit(x, *, spp: int, seed: int):
    """No light sampled at the first surface hit: the plain render minus the direct light at the first diffuse
    surface (the two-segment paths with the sphere black, which same-seed renders share with the plain one). The
    light seen in the mirror, a specular bounce's, is kept."""
    h, w = x.shape[:2]
    return _render(w, h, spp, seed) - _two_segments(w, h, spp, seed, _sphere_black)


def _roulette_unstopped(x, *, spp: int, seed: int, survival: float = 0.8, start: int = 3):
    """Russian roulette whose losers go on: survivors divided by ``survival``, the others continue undivided, so each
    segment after the ``start``-th weighs ``2 - survival`` in the mean. Paths of each length from same-seed renders
    without roulette (max depth k minus k - 1), weighted so."""
    h, w = x.shape[:2]
    by_depth = np.array([_render(w, h, spp, seed, max_depth=k, dict_edit=unseen._no_roulette) for k in range(1, 9)])
    lengths = np.diff(by_depth, axis=0, prepend=0.0)
    weights = (2.0 - survival) ** np.maximum(np.arange(1, 9) - start, 0)
    return np.einsum("k...,k->...", lengths, weights)


def _mirror_lit_as_diffuse(x, *, spp: int, seed: int):
    """The mirror's BSDF evaluated as its reflectance 1 (not 0, a delta) in light sampling: at the sphere, light
    sampling adds pi times a white Lambertian's direct light (1 where the Lambertian has 1/pi). The glow seen from the
    camera: pi times the two-segment paths with the sphere white and every other surface black. (Its light on the
    room, which the mistake also adds, is left out.)"""
    h, w = x.shape[:2]
    return _render(w, h, spp, seed) + math.pi * _two_segments(w, h, spp, seed, _sphere_white_rest_black)


def _sphere_cosines(w: int, h: int, k: int) -> np.ndarray:
    """(H, k, W, k): where the centre ray of each of a pixel's k x k cells meets the sphere, the cosine between it and
    the sphere's normal; 1 where it does not (nothing lies in front of the sphere)."""
    from mcrt.mitsuba_scene import sensor_rays
    from mcrt.scene import load_scene

    s = load_scene()
    sph = next(o for o in s.objects if o.name == "sphere")
    jj, ii = np.mgrid[0:k * h, 0:k * w]
    o, d = sensor_rays(s, "near", k * w, k * h, ii, jj, 0.5, 0.5)
    oc = o - np.asarray(sph.center)
    b = np.einsum("ij,ij->i", oc, d)
    disc = b * b - np.einsum("ij,ij->i", oc, oc) + sph.radius ** 2
    t = -b - np.sqrt(np.maximum(disc, 0.0))
    n = (oc + t[:, None] * d) / sph.radius
    return np.where(disc > 0, -np.einsum("ij,ij->i", n, d), 1.0).reshape(h, k, w, k)


def _mirror_cosine(x, *, spp: int, seed: int, k: int = 4):
    """Each mirror bounce's weight times the cosine at the sphere (``f cos / pdf`` with the mirror's f and pdf 1):
    the sphere seen from the camera darker towards its rim. A render ``k`` times finer, each cell that sees the sphere
    times its ray's cosine. (Mirror bounces deeper in a path, which the mistake also dims, are kept.)"""
    h, w = x.shape[:2]
    cells = untried._cells(w, h, k, spp, seed) * _sphere_cosines(w, h, k)[..., None]
    return cells.mean(axis=(1, 3))


def _renormalised_each_pass(x, *, passes: int, spp: int, seed: int):
    """``passes`` passes of ``spp`` (a seed each), the buffer divided by ``spp`` after each pass's sum is added: the
    last pass's mean plus the earlier ones' over powers of ``spp``."""
    h, w = x.shape[:2]
    buf = np.zeros((h, w, 3))
    for k in range(passes):
        buf = (buf + spp * _render(w, h, spp, seed + k)) / spp
    return buf


def _random_pixel_counts(x, *, spp: int, seed: int):
    """Samples thrown at random pixels (``spp`` W H of them), each pixel's sum divided by ``spp``: its mean times a
    Poisson count over ``spp`` (the count's share of the noise of its mean left out)."""
    return x * (np.random.default_rng(seed).poisson(spp, x.shape[:2]) / spp)[..., None]


def _mean_of_squares(x, *, spp: int, seed: int):
    """The buffer of squared samples over ``spp`` written: the per-sample variance times (n - 1) / n plus the mean
    squared, from one Mitsuba render."""
    from mcrt.mitsuba_scene import render_with_variance, scene_dict
    from mcrt.scene import load_scene

    h, w = x.shape[:2]
    r = render_with_variance(scene_dict(load_scene(), "near", w, h, 8, spp=spp), spp=spp, seed=seed)
    mean, var = np.asarray(r.mean, np.float64), np.asarray(r.variance, np.float64)
    return var * (spp - 1) / spp + mean ** 2


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _floor_checker(d: dict, *, dark: float = 0.3, square: float = 2.0) -> dict:
    """The floor with a checkerboard texture (squares ``square`` wide, albedos 0.6 and ``dark``) on texture
    coordinates (x, y) / (2 ``square``): Mitsuba's checkerboard has 2 x 2 squares a unit of uv."""
    import mitsuba as mi

    sf = fresh._surface("floor")
    tris = np.asarray(sf.triangles, np.float64)
    grey = [float(a) for a in sf.material.albedo]
    checker = {"type": "checkerboard", "color0": {"type": "rgb", "value": grey},
               "color1": {"type": "rgb", "value": [dark] * 3}}
    props = mi.Properties()
    props["bsdf"] = mi.load_dict({"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": checker}})
    n = tris.shape[0]
    mesh = mi.Mesh("floor", 3 * n, n, props, has_vertex_texcoords=True)
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(tris.reshape(-1).astype(np.float32))
    params["vertex_texcoords"] = mi.Float((tris[..., :2] / (2.0 * square)).reshape(-1).astype(np.float32))
    params["faces"] = mi.UInt32(np.arange(3 * n, dtype=np.uint32))
    params.update()
    return dict(d, floor=mesh)


def _tetra_see_through(d: dict, *, opacity: float = 0.5) -> dict:
    """The tetrahedron behind an opacity mask of ``opacity`` (light passes the rest straight through, shadow rays
    too under ``volpath``)."""
    from mcrt.mitsuba_scene import _bsdf_dict, _mesh

    sf = fresh._surface("tetrahedron")
    return dict(d, tetrahedron=_mesh(sf, {"type": "mask", "opacity": opacity, "bsdf": _bsdf_dict(sf.material)}))


def _unit(v) -> tuple[float, ...]:
    a = np.asarray(v, np.float64)
    return tuple(float(c) for c in a / np.linalg.norm(a))


def _albedos_normalised(s):
    """Every Lambertian's albedo divided by its length (a colour built with the vector type, which normalises)."""
    from mcrt.scene import Lambertian

    room = replace(s.room, floor_albedo=_unit(s.room.floor_albedo), ceiling_albedo=_unit(s.room.ceiling_albedo),
                   walls=tuple(replace(w, albedo=_unit(w.albedo)) for w in s.room.walls))
    objs = tuple(replace(o, material=replace(o.material, albedo=_unit(o.material.albedo)))
                 if isinstance(o.material, Lambertian) else o for o in s.objects)
    return replace(s, room=room, objects=objs)


def _floor_fan_short(d: dict) -> dict:
    """The floor's fan from corner A one triangle short (``range(1, n - 2)``): triangle A, E, F missing."""
    from mcrt.mitsuba_scene import _bsdf_dict

    sf = fresh._surface("floor")
    return fresh._rebuilt(d, "floor", np.asarray(sf.triangles)[:-1], _bsdf_dict(sf.material))


def _tetra_model_space(s):
    """The tetrahedron's vertices about its centroid (model space), the move into place never applied."""
    def about_centroid(o):
        v = np.asarray(o.vertices, np.float64)
        return replace(o, vertices=tuple(tuple(float(c) for c in p) for p in v - v.mean(axis=0)))

    return replace(s, objects=tuple(about_centroid(o) if o.name == "tetrahedron" else o for o in s.objects))


def _sphere_normal_from_origin(d: dict, *, segments: int = 128, rings: int = 64) -> dict:
    """The mirror sphere with the normal ``normalize(hit)`` (the centre not subtracted): a fine mesh of the sphere
    whose vertex (shading) normals are their positions normalised, the mirror reflecting about them. That normal
    points away from the camera, so the mirror is two-sided, as the student's reflection ``d - 2 (d.n) n`` is (it
    does not change with n's sign)."""
    import mitsuba as mi

    from mcrt.mitsuba_scene import _bsdf_dict
    from mcrt.scene import load_scene

    sph = next(o for o in load_scene().objects if o.name == "sphere")
    tris = untried._sphere_mesh(sph.center, sph.radius, segments, rings).reshape(-1, 3)
    props = mi.Properties()
    props["bsdf"] = mi.load_dict({"type": "twosided", "bsdf": _bsdf_dict(sph.material)})
    n = tris.shape[0] // 3
    mesh = mi.Mesh("sphere", 3 * n, n, props, has_vertex_normals=True)
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(tris.reshape(-1).astype(np.float32))
    params["vertex_normals"] = mi.Float((tris / np.linalg.norm(tris, axis=1, keepdims=True)).reshape(-1)
                                        .astype(np.float32))
    params["faces"] = mi.UInt32(np.arange(3 * n, dtype=np.uint32))
    params.update()
    return dict(d, sphere=mesh)


def _forward_negated(s):
    """The camera's view vector negated (``+ w`` where the look-from-minus-look-at convention needs ``- w``); its
    right vector kept, so the image is a camera looking back, mirrored."""
    c = s.cameras["near"]
    return cases._camera(s, forward=tuple(-f for f in c.forward))


def _light_vertices(d: dict, change, *, reflecting: bool = False) -> dict:
    """The light's mesh rebuilt (black, or reflecting like the ceiling), its (2, 3, 3) vertices as ``change`` makes
    them."""
    import mitsuba as mi

    d = untried._light_reflecting(d) if reflecting else untried._light_mesh(d)
    params = mi.traverse(d["light"])
    v = change(np.array(params["vertex_positions"], np.float32).reshape(-1, 3, 3))
    params["vertex_positions"] = mi.Float(np.asarray(v, np.float32).reshape(-1))
    params.update()
    return d


def _second_face_flipped(v: np.ndarray) -> np.ndarray:
    v[1] = v[1, [0, 2, 1]]
    return v


def _light_second_face_up(d: dict) -> dict:
    """The light's second triangle wound the other way: its normal up, so that half emits into the ceiling."""
    return _light_vertices(d, _second_face_flipped)


def _doubled_about_centre(v: np.ndarray) -> np.ndarray:
    c = v.reshape(-1, 3).mean(axis=0)
    return c + (v - c) * np.array([2.0, 2.0, 1.0], np.float32)


def _light_4x4(d: dict) -> dict:
    """The light as the 4 x 4 square its samples cover, same radiance, reflecting like the ceiling: with the camera's
    view of the light taken from the scene (:func:`mcrt.grade.accuracy.novel._light_sampled_elsewhere`), the band
    around the real square shows the ceiling there (the square itself reflects a little light it should not)."""
    return _light_vertices(d, _doubled_about_centre, reflecting=True)


# --------------------------------------------------------------------------
# Files as students' programs write them (the program's buffer in, file out)
# --------------------------------------------------------------------------


def _rgbe_log2(image: np.ndarray) -> np.ndarray:
    """(H, W, 4) RGBE bytes with the exponent ``floor(log2(m))`` of the largest channel m (``frexp``'s less one): the
    channels times 256 / 2^e, rounded, so m's mantissa is 256 to 511, which the cast to bytes wraps."""
    v = np.maximum(np.nan_to_num(image.astype(np.float64)), 0.0)
    m = v.max(axis=2)
    ok = m > 1e-32
    e = np.floor(np.log2(np.where(ok, m, 1.0)))
    codes = np.floor(v * (256.0 / 2.0 ** e)[..., None] + 0.5).astype(np.int64) % 256
    rgbe = np.zeros(m.shape + (4,), np.uint8)
    rgbe[..., :3] = np.where(ok[..., None], codes, 0)
    rgbe[..., 3] = np.where(ok, e + 128, 0)
    return rgbe


def _write_hdr_log2_exponent(image: np.ndarray, folder: Path) -> Path:
    h, w = image.shape[:2]
    path = folder / "render.hdr"
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"-Y {h} +X {w}\n".encode()
                     + _rgbe_log2(image).tobytes())
    return path


def _power_2_4(image: np.ndarray) -> np.ndarray:
    """8-bit codes of ``v ** (1 / 2.4)``: sRGB's exponent alone, without its linear segment, scale and offset."""
    return np.floor(np.clip(np.nan_to_num(image), 0.0, 1.0) ** (1.0 / 2.4) * 255.0 + 0.5).astype(np.uint8)


def _write_png_power_2_4(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_power_2_4(image), folder)


def _write_png_srgb_chunk(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB PNG with an ``sRGB`` chunk (rendering intent perceptual) after its header chunk."""
    path = novel._write_png(blind._srgb8(image), folder)
    data = path.read_bytes()
    end_of_ihdr = 8 + 4 + 4 + 13 + 4  # signature, then IHDR's length, type, 13 bytes and CRC
    path.write_bytes(data[:end_of_ihdr] + unseen._png_chunk(b"sRGB", b"\x00") + data[end_of_ihdr:])
    return path


def _write_exr_decreasing_y(image: np.ndarray, folder: Path) -> Path:
    """A float EXR (R, G, B) whose scanlines are stored bottom line first (line order ``DECREASING_Y``)."""
    import OpenEXR

    path = folder / "render.exr"
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
                  "lineOrder": OpenEXR.DECREASING_Y},
                 {c: np.ascontiguousarray(image[..., i], np.float32) for i, c in enumerate("RGB")}).write(str(path))
    return path


# --------------------------------------------------------------------------
# Correct renders made in other ways
# --------------------------------------------------------------------------


def _welford(x, *, passes: int, spp: int, seed: int):
    """``passes`` Mitsuba passes of ``spp`` (a seed each) combined by a running mean, ``mean += (pass - mean) / k``."""
    h, w = x.shape[:2]
    mean = np.zeros((h, w, 3))
    for k in range(passes):
        mean += (_render(w, h, spp, seed + k) - mean) / (k + 1)
    return mean


def _mi_render(x, *, spp: int, seed: int):
    """Mitsuba's own ``mi.render`` of the scene's dict: its film (box filter) accumulates the samples."""
    import mitsuba as mi

    from mcrt.mitsuba_scene import scene_dict
    from mcrt.scene import load_scene

    h, w = x.shape[:2]
    return np.asarray(mi.render(mi.load_dict(scene_dict(load_scene(), "near", w, h, 8, spp=spp)), spp=spp, seed=seed),
                      np.float64)


def _caustics_apart(x, *, spp: int, seed: int):
    """mcrt's paths without mirror caustics and the mirror caustics alone (eye D ... D S+ L), two renders summed."""
    return (untold._mcrt(x, spp=spp, seed=seed, mirror_caustics="skip")
            + untold._mcrt(x, spp=spp, seed=seed + 1, mirror_caustics="only"))


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_film_grain", "pp_histogram_equalised", "pp_highlights_knee", "pp_edges_smoothed"),
    "file": ("file_hdr_log2_exponent", "file_png_power_2_4", "file_two_decimals", "file_manifest_says_linear"),
    "materials": ("floor_checkerboard", "floor_wall_ab_colour", "tetra_see_through", "albedos_normalised"),
    "geometry": ("floor_fan_short", "tetra_model_space", "sphere_normal_from_origin"),
    "camera": ("camera_looking_back", "jitter_in_disk", "jitter_fixed_grid"),
    "light": ("light_sampled_4x4", "light_face_wound_up", "light_z_sign"),
    "integrator": ("first_hit_unlit", "roulette_unstopped", "mirror_lit_in_light_sampling", "mirror_cosine_weighted"),
    "samples": ("passes_renormalised", "samples_random_pixels", "squares_written"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_film_grain", "grain", **_posted("grain_0.05", partial(_grain, seed=_crc("pp_film_grain"))),
             truth="film grain for the look: a normal number a pixel times 0.05 sqrt(luminance), clipped at 0, as EXR"),
        Spec("pp_histogram_equalised", "tone_map", True, held_out=True, **_posted("equalised", _equalised),
             truth="skimage.exposure.equalize_hist over the whole image (256 bins): values in [0, 1], as EXR"),
        Spec("pp_highlights_knee", "tone_map", **_posted("knee_0.8", _soft_knee),
             truth="highlights compressed above 0.8 by a soft knee towards 1 (the light, its reflection, the brightest "
             "patches), as EXR"),
        Spec("pp_edges_smoothed", "blur", held_out=True, **_posted("fxaa_like", _edges_smoothed),
             truth="an FXAA-like pass: pixels whose 3 x 3 display-luma range is over max(0.0625, 0.125 max) replaced "
             "by their 3 x 3 mean, as EXR"),
        # Writing the file
        Spec("file_hdr_log2_exponent", "code_overflow", True, writer=_write_hdr_log2_exponent, file="hdr-log2-exponent",
             truth="a Radiance HDR with exponent floor(log2(max)) for frexp's: the largest channel's mantissa 256-511 "
             "wrapped to a byte"),
        Spec("file_png_power_2_4", "encoding", held_out=True, writer=_write_png_power_2_4, file="png-power-1/2.4",
             truth="an 8-bit PNG of v ** (1 / 2.4): sRGB's exponent without its linear segment and offset"),
        Spec("file_two_decimals", "quantisation", **_posted("rounded_2dp", partial(np.round, decimals=2)),
             truth="the values rounded to two decimals before the EXR (np.round(img, 2)): the shadows in steps of "
             "0.01"),
        Spec("file_manifest_says_linear", "encoding", held_out=True, spp=256, file="png-srgb",
             manifest="linear = true\n",
             truth="an 8-bit sRGB PNG whose manifest says linear = true (a template's line copied)"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("floor_checkerboard", "albedo", True, mitsuba_edit=_floor_checker,
             truth="a tutorial's checkerboard left on the floor: squares of 2, albedos 0.6 and 0.3"),
        Spec("floor_wall_ab_colour", "albedo", True, held_out=True, edit=cases.floor_albedo((0.75, 0.15, 0.15)),
             truth="the floor given wall AB's colour (0.75, 0.15, 0.15) (the walls' list read at the floor's slot)"),
        Spec("tetra_see_through", "material", True, integrator="volpath", mitsuba_edit=_tetra_see_through,
             truth="the tetrahedron half see-through (an opacity field left at 0.5), shadows too"),
        Spec("albedos_normalised", "albedo", True, held_out=True, edit=_albedos_normalised,
             truth="every albedo divided by its length (built with the normalising vector type): greys 0.577, walls' "
             "main channel near 0.96"),
        # Geometry
        Spec("floor_fan_short", "mesh_face", True, mitsuba_edit=_floor_fan_short,
             truth="the floor's fan from A one triangle short: triangle A, E, F missing, the void seen through it"),
        Spec("tetra_model_space", "object_moved", True, held_out=True, edit=_tetra_model_space,
             truth="the tetrahedron left in model space, about its centroid at the origin: just in front of the "
             "camera"),
        Spec("sphere_normal_from_origin", "normals", True, mitsuba_edit=_sphere_normal_from_origin,
             truth="the sphere's normal normalize(hit), its centre never subtracted: the mirror reflecting about "
             "nearly one direction"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera model
        Spec("camera_looking_back", "camera_rotation", True, edit=_forward_negated,
             **_posted("mirrored", _columns_reversed),
             truth="the view vector's sign flipped (+ w for - w): the camera looking back along -x, the image "
             "mirrored"),
        Spec("jitter_in_disk", "pixel_footprint", held_out=True, **_posted("jitter_disk", partial(
            _jitter_disk, spp=4, seed=c("jitter_in_disk"))),
             truth="sub-pixel offsets uniform in a disk of diameter one pixel (a disk sampler reused)"),
        Spec("jitter_fixed_grid", "pixel_footprint", **_posted("grid_2x2", partial(
            _grid_2x2, spp=64, seed=c("jitter_fixed_grid"))),
             truth="every sample through one of four fixed points (0.25 or 0.75 in x and y): a 2 x 2 grid, not "
             "jittered"),
        # Light model
        Spec("light_sampled_4x4", "light_pdf", True, **_posted("light_4x4", partial(
            novel._light_sampled_elsewhere, spp=256, seed=c("light_sampled_4x4"), dict_edit=_light_4x4)),
             truth="the light sampled over 4 x 4 (its half-size taken for its size), pdf 1/16, samples off the light "
             "counted: its light on surfaces from a 4 x 4 square, the light seen right"),
        Spec("light_face_wound_up", "light_facing", True, held_out=True, mitsuba_edit=_light_second_face_up,
             truth="the light's second triangle wound the other way: half the square emits into the ceiling"),
        Spec("light_z_sign", "light_position", True, edit=cases.light(center=(5.0, 0.0, -4.99)),
             truth="the light's height typed -4.99 for 4.99: just above the floor, emitting into it"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples and passes."""
    c = _crc
    return (
        # Integrator
        Spec("first_hit_unlit", "direct_missing", True, **_posted("first_hit_unlit", partial(
            _first_hit_unlit, spp=256, seed=c("first_hit_unlit"))),
             truth="no light sampled at the first surface hit (if depth > 0 around the light sample): the surfaces "
             "seen lit only indirectly"),
        Spec("roulette_unstopped", "roulette", True, held_out=True, **_posted("roulette_unstopped", partial(
            _roulette_unstopped, spp=128, seed=c("roulette_unstopped"))),
             truth="Russian roulette from the 3rd segment, survival 0.8, survivors divided by 0.8 and losers not "
             "stopped: each later segment weighs 1.2"),
        Spec("mirror_lit_in_light_sampling", "material", True, **_posted("mirror_glow", partial(
            _mirror_lit_as_diffuse, spp=256, seed=c("mirror_lit_in_light_sampling"))),
             truth="the mirror's BSDF evaluated as 1 in light sampling: the sphere glows as a Lambertian of albedo pi "
             "lit directly, over its reflection"),
        Spec("mirror_cosine_weighted", "specular_weight", True, held_out=True, **_posted("mirror_cosine", partial(
            _mirror_cosine, spp=16, seed=c("mirror_cosine_weighted"))),
             truth="each mirror bounce weighted by the cosine, as a diffuse bounce: the sphere darker towards its "
             "rim"),
        # Samples and passes
        Spec("passes_renormalised", "light_radiance", **_posted("renormalised_passes", partial(
            _renormalised_each_pass, passes=4, spp=64, seed=c("passes_renormalised"))),
             truth="4 passes of 64 spp, the buffer divided by 64 after each: the earlier means added in, 1.6 % too "
             "bright"),
        Spec("samples_random_pixels", "sample_count", held_out=True, **_posted("random_pixels", partial(
            _random_pixel_counts, spp=256, seed=c("samples_random_pixels"))),
             truth="256 W H samples thrown at random pixels, each pixel's sum divided by 256: each pixel times "
             "Poisson(256) / 256"),
        Spec("squares_written", "wrong_buffer", True, **_posted("mean_of_squares", partial(
            _mean_of_squares, spp=256, seed=c("squares_written"))),
             truth="the buffer of squared samples over n written for the mean's: the mean squared plus the variance"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_mcrt_bidirectional", None, spp=64, renderer="mcrt", **_posted("mcrt_bidirectional", partial(
            untold._mcrt, spp=64, seed=c("ok_mcrt_bidirectional"), bidirectional=True)),
             truth="mcrt's bidirectional estimator (light tracing for the mirror caustics) 64 spp, EXR"),
        Spec("ok_mcrt_plugin", None, held_out=True, spp=64, renderer="mcrt", **_posted("mcrt_plugin", partial(
            untold._mcrt, spp=64, seed=c("ok_mcrt_plugin"), renderer="plugin")),
             truth="mcrt's estimator as a Mitsuba integrator (renderer plugin) 64 spp, EXR"),
        Spec("ok_mcrt_sobol", None, spp=128, renderer="mcrt", **_posted("mcrt_sobol", partial(
            untold._mcrt, spp=128, seed=c("ok_mcrt_sobol"), pixel_sampler="sobol")),
             truth="mcrt 128 spp with Owen-scrambled Sobol pixel samples (8 replicates), EXR"),
        Spec("ok_welford_passes", None, held_out=True, spp=256, **_posted("welford", partial(
            _welford, passes=8, spp=32, seed=c("ok_welford_passes"))),
             truth="Mitsuba path, 8 passes of 32 spp combined by a running (Welford) mean, EXR"),
        Spec("ok_mi_render_film", None, spp=256, **_posted("mi_render", partial(
            _mi_render, spp=256, seed=c("ok_mi_render_film"))),
             truth="Mitsuba's own mi.render 256 spp through its film (box filter), EXR"),
        Spec("ok_png_srgb_chunk", None, held_out=True, spp=320, writer=_write_png_srgb_chunk, file="png-srgb-chunk",
             truth="Mitsuba path 320 spp, an 8-bit sRGB PNG with an sRGB chunk"),
        Spec("ok_exr_decreasing_y", None, spp=240, writer=_write_exr_decreasing_y, file="exr-decreasing-y",
             truth="Mitsuba path 240 spp, a float EXR stored bottom line first (DECREASING_Y)"),
        Spec("ok_mcrt_caustics_apart", None, held_out=True, spp=96, renderer="mcrt", **_posted("caustics_apart",
             partial(_caustics_apart, spp=96, seed=c("ok_mcrt_caustics_apart"))),
             truth="mcrt 96 spp without mirror caustics plus 96 spp of the mirror caustics alone, summed, EXR"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "tone_map": "a curve on the values after rendering (the histogram equalised, the highlights compressed)",
    "blur": "a filter after rendering (edges smoothed by an anti-aliasing pass)",
    "code_overflow": "codes past a byte wrapped round (an RGBE mantissa with the exponent one short)",
    "encoding": "the values' encoding (a power 1/2.4 for the sRGB curve; an sRGB PNG declared linear)",
    "quantisation": "values quantised wrongly (rounded to two decimals)",
    "albedo": "a surface's colour (a checkerboard left on the floor, another surface's colour, albedos normalised)",
    "material": "a surface rendered with another material (see-through; the mirror lit as a diffuse surface)",
    "mesh_face": "a face of a mesh missing (a floor triangle)",
    "object_moved": "an object moved (a mesh left in model space)",
    "normals": "surface normals wrong (the sphere's taken from the origin)",
    "camera_rotation": "the camera's rotation (the view vector's sign flipped)",
    "pixel_footprint": "each pixel's samples not spread over its square (a disk, four fixed points)",
    "light_pdf": "the light sampled wrongly (over a larger square): the light seen right, its light on surfaces not",
    "light_facing": "the light emitting on the wrong side (half of it, a triangle wound the other way)",
    "light_position": "the light's position (its height's sign)",
    "roulette": "Russian roulette done wrongly (the paths it should stop not stopped)",
    "light_radiance": "the light's radiance (or a constant factor: the earlier passes' means added in)",
}
_WORDS = {**cases.CAUSES, **outside.CAUSES, **programs.NEW_CAUSES, **fresh.NEW_CAUSES, **blind.NEW_CAUSES,
          **unseen.NEW_CAUSES, **untried.NEW_CAUSES, **novel.NEW_CAUSES, **untold.NEW_CAUSES, **NEW_CAUSES,
          **_REWORDED}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = {c: _WORDS[c] for c in dict.fromkeys(s.cause for s in MISTAKES)}


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
