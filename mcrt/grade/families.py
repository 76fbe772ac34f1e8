r"""Families of mistakes a student's program makes beyond the scene's parameters.

Each family is a callable ``family(fit, inputs) -> [candidate, ...]`` (the
explanation stage's contract): ``fit`` holds the hand-in S, the reference R,
D = S - R, the pixels used and the chi-square weights (``fit.delta(change)``
is the chi-square a predicted change leaves); ``inputs.basis`` the mcrt
renders, among them those :func:`prepare` adds. Each candidate keeps its
fitted value in the student's terms.

============== ================================================ =======================================
family         model image                                      how it is fitted
============== ================================================ =======================================
tone_curve     f_c(R), f_c monotone per channel (any tone map,  isotonic regression of S on R per
               clamp or encoding), named when it matches        channel (scipy.optimize.isotonic_
               Reinhard, ACES, a clamp or 8-bit quantisation    regression) on quantile bins of R
material       an object rendered as another material           mcrt renders of the object diffuse or
               (diffuse for the mirror, mirror for the          mirror at 0, 1/2, 1, interpolated per
               diffuse), its albedo or reflectance fitted       channel (Lagrange)
falloff        R (1 + a smooth polynomial of the pixel's        weighted least squares; and cos^k of
               position): a vignette, cos weighting             the ray's angle, k scanned
resampling     R box-filtered to 1/k the resolution and         closed form, k = 2, 4
               enlarged (nearest: blocks; bilinear)
object_size    an object's size (a sphere's radius, a           mcrt renders at a few scales,
               tetrahedron about its centroid)                  interpolated between neighbours
============== ================================================ =======================================

Noise that does not match the declared samples per pixel is not a change of
the mean: the noise criterion of the grader words it (the spp the noise is
like, against the spp declared).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from mcrt.scene import Lambertian, Mirror, Scene

#: Quantile bins of R per channel for the isotonic fit (each bin's fitted level is one parameter at most).
BINS = 24
#: Albedo or reflectance nodes of an object rendered as another material.
MATERIAL_NODES = (0.0, 0.5, 1.0)
#: Scale factors of an object's size rendered (1 is the scene's own).
SIZES = (0.8, 0.9, 0.95, 1.05, 1.1, 1.2)
#: Resolution factors of the resampling family.
FACTORS = (2, 4)


def _candidate(family: str, name: str, text: str, chi2: float, params: int, *, value, change: np.ndarray):
    """A candidate of the explanation stage (its Candidate class; ``change`` is M - R)."""
    from mcrt.grade.explain import Candidate

    return Candidate(family, name, text, chi2, params, value=value, delta=change)


def _num(x: float, digits: int = 2) -> str:
    return f"{x:.{digits}f}".rstrip("0").rstrip(".")


def _fmt(v) -> str:
    v = [float(x) for x in v]
    if len({round(x, 2) for x in v}) == 1:
        return _num(v[0])
    return "(" + ", ".join(f"{x:.2f}" for x in v) + ")"


# --------------------------------------------------------------------------
# A monotone value curve
# --------------------------------------------------------------------------


def _aces(x):
    """Narkowicz's fit of the ACES filmic curve."""
    return np.clip(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0)


def _named_curves() -> dict[str, tuple[str, callable]]:
    from mcrt.imageio import srgb_oetf

    def q8(x):
        return np.floor(np.clip(x, 0.0, 1.0) * 255.0 + 0.5) / 255.0

    return {
        "reinhard": ("put through Reinhard's tone map x / (1 + x)", lambda x: x / (1.0 + x)),
        "reinhard+srgb": ("put through Reinhard's tone map x / (1 + x), then the sRGB curve", lambda x: srgb_oetf(x / (1.0 + x))),
        "aces": ("put through the ACES filmic tone map", _aces),
        "aces+srgb": ("put through the ACES filmic tone map, then the sRGB curve", lambda x: srgb_oetf(_aces(x))),
        "clamp": ("clamped to [0, 1]", lambda x: np.clip(x, 0.0, 1.0)),
        "quantised": ("clamped to [0, 1] and rounded to 8 bits (linear)", q8),
    }


