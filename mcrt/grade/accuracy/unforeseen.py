r"""A sixteenth class of hand-ins: mistakes in students' tracers, scene input and output no class tried, written blind.

How it was written: from what goes wrong in students' programs (the steps
after rendering, the code that saves the image and its manifest, the scene
typed in or parsed, the camera's rays and sub-pixel offsets, the light's
samples and the emission a ray sees, the integrator's loop, the loops and
threads that add up the samples and place the tiles), not from the grader.
Its author read the other classes' specs and cause words, the catalogue
(:mod:`mcrt.mutants`), the scene files and design notes, mcrt's scene,
camera and image code, :data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to
stay clear of their mistakes; never the grader's rules (what decides a
cause) nor its reports, and graded none of it, not one case. Each cause and
``major`` flag was set from the mistake alone; every mistake is worded by a
cause the other classes already have (:data:`NEW_CAUSES` is empty), so
``SAME_MISTAKE`` needed no new entry. The mistakes differ from those of the
fifteen other classes (:mod:`~mcrt.grade.accuracy.cases`,
:mod:`~mcrt.grade.accuracy.outside`, :mod:`~mcrt.grade.accuracy.programs`,
:mod:`~mcrt.grade.accuracy.fresh`, :mod:`~mcrt.grade.accuracy.blind`,
:mod:`~mcrt.grade.accuracy.unseen`, :mod:`~mcrt.grade.accuracy.untried`,
:mod:`~mcrt.grade.accuracy.novel`, :mod:`~mcrt.grade.accuracy.untold`,
:mod:`~mcrt.grade.accuracy.unmet`, :mod:`~mcrt.grade.accuracy.unheard`,
:mod:`~mcrt.grade.accuracy.unsaid`, :mod:`~mcrt.grade.accuracy.unasked`,
:mod:`~mcrt.grade.accuracy.unsought`, :mod:`~mcrt.grade.accuracy.unguessed`)
and from the catalogue's bugs:

* **post-processing**: the chroma (colour differences from the luminance)
  averaged over 2 x 2 blocks (a 4:2:0 subsampling written by hand) on the
  linear render; a triangular dither of one 8-bit step added to the linear
  values of an EXR; a 3 x 3 Laplacian sharpening kernel; scikit-image's
  sigmoid contrast curve (``adjust_sigmoid``, cutoff 0.5, gain 10);
* **writing the file**: the film's sum buffer (256 samples) written for the
  mean; a half-float EXR saved with B44 compression (lossy); 16-bit sRGB
  codes ``round(v * 65536)`` (white wraps to 0); a float image handed to
  imageio, which stretches what lies outside [0, 1] from its minimum to its
  maximum (linear codes, read as sRGB);
* **materials**: every Lambertian's BRDF times an energy "safety factor"
  0.95; the walls given per-vertex colours (each corner the mean of its two
  walls' colours, a gradient along every wall); the tetrahedron given a
  principled material whose metallic flag was left at 1;
* **geometry**: the ceiling placed at the room's height 10 for z = 5 (the
  light hanging mid-air); a hole cut in the ceiling for the light with a
  margin (2.2 x 2.2): a thin gap round the light onto the void; the apex's
  height above the base (2.9) read as its z;
* **camera**: the field of view halved twice (``radians(fov) / 4``: 45
  degrees); the sub-pixel offsets' vertical stratum taken from the pixel's
  row (``j % 16``) for the sample's index; a stereo template's right-eye
  offset (0.032) left on;
* **light model**: the light's radiance parsed as an 8-bit colour (20 /
  255); its samples drawn with a margin of 1 % of each side and the pdf of
  the smaller square; the emission a camera or mirror ray sees weighted by
  the cosine at the light;
* **integrator**: the diffuse bounce's azimuth drawn as ``pi u`` for
  ``2 pi u`` (half the hemisphere, weighted as the whole); the depth counted
  at diffuse vertices only (a camera ray's mirror bounce not counted); the
  mirror reflecting the camera's forward vector for every camera ray; the
  throughput divided by the roulette's survival 0.5 before its test, the
  light sample added either way;
* **samples and passes**: the tiles' origins never added to their pixels'
  rays (every tile the top-left tile's view); the film's sums kept in
  bfloat16; four threads storing (``=``) their partial sums for adding; the
  manifest's spp the samples times the maximum depth.

The correct hand-ins come in ways no class used: Mitsuba with sub-pixel
offsets from a rank-1 lattice shifted at random in each pixel, Mitsuba with
every wall split into four triangles about its centre, a float EXR with
ZSTD compression, a Radiance HDR stored column by column (``+X W -Y H``),
mcrt with the camera's forward and up typed unnormalised, an 8-bit PNG
written by hand with the Up filter and its data split over several IDAT
chunks, Mitsuba with the sensor's ``to_world`` matrix built by hand, and
Mitsuba with the mirror a blend of two perfect mirrors.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s
``edit`` and ``mitsuba_edit``), Mitsuba renders combined where light
transport or pixel integrals are linear in what is combined (paths by
length, windows of the camera, threads), Mitsuba's path integrator sampling
the rays a student's camera, mirror or bounce makes (the helpers of
:mod:`~mcrt.grade.accuracy.unsaid`), or its samples, one by one, added up as
a student's loop adds them (:func:`mcrt.grade.accuracy.unasked._samples`,
:func:`mcrt.grade.accuracy.unsought._film_samples`), or correct renders
post-processed and written with NumPy, SciPy, scikit-image, OpenEXR and
Pillow as students' programs do. mcrt renders only correct hand-ins.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over
:data:`CATEGORIES`: the 2nd, 4th, ... of each category and of the correct
hand-ins) are as in :mod:`~mcrt.grade.accuracy.unguessed`, fixed before any
case was graded.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unguessed, unheard, unmet,
                                 unsaid, unseen, unsought, untold, untried)
from mcrt.grade.accuracy.cases import Spec

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


def _crc(name: str) -> int:
    return 301000 + zlib.crc32(name.encode()) % 100000


_render = unseen._render
_posted = unseen._posted

#: The grade's image side and the class's spp, for the totals a manifest quotes (the class is built at 64 x 64).
_SIDE = 64
_S = 256
#: The assignment's maximum depth.
_DEPTH = 8


def _scene():
    from mcrt.scene import load_scene

    return load_scene()


# --------------------------------------------------------------------------
# Post-processing (linear render in, what the program writes out)
# --------------------------------------------------------------------------


def _chroma_2x2(x):
    """The colour differences from the luminance (B - Y, R - Y) averaged over 2 x 2 blocks (4:2:0 chroma subsampling
    written by hand) on the linear render, the luminance kept, back to R, G, B, negatives clipped to 0."""
    x = np.asarray(x, np.float64)
    h, w = x.shape[:2]
    y = unseen._luma(x)
    cb, cr = x[..., 2] - y, x[..., 0] - y

    def blocks(c):
        hh, ww = h - h % 2, w - w % 2
        out = c.copy()
        m = c[:hh, :ww].reshape(hh // 2, 2, ww // 2, 2).mean(axis=(1, 3))
        out[:hh, :ww] = np.repeat(np.repeat(m, 2, axis=0), 2, axis=1)
        return out

    cb, cr = blocks(cb), blocks(cr)
    r, b = y + cr, y + cb
    k = programs._LUMA
    g = (y - k[0] * r - k[2] * b) / k[1]
    return np.maximum(np.stack([r, g, b], axis=-1), 0.0)


def _dither_linear(x, *, seed: int = 0, step: float = 1.0 / 255.0):
    """A triangular-pdf dither of one 8-bit step ((u1 - u2) / 255, meant for an 8-bit file) added to the linear
    values, negatives clipped to 0."""
    x = np.asarray(x, np.float64)
    u = np.random.default_rng(seed).random((2,) + x.shape)
    return np.maximum(x + step * (u[0] - u[1]), 0.0)


#: The 3 x 3 Laplacian sharpening kernel of image-processing tutorials (the image plus its negative Laplacian).
_SHARPEN = np.array([[0.0, -1.0, 0.0], [-1.0, 5.0, -1.0], [0.0, -1.0, 0.0]])


def _laplacian_sharpen(x):
    """Each channel convolved with :data:`_SHARPEN` (scipy.ndimage.convolve, edges repeated), negatives clipped to 0."""
    from scipy.ndimage import convolve

    x = np.asarray(x, np.float64)
    return np.maximum(np.stack([convolve(x[..., c], _SHARPEN, mode="nearest") for c in range(3)], axis=-1), 0.0)


def _sigmoid(x, *, cutoff: float = 0.5, gain: float = 10.0):
    """skimage.exposure.adjust_sigmoid: 1 / (1 + exp(gain (cutoff - v))) of every value."""
    from skimage.exposure import adjust_sigmoid

    return adjust_sigmoid(np.maximum(np.asarray(x, np.float64), 0.0), cutoff=cutoff, gain=gain)


# --------------------------------------------------------------------------
# Files as students' programs write them (the program's buffer in, file out)
# --------------------------------------------------------------------------


def _write_exr_sum(image: np.ndarray, folder: Path, *, spp: int = _S) -> Path:
    """A float EXR of the film's sum buffer: each pixel the sum of its ``spp`` samples (the mean times ``spp``)."""
    return fresh._write_exr(np.asarray(image, np.float64) * spp, folder)


