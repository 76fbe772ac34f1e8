r"""The light sample's geometry term written wrongly: its cosines, its fall-off, a clamp, a cone.

Next-event estimation at a surface point :math:`p` adds
:math:`f\,L_e\,G(p, y) / p_A(y)` for a point :math:`y` drawn on the light,
:math:`G = \cos_s \cos_l / d^2` (the cosines at the surface and at the
light, the distance between them). A tracer that writes :math:`G` as
something else, :math:`G'`, changes the direct light of every surface by
the ratio of the two integrated over the light. With :math:`D` the direct
light at the first hit (the basis's paths of depth 2 less those of depth 1)
and :math:`p` the first hits of each pixel's :data:`SUB` :math:`^2` rays on
Lambertian surfaces, the model image is :math:`R + D\,(k - 1)` with

.. math::

    k = \frac{\sum_p \sum_y G'(p, y)}{\sum_p \sum_y G(p, y)}

over :data:`QUADRATURE` :math:`^2` points of the light (no visibility: a
point in full light or in full shadow is exact, a penumbra approximate).
Where :math:`G` sums to 0 and :math:`G'` does not (a surface facing away
that a half-Lambert lights), the model adds the unshadowed
:math:`\rho L_e A \bar{G'} / \pi`. The mistakes (:func:`variants`): the
light's cosine applied twice, or clamped from below in the pdf; the
pdf left in area measure, or converted without its :math:`d^2` or its
cosine at the light; the cosines and the distance taken from the light's centre; the fall-off
:math:`1/d`, or a point light's attenuation :math:`1/(1 + a d + b d^2)`
(OpenGL tutorials' table, by range) for the inverse square or beside it;
the light's cosine taken with the surface's normal; a spotlight's cone
left on; the surface's cosine twice; Valve's half-Lambert; and the light
sample taken from the eye (the ray's origin for the hit point), whose
direct light replaces :math:`D` outright (unshadowed: the eye sees the
light). Each is a candidate with no free parameter
or with the one its table scans (the clamp, the range, the cone). Its
change is made once per assignment (:func:`_prepare`); only its fit is per
hand-in. The model changes the light sample at the surfaces the camera sees
directly; where a tracer makes the mistake at every vertex, the light that
bounces on changes too, and the words say "partly like".
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit

#: Points along each side of the light in its quadrature (the light's midpoints of a QUADRATURE^2 grid).
QUADRATURE = 8
#: Rays along each side of a pixel (SUB^2 at the strata's centres): a pixel on an edge sums its surfaces' terms.
SUB = 2
#: The cosine at the light clamped from below in a solid-angle pdf (against a division by zero).
CLAMPS = (0.05, 0.1, 0.2, 0.3)
#: Spotlight cones (half-angles, degrees) a template leaves on.
CONES = (30.0, 45.0, 60.0, 75.0)
#: OpenGL tutorials' attenuation 1 / (1 + a d + b d^2) by the light's range: (a, b).
ATTENUATION = {7: (0.7, 1.8), 13: (0.35, 0.44), 20: (0.22, 0.20), 32: (0.14, 0.07), 50: (0.09, 0.032),
               65: (0.07, 0.017), 100: (0.045, 0.0075), 160: (0.027, 0.0028), 200: (0.022, 0.0019),
               325: (0.014, 0.0007), 600: (0.007, 0.0002)}
#: The shortest range whose attenuation, kept beside the inverse square, leaves a tenth of the direct light ten units
#: away: a shorter one leaves almost none, which is the direct light missing in other words (the image cannot tell).
KEPT_RANGE = 32


def _pos(x):
    return np.maximum(x, 0.0)


def variants() -> dict[str, list[tuple[object, str, object]]]:
    """{family: [(value, words, G'(cos_s, cos_l, d, centre))]}: each family's mistakes of the geometry term, with the
    signed cosines (cos_s at the surface, cos_l at the light), the distance, and the same three from the light's
    centre (shape (pixels, 1))."""
    return {
        "light_cosine": [
            ("cos_l^2", "the cosine at the light applied twice in the light sample (in the geometry term and in the "
                        "conversion of its pdf to solid angle): cos_s cos_l^2 / d^2",
             lambda cs, cl, d, c: _pos(cs) * _pos(cl) ** 2 / d**2),
            ("centre", "the light sample's cosines and distance computed from the light's centre, not from the point "
                       "drawn on it (the shadow ray to that point)",
             lambda cs, cl, d, c: np.broadcast_to(_pos(c[0]) * _pos(c[1]) / c[2] ** 2, cs.shape)),
            ("surface normal", "the cosine at the light taken with the surface's normal (one name for two normals): "
                               "cos_s^2 / d^2 in the light sample",
             lambda cs, cl, d, c: _pos(cs) * np.abs(cs) / d**2),
        ] + [(f"clamp {k:g}", f"the cosine at the light clamped to at least {k:g} in the light sample's solid-angle "
                              f"pdf d^2 / (A max(cos_l, {k:g})): light leaving the light obliquely counted as at "
                              f"{k:g}", lambda cs, cl, d, c, k=k: _pos(cs) * _pos(cl) ** 2 / np.maximum(cl, k) / d**2)
             for k in CLAMPS],
        "light_falloff": [
            ("1/d", "the light sample's fall-off 1 / d where the inverse square 1 / d^2 belongs",
             lambda cs, cl, d, c: _pos(cs) * _pos(cl) / d),
        ] + [(f"attenuation {r}", f"a point light's attenuation 1 / (1 + {a:g} d + {b:g} d^2) (an OpenGL tutorial's, "
                                  f"for a range of {r}) where the inverse square 1 / d^2 belongs in the light sample",
              lambda cs, cl, d, c, a=a, b=b: _pos(cs) * _pos(cl) / (1.0 + a * d + b * d * d))
             for r, (a, b) in ATTENUATION.items()]
        + [(f"attenuated {r}", f"a point light's attenuation 1 / (1 + {a:g} d + {b:g} d^2) (an OpenGL tutorial's, for "
                               f"a range of {r}) kept in the area light's sample beside its 1 / d^2",
            lambda cs, cl, d, c, a=a, b=b: _pos(cs) * _pos(cl) / d**2 / (1.0 + a * d + b * d * d))
           for r, (a, b) in ATTENUATION.items() if r >= KEPT_RANGE]
        + [(f"cone {t:g}", f"a spotlight's cone of {t:g} degrees left on in the light sample: no light leaving the "
                           f"light more than {t:g} degrees from its normal",
            lambda cs, cl, d, c, t=t: _pos(cs) * _pos(cl) * (cl >= np.cos(np.radians(t))) / d**2) for t in CONES],
        "surface_cosine_twice": [
            ("cos_s^2", "the cosine at the surface applied twice in the light sample (Lambert's cosine written into "
                        "the BRDF and kept in the geometry term): cos_s^2 cos_l / d^2",
             lambda cs, cl, d, c: _pos(cs) ** 2 * _pos(cl) / d**2),
        ],
        # The light sample's pdf 1 / A left in area measure, or turned into solid angle with a factor missing.
        "light_measure": [
            ("area pdf", "the light sample's pdf 1 / A in area measure used where the solid angle's d^2 / (A cos_l) "
                         "belongs (never converted): no fall-off with distance and no cosine at the light, cos_s in "
                         "the light sample", lambda cs, cl, d, c: _pos(cs) * (cl > 0)),
            ("no inverse square", "the light sample's pdf converted to solid angle without its d^2: cos_s cos_l in the "
                                  "light sample, no fall-off with distance", lambda cs, cl, d, c: _pos(cs) * _pos(cl)),
            ("no light cosine", "the light sample's pdf converted to solid angle without the cosine at the light: "
                                "cos_s / d^2 in the light sample, light leaving the light obliquely too bright",
             lambda cs, cl, d, c: _pos(cs) * (cl > 0) / d**2),
        ],
        "shading_cosine": [
            ("half-Lambert", "Valve's half-Lambert (0.5 cos_s + 0.5)^2 for the cosine at the surface in the light "
                             "sample (a game shader's soft lighting): light arriving obliquely too bright, surfaces "
                             "turned from the light lit a little",
             lambda cs, cl, d, c: (0.5 * cs + 0.5) ** 2 * _pos(cl) / d**2),
        ],
    }


def _geometry(scene, p: np.ndarray, n: np.ndarray):
    """The signed cosines and distances between points ``p`` (normals ``n``), shape (pixels, 3), and the light's
    quadrature points, shape (pixels, Q^2); the same from the light's centre, shape (pixels, 1)."""
    lt = scene.light
    q = (np.arange(QUADRATURE) + 0.5) / QUADRATURE - 0.5
    gx, gy = np.meshgrid(q * lt.size[0], q * lt.size[1])
    ys = np.asarray(lt.center, float) + np.stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)], axis=1)
    nl = np.asarray(lt.normal, float)

    def terms(y):
        w = y[None, :, :] - p[:, None, :]
        d = np.maximum(np.linalg.norm(w, axis=-1), 1e-9)
        return np.einsum("pk,pyk->py", n, w) / d, -np.einsum("k,pyk->py", nl, w) / d, d

    return terms(ys), terms(np.asarray(lt.center, float)[None, :])


