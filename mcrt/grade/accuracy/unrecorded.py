r"""A twenty-seventh class of hand-ins: mistakes of students' tracers, scene input and output no class tried, blind.

How it was written: from what goes wrong in students' programs written in C and
C++ and their usual libraries (stb_image_write's writers and their stride and
component arguments; tinyexr's channels, named in alphabetical order; OpenEXR's
frame buffer strides; C's integer ``abs``, integer division and ``int``
overflow; ``rand()`` and ``RAND_MAX``; ``std::mt19937`` and its distributions
seeded or copied wrongly; OpenMP's shared accumulators and threads; glm's
``perspective``, ``lookAt``, ``reflect`` and column-major matrices; Eigen's
``normalized()``; ``std::max`` with a template argument; ``memcpy`` and
``sizeof`` a pointer; array-of-struct strides; ``strcmp``; ``atoi``), not from the
grader. Its author read the other classes' specs and cause words, the catalogue
(:mod:`mcrt.mutants`), the scene files and design notes, mcrt's scene, camera and
image code, :data:`~mcrt.grade.accuracy.run.CAUSE_OF` and
:data:`~mcrt.grade.accuracy.run.SAME_MISTAKE`, to reuse their words and to stay
clear of their mistakes; never the grader's rules (what decides a cause) nor its
reports, and graded none of it, not one case. Each cause and ``major`` flag was
set from the mistake alone; every mistake is worded by a cause the other classes
already have (:data:`NEW_CAUSES` is empty), so ``SAME_MISTAKE`` needed no new
entry. The mistakes differ from those of the twenty-six other classes
(:mod:`~mcrt.grade.accuracy.cases`, :mod:`~mcrt.grade.accuracy.outside` and the
modules of :data:`_EARLIER`, from :mod:`~mcrt.grade.accuracy.programs` to
:mod:`~mcrt.grade.accuracy.unnoticed`) and from the catalogue's bugs:

* **post-processing**: negative values dropped with C's ``abs`` (the integer one:
  every value truncated); a 3 x 3 box blur over a ``float*`` with its offsets
  in floats, not pixels (the channels mixed, ghosts a third of the width away); the image divided by its maximum found with
  ``std::max<int>`` (20 for 20.x); a saturation boost in a ``glm::mat3`` filled
  row by row (column-major: transposed);
* **writing the file**: OpenEXR's ``setFrameBuffer`` with the x and y strides
  swapped (transposed); tinyexr's channels named B, G, R with the data in R, G, B
  order; ``stbi_write_hdr`` of the film after the PNG's conversion done in place
  (display values); ``stbi_write_hdr`` with 3 components of a ``glm::vec4`` film;
* **materials**: ``glm::reflect(n, d)`` for ``glm::reflect(d, n)``; the sphere's
  normal ``p - c`` handed to ``glm::reflect`` unnormalised (1.5 long); the
  albedos parsed with ``atoi`` (0);
* **geometry**: the unit sphere placed by ``glm::translate(glm::scale(...), c)``
  (its centre scaled by its radius: outside the room); the tetrahedron's
  vertices copied with ``memcpy(dst, src, sizeof(src))`` of a pointer (2 floats:
  every face degenerate); its vertices read with a stride of 3 floats from an
  interleaved position-normal array;
* **camera**: ``glm::perspective`` given 90 for radians (a field of view of
  116.6 degrees); ``glm::lookAt``'s view matrix used to turn camera rays into
  the world (the view turned); the jittered pixel passed to ``cameraRay(int,
  int)`` (every sample through the pixel's corner);
* **light model**: ``(float) rand() / (RAND_MAX + 1)`` overflowing to
  ``INT_MIN`` (the light's points from a square beside it); the light's point
  from ``std::uniform_int_distribution<int>(0, 1)`` (its 4 corners); the light
  samples weighted by ``1 / nLight`` in integer division (0);
* **integrator**: the bounce's cosine through C's integer ``abs`` (0: no
  indirect light); the bounce's generator constructed with a fixed seed in the
  bounce function (one direction in every frame); roulette's test ``rand() /
  RAND_MAX > p`` (never true: the survivors' weight without a death); the tangent
  frame's ``t.normalized();`` discarded (Eigen);
* **samples and passes**: ``#pragma omp parallel for`` over the samples with a
  shared accumulator (updates lost); ``std::mt19937`` copied by value into 4
  threads (the bands' noise the same); the accumulator cleared with
  ``memset(acc, 0, sizeof(acc))`` of a pointer (a preview's samples left in);
  each pass kept as ``unsigned char`` codes (clipped and truncated).

The correct hand-ins come in ways no class used: an RGBE picture as
``stbi_write_hdr`` writes it (truncated mantissas, run-length encoded), a binary
PPM by ``fwrite`` of ``unsigned char`` rows, Mitsuba's samples summed in
``double``, Mitsuba's samples summed by an OpenMP ``reduction(+:...)`` of 4
threads in ``float``, Mitsuba with the first bounce the normal plus
``glm::sphericalRand(1.0f)``, Mitsuba with the first vertex's direct light the
mean of 2 light samples, a half-float EXR as tinyexr writes it (channels B, G, R,
each with its own data), and an 8-bit PNG as ``stbi_write_png`` writes it with
the stride ``W * 3``.

Every wrong image comes from **Mitsuba**: edited scenes (:class:`Spec`'s ``edit``
and ``mitsuba_edit``), Mitsuba renders at another field of view or camera,
Mitsuba's path integrator on rays a student's camera or mirror makes
(:func:`mcrt.grade.accuracy.unsaid._traced`), its first vertex's direct light
redone as a student's light sample makes it
(:func:`mcrt.grade.accuracy.unheralded._first_vertex`), its first bounce redrawn
(:func:`mcrt.grade.accuracy.unprompted._first_bounce`), its samples, one by one,
reweighted or dropped (same-seed samples of max depth 2 and 8,
:func:`mcrt.grade.accuracy.unbeknown._camera_samples`,
:func:`mcrt.grade.accuracy.unbidden._all_samples`), or correct renders
post-processed and written with NumPy, Pillow, OpenEXR's bindings and the standard
library as students' C and C++ programs do. mcrt renders none of it.

Causes (:data:`_REWORDED`) and the held-out rule (:func:`held_out_rule` over
:data:`CATEGORIES`: the 2nd, 4th, ... of each category and of the correct
hand-ins) are as in :mod:`~mcrt.grade.accuracy.unnoticed`, fixed before any case
was graded.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from mcrt.grade.accuracy import (blind, cases, fresh, novel, outside, programs, unasked, unbeknown, unbidden,
                                 unforeseen, unguessed, unheard, unheralded, unlooked, unmet, unnoticed, unprompted,
                                 unremarked, unremembered, unsaid, unseen, unsought, untold, untried, unvisited,
                                 unwonted)
from mcrt.grade.accuracy.cases import Spec

#: The causes new in this class, as the report words them: none (every mistake is one the other classes word).
NEW_CAUSES: dict[str, str] = {}


#: The classes after the first two, in the order they were written (their causes' words are this class's too).
_EARLIER = (programs, fresh, blind, unseen, untried, novel, untold, unmet, unheard, unsaid, unasked, unsought,
            unguessed, unforeseen, unprompted, unbidden, unheralded, unbeknown, unvisited, unlooked, unwonted,
            unremarked, unremembered, unnoticed)


def _crc(name: str) -> int:
    return 1401000 + zlib.crc32(name.encode()) % 100000


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


def _int_abs(x):
    """``c = abs(c)`` on each float channel with C's ``abs`` of ``<stdlib.h>`` (the integer one, no ``<cmath>``
    overload in C): the value converted to ``int`` (truncated towards zero), its absolute value back to float."""
    return np.abs(np.trunc(np.asarray(x, np.float64)))


def _blur_float_offsets(x):
    """A 3 x 3 box blur over the ``float*`` RGB buffer into a second one, each value ``out[i]`` the mean of ``img[i +
    dx + dy * W]`` for dx, dy in -1..1 (i = 3 (y W + x) + c): the channel and pixel strides left out, the neighbours
    the floats next to it (its pixel's other channels, the next or previous pixel's) and W floats (W / 3 pixels)
    before and after it; indices past the buffer's ends clamped to them."""
    img = np.asarray(x, np.float64)
    h, w = img.shape[:2]
    flat = img.reshape(-1)
    i = np.arange(flat.size)
    out = sum(flat[np.clip(i + dx + dy * w, 0, flat.size - 1)] for dx in (-1, 0, 1) for dy in (-1, 0, 1)) / 9.0
    return out.reshape(h, w, 3)