def _write_exr_b44(image: np.ndarray, folder: Path) -> Path:
    """A half-float EXR (R, G, B) with B44 compression: lossy, each 4 x 4 block of a channel packed in 14 bytes."""
    import OpenEXR

    path = folder / "render.exr"
    chans = {c: np.ascontiguousarray(image[..., i], np.float16) for i, c in enumerate("RGB")}
    OpenEXR.File({"compression": OpenEXR.B44_COMPRESSION, "type": OpenEXR.scanlineimage}, chans).write(str(path))
    return path


def _codes_times_65536(image: np.ndarray) -> np.ndarray:
    """16-bit sRGB codes ``round(v * 65536)`` of the values clipped to [0, 1], cast to uint16: 65536 (white, and
    everything from 1 - 1/131072) wraps to 0."""
    from mcrt.image_files import srgb_oetf

    v = srgb_oetf(np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 1.0))
    return np.round(v * 65536.0).astype(np.int64).astype(np.uint16)


def _write_png16_times_65536(image: np.ndarray, folder: Path) -> Path:
    return untried._write_png16(_codes_times_65536(image), folder)


def _imageio_stretched(image: np.ndarray) -> np.ndarray:
    """What imageio (2.x, ``image_as_uint``) makes of a float image whose values leave [0, 1]: the values stretched
    from their minimum to their maximum onto 0-255, ``+ 0.499999999``, cast to uint8 (linear codes)."""
    v = np.nan_to_num(np.asarray(image, np.float64))
    lo, hi = float(v.min()), float(v.max())
    return ((v - lo) / max(hi - lo, 1e-300) * 255.0 + 0.499999999).astype(np.uint8)


def _write_png_imageio_stretched(image: np.ndarray, folder: Path) -> Path:
    return novel._write_png(_imageio_stretched(image), folder)


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _corner_colours(s) -> dict[str, np.ndarray]:
    """Each corner's colour: the mean of the two walls' colours that meet there (a mesh exporter's vertex colours)."""
    walls = s.room.walls
    out = {}
    for k, w in enumerate(walls):
        out[w.corners[0]] = (np.asarray(w.albedo, np.float64) + np.asarray(walls[k - 1].albedo, np.float64)) / 2.0
    return out


def _vertex_colour_mesh(name: str, tris: np.ndarray, colours: np.ndarray):
    """An ``mi.Mesh`` of ``tris`` (n, 3, 3) with the per-vertex colours ``colours`` (n, 3, 3) interpolated across each
    face by a two-sided diffuse BSDF (``mesh_attribute`` texture)."""
    import mitsuba as mi

    tris = np.asarray(tris, np.float64)
    n = tris.shape[0]
    props = mi.Properties()
    props["bsdf"] = mi.load_dict({"type": "twosided", "bsdf": {
        "type": "diffuse", "reflectance": {"type": "mesh_attribute", "name": "vertex_color"}}})
    mesh = mi.Mesh(name, 3 * n, n, props)
    mesh.add_attribute("vertex_color", 3, mi.Float(np.asarray(colours, np.float32).reshape(-1)))
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(tris.reshape(-1).astype(np.float32))
    params["faces"] = mi.UInt32(np.arange(3 * n, dtype=np.uint32))
    params.update()
    return mesh


