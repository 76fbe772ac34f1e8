r"""An auxiliary buffer written for the rendered image: the first hits' albedo, normals or distance.

A film that keeps auxiliary buffers beside the image (an AOV for a
denoiser, a debugging view) can write the wrong one. Each is a function of
what each pixel's camera rays meet first (:func:`mcrt.grade.hits.first_hits`,
4 x 4 rays a pixel, prepared once): with :math:`c_k` the share of a pixel's
rays meeting surface k, :math:`n` their mean normal (facing the ray) and
:math:`d` their mean distance, the model images are

* the albedo buffer :math:`\sum_k c_k \rho_k`: each diffuse surface's
  albedo, and one grey value fitted for the mirror and one for the light
  (a renderer's albedo of a mirror or an emitter is its own convention: 0,
  1, or what the mirror reflects);
* the normal buffer, as colours :math:`(n + 1) / 2` or as they are (a
  display file clips the negatives), each also read back through the sRGB
  curve (codes written linear into a file that says sRGB);
* the depth buffer :math:`a + b\,d` (a and b fitted: a distance in the
  scene's units, or normalised and inverted for display).

Pixels whose rays meet several surfaces are mixtures, as a film's are. The
same first hits give :mod:`~mcrt.grade.explain.view_cosine` its cosine to the
eye, :mod:`~mcrt.grade.explain.direct_albedo` each pixel's albedo and
:mod:`~mcrt.grade.explain.clip` each ray's distance (all read this family's
prepared dict).
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.grade.feedback import num as _num

#: What each buffer is, in words (followed by ", written for the rendered image").
WORDS = {"albedo": "the film's albedo buffer (each pixel the reflectance of the first surface its rays meet: each "
                   "diffuse surface's colour, the mirror {mirror}, the light {light})",
         "normals": "the surface normals written as colours{how} (each pixel the normal of the first surface its rays "
                    "meet, x, y, z as red, green, blue)",
         "depth": "a depth buffer (each pixel the distance to the first surface its rays meet, {how})"}


def aov(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The albedo, normal and depth buffers, each at its best fit (the module docstring)."""
    hits = inputs.basis.extra.get(aov.name) if inputs.basis is not None else None
    if hits is None or hits["cover"].shape[:2] != fit.R.shape[:2]:
        return []
    w = np.where(fit.ok, fit.w, 0.0)
    return [c for c in (_albedo(fit, w, hits), _normals(fit, hits), _depth(fit, w, hits)) if c is not None]


