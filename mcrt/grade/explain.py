r"""Explaining a failing image by the parametric mistake that fits it best, in the student's terms.

The bug catalogue (:mod:`mcrt.mutants`) names estimator bugs; students also
get the scene wrong. Here a failing image S (grade resolution, as handed in
after flips only) is compared with a family of mistakes, each a model image
:math:`M_\theta` with a parameter the student can recognise:

============== ============================================ ===================================
family         model image                                  how it is made
============== ============================================ ===================================
scale          k R (one k, or one per channel: the light's  closed form
               radiance, an exposure, a white balance)
channels       R with its channels reordered                closed form
albedo         each surface's albedo per channel            mcrt renders at albedo 0, 1/2, 1
                                                            and the scene's, Lagrange
                                                            interpolation per channel
reflectance    the mirror's reflectance per channel         the same with 0, 1/2 and 1
light          the light moved along x, y, z; its size      mcrt renders at a few offsets
camera         field of view, rotation, pixel-centre offset a 4x finer mcrt image warped by the
                                                            pinhole homography, box-filtered
eye            the camera's eye moved                       mcrt renders at a few offsets
object         missing, or moved along x, y, z              mcrt renders
depth          paths cut at depth k                         mcrt renders at max depth k
emitter        the light black where seen directly          R minus the max-depth-1 image
encoding       sRGB or a power curve on the values          closed form on R
blur           a Gaussian blur of width sigma               closed form on R
catalogue      R + (E_m - E_0) for each catalogued bug      the catalogue's renders
beyond the     tone curves, fall-off, resampling, an        :mod:`mcrt.grade.families`
scene file     object's material and size
============== ============================================ ===================================

Every rendered family changes the reference by what mcrt says the mistake
changes, :math:`M_\theta = R + (B_\theta - B_0)`, with :math:`B_\theta` and
the baseline :math:`B_0` rendered with the same seed (common random numbers)
by :func:`prepare_basis` into the grading cache; at grade time everything is
NumPy (:func:`explain`). Each candidate's parameter minimises, pixel by pixel
and channel by channel,

.. math::

    \chi^2(\theta) = \sum_{p,c} \frac{(S - M_\theta)^2}{V + W + (f R)^2},

with V the noise model of the bias test (the student's noise and the
reference's), W the basis renders' own noise and f = 0.2 % the floor that no
two renderers share. The share of the difference a candidate explains is
the share of the *excess* chi-square it removes,

.. math::

    e = \frac{\chi^2_0 - \chi^2(\hat\theta)}{\chi^2_0 - n},

where :math:`\chi^2(\hat\theta)` includes :math:`p \ln n` for the p
fitted parameters (the Bayesian information criterion: three albedos do not
beat a fixed bug by fitting noise), :math:`\chi^2_0` is that of the
reference itself (M = R) and n the
number of terms (what noise alone gives; the best candidate's chi^2 where
that is lower, since capped terms of heavy-tailed noise average less than
1). The best candidate is named when it explains at least :data:`NAMED` of
the difference and lowers chi^2 by at least :data:`GAIN_SIGMAS` standard
deviations of noise's (:math:`\sqrt{2n}`); otherwise the feedback
says that no candidate does and shows where the image differs. The grader
then claims the named cause only when what it leaves is noise
(:func:`mcrt.grade.adequacy.judge`). A catalogued
bug that explains nearly as much as the best (within :data:`TIE`) is named
first: several families contain a catalogued bug exactly (the mirror's
reflectance 0 is ``mirror_wrong_sign``, the sRGB curve ``gamma_output``,
depth 9 ``depth_off_by_one``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from types import SimpleNamespace
import numpy as np

from mcrt.grade.families import FAMILIES
from mcrt.grade.families import prepare as prepare_families
from mcrt.scene import Lambertian, Mirror, Scene

#: Share of the excess chi-square the best candidate must explain to be named.
NAMED = 0.5
#: The best candidate must also lower chi^2 by this many standard deviations of noise's chi^2 (sqrt(2 n)).
GAIN_SIGMAS = 2.0
#: A catalogued bug within this share of the best candidate is named first.
TIE = 0.02
#: Floor of the relative error no two renderers share (as in mcrt.grade.diagnose).
FLOOR = 0.002
#: Oversampling of the image warped for the camera families, and samples per grade pixel and axis of a warp;
#: the fine image sees WIDE times further to each side (tan of the half angle), so that warps stay inside it.
FINE = 4
WIDE = 1.2
SUB = 2
#: Largest contribution of one term to chi^2 (z^2): heavy-tailed noise (a firefly the noise model did not
#: foresee) counts as a clear mismatch, not as a hundred.
CAP = 100.0
#: Uncertainty (pixels) in where an edge lies, in every model image.
EDGE = 0.05
#: Albedo nodes rendered per surface (with the scene's own value).
ALBEDO_NODES = (0.0, 0.5, 1.0)
#: Offsets (scene units) of the light, the objects and the eye; light size factors.
LIGHT_OFFSETS = (-2.0, -1.5, -1.0, -0.5, 0.5, 1.0, 1.5, 2.0)
LIGHT_DROPS = (-0.5, -1.0)
LIGHT_SIZES = (0.5, 0.75, 1.25, 1.5)
OBJECT_OFFSETS = (-1.5, -1.0, -0.5, 0.5, 1.0, 1.5)
EYE_OFFSETS = (-0.5, -0.3, -0.2, -0.1, 0.1, 0.2, 0.3, 0.5)
DEPTHS = (1, 2, 3, 4, 5, 6, 7, 9, 10, 12, -1)
AXES = "xyz"


# --------------------------------------------------------------------------
# The basis: what the cache holds
# --------------------------------------------------------------------------


@dataclass
class Basis:
    """mcrt renders of the scene's variations at the grade resolution (see the module docstring)."""

    camera: str
    spp: int
    base: np.ndarray  # (H, W, 3) the scene as it is, basis seed
    var: np.ndarray  # (H, W, 3) its per-sample variance
    fine: np.ndarray  # (~FINE WIDE H, ~FINE WIDE W, 3) the scene as it is, wider, for warps
    fine_tan: float  # tan of the fine image's horizontal half angle
    fov_deg: float
    max_depth: int
    albedo: dict[str, tuple[np.ndarray, np.ndarray, tuple]] = field(default_factory=dict)  # label -> (nodes, images, scene)
    nodes: dict[str, list[tuple[object, np.ndarray]]] = field(default_factory=dict)  # family/key -> [(value, image)]
    values: dict[str, object] = field(default_factory=dict)  # the scene's values, for the words
    extra: dict[str, object] = field(default_factory=dict)  # renders of other families (mcrt.grade.families)
    prepare_time: float = 0.0