def _wall_vertex_colours(name: str) -> np.ndarray:
    """(n, 3, 3): the colour of each vertex of wall ``name``'s triangles, its corner's (:func:`_corner_colours`)."""
    s = _scene()
    colours = _corner_colours(s)
    xy = {c: np.asarray(p, np.float64) for c, p in s.room.corners.items()}
    tris = np.asarray(fresh._surface(name).triangles, np.float64)
    out = np.zeros_like(tris)
    for i, tri in enumerate(tris):
        for j, v in enumerate(tri):
            corner = min(xy, key=lambda c: float(np.hypot(*(xy[c] - v[:2]))))
            out[i, j] = colours[corner]
    return out


def _walls_vertex_coloured(d: dict) -> dict:
    """Every wall with per-vertex colours: each corner the mean of its two walls' albedos, interpolated along the
    wall."""
    out = dict(d)
    for w in _scene().room.walls:
        name = f"wall_{w.corners[0]}{w.corners[1]}"
        out[name] = _vertex_colour_mesh(name, fresh._surface(name).triangles, _wall_vertex_colours(name))
    return out


def _tetra_metallic(d: dict) -> dict:
    """The tetrahedron a principled material (base colour its albedo, roughness 0.5) with its metallic flag at 1."""
    sf = fresh._surface("tetrahedron")
    bsdf = {"type": "principled", "base_color": {"type": "rgb", "value": [float(a) for a in sf.material.albedo]},
            "metallic": 1.0, "roughness": 0.5}
    return fresh._rebuilt(d, "tetrahedron", sf.triangles, bsdf)


def _ceiling_at_height(s, *, z: float = 10.0):
    """The ceiling (and the walls' tops) at z = ``z``: the room's height read as the ceiling's z."""
    return replace(s, room=replace(s.room, ceiling_z=float(z)))


def _hole_tris(*, margin: float = 0.1) -> np.ndarray:
    """The ceiling's triangles with the light's footprint grown by ``margin`` on every side cut out of it (the
    scene's own cutting, :func:`mcrt.scene._fan`), wound to face down."""
    from mcrt.scene import _fan

    s = _scene()
    cx, cy, _ = s.light.center
    hx, hy = s.light.size[0] / 2.0 + margin, s.light.size[1] / 2.0 + margin
    z = s.room.ceiling_z
    return np.array([[[*a, z], [*c, z], [*b, z]] for a, b, c in _fan(s.room.polygon(), (cx - hx, cx + hx, cy - hy,
                                                                                        cy + hy))], np.float64)


def _ceiling_hole(d: dict) -> dict:
    """A hole cut in the ceiling for the light, 0.1 wider than it on every side (2.2 x 2.2)."""
    from mcrt.mitsuba_scene import _bsdf_dict

    return fresh._rebuilt(d, "ceiling", _hole_tris(), _bsdf_dict(fresh._surface("ceiling").material))


def _tetra_apex_relative(s, *, height: float = 2.9):
    """The apex's height above the base (2.9) read as its z: (8.5, -2.3, 2.9) for (8.5, -2.3, -2.0)."""
    return unguessed._tetra_vertices(s, lambda v: tuple(v[:3]) + ((v[3][0], v[3][1], float(height)),))


def _light_margin_tris(*, margin: float = 0.01) -> np.ndarray:
    """The square the light's samples come from when each coordinate is drawn in [margin, 1 - margin] of its side."""
    lt = _scene().light
    return unsaid._square(lt.center[0], lt.center[1], lt.center[2], lt.size[0] / 2.0 * (1.0 - 2.0 * margin))


def _light_margin(d: dict) -> dict:
    """The light as its samples see it: the smaller square of :func:`_light_margin_tris` at the light's radiance."""
    return unsaid._meshes(d, light=(_light_margin_tris(), _scene().light.radiance))


def _walls_in_four(d: dict) -> dict:
    """Every wall's quad split into four triangles about its centre (the same surface, another tessellation)."""
    from mcrt.mitsuba_scene import _bsdf_dict

    for w in _scene().room.walls:
        name = f"wall_{w.corners[0]}{w.corners[1]}"
        sf = fresh._surface(name)
        tris = np.asarray(sf.triangles, np.float64)
        n = np.cross(tris[0, 1] - tris[0, 0], tris[0, 2] - tris[0, 0])
        corners = np.unique(tris.reshape(-1, 3), axis=0)
        centre = corners.mean(axis=0)
        # The corners in order round the centre (in the wall's plane), each edge with the centre a triangle wound as
        # the scene winds the wall.
        u = corners[0] - centre
        v = np.cross(n, u)
        ang = np.arctan2((corners - centre) @ v, (corners - centre) @ u)
        ring = corners[np.argsort(ang)]
        four = np.array([[centre, ring[k], ring[(k + 1) % 4]] for k in range(4)])
        m = np.cross(four[:, 1] - four[:, 0], four[:, 2] - four[:, 0])
        four = np.where((m @ n < 0)[:, None, None], four[:, [0, 2, 1]], four)
        d = fresh._rebuilt(d, name, four, _bsdf_dict(sf.material))
    return d


def _unnormalised_camera(s):
    """The near camera's forward and up typed unnormalised, (3, 0, 0) and (0, 0, 2): the same directions."""
    c = s.cameras["near"]
    return cases._camera(s, forward=tuple(3.0 * a for a in c.forward), up=tuple(2.0 * a for a in c.up))