def _lsq(columns: list, S: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Weighted least-squares coefficients of S on the columns (each broadcast to S's shape)."""
    A = np.stack([np.broadcast_to(c, S.shape).ravel() for c in columns], axis=1) * np.sqrt(w.ravel())[:, None]
    return np.linalg.lstsq(A, S.ravel() * np.sqrt(w.ravel()), rcond=None)[0]


def _albedo(fit: Fit, w: np.ndarray, hits: dict) -> Candidate:
    """Each diffuse surface's albedo where the rays meet it; the mirror's and the light's grey values fitted."""
    cover, rho = hits["cover"], hits["albedo"]
    fixed = cover @ rho
    parts = [cover[..., hits["mirror"]].sum(axis=-1, keepdims=True), cover[..., hits["light"]].sum(axis=-1, keepdims=True)]
    m, l = np.maximum(_lsq(parts, fit.S - fixed, w), 0.0)
    M = fixed + m * parts[0] + l * parts[1]
    # Two places are all a grey value read off a few hundred pixels says (a fitted 0.0005 is a renderer's 0).
    text = WORDS["albedo"].format(mirror=_num(round(float(m), 2)), light=_num(round(float(l), 2))) + (
        ", written for the rendered image")
    return Candidate("wrong_buffer", "albedo buffer", text, fit.model(M), 2,
                     value={"buffer": "albedo", "mirror": float(m), "light": float(l)}, change=M - fit.R)


def _normals(fit: Fit, hits: dict) -> Candidate:
    """The normals as (n + 1) / 2 or as they are (clipped at 0 in a display file), each also sRGB-decoded."""
    from mcrt.image_files import srgb_eotf

    n = hits["normal"]
    clip = float(np.max(fit.S)) <= 1.0  # a display file's values
    forms = {" ((n + 1) / 2)": (n + 1.0) / 2.0, " as they are": np.maximum(n, 0.0) if clip else n}
    best = None
    for how, img in forms.items():
        for decoded, M in ((False, img), (True, srgb_eotf(np.clip(img, 0.0, 1.0)))):
            chi = fit.model(M)
            if best is None or chi < best[0]:
                best = (chi, how + (", their codes read back through the sRGB curve" if decoded else ""), M)
    chi, how, M = best
    return Candidate("wrong_buffer", "normal buffer", WORDS["normals"].format(how=how) + ", written for the rendered "
                     "image", chi, 1, value={"buffer": "normals", "form": how.strip()}, change=M - fit.R)


#: The least a depth buffer's values span from the nearest pixel to the farthest (white is 1): a near-constant fit
#: (b near 0) is any near-black or flat image, no depth written for display or as a distance.
MIN_DEPTH_SPAN = 0.1


def _depth(fit: Fit, w: np.ndarray, hits: dict) -> Candidate | None:
    """a + b d in every channel, a and b by weighted least squares (either may be negative: a depth inverted for
    display); None where it spans less than :data:`MIN_DEPTH_SPAN`."""
    d = hits["distance"][..., None]
    a, b = _lsq([1.0, d], fit.S, w)
    if abs(b) * float(np.ptp(d)) < MIN_DEPTH_SPAN:
        return None
    M = np.broadcast_to(a + b * d, fit.S.shape)
    # An offset below 1 % of the middle distance's value is the fit's noise, not a depth inverted or shifted.
    how = f"{_num(a)} + {_num(b)} d" if abs(a) > 0.01 * abs(b) * float(np.median(d)) else f"{_num(b)} d"
    return Candidate("wrong_buffer", "depth buffer", WORDS["depth"].format(how=how) + ", written for the rendered "
                     "image", fit.model(M), 2, value={"buffer": "depth", "offset": float(a), "scale": float(b)},
                     change=M - fit.R)


def _prepare(a, scene, render) -> dict:
    """The assignment camera's first hits at the grade resolution, and each label's diffuse albedo (0 for the
    mirror, the light and nothing, whose labels are listed apart)."""
    from mcrt.grade.hits import first_hits
    from mcrt.scene import Lambertian

    hits = first_hits(scene, a.camera, a.grade_width, a.grade_height)
    mats = [s.material for s in scene.surfaces()] + [sp.material for sp in scene.spheres()] + ["nothing"]
    rho = np.array([m.albedo if isinstance(m, Lambertian) else (0.0, 0.0, 0.0) for m in mats], np.float64)
    return {"cover": hits.counts / hits.counts.sum(axis=-1, keepdims=True), "albedo": rho,
            "mirror": [k for k, m in enumerate(mats) if m is not None and not isinstance(m, (Lambertian, str))],
            "light": [k for k, m in enumerate(mats) if m is None], "normal": hits.normal, "distance": hits.distance,
            "view_cosine": _view_cosine(hits, mats),
            "ray_distance": hits.ray_distance.astype(np.float32), "ray_depth": hits.ray_depth.astype(np.float32)}


def _view_cosine(hits, mats) -> np.ndarray:
    """(H, W, 1) the mean over each pixel's rays of |n . d| where a ray meets a Lambertian, 1 where it meets anything
    else (mcrt.grade.explain.view_cosine's factor)."""
    from mcrt.scene import Lambertian

    diffuse = np.array([isinstance(m, Lambertian) for m in mats])
    f = hits.cosines[..., diffuse].sum(axis=-1) + hits.counts[..., ~diffuse].sum(axis=-1)
    return (f / hits.counts.sum(axis=-1))[..., None]


aov.name = "aov"
aov.prepare = _prepare