def _max_int_normalised(x):
    """The image divided by its largest value found as ``float m = 0; m = std::max<int>(m, v)`` (both arguments
    converted to ``int``): the integer part of the maximum (20 for the light's 20.x; at least 1 here)."""
    img = np.asarray(x, np.float64)
    return img / max(float(np.floor(np.nan_to_num(img).max())), 1.0)


#: Rec. 709 luminance weights and the saturation the program boosts by.
_LUMA = np.array([0.2126, 0.7152, 0.0722])
_SATURATION = 1.2


def _saturation_matrix(s: float = _SATURATION) -> np.ndarray:
    """The saturation boost meant, as a matrix on RGB columns: s I - (s - 1) 1 w^T (each row the luminance weights)."""
    return s * np.eye(3) - (s - 1.0) * np.outer(np.ones(3), _LUMA)


def _saturation_transposed(x, *, s: float = _SATURATION):
    """The saturation boost's matrix written row by row into ``glm::mat3(...)``, which takes its arguments column by
    column: the transpose applied, ``out_c = s x_c - (s - 1) w_c (r + g + b)``, then ``glm::max(c, 0.0f)``."""
    img = np.asarray(x, np.float64)
    return np.maximum(img @ _saturation_matrix(s), 0.0)


# --------------------------------------------------------------------------
# Writers (the render in, the file a program writes)
# --------------------------------------------------------------------------


def _write_exr_strides_swapped(image: np.ndarray, folder: Path) -> Path:
    """OpenEXR's ``Imf::RgbaOutputFile`` (half R, G, B, A) given ``setFrameBuffer(&px[0][0], W, 1)``, the x and y
    strides swapped for ``(1, W)``: pixel (x, y) taken from ``px[x][y]``: the (square) image transposed."""
    h, w = image.shape[:2]
    t = np.ascontiguousarray(np.asarray(image).transpose(1, 0, 2))
    chans = {c: np.ascontiguousarray(t[..., i], np.float16) for i, c in enumerate("RGB")}
    chans["A"] = np.ones((w, h), np.float16)
    path = folder / "render.exr"
    fresh._exr_file(path, chans)
    return path


def _write_exr_names_bgr_data_rgb(image: np.ndarray, folder: Path) -> Path:
    """tinyexr's ``SaveEXRImageToFile`` with ``header.channels`` named B, G, R (the order its example and OpenEXR's
    readers want) and ``image.images`` filled R, G, B: red stored under the name B, blue under R."""
    path = folder / "render.exr"
    fresh._exr_file(path, {n: np.ascontiguousarray(image[..., i], np.float32) for i, n in enumerate("BGR")})
    return path


def _stb_rgbe(v: np.ndarray) -> np.ndarray:
    """(H, W, 4) RGBE codes as ``stbiw__linear_to_rgbe`` makes them: frexp of the largest channel, each channel times
    mantissa * 256 / max, truncated by the cast to ``unsigned char``; under 1e-32 all zero."""
    v = np.maximum(np.nan_to_num(np.asarray(v, np.float64)), 0.0)
    m = v.max(axis=2)
    mant, ex = np.frexp(m)
    ok = m >= 1e-32
    f = np.where(ok, mant * 256.0 / np.where(ok, m, 1.0), 0.0)
    out = np.zeros(v.shape[:2] + (4,), np.uint8)
    out[..., :3] = np.where(ok[..., None], np.minimum(np.floor(v * f[..., None]), 255), 0).astype(np.uint8)
    out[..., 3] = np.where(ok, ex + 128, 0).astype(np.uint8)
    return out


def _stb_hdr_bytes(rgb: np.ndarray) -> bytes:
    """The bytes of ``stbi_write_hdr``: its header (with its EXPOSURE line), ``-Y H +X W``, scanlines of 8 pixels and
    more run-length encoded channel by channel."""
    from mcrt.image_files import _rle_channel

    h, w = rgb.shape[:2]
    rgbe = _stb_rgbe(rgb)
    parts = [b"#?RADIANCE\n# Written by stb_image_write\nFORMAT=32-bit_rle_rgbe\n"
             b"EXPOSURE=          1.0000000000000\n\n" + f"-Y {h} +X {w}\n".encode()]
    for y in range(h):
        if 8 <= w < 32768:
            parts.append(bytes((2, 2, w >> 8, w & 255)))
            parts.extend(_rle_channel(rgbe[y, :, c]) for c in range(4))
        else:
            parts.append(rgbe[y].tobytes())
    return b"".join(parts)