def _to_world_matrix() -> np.ndarray:
    """(4, 4): the near camera's to_world built by hand: columns left (up x forward), up (forward x left), forward,
    eye (Mitsuba's camera looks along its +z, its +x to the image's left)."""
    cam = _scene().cameras["near"]
    f = np.asarray(cam.forward, np.float64)
    f = f / np.linalg.norm(f)
    left = np.cross(np.asarray(cam.up, np.float64), f)
    left = left / np.linalg.norm(left)
    up = np.cross(f, left)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = left, up, f, cam.eye
    return m


def _sensor_by_hand(d: dict) -> dict:
    import mitsuba as mi

    return dict(d, sensor=dict(d["sensor"], to_world=mi.ScalarTransform4f(_to_world_matrix().tolist())))


def _mirror_as_blend(d: dict) -> dict:
    """The mirror a blend (weight 0.5) of two perfect mirrors: the same BSDF."""
    mirror = {"type": "conductor", "material": "none"}
    return blind._sphere_bsdf(d, {"type": "blendbsdf", "weight": 0.5, "bsdf_0": dict(mirror), "bsdf_1": dict(mirror)})


# --------------------------------------------------------------------------
# The camera's sub-pixel offsets (Mitsuba's samples through them, unsought._film_samples)
# --------------------------------------------------------------------------


def _row_strata(rng, n: int, *, w: int, pixels: int, strata: int = 16):
    """Sub-pixel offsets whose vertical stratum is the pixel's row modulo ``strata`` (``j % 16``, a loop index mixed
    up with the sample's): u uniform, v in [(j % 16) / 16, (j % 16 + 1) / 16)."""
    rows = np.arange(pixels) // w
    u = rng.random((pixels, n))
    v = ((rows % strata)[:, None] + rng.random((pixels, n))) / strata
    return u, v


def _mean_through(x, *, spp: int, seed: int, jitter):
    """Each pixel the mean of Mitsuba's samples through the offsets ``jitter(rng, n, w=, pixels=)`` makes."""
    h, w = x.shape[:2]
    total = np.zeros((h * w, 3))
    for L, _, _ in unsought._film_samples(w, h, spp, seed, partial(jitter, w=w, pixels=w * h)):
        total += L.sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _lattice_generator(n: int) -> int:
    """A generator of a rank-1 lattice of ``n`` points: the integer nearest n / golden ratio coprime with n."""
    g = max(1, int(round(n / ((1.0 + math.sqrt(5.0)) / 2.0))))
    while math.gcd(g, n) != 1:
        g += 1
    return g


def _lattice(rng, n: int, *, w: int, pixels: int):
    """Sub-pixel offsets of a rank-1 lattice (i / n, i g / n), shifted at random in each pixel (Cranley-Patterson):
    every offset uniform on the pixel."""
    i = np.arange(n)
    g = _lattice_generator(n)
    shift = rng.random((2, pixels, 1))
    u = np.mod(i / n + shift[0], 1.0)
    v = np.mod((i * g % n) / n + shift[1], 1.0)
    return u, v


# --------------------------------------------------------------------------
# Renderer mistakes realised with Mitsuba renders combined, on rays, or sample by sample
# --------------------------------------------------------------------------