#: Exposures scanned before a named tone map (a student's exposure slider; 1 is none).
EXPOSURES = (0.25, 0.35, 0.5, 0.7, 1.0, 1.4, 2.0, 2.8, 4.0)


def tone_curve(fit, inputs) -> list:
    """Named tone maps (an exposure scanned before each), and any monotone curve per channel (isotonic)."""
    R = np.maximum(fit.R, 0.0)
    out = []
    for key, (words, f) in _named_curves().items():
        scan = EXPOSURES if key not in ("clamp", "quantised") else (1.0,)
        errs = [fit.model(f(k * R)) for k in scan]
        i = int(np.argmin(errs))
        k = scan[i]
        exp = f" after an exposure of {_num(k)}" if k != 1.0 else ""
        out.append(_candidate("tone_curve", f"tone map {key}", f"the values {words}{exp} before saving",
                              errs[i], 1 if len(scan) > 1 else 0, value={"curve": key, "exposure": k}, change=f(k * R) - fit.R))
    out.append(_isotonic(fit))
    return out


def _isotonic(fit):
    from scipy.optimize import isotonic_regression

    M = np.array(fit.R, np.float64)
    params, knots = 0, []
    for c in range(3):
        ok = fit.ok[..., c]
        x, y, w = fit.R[..., c][ok], fit.S[..., c][ok], fit.w[..., c][ok]
        if x.size < BINS:
            continue
        order = np.argsort(x, kind="stable")
        groups = np.array_split(order, BINS)
        wx = np.array([max(float(w[g].sum()), 1e-300) for g in groups])
        xm = np.array([float(np.sum(w[g] * x[g])) for g in groups]) / wx
        ym = np.array([float(np.sum(w[g] * y[g])) for g in groups]) / wx
        res = isotonic_regression(ym, weights=wx, increasing=True)
        levels = res.x
        params += len(res.blocks) - 1
        M[..., c] = np.interp(fit.R[..., c], xm, levels)
        knots.append((xm, levels))
    change = M - fit.R
    probe = [float(v) for v in np.quantile(fit.R[fit.ok], [0.1, 0.5, 0.99])] if fit.ok.any() else []
    lum = [float(np.mean([np.interp(p, xm, lv) for xm, lv in knots])) for p in probe] if knots else []
    says = ", ".join(f"{_num(p, 3)} to {_num(q, 3)}" for p, q in zip(probe, lum))
    text = (f"the values through a monotone curve (a tone map, clamp or encoding) that maps {says}" if says
            else "the values through a monotone curve")
    return _candidate("tone_curve", "monotone curve", text, fit.delta(change), params,
                      value={"curve": "monotone", "maps": [[p, q] for p, q in zip(probe, lum)]}, change=change)


# --------------------------------------------------------------------------
# A smooth fall-off across the image
# --------------------------------------------------------------------------


def _coords(h: int, w: int):
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    return (xx + 0.5) / w * 2 - 1, 1 - (yy + 0.5) / h * 2  # x right, y up, in [-1, 1]