def _prepare(a, scene, render) -> dict:
    """{(family, value): (words, k (H, W, 1), added (H, W, 3))}: each variant's factor on the first hit's direct
    light, and the light it adds where the correct geometry term sums to 0 (the module docstring)."""
    from mcrt.camera import primary_directions
    from mcrt.grade.hits import nearest
    from mcrt.scene import Lambertian

    w, h = a.grade_width, a.grade_height
    mats = [s.material for s in scene.surfaces()] + [sp.material for sp in scene.spheres()] + [None]
    diffuse = np.array([isinstance(m, Lambertian) for m in mats])
    albedo = np.array([m.albedo if isinstance(m, Lambertian) else (0.0, 0.0, 0.0) for m in mats])
    cam = scene.camera(a.camera)
    jj, ii = np.mgrid[0:h, 0:w]
    rays = []  # each of a pixel's SUB^2 rays: where it meets a Lambertian first (its label, point, normal)
    for su in range(SUB):
        for sv in range(SUB):
            d = primary_directions(cam, w, h, ii, jj, np.full(ii.shape, (su + 0.5) / SUB),
                                   np.full(ii.shape, (sv + 0.5) / SUB)).reshape(-1, 3)
            label, t, n = nearest(scene, np.asarray(cam.eye, float), d)
            rays.append((label, np.asarray(cam.eye, float) + np.where(np.isfinite(t), t, 0.0)[:, None] * d, n))
    area = scene.light.size[0] * scene.light.size[1]
    sums: dict = {}
    table = variants()
    eye_lit = 0.0  # each pixel's light sample taken from the eye with its surface's normal (no shadow: the eye sees it)
    for label, p, n in rays:
        (cs, cl, dist), centre = _geometry(scene, p, n)
        on = diffuse[label]
        (ce, le, de), _ = _geometry(scene, np.broadcast_to(np.asarray(cam.eye, float), p.shape), n)
        eye_lit = eye_lit + np.where(on, (_pos(ce) * _pos(le) / de**2).sum(axis=1), 0.0)[:, None] * albedo[label]
        G = np.where(on, (_pos(cs) * _pos(cl) / dist**2).sum(axis=1), 0.0)
        for family, vs in table.items():
            for value, words, g in vs:
                Gp = np.where(on, g(cs, cl, dist, centre).sum(axis=1), 0.0)
                # Rays whose surface the right term does not light add their own (a half-Lambert's), apart.
                s0 = sums.setdefault((family, value), [words, 0.0, 0.0, 0.0])
                s0[1], s0[2] = s0[1] + G, s0[2] + np.where(G > 0, Gp, 0.0)
                s0[3] = s0[3] + np.where(G > 0, 0.0, Gp)[:, None] * albedo[label]
    share = sum(diffuse[label] for label, _, _ in rays) / SUB**2
    out = {}
    for key, (words, G, Gp, extra) in sums.items():
        k = np.where(G > 0, Gp / np.where(G > 0, G, 1.0), 1.0)
        k = (1.0 + share * (k - 1.0)).reshape(h, w, 1)
        added = extra.reshape(h, w, 3) / (SUB**2 * QUADRATURE**2) * area / np.pi * np.asarray(scene.light.radiance)
        out[key] = (words, k, added)
    # The light sample taken from the ray's origin: the direct light of the pixel's surfaces replaced outright.
    out[("light_cosine", "ray origin")] = (
        "the light sample taken from the ray's origin (ray.o, the eye for a camera ray) where the hit point belongs, "
        "with the surface's normal: no shadows, every surface lit as if it stood at the eye",
        (1.0 - share).reshape(h, w, 1),
        eye_lit.reshape(h, w, 3) / (SUB**2 * QUADRATURE**2) * area / np.pi * np.asarray(scene.light.radiance))
    return out


def light_geometry(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """R + D (k - 1) (+ the light added where none arrived) for each variant (the module docstring); of the variants
    scanned within a family by one table (clamps, ranges, cones), the best."""
    b = inputs.basis
    prepared = b.extra.get(light_geometry.name) if b is not None else None
    depth = dict(b.nodes.get("depth", ())) if b is not None else {}
    if not prepared or 1 not in depth or 2 not in depth:
        return []
    D = np.asarray(depth[2], np.float64) - np.asarray(depth[1], np.float64)
    if D.shape != fit.R.shape:
        return []
    best: dict[str, Candidate] = {}
    for (family, value), (words, k, added) in prepared.items():
        change = D * (k - 1.0) + added
        head, _, number = value.rpartition(" ")
        scanned = number.replace(".", "", 1).isdigit()  # one of a table's values (a clamp, a range, a cone)
        table = head if scanned else value
        cand = Candidate(family, f"light sample: {value}", words, fit.delta(change), 1 if scanned else 0,
                         value=value, change=change)
        key = f"{family}:{table}"
        if key not in best or cand.chi2 < best[key].chi2:
            best[key] = cand
    return list(best.values())


light_geometry.name, light_geometry.prepare = "light_geometry", _prepare