def _write_hdr_stb(image: np.ndarray, folder: Path) -> Path:
    path = folder / "render.hdr"
    path.write_bytes(_stb_hdr_bytes(image))
    return path


def _vec4_read_as_3(image: np.ndarray) -> np.ndarray:
    """The (H, W, 3) floats ``stbi_write_hdr(path, W, H, 3, &film[0].x)`` reads of a ``std::vector<glm::vec4>`` film
    (alpha 1): pixel i the floats 3 i to 3 i + 2 of the RGBA stream, the first three quarters of it."""
    h, w = image.shape[:2]
    rgba = np.concatenate([np.asarray(image, np.float64), np.ones((h, w, 1))], axis=2).reshape(-1)
    return rgba[:h * w * 3].reshape(h, w, 3)


def _write_hdr_vec4_as_3(image: np.ndarray, folder: Path) -> Path:
    path = folder / "render.hdr"
    path.write_bytes(_stb_hdr_bytes(_vec4_read_as_3(image)))
    return path


def _display_in_place(image: np.ndarray) -> np.ndarray:
    """The film after the PNG's conversion done in place, ``film[i] = srgb(std::clamp(film[i], 0.0f, 1.0f))``: the
    display values, clipped at 1 and sRGB-encoded (before the cast to 8 bits)."""
    from mcrt.image_files import srgb_oetf

    return srgb_oetf(np.clip(np.nan_to_num(np.asarray(image, np.float64)), 0.0, 1.0))


def _write_hdr_display_buffer(image: np.ndarray, folder: Path) -> Path:
    path = folder / "render.hdr"
    path.write_bytes(_stb_hdr_bytes(_display_in_place(image)))
    return path


# --------------------------------------------------------------------------
# Scene and Mitsuba dict edits
# --------------------------------------------------------------------------


def _albedos_atoi(s):
    """Every albedo parsed with ``atoi`` for ``atof`` (``atoi("0.75")`` is 0): every diffuse surface black."""
    return unbidden._albedos_mapped(s, lambda a: (0.0,) * len(a))


def _sphere_scaled_then_moved(s):
    """The unit sphere placed by ``glm::translate(glm::scale(glm::mat4(1.0f), glm::vec3(r)), c)`` (the translation
    applied first, then the scale): its centre r c, its radius r."""
    objects = tuple(replace(o, center=tuple(o.radius * float(v) for v in o.center)) if o.name == "sphere" else o
                    for o in s.objects)
    return replace(s, objects=objects)


def _face_normals(tris: np.ndarray) -> np.ndarray:
    return unsaid._unit(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]))


def _strided_vertices(tris: np.ndarray) -> np.ndarray:
    """(n, 3, 3): the mesh's 3 n vertices read as ``&verts[0].p.x + 3 k`` from an array of ``struct Vertex { vec3
    p, n; }`` (6 floats each): read vertex k the position of vertex k / 2 when k is even, the normal of vertex
    (k - 1) / 2 when odd (each vertex's normal its face's)."""
    tris = np.asarray(tris, np.float64)
    pos = tris.reshape(-1, 3)
    nrm = np.repeat(_face_normals(tris), 3, axis=0)
    inter = np.stack([pos, nrm], axis=1).reshape(-1, 3)  # p0, n0, p1, n1, ...
    return inter[:len(pos)].reshape(tris.shape)


def _tetra_strided(d: dict) -> dict:
    sf = fresh._surface("tetrahedron")
    return fresh._rebuilt(d, "tetrahedron", _strided_vertices(sf.triangles), _bsdf(sf.material))


# --------------------------------------------------------------------------
# The camera
# --------------------------------------------------------------------------

#: The field of view of ``glm::perspective(90.0f, 1.0f, ...)`` (90 taken as radians): half-angle 45 radians, whose
#: tangent is 1.62.
_FOV_GLM_DEGREES = math.degrees(2.0 * math.atan(math.tan(45.0)))


def _lookat_as_camera_to_world(s):
    """Camera rays turned into the world by ``glm::lookAt(eye, eye + forward, up)`` (the view matrix, world to camera)
    for its inverse: the camera's -z taken to the view matrix's third column (0, -1, 0), its y to (-1, 0, 0)."""
    return cases._camera(s, forward=(0.0, -1.0, 0.0), up=(-1.0, 0.0, 0.0))


def _corner_rays(x, *, spp: int, seed: int):
    """Mitsuba's path on rays through each pixel's top left corner: the jittered film position passed to ``Ray
    cameraRay(int px, int py)`` (truncated to the pixel's index)."""
    h, w = x.shape[:2]

    def camera(fx, fy):
        return unsaid._pinhole(np.floor(np.asarray(fx) * w) / w, np.floor(np.asarray(fy) * h) / h)

    return unsaid._traced(x, spp=spp, seed=seed, camera=camera)


# --------------------------------------------------------------------------
# Light samples at the first vertex (unheralded._first_vertex's ``direct``)
# --------------------------------------------------------------------------

_light_points = unnoticed._light_points
_light_at = unnoticed._light_at


def _light_rand_overflow(mscene, rng, p, n, rho, mitsuba):
    """The light's point at ``(float) rand() / (RAND_MAX + 1)`` in both coordinates, ``RAND_MAX + 1`` an ``int``
    overflowing to ``INT_MIN`` (glibc's RAND_MAX 2^31 - 1): u, v in (-1, 0], a square the light's size beside it
    towards -x and -y, weighted as the light."""
    m = len(p)
    return _light_at(mscene, p, n, rho, _light_points(-rng.random(m), -rng.random(m)))


def _light_int_corners(mscene, rng, p, n, rho, mitsuba):
    """The light's point from ``std::uniform_int_distribution<int>(0, 1)`` for a real one: u, v each 0 or 1, one of
    the light's 4 corners."""
    m = len(p)
    return _light_at(mscene, p, n, rho, _light_points(rng.integers(0, 2, m).astype(float),
                                                      rng.integers(0, 2, m).astype(float)))


def _light_two_averaged(mscene, rng, p, n, rho, mitsuba):
    """Two uniform points on the light, their light samples averaged."""
    m = len(p)
    return 0.5 * sum(_light_at(mscene, p, n, rho, _light_points(rng.random(m), rng.random(m))) for _ in range(2))


def _light_sample(name: str, direct) -> dict:
    """A spec's post-process: Mitsuba's path with its first vertex's light sample made by ``direct``."""
    return _posted(name, partial(unheralded._first_vertex, spp=_S, seed=_crc(name), direct=direct))