def falloff(fit, inputs) -> list:
    """A multiplicative quadratic field (weighted least squares), and cos^k of the ray's angle (k scanned)."""
    h, w = fit.R.shape[:2]
    x, y = _coords(h, w)
    cols = [x, y, x * x, x * y, y * y]
    A = np.stack([np.where(fit.ok, fit.R * c[..., None], 0.0).ravel() for c in cols], axis=1)
    sw = np.sqrt(np.where(fit.ok, fit.w, 0.0)).ravel()
    beta, *_ = np.linalg.lstsq(A * sw[:, None], fit.D.ravel() * sw, rcond=None)
    g = 1.0 + sum(b * c for b, c in zip(beta, cols))
    change = fit.R * (g[..., None] - 1.0)
    edges = {"left": g[:, 0].mean(), "right": g[:, -1].mean(), "top": g[0].mean(), "bottom": g[-1].mean(),
             "corners": float(np.mean([g[0, 0], g[0, -1], g[-1, 0], g[-1, -1]]))}
    words = ", ".join(f"{100 * v:.0f} % at the {k}" for k, v in edges.items())  # the centre's factor is 1
    out = [_candidate("falloff", "smooth fall-off", "the brightness changing smoothly across the image, relative to its centre: "
                      f"{words} (a vignette, a weight per pixel, a light's fall-off)", fit.delta(change), 5,
                      value={k: float(v) for k, v in edges.items()}, change=change)]
    basis = getattr(inputs, "basis", None)
    fov = getattr(basis, "fov_deg", 90.0)
    t = math.tan(math.radians(fov) / 2)
    cos = 1.0 / np.sqrt(1.0 + (x * t) ** 2 + (y * t * h / w) ** 2)
    ks = np.arange(-4.0, 4.01, 0.25)
    errs = [fit.delta(fit.R * (cos[..., None] ** k - 1.0)) for k in ks]
    i = int(np.argmin(errs))
    k = float(ks[i])
    how = (f"multiplied by cos^{_num(k)} of the angle between its ray and the view axis" if k > 0 else
           f"divided by cos^{_num(-k)} of the angle between its ray and the view axis")
    out.append(_candidate("falloff", "cosine weight", f"each pixel {how} (a camera model that weights rays)",
                          errs[i], 1, value={"cos_power": k}, change=fit.R * (cos[..., None] ** k - 1.0)))
    return out


# --------------------------------------------------------------------------
# Resolution and resampling
# --------------------------------------------------------------------------