def _surface_edits(scene: Scene) -> dict[str, tuple[str, tuple, callable]]:
    """label -> (kind, the scene's value, value -> edited scene) for every surface with a colour."""
    out = {}
    room = scene.room
    for w in room.walls:
        key = "".join(w.corners)

        def wall(v, key=key):
            walls = tuple(replace(x, albedo=tuple(v)) if "".join(x.corners) == key else x for x in scene.room.walls)
            return replace(scene, room=replace(scene.room, walls=walls))
        out[f"wall {key}"] = ("albedo", tuple(w.albedo), wall)
    out["the floor"] = ("albedo", tuple(room.floor_albedo),
                        lambda v: replace(scene, room=replace(scene.room, floor_albedo=tuple(v))))
    out["the ceiling"] = ("albedo", tuple(room.ceiling_albedo),
                          lambda v: replace(scene, room=replace(scene.room, ceiling_albedo=tuple(v))))
    for o in scene.objects:
        def obj(v, name=o.name):
            objs = []
            for x in scene.objects:
                if x.name == name:
                    m = x.material
                    x = replace(x, material=replace(m, albedo=tuple(v)) if isinstance(m, Lambertian)
                                else replace(m, reflectance=tuple(v)))
                objs.append(x)
            return replace(scene, objects=tuple(objs))
        m = o.material
        if isinstance(m, Lambertian):
            out[f"the {o.name}"] = ("albedo", tuple(m.albedo), obj)
        elif isinstance(m, Mirror):
            out[f"the mirror {o.name}"] = ("reflectance", tuple(m.reflectance), obj)
    return out


def _shift(p, axis: int, d: float):
    q = list(p)
    q[axis] = float(q[axis] + d)
    return tuple(q)


def _light_variants(scene: Scene) -> dict[str, list[tuple[float, Scene]]]:
    lt = scene.light
    out: dict[str, list] = {}
    for axis, offsets in ((0, LIGHT_OFFSETS), (1, LIGHT_OFFSETS), (2, LIGHT_DROPS)):
        out[f"light_{AXES[axis]}"] = [(d, replace(scene, light=replace(lt, center=_shift(lt.center, axis, d))))
                                      for d in offsets]
    out["light_size"] = [(f, replace(scene, light=replace(lt, size=(lt.size[0] * f, lt.size[1] * f)))) for f in LIGHT_SIZES]
    return {k: [(d, s) for d, s in v if _light_inside(s)] for k, v in out.items()}


def _light_inside(s: Scene) -> bool:
    return all(s.room.contains(c, -1e-6 * s.room.size()) for c in s.light.corners()) and \
        s.light.center[2] < s.room.ceiling_z


def _object_variants(scene: Scene) -> dict[str, list[tuple[object, Scene]]]:
    out: dict[str, list] = {}
    for o in scene.objects:
        out[f"missing:{o.name}"] = [(None, replace(scene, objects=tuple(x for x in scene.objects if x.name != o.name)))]
        for axis in range(3):
            vs = []
            for d in OBJECT_OFFSETS:
                if hasattr(o, "center"):
                    moved = replace(o, center=_shift(o.center, axis, d))
                    ok = scene.room.contains(moved.center, moved.radius)
                else:
                    moved = replace(o, vertices=tuple(_shift(v, axis, d) for v in o.vertices))
                    ok = all(scene.room.contains(v, 0.0) for v in moved.vertices)
                if ok:
                    vs.append((d, replace(scene, objects=tuple(moved if x.name == o.name else x for x in scene.objects))))
            out[f"moved:{o.name}:{AXES[axis]}"] = vs
    return out


def _eye_variants(scene: Scene, camera: str) -> dict[str, list[tuple[float, Scene]]]:
    c = scene.cameras[camera]
    out = {}
    for axis in range(3):
        vs = []
        for d in EYE_OFFSETS:
            c2 = replace(c, eye=_shift(c.eye, axis, d))
            if scene.room.contains(c2.eye, 1e-3 * scene.room.size()):
                vs.append((d, replace(scene, cameras={**scene.cameras, camera: c2})))
        out[f"eye_{AXES[axis]}"] = vs
    return out