def _light_seen_cosine(x, *, spp: int, seed: int):
    """The emission a camera ray sees, directly or after its mirror bounce, weighted by the cosine at the light (the
    radiance returned as an intensity's ``Le cos``): Mitsuba's samples on the pinhole's rays, those whose ray (or its
    reflection in the sphere) meets the light first, where a sample is the light's radiance alone, that radiance times
    the cosine."""
    h, w = x.shape[:2]
    le = np.asarray(_scene().light.radiance, np.float64)
    total = np.zeros((h * w, 3))
    for L, o, d in unasked._samples(w, h, spp, seed):
        shape = L.shape[:2]
        o2, d2 = o.reshape(-1, 3), d.reshape(-1, 3)
        ro, rd, hit = unsaid._reflected(o2, d2)
        direct = unasked._hits_light(o2, d2) & (hit == 0)
        mirrored = (hit == 1) & unasked._hits_light(ro, rd)
        cos = np.where(direct, d2[:, 2], np.where(mirrored, rd[:, 2], 1.0))
        # A sample of such a ray is the light's radiance alone (the light's surface is black); one that is not (a
        # ray grazing the light's edge in single precision) is kept as it is.
        seen = (direct | mirrored).reshape(shape) & (np.abs(L - le).max(axis=-1) < 1e-3)
        L = np.where(seen[..., None], le * cos.reshape(shape)[..., None], L)
        total += L.sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _frame_of(n: np.ndarray):
    """(t, b): an orthonormal tangent frame of each unit normal (N, 3), t from ``n x (1, 0, 0)`` (or ``(0, 1, 0)``
    where n is near x)."""
    a = np.where((np.abs(n[:, 0]) < 0.9)[:, None], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    t = unsaid._unit(np.cross(n, a))
    return t, np.cross(n, t)


def _half_circle_directions(rng, n: np.ndarray) -> np.ndarray:
    """(N, 3): cosine-weighted directions about the normals ``n`` with the azimuth ``pi u`` for ``2 pi u``: only the
    half of the hemisphere on the frame's +b side."""
    u1, u2 = rng.random((2, len(n)))
    r, phi = np.sqrt(u1), math.pi * u2
    t, b = _frame_of(n)
    return (r * np.cos(phi))[:, None] * t + (r * np.sin(phi))[:, None] * b + np.sqrt(np.maximum(1.0 - u1, 0.0))[:,
                                                                                                              None] * n


def _first_normal(mscene, o: np.ndarray, d: np.ndarray) -> np.ndarray:
    """(N, 3): the geometric normal of each ray's first hit, turned to face the ray's origin."""
    import mitsuba as mi

    si = mscene.ray_intersect(unsaid._rays(o, d))
    n = mi.Vector3f(si.n)
    n = np.stack([np.array(n[c], np.float64) for c in range(3)], axis=1)
    return np.where((np.einsum("ij,ij->i", n, d) > 0.0)[:, None], -n, n)


def _bounce_half_circle(x, *, spp: int, seed: int):
    """The diffuse bounce's direction drawn with the azimuth ``pi u`` (:func:`_half_circle_directions`), weighted by
    the albedo as a cosine-weighted sample, at the first surface a camera ray meets: its light sample right
    (Mitsuba's max-depth-2 sample minus max-depth-1, same seed), the bounce going on from the hit point with
    Mitsuba's path of the 7 segments left less the emission it sees at once (a student's tracer counts the light by
    light samples). Mirror and light hits, Mitsuba's."""
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
            nrm = _first_normal(full, od, dd)
            p = od + t[diffuse, None] * dd
            nd = _half_circle_directions(rng, nrm)
            po = p + 1e-4 * nrm
            cont = unsaid._sampled(rest, po, nd, cseed + 104729) - unsaid._sampled(one, po, nd, cseed + 104729)
            L[diffuse] = direct + rho[diffuse] * cont
        total += L.reshape(h * w, n, 3).sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _mirror_uncounted(x, *, spp: int, seed: int):
    """The depth counted at diffuse vertices only: a camera ray reflected by the sphere goes on with a path of the
    full 8 segments (Mitsuba's max depth 8 from the sphere, for 7), the rest Mitsuba's path on the pinhole's rays."""
    h, w = x.shape[:2]
    full = unsaid._loaded(_DEPTH)
    total = np.zeros((h * w, 3))
    for cseed, n, fx, fy in unsaid._lanes(w, h, spp, seed):
        o, d = unsaid._pinhole(fx, fy)
        o, d, used = unsaid._reflected(np.asarray(o, np.float64), np.asarray(d, np.float64))
        L = np.zeros((len(o), 3))
        for k in (0, 1):
            sel = used == k
            if sel.any():
                L[sel] = unsaid._sampled(full, o[sel], d[sel], cseed + 7919 * k)
        total += L.reshape(h * w, n, 3).sum(axis=1)
    return (total / spp).reshape(h, w, 3)


def _reflect_forward(o, d):
    """Camera rays that meet the sphere reflected as the camera's forward vector is, ``f - 2 (f . n) n``, not as
    their own directions: (origins, directions, segments used)."""
    c, radius = unsaid._sphere()
    f = np.asarray(_scene().cameras["near"].frame()[2], np.float64)
    oc = o - c
    b = np.einsum("ij,ij->i", oc, d)
    disc = b * b - (np.einsum("ij,ij->i", oc, oc) - radius * radius)
    t = -b - np.sqrt(np.maximum(disc, 0.0))
    hit = (disc > 0.0) & (t > 0.0)
    p = o + t[:, None] * d
    n = (p - c) / radius
    r = unsaid._unit(f[None, :] - 2.0 * (n @ f)[:, None] * n)
    return (np.where(hit[:, None], p + 1e-4 * n, o), np.where(hit[:, None], r, d), hit.astype(int))


def _roulette_divided_first(x, *, spp: int, seed: int, start: int = 3, survival: float = 0.5):
    """Russian roulette from vertex ``start`` with the throughput divided by ``survival`` before the test and the
    vertex's light sample added either way: every vertex's light from ``start`` on counted 1 / survival times
    (paths of ``start`` + 1 segments or more), the continuation unbiased. Same-seed Mitsuba renders: the paths of
    at most ``start`` segments plus 1 / survival times the rest."""
    h, w = x.shape[:2]
    full, short = _render(w, h, spp, seed), _render(w, h, spp, seed, max_depth=start)
    return short + (full - short) / survival


def _tiles_from_origin(x, *, spp: int, seed: int, tiles: int = 4):
    """Each of the ``tiles`` x ``tiles`` tiles rendered with its pixels' rays for the top-left tile's (the tile's
    origin never added), a seed each: the top-left tile's view in every tile."""
    h, w = x.shape[:2]
    th, tw = h // tiles, w // tiles
    window = unseen._window(tw, w, 0.5 - tiles / 2.0, 0.5 - tiles / 2.0)
    out = np.zeros((h, w, 3))
    for r in range(tiles):
        for c in range(tiles):
            out[r * th:(r + 1) * th, c * tw:(c + 1) * tw] = _render(tw, th, spp, seed + r * tiles + c, sensor=window)
    return out


def _bfloat16(a: np.ndarray) -> np.ndarray:
    """``a`` rounded to bfloat16 (8 significant bits, float32's range; round to nearest, ties to even), as float32."""
    b = np.ascontiguousarray(a, np.float32).view(np.uint32).astype(np.uint64)
    b = (b + 0x7FFF + ((b >> 16) & 1)) & 0xFFFF0000
    return b.astype(np.uint32).view(np.float32)


def _bfloat16_sums(x, *, spp: int, seed: int):
    """Each pixel's sum kept in bfloat16 (a GPU tensor's half type), Mitsuba's samples added one by one in a pixel's
    order, each add rounded to bfloat16, the sum divided by the spp at the end: the adds rounded to 8 significant
    bits, the samples under half a step of the sum lost once it is large."""
    h, w = x.shape[:2]
    total = np.zeros((h * w, 3), np.float32)
    for L, _, _ in unasked._samples(w, h, spp, seed):
        for k in range(L.shape[1]):
            total = _bfloat16(total + _bfloat16(L[:, k]))
    return (total.astype(np.float64) / spp).reshape(h, w, 3)


def _last_thread_only(x, *, threads: int, spp: int, seed: int):
    """``threads`` threads of ``spp`` / threads samples each storing (``=``) their partial sums where they should add
    (``+=``): the last thread's sum kept, divided by ``spp``."""
    h, w = x.shape[:2]
    n = spp // threads
    return _render(w, h, n, seed + threads - 1) * n / spp


# --------------------------------------------------------------------------
# Correct files written in other ways
# --------------------------------------------------------------------------


def _write_exr_zstd(image: np.ndarray, folder: Path) -> Path:
    """A float EXR (R, G, B) with ZSTD compression (lossless)."""
    import OpenEXR

    path = folder / "render.exr"
    chans = {c: np.ascontiguousarray(image[..., i], np.float32) for i, c in enumerate("RGB")}
    OpenEXR.File({"compression": OpenEXR.ZSTD_COMPRESSION, "type": OpenEXR.scanlineimage}, chans).write(str(path))
    return path


def _write_hdr_columns(image: np.ndarray, folder: Path) -> Path:
    """A Radiance HDR stored column by column, left column first, each from the top: resolution string
    ``+X W -Y H`` (flat RGBE, mcrt's encoder)."""
    from mcrt.image_files import _rgbe_encode

    h, w = image.shape[:2]
    path = folder / "render.hdr"
    rgbe = _rgbe_encode(path, np.asarray(image, np.float64).transpose(1, 0, 2))
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"+X {w} -Y {h}\n".encode()
                     + np.ascontiguousarray(rgbe).tobytes())
    return path