def _blocks_equal(S: np.ndarray, k: int) -> float:
    """Share of k x k blocks whose pixels are all equal (the trace of nearest-neighbour enlarging)."""
    h, w = S.shape[:2]
    if h % k or w % k:
        return 0.0
    b = S.reshape(h // k, k, w // k, k, -1)
    return float(np.mean(np.all(b == b[:, :1, :, :1], axis=(1, 3, 4))))


def resampling(fit, inputs) -> list:
    """The image rendered at 1/k the resolution and enlarged, by nearest neighbour or bilinearly."""
    from scipy.ndimage import zoom

    from mcrt.stats.tiles import block_means

    h, w = fit.R.shape[:2]
    out = []
    for k in FACTORS:
        if h % k or w % k:
            continue
        low = block_means(fit.R, k)
        near = np.repeat(np.repeat(low, k, axis=0), k, axis=1)
        lin = zoom(low, (k, k, 1), order=1, mode="nearest", grid_mode=True)
        eq = _blocks_equal(fit.S, k)
        blocks = f" ({100 * eq:.0f} % of its {k} x {k} blocks are one colour)" if eq > 0.5 else ""
        out.append(_candidate("resampling", f"enlarged {k}x (nearest)", f"the image rendered at {w // k} x {h // k} "
                              f"pixels and enlarged {k} times by repeating pixels{blocks}", fit.model(near), 1,
                              value={"factor": k, "method": "nearest", "equal_blocks": eq}, change=near - fit.R))
        out.append(_candidate("resampling", f"enlarged {k}x (bilinear)", f"the image rendered at {w // k} x {h // k} "
                              f"pixels and enlarged {k} times by bilinear interpolation", fit.model(lin), 1,
                              value={"factor": k, "method": "bilinear"}, change=lin - fit.R))
    return out


# --------------------------------------------------------------------------
# An object's material and size: renders
# --------------------------------------------------------------------------


def _with_object(scene: Scene, name: str, **changes) -> Scene:
    return replace(scene, objects=tuple(replace(o, **changes) if o.name == name else o for o in scene.objects))


def _scaled(o, f: float):
    if hasattr(o, "radius"):
        return {"radius": o.radius * f}
    c = np.mean(o.vertices, axis=0)
    return {"vertices": tuple(tuple(float(x) for x in c + f * (np.asarray(v) - c)) for v in o.vertices)}


def prepare(a, scene: Scene, render) -> dict:
    """mcrt renders the material and size families need, at the grade resolution (``render`` as in
    :func:`mcrt.grade.explain.prepare_basis`, same spp and seed as its basis): {'material': {object: (kind,
    nodes, images)}, 'size': {object: [(factor, image)]}}."""
    w, h, d, cam = a.grade_width, a.grade_height, a.max_depth, a.camera
    spp = max(64, a.diagnosis_spp // 4)
    seed = a.seed + 7

    def img(s: Scene) -> np.ndarray:
        return render(s, cam, w, h, d, spp, seed).mean.astype(np.float32)

    out = {"material": {}, "size": {}}
    for o in scene.objects:
        kind = "mirror" if isinstance(o.material, Lambertian) else "diffuse"
        imgs = []
        for v in MATERIAL_NODES:
            m = Mirror(reflectance=(v, v, v)) if kind == "mirror" else Lambertian(albedo=(v, v, v))
            imgs.append(img(_with_object(scene, o.name, material=m)))
        out["material"][o.name] = (kind, np.asarray(MATERIAL_NODES), np.stack(imgs))
        out["size"][o.name] = [(f, img(_with_object(scene, o.name, **_scaled(o, f)))) for f in SIZES]
    return out


def _renders(inputs) -> dict | None:
    basis = getattr(inputs, "basis", None)
    return getattr(basis, "extra", {}).get("families") if basis is not None else None


def _lagrange(x: float, nodes: np.ndarray) -> np.ndarray:
    L = np.ones(len(nodes))
    for j, xj in enumerate(nodes):
        for m, xm in enumerate(nodes):
            if m != j:
                L[j] *= (x - xm) / (xj - xm)
    return L


#: Values scanned per channel for an object's albedo or reflectance.
GRID = np.linspace(0.0, 1.0, 41)


def material(fit, inputs) -> list:
    """Each object rendered as the other material, its albedo or reflectance fitted per channel."""
    r = _renders(inputs)
    if not r:
        return []
    base = inputs.basis.base.astype(np.float64)
    out = []
    for name, (kind, nodes, imgs) in r["material"].items():
        fitted = []
        change = np.zeros_like(base)
        for c in range(3):
            best = None
            for v in GRID:
                dm = np.zeros_like(base)
                dm[..., c] = np.tensordot(_lagrange(v, nodes), imgs[..., c], axes=(0, 0)) - base[..., c]
                e = fit.delta(dm)
                if best is None or e < best[0]:
                    best = (e, v, dm[..., c])
            fitted.append(float(best[1]))
            change[..., c] = best[2]
        word = "a mirror of reflectance" if kind == "mirror" else "a diffuse (Lambertian) surface of albedo"
        was = "a diffuse surface" if kind == "mirror" else "a mirror"
        out.append(_candidate("material", f"{name} as {kind}", f"the {name} rendered as {word} {_fmt(fitted)} where "
                              f"the scene makes it {was}", fit.delta(change), 3,
                              value={"object": name, "material": kind, "value": fitted}, change=change))
    return out


def object_size(fit, inputs) -> list:
    """Each object's size: the scale between the two rendered sizes that fit best (linear between them)."""
    r = _renders(inputs)
    if not r:
        return []
    base = inputs.basis.base.astype(np.float64)
    out = []
    for name, nodes in r["size"].items():
        pts = sorted([(1.0, base)] + [(f, i.astype(np.float64)) for f, i in nodes], key=lambda p: p[0])
        best = None
        for (f0, i0), (f1, i1) in zip(pts, pts[1:]):
            for t in np.linspace(0.0, 1.0, 11):
                dm = (1 - t) * i0 + t * i1 - base
                e = fit.delta(dm)
                if best is None or e < best[0]:
                    best = (e, f0 + t * (f1 - f0), dm)
        e, f, dm = best
        what = "radius" if name == "sphere" else "size"
        out.append(_candidate("object_size", f"size of the {name}", f"the {name}'s {what} {_num(f)} times the "
                              "scene's", e, 1, value={"object": name, "scale": f}, change=dm))
    return out


#: The families of this module, in the order the explanation runs them.
FAMILIES = (tone_curve, falloff, resampling, material, object_size)