def prepare_basis(a, scene: Scene, render) -> Basis:
    """Render every image :func:`explain` needs, for the assignment ``a``.

    ``render(scene, camera, width, height, max_depth, spp, seed)`` returns a
    :class:`mcrt.film.RenderResult`; the grading context passes its cached
    mcrt render (:func:`mcrt.grade.expected.cached_render`), so each image is
    rendered once per machine.
    """
    t0 = time.perf_counter()
    w, h, d, cam = a.grade_width, a.grade_height, a.max_depth, a.camera
    spp = max(64, a.diagnosis_spp // 4)
    seed = a.seed + 7

    def img(s: Scene, depth: int = d, width: int = w, height: int = h, n: int = spp) -> np.ndarray:
        return render(s, cam, width, height, depth, n, seed).mean.astype(np.float32)

    base_r = render(scene, cam, w, h, d, spp, seed)
    c0 = scene.cameras[cam]
    t_fine = WIDE * math.tan(math.radians(c0.fov_x_deg) / 2)
    wide = replace(scene, cameras={**scene.cameras, cam: replace(c0, fov_x_deg=math.degrees(2 * math.atan(t_fine)))})
    fine = img(wide, width=round(FINE * WIDE * w), height=round(FINE * WIDE * h), n=max(16, spp // FINE**2 * 4))
    b = Basis(camera=cam, spp=spp, base=base_r.mean.astype(np.float32),
              var=np.maximum(base_r.variance, 0).astype(np.float32), fine=fine, fine_tan=t_fine,
              fov_deg=float(c0.fov_x_deg), max_depth=d)
    for label, (kind, value, edit) in _surface_edits(scene).items():
        nodes = [v for v in ALBEDO_NODES if not (kind == "reflectance" and v == 1.0 and all(x == 1.0 for x in value))]
        imgs = [img(edit((v, v, v))) for v in nodes]
        b.albedo[label] = (np.asarray(nodes, np.float64), np.stack(imgs), tuple(value))
        b.values[label] = (kind, tuple(value))
    for fam in (_light_variants(scene), _object_variants(scene), _eye_variants(scene, cam)):
        for key, vs in fam.items():
            if vs:
                b.nodes[key] = [(v, img(s)) for v, s in vs]
    b.nodes["depth"] = [(k, img(scene, depth=k)) for k in DEPTHS if k != d]
    lt, c = scene.light, scene.cameras[cam]
    b.values.update(light_center=tuple(lt.center), light_size=tuple(lt.size), light_radiance=tuple(lt.radiance),
                    eye=tuple(c.eye), objects={o.name: tuple(float(x) for x in (o.center if hasattr(o, "center")
                                                                            else np.mean(o.vertices, axis=0)))
                                                for o in scene.objects})
    b.extra["families"] = prepare_families(a, scene, render)
    b.prepare_time = time.perf_counter() - t0
    return b


# --------------------------------------------------------------------------
# Candidates
# --------------------------------------------------------------------------


@dataclass
class Candidate:
    """One explanation: its family, its fitted value in words, chi^2 and the share of the difference it explains."""

    family: str  # 'albedo', 'light_x', 'fov', 'catalogue', ...
    key: str  # what it names: 'albedo of wall DE', 'nee_no_area', ...
    text: str  # in the student's terms, one clause
    chi2: float
    params: int
    explained: float = 0.0
    value: object = None
    catalogue: bool = False
    delta: np.ndarray | None = None  # M - R (H, W, 3), for where
    where: str = ""

    def to_dict(self) -> dict:
        return {"mutant": self.key, "family": self.family, "description": self.text, "explained": self.explained,
                "chi2": self.chi2, "value": _jsonable(self.value), "catalogue": self.catalogue, "where": self.where,
                "amplitude": None, "chi2_best_amplitude": None}


def _jsonable(v):
    if isinstance(v, (tuple, list, np.ndarray)):
        return [_jsonable(x) for x in v]
    if isinstance(v, (np.floating, np.integer)):
        return v.item()
    return v


def _fmt(v, digits: int = 2) -> str:
    v = tuple(float(x) for x in v)
    if len(set(round(x, digits) for x in v)) == 1:
        return f"{v[0]:.{digits}f}"
    return "(" + ", ".join(f"{x:.{digits}f}" for x in v) + ")"


def _num(x: float) -> str:
    return f"{x:.2f}".rstrip("0").rstrip(".")


class _Fit:
    r"""chi^2 of model images against the student's image, each term capped at CAP (see the module docstring).

    The chi^2 sums two levels: single pixels (what a shift, a blur or an
    edge changes) and the means of ``tile`` x ``tile`` tiles (what a smooth
    bias of a per cent changes: a single pixel's noise hides it, a tile's
    mean does not). Every chi^2 here, that of the reference included, has
    the same pixel weights
    :math:`1 / (\tilde V + W + (f R)^2 + (\epsilon |\nabla R|)^2)`:
    :math:`\tilde V` is the noise variance raised to its 3x3 mean where that
    is larger (a pixel's variance estimated from a few thousand heavy-tailed
    samples is usually too small; its neighbours' share the rare bright
    paths), and :math:`\epsilon` = EDGE pixel of uncertainty in where an edge
    lies (no model image puts a light's edge exactly). A tile mean's variance
    is the sum of its pixels' over the count squared, plus the floor.
    """

    def __init__(self, S, R, V, ok, W, tile: int = 8):
        from scipy.ndimage import uniform_filter

        self.S, self.R, self.ok = S, R, ok
        V = np.where(np.isfinite(V), V, 0.0)
        V = np.maximum(V, uniform_filter(V, (3, 3, 1), mode="nearest"))
        gy, gx = np.gradient(R, axis=(0, 1))
        edge = EDGE**2 * (gx**2 + gy**2)
        var = V + W + (FLOOR * R) ** 2 + edge
        self.w = np.where(ok, 1.0 / np.maximum(var, 1e-30), 0.0)
        self.D = np.where(ok, S - R, 0.0)
        self.t = max(1, min(int(tile), *R.shape[:2]))
        self.hc, self.wc = (R.shape[0] // self.t) * self.t, (R.shape[1] // self.t) * self.t
        cnt = self.blocks(ok.astype(np.float64))
        self.cnt = np.maximum(cnt, 1.0)
        r_t = self.blocks(np.where(ok, R, 0.0)) / self.cnt
        v_t = self.blocks(np.where(ok, var, 0.0)) / self.cnt**2 + (FLOOR * r_t) ** 2
        self.wt = np.where(cnt >= 2, 1.0 / np.maximum(v_t, 1e-30), 0.0)
        self.Dt = self.blocks(self.D) / self.cnt
        self.n = int(np.count_nonzero(ok)) + int(np.count_nonzero(cnt >= 2))
        self.chi0 = self.delta(0.0)

    def blocks(self, x: np.ndarray) -> np.ndarray:
        """Sums over the tiles of x (..., H, W, C), cropped to whole tiles: (..., H/t, W/t, C)."""
        x = x[..., : self.hc, : self.wc, :]
        t = self.t
        sh = x.shape[:-3] + (self.hc // t, t, self.wc // t, t, x.shape[-1])
        return x.reshape(sh).sum(axis=(-4, -2))

    def tile_means(self, dm: np.ndarray) -> np.ndarray:
        return self.blocks(np.where(self.ok, dm, 0.0)) / self.cnt

    def delta(self, dm) -> float:
        """chi^2 of M = R + dm (pixels and tiles)."""
        dt = self.tile_means(np.broadcast_to(dm, self.D.shape)) if not np.isscalar(dm) else dm
        return float(np.sum(np.minimum((self.D - dm) ** 2 * self.w, CAP)) +
                     np.sum(np.minimum((self.Dt - dt) ** 2 * self.wt, CAP)))

    def model(self, m: np.ndarray) -> float:
        return self.delta(m - self.R)

    def irls(self, dm) -> np.ndarray:
        """Weights of a least-squares step that caps like chi^2: w where z^2 < CAP, w CAP / z^2 beyond (pixels)."""
        z2 = (self.D - dm) ** 2 * self.w
        return self.w * np.minimum(1.0, CAP / np.maximum(z2, 1e-300))


def _scale_candidates(fit: _Fit, values: dict) -> list[Candidate]:
    S, R, w = fit.S, fit.R, fit.w
    ok = fit.ok
    num = np.sum(np.where(ok, S * R * w, 0.0), axis=(0, 1))
    den = np.sum(np.where(ok, R * R * w, 0.0), axis=(0, 1))
    kc = np.where(den > 0, num / np.maximum(den, 1e-300), 1.0)
    k1 = float(np.sum(num) / max(np.sum(den), 1e-300))
    out = [Candidate("scale", "overall scale", f"the whole image {_num(k1)} times the reference (an exposure or "
                     f"display scale, or the light's radiance {_fmt(np.asarray(values.get('light_radiance', (1, 1, 1))) * k1, 1)})",
                     fit.model(k1 * R), 1, value=k1, delta=(k1 - 1) * R)]
    Le = np.asarray(values.get("light_radiance", (1.0, 1.0, 1.0)))
    out.append(Candidate("light_radiance", "the light's radiance",
                         f"the light's radiance {_fmt(Le * kc, 1)} where the scene says {_fmt(Le, 1)} (every channel of "
                         f"the image scaled by {_fmt(kc)})", fit.model(kc * R), 3, value=tuple(Le * kc),
                         delta=(kc - 1) * R))
    names = "RGB"
    for perm in ((0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)):
        Rp = R[..., perm]
        k = float(np.sum(np.where(ok, S * Rp * w, 0.0)) / max(np.sum(np.where(ok, Rp * Rp * w, 0.0)), 1e-300))
        order = "".join(names[i] for i in perm)
        out.append(Candidate("channels", f"channels {order}", f"the colour channels written in the order {order} "
                             "instead of RGB", fit.model(k * Rp), 1, value=order, delta=k * Rp - R))
    return out


def _lagrange(x: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """Lagrange weights (len(x), len(nodes)) of the polynomial through ``nodes`` evaluated at ``x``."""
    L = np.ones((len(x), len(nodes)))
    for j, xj in enumerate(nodes):
        for m, xm in enumerate(nodes):
            if m != j:
                L[:, j] *= (x - xm) / (xj - xm)
    return L


def _albedo_candidates(fit: _Fit, b: Basis) -> list[Candidate]:
    r"""Each surface's albedo, fitted per channel on a grid of 101 values in [0, 1] then refined by a parabola.

    Channel c of the image depends on channel c of the albedos only (RGB
    transport is channel-independent), so the three channels fit apart.
    """
    grid = np.linspace(0.0, 1.0, 101)
    out = []
    for label, (nodes, imgs, scene_v) in b.albedo.items():
        fitted, dm = [], np.zeros_like(b.base, dtype=np.float64)
        for c in range(3):
            xs = np.append(nodes, scene_v[c])
            ys = np.concatenate([imgs[:, :, :, c], b.base[None, :, :, c]]).astype(np.float64)
            keep = np.concatenate([np.abs(nodes - scene_v[c]) > 1e-3, [True]])
            xs, ys = xs[keep], ys[keep]
            L = _lagrange(grid, xs)
            curves = np.tensordot(L, ys, axes=(1, 0)) - b.base[None, :, :, c]  # (101, H, W): M - R
            err = np.sum(np.minimum((fit.D[None, :, :, c] - curves) ** 2 * fit.w[None, :, :, c], CAP), axis=(1, 2))
            ct = fit.blocks(np.where(fit.ok[None, :, :, c:c + 1], curves[..., None], 0.0))[..., 0] / fit.cnt[None, :, :, c]
            err = err + np.sum(np.minimum((fit.Dt[None, :, :, c] - ct) ** 2 * fit.wt[None, :, :, c], CAP), axis=(1, 2))
            i = int(np.argmin(err))
            fitted.append(float(_refine(grid, err, i)))
            dm[..., c] = np.tensordot(_lagrange(np.array([fitted[-1]]), xs), ys, axes=(1, 0))[0] - b.base[..., c]
        kind = b.values[label][0]
        word = "albedo" if kind == "albedo" else "reflectance"
        out.append(Candidate(word, f"{word} of {label}", f"{label} with {word} {_fmt(fitted)} where the scene says "
                             f"{_fmt(scene_v)}", fit.delta(dm), 3, value=tuple(fitted), delta=dm))
    return out


def _refine(grid: np.ndarray, err: np.ndarray, i: int) -> float:
    """The minimum of the parabola through the grid's best point and its neighbours."""
    if 0 < i < len(grid) - 1:
        y0, y1, y2 = err[i - 1], err[i], err[i + 1]
        den = y0 - 2 * y1 + y2
        if den > 0:
            return float(grid[i] + 0.5 * (y0 - y2) / den * (grid[1] - grid[0]))
    return float(grid[i])


def _node_candidates(fit: _Fit, b: Basis) -> list[Candidate]:
    """The rendered variations: the best node of each family (light, objects, eye, depth)."""
    out = []
    v = b.values
    best_moved: dict[str, Candidate] = {}
    for key, nodes in b.nodes.items():
        scores = [fit.delta(img.astype(np.float64) - b.base) for _, img in nodes]
        i = int(np.argmin(scores))
        val, img = nodes[i]
        dm = img.astype(np.float64) - b.base
        fam = key.split(":")[0]
        if key.startswith("light_") and key != "light_size":
            axis = AXES.index(key[-1])
            c = _shift(v["light_center"], axis, val)
            text = (f"the light moved by {val:+g} along {key[-1]} (centre {_fmt(c, 2)} where the scene says "
                    f"{_fmt(v['light_center'], 2)})")
            cand = Candidate("light_position", f"light moved along {key[-1]}", text, scores[i], 1, value=c)
        elif key == "light_size":
            s = tuple(x * val for x in v["light_size"])
            cand = Candidate("light_size", "the light's size", f"the light's size {_num(s[0])} x {_num(s[1])} where "
                             f"the scene says {_num(v['light_size'][0])} x {_num(v['light_size'][1])} (same radiance)",
                             scores[i], 1, value=s)
        elif fam == "missing":
            name = key.split(":")[1]
            cand = Candidate("object_missing", f"{name} missing", f"the {name} missing from the image", scores[i], 0,
                             value=name)
        elif fam == "moved":
            name, ax = key.split(":")[1:]
            cand = Candidate("object_moved", f"{name} moved", f"the {name} moved by {val:+g} along {ax}", scores[i], 1,
                             value=(name, ax, val))
            if name in best_moved and best_moved[name].chi2 <= cand.chi2:
                continue
            cand.delta = dm
            best_moved[name] = cand
            continue
        elif key.startswith("eye_"):
            cand = Candidate("eye", "the camera's eye", f"the camera's eye moved by {val:+g} along {key[-1]} (at "
                             f"{_fmt(_shift(v['eye'], AXES.index(key[-1]), val), 2)} where the scene says "
                             f"{_fmt(v['eye'], 2)})", scores[i], 1, value=val)
        elif key == "depth":
            cand = Candidate("depth", "path depth", f"paths cut at depth {'unbounded' if val == -1 else val} "
                             f"(Mitsuba's convention, where the assignment asks for {b.max_depth})", scores[i], 1,
                             value=val)
        else:
            continue
        cand.delta = dm
        out.append(cand)
    out += list(best_moved.values())
    emit = dict(b.nodes.get("depth", []))
    if 1 in emit:
        dm = -emit[1].astype(np.float64)
        out.append(Candidate("emitter_hidden", "the light not seen directly", "the light itself black where the camera "
                             "sees it directly (emission left out at the first hit)", fit.delta(dm), 0, delta=dm))
    return out


def _curve_candidates(fit: _Fit) -> list[Candidate]:
    """Encoding curves on the reference: sRGB (and its inverse), power curves; a Gaussian blur."""
    from scipy.ndimage import gaussian_filter

    from mcrt.imageio import srgb_eotf, srgb_oetf

    R = np.maximum(fit.R, 0.0)
    out = [Candidate("encoding", "sRGB curve", "the values sRGB-encoded (a display curve) instead of linear",
                     fit.model(srgb_oetf(R)), 0, value="srgb", delta=srgb_oetf(R) - fit.R),
           Candidate("encoding", "decoded twice", "the values decoded from sRGB once too often (linear values written "
                     "to a PNG that says sRGB, or decoded twice)", fit.model(srgb_eotf(np.minimum(R, 1.0))), 0,
                     value="srgb-inverse", delta=srgb_eotf(np.minimum(R, 1.0)) - fit.R)]
    exps = np.linspace(0.25, 2.5, 91)
    errs = np.array([fit.model(R**p) for p in exps])
    i = int(np.argmin(errs))
    p = _refine(exps, errs, i)
    g = 1.0 / p
    what = (f"a power curve x^(1/{_num(g)}) (gamma {_num(g)} encoding)" if p < 1 else
            f"a power curve x^{_num(p)} (decoded with gamma {_num(p)} once too often)")
    out.append(Candidate("encoding", "power curve", f"the values through {what} instead of linear", fit.model(R**p), 1,
                         value=g, delta=R**p - fit.R))
    sig = np.array([0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 1.0, 1.2, 1.5, 2.0, 3.0])
    errs = np.array([fit.model(gaussian_filter(fit.R, (s, s, 0), mode="nearest")) for s in sig])
    i = int(np.argmin(errs))
    s = sig[i]
    out.append(Candidate("blur", "blur", f"the image blurred (or denoised) by about {_num(s)} pixel (a Gaussian of that "
                         "standard deviation)", float(errs[i]), 1, value=float(s),
                         delta=gaussian_filter(fit.R, (s, s, 0), mode="nearest") - fit.R))
    return out


# --------------------------------------------------------------------------
# The camera: warping a finer image
# --------------------------------------------------------------------------


def _rot(yaw: float, pitch: float, roll: float) -> np.ndarray:
    """Rotation of camera-frame directions (x right, y up, z forward): yaw left, pitch up, roll, in degrees."""
    a, b, c = (math.radians(t) for t in (yaw, pitch, roll))
    Ry = np.array([[math.cos(a), 0, -math.sin(a)], [0, 1, 0], [math.sin(a), 0, math.cos(a)]])
    Rx = np.array([[1, 0, 0], [0, math.cos(b), math.sin(b)], [0, -math.sin(b), math.cos(b)]])
    Rz = np.array([[math.cos(c), -math.sin(c), 0], [math.sin(c), math.cos(c), 0], [0, 0, 1]])
    return Ry @ Rx @ Rz


class _Warp:
    r"""The image of a pinhole camera with another field of view, rotation or pixel-centre offset.

    A student pixel's sample (i + (s + 1/2)/SUB + dx, j + ...) is a
    direction in the student's camera frame,
    :math:`d = (s_x t_s, s_y t_s h/w, 1)` with :math:`t = \tan(fov/2)`;
    rotated into the scene's camera frame it projects to the scene camera's
    film, where the FINE times finer (and WIDE times wider) image is sampled bilinearly; the SUB^2
    samples of a pixel are averaged (its box filter). Exact for a pinhole (a
    rotation about the eye is a homography) up to the interpolation. The
    model image is ``image(...) - identity``, added to the reference.
    """

    def __init__(self, b: Basis):
        from scipy.ndimage import map_coordinates

        self.map = map_coordinates
        self.F = [np.ascontiguousarray(b.fine[..., c], dtype=np.float32) for c in range(3)]
        self.Hf, self.Wf = b.fine.shape[:2]
        self.h, self.w = b.base.shape[:2]
        self.t = math.tan(math.radians(b.fov_deg) / 2)
        self.tf = b.fine_tan
        jj, ii = np.mgrid[0:self.h * SUB, 0:self.w * SUB]
        self.u, self.v = (ii + 0.5) / SUB, (jj + 0.5) / SUB  # in grade pixels
        self.identity = self.image()

    def image(self, fov: float | None = None, yaw=0.0, pitch=0.0, roll=0.0, dx=0.0, dy=0.0) -> np.ndarray:
        ts = self.t if fov is None else math.tan(math.radians(fov) / 2)
        asp = self.h / self.w
        sx = 2 * (self.u + dx) / self.w - 1
        sy = 1 - 2 * (self.v + dy) / self.h
        R = _rot(yaw, pitch, roll)
        x, y = sx * ts, sy * ts * asp
        X = R[0, 0] * x + R[0, 1] * y + R[0, 2]
        Y = R[1, 0] * x + R[1, 1] * y + R[1, 2]
        Z = np.maximum(R[2, 0] * x + R[2, 1] * y + R[2, 2], 1e-9)
        px = (X / Z / self.tf + 1) * self.Wf / 2 - 0.5
        py = (1 - Y / Z / (self.tf * self.Hf / self.Wf)) * self.Hf / 2 - 0.5
        coords = np.stack([py.ravel(), px.ravel()])
        out = np.stack([self.map(f, coords, order=1, mode="nearest").reshape(py.shape) for f in self.F], axis=-1)
        return out.reshape(self.h, SUB, self.w, SUB, 3).mean(axis=(1, 3), dtype=np.float64)


#: The camera families: parameter names, start scans, finite-difference steps, bounds.
_CAMERA = {
    "fov": (("fov",), {"fov": (0.9, 0.95, 1.05, 1.1)}, {"fov": 0.2}, {"fov": (0.8, 1.2)}),
    "pixel_offset": (("dx", "dy"), {"dx": (-1.0, -0.5, 0.5, 1.0), "dy": (-1.0, -0.5, 0.5, 1.0)},
                     {"dx": 0.1, "dy": 0.1}, {"dx": (-2.0, 2.0), "dy": (-2.0, 2.0)}),
    "rotation": (("yaw", "pitch", "roll"), {"yaw": (-4.0, -2.0, -1.0, 1.0, 2.0, 4.0), "pitch": (-4.0, -2.0, -1.0, 1.0, 2.0, 4.0),
                                            "roll": (-6.0, -3.0, 3.0, 6.0)},
                 {"yaw": 0.1, "pitch": 0.1, "roll": 0.2}, {"yaw": (-10, 10), "pitch": (-10, 10), "roll": (-20, 20)}),
}


def _fit_camera(fit: _Fit, wp: _Warp, family: str, fov0: float, steps: int = 4) -> tuple[dict, float, np.ndarray]:
    r"""Fit one camera family: a scan of each parameter alone for a start, then Gauss-Newton steps.

    Each step solves :math:`(J^T W J)\,\delta = J^T W r` with J by central
    differences and W the capped chi^2's weights (:meth:`_Fit.irls`); a step
    that does not lower chi^2 is halved, twice at most.
    """
    names, scans, h, bounds = _CAMERA[family]
    scale = {"fov": fov0}

    def kw(p):
        return {n: p[i] for i, n in enumerate(names)}

    def img(p):
        return wp.image(**kw(p)) - wp.identity

    p = np.array([fov0 if n == "fov" else 0.0 for n in names])
    best = fit.delta(img(p))
    for i, n in enumerate(names):
        for v in scans[n]:
            q = p.copy()
            q[i] = v * scale.get(n, 1.0)
            c = fit.delta(img(q))
            if c < best:
                best, p = c, q
    lo = np.array([bounds[n][0] * scale.get(n, 1.0) for n in names])
    hi = np.array([bounds[n][1] * scale.get(n, 1.0) for n in names])
    for _ in range(steps):
        m = img(p)
        J = []
        for i, n in enumerate(names):
            e = np.zeros_like(p)
            e[i] = h[n]
            J.append(((img(p + e) - img(p - e)) / (2 * h[n])).ravel())
        J = np.stack(J, axis=1)
        wv = fit.irls(m).ravel()
        r = (fit.D - m).ravel()
        A = J.T @ (J * wv[:, None])
        g = J.T @ (wv * r)
        try:
            d = np.linalg.solve(A + 1e-9 * np.trace(A) * np.eye(len(p)), g)
        except np.linalg.LinAlgError:
            break
        for _ in range(3):
            q = np.clip(p + d, lo, hi)
            c = fit.delta(img(q))
            if c < best:
                best, p = c, q
                break
            d = d / 2
        else:
            break
    return kw(p), best, img(p)


def _camera_candidates(fit: _Fit, b: Basis) -> list[Candidate]:
    wp = _Warp(b)
    f0 = b.fov_deg
    out = []
    p, chi, dm = _fit_camera(fit, wp, "fov", f0)
    out.append(Candidate("fov", "field of view", f"the camera's field of view {p['fov']:.1f} degrees where the scene "
                         f"says {_num(f0)}", chi, 1, value=float(p["fov"]), delta=dm))
    p, chi, dm = _fit_camera(fit, wp, "pixel_offset", f0)
    dx, dy = float(p["dx"]), float(p["dy"])
    out.append(Candidate("pixel_offset", "pixel-centre offset", f"the image shifted by ({dx:+.2f}, {dy:+.2f}) pixel "
                         "(x right, y down), as when pixel centres are not at (i + 0.5, j + 0.5)", chi, 2,
                         value=(dx, dy), delta=dm))
    p, chi, dm = _fit_camera(fit, wp, "rotation", f0)
    ya, pi_, ro = (float(p[k]) for k in ("yaw", "pitch", "roll"))
    out.append(Candidate("rotation", "camera rotation", f"the camera rotated by yaw {ya:+.1f}, pitch {pi_:+.1f} and roll "
                         f"{ro:+.1f} degrees (left, up and anticlockwise positive), as when its forward or up vector is "
                         "off", chi, 3, value=(ya, pi_, ro), delta=dm))
    return out


def _catalogue_candidates(fit: _Fit, mutants: dict, baseline, texts: dict) -> list[Candidate]:
    from mcrt.grade.diagnose import short_text

    out = []
    base = baseline.mean.astype(np.float64)
    for name, e in mutants.items():
        dm = e.mean.astype(np.float64) - base
        out.append(Candidate("catalogue", name, short_text(texts.get(name, name)), fit.delta(dm), 0, catalogue=True,
                             delta=dm))
    return out


# --------------------------------------------------------------------------
# The explanation
# --------------------------------------------------------------------------


#: The families that are mistakes of the camera (what the misregistration test of mcrt.grade.structure also sees).
CAMERA_FAMILIES = frozenset({"fov", "pixel_offset", "rotation", "eye"})
#: The families a TA counts as major mistakes whatever their share of the image: the camera, the scene's geometry
#: (an object or the light missing, moved or resized) and its colours (mcrt.grade.grader._Grader._loss).
MAJOR_FAMILIES = CAMERA_FAMILIES | {"object_missing", "object_moved", "light_position", "light_size", "albedo", "channels",
                                    "material", "object_size"}


@dataclass
class Explanation:
    """The ranked candidates and what the feedback says."""

    candidates: list[Candidate]  # best first
    chi2_none: float
    terms: int
    named: Candidate | None  # the best, when it explains at least NAMED; else None
    sentence: str  # for the bias test's output
    headline: str  # for the summary
    where: str
    seconds: float = 0.0

    def to_dict(self) -> dict:
        return {"chi2_none": self.chi2_none, "terms": self.terms, "named": self.named.key if self.named else None,
                "family": self.named.family if self.named else None, "sentence": self.sentence,
                "where": self.where, "seconds": self.seconds,
                "candidates": [c.to_dict() for c in self.candidates[:8]]}


def explain(S: np.ndarray, R: np.ndarray, V: np.ndarray, mask: np.ndarray, basis: Basis, *, mutants: dict | None = None,
            baseline=None, texts: dict | None = None, where_fn=None, tile: int = 8) -> Explanation:
    """Fit every family of mistakes to the image S (see the module docstring).

    ``V`` is the per-pixel noise variance of S - R (the student's and the
    reference's), ``mask`` the pixels to use; ``mutants`` and ``baseline``
    (the catalogue's expected images, :class:`mcrt.grade.expected.Expected`)
    make the catalogued bugs candidates too. ``where_fn(delta)`` describes
    where an image change lies (the grader passes the region words of
    :mod:`mcrt.grade.diagnose`); ``tile`` is the edge of the tiles of the
    tile level of chi^2 (:class:`_Fit`).
    """
    t0 = time.perf_counter()
    S, R, V = (np.asarray(x, np.float64) for x in (S, R, V))
    ok = mask[..., None] & np.isfinite(S) & np.isfinite(V) & np.isfinite(R)
    ok = np.broadcast_to(ok, S.shape)
    W = basis.var.astype(np.float64) / basis.spp  # a variation minus the base, common random numbers
    fit = _Fit(S, R, V, ok, W, tile)
    cands = _scale_candidates(fit, basis.values) + _curve_candidates(fit) + _albedo_candidates(fit, basis) + \
        _node_candidates(fit, basis) + _camera_candidates(fit, basis)
    cands += [c for family in FAMILIES for c in family(fit, SimpleNamespace(basis=basis))]
    if mutants:
        cands += _catalogue_candidates(fit, mutants, baseline, texts or {})
    # What noise alone leaves: n terms of about 1 (less where the cap bites on heavy tails), or what the best
    # candidate leaves if that is less.
    # Each fitted parameter costs ln(n) (the Bayesian information criterion): a surface's three albedos do not
    # win over a fixed bug by fitting the noise.
    pen = math.log(max(fit.n, 2))
    for c in cands:
        c.chi2 = c.chi2 + c.params * pen
    floor = min([float(fit.n)] + [c.chi2 for c in cands])
    excess = fit.chi0 - floor
    for c in cands:
        c.explained = float(min((fit.chi0 - c.chi2) / excess, 1.0)) if excess > 0 else 0.0
    cands.sort(key=lambda c: (-c.explained, c.params))
    cands = _catalogue_first(cands)
    best = cands[0] if cands else None
    gain = fit.chi0 - best.chi2 if best is not None else 0.0
    named = best if best is not None and best.explained >= NAMED and gain >= GAIN_SIGMAS * math.sqrt(2 * fit.n) else None
    for c in cands[:5]:
        if where_fn is not None and c.delta is not None:
            c.where = where_fn(c.delta)
    where = where_fn(S - R) if where_fn is not None else ""
    if named is not None:
        alt = next((c for c in cands[1:3] if c.family != named.family and not c.catalogue
                    and c.explained >= named.explained - TIE), None)
        sentence = (f"It looks like {named.text}: that explains {100 * named.explained:.0f} % of the difference"
                    + (f" (so would {alt.text}, {100 * alt.explained:.0f} %)" if alt else "")
                    + (f"; it changes the image {named.where}" if named.where else "") + ".")
        headline = f"It looks like {named.text}."
    else:
        tried = ("No single mistake we tried (the catalogued bugs, the scene's colours, light, objects and camera, "
                 "the path depth, encodings and blur)")
        if best is not None and best.explained >= NAMED:  # it fits, but no better than noise would let anything fit
            sentence = (f"{tried} stands out: the difference is too close to the noise to tell them apart (the closest, "
                        f"{best.text}, lowers chi-square by {gain:.0f} where noise alone varies it by about "
                        f"{math.sqrt(2 * fit.n):.0f})")
        else:
            sentence = (f"{tried} explains most of the difference"
                        + (f": the closest, {best.text}, explains {100 * max(best.explained, 0):.0f} %" if best else ""))
        sentence += (f". The image differs {where}" if where else "") + "."
        headline = "No single mistake we tried explains the difference" + (f"; it differs {where}" if where else "") + "."
    return Explanation(cands, fit.chi0, fit.n, named, sentence, headline, where, time.perf_counter() - t0)


def _catalogue_first(cands: list[Candidate]) -> list[Candidate]:
    """A catalogued bug within TIE of the best goes first (it names a known bug; see the module docstring)."""
    if not cands or cands[0].catalogue:
        return cands
    top = cands[0].explained
    cat = next((c for c in cands if c.catalogue and c.explained >= top - TIE), None)
    if cat is None:
        return cands
    return [cat] + [c for c in cands if c is not cat]