def _light_one_over_n_int(mscene, rng, p, n, rho, mitsuba):
    """The light samples' sum weighted ``L += Ld * (1 / nLight)``, an integer division: 0."""
    return np.zeros_like(np.asarray(mitsuba, np.float64))


# --------------------------------------------------------------------------
# Mirror, materials, bounces and samples of the path
# --------------------------------------------------------------------------


def _reflect_glm_swapped(o, d):
    """Camera rays that meet the sphere reflected with ``glm::reflect(n, d)`` for ``glm::reflect(d, n)`` (glm's is
    ``I - 2 dot(N, I) N``): ``n - 2 (d . n) d``, a unit vector (back into the ball where the ray meets it head on,
    along the normal at its rim): (origins, directions, segments used). The hit points are
    :func:`mcrt.grade.accuracy.unsaid._reflected`'s."""
    po, _, used = unsaid._reflected(o, d)
    n = unsaid._unit(po - unsaid._sphere()[0])
    r = unsaid._unit(n - 2.0 * np.einsum("ij,ij->i", d, n)[:, None] * d)
    return po, np.where(used[:, None] > 0, r, d), used


def _materials_strcmp_inverted(d: dict) -> dict:
    """``if (strcmp(mat.type, "mirror"))`` taken for a test of equality (``strcmp`` is 0 when the strings are equal):
    every Lambertian surface a mirror of its albedo, the mirror ball a Lambertian of its reflectance (white)."""
    from mcrt.scene import Lambertian, Mirror

    s = _scene()
    for sf in s.surfaces():
        if isinstance(sf.material, Lambertian):
            d = fresh._rebuilt(d, sf.name, sf.triangles, _bsdf(Mirror(reflectance=sf.material.albedo)))
    for sph in s.spheres():
        d = dict(d, **{sph.name: dict(d[sph.name], bsdf=_bsdf(Lambertian(albedo=sph.material.reflectance)))})
    return d


def _cosine_draw(rng, n):
    """Cosine-weighted directions (Malley's method in :func:`mcrt.grade.accuracy.unforeseen._frame_of`'s frame)."""
    u1, u2 = rng.random((2, len(n)))
    return _cosine_at(n, u1, u2), np.ones(len(n))


def _cosine_at(n, u1, u2, frame=unforeseen._frame_of):
    phi = 2.0 * math.pi * np.asarray(u2, np.float64)
    r, z = np.sqrt(u1), np.sqrt(1.0 - np.asarray(u1, np.float64))
    t, b = frame(n)
    return unsaid._unit((r * np.cos(phi))[:, None] * t + (r * np.sin(phi))[:, None] * b + z[:, None] * n)


def _cosine_int_abs(rng, n):
    """The bounce's weight ``albedo * abs(dot(n, d)) / pdf`` with C's integer ``abs``: the cosine truncated to 0
    (1 only along the normal exactly): weight 0."""
    d, _ = _cosine_draw(rng, n)
    return d, np.abs(np.trunc(np.einsum("ij,ij->i", d, n)))


#: The first two outputs of ``std::mt19937`` at its default seed 5489 (libstdc++'s ``uniform_real_distribution<float>``
#: takes one 32-bit output a number: x / 2^32).
_MT19937_FIRST = (3499211612, 581869302)


def _bounce_fixed_seed(rng, n):
    """The bounce drawn from ``std::mt19937 gen; std::uniform_real_distribution<float> U(0, 1);`` constructed inside
    the bounce function: u1, u2 the stream's first two numbers at every call, one direction in every normal's frame."""
    u1, u2 = (np.full(len(n), v / 2.0 ** 32) for v in _MT19937_FIRST)
    return _cosine_at(n, u1, u2), np.ones(len(n))