def _up_filtered(codes: np.ndarray) -> bytes:
    """The PNG scanlines of (H, W, 3) 8-bit codes, each with filter type 2 (Up: each byte less the byte above)."""
    rows = codes.astype(np.int16).reshape(codes.shape[0], -1)
    above = np.vstack([np.zeros_like(rows[:1]), rows[:-1]])
    return b"".join(b"\x02" + ((r - a) % 256).astype(np.uint8).tobytes() for r, a in zip(rows, above))


def _write_png_up_idats(image: np.ndarray, folder: Path, *, chunk: int = 512) -> Path:
    """An 8-bit sRGB PNG written by hand: IHDR, the zlib stream of Up-filtered rows split over IDAT chunks of
    ``chunk`` bytes, IEND."""
    import struct

    h, w = image.shape[:2]
    stream = zlib.compress(_up_filtered(blind._srgb8(image)), 6)
    idats = b"".join(unseen._png_chunk(b"IDAT", stream[k:k + chunk]) for k in range(0, len(stream), chunk))
    data = (b"\x89PNG\r\n\x1a\n" + unseen._png_chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
            + idats + unseen._png_chunk(b"IEND", b""))
    path = folder / "render.png"
    path.write_bytes(data)
    return path


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_chroma_2x2_blocks", "pp_dither_in_linear", "pp_laplacian_sharpen", "pp_sigmoid_contrast"),
    "file": ("file_exr_sum_buffer", "file_exr_b44_lossy", "file_png16_times_65536", "file_png_imageio_stretched"),
    "materials": ("diffuse_energy_factor_095", "walls_vertex_colours", "tetra_metallic_flag"),
    "geometry": ("ceiling_at_room_height", "ceiling_hole_with_margin", "tetra_apex_height_as_z"),
    "camera": ("fov_halved_twice", "strata_row_from_pixel_row", "stereo_right_eye_left_on"),
    "light": ("light_radiance_over_255", "light_samples_margin", "light_seen_cosine_weighted"),
    "integrator": ("bounce_azimuth_half_circle", "depth_mirror_uncounted", "mirror_reflects_forward",
                   "roulette_divided_before_test"),
    "samples": ("tiles_origin_not_added", "film_sums_bfloat16", "threads_store_not_add", "manifest_spp_times_depth"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file and the manifest."""
    return (
        # Post-processing
        Spec("pp_chroma_2x2_blocks", "blur", **_posted("chroma_2x2", _chroma_2x2),
             truth="the colour differences B - Y and R - Y (Y the luminance) averaged over 2 x 2 blocks (a 4:2:0 "
             "chroma subsampling written by hand) on the linear render, the luminance kept, negatives clipped to 0, as "
             "EXR: colours smeared over the blocks, colour fringes at the edges"),
        Spec("pp_dither_in_linear", "grain", held_out=True,
             **_posted("dither_linear", partial(_dither_linear, seed=_crc("pp_dither_in_linear"))),
             truth="a triangular dither of one 8-bit step, (u1 - u2) / 255 (meant for an 8-bit file), added to the "
             "linear values of the EXR, negatives clipped to 0: a little noise, the blacks lifted slightly"),
        Spec("pp_laplacian_sharpen", "sharpen", **_posted("laplacian_sharpen", _laplacian_sharpen),
             truth="a 3 x 3 Laplacian sharpening kernel (5 at the centre, -1 at the four neighbours) on each channel "
             "after rendering, negatives clipped to 0, as EXR: edges and noise sharpened"),
        Spec("pp_sigmoid_contrast", "tone_map", True, held_out=True, **_posted("sigmoid", _sigmoid),
             truth="scikit-image's sigmoid contrast curve (exposure.adjust_sigmoid, cutoff 0.5, gain 10), "
             "1 / (1 + exp(10 (0.5 - v))), applied before the EXR: black 0.007, values over 1 near 1"),
        # Writing the file and the manifest
        Spec("file_exr_sum_buffer", "light_radiance", True, writer=_write_exr_sum, file="exr-sum",
             truth="the film's sum buffer (each pixel the sum of its 256 samples) written to the EXR for the mean: "
             "256 times too bright"),
        Spec("file_exr_b44_lossy", "lossy_compression", held_out=True, writer=_write_exr_b44, file="exr-half-b44",
             truth="a half-float EXR saved with B44 compression (lossy: each 4 x 4 block of a channel packed in 14 "
             "bytes): small errors in every block, larger where a block holds the light's edge"),
        Spec("file_png16_times_65536", "code_overflow", True, writer=_write_png16_times_65536, file="png16-65536",
             truth="16-bit sRGB codes round(v * 65536) (for 65535) of the values clipped to [0, 1], cast to uint16: "
             "white wraps to 0 (the light and its reflection black), every other code a hair high"),
        Spec("file_png_imageio_stretched", "normalised", True, held_out=True, writer=_write_png_imageio_stretched,
             file="png-imageio-stretched",
             truth="the linear float image handed to imageio.imwrite as PNG: its values leave [0, 1], so imageio "
             "stretches them from their minimum to their maximum (the light) onto 0-255, linear codes read as sRGB"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("diffuse_energy_factor_095", "brdf_norm", mitsuba_edit=partial(blind._diffuse_remapped, factor=0.95),
             truth="every Lambertian's BRDF 0.95 albedo / pi (an energy 'safety factor' against albedos near 1): "
             "the direct light on surfaces 5 % dark, each bounce a further 5 %"),
        Spec("walls_vertex_colours", "albedo", True, held_out=True, mitsuba_edit=_walls_vertex_coloured,
             truth="the walls coloured per vertex (a mesh exporter's vertex colours: each corner the mean of the two "
             "walls' colours that meet there), interpolated along each wall: every wall a gradient between its "
             "neighbours' mixes"),
        Spec("tetra_metallic_flag", "material", True, mitsuba_edit=_tetra_metallic,
             truth="the tetrahedron given a principled material (base colour its albedo, roughness 0.5) whose "
             "metallic flag was left at 1: an orange rough metal, glossy, no diffuse light"),
        # Geometry
        Spec("ceiling_at_room_height", "object_moved", True, edit=_ceiling_at_height,
             truth="the ceiling placed at the room's height 10 for z = 5 (the walls built up to it): the light "
             "hanging mid-air 5 below it, the ceiling far above lit only indirectly"),
        Spec("ceiling_hole_with_margin", "mesh_face", held_out=True, mitsuba_edit=_ceiling_hole,
             truth="a hole cut in the ceiling for the light with a margin of 0.1 (2.2 x 2.2 for the 2 x 2 light): "
             "a thin gap round the light onto the void above, black where seen"),
        Spec("tetra_apex_height_as_z", "object_shape", True, edit=_tetra_apex_relative,
             truth="the apex's height above the base (2.9) read as its z: apex (8.5, -2.3, 2.9) for (8.5, -2.3, "
             "-2.0), a spike reaching 2 below the ceiling"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    c = _crc
    return (
        # Camera
        Spec("fov_halved_twice", "camera_fov", True, edit=cases.fov(45.0),
             truth="the field of view halved twice, tan(radians(fov) / 4) for tan(radians(fov) / 2): 45 degrees for "
             "90, the view's middle magnified"),
        Spec("strata_row_from_pixel_row", "pixel_footprint", held_out=True, **_posted("row_strata", partial(
            _mean_through, spp=_S, seed=c("strata_row_from_pixel_row"), jitter=_row_strata)),
             truth="the sub-pixel offsets' vertical stratum taken from the pixel's row (j % 16) for the sample's "
             "index: each pixel's samples in a band 1/16 pixel high at a height cycling with the row, u uniform"),
        Spec("stereo_right_eye_left_on", "camera_eye", edit=cases.eye(dy=-0.032),
             truth="a stereo template's right-eye offset left on: the eye 0.032 (half of 0.064) to the right, "
             "(-1, -0.032, 0) for (-1, 0, 0)"),
        # Light model
        Spec("light_radiance_over_255", "light_radiance", True, edit=cases.light(radiance=(20.0 / 255.0,) * 3),
             truth="the light's radiance parsed as an 8-bit colour (values over 1 taken for 0-255 codes): 20 / 255 "
             "= 0.078 for 20"),
        Spec("light_samples_margin", "light_pdf", held_out=True, **_posted("light_margin", partial(
            unheard._light_changed_for_samples, spp=_S, seed=c("light_samples_margin"), dict_edit=_light_margin)),
             truth="the light's sample coordinates drawn in [0.01, 0.99] of each side (a margin against its edges) "
             "with the pdf of that smaller square: its light on surfaces from a 1.96 x 1.96 square, 4 % dark, the "
             "light seen right"),
        Spec("light_seen_cosine_weighted", "light_seen", **_posted("light_seen_cosine", partial(
            _light_seen_cosine, spp=_S, seed=c("light_seen_cosine_weighted"))),
             truth="the emission a camera ray sees, directly or in the mirror, weighted by the cosine at the light "
             "(Le cos, an intensity's formula): the light's own pixels and its reflection dimmer, its light on "
             "surfaces right"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples, passes, threads and tiles."""
    c = _crc
    return (
        # Integrator
        Spec("bounce_azimuth_half_circle", "indirect_scale", **_posted("bounce_half_circle", partial(
            _bounce_half_circle, spp=_S, seed=c("bounce_azimuth_half_circle"))),
             truth="the diffuse bounce's azimuth drawn as pi u for 2 pi u (at the first surface a camera ray meets; "
             "Mitsuba's path after it): only half the hemisphere sampled, weighted as the whole, the indirect light "
             "from one side counted twice, the direct right"),
        Spec("depth_mirror_uncounted", "depth", held_out=True, **_posted("mirror_uncounted", partial(
            _mirror_uncounted, spp=_S, seed=c("depth_mirror_uncounted"))),
             truth="the depth counted at diffuse vertices only: a camera ray's mirror bounce not counted, the room "
             "in the mirror with paths of 9 segments for 8 (a little brighter), the rest right"),
        Spec("mirror_reflects_forward", "material", True, **_posted("mirror_forward", partial(
            unsaid._traced, spp=_S, seed=c("mirror_reflects_forward"), after=_reflect_forward)),
             truth="the mirror reflecting the camera's forward vector (1, 0, 0) for every camera ray, not the ray's "
             "own direction (a variable mixed up): the sphere showing the room as a parallel beam would see it"),
        Spec("roulette_divided_before_test", "roulette", True, held_out=True, **_posted("roulette_before", partial(
            _roulette_divided_first, spp=_S, seed=c("roulette_divided_before_test"))),
             truth="Russian roulette from the 3rd vertex with survival 0.5, the throughput divided by 0.5 before the "
             "test and the light sample added either way: the light of paths of 4 segments or more counted twice"),
        # Samples, passes, threads and tiles
        Spec("tiles_origin_not_added", "row_stride", True, **_posted("tiles_from_origin", partial(
            _tiles_from_origin, spp=_S, seed=c("tiles_origin_not_added"))),
             truth="the 4 x 4 tiles' origins never added to their pixels' rays (only to where they are written): "
             "every tile rendered as the top-left tile, a seed each"),
        Spec("film_sums_bfloat16", "quantisation", held_out=True, **_posted("bfloat16_sums", partial(
            _bfloat16_sums, spp=_S, seed=c("film_sums_bfloat16"))),
             truth="the film's per-pixel sums kept in a bfloat16 tensor (to save GPU memory), the 256 samples added "
             "one by one: each add rounded to 8 significant bits, the samples under half a step of the sum lost "
             "once it is large (the image darker, most where the samples vary)"),
        Spec("threads_store_not_add", "sample_count", True, **_posted("last_thread", partial(
            _last_thread_only, threads=4, spp=_S, seed=c("threads_store_not_add"))),
             truth="four threads of 64 samples storing (=) their partial sums into the pixel for adding (+=): the "
             "last thread's sum kept, divided by 256: a quarter of the truth, 64 samples' noise"),
        Spec("manifest_spp_times_depth", "spp_claim", held_out=True, declared_spp=_S * _DEPTH,
             truth="the manifest's spp the samples times the maximum depth (256 x 8 = 2048, 'rays per pixel'), for "
             "the 256 a pixel rendered (the image right)"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_lattice_offsets", None, spp=192, **_posted("lattice", partial(
            _mean_through, spp=192, seed=c("ok_lattice_offsets"), jitter=_lattice)),
             truth="Mitsuba path 192 spp, sub-pixel offsets from a rank-1 lattice shifted at random in each pixel "
             "(Cranley-Patterson), EXR"),
        Spec("ok_walls_in_four", None, held_out=True, spp=152, mitsuba_edit=_walls_in_four,
             truth="Mitsuba path 152 spp with every wall split into four triangles about its centre, EXR"),
        Spec("ok_exr_zstd", None, spp=136, writer=_write_exr_zstd, file="exr-zstd",
             truth="Mitsuba path 136 spp, a float EXR with ZSTD compression"),
        Spec("ok_hdr_column_major", None, held_out=True, spp=120, writer=_write_hdr_columns, file="hdr-columns",
             truth="Mitsuba path 120 spp, a Radiance HDR stored column by column (resolution string +X W -Y H)"),
        Spec("ok_mcrt_unnormalised_camera", None, spp=104, renderer="mcrt", edit=_unnormalised_camera,
             truth="mcrt 104 spp with the camera's forward and up typed unnormalised, (3, 0, 0) and (0, 0, 2), EXR"),
        Spec("ok_png_up_filter_idats", None, held_out=True, spp=344, writer=_write_png_up_idats,
             file="png-srgb-up-idats",
             truth="Mitsuba path 344 spp, an 8-bit sRGB PNG written by hand with the Up filter on every row and its "
             "data split over IDAT chunks of 512 bytes"),
        Spec("ok_sensor_matrix_by_hand", None, spp=88, mitsuba_edit=_sensor_by_hand,
             truth="Mitsuba path 88 spp with the sensor's to_world matrix built by hand (left, up, forward, eye as "
             "its columns), EXR"),
        Spec("ok_mirror_two_halves", None, held_out=True, spp=328, mitsuba_edit=_mirror_as_blend,
             truth="Mitsuba path 328 spp with the mirror a blend (weight 0.5) of two perfect mirrors, EXR"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "blur": "a filter after rendering (the colours averaged over 2 x 2 blocks)",
    "grain": "noise added after rendering (a dither in the linear values)",
    "sharpen": "a sharpening filter after rendering (a Laplacian kernel)",
    "tone_map": "a tone curve applied before saving (a sigmoid contrast curve)",
    "light_radiance": "a constant factor on the image or the light (a sum buffer written, the radiance read as an "
                      "8-bit colour)",
    "lossy_compression": "the image saved with lossy compression (an EXR's B44)",
    "code_overflow": "values past the top code wrapped round (16-bit codes of v * 65536): the brightest pixels black",
    "normalised": "the values stretched after rendering (from their minimum to their maximum, by the writing library)",
    "brdf_norm": "a BRDF's normalisation (a factor under 1 on every Lambertian)",
    "albedo": "a surface's colour (the walls' colours per vertex, mixed at the corners)",
    "material": "an object rendered with another material (a metal), or the mirror's reflection computed wrongly",
    "object_moved": "an object moved (the ceiling raised)",
    "mesh_face": "part of a surface missing (a gap in the ceiling round the light)",
    "object_shape": "an object's shape (a vertex in the wrong place)",
    "camera_fov": "the camera's field of view (halved twice)",
    "pixel_footprint": "each pixel's samples not spread over its square (a stratum from the pixel's row)",
    "camera_eye": "the camera's eye position (a stereo offset)",
    "light_pdf": "the light sampled wrongly (a smaller square than the light): the light seen right, its light on "
                 "surfaces not",
    "light_seen": "the light's own pixels (where the camera or the mirror sees it) at the wrong brightness "
                  "(weighted by a cosine), its light on surfaces right",
    "indirect_scale": "the indirect light wrong (half the hemisphere sampled as the whole), the direct light right",
    "depth": "the path depth (a mirror bounce not counted)",
    "roulette": "Russian roulette's division in the wrong place (the light sample of a path the roulette ends counted "
                "too)",
    "row_stride": "pixels computed or written for the wrong place (tiles without their origin)",
    "quantisation": "values quantised wrongly (the sums kept in bfloat16)",
    "sample_count": "each pixel's sum divided by the nominal spp, not by the samples it kept (threads' sums stored, "
                    "not added)",
    "spp_claim": "more samples per pixel declared than rendered (the samples times the depth)",
}
_WORDS = {**cases.CAUSES, **outside.CAUSES, **programs.NEW_CAUSES, **fresh.NEW_CAUSES, **blind.NEW_CAUSES,
          **unseen.NEW_CAUSES, **untried.NEW_CAUSES, **novel.NEW_CAUSES, **untold.NEW_CAUSES, **unmet.NEW_CAUSES,
          **unheard.NEW_CAUSES, **unsaid.NEW_CAUSES, **unasked.NEW_CAUSES, **unsought.NEW_CAUSES,
          **unguessed.NEW_CAUSES, **NEW_CAUSES, **_REWORDED}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = {c: _WORDS[c] for c in dict.fromkeys(s.cause for s in MISTAKES)}


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