def _frame_unnormalised(n):
    """The tangent frame with Eigen's ``t.normalized();`` as a statement (its result discarded, ``t`` left as it
    was): t = n x a (length sin of the angle between n and a), b = n x t."""
    a = np.where((np.abs(n[:, 0]) < 0.9)[:, None], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    t = np.cross(n, a)
    return t, np.cross(n, t)


def _bounce_eigen_frame(rng, n):
    """Malley's cosine-weighted bounce in the frame of :func:`_frame_unnormalised`, the direction normalised: the
    tangential parts shortened where n leans towards a, the bounces pulled towards the normal."""
    u1, u2 = rng.random((2, len(n)))
    return _cosine_at(n, u1, u2, frame=_frame_unnormalised), np.ones(len(n))


def _sphere_rand_plus_normal(rng, n):
    """The normal plus ``glm::sphericalRand(1.0f)`` (a uniform point on the unit sphere), normalised: cosine-weighted,
    weight 1."""
    s = n + unsaid._unit(rng.normal(size=(len(n), 3)))
    length = np.linalg.norm(s, axis=1, keepdims=True)
    return np.where(length > 1e-9, s / np.maximum(length, 1e-12), n), np.ones(len(n))


def _bounce(name: str, draw) -> dict:
    return _posted(name, partial(unprompted._first_bounce, spp=_S, seed=_crc(name), draw=draw))


def _roulette_never_sample(o, d, seed, *, full, direct):
    """A sample whose path meets Russian roulette at its first bounce, ``if (rand() / RAND_MAX > p) break; beta /=
    p;``: the integer division is 0 (but at RAND_MAX), never above p: every path survives, divided by p = max
    (albedo): L2 + (L8 - L2) / p."""
    L, near = unsaid._sampled(full, o, d, seed), unsaid._sampled(direct, o, d, seed)
    p = unsaid._first_albedo(full, o, d).max(axis=1)
    diffuse = p > 0.0
    return np.where(diffuse[:, None], near + (L - near) / np.where(diffuse, p, 1.0)[:, None], L)


def _roulette_never(x, *, spp: int, seed: int):
    return unbeknown._camera_samples(x, spp=spp, seed=seed, sample=partial(
        _roulette_never_sample, full=unsaid._loaded(_DEPTH), direct=unsaid._loaded(2)))


# --------------------------------------------------------------------------
# Samples and passes
# --------------------------------------------------------------------------

#: The share of a pixel's ``+=`` a race between OpenMP's threads loses.
_LOST = 0.25


def _race_lost(x, *, spp: int, seed: int, lost: float = _LOST):
    """``#pragma omp parallel for`` over a pixel's samples, each adding to the shared ``color`` (no ``reduction``, no
    ``atomic``): an update lost when another thread's read-modify-write overlaps it, modelled as each sample's lost
    with probability ``lost``; the sum divided by the spp."""
    h, w = x.shape[:2]
    L = unbidden._all_samples(w, h, spp, seed)
    keep = np.random.default_rng(seed + 59).random(L.shape[:2]) >= lost
    return ((L * keep[..., None]).sum(axis=1) / spp).reshape(h, w, 3)


def _bands_one_stream(x, *, spp: int, seed: int, bands: int = 4, lanes: int = 1 << 18):
    """Rows in ``bands`` bands (OpenMP's static schedule of 4 threads), each thread's ``std::mt19937`` a copy of the
    same one (captured by value): every band's pixel the same random numbers (jitter and path) as the pixel as many
    rows up in the first band. Mitsuba's path, each band's lanes with the first band's seeds."""
    h, w = x.shape[:2]
    hb = h // bands
    full = unsaid._loaded(_DEPTH)
    per = max(1, lanes // (w * hb))
    total = np.zeros((h, w, 3))
    done = k = 0
    while done < spp:
        n = min(per, spp - done)
        rng = np.random.default_rng(seed + k)
        jx, jy = rng.random((2, hb * w * n))
        iy, ix = np.divmod(np.arange(hb * w * n) // n, w)
        for b in range(bands):
            o, d = (np.array(a, np.float64) for a in unsaid._pinhole((ix + jx) / w, (b * hb + iy + jy) / h))
            L = unsaid._sampled(full, o, d, seed + 7919 + k)
            total[b * hb:(b + 1) * hb] += L.reshape(hb, w, n, 3).sum(axis=2)
        done += n
        k += 1
    return total / spp


#: The preview's spp, rendered into the accumulator before the final render.
_PREVIEW = 64


def _preview_left(x, *, spp: int, seed: int, preview: int = _PREVIEW):
    """The accumulator ``float* acc`` cleared with ``memset(acc, 0, sizeof(acc))`` (8 bytes: its first 2 floats)
    between a preview of ``preview`` spp and the final render: the preview's sums left in every value but pixel (0,
    0)'s red and green, all divided by the final spp."""
    h, w = x.shape[:2]
    prev = _render(w, h, preview, seed + 1) * preview
    left = prev.reshape(-1)
    left[:2] = 0.0
    return np.asarray(x, np.float64) + left.reshape(h, w, 3) / spp


#: The passes, and their spp (the declared 256 all told).
_PASSES, _PASS_SPP = 8, 32


def _passes_uchar(x, *, seed: int, passes: int = _PASSES, pass_spp: int = _PASS_SPP):
    """Each pass's mean kept as ``unsigned char`` codes, ``(unsigned char)(255 * std::min(v, 1.0f))`` (clipped at 1,
    truncated), the passes' codes averaged and divided by 255, written as EXR."""
    h, w = x.shape[:2]
    codes = [np.floor(255.0 * np.clip(_render(w, h, pass_spp, seed + k), 0.0, 1.0)) for k in range(passes)]
    return np.mean(codes, axis=0) / 255.0


def _samples_double(x, *, spp: int, seed: int):
    """Mitsuba's samples summed in a ``double`` accumulator, divided by the spp."""
    h, w = x.shape[:2]
    return unbidden._all_samples(w, h, spp, seed).astype(np.float64).mean(axis=1).reshape(h, w, 3)


def _samples_reduction(x, *, spp: int, seed: int, threads: int = 4):
    """Mitsuba's samples summed by ``#pragma omp parallel for reduction(+:r, g, b)`` over a pixel's samples: each of
    ``threads`` threads its share in a private ``float``, the partial sums added, divided by the spp."""
    h, w = x.shape[:2]
    L = unbidden._all_samples(w, h, spp, seed).astype(np.float32)
    parts = [c.sum(axis=1, dtype=np.float32) for c in np.array_split(L, threads, axis=1)]
    return (sum(parts[1:], parts[0]) / np.float32(spp)).astype(np.float64).reshape(h, w, 3)


# --------------------------------------------------------------------------
# Correct files made in other ways
# --------------------------------------------------------------------------


def _write_ppm_fwrite_rows(image: np.ndarray, folder: Path) -> Path:
    """A binary PPM by ``fprintf(f, "P6\\n%d %d\\n255\\n", W, H)`` and ``fwrite(row, 1, 3 * W, f)`` of each row's
    ``unsigned char`` codes, ``(unsigned char)(255 * srgb(clamp(v)) + 0.5f)``, to a file opened ``"wb"``."""
    h, w = image.shape[:2]
    c8 = blind._srgb8(image)
    path = folder / "render.ppm"
    path.write_bytes(unheard._ppm_header(w, h) + b"".join(np.ascontiguousarray(c8[j]).tobytes() for j in range(h)))
    return path


def _write_exr_bgr_half(image: np.ndarray, folder: Path) -> Path:
    """tinyexr's ``SaveEXRImageToFile`` with the channels named B, G, R, each with its own data, as half floats
    (``requested_pixel_types`` HALF)."""
    path = folder / "render.exr"
    fresh._exr_file(path, {n: np.ascontiguousarray(image[..., i], np.float16) for n, i in (("B", 2), ("G", 1),
                                                                                           ("R", 0))})
    return path


def _write_png_stride_3w(image: np.ndarray, folder: Path) -> Path:
    """An 8-bit sRGB PNG as ``stbi_write_png(path, W, H, 3, data, W * 3)`` writes it: the codes as they are."""
    return novel._write_png(blind._srgb8(image), folder)


# --------------------------------------------------------------------------
# The class
# --------------------------------------------------------------------------

#: The categories of the module docstring, in order: each mistake's category, by name (the held-out rule reads them).
CATEGORIES: dict[str, tuple[str, ...]] = {
    "post-processing": ("pp_c_abs_integer", "pp_blur_float_offsets", "pp_max_int_template",
                        "pp_glm_mat3_row_major"),
    "file": ("file_openexr_strides_swapped", "file_tinyexr_rgb_under_bgr_names", "file_stbi_hdr_display_buffer",
             "file_stbi_hdr_vec4_as_3"),
    "materials": ("mirror_glm_reflect_swapped", "materials_strcmp_inverted", "albedos_atoi"),
    "geometry": ("sphere_glm_scale_then_translate", "tetra_memcpy_sizeof_pointer", "tetra_vertex_stride_3"),
    "camera": ("fov_glm_perspective_degrees", "camera_lookat_view_as_world", "pixel_jitter_int_parameters"),
    "light": ("light_rand_max_plus_one_overflow", "light_uniform_int_corners", "light_samples_one_over_n_int"),
    "integrator": ("bounce_cosine_c_abs", "bounce_mt19937_fixed_seed", "roulette_rand_int_division",
                   "bounce_eigen_normalized_discarded"),
    "samples": ("samples_omp_shared_race", "samples_mt19937_copied_threads", "passes_memset_sizeof_pointer",
                "passes_uchar_codes"),
}


def _mistakes() -> tuple[Spec, ...]:
    return _after_rendering() + _in_the_scene() + _camera_and_light() + _integrator_and_samples()


def _after_rendering() -> tuple[Spec, ...]:
    """Post-processing, writing the file."""
    return (
        # Post-processing
        Spec("pp_c_abs_integer", "quantisation", True, **_posted("c_abs", _int_abs),
             truth="the denoised image's negative values dropped with c = abs(c) in a C file that includes "
             "stdlib.h, not math.h: C's abs takes an int, so every channel is truncated to an integer: every "
             "surface under 1 written 0, the room black, the light (20) and its reflection kept, as EXR"),
        Spec("pp_blur_float_offsets", "blur", held_out=True, **_posted("blur_float_offsets", _blur_float_offsets),
             truth="a 3 x 3 box blur against the noise over the float* RGB buffer with the neighbours at img[i + dx "
             "+ dy * W], i = 3 (y W + x) + c, the channel and pixel strides left out: each value averaged with the "
             "floats beside it (its pixel's other channels, the next and previous pixels') and with those W floats, "
             "a third of the width, before and after it: the colours greyed and smeared, ghosts a third of the "
             "image to either side, as EXR"),
        Spec("pp_max_int_template", "normalised", True, **_posted("max_int", _max_int_normalised),
             truth="the image divided by its maximum to fit [0, 1], the maximum found as m = std::max<int>(m, v) "
             "(the template argument written to make mixed float and int arguments compile: both truncated): 20 "
             "for the light's 20.x: the light about 1, the room 20 times too dark, as EXR"),
        Spec("pp_glm_mat3_row_major", "colour_grade", True, held_out=True, **_posted(
            "mat3_transposed", _saturation_transposed),
             truth="a saturation boost of 1.2 (1.2 c - 0.2 Y) as a glm::mat3 written row by row in its "
             "constructor, which fills column by column: the transpose applied, each channel 1.2 c minus 0.2 times "
             "its own luminance weight times r + g + b, clamped at 0: green pulled down most, the room magenta, "
             "as EXR"),
        # Writing the file
        Spec("file_openexr_strides_swapped", "orientation", True, writer=_write_exr_strides_swapped,
             file="exr-openexr-strides",
             truth="the EXR written with OpenEXR's Imf::RgbaOutputFile (half RGBA) and setFrameBuffer(&px[0][0], W, "
             "1), the x and y strides swapped for (1, W): pixel (x, y) read from px[x][y]: the image transposed, "
             "the floor at the left, the light at the right"),
        Spec("file_tinyexr_rgb_under_bgr_names", "channels", True, held_out=True,
             writer=_write_exr_names_bgr_data_rgb, file="exr-tinyexr-swapped",
             truth="tinyexr's SaveEXRImageToFile with header.channels named B, G, R as its example has them "
             "(alphabetical, as OpenEXR readers expect) and image.images filled with the R, G, B planes in that "
             "order: red stored as B and blue as R: red and blue swapped"),
        Spec("file_stbi_hdr_display_buffer", "encoding", True, writer=_write_hdr_display_buffer,
             file="hdr-stbi-display",
             truth="stbi_write_hdr called after the PNG's conversion done in place on the film, film[i] = "
             "srgb(std::clamp(film[i], 0.0f, 1.0f)): the Radiance picture holding the display values, sRGB-encoded "
             "and clipped at 1: the room too bright and flat, the light 1"),
        Spec("file_stbi_hdr_vec4_as_3", "row_stride", True, held_out=True, writer=_write_hdr_vec4_as_3,
             file="hdr-stbi-vec4",
             truth="stbi_write_hdr(\"out.hdr\", W, H, 3, &film[0].x) of a std::vector<glm::vec4> film (alpha 1): "
             "pixel i read from floats 3 i to 3 i + 2 of the RGBA stream: the image's first three quarters "
             "squeezed into it, the alpha of 1 read into a channel in turn: diagonal streaks, colours turned"),
    )


def _in_the_scene() -> tuple[Spec, ...]:
    """Materials, geometry."""
    return (
        # Materials
        Spec("mirror_glm_reflect_swapped", "material", True, **_posted(
            "glm_reflect_swapped", partial(unsaid._traced, spp=_S, seed=_crc("mirror_glm_reflect_swapped"),
                                           after=_reflect_glm_swapped)),
             truth="the mirror's reflection glm::reflect(n, d) for glm::reflect(d, n) (glm's reflect(I, N) is I - "
             "2 dot(N, I) N), for camera rays (Mitsuba's path after it): n - 2 (d . n) d: back into the ball where "
             "the ray meets it head on, along the outward normal at its rim: the sphere dark in the middle, the "
             "room behind the viewer and the walls around it at its edge"),
        Spec("materials_strcmp_inverted", "material", True, held_out=True, mitsuba_edit=_materials_strcmp_inverted,
             truth="the material chosen with if (strcmp(m.type, \"mirror\")) { mirror } else { diffuse }, strcmp's "
             "0 for equal strings taken as false: every diffuse surface a mirror tinted by its albedo, the mirror "
             "ball a white diffuse ball: a hall of coloured mirrors lit only by what the ball scatters"),
        Spec("albedos_atoi", "albedo", True, edit=_albedos_atoi,
             truth="every albedo parsed from the scene file with atoi for atof (atoi(\"0.75\") is 0): every "
             "diffuse surface black: only the light and its reflection in the mirror ball seen"),
        # Geometry
        Spec("sphere_glm_scale_then_translate", "object_moved", True, edit=_sphere_scaled_then_moved,
             truth="the mirror ball a unit sphere in object space placed by glm::translate(glm::scale(glm::mat4("
             "1.0f), glm::vec3(r)), c): glm's calls multiply on the right, so the point is translated first and "
             "then scaled: the centre 1.5 c = (14.25, 3, -4.95), the radius right: the ball through the wall and "
             "the floor, outside the room, not seen"),
        Spec("tetra_memcpy_sizeof_pointer", "object_missing", True, held_out=True, edit=cases.without("tetrahedron"),
             truth="the tetrahedron's 12 vertex floats copied with memcpy(tet.v, src, sizeof(src)) where src is a "
             "float*: sizeof a pointer, 8 bytes: the first vertex's x and y copied, the rest left 0: every face "
             "degenerate, the tetrahedron gone, the floor under it seen"),
        Spec("tetra_vertex_stride_3", "object_shape", True, mitsuba_edit=_tetra_strided,
             truth="the tetrahedron's 12 vertices read as &verts[0].p.x + 3 k from an array of struct Vertex { "
             "glm::vec3 p, n; } (6 floats each): the even ones the positions of vertices 0 to 5, the odd ones "
             "their unit normals, points by the origin: thin orange triangles from the tetrahedron's place to in "
             "front of the camera, most of the tetrahedron gone"),
    )


def _camera_and_light() -> tuple[Spec, ...]:
    """Camera and light models."""
    return (
        # Camera
        Spec("fov_glm_perspective_degrees", "camera_fov", True, edit=cases.fov(_FOV_GLM_DEGREES),
             truth="the rays made through the inverse of glm::perspective(90.0f, 1.0f, 0.1f, 100.0f), whose fovy "
             "is in radians: a half-angle of 45 radians, whose tangent is 1.62: a field of view of 116.6 degrees "
             "for 90: the view much wider, the room smaller"),
        Spec("camera_lookat_view_as_world", "camera_rotation", True, held_out=True, edit=_lookat_as_camera_to_world,
             truth="camera rays turned into the world by the rotation of glm::lookAt(eye, eye + forward, up), the "
             "view matrix (world to camera), not its inverse: the camera's -z sent along (0, -1, 0) and its up "
             "along (-1, 0, 0): the view turned 90 degrees to the right and rolled, onto the walls at the camera's "
             "right"),
        Spec("pixel_jitter_int_parameters", "pixel_offset", **_posted("corner_rays", partial(
            _corner_rays, spp=_S, seed=_crc("pixel_jitter_int_parameters"))),
             truth="each sample's jittered position x + U(gen), y + U(gen) passed to Ray cameraRay(int px, int py), "
             "which divides (px / W): the jitter truncated away, every sample through the pixel's top left corner: "
             "the image half a pixel up and to the left, without antialiasing"),
        # Light model
        Spec("light_rand_max_plus_one_overflow", "light_pdf", True, **_light_sample(
            "light_rand_max_plus_one_overflow", _light_rand_overflow),
             truth="the light's point from u = (float) rand() / (RAND_MAX + 1), glibc's RAND_MAX 2^31 - 1, so "
             "RAND_MAX + 1 overflows to INT_MIN: u and v in (-1, 0], at the first surface a camera ray meets "
             "(Mitsuba's path after it): the light sampled on a square of its size beside it, 2 units towards -x "
             "and -y, as if it were there: its light on the surfaces moved, the light seen right"),
        Spec("light_uniform_int_corners", "light_pdf", held_out=True, **_light_sample(
            "light_uniform_int_corners", _light_int_corners),
             truth="the light's point from std::uniform_int_distribution<int> U(0, 1) typed for "
             "uniform_real_distribution<float>: u and v each 0 or 1, one of the light's 4 corners, at the first "
             "surface a camera ray meets (Mitsuba's path after it): four hard shadows of each object for one soft "
             "one, the light seen right"),
        Spec("light_samples_one_over_n_int", "direct_missing", True, **_light_sample(
            "light_samples_one_over_n_int", _light_one_over_n_int),
             truth="the light samples at a vertex summed as L += Ld * (1 / nLight) with the int nLight = 4: 1 / 4 "
             "is 0 in integer division, at the first surface a camera ray meets (Mitsuba's path after it): no "
             "direct light there, the surfaces lit by bounces only, the light and its reflection seen right"),
    )


def _integrator_and_samples() -> tuple[Spec, ...]:
    """The integrator, samples, passes and counters."""
    c = _crc
    return (
        # Integrator
        Spec("bounce_cosine_c_abs", "indirect_scale", True, **_bounce("bounce_cosine_c_abs", _cosine_int_abs),
             truth="the diffuse bounce weighted albedo * abs(dot(n, d)) / pdf with C's integer abs (no <cmath>): "
             "the cosine truncated to 0, at the first surface a camera ray meets (Mitsuba's path after it): no "
             "light past the first diffuse bounce, the shadows black, the direct light right"),
        Spec("bounce_mt19937_fixed_seed", "indirect_scale", True, held_out=True, **_bounce(
            "bounce_mt19937_fixed_seed", _bounce_fixed_seed),
             truth="the bounce drawn with std::mt19937 gen; std::uniform_real_distribution<float> U(0, 1); declared "
             "inside the bounce function (default seed 5489): u1 = 0.815, u2 = 0.135 at every call, one "
             "cosine-weighted direction in every normal's frame, at the first surface a camera ray meets "
             "(Mitsuba's path after it): the indirect light from one direction, patchy, the direct light right"),
        Spec("roulette_rand_int_division", "roulette", True, **_posted("roulette_never", partial(
            _roulette_never, spp=_S, seed=c("roulette_rand_int_division"))),
             truth="Russian roulette as if (rand() / RAND_MAX > p) break; beta /= p; at the first bounce: the "
             "integer division is 0, never above p: no path ended, every one divided by p = max(albedo), at the "
             "first surface a camera ray meets (Mitsuba's path after it): the indirect light too bright (by 1 / "
             "0.8 off the ceiling, 1 / 0.75 off the red wall), the direct light right"),
        Spec("bounce_eigen_normalized_discarded", "indirect_scale", held_out=True, **_bounce(
            "bounce_eigen_normalized_discarded", _bounce_eigen_frame),
             truth="the tangent frame t = n.cross(a); t.normalized(); b = n.cross(t) in Eigen, normalized()'s "
             "copy discarded (normalize() meant): t and b as long as the sine between n and a, the cosine-weighted "
             "bounce's tangential parts shortened, at the first surface a camera ray meets (Mitsuba's path after "
             "it): on the slanted walls and the tetrahedron the bounces pulled towards the normal, the indirect "
             "light slightly off"),
        # Samples, passes and counters
        Spec("samples_omp_shared_race", "sample_count", True, **_posted("omp_race", partial(
            _race_lost, spp=_S, seed=c("samples_omp_shared_race"))),
             truth="#pragma omp parallel for over a pixel's samples, each adding to the shared glm::vec3 color "
             "(no reduction, no atomic): the updates of overlapping threads lost, about a quarter of them, the sum "
             "still divided by the spp: the image a quarter too dark, noisier"),
        Spec("samples_mt19937_copied_threads", "same_seed", held_out=True, **_posted("mt19937_copied", partial(
            _bands_one_stream, spp=_S, seed=c("samples_mt19937_copied_threads"))),
             truth="one std::mt19937 captured by value into the #pragma omp parallel region (firstprivate), 4 "
             "threads with the rows in 4 bands: every thread the same stream, each band's pixels the same "
             "random numbers (jitter and paths) as the pixels as many rows up in the first: the noise repeated "
             "down the image four times"),
        Spec("passes_memset_sizeof_pointer", "buffer_reused", True, **_posted("memset_pointer", partial(
            _preview_left, spp=_S, seed=c("passes_memset_sizeof_pointer"))),
             truth="the accumulator float* acc cleared with memset(acc, 0, sizeof(acc)) between a preview of 64 "
             "spp and the final 256: 8 bytes, the first pixel's red and green, cleared: the preview's sums left in "
             "every other value, divided by 256: the image 25 % too bright, 256 declared"),
        Spec("passes_uchar_codes", "quantisation", True, held_out=True, **_posted("passes_uchar", partial(
            _passes_uchar, seed=c("passes_uchar_codes"))),
             truth="8 passes of 32 spp, each pass's image kept as unsigned char codes (unsigned char)(255 * "
             "std::min(v, 1.0f)) to be shown while rendering, the codes averaged and divided by 255 into the EXR: "
             "the light and its reflection clipped at 1, the rest truncated to 255ths (the mean 1/510 low)"),
    )


def _correct() -> tuple[Spec, ...]:
    c = _crc
    return (
        Spec("ok_hdr_stbi_write_hdr", None, writer=_write_hdr_stb, file="hdr-stbi",
             truth="Mitsuba path 256 spp, a Radiance picture as stbi_write_hdr writes it: its header with "
             "EXPOSURE=1.0, mantissas truncated, scanlines run-length encoded"),
        Spec("ok_ppm_fwrite_unsigned_rows", None, held_out=True, spp=200, writer=_write_ppm_fwrite_rows,
             file="ppm-fwrite-rows",
             truth="Mitsuba path 200 spp, a binary PPM opened \"wb\", the header by fprintf and each row's unsigned "
             "char sRGB codes (rounded, clamped) by fwrite"),
        Spec("ok_samples_double_accumulator", None, spp=128, **_posted("double_sum", partial(
            _samples_double, spp=128, seed=c("ok_samples_double_accumulator"))),
             truth="Mitsuba path 128 spp, its samples summed in a double accumulator, EXR"),
        Spec("ok_samples_omp_reduction", None, held_out=True, spp=192, **_posted("omp_reduction", partial(
            _samples_reduction, spp=192, seed=c("ok_samples_omp_reduction"))),
             truth="Mitsuba path 192 spp, each pixel's samples summed by #pragma omp parallel for reduction(+:r, "
             "g, b) over 4 threads in float, EXR"),
        Spec("ok_bounce_glm_spherical_rand", None, **_bounce("ok_bounce_glm_spherical_rand",
                                                             _sphere_rand_plus_normal),
             truth="Mitsuba path 256 spp with the first bounce glm::normalize(n + glm::sphericalRand(1.0f)) "
             "(cosine-weighted), EXR"),
        Spec("ok_light_two_samples_averaged", None, held_out=True, **_light_sample(
            "ok_light_two_samples_averaged", _light_two_averaged),
             truth="Mitsuba path 256 spp with the first vertex's direct light the mean of 2 light samples at "
             "uniform points of the light, EXR"),
        Spec("ok_exr_tinyexr_bgr_half", None, spp=176, writer=_write_exr_bgr_half, file="exr-tinyexr-half",
             truth="Mitsuba path 176 spp, a half-float EXR as tinyexr writes it, the channels named B, G, R each "
             "with its own plane"),
        Spec("ok_png_stbi_stride_3w", None, held_out=True, spp=168, writer=_write_png_stride_3w, file="png-stbi",
             truth="Mitsuba path 168 spp, an 8-bit sRGB PNG by stbi_write_png(\"out.png\", W, H, 3, data, W * 3)"),
    )


MISTAKES, CORRECT = _mistakes(), _correct()
SPECS: tuple[Spec, ...] = MISTAKES + CORRECT

#: Existing causes worded for this class's cases (their old words name only another instance of the mistake).
_REWORDED = {
    "quantisation": "values quantised wrongly (truncated to integers by C's integer abs, 8-bit codes kept between "
                    "passes)",
    "blur": "a filter after rendering (a box blur whose neighbours are the wrong floats)",
    "orientation": "the image written transposed (a frame buffer's strides swapped)",
    "encoding": "the values' encoding (display values, clipped and sRGB-encoded, in an HDR file)",
    "normalised": "the values normalised after rendering (divided by the integer part of their maximum)",
    "colour_grade": "the colours graded after rendering (a saturation matrix transposed)",
    "row_stride": "pixels written at the wrong addresses (4-float pixels read as 3)",
    "channels": "colour channels written in the wrong order (red and blue under each other's names)",
    "material": "an object rendered with another material (the mirror's reflection's arguments swapped, mirrors "
                "and diffuse surfaces exchanged)",
    "albedo": "a surface's colour (every albedo parsed as 0)",
    "object_moved": "an object moved (the sphere's centre scaled by its radius)",
    "object_missing": "an object missing (the tetrahedron's vertices not copied)",
    "object_shape": "an object's shape (the tetrahedron's vertices read with the wrong stride)",
    "camera_fov": "the camera's field of view (degrees taken as radians)",
    "camera_rotation": "the camera's rotation (the view matrix used for its inverse)",
    "pixel_offset": "the pixel centres (every sample through the pixel's corner)",
    "light_pdf": "the light sampled wrongly (points beside it, only its corners): the light seen right, its light on "
                 "surfaces not",
    "direct_missing": "direct light missing at the first surface hit (its samples weighted by an integer "
                      "division's 0)",
    "indirect_scale": "the indirect light wrong (the bounce's cosine 0, one direction, a frame not normalised), the "
                      "direct light right",
    "roulette": "Russian roulette wrong (no path ended, each divided by the survival probability)",
    "sample_count": "each pixel's sum divided by more samples than it kept (updates lost to a race)",
    "same_seed": "renders that should be independent made with the same seed (one stream copied to every thread)",
    "buffer_reused": "another render's samples left in the accumulation buffer (a preview's, cleared by a pointer's "
                     "size)",
}
#: The causes of this class's cases, as the report words them.
CAUSES: dict[str, str] = blind.class_causes(MISTAKES, _EARLIER, NEW_CAUSES, _REWORDED)


def held_out_rule(specs: tuple[Spec, ...] = SPECS) -> dict[str, bool]:
    """Which cases the rule of the module docstring holds out (the blind class's rule,
    :func:`mcrt.grade.accuracy.blind.alternating`, over :data:`CATEGORIES`)."""
    return blind.alternating(CATEGORIES, specs)
